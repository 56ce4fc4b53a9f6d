"""Cases marched together (liftoff.transient.batch.solve_batch) against the same cases solved
one by one (liftoff.transient.solve): the independent reference is the one-by-one kernel,
its arithmetic written differently (per-case matrix-vector products, the end-of-step state
formed, the loads as tables, the accelerations formed).

The two orders of summation cannot agree bit for bit, and how far apart they may land is
the problem's own rounding sensitivity: the contact force is K_C times the small
difference of the two bodies' large displacements at a post. It is measured here, not
assumed: the same case solved one by one with the vehicle's elastic modes in reverse
order (an equivalent problem, the same sums in another order) sets the scale, and the
batch must land within ten times that spread (or 1e-12 of the peak, whichever is larger);
events (separation, recontact, the contact states) must be the same."""
import math
from dataclasses import replace

import numpy as np
import pytest

from liftoff.core.errors import InputError
from liftoff.transient import Forcing, ModalBody, TabulatedForce, TransientProblem, solve
from liftoff.transient.batch import solve_batch
from liftoff.transient.effects import softening_factors
from liftoff.transient.examples import holddown_contacts, toy_pad, toy_vehicle
from liftoff.transient.model import ModalFeedback

G = (0.0, 0.0, -9.81)
RELEASE = 0.25


def _reversed_elastic(body: ModalBody) -> ModalBody:
    """The same body with its elastic modes in reverse order (rigid ones kept first)."""
    nr = int(np.sum(body.omega == 0))
    perm = np.r_[np.arange(nr), np.arange(body.n_modes - 1, nr - 1, -1)]
    return replace(body, omega=body.omega[perm], zeta=body.zeta[perm], phi=body.phi[:, perm],
                   participation=body.participation[perm])


def _case(k: int, vehicle: ModalBody, pad: ModalBody, **kw) -> TransientProblem:
    """Case k: thrust scaled by 1 + 0.1 k at the top, posts released at RELEASE + 0.01 k, odd
    cases with gravity softening (a rank-3 feedback, eq. 27) and a lateral gust."""
    thrust = 1.4 * 50e3 * 9.81 * (1 + 0.1 * k)
    tables = [TabulatedForce("a", "top:Tz", [0.0, 0.2, 0.6], [0.0, thrust, thrust])]
    feedback = []
    if k % 2:
        tables.append(TabulatedForce("a", "top:Tx", [0.0, 0.1, 0.15, 0.6], [0.0, 2e3 * k, -1e3, 0.0]))
        U, V = softening_factors(vehicle, np.array(G))
        feedback = [ModalFeedback("a", U @ V, until=0.45, factors=(U, V))]
    contacts = holddown_contacts(4, stiffness=2e9, release_time=RELEASE + 0.01 * k)
    return TransientProblem(vehicle, pad, contacts, Forcing(tables=tables, gravity=G, feedback=feedback),
                            t_end=0.6, h=2e-4, outputs={"a": ["top:Tz", "post_1:Tz"], "b": ["pad_1:Tz"]},
                            progress=False, **kw)


def _peak(x: np.ndarray) -> float:
    return float(np.abs(x).max())


def _compare(batch, alone, permuted):
    """(largest batch - one-by-one difference, largest one-by-one reordering spread) of
    every history, each relative to its peak, over the cases; events must match."""
    worst, spread = 0.0, 0.0
    for rb, r1, rp in zip(batch, alone, permuted):
        assert np.array_equal(rb.contact_state, r1.contact_state)
        assert np.array_equal(rb.recontact_count, r1.recontact_count)
        assert np.allclose(rb.separation_time, r1.separation_time, equal_nan=True)
        pairs = [(rb.contact_force, r1.contact_force, rp.contact_force)]
        for key in "ab":
            for kind in ("displacement", "velocity", "acceleration"):
                pairs.append((getattr(rb, kind)[key], getattr(r1, kind)[key], getattr(rp, kind)[key]))
        pairs.append((rb.rigid_body_motion_a, r1.rigid_body_motion_a, rp.rigid_body_motion_a))
        for b, o, p in pairs:
            sc = max(_peak(o), 1e-300)
            worst = max(worst, _peak(b - o) / sc)
            spread = max(spread, _peak(p - o) / sc)
    return worst, spread


@pytest.mark.parametrize("static_above_hz", [None, 40.0])
def test_batch_equals_one_by_one(static_above_hz):
    """Five dispersed lift-offs (thrust, release time, softening, gust) of the toy vehicle on
    the toy pad, in groups of two (a partial group last), against each solved alone: every
    history within ten times the reordering spread (or 1e-12 of its peak), the same
    separations, recontacts and states. With the modes above 40 Hz static too."""
    vehicle, pad = toy_vehicle(), toy_pad()
    problems = [_case(k, vehicle, pad, static_above_hz=static_above_hz) for k in range(5)]
    batch = solve_batch(problems, group=2)
    alone = [solve(p) for p in problems]
    rev = _reversed_elastic(vehicle)
    permuted = [solve(_case(k, rev, pad, static_above_hz=static_above_hz)) for k in range(5)]
    assert all(np.isfinite(r.separation_time).all() for r in alone)       # every post opens: events covered
    worst, spread = _compare(batch, alone, permuted)
    print(f"batch vs one by one: {worst:.2e} of the peak; one by one, modes reordered: {spread:.2e}")
    assert worst <= max(10 * spread, 1e-12)
    assert len(batch) == 5 and batch[3].metadata["n_steps"] == alone[3].metadata["n_steps"]


def test_batch_refuses_what_it_cannot_share():
    """A batch shares the bodies, contacts and step; rigid rows, contact laws, an accuracy
    target and kept modal histories are refused with the field named."""
    vehicle, pad = toy_vehicle(), toy_pad()
    p0 = _case(0, vehicle, pad)
    with pytest.raises(InputError, match="batch problem 1: its body_a differs"):
        solve_batch([p0, _case(1, toy_vehicle(zeta=0.03), pad)])
    with pytest.raises(InputError, match="batch problem 1: t_end"):
        solve_batch([p0, replace(_case(1, vehicle, pad), t_end=0.5)])
    with pytest.raises(InputError, match="rigid contact rows"):
        solve_batch([replace(p0, contacts=holddown_contacts(4, rigid=True))])
    with pytest.raises(InputError, match="accuracy"):
        solve_batch([replace(p0, accuracy=1e-3)])
    with pytest.raises(InputError, match="keep_modal"):
        solve_batch([replace(p0, keep_modal=True)])
    with pytest.raises(InputError, match="contacts differ"):
        solve_batch([p0, replace(p0, contacts=holddown_contacts(4, stiffness=3e9, release_time=RELEASE))])
    # a later problem's contact laws (the kernel is built from problem 0's rows: they would be dropped)
    rubbing = [replace(c, friction=0.3) for c in p0.contacts]
    with pytest.raises(InputError, match="batch problem 1: friction, dashpots"):
        solve_batch([p0, replace(p0, contacts=rubbing)])
    # a body that differs only in its reference point (problem 0's rigid-body output rows would be used)
    moved = replace(vehicle, ref_point=np.asarray(vehicle.ref_point, float) + [0.0, 0.0, 1.0])
    with pytest.raises(InputError, match="batch problem 1: its body_a differs"):
        solve_batch([p0, replace(p0, body_a=moved)])
    assert solve_batch([]) == []
    assert math.isfinite(solve_batch([p0])[0].separation_time[0])


def _modes_inputs(rng, n=37, nc=5, m=3, kq=(4, 2), kv=(2, 0), na=22):
    """A step's inputs for _modes: 37 modes, 22 of body a (five blocks of four and two alone),
    15 of body b (three and three alone); kq, kv: each body's output rows on X_q and X_v."""
    S = rng.standard_normal((6, n))
    X = [rng.standard_normal((n, 8)) for _ in range(5)]     # Xq, Xv, Pc, F (nc rows), Y (m rows)
    X[3], X[4] = X[3][:nc].copy(), X[4][:m].copy()
    X[0][3, 2], X[1][4, 5], X[2][5, 1], X[3][1, 6] = -0.0, 5e-320, 1e-310, -0.0
    PhiT, Mq, Mv = rng.standard_normal((n, nc)), rng.standard_normal((n, m)), rng.standard_normal((n, m))
    R = (rng.standard_normal((na, kq[0])), rng.standard_normal((na, kv[0])),
         rng.standard_normal((n - na, kq[1])), rng.standard_normal((n - na, kv[1])))
    return np.ascontiguousarray(S.T), X, PhiT, Mq, Mv, R, na


def _pass(ST, X, PhiT, Mq, Mv, R, na, from_f):
    """_modes on the state X = [Xq, Xv, Pc, F, Y, E, O] (mutated)."""
    from liftoff.transient.batch import _modes
    _modes(ST, *X[:4], PhiT, Mq, Mv, X[4], X[5], na, R, X[6], from_f)


def _scratch(nc, R, K):
    return [np.full((nc, K), np.nan), tuple(np.full((r.shape[1], K), np.nan) for r in R)]


@pytest.mark.parametrize("kq, kv", [((4, 2), (2, 0)), ((0, 0), (0, 0)), ((3, 1), (1, 2))])
def test_full_group_step_is_the_rolled_loop_bit_for_bit(kq, kv):
    """A full group's pass over the modes (_modes8: four modes at a time, unrolled so it
    vectorizes; each body's last modes alone) against the rolled loop that partial groups take
    (the same eight cases as two groups of four), with Pc taken from the state and from F,
    with and without output rows: the same arithmetic in the same order, so equal bit for
    bit, including signed zeros and subnormals."""
    ST, X, PhiT, Mq, Mv, R, na = _modes_inputs(np.random.default_rng(7), kq=kq, kv=kv)
    nc = X[3].shape[0]
    full = [x.copy() for x in X] + _scratch(nc, R, 8)
    halves = [[np.ascontiguousarray(x[:, s]) for x in X] + _scratch(nc, R, 4) for s in (slice(0, 4), slice(4, 8))]
    for from_f in (False, True, True):
        _pass(ST, full, PhiT, Mq, Mv, R, na, from_f)
        for h in halves:
            _pass(ST, h, PhiT, Mq, Mv, R, na, from_f)
        for j in (0, 1, 2, 5):
            rolled = np.hstack([halves[0][j], halves[1][j]])
            assert np.array_equal(full[j].view(np.int64), rolled.view(np.int64))
        for o, a, b in zip(full[6], halves[0][6], halves[1][6]):
            assert np.array_equal(o.view(np.int64), np.hstack([a, b]).view(np.int64))


@pytest.mark.parametrize("K", [8, 3])
def test_step_over_the_modes_is_the_matrix_products(K):
    """_modes against the same step written as numpy's matrix products (Pc = Phi^T F, the
    load terms Mq Y and Mv Y, the sweep, E = Phi X_q, each body's output rows' Rq X_q and
    Rv X_v): equal to the round-off of sums of nc, m or n terms (here at most 37 terms of
    O(1): 1e-13 of the values' O(10) scale is far above the ~1e-15 such sums can differ by in
    another order, far below any error)."""
    ST, X, PhiT, Mq, Mv, R, na = _modes_inputs(np.random.default_rng(11))
    S = ST.T
    Xq, Xv, Pc, F, Y = (np.ascontiguousarray(x[:, :K]) for x in X)
    state = [Xq, Xv, Pc, F, Y] + _scratch(F.shape[0], R, K)
    Pc_ref = PhiT @ F
    Lq, Lv = Mq @ Y, Mv @ Y
    Xq_ref = S[0, :, None] * Xq + S[1, :, None] * Xv + S[2, :, None] * Pc_ref + Lq
    Xv_ref = S[3, :, None] * Xq + S[4, :, None] * Xv + S[5, :, None] * Pc_ref + Lv
    _pass(ST, state, PhiT, Mq, Mv, R, na, True)
    O_ref = (R[0].T @ Xq_ref[:na], R[1].T @ Xv_ref[:na], R[2].T @ Xq_ref[na:], R[3].T @ Xv_ref[na:])
    for got, ref in ((Pc, Pc_ref), (Xq, Xq_ref), (Xv, Xv_ref), (state[5], PhiT.T @ Xq_ref), *zip(state[6], O_ref)):
        assert np.max(np.abs(got - ref), initial=0.0) <= 1e-13 * max(1.0, np.max(np.abs(ref), initial=0.0))
    keep = Pc.copy()
    state[3] = F * 2.0
    _pass(ST, state, PhiT, Mq, Mv, R, na, False)     # from the state: F ignored, Pc kept
    assert np.array_equal(Pc, keep)


def test_results_taken_one_at_a_time_are_the_list_and_free_the_group():
    """solve_batch_iter marches every case before it returns (a refusal is raised there, as
    solve_batch raises it) and makes each result when taken: the same results, bit for bit,
    as solve_batch's; once every result of a group has been taken and let go, the group's
    output histories are freed (a weak reference to one of them dies)."""
    import gc
    import weakref

    from liftoff.transient import batch as B
    from liftoff.transient.batch import solve_batch_iter

    vehicle, pad = toy_vehicle(), toy_pad()
    problems = [_case(k, vehicle, pad) for k in range(3)]
    listed = solve_batch(problems, group=3)
    groups = []
    made = B._group_history

    def spy(*args):
        h = made(*args)
        groups.append(weakref.ref(h.Y_a))
        return h

    B._group_history = spy
    try:
        it = solve_batch_iter(problems, group=3)
    finally:
        B._group_history = made
    assert len(groups) == 1 and groups[0]() is not None     # marched, its histories held for the results
    for k, res in enumerate(it):
        ref = listed[k]
        assert np.array_equal(res.contact_force, ref.contact_force)
        for key in "ab":
            assert np.array_equal(res.displacement[key], ref.displacement[key])
            assert np.array_equal(res.acceleration[key], ref.acceleration[key])
        assert res.metadata["n_steps"] == ref.metadata["n_steps"]
        del res
    gc.collect()
    assert groups[0]() is None                              # every result taken and let go: the group freed
    bad = [_case(0, vehicle, pad), replace(_case(1, vehicle, pad), t_end=0.5)]
    with pytest.raises(InputError, match="t_end"):
        solve_batch_iter(bad)                               # refused at the call, not at the first result
