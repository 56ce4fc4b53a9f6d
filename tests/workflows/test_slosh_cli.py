"""`liftoff slosh` (issue 25): the slosh modes of the scenario's tanks and their equivalent
mechanical model, end to end on a coarse hydroelastic core; bad input refused before any
meshing. The physics is checked against closed forms in tests/fem/test_slosh.py."""
import csv
import importlib.util

import numpy as np
import pytest

from liftoff.workflows.cli import main

HAVE_FE = all(importlib.util.find_spec(m) is not None for m in ("dolfinx", "gmsh", "slepc4py"))
pytestmark = [pytest.mark.fem, pytest.mark.skipif(not HAVE_FE, reason="needs dolfinx")]
G = 9.80665


def _scenario(tmp_path, extra=""):
    p = tmp_path / "s.toml"
    p.write_text('extends = "shuttle"\ntitle = "slosh"\n[model.component.core]\nmesh_size = 1.2\n' + extra)
    return p


def test_slosh_table_of_the_core_tanks(tmp_path, capsys):
    out = tmp_path / "slosh.csv"
    assert main(["slosh", str(_scenario(tmp_path)), "--modes", "2", "--csv", str(out)]) == 0
    text = capsys.readouterr().out
    assert "core / core_lox_liquid" in text and "core / core_lh2_liquid" in text and "convergence: P2 against P1" in text
    lines = out.read_text().splitlines()
    assert lines[0].startswith("# ") and "SI units" in lines[0]
    rows = list(csv.DictReader(lines[1:]))
    for liquid in ("core_lox_liquid", "core_lh2_liquid"):
        mine = [r for r in rows if r["liquid"] == liquid]
        assert [r["kind"] for r in mine] == ["impulsive", "impulsive", "slosh", "slosh"]
        m0 = float(mine[0]["mass_kg"])
        for r in mine[2:]:
            f, m = float(r["frequency_Hz"]), float(r["mass_kg"])
            w2 = (2 * np.pi * f) ** 2
            assert 0.1 < f < 2.0 and 0 < m < m0                     # metre-size tanks: tenths of a Hz
            assert float(r["stiffness_N_per_m"]) == pytest.approx(m * w2, rel=1e-8)
            assert float(r["pendulum_length_m"]) == pytest.approx(G / w2, rel=1e-8)
            assert np.hypot(float(r["direction_x"]), float(r["direction_y"])) == pytest.approx(1.0, rel=1e-8)
            assert float(r["g_eff_m_per_s2"]) == G
            assert float(r["wave_height_per_force_m_per_N"]) > 0
        # the first pair's force acts above the impulsive mass's (the waves ride on top)
        assert float(mine[2]["height_m"]) > float(mine[0]["height_m"])


@pytest.mark.parametrize("args, message", [
    (["--g-eff", "0"], "--g-eff must be > 0"),
    (["--g-eff", "nan"], "--g-eff must be > 0"),
    (["--modes", "0"], "--modes must be >= 1"),
    (["--csv", "/nonexistent-folder/x.csv"], "does not exist"),
])
def test_bad_arguments_refused_before_meshing(tmp_path, capsys, args, message):
    assert main(["slosh", str(_scenario(tmp_path)), *args]) == 2
    err = capsys.readouterr()
    assert message in err.err and len(err.err.strip().splitlines()) == 1 and "meshing" not in err.out


def test_a_stick_model_has_no_tanks_to_slosh(tmp_path, capsys):
    p = tmp_path / "stick.toml"
    p.write_text('extends = "shuttle"\ntitle = "stick"\n[model]\nsource = "stick"\n')
    assert main(["slosh", str(p)]) == 2
    assert 'needs [model] source = "fe"' in capsys.readouterr().err


def test_a_barge_scenario_is_read_as_its_model(tmp_path, capsys):
    """kind = "barge": its three FE parts are meshed; none holds a hydroelastic liquid, which
    is said in one line (exit 2), not a parse error of the barge's own keys."""
    from liftoff.workflows.init import init

    path = init("barge", tmp_path / "b")
    assert main(["slosh", str(path)]) == 2
    err = capsys.readouterr().err
    assert "nothing sloshes" in err and len(err.strip().splitlines()) == 1


def test_g_eff_defaults_to_the_scenarios_slosh_gravity(tmp_path, capsys):
    """Without --g-eff the modes are at the scenario's [model] slosh_gravity (what a run's
    pendulums use); omega^2 = g_eff lambda on the same mesh, so the frequencies scale as
    sqrt(g_eff) to the eigensolver's accuracy (1e-8 in tests/fem/test_slosh.py; 1e-6 here)."""
    two = tmp_path / "two.csv"
    one = tmp_path / "one.csv"
    (tmp_path / "a").mkdir()
    assert main(["slosh", str(_scenario(tmp_path / "a", f"[model]\nslosh_gravity = {2 * G!r}\n")), "--modes", "1",
                 "--csv", str(two)]) == 0
    assert main(["slosh", str(_scenario(tmp_path, f"[model]\nslosh_gravity = {2 * G!r}\n")), "--modes", "1",
                 "--g-eff", str(G), "--csv", str(one)]) == 0
    capsys.readouterr()

    def slosh(path):
        rows = [r for r in csv.DictReader(path.read_text().splitlines()[1:]) if r["kind"] == "slosh"]
        return {(r["liquid"], r["mode"]): r for r in rows}

    a, b = slosh(two), slosh(one)
    assert a.keys() == b.keys() and len(a) == 4      # --modes 1: each tank's first pair (whole pairs kept)
    for k in a:
        assert float(a[k]["g_eff_m_per_s2"]) == 2 * G and float(b[k]["g_eff_m_per_s2"]) == G
        assert float(a[k]["frequency_Hz"]) == pytest.approx(np.sqrt(2) * float(b[k]["frequency_Hz"]), rel=1e-6)
        assert float(a[k]["mass_kg"]) == pytest.approx(float(b[k]["mass_kg"]), rel=1e-6)   # masses do not depend on g
