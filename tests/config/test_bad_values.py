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


@pytest.mark.parametrize("over, match", [
    # an uncertainty factor widens the design range (analysis.aggregate.factored_outward): 0.25 for 1.25 cut it 4x
    ({"postprocess": {"uncertainty": {"interface_force": 0.25}}},
     r"s: postprocess\.uncertainty\.interface_force: an uncertainty factor is at least 1, got 0\.25"),
    # both sides of a joint: recovered as attach_<point> twice, refused only after the model stages
    ({"recovery": {"attach": ["att_orb_fwd@core", "att_orb_fwd@orbiter"]}},
     r"s: recovery\.attach\[1\]: 'att_orb_fwd@orbiter': a second entry at point 'att_orb_fwd'"),
    # a convective model without a hydroelastic liquid did nothing, silently
    ({"model": {"liquid": "smeared", "convective": "free"}},
     r"s: model\.convective: \"free\" needs a hydroelastic liquid"),
    # two entries of one name in a case: merged into one, the first lost
    ({"case": [{"name": "hot", "post": [{"name": "x", "vehicle": "srb_left_hd_1"},
                                        {"name": "x", "vehicle": "srb_left_hd_2"}]}]},
     r"s: case\[2\]: post: two entries named 'x'"),
])
def test_values_a_run_would_ignore_or_misuse(over, match):
    """Found by a review (2026-12-07): each passed and did something else than asked."""
    with pytest.raises(InputError, match=match) as exc:
        parse_scenario(merge(DEFAULT, over), "s")
    assert "\n" not in str(exc.value)


@pytest.mark.parametrize("over, key", [({"degree": 2}, r"model\.degree"),
                                       ({"pad": {"f_max": 100.0, "mesh_size": 1.0}}, r"model\.pad\.mesh_size")])
def test_stick_keys_it_would_ignore(over, key):
    """The stick source has beams and a lumped pad: [model] degree and the pad's mesh_size
    did nothing there, silently."""
    from ..workflows.test_run import STICK

    data = {k: v for k, v in DEFAULT.items() if k != "model"}
    data["model"] = {**STICK, **over}            # (the stick model replaces the default's [model], as extends does)
    with pytest.raises(InputError, match=rf"s: {key}: .*it would be silently ignored"):
        parse_scenario(data, "s")


def test_a_child_scenario_naming_an_entry_twice_is_refused(tmp_path):
    """extends merges lists of named entries by name: two [[post]] named alike in the child
    became one (the first one's values lost); refused, naming the file."""
    from liftoff.config import load_scenario

    p = tmp_path / "child.toml"
    p.write_text('extends = "shuttle"\n[[post]]\nname = "extra"\nvehicle = "srb_left_hd_1"\npad = "pad_post_left_1"\n'
                 '[[post]]\nname = "extra"\nvehicle = "srb_left_hd_2"\npad = "pad_post_left_2"\n')
    with pytest.raises(InputError, match=r"child\.toml: post: two entries named 'extra'"):
        load_scenario(p)


def test_a_csv_header_is_a_line_without_numbers(tmp_path):
    """The optional header of a CSV table is a first line with no number in it: a first data
    row with a typo ('0.0O') was taken for a header and the table started a row late."""
    import numpy as np

    from liftoff.config.files import read_csv_table
    from liftoff.config.values import Where

    w = Where("s", "profiles.thrust")
    (tmp_path / "a.csv").write_text("time,value\n0.0,0.0\n1.0,0.5\n")
    np.testing.assert_array_equal(read_csv_table(tmp_path / "a.csv", w), [[0.0, 0.0], [1.0, 0.5]])
    (tmp_path / "b.csv").write_text("0.0, 0.0O\n1.0, 0.5\n2.0, 1.0\n")
    with pytest.raises(InputError, match=r"b\.csv line 1: not a number in '0\.0, 0\.0O'"):
        read_csv_table(tmp_path / "b.csv", w)


def test_a_meshless_type_ignores_an_inherited_mesh_size():
    """[model] mesh_size applies to every component; a rigid mass or rigid ground has no mesh,
    and refused it as if it were its own ('remove the component's mesh_size', which it did
    not have). Its own is still refused."""
    from liftoff.config.component_types import Context, get
    from liftoff.config.values import Where
    from liftoff.meshes.layout import StackLayout

    params = {"point": "p", "at": [0.0, 0.0, 1.0], "mass": 10.0}
    w = Where("s", "model.component.ballast.params")
    rigid = get("rigid_mass", "vehicle")
    assert rigid.read(Context("ballast", 1.0, StackLayout(), mesh_size_given=False), w, params).mass == 10.0
    with pytest.raises(InputError, match="a rigid mass has no mesh"):
        rigid.read(Context("ballast", 1.0, StackLayout()), w, params)
