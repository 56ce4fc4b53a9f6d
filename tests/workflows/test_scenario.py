"""Scenario files: the embedded default parses; bad inputs give one line naming the key."""
import copy
import tomllib

import pytest

from liftoff.core.errors import InputError
from liftoff.workflows.scenario import default_text, load_scenario, merge, parse_scenario


@pytest.fixture(scope="module")
def base():
    return tomllib.loads(default_text())


def test_default_scenario_parses(base):
    sc = load_scenario(None)
    assert [c.name for c in sc.cases] == ["nominal", "no-control"]
    nominal, noctl = sc.cases
    assert len(nominal.posts) == 8 and all(p.release_time == 6.6 for p in nominal.posts)
    assert nominal.control["enabled"] and not noctl.control["enabled"]
    assert {e.name for e in nominal.engines} == {"ssme_1", "ssme_2", "ssme_3", "srb_left", "srb_right"}
    srb = next(e for e in nominal.engines if e.name == "srb_left")
    t, v = srb.table()
    assert t[0] == pytest.approx(6.6) and v.max() == pytest.approx(12.5e6)


def test_cases_merge_named_tables(base):
    d = copy.deepcopy(base)
    d["case"] = [{"name": "stud-hang", "post": [{"name": "left_1", "vehicle": "srb_left_hd_1",
                                                 "pad": "pad_post_left_1", "release_time": float("inf")}]}]
    sc = parse_scenario(d, "x.toml")
    posts = {p.name: p for p in sc.cases[0].posts}
    assert len(posts) == 8 and posts["left_1"].release_time == float("inf")
    assert posts["left_2"].release_time == 6.6
    assert merge({"a": {"b": 1, "c": 2}}, {"a": {"c": 3}}) == {"a": {"b": 1, "c": 3}}


def _set(d, path, value):
    keys = path.split(".")
    for k in keys[:-1]:
        d = d[int(k)] if isinstance(d, list) else d.setdefault(k, {})
    last = keys[-1]
    if value is _DEL:
        del d[last]
    elif isinstance(d, list):
        d[int(last)] = value
    else:
        d[last] = value


_DEL = object()

BAD = [
    ("tittle", "x", "unknown key 'tittle'"),
    ("model.source", "nastran", "model.source"),
    ("model.zeta", 1.5, "model.zeta"),
    ("model.degree", 3, "model.degree"),
    ("model.materials", {"core_wall": {"E": -1.0, "nu": 0.3, "rho": 2800.0}}, "model.materials.core_wall.E"),
    ("model.materials", {"core_wall": {"E": 7e10, "nu": 0.6, "rho": 2800.0}}, "model.materials.core_wall.nu"),
    ("model.component", {"booster": {}}, "model.component: unknown key 'booster'"),
    ("post_defaults.stiffness", [1e9, -1e9, 1e9], "post[0].stiffness[1]"),
    ("post_defaults.stiffness", [1e9, 1e9], "post[0].stiffness: expected 3 numbers"),
    ("post.2.vehicle", 7, "post[2].vehicle"),
    ("post.3.name", "left_1", "post[3].name: duplicate post name"),
    ("engine.0.profile", "rs25", "engine[0].profile: unknown profile 'rs25'"),
    ("engine.1.direction", [0.0, 0.0, 0.0], "engine[1].direction: zero thrust direction"),
    ("profiles.ssme.time", [0.0, 1.0, 0.5, 2.0, 3.0, 4.0, 5.0, 6.0], "profiles.ssme.time: times must increase"),
    ("profiles.srb.value", [0.0, 1.0], "profiles.srb.value: 2 values for 6 times"),
    ("gravity.accel", [0.0, -9.8], "gravity.accel: expected 3 numbers"),
    ("cryo.alpha", -1e-5, "cryo.alpha: must be positive"),
    ("cryo.volumes", [], "cryo.volumes"),
    ("control.gimbals", ["srb_left_gimbal:Tx"], "control.gimbals"),
    ("control.gimbals", ["a:Tx", "b:Ty", "c:Tq"], "control.gimbals[2]"),
    ("softening.enabled", "yes", "softening.enabled: expected true or false"),
    ("time.t_end", -1.0, "time.t_end"),
    ("time.h", 0.0, "time.h: must be positive"),
    ("time.method", "newmark", "time.method"),
    ("time.t_end", _DEL, "time: missing required key 't_end'"),
    ("recovery.top", 3, "recovery.top"),
    ("output.plots", 1, "output.plots"),
    ("case.0.name", "no-control", "case[1].name: duplicate case name"),
    ("case.1.nme", "x", "case[1]: unknown key 'nme'"),
    ("case.1.control", {"enabled": True, "gimbals": ["x:Tx"]}, "case[1].control.gimbals"),
]


@pytest.mark.parametrize("path, value, expect", BAD, ids=[b[0] + ":" + b[2][:20] for b in BAD])
def test_bad_input_one_line_naming_the_key(base, path, value, expect):
    d = copy.deepcopy(base)
    _set(d, path, value)
    with pytest.raises(InputError) as exc:
        parse_scenario(d, "bad.toml")
    msg = str(exc.value)
    assert "\n" not in msg and msg.startswith("bad.toml: ")
    assert expect in msg, msg


def test_force_table_needs_time(base):
    d = copy.deepcopy(base)
    d["force"] = [{"label": "stack_top:Tx", "value": [0.0, 1.0]}]
    with pytest.raises(InputError, match=r"force\[0\]: a tabulated force needs 'time'"):
        parse_scenario(d, "bad.toml")
    d["force"] = [{"label": "stack_top", "value": 1.0}]
    with pytest.raises(InputError, match=r"force\[0\].label"):
        parse_scenario(d, "bad.toml")


def test_files(tmp_path):
    with pytest.raises(InputError, match="scenario file not found"):
        load_scenario(tmp_path / "none.toml")
    p = tmp_path / "broken.toml"
    p.write_text("title = \n")
    with pytest.raises(InputError, match="broken.toml: not valid TOML"):
        load_scenario(p)
