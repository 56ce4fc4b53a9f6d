"""The kernel recovers its outputs for blocks of OUT_BLOCK steps at once (one matrix-matrix
product per body and kind, transient/kernel.py ``_outputs_block``) instead of one
matrix-vector product a step. Every output row must still be L x of its own step: checked
against the modal histories of the same run (keep_modal), for chunks that end inside a
block and runs shorter than one block."""
from dataclasses import replace

import numpy as np
import pytest

from liftoff.transient import Forcing, Recovery, TabulatedForce, TransientProblem, solve
from liftoff.transient import solver
from liftoff.transient.examples import holddown_contacts, toy_pad, toy_vehicle
from liftoff.transient.kernel import OUT_BLOCK

EPS = np.finfo(float).eps


def _problem(n_steps: int) -> TransientProblem:
    veh, pad = toy_vehicle(), toy_pad()
    h = 1e-4
    t_end = n_steps * h
    contacts = holddown_contacts(release_time=0.4 * t_end)
    rng = np.random.default_rng(11)
    la, lb = veh.dof_labels[:5], pad.dof_labels[:3]
    recs = [Recovery("mixed", "a", ["r0", "r1", "r2"], disp=rng.normal(size=(3, veh.n_modes)),
                     vel=rng.normal(size=(3, veh.n_modes)), acc=rng.normal(size=(3, veh.n_modes))),
            Recovery("pad_acc", "b", ["p0", "p1"], acc=rng.normal(size=(2, pad.n_modes)))]
    thrust = TabulatedForce("a", veh.dof_labels[2], [0.0, 0.5 * t_end, t_end], [0.0, 3e6, 3e6])
    return TransientProblem(veh, pad, contacts, Forcing(tables=[thrust], gravity=(0.0, 0.0, -9.81)), t_end, h=h,
                            initial="static", outputs={"a": list(la), "b": list(lb)}, recoveries=recs,
                            keep_modal=True, progress=False)


def _check(res, problem) -> None:
    """Each output history against L x from the modal histories; the two differ only by the
    order of the sums (BLAS-3 against numpy's matrix product here): |dy| <= 2 n eps |L| |x|
    per entry, n the modes summed (the standard bound of a dot product, twice)."""
    for key, body in (("a", problem.body_a), ("b", problem.body_b)):
        q, v, acc = (res.modal[f"{k}_{key}"] for k in ("q", "v", "acc"))
        n = body.n_modes
        for kind, x in (("displacement", q), ("velocity", v), ("acceleration", acc)):
            L = body.phi[[body.dof_index(lab) for lab in problem.outputs[key]]]
            y = getattr(res, kind)[key]
            bound = 2 * n * EPS * (np.abs(x) @ np.abs(L).T)
            assert np.all(np.abs(y - x @ L.T) <= bound + 1e-300), (key, kind)
    for r in problem.recoveries:
        q, v, acc = (res.modal[f"{k}_{r.body}"] for k in ("q", "v", "acc"))
        ref = np.zeros((q.shape[0], len(r.labels)))
        bound = np.zeros_like(ref)
        for mat, x in ((r.disp, q), (r.vel, v), (r.acc, acc)):
            if mat is not None:
                ref += x @ mat.T
                bound += 2 * x.shape[1] * EPS * (np.abs(x) @ np.abs(mat).T)
        assert np.all(np.abs(res.recovered[r.name] - ref) <= 3 * bound + 1e-300), r.name


@pytest.mark.parametrize("n_steps, chunk", [(3 * OUT_BLOCK + 17, solver.CHUNK), (3 * OUT_BLOCK + 17, 50),
                                            (OUT_BLOCK - 5, solver.CHUNK), (2 * OUT_BLOCK, OUT_BLOCK)])
def test_block_outputs_are_each_steps_own(monkeypatch, n_steps, chunk):
    monkeypatch.setattr(solver, "CHUNK", chunk)
    problem = _problem(n_steps)
    res = solve(problem)
    assert res.time.size == n_steps + 1 and np.isfinite(res.separation_time).any()   # the run released and lifted off
    _check(res, problem)
    assert np.abs(res.displacement["a"][1:]).min(axis=0).max() > 0     # no row left unwritten (zero)


def test_zero_rows_are_skipped():
    """Rows that are zero throughout (a recovery component no mode loads) are not handed to
    the kernel (OutputPlan.kernel_rows); the kernel zeroes each output row before it adds
    the products, so their targets stay exactly 0, and every other history is still L x of
    its step (the same bound as above: with fewer rows in a product, BLAS may split it
    otherwise, so the bits may differ from a run with the zero rows; the default's did not)."""
    problem = _problem(2 * OUT_BLOCK + 9)
    rec = problem.recoveries[0]
    rec.disp[1] = 0.0                            # "r1": zero on q and v, loaded on acc
    rec.vel[1] = 0.0
    zero = Recovery("zero", "a", ["z0", "z1"], disp=np.zeros((2, problem.body_a.n_modes)))
    problem = replace(problem, recoveries=[*problem.recoveries, zero])
    plan = solver.output_plan(problem, "a")
    L, kind, targ = plan.kernel_rows()
    assert L.shape[0] == plan.L.shape[0] - 4 and np.all(np.any(L != 0, axis=1))
    assert np.all(np.diff(kind) >= 0)                                  # still grouped by kind
    res = solve(problem)
    _check(res, problem)
    assert np.all(res.recovered["zero"] == 0.0)
    assert np.all(np.abs(res.recovered["mixed"][1:]).min(axis=0) > 0)   # "r1" (acc only) recovered
