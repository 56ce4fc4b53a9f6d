"""Converged loads (issue 22) on the stick stack: the static start of the transient (section
2.6) against the static solve of the un-truncated CB models (the assembled vehicle and pad
and the posts as springs, physical DOFs, numpy: no modes), with every system mode, with a
cut and residual vectors, and with a cut alone; the truncation check in the run's summary
and results metadata."""
import json
import tomllib

import numpy as np
import pytest

from liftoff.reduction import label_transform, system_rb
from liftoff.reduction.system import rigid_inertia
from liftoff.transient import load_result, static_equilibrium
from liftoff.workflows.cache import StageCache
from liftoff.workflows.cli import main
from liftoff.workflows.loads import build_problem
from liftoff.workflows.pipeline import build_stack
from liftoff.config import default_text, parse_scenario

from ..roundoff import solve_rtol
from .test_run import _toml

STICK = {"source": "stick", "mesh_size": 6.0, "zeta": 0.01}
CUT = {"f_max": 15.0, "pad_f_max": 40.0}


def case_of(system: dict, **over):
    d = tomllib.loads(default_text())
    d["model"] = {**STICK, "system": system}
    d.pop("case")
    d["softening"] = {"enabled": False}      # KSOF is modal feedback: no physical-DOF counterpart here
    d["control"] = {"enabled": False}
    d.update(over)
    return parse_scenario(d, "test.toml").cases[0]


def physical_static(stack, cp) -> tuple[np.ndarray, float]:
    """The vehicle's boundary displacements in static equilibrium at t0 from the assembled CB
    stiffness of vehicle and pad with the posts' K_C between their labels; loads: gravity
    M RB g on both, the constant forces (cryo) and the tables at t0 on the vehicle.
    Returns (displacements at the vehicle's body labels, cond of the coupled K)."""
    pr = cp.problem
    va, pa = stack.vehicle_asm, stack.pad_asm
    nv, n = va.n_dof, va.n_dof + pa.n_dof
    K = np.zeros((n, n))
    K[:nv, :nv], K[nv:, nv:] = va.K, pa.K
    for c in pr.contacts:
        for la, lb, k in zip(c.labels_a, c.labels_b, c.stiffness):
            d = np.zeros(n)
            d[va.boundary_dof(la)], d[nv + pa.boundary_dof(lb)] = 1.0, -1.0
            K += k * np.outer(d, d)
    g = np.asarray(pr.forcing.gravity, float)
    # (the grounded pad's gravity: its own rigid-body field's loads, reduction.system.rigid_inertia)
    F = np.concatenate([va.M @ system_rb(va)[:, :3] @ g, rigid_inertia(pa)[0][:, :3] @ g])
    for p in pr.forcing.constant:
        F[va.boundary_dof(p.label)] += p.value
    for tb in pr.forcing.tables:
        F[va.boundary_dof(tb.label)] += np.interp(pr.t0, tb.time, tb.value)
    x = np.linalg.solve(0.5 * (K + K.T), F)
    return label_transform(va, pr.body_a.dof_labels) @ x[:nv], float(np.linalg.cond(K))


@pytest.mark.parametrize("system, exact", [({}, True), ({**CUT, "residual_vectors": True}, True),
                                           ({**CUT, "residual_vectors": False}, False)],
                         ids=["all modes", "cut + residual vectors", "cut"])
def test_static_start_is_the_cb_static_solve(system, exact):
    case = case_of(system)
    stack = build_stack(case.model, StageCache(None), progress=False)
    cp = build_problem(case, stack, progress=False)
    pr = cp.problem
    st = static_equilibrium(pr.body_a, pr.body_b, pr.contacts, pr.forcing, pr.t0)
    modal = pr.body_a.phi @ st.q_a
    ref, cond = physical_static(stack, cp)
    err = np.abs(modal - ref).max() / np.abs(ref).max()
    tol = solve_rtol(cond, ref.size)
    vcheck, pcheck = cp.truncation
    print(f"{stack.vehicle.n_modes} + {stack.pad.n_modes} modes: static start vs CB static solve {err:.1e} "
          f"(bound {tol:.1e}); {vcheck.line()}; {pcheck.line()}")
    if exact:               # every mode kept, or residual vectors: the static start is exact
        assert err <= tol
        assert vcheck.static_error <= tol and pcheck.static_error <= tol
        if vcheck.n_residual:   # ... but the check counts the eigenmodes: a cut is still a cut
            assert not vcheck.ok and "with the residual vectors" in vcheck.line()
        else:
            assert vcheck.flex_error <= tol and pcheck.flex_error <= tol
    else:
        assert err > 0.01
        assert not vcheck.ok and vcheck.warning() and "residual vectors" in vcheck.warning()


def test_run_reports_the_truncation_check(tmp_path, capsys):
    d = tomllib.loads(default_text())
    d["model"] = {**STICK, "system": {**CUT, "residual_vectors": False}}
    d["time"]["t_end"] = 7.0
    d["case"] = [{"name": "nominal"}]
    p = tmp_path / "cut.toml"
    p.write_text(_toml(d))
    assert main(["run", str(p), "--out", str(tmp_path / "out"), "--no-snapshots", "--no-progress",
                 "--no-error-estimate"]) == 0
    text = (tmp_path / "out" / "summary.txt").read_text()
    assert "modes kept (truncation check" in text
    assert "warning: vehicle: the kept modes miss" in text and "warning: pad" in text
    meta = load_result(tmp_path / "out" / "results_nominal.h5").metadata["truncation"]
    assert [m["body"] for m in meta] == ["vehicle", "pad"]
    assert not meta[0]["ok"] and meta[0]["flexibility_shortfall"] > 0.01 and meta[0]["f_cut_hz"] <= 15.0
    json.dumps(meta)                                              # plain JSON in the results file
    # the same with every mode: no warning, the shortfall is round-off
    d["model"] = STICK
    p.write_text(_toml(d))
    assert main(["run", str(p), "--out", str(tmp_path / "all"), "--no-snapshots", "--no-progress",
                 "--no-error-estimate"]) == 0
    text = (tmp_path / "all" / "summary.txt").read_text()
    assert "vehicle: all " in text and "warning:" not in text
    # --no-error-estimate: the summary says the step is not checked, and claims no estimate (issue 27)
    assert "step: not checked" in text and "Richardson" not in text and "no step-error estimate" in text
    meta = load_result(tmp_path / "all" / "results_nominal.h5").metadata["truncation"]
    assert all(m["ok"] and m["f_cut_hz"] is None and m["flexibility_shortfall"] < 1e-6 for m in meta)
