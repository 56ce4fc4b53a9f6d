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


def test_accuracy_below_round_off():
    """accuracy = 1e-15 (issue 27: 8.5 GB of halved runs before exit 4) is refused at the key."""
    with pytest.raises(InputError, match=r"time\.accuracy: 1e-15 is below what the arithmetic resolves"):
        parse_scenario(merge(DEFAULT, {"time": {"accuracy": 1e-15}}), "s")
    parse_scenario(merge(DEFAULT, {"time": {"accuracy": 1e-3}}), "s")
