"""Bad input that used to exit 1 or pass silently (issue 27): each a one-line InputError
naming the file and the key."""
from __future__ import annotations

import pytest

from liftoff.config import default_text, merge, parse_scenario, parse_toml
from liftoff.config.barge import parse_barge
from liftoff.config.extends import example_text
from liftoff.core.errors import InputError

DEFAULT = parse_toml(default_text(), "d")


@pytest.mark.parametrize("text, match", [
    ("a = " + "[" * 3000 + "]" * 3000, r"s\.toml: TOML nested too deep"),
    ("t = " + "9" * 5000, r"s\.toml: TOML value not usable: an integer with thousands of digits"),
])
def test_pathological_toml(text, match):
    with pytest.raises(InputError, match=match) as exc:
        parse_toml(text, "s.toml")
    assert "\n" not in str(exc.value)


@pytest.mark.parametrize("over, match", [
    ({"time": {"h": 5e-324}}, r"s: time\.h: step .* makes more than 1e\+09 steps"),
    ({"cryo": {"delta_T": -1e6}}, r"s: cryo\.delta_T: .* below absolute zero"),
    ({"cryo": {"alpha": 1.0}}, r"s: cryo: free thermal strain alpha delta_T = -200 beyond 0\.02"),
    ({"case": [{"name": "envelope"}]}, r"s: case\[2\]\.name: 'envelope' names the run's envelope outputs"),
])
def test_values_no_run_can_use(over, match):
    with pytest.raises(InputError, match=match):
        parse_scenario(merge(DEFAULT, over), "s")


def test_barge_case_named_envelope():
    data = merge(parse_toml(example_text("barge"), "b"), {"case": [{"name": "envelope"}]})
    with pytest.raises(InputError, match=r"'envelope' names the run's envelope outputs"):
        parse_barge(data, "b")


def test_the_defaults_cryo_is_within_the_bounds():
    """The default's cryo preload (LH2/LOX tank shrinkage) passes the new bounds."""
    c = parse_scenario(DEFAULT, "d").cases[0].cryo
    assert c.enabled and -320.0 <= c.delta_T < 0 and abs(c.alpha * c.delta_T) < 0.02


def test_case_override_of_an_unknown_post_names_the_posts():
    """A case override's misspelt post name is a new, incomplete post: the message says so and
    lists the posts (issue 27: it said "missing required key 'vehicle'")."""
    over = {"case": [{"name": "x", "post": [{"name": "nope", "release_time": 1.0}]}]}
    with pytest.raises(InputError, match=r"case\[2\]\.post\[8\] 'nope': no 'vehicle': 'nope' is not one of the posts "
                                         r"\(left_1, .*right_4\), so it is a new post"):
        parse_scenario(merge(DEFAULT, over), "s")


def test_attitude_hold_bandwidth_beyond_a_control_design():
    """bandwidth_hz = 1e4 (issue 27: "diverged ... reduce h") is refused at the key."""
    with pytest.raises(InputError, match=r"control\.bandwidth_hz: 10000 Hz: an attitude-hold loop .* at most 20 Hz"):
        parse_scenario(merge(DEFAULT, {"control": {"law": "attitude-hold", "bandwidth_hz": 1e4}}), "s")


def test_mode_samples_below_the_nyquist_rate():
    """[time] mode_samples < 2 would alias the highest mode: refused at the key; the default
    scenario samples it twice a period (docs/workflow.md, "Convergence in the step")."""
    with pytest.raises(InputError, match=r"time\.mode_samples: steps a period of the bodies' highest mode: at least 2"):
        parse_scenario(merge(DEFAULT, {"time": {"mode_samples": 1.9}}), "s")
    with pytest.raises(InputError, match=r"time\.mode_samples: .* at most 64 \(a finer step: give h or accuracy\), got 65"):
        parse_scenario(merge(DEFAULT, {"time": {"mode_samples": 65}}), "s")
    assert {c.time.mode_samples for c in parse_scenario(DEFAULT, "s").cases} == {2.0}


def test_accuracy_below_round_off():
    """accuracy = 1e-15 (issue 27: 8.5 GB of halved runs before exit 4) is refused at the key."""
    with pytest.raises(InputError, match=r"time\.accuracy: 1e-15 is below what the arithmetic resolves"):
        parse_scenario(merge(DEFAULT, {"time": {"accuracy": 1e-15}}), "s")
    parse_scenario(merge(DEFAULT, {"time": {"accuracy": 1e-3}}), "s")


STICK = {**DEFAULT, "model": {"source": "stick"}}      # the stick model of the default stack


@pytest.mark.parametrize("key, value, match", [
    ("srb_mass", 1e-30, r"StickParams\.srb_mass = 1e-30 kg is outside \[1, 1e\+07\] kg"),
    ("core_mass_lox", 1e30, r"StickParams\.core_mass_lox = 1e\+30 kg is outside \[1, 1e\+07\] kg"),
    ("payload_mass", 1e-30, r"StickParams\.payload_mass = 1e-30 kg is outside"),
    ("core_wall", 1e3, r"StickParams\.core_wall = 1000 m is outside \[0\.0001, 0\.42\d*\] m"),
    ("srb_wall", 1e-30, r"StickParams\.srb_wall = 1e-30 m is outside"),
    ("ssme_cg_below_bulkhead", 1e-30, r"StickParams\.ssme_cg_below_bulkhead = 1e-30 m is outside \[0\.01, 1000\] m"),
    ("orbiter_length", 1e6, r"StickParams\.orbiter_length = 1e\+06 m is outside \[0\.01, 1000\] m"),
    ("srb_E", 1e-30, r"StickParams\.srb_E = 1e-30 Pa is outside \[1e\+09, 1\.2e\+12\] Pa"),
    ("orbiter_I", 1e30, r"StickParams\.orbiter_I = 1e\+30 m\^4 is outside \[1e-06, 10000\] m\^4"),
    ("post_A", 1e-30, r"StickParams\.post_A = 1e-30 m\^2 is outside \[0\.0001, 100\] m\^2"),
])
def test_stick_parameters_beyond_physical_ranges(key, value, match):
    """Issue 27: ``srb_mass = 1e-30`` said "component 'srb_left' floats (or has a mechanism)",
    other absurd masses, walls and lengths ran or failed far away (a ZeroDivisionError for a
    zero-length SSME link). Each is refused at the key, with the range it must lie in."""
    with pytest.raises(InputError, match=r"^s: model\.stick: " + match) as exc:
        parse_scenario(merge(STICK, {"model": {"stick": {key: value}}}), "s")
    assert "\n" not in str(exc.value)


def test_the_stick_defaults_are_within_the_ranges():
    """Every default StickParams value (the Shuttle-like stack) passes the ranges."""
    from liftoff.meshes import StickParams

    StickParams().check()
    assert parse_scenario(STICK, "d").cases[0].model.components["srb_left"].builder.srb_mass == 590.0e3


def test_fixed_length_builder_arrays_are_named_at_their_key():
    """A builder's array whose length the geometry fixes (a platform deck's (x, y) size, a
    dock's piles grid and (x, y, z) sizes, a barge's saddle): the wrong length is one line at
    its key ("too many values to unpack" at the params table before)."""
    pad = {"type": "platform", "mesh_size": 2.4, "params": {"posts": {"srb_left_hd_1": [-8.0, 1.0, 0.0]}}}
    for size, n in (([10.0, 12.0, 3.0], 3), ([10.0], 1)):
        data = merge(DEFAULT, {"model": {"pad": merge(pad, {"params": {"deck_size": size}})}})
        with pytest.raises(InputError, match=rf"s: model\.pad\.params\.deck_size: has {n} entries, expected 2$"):
            parse_scenario(data, "s")
    for part, key, value, n in (("dock", "pile_grid", [3, 5, 2], 2), ("dock", "fender_size", [0.6, 2.0], 3),
                                ("barge", "saddle_size", [2.0, 5.0], 3)):
        data = merge(parse_toml(example_text("barge"), "b"), {"model": {part: {"params": {key: value}}}})
        with pytest.raises(InputError, match=rf"{key}: has {len(value)} entries, expected {n}$") as exc:
            parse_barge(data, "b")
        assert "\n" not in str(exc.value)
