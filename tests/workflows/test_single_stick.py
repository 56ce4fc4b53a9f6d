"""The single-stick example (examples/single_stick): a two-stage launcher described as
components of registered types (two tank stages, the user's .geo interstage and fairing, a
Nastran Craig-Bampton payload) on the user's .geo launch table, end to end.

Its files are what make_files.py writes; ``liftoff run`` gives the payload interface
loads; the vehicle's first free-free bending frequency agrees with a second method, a
Timoshenko beam (stick) model of the same stack built here from closed forms: the tank
stages' wall sections and propellant (meshes.tank's closed forms of TankParams), the
barrels' sections and the payload's tube, all joints rigid (plane sections).

Tolerance of the bending check: the stick is stiffer by construction (its joints keep plane
sections; the FE joins the stages at four patches and tied arcs, whose walls ovalise, and
its domes are not annuli). On the first stage alone the FE (P1, 0.9 m) is 2.7 % below the
stick (3.386 vs 3.479 Hz); on the stack 3.0 % (1.916 vs 1.975 Hz). The FE is asserted
within [0.94, 1.0] of the stick: twice the measured gap, and never above it.
"""
from __future__ import annotations

import csv
import importlib.util
import json
import re
import runpy
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "examples" / "single_stick"


def test_example_files_are_what_make_files_writes(tmp_path):
    pytest.importorskip("pyyeti.nastran")
    runpy.run_path(str(EXAMPLE / "make_files.py"), run_name="make_files")["main"](tmp_path)
    for name in ("interstage.geo", "fairing.geo", "pad.geo"):
        assert (EXAMPLE / name).read_text() == (tmp_path / name).read_text(), name
    from liftoff.reduction.nastran import import_nastran

    grids = {1: "payload_if", 2: "payload_top"}
    a, b = (import_nastran(p / "payload.pch", name="payload", units="in-lbf-s", grid_names=grids)
            for p in (EXAMPLE, tmp_path))
    # the same beam and eigensolve, written to 10 significant digits: agree to 1e-9
    np.testing.assert_allclose(a.fixed_freq_hz, b.fixed_freq_hz, rtol=1e-9)
    np.testing.assert_allclose(a.M_B, b.M_B, rtol=0, atol=1e-9 * np.abs(b.M_B).max())
    np.testing.assert_allclose(a.K_B, b.K_B, rtol=0, atol=1e-9 * np.abs(b.K_B).max())


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    pytest.importorskip("dolfinx")
    pytest.importorskip("pyyeti.nastran")
    out = tmp_path_factory.mktemp("single_stick") / "out"
    cache = tmp_path_factory.getbasetemp() / "single_stick_cache"
    p = subprocess.run([sys.executable, "-m", "liftoff.workflows.cli", "run", str(EXAMPLE / "scenario.toml"),
                        "--out", str(out), "--cache", str(cache), "--no-snapshots", "--no-progress"],
                       capture_output=True, text=True, timeout=1800)
    assert p.returncode == 0, p.stderr[-3000:]
    return out, p


def _figures_module():
    spec = importlib.util.spec_from_file_location("single_stick_figures",
                                                  ROOT / "benchmarks" / "single_stick_figures.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_first_bending_against_a_timoshenko_stick(run):
    out, _ = run
    figures = _figures_module()
    fig = figures.figures_of_run(out)
    f = figures.stick_of_example().frequencies()
    assert f[0] < 1e-2 and f[1] < 1e-2           # the two rigid-body modes of the plane
    # the closed forms' mass against the meshed one: faceting of the domes, ~0.2 %
    assert abs(fig["vehicle_mass_kg"] / fig["stick_mass_kg"] - 1) < 5e-3
    assert 0.94 <= fig["first_bending_fe_hz"] / fig["first_bending_stick_hz"] <= 1.0, fig
    # the figures docs/workflow.md shows (docs/figures/single_stick.json) are this run's
    df = importlib.util.spec_from_file_location("default_figures", ROOT / "benchmarks" / "default_figures.py")
    dmod = importlib.util.module_from_spec(df)
    df.loader.exec_module(dmod)
    checked_in = json.loads(figures.JSON.read_text())
    diff = dmod.differences(json.loads(json.dumps(fig)), checked_in)
    assert not diff, f"run `python benchmarks/single_stick_figures.py`: {diff}"


def test_example_runs_end_to_end_with_payload_interface_loads(run):
    out, p = run
    lines = [line for line in (out / "interface_loads_nominal.csv").open() if not line.startswith("#")]
    interfaces = {r["interface"] for r in csv.DictReader(lines)}
    assert "attach payload_if on payload" in interfaces, interfaces
    peaks = {}
    for case in ("nominal", "controlled-release"):
        rows = {r[0]: r for r in csv.reader(line for line in (out / f"maxmin_{case}.csv").open()
                                            if not line.startswith("#"))}
        peaks[case] = float(rows["load factor payload Nz"][2])
        assert float(rows["attach payload_if on payload Tz"][2]) > 0
    # every case lifts off (the clamps separate), and the controlled release halves the
    # payload's axial load factor of the instantaneous one (4.46 vs 2.19 g when written)
    summary = (out / "summary.txt").read_text()
    separations = [float(x) for x in re.findall(r"clamp_1\s+2\.500\s+([0-9.]+)", summary)]
    assert len(separations) == 2 and all(2.5 <= t < 4.5 for t in separations), separations
    assert peaks["controlled-release"] < 0.75 * peaks["nominal"], peaks
