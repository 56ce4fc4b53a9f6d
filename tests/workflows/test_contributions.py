"""--contributions (issue 24; workflows/contributions.py, analysis/contributions.py): each
compared peak split into other + forcing + modes + damping on the stick stack. Independent
checks: a change of one cause alone is attributed to it alone (the other parts exactly
zero: the swapped problems are then the same problem, bit for bit), the earlier run is
reproduced by its rebuilt scenario (other within the CSV's 7 digits), and with every cause
changed the parts add up to the compared change."""
import copy
import csv
import tomllib

import numpy as np
import pytest

from liftoff.config import default_text
from liftoff.workflows.cli import main

from .test_run import STICK, _toml


def _write(path, d):
    path.write_text(_toml(d))
    return path


def _base():
    d = tomllib.loads(default_text())
    d["model"] = copy.deepcopy(STICK)
    d["time"]["t_end"] = 7.0
    d["case"] = [{"name": "nominal"}]
    return d


def _rows(path):
    lines = [ln for ln in path.read_text().splitlines() if not ln.startswith("#")]
    return list(csv.DictReader(lines))


@pytest.fixture(scope="module")
def earlier(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("contrib")
    old = _write(tmp / "old.toml", _base())
    assert main(["run", str(old), "--out", str(tmp / "old"), "--cache", str(tmp / "c"), "--no-progress",
                 "--no-snapshots", "--no-plots", "--no-error-estimate"]) == 0
    return tmp, old


def _split(tmp, old, d, name):
    new = _write(tmp / f"{name}.toml", d)
    assert main(["run", str(new), "--out", str(tmp / name), "--cache", str(tmp / "c"), "--no-progress",
                 "--no-snapshots", "--no-plots", "--no-error-estimate", "--compare", str(tmp / "old"),
                 "--contributions", str(old)]) == 0
    rows = _rows(tmp / name / "contributions.csv")
    assert len(rows) > 100                                   # every row of the stick's envelope, max and min
    return rows


def _scale(r):
    return max(abs(float(r["old"])), abs(float(r["new"])), 1e-30)


@pytest.mark.parametrize("change, alone", [
    (lambda d: d["model"].update(zeta=0.02), "damping"),
    (lambda d: d["engine"][0].update(scale=1.05 * d["engine"][0]["scale"]), "forcing"),
])
def test_one_cause_alone_is_attributed_to_it(earlier, change, alone, capsys):
    tmp, old = earlier
    d = _base()
    change(d)
    rows = _split(tmp, old, d, alone)
    capsys.readouterr()
    moved = 0
    for r in rows:
        for part in ("forcing", "modes", "damping"):
            if part != alone:
                assert float(r[part]) == 0.0, (r["item"], r["side"], part, r[part])
        # the rebuilt earlier case is the earlier run: the CSV's 7 digits
        assert abs(float(r["other"])) <= 1e-6 * _scale(r), r
        assert float(r[alone]) == pytest.approx(float(r["change"]) - float(r["other"]), rel=1e-9,
                                                abs=1e-12 * _scale(r))
        moved += abs(float(r["change"])) > 1e-3 * _scale(r)
    assert moved > 10                                      # the change matters


def test_every_cause_changed_adds_up(earlier, capsys):
    tmp, old = earlier
    d = _base()
    d["model"]["zeta"] = 0.015
    d["model"]["mesh_size"] = 4.0                          # other stick elements: other modes
    d["engine"][3]["scale"] = 1.03 * d["engine"][3]["scale"]
    rows = _split(tmp, old, d, "all")
    out = capsys.readouterr().out
    assert "Largest changes from the earlier run, split" in out
    parts = np.array([[float(r[k]) for k in ("other", "forcing", "modes", "damping")] for r in rows])
    change = np.array([float(r["change"]) for r in rows])
    scale = np.array([_scale(r) for r in rows])
    np.testing.assert_allclose(parts.sum(axis=1), change, rtol=0, atol=1e-12 * scale.max())
    assert np.all(np.abs(parts[:, 1:]).max(axis=0) > 0)          # each of the three causes moved something
    assert np.abs(parts[:, 0]).max() <= 1e-6 * scale.max()


def test_contributions_are_checked_before_any_stage(earlier, tmp_path, capsys):
    tmp, old = earlier
    new = _write(tmp_path / "n.toml", _base())
    other = _base()
    other["case"] = [{"name": "windy"}]
    other = _write(tmp_path / "o.toml", other)
    for args, expect in ((["--contributions", str(old)], "--contributions"),
                         (["--compare", str(tmp / "old"), "--contributions", str(tmp_path / "nope.toml")],
                          "no such scenario file"),
                         (["--compare", str(tmp / "old"), "--contributions", str(other)], "has no case 'nominal'"),
                         (["--compare", str(tmp / "old"), "--contributions", str(old), "--cases", "2"],
                          "without --cases")):
        assert main(["run", str(new), "--out", str(tmp_path / "x"), "--cache", str(tmp_path / "c"),
                     "--no-progress"] + args) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and expect in err, err
        assert not (tmp_path / "c").exists()            # refused before the model stages


def test_a_split_that_cannot_be_made_leaves_the_run_and_warns(earlier, monkeypatch, capsys):
    """A new case that cannot run on the earlier model: the run's outputs are written, a
    one-line warning says no split was, and there is no contributions.csv."""
    from liftoff.core.errors import InputError
    from liftoff.workflows import contributions

    def fail(*a, **k):
        raise InputError("the new case 'nominal' cannot run on the earlier model (point 'x' is not on it)")

    monkeypatch.setattr(contributions, "states", fail)
    tmp, old = earlier
    new = _write(tmp / "same.toml", _base())
    assert main(["run", str(new), "--out", str(tmp / "same"), "--cache", str(tmp / "c"), "--no-progress",
                 "--no-snapshots", "--no-plots", "--no-error-estimate", "--compare", str(tmp / "old"),
                 "--contributions", str(old)]) == 0
    err = capsys.readouterr().err
    assert "liftoff: warning: --contributions: no split written (the new case 'nominal' cannot run" in err
    assert (tmp / "same" / "compare.csv").is_file() and not (tmp / "same" / "contributions.csv").exists()


def test_an_earlier_envelope_of_other_cases_is_refused(earlier, tmp_path):
    """--contributions rebuilds the earlier run from its named cases: an earlier envelope set
    partly by other cases (a campaign's generated ones) is refused before any stage, naming
    them (a review: their whole excess went into 'other', 100 % of a peak with nothing
    changed)."""
    from liftoff.workflows.cli import main

    tmp, old = earlier
    lines = (tmp / "old" / "maxmin_envelope.csv").read_text().splitlines()
    head = [ln for ln in lines if ln.startswith("#")]
    body = [ln for ln in lines if not ln.startswith("#")]
    cols = body[0].split(",")
    k = cols.index("case_max")
    first = body[1].split(",")
    first[k] = "d0001"                           # one value set by a generated case
    (tmp_path / "env.csv").write_text("\n".join(head + [body[0], ",".join(first)] + body[2:]) + "\n")
    new = _write(tmp / "same2.toml", _base())
    assert main(["run", str(new), "--out", str(tmp_path / "x"), "--cache", str(tmp / "c"), "--no-progress",
                 "--no-snapshots", "--no-plots", "--no-error-estimate", "--compare", str(tmp_path / "env.csv"),
                 "--contributions", str(old)]) == 2
    assert not (tmp_path / "x").exists()


def test_compare_lists_items_in_one_run_only(tmp_path):
    """compare.csv has a row for an item in one run only (its other side empty, a status), and
    the console count says how many (a review: a removed attach point's six rows vanished)."""
    from liftoff.analysis import aggregate
    from liftoff.analysis.tables import format_changes

    new = [{"item": "A", "unit": "N", "max": 2.0, "min": -1.0, "category": "contact_force", "case_max": "nominal",
            "case_min": "nominal"},
           {"item": "NEW", "unit": "N", "max": 9e6, "min": 0.0, "category": "contact_force", "case_max": "nominal",
            "case_min": "nominal"}]
    old = {"A": {"max": 1.0, "min": -1.0, "unit": "N", "case_max": "nominal", "case_min": "d0003"},
           "GONE": {"max": 5e6, "min": 0.0, "unit": "N", "case_max": "nominal", "case_min": "nominal"}}
    path, rows = aggregate.write_compare(new, old, tmp_path)
    status = {r["item"]: r["status"] for r in rows}
    assert status == {"A": "both", "NEW": "only in this run", "GONE": "only in the earlier run"}
    text = path.read_text()
    assert "cases setting this run's values: nominal; the earlier run's: nominal, d0003" in text
    assert "1 items compared; 1 only in the earlier run, 1 only in this one" in format_changes(rows)
