"""Generated cases ([dispersion]): reproducible from the scenario and the index, the
distributions they claim, targets anywhere in the scenario, database forcing files, and
one-line errors naming the key."""
import copy
import math
import tomllib

import numpy as np
import pytest

from liftoff.config import default_text, parse_scenario
from liftoff.config.dispersion import Variable
from liftoff.config.values import Where
from liftoff.core.errors import InputError


def _data(**disp):
    d = tomllib.loads(default_text())
    d["dispersion"].update(disp)
    return d


def test_same_seed_same_cases_and_each_case_from_its_index_alone():
    a = parse_scenario(_data(), "s.toml", n_cases=6)
    b = parse_scenario(_data(), "s.toml", n_cases=3)
    for i in range(3):
        assert a.generated_raw(i) == b.generated_raw(i)           # case i does not depend on n_cases
    assert a.generated_raw(4) == parse_scenario(_data(), "s.toml", n_cases=6).generated_raw(4)
    other = parse_scenario(_data(seed=7), "s.toml", n_cases=3)
    assert other.generated_raw(1)[1] != a.generated_raw(1)[1]
    # adding a variable leaves the draws of the others as they were (one stream per variable)
    d = _data()
    d["dispersion"]["variables"]["ramp"] = {"targets": "control.ramp", "op": "scale", "distribution": "uniform",
                                            "low": 0.5, "high": 2.0}
    c = parse_scenario(d, "s.toml", n_cases=3)
    info_a, info_c = a.generated_raw(2)[1], c.generated_raw(2)[1]
    assert {k: v for k, v in info_c.items() if not k.startswith("ramp")} == info_a
    assert c.generated_case(2).control.ramp == pytest.approx(0.05 * info_c["ramp[control.ramp]"])


def test_draws_land_on_their_targets():
    sc = parse_scenario(_data(), "s.toml", n_cases=2)
    raw, info = sc.generated_raw(1)
    case = sc.generated_case(1)
    eng = {e.name: e for e in case.engines}
    base = {e.name: e for e in sc.cases[0].engines}
    dl = info["srb_ignition_delay[engine[srb_left].start]"]
    assert eng["srb_left"].start == pytest.approx(6.6 + dl, abs=1e-15)
    assert eng["srb_left"].thrust.max() == pytest.approx(12.5e6 * info["srb_thrust[engine[srb_left].scale]"])
    d = np.array([info["srb_misalignment_x[engine[srb_left].direction[0]]"],
                  info["srb_misalignment_y[engine[srb_left].direction[1]]"], 1.0])
    np.testing.assert_allclose(eng["srb_left"].direction, d / np.linalg.norm(d), rtol=1e-14)
    assert eng["ssme_1"].start == pytest.approx(base["ssme_1"].start + info["ssme_start[engine[ssme_1].start]"])
    posts = {p.name: p for p in case.posts}
    for name in ("left_1", "right_4"):                           # post_defaults' value, dispersed per post
        assert posts[name].release_time == pytest.approx(6.6 + info[f"release_scatter[post[{name}].release_time]"])
    winds = [f for f in case.forces if f.label.startswith("stack_top")]
    assert winds[0].table.max() == pytest.approx(2.8e4 * info["wind_x"])        # one shared draw ...
    mids = [f for f in case.forces if f.label == "att_orb_fwd:Tx"]
    assert mids[0].table.max() == pytest.approx(5.6e4 * info["wind_x"])       # ... for every x component
    assert sc.cases[0].forces[0].table.max() == 0.0                            # named cases: calm


def test_distributions():
    """Inverse-CDF draws: normal moments (sampling tolerance 5 sigma of the mean and of the
    variance), truncated normal and uniform inside their bounds and with the truncated
    normal's mean (closed form mean + std (phi(a) - phi(b)) / (Phi(b) - Phi(a)))."""
    from scipy.stats import norm

    n = 4000
    v = Variable("x", ("t",), "add", "normal", mean=2.0, std=0.5)
    x = np.array([v.draw(11, i) for i in range(n)])
    assert abs(x.mean() - 2.0) < 5 * 0.5 / math.sqrt(n)
    assert abs(x.var(ddof=1) / 0.25 - 1) < 5 * math.sqrt(2 / (n - 1))
    t = Variable("y", ("t",), "add", "truncnormal", mean=0.0, std=1.0, low=-0.5, high=2.0)
    y = np.array([t.draw(11, i) for i in range(n)])
    a, b = -0.5, 2.0
    mean = (norm.pdf(a) - norm.pdf(b)) / (norm.cdf(b) - norm.cdf(a))
    assert y.min() >= a and y.max() <= b and abs(y.mean() - mean) < 5 * y.std() / math.sqrt(n)
    u = Variable("z", ("t",), "add", "uniform", low=3.0, high=4.0)
    z = np.array([u.draw(11, i) for i in range(n)])
    assert z.min() >= 3.0 and z.max() < 4.0 and abs(z.mean() - 3.5) < 5 * (1 / math.sqrt(12)) / math.sqrt(n)
    assert v.draw(11, 5) == Variable("x", ("t",), "add", "normal", mean=2.0, std=0.5).draw(11, 5)


def test_database_cases(tmp_path):
    """One forcing file per case (CSV with a header of DOF labels; HDF5 time/force/labels):
    case i takes file i mod n, its columns become tabulated vehicle forces."""
    import h5py

    (tmp_path / "db").mkdir()
    (tmp_path / "db" / "gust_0.csv").write_text("time,stack_top:Tx,stack_top:Ty\n0,0,0\n1,1e4,-2e4\n2,0,0\n")
    with h5py.File(tmp_path / "db" / "gust_1.h5", "w") as f:
        f["time"] = [0.0, 0.5, 3.0]
        f["force"] = [[0.0], [3e4], [0.0]]
        f["labels"] = np.array([b"payload_station:Tx"])
    d = _data()
    d["dispersion"] = {"seed": 1, "database": {"files": ["db/gust_0.csv", "db/gust_1.h5"]}}
    sc = parse_scenario(d, "s.toml", tmp_path)
    assert sc.n_generated == 2                                       # n_cases defaults to the number of files
    c0, c1 = sc.generated_case(0), sc.generated_case(1)
    extra0 = [f for f in c0.forces if f.label.startswith("stack_top") and f.table.any()]
    assert [f.label for f in extra0] == ["stack_top:Tx", "stack_top:Ty"]
    np.testing.assert_array_equal(extra0[1].table, [0, -2e4, 0])
    (f1,) = [f for f in c1.forces if f.label == "payload_station:Tx" and f.table.any()]
    np.testing.assert_array_equal(f1.time, [0.0, 0.5, 3.0])
    assert sc.generated_raw(1)[1]["database"] == "gust_1.h5"
    sc3 = parse_scenario(d, "s.toml", tmp_path, n_cases=3)
    assert sc3.generated_raw(2)[1]["database"] == "gust_0.csv"       # cycles through the files


@pytest.mark.parametrize("change, msg", [
    (lambda d: d["variables"]["srb_thrust"].update(distribution="lognormal"),
     "s.toml: dispersion.variables.srb_thrust.distribution: must be one of normal, uniform, truncnormal"),
    (lambda d: d["variables"]["srb_thrust"].update(std=-1.0), "srb_thrust.std: must be positive"),
    (lambda d: d["variables"]["srb_thrust"].update(low=1.2), "srb_thrust.high: must be greater than low"),
    (lambda d: d["variables"]["release_scatter"].update(mean=0.0),
     "release_scatter.mean: not a parameter of a uniform distribution"),
    (lambda d: d["variables"]["srb_thrust"].update(targets=["engine[srb_middle].scale"]),
     "srb_thrust.targets[0]: engine[srb_middle].scale: no entry named 'srb_middle'"),
    (lambda d: d["variables"]["srb_thrust"].update(targets=["model.zeta"]),
     "srb_thrust.targets[0]: [model] values cannot be dispersed"),
    (lambda d: d["variables"]["srb_thrust"].update(targets=["control.gimbals"]),
     "is not a number or an array of numbers"),
    (lambda d: d["variables"]["srb_thrust"].update(targets=["engine[9].scale"]), "index [9] out of range"),
    (lambda d: d["variables"]["srb_thrust"].update(color="red"), "srb_thrust: unknown key 'color'"),
    (lambda d: d.update(**{"from": "windy"}), "dispersion.from: no [[case]] named 'windy'"),
    (lambda d: d.update(database={"files": "nothing_*.csv"}), "dispersion.database.files[0]: no file matches"),
    # a shared variable's cases.csv column is its name: it overwrote the case's index, name or step
    (lambda d: d["variables"].update(h=d["variables"].pop("srb_thrust")),
     "dispersion.variables.h: the name 'h' is a column of cases.csv (the case's h); name the variable otherwise"),
    (lambda d: d["variables"].update(name=d["variables"].pop("srb_thrust")), "variables.name: the name 'name' is"),
])
def test_bad_dispersions_name_the_key(change, msg):
    d = tomllib.loads(default_text())
    change(d["dispersion"])
    with pytest.raises(InputError) as exc:
        parse_scenario(d, "s.toml", n_cases=2)
    assert msg in str(exc.value) and str(exc.value).startswith("s.toml: "), str(exc.value)


def test_cases_need_a_dispersion_and_names_stay_apart():
    d = tomllib.loads(default_text())
    del d["dispersion"]
    with pytest.raises(InputError, match="--cases 3: the scenario has no \\[dispersion\\] section"):
        parse_scenario(d, "s.toml", n_cases=3)
    d = tomllib.loads(default_text())
    d["case"][0]["name"] = "d0001"
    with pytest.raises(InputError, match="case\\[0\\].name: 'd0001' is the name of a generated case"):
        parse_scenario(d, "s.toml")
    d = tomllib.loads(default_text())
    d["dispersion"]["from"] = "no-control"
    sc = parse_scenario(copy.deepcopy(d), "s.toml", n_cases=1)
    assert sc.generated_case(0).control.enabled is False         # dispersed from the named case


@pytest.mark.parametrize("text, msg", [
    ("time,stack_top:Tx,stack_top:Ty\n0,0,0\n# a comment\n1,1e4,x\n", "g.csv line 4, column 3 'stack_top:Ty': not a number: 'x'"),
    ("time,stack_top:Tx\n0,0\n1,1e4,5\n", "g.csv line 3: 3 columns, expected 2 (time and one per label)"),
    ("time,stack_top:Tx,stack_top:Tq\n0,0,0\n1,1,1\n", "g.csv line 1, column 3 'stack_top:Tq': malformed DOF label"),
    ("time,stack_top:Tx,stack_top:Tx\n0,0,0\n1,1,1\n",
     "g.csv line 1, column 3 'stack_top:Tx': the same DOF as column 2 (one column per DOF)"),
])
def test_database_csv_errors_name_file_line_and_column(tmp_path, text, msg):
    """Issue 27: a bad database column was blamed on a `force[6]` that is not in the file; every
    error of a database CSV names the file, its line and the column (with its label)."""
    (tmp_path / "db").mkdir()
    (tmp_path / "db" / "g.csv").write_text(text)
    with pytest.raises(InputError) as exc:
        parse_scenario(_data(database={"files": ["db/g.csv"]}), "s.toml", tmp_path, n_cases=1).generated_case(0)
    assert str(exc.value).startswith(f"s.toml: dispersion.database: db/{msg}"), str(exc.value)
    assert "\n" not in str(exc.value)


def test_database_labels_checked_against_the_model(tmp_path):
    """Database.check reads every file once and asks the model about each column's DOF: an
    unknown DOF is named by file, line 1 and column, not by the generated force it becomes."""
    (tmp_path / "db").mkdir()
    (tmp_path / "db" / "a.csv").write_text("time,stack_top:Tx\n0,0\n1,1\n")
    (tmp_path / "db" / "b.csv").write_text("time,stack_top:Tx,nope:Ty\n0,0,0\n1,1,1\n")
    sc = parse_scenario(_data(database={"files": ["db/*.csv"]}), "s.toml", tmp_path)

    def known(label: str) -> None:
        if not label.startswith("stack_top:"):
            raise InputError(f"unknown DOF label {label!r} on body 'vehicle'")

    with pytest.raises(InputError) as exc:
        sc.dispersion.database.check(Where("s.toml", "dispersion.database"), known)
    assert str(exc.value) == ("s.toml: dispersion.database: db/b.csv line 1, column 3 'nope:Ty': unknown DOF label "
                              "'nope:Ty' on body 'vehicle'")


@pytest.mark.parametrize("n", [10 ** 9, -3])
def test_case_counts_beyond_the_cap_are_refused_before_any_case_is_generated(monkeypatch, n):
    """Issue 27: `--cases 1000000000` generated and parsed every case before running any (the
    file's n_cases had a cap of 1e7, the command line's none). The count is refused at once:
    no case is generated (Dispersion.generate would fail the test)."""
    from liftoff.config.dispersion import Dispersion

    def no_generation(*a, **k):
        raise AssertionError("a case was generated")

    monkeypatch.setattr(Dispersion, "generate", no_generation)
    with pytest.raises(InputError, match=rf"^s\.toml: --cases {n}: out of range \[0, 10000000\]"):
        parse_scenario(_data(), "s.toml", n_cases=n)
    sc = parse_scenario(_data(), "s.toml")
    with pytest.raises(InputError, match=rf"^s\.toml: --cases {n}: out of range"):
        sc.with_generated(n)
