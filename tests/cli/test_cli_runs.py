"""Good scenarios through the command line: exit 0, results.h5 with the documented layout, and
physics checked against independent closed forms (free fall, Newton's second law, 1-D waves)."""
from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest

from liftoff.workflows.cli import main

from .conftest import M1, M2, base_scenario, write_scenario

from ..roundoff import sum_rtol

REPO = Path(__file__).resolve().parents[2]
EXAMPLES = REPO / "examples"
G = 9.81

# datasets every results.h5 carries (docs/transient-cli.md, "Results file")
DATASETS = ["time", "iterations", "contact/names", "contact/labels", "contact/force", "contact/state",
            "contact/separation_time", "contact/recontact_count", "contact/release_time",
            "body_a/output_labels", "body_a/displacement", "body_a/velocity", "body_a/acceleration",
            "body_b/output_labels", "body_b/displacement", "body_b/velocity", "body_b/acceleration"]


def _check_layout(path: Path) -> h5py.File:
    f = h5py.File(path, "r")
    assert f.attrs["format"] == "liftoff-transient-result"
    for name in DATASETS:
        assert name in f, name
        assert "units" in f[name].attrs, name
    n_t = f["time"].shape[0]
    assert f["contact/force"].shape == (n_t, f["contact/labels"].shape[0])
    assert f["contact/state"].shape == (n_t, f["contact/names"].shape[0])
    for b in ("body_a", "body_b"):
        assert f[f"{b}/displacement"].shape == (n_t, f[f"{b}/output_labels"].shape[0])
    assert f["time"].attrs["units"] == "s" and f["contact/force"].attrs["units"].startswith("N")
    return f


def _liftoff(args: list[str]) -> subprocess.CompletedProcess:
    exe = Path(sys.executable).with_name("liftoff")
    cmd = [str(exe)] if exe.exists() else [sys.executable, "-m", "liftoff.workflows.cli"]
    return subprocess.run(cmd + args, capture_output=True, text=True, timeout=300)


def test_fixture_scenario_runs(case_dir: Path, capsys):
    """The fixture that test_bad_input breaks is itself valid: static preload = weight, lift-off after release."""
    out = case_dir / "out"
    code = main(["transient", str(write_scenario(case_dir, base_scenario())), "--out", str(out), "--no-progress"])
    text = capsys.readouterr().out
    assert code == 0
    assert f"results  {out / 'results.h5'}" in text and "post" in text
    with _check_layout(out / "results.h5") as f:
        fz = f["contact/force"][0, 1]          # axial column, force on the vehicle (N)
        # statics: the post carries the vehicle weight (m1 + m2) g; 1e-9: a linear solve in double precision
        assert fz == pytest.approx((M1 + M2) * G, rel=1e-9)
        t, state = f["time"][()], f["contact/state"][:, 0]
        assert np.all(state[t < 0.005] == 0)                  # bolted until the release time
        assert 0.005 <= f["contact/separation_time"][0] < 0.02   # thrust 2000 N > weight 392 N: it lifts off
        assert np.all(f["contact/force"][state == 2] == 0.0)  # no force while open


def test_python_m_entry_point(tmp_path: Path):
    """`python -m liftoff.workflows.cli` works; a missing required option is an argparse error (exit 2)."""
    proc = subprocess.run([sys.executable, "-m", "liftoff.workflows.cli", "--help"], capture_output=True, text=True)
    assert proc.returncode == 0 and "transient" in proc.stdout
    proc = subprocess.run([sys.executable, "-m", "liftoff.workflows.cli", "transient"], capture_output=True, text=True)
    assert proc.returncode == 2 and "--out" in proc.stderr


def test_example_drop_rod(tmp_path: Path):
    """Free fall: the rod (at rest, gap 50 mm + block sag 4.905e-5 m) hits the block at sqrt(2 s0 / g)."""
    proc = _liftoff(["transient", str(EXAMPLES / "drop_rod" / "scenario.toml"), "--out", str(tmp_path),
                     "--no-progress"])
    assert proc.returncode == 0, proc.stderr
    with _check_layout(tmp_path / "results.h5") as f:
        t, state = f["time"][()], f["contact/state"][:, 0]
        h = t[1] - t[0]
        first = t[np.flatnonzero(state == 1)[0]]
        s0 = 0.05 + 5.0 * G / 1.0e6
        # closing is detected at the end of the step in which it happens: within one step after
        assert 0.0 <= first - math.sqrt(2 * s0 / G) <= h
        assert np.all(f["contact/force"][state == 2] == 0.0)          # no force while open
        assert np.all(f["contact/force"][:, 0] >= 0.0)                # compression only (on the rod: +z)


def test_example_rod_impact(tmp_path: Path):
    """1-D waves: plateau rho c A v0 / 2, duration 2L/c, velocities exchanged (tolerances: 100 modes)."""
    proc = _liftoff(["transient", str(EXAMPLES / "rod_impact" / "scenario.toml"), "--out", str(tmp_path),
                     "--no-progress"])
    assert proc.returncode == 0, proc.stderr
    L, E, rho, A, v0 = 1.0, 70e9, 2700.0, 1e-3, 2.0
    c, m = math.sqrt(E / rho), rho * A * L
    T = 2 * L / c
    with _check_layout(tmp_path / "results.h5") as f:
        t, F = f["time"][()], -f["contact/force"][:, 0]               # force on A is -x: compression > 0
        plateau = F[(t > 0.2 * T) & (t < 0.8 * T)].mean()
        closed = t[np.flatnonzero(f["contact/state"][:, 0] == 1)[0]]
        duration = f["contact/separation_time"][0] - closed
        va, vb = f["body_a/modal_v"][-1, 0] / math.sqrt(m), f["body_b/modal_v"][-1, 0] / math.sqrt(m)
    # the Gibbs ripple of a 100-mode series averages out over the middle 60 % of the plateau: 2 %
    assert plateau == pytest.approx(rho * c * A * v0 / 2, rel=0.02)
    # the wave front is smeared over ~L/N per passage: 2/N of 2L/c
    assert duration == pytest.approx(T, rel=2.0 / 100)
    assert abs(va) < 0.02 * v0 and vb == pytest.approx(v0, rel=0.02)


def test_example_vehicle_on_pad(tmp_path: Path):
    """Statics: the posts carry the weight; after lift-off, Newton: z'' of the c.g. = (1.3 W - W) / m."""
    proc = _liftoff(["transient", str(EXAMPLES / "vehicle_on_pad" / "scenario.toml"), "--out", str(tmp_path),
                     "--no-progress"])
    assert proc.returncode == 0, proc.stderr
    assert "holddown_1" in proc.stdout
    mass = 50e3
    with _check_layout(tmp_path / "results.h5") as f:
        axial = [0, 3, 6, 9]
        # 1e-9: a linear static solve; the posts carry the weight (thrust is 0 at t = 0)
        assert f["contact/force"][0, axial].sum() == pytest.approx(mass * G, rel=1e-9)
        sep = f["contact/separation_time"][()]
        assert np.all((sep >= 0.5) & (sep < 0.6)), sep
        t, z = f["time"][()], f["body_a/rigid_body_motion"][:, 2]
        late = t > 0.8
        assert np.all(f["contact/state"][late] == 2)                  # flying free
        # rigid-body motion is exact for forces linear over a step: quadratic in t, a = 0.3 g
        acc = 2 * np.polyfit(t[late], z[late], 2)[0]
        assert acc == pytest.approx(0.3 * G, rel=1e-6)


def test_example_docking(tmp_path: Path):
    """Two free-free modules: momentum of the pair kept (round-off), all four latches captured,
    the pair's c.g. moving on at m_a v_a / (m_a + m_b); oriented normals written with the result."""
    proc = _liftoff(["transient", str(EXAMPLES / "docking" / "scenario.toml"), "--out", str(tmp_path),
                     "--no-progress"])
    assert proc.returncode == 0, proc.stderr
    assert "latch_4 captured at" in proc.stdout
    m = 6000.0
    with _check_layout(tmp_path / "results.h5") as f:
        assert (f["contact/state"][-1] == 0).all()                    # all latched (bolted)
        assert f["contact/direction/component"][0].decode() == "n"
        np.testing.assert_allclose(f["contact/direction/vector"][0], [-math.sqrt(3) / 2, -0.5, 0.0], atol=1e-11)
        meta = json.loads(f.attrs["metadata"])
        assert all(t is not None for t in meta["capture_time"].values())
        # rigid-body motion about each body's c.g.: translation velocity by differences of positions
        t = f["time"][()]
        xa, xb = f["body_a/rigid_body_motion"][:, 0], f["body_b/rigid_body_motion"][:, 0]
    # momentum: the pair's c.g. moves at 0.15 m / (2 m) = 0.075 m/s at every step (linear in t, round-off
    # of the exact rigid-mode steps; 1e-10 for the differences of positions)
    xcg = (xa + xb) / 2
    np.testing.assert_allclose(np.diff(xcg) / np.diff(t), 0.075, rtol=1e-10)


def test_ground_rigid_bolt_modal_force_and_recovery(case_dir: Path, capsys):
    """Body b = ground with a rigid (Lagrange) bolt; a [[modal_force]] CSV equal to Phi_row^T F(t) must act
    exactly like the [[force]] table it replaces; a [[recovery]] row equal to the phi row of top:Tz must
    reproduce the top:Tz displacement output."""
    from .conftest import vehicle_body

    veh = vehicle_body()
    row = veh.rows(["top:Tz"])[0]
    table = np.array([[0.0, 0.0], [0.004, 0.0], [0.006, 2000.0], [0.02, 2000.0]])
    with open(case_dir / "modal.csv", "w") as fh:
        fh.write("time," + ",".join(f"q{i}" for i in range(veh.n_modes)) + "\n")
        for t, F in table:
            fh.write(f"{t!r}," + ",".join(repr(x) for x in row * F) + "\n")
    np.savez(case_dir / "rec.npz", labels=np.array(["top_z"]), disp=row[None, :], units=np.array("m"))
    runs = {}
    for variant in ("force", "modal"):
        data = base_scenario()
        data["bodies"]["b"] = "ground"
        data["contact"][0].pop("labels_b")
        data["contact"][0].pop("stiffness")
        data["contact"][0]["rigid"] = True
        data["output"].pop("b")
        data["recovery"] = [{"name": "top_z", "body": "a", "file": "rec.npz"}]
        if variant == "modal":
            data["force"] = data["force"][1:]
            data["modal_force"] = [{"body": "a", "csv": "modal.csv"}]
        out = case_dir / variant
        assert main(["transient", str(write_scenario(case_dir, data, f"{variant}.toml")), "--out", str(out),
                     "--no-progress"]) == 0, capsys.readouterr().err
        with _check_layout(out / "results.h5") as f:
            runs[variant] = {k: f[k][()] for k in ("contact/force", "body_a/displacement", "recovered/top_z")}
            assert f["recovered/top_z"].attrs["units"] == "m"
    for k in runs["force"]:
        # the same modal load, summed in a different order: round-off, accumulated over the steps
        n_t = runs["force"][k].shape[0]
        np.testing.assert_allclose(runs["modal"][k], runs["force"][k], rtol=1e-9,
                                   atol=sum_rtol(n_t) * np.abs(runs["force"][k]).max())
    # rigid bolt on ground: static preload = weight (exact Lagrange multiplier)
    assert runs["force"]["contact/force"][0, 1] == pytest.approx((M1 + M2) * G, rel=1e-9)
    # the same 3-term dot product (3 modes) in another order; its terms (rigid drift and elastic
    # part) are within 1e2 of the result here
    x = runs["force"]["body_a/displacement"][:, 0]
    np.testing.assert_allclose(runs["force"]["recovered/top_z"][:, 0], x, rtol=0, atol=100 * sum_rtol(3) * np.abs(x).max())


def test_gravity_softening_is_wired_and_softens():
    """[softening] enabled = true adds KSOF (transient.effects.softening_matrix, eq. 27) as a feedback on
    body a until `until`; in statics under a side load it increases the lateral c.g. deflection
    (the reference's Table 1: gravity softening adds deflection). The older spelling in [gravity]
    (softening = true, softening_until) gives the same feedback."""
    import copy
    import tomllib

    from liftoff.transient import static_equilibrium
    from liftoff.transient.effects import cg_motion_matrix, softening_matrix
    from liftoff.config import parse_twobody

    base = EXAMPLES / "vehicle_on_pad"
    data = tomllib.loads((base / "scenario.toml").read_text())
    data["force"] = [{"body": "a", "label": "top:Tx", "value": 2.0e4}]
    cg_x = {}
    for soft in (False, True):
        d = copy.deepcopy(data)
        if soft:
            d["softening"] = {"enabled": True, "until": 0.5}
        p = parse_twobody(d, base, "scenario.toml").problem
        if soft:
            (fb,) = p.forcing.feedback
            assert fb.body == "a" and fb.until == 0.5
            np.testing.assert_array_equal(fb.dense()[0], softening_matrix(p.body_a, [0.0, 0.0, -G]))
            old = copy.deepcopy(data)
            old["gravity"].update(softening=True, softening_until=0.5)
            (fb_old,) = parse_twobody(old, base, "scenario.toml").problem.forcing.feedback
            assert fb_old.until == 0.5 and np.array_equal(fb_old.dense()[0], fb.dense()[0])
        else:
            assert p.forcing.feedback == []
        st = static_equilibrium(p.body_a, p.body_b, p.contacts, p.forcing)
        cg_x[soft] = (cg_motion_matrix(p.body_a) @ st.q_a)[0]
    assert cg_x[False] > 0 and cg_x[True] > cg_x[False]


def test_method_override_fixed_point_agrees_with_direct(tmp_path: Path, capsys):
    """--method fixed-point runs the reference's iteration (eq. 11, tol 1 N from [time]); at h = 0.25/f_h
    (rho(K_C W) < 1) it converges to the direct solve's contact forces within a few tol."""
    scenario = str(EXAMPLES / "vehicle_on_pad" / "scenario.toml")
    forces, methods = {}, {}
    for method in ("direct", "fixed-point"):
        out = tmp_path / method
        assert main(["transient", scenario, "--out", str(out), "--method", method, "--no-progress"]) == 0
        assert f"method {method}," in capsys.readouterr().out
        with h5py.File(out / "results.h5", "r") as f:
            forces[method] = f["contact/force"][()]
            methods[method] = json.loads(f.attrs["metadata"])["method"]
    assert methods == {"direct": "direct", "fixed-point": "fixed-point"}
    # the iteration stops when successive forces differ by < tol = 1 N, with a contraction factor
    # below 1 the remaining error is a few tol; the peak force is 1.6e5 N
    assert np.abs(forces["fixed-point"] - forces["direct"]).max() < 10.0


def test_axial_by_name_auto_step_and_sections(case_dir: Path):
    """The normal direction may be named by label or component; h = "auto" is the default
    0.25/f_h; [time] tol/max_iter reach the problem (the sections liftoff run reads too)."""
    from liftoff.config import parse_twobody

    axes = []
    for axial in (1, "Tz", "base:Tz"):
        data = base_scenario()
        data["contact"][0]["axial"] = axial
        data["time"].update(h="auto", tol=0.5, max_iter=7)
        p = parse_twobody(data, case_dir, "s.toml").problem
        assert p.h is None and p.tol == 0.5 and p.max_iter == 7
        axes.append(p.contacts[0].axial)
    assert axes == [1, 1, 1]


def test_contact_free_modal_transient(case_dir: Path, capsys):
    """Without [[contact]] the same engine runs a plain modal transient: the free-free two-mass
    vehicle under a constant axial force F on its top mass accelerates as a rigid body,
    x_cg = F t^2 / (2 (m1 + m2)) (the elastic mode averages out of the c.g.)."""
    data = base_scenario()
    for key in ("contact", "gravity"):
        del data[key]
    data["bodies"]["b"] = "ground"
    data["force"] = [{"body": "a", "label": "top:Tz", "value": 100.0}]
    data["initial"] = {"mode": "zero"}
    data["output"] = {"a": ["top:Tz", "base:Tz"]}
    out = case_dir / "free"
    assert main(["transient", str(write_scenario(case_dir, data)), "--out", str(out), "--no-progress"]) == 0
    with h5py.File(out / "results.h5") as f:
        t, d = f["time"][()], f["body_a/displacement"][()]
        assert f["contact/force"].shape == (t.size, 0)
    x_cg = (M1 * d[:, 1] + M2 * d[:, 0]) / (M1 + M2)
    assert np.allclose(x_cg, 100.0 * t ** 2 / (2 * (M1 + M2)), rtol=1e-9, atol=1e-15)
