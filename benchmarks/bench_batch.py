"""The issue-28 proposal of marching a campaign's cases together, measured: K cases that
share both bodies (only their forcing differs) in one time loop whose products over all
modes are matrix-matrix products (BLAS-3), against the same K cases solved one by one
with ``liftoff.transient.solve``.

    .venv/bin/python benchmarks/bench_batch.py [--modes 3000 300] [--cases 64] [--repeat 2]

The batched kernel below does, case by case, what liftoff's kernel does (the same compiled
helpers: free step, candidate rows, active-set solve, end-of-step state), but takes
e_free = Q_free Phi_c^T, the contact loads F Phi_c and the outputs X L^T for all K cases at
once. It was built to be adopted and was not: on this 2-core machine (1 MiB L2) it is no
faster per case-step than one-by-one solves. A step streams every case's own modal
arrays (q, v, the free state, the loads: about ten of n each), which batching cannot
share; the shared matrices it reads once instead of K times are the smaller part, and the
K states no longer stay in cache. See README, "Benchmarks".

It also shows why "results equal to one-by-one solves to 1e-12 of the peak" is not a
property of the arithmetic: the contact forces of a bolted stack are K_C times small
differences of large modal displacements, so two summation orders of the same products
(BLAS-3 here, BLAS-2 there) differ by 1e-11 of the peak force after one step and more
after a release. The printed "contact force difference" is that measure.

Per case-step time: the slope of the wall time over two run lengths (500 and 2,500
steps), so the set-up (static solve, step choice) drops out; min of ``--repeat``.
"""
from __future__ import annotations

import argparse
import dataclasses
import os
import platform
import sys
import time as _time
import warnings
from pathlib import Path
from types import SimpleNamespace
from typing import NamedTuple

import liftoff  # noqa: F401 - before numpy: it picks the OpenBLAS kernels (liftoff/core/openblas.py)
import numpy as np
from numba import njit

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_transient import problem  # noqa: E402

from liftoff.core.errors import ConvergenceError, InputError  # noqa: E402
from liftoff.transient import TabulatedForce, solve  # noqa: E402
from liftoff.transient.assembly import contact_rows, modal_load  # noqa: E402
from liftoff.transient.coefficients import step_coefficients  # noqa: E402
from liftoff.transient.guard import GrowthGuard  # noqa: E402
from liftoff.transient.kernel import (OK, History, OutputRows, Stepping, _candidates, _feedback,  # noqa: E402
                                      _outputs_block, _post_step, _pre_step, _record_contact, _solve_direct)
from liftoff.transient.solver import (CHUNK, _contact_inputs, _failure, _modal_inputs, _new_cache,  # noqa: E402
                                      _result, _spectral_radius, _start, initial_contact_force, initial_state,
                                      output_plan)
from liftoff.transient.stepping import choose_step  # noqa: E402


#: History's kept-state fields, unused here (this kernel recovers its outputs every step)
NO_BLOCK = (np.zeros((3, 0, 0)), np.zeros((3, 0, 0)), np.zeros(1, dtype=np.int64))


class CaseData(NamedTuple):
    """What differs between the cases of a batch (:func:`march_batch`), case k in row k:
    their applied loads on one merged grid, feedback and release times. Shapes as in
    :class:`Modal` with a leading case axis."""

    const: np.ndarray    # (K, n) constant modal load
    Pk: np.ndarray       # (K, n_k, n) tabulated modal load on the shared grid Modal.tk
    U: np.ndarray        # (K, n, r) feedback factors (zero columns where a case has fewer terms)
    V: np.ndarray        # (K, r, 2 n)
    since: np.ndarray    # (K, r) s
    until: np.ndarray    # (K, r) s
    release: np.ndarray  # (K, ncon) s


class BatchState(NamedTuple):
    """:class:`State` of K cases, case k in row k (the reference's contact path only)."""

    q: np.ndarray        # (K, n)
    v: np.ndarray        # (K, n)
    f: np.ndarray        # (K, nc)
    active: np.ndarray   # (K, nc) bool
    Pc: np.ndarray       # (K, n)
    Pext: np.ndarray     # (K, n)
    ptr: np.ndarray      # (K,) int64


class BatchHistory(NamedTuple):
    """:class:`History` of K cases (no modal histories), case k first."""

    Y_a: np.ndarray      # (K, n_t, n_out_a)
    Y_b: np.ndarray      # (K, n_t, n_out_b)
    Fc: np.ndarray       # (K, n_t, nc)
    state: np.ndarray    # (K, n_t, ncon) int8
    iters: np.ndarray    # (K, n_t) int32


@njit(cache=False)
def _outputs_cases(L, kind, targ, X, Ytmp, Y, r):
    """Y[:, r] of every case: liftoff's block recovery (``_outputs_block``) with the K cases'
    q, v, acc as the block's rows (X (3, K, n_body)), one matrix-matrix product per kind."""
    if Y.shape[2] == 0:
        return
    _outputs_block(L, kind, targ, X, X.shape[1], Ytmp, 0)
    for k in range(X.shape[1]):
        for c in range(Y.shape[2]):
            Y[k, r, c] = Ytmp[k, c]


@njit(cache=False)
def march_batch(i0, i1, steps, modal, cases, contact, rows_out, state, cache, hist):
    """March K cases that share both bodies, their contact rows and outputs (``modal``,
    ``contact``, ``rows_out`` as for :func:`march`; the loads, feedback and release times of
    each case in ``cases`` :class:`CaseData`) through steps i0 -> i1, the direct active-set
    solve without contact laws. The modal update and the active-set solve are those of
    :func:`march`, case by case; the products over all modes are done for all cases at once
    (e_free = Q_free Phi^T, the contact loads F Phi and the outputs X L^T: BLAS-3 instead of
    one matrix-vector product per case). The pattern inverses are shared (the same W).
    Returns (status, step, info1, info2, case): the first case that failed, else -1."""
    t0, h, method, tol, max_iter = steps
    na, coef, w2, zw2, const0, tk, Pk0, U0, V0, since0, until0 = modal
    const, Pk, U, V, since, until, release = cases
    Phi_c, Cdiag, coff, dcontact, axial, nsign, release0, W, C2, laws = contact[:10]
    L_a, kind_a, targ_a, L_b, kind_b, targ_b = rows_out
    Q, Vel, F, active, Pc, Pext, ptr = state
    keys, invs, used = cache
    Y_a, Y_b, Fc, states, iters = hist
    K, n = Q.shape
    nc = F.shape[1]
    nb = n - na
    n2 = W.shape[0]
    any_rigid = n2 > nc
    rigid = Cdiag == 0.0
    PhiT = np.ascontiguousarray(Phi_c.T)
    has_fb = V.shape[1] > 0
    Vq = np.ascontiguousarray(V[:, :, :n]); Vv = np.ascontiguousarray(V[:, :, n:]); sfb = np.empty(V.shape[1])
    P1 = np.empty((K, n)); fb = np.zeros((K, n)); Qf = np.empty((K, n)); Vf = np.empty((K, n))
    acc = np.empty((K, n)); Gs = np.zeros((K, nc)); Fpen = np.zeros((K, nc))
    Pf = np.zeros((K, n)); Pg = np.zeros((K, n))
    Xa = np.empty((3, K, na)); Xb = np.empty((3, K, nb))
    Ya_t = np.empty((K, Y_a.shape[2])); Yb_t = np.empty((K, Y_b.shape[2]))
    u = np.zeros(n2); fn = np.empty(nc); g = np.zeros(nc)
    rows2 = np.zeros(n2, dtype=np.bool_)
    cols2 = np.zeros(n2, dtype=np.bool_)
    opening = np.zeros(nc, dtype=np.bool_)
    cand = np.empty(nc, dtype=np.bool_)
    free = np.empty(nc, dtype=np.bool_)
    bolted = np.empty(release.shape[1], dtype=np.bool_)
    anyf = np.zeros(K, dtype=np.bool_)
    anyg = np.zeros(K, dtype=np.bool_)
    E = np.zeros((K, nc)); Ed = np.zeros((K, nc))
    for i in range(i0, i1):
        ta = t0 + i * h
        tb = t0 + (i + 1) * h
        # ---------------- free step of every case (contact force at t1 = 0)
        for k in range(K):
            if has_fb:
                _feedback(Q[k], Vel[k], U[k], Vq[k], Vv[k], since[k], until[k], ta, sfb, fb[k])
            ptr[k] = _pre_step(coef, const[k], tk, Pk[k], ptr[k], tb, has_fb, fb[k], Q[k], Vel[k], Pext[k], Pc[k],
                               P1[k], Qf[k], Vf[k])
        np.dot(Qf, PhiT, E)                    # (K, nc): free relative displacements, one BLAS-3 product
        if any_rigid:
            np.dot(Vf, PhiT, Ed)
        r = i + 1
        # ---------------- contact solve, case by case
        for k in range(K):
            _candidates(tb, release[k], dcontact, axial, coff, rigid, any_rigid, E[k], Ed[k], bolted, cand, free,
                        active[k], u)
            for j in range(nc):
                opening[j] = False
            st, it, info1, info2 = _solve_direct(W, C2, nsign, keys, invs, used, u, free, rigid, active[k], opening,
                                                 max_iter, fn, g, rows2, cols2)
            if st != OK:
                return st, i + 1, info1, info2, k
            af = False
            ag = False
            for j in range(nc):
                F[k, j] = fn[j]
                Gs[k, j] = g[j]
                Fpen[k, j] = 0.0 if rigid[j] else fn[j]
                af = af or fn[j] != 0.0
                ag = ag or g[j] != 0.0
            anyf[k] = af
            anyg[k] = ag
            _record_contact(r, it, fn, bolted, active[k], opening, dcontact, axial, Fc[k], states[k], iters[k])
        # ---------------- contact loads of every case (BLAS-3) and the end-of-step state
        if any_rigid:
            np.dot(F, Phi_c, Pf)
            np.dot(Gs, Phi_c, Pg)
            np.dot(Fpen, Phi_c, Pc)
            Pend = Pf
        else:                                  # penalty rows only: the end load is the next step's start load
            np.dot(F, Phi_c, Pc)
            Pend = Pc
        for k in range(K):
            _post_step(coef, Qf[k], Vf[k], P1[k], Pend[k], Pg[k], anyf[k], anyg[k], zw2, w2, Q[k], Vel[k], acc[k])
        # ---------------- outputs at t1 (BLAS-3 per body and kind)
        for k in range(K):
            for m in range(na):
                Xa[0, k, m] = Q[k, m]; Xa[1, k, m] = Vel[k, m]; Xa[2, k, m] = acc[k, m]
            for m in range(nb):
                Xb[0, k, m] = Q[k, na + m]; Xb[1, k, m] = Vel[k, na + m]; Xb[2, k, m] = acc[k, na + m]
        _outputs_cases(L_a, kind_a, targ_a, Xa, Ya_t, Y_a, r)
        if nb > 0:
            _outputs_cases(L_b, kind_b, targ_b, Xb, Yb_t, Y_b, r)
    return OK, i1, 0.0, 0.0, -1


def _merged_grid(modals) -> tuple[np.ndarray, np.ndarray]:
    """(tk, Pk (K, n_k, n)): every case's load table on the union of their breakpoints (exact:
    each table is linear between its own breakpoints, all of them in the union)."""
    tk = np.unique(np.concatenate([m.tk for m in modals]))
    n = modals[0].w2.size
    Pk = np.zeros((len(modals), tk.size, n))
    for k, m in enumerate(modals):
        if m.tk.size == tk.size and np.array_equal(m.tk, tk):
            Pk[k] = m.Pk
        elif m.tk.size:
            for j in range(n):
                Pk[k, :, j] = np.interp(tk, m.tk, m.Pk[:, j])
    return tk, Pk


def _case_data(modals, rows_k, tk_Pk) -> CaseData:
    """The cases' loads, feedback (padded to the largest rank with terms that are never on)
    and release times, stacked."""
    K, n = len(modals), modals[0].w2.size
    r = max(m.V.shape[0] for m in modals)
    U, V = np.zeros((K, n, r)), np.zeros((K, r, 2 * n))
    since, until = np.zeros((K, r)), np.zeros((K, r))        # since = until: off
    for k, m in enumerate(modals):
        rk = m.V.shape[0]
        U[k, :, :rk], V[k, :rk], since[k, :rk], until[k, :rk] = m.U, m.V, m.since, m.until
    const = np.ascontiguousarray(np.stack([m.const for m in modals]))
    release = np.ascontiguousarray(np.stack([rows.release for rows in rows_k]))
    return CaseData(const, tk_Pk[1], U, V, since, until, release)


def _solve_batch(problems: list[TransientProblem], chunk: int) -> list[TransientResult]:
    started = _time.perf_counter()
    p0 = problems[0]
    pa, pb, K = p0.body_a, p0.body_b, len(problems)
    rows_k = [contact_rows(pa, pb, p.contacts) for p in problems]
    rows = rows_k[0]
    step = choose_step(p0, rows)
    n, nc, n_t = pa.n_modes + pb.n_modes, rows.n, step.n_steps + 1
    coefs = (step_coefficients(pa.omega, pa.zeta, step.h, p0.static_modes("a")),
             step_coefficients(pb.omega, pb.zeta, step.h, p0.static_modes("b")))
    plans = (output_plan(p0, "a"), output_plan(p0, "b"))
    contact, W = _contact_inputs(rows, coefs)
    hist = BatchHistory(np.zeros((K, n_t, plans[0].ntarg)), np.zeros((K, n_t, plans[1].ntarg)),
                        np.zeros((K, n_t, nc)), np.zeros((K, n_t, len(rows.names)), dtype=np.int8),
                        np.zeros((K, n_t), dtype=np.int32))
    empty = np.zeros((0, 0))
    modals, states, guards = [], [], []
    for k, p in enumerate(problems):
        fo = p.forcing
        try:
            init = initial_state(p)
            f0, active0 = initial_contact_force(pa, pb, rows_k[k], fo, init, p.t0)
        except (InputError, ConvergenceError) as exc:
            raise type(exc)(f"batch case {k}: {exc}") from None
        loads = (modal_load(pa, "a", fo), modal_load(pb, "b", fo))
        views = History(hist.Y_a[k], hist.Y_b[k], hist.Fc[k], hist.state[k], hist.iters[k], False,
                        empty, empty, empty, empty, empty, empty, *NO_BLOCK)
        state = _start(p, rows_k[k], contact, init, f0, active0, loads, plans, views)
        modal = _modal_inputs(p, coefs, loads)
        modals.append(modal)
        states.append(state)
        guards.append(GrowthGuard(rows_k[k], modal, state, step.h, step.margin))
        guards[-1].start(step.t0, step.t_end)
    tk_Pk = _merged_grid(modals)
    cases = _case_data(modals, rows_k, tk_Pk)
    m0 = modals[0]
    modal = m0._replace(const=m0.const, tk=tk_Pk[0], Pk=np.zeros((0, n)), U=np.zeros((n, 0)),
                        V=np.zeros((0, 2 * n)), since=np.zeros(0), until=np.zeros(0))
    stack = lambda name: np.ascontiguousarray(np.stack([getattr(s, name) for s in states]))  # noqa: E731
    state = BatchState(stack("q"), stack("v"), stack("f"), stack("active"), stack("Pc"), stack("Pext"),
                       np.zeros(K, dtype=np.int64))
    cache = _new_cache(contact.W.shape[0], cap=256)
    steps = Stepping(float(p0.t0), float(step.h), 0, float(p0.tol), int(p0.max_iter))
    out_rows = OutputRows(plans[0].L, plans[0].kind, plans[0].targ, plans[1].L, plans[1].kind, plans[1].targ)
    _march(problems, step, (steps, modal, cases, contact, out_rows), state, cache, hist, guards, W, rows_k,
           max(1, chunk))
    results = []
    for k, p in enumerate(problems):
        one = History(hist.Y_a[k], hist.Y_b[k], hist.Fc[k].copy(), hist.state[k].copy(), hist.iters[k].copy(),
                      False, empty, empty, empty, empty, empty, empty, *NO_BLOCK)
        res = _result(p, rows_k[k], step, plans, one, int(cache.used[0]), started, states[k])
        results.append(res)
    return results


def _march(problems, step, inputs, state: BatchState, cache, hist: BatchHistory, guards, W, rows_k, chunk) -> None:
    """Every step in compiled chunks (a progress bar between chunks when any problem asks
    for progress), each case's growth guard and finiteness checked after each chunk."""
    bar = None
    K = len(problems)
    if any(p.progress for p in problems) and step.n_steps > 4 * chunk:
        from tqdm import tqdm

        bar = tqdm(total=step.n_steps * K, unit="case-step", desc=f"transient, {K} cases", leave=False)
    try:
        i = 0
        while i < step.n_steps:
            i1 = min(i + chunk, step.n_steps)
            status, at, info1, info2, case = march_batch(i, i1, *inputs, state, cache, hist)
            if status != 0:
                try:
                    _failure(status, step.t0 + at * step.h, info1, info2,
                             lambda: _spectral_radius(W, rows_k[case], state.active[case]))
                except (InputError, ConvergenceError) as exc:
                    raise type(exc)(f"batch case {case}: {exc}") from None
            times = step.t0 + step.h * np.arange(i + 1, i1 + 1)
            for k in range(K):
                if not (np.all(np.isfinite(state.q[k])) and np.all(np.isfinite(state.v[k]))):
                    raise ConvergenceError(f"batch case {k}: the solution diverged (non-finite values) by "
                                           f"t = {step.t0 + step.h * i1:.6g} s with h = {step.h:.4g} s; reduce h")
                view = SimpleNamespace(q=state.q[k], v=state.v[k], active=state.active[k], f=state.f[k])
                try:
                    guards[k].check(step.t0 + step.h * i1, view, hist.Fc[k, i + 1:i1 + 1], times)
                except ConvergenceError as exc:
                    raise ConvergenceError(f"batch case {k}: {exc}") from None
            if bar is not None:
                bar.update((i1 - i) * K)
            i = i1
    finally:
        if bar is not None:
            bar.close()



def solve_batch(problems):
    """The K problems (sharing both bodies, contacts, step and outputs) marched together."""
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1, user_api="blas"):
        return _solve_batch(list(problems), CHUNK)


def cases(n_steps: int, n_veh: int, n_pad: int, K: int):
    """bench_transient's problem, bolted throughout, its thrust scaled by 1 + 0.01 k in case k."""
    base = problem(n_steps, n_veh=n_veh, n_pad=n_pad, release=None)
    fo = base.forcing
    return [dataclasses.replace(base, progress=False, forcing=dataclasses.replace(
        fo, tables=[TabulatedForce(t.body, t.label, t.time, t.value * (1 + 0.01 * k)) for t in fo.tables]))
        for k in range(K)]


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--modes", type=int, nargs=2, default=[3000, 300], metavar=("VEHICLE", "PAD"))
    ap.add_argument("--cases", type=int, default=64)
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--check", type=int, default=4, help="cases solved one by one (their time scaled to --cases)")
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore")                      # the synthetic stack's step warning
    nv, npd, K = args.modes[0], args.modes[1], args.cases
    short, long_ = cases(500, nv, npd, K), cases(2500, nv, npd, K)
    solve_batch(short[:2]), solve(short[0])              # compile
    def batch(P):
        t = _time.perf_counter(); out = solve_batch(P); return _time.perf_counter() - t, out
    def alone(P):
        t = _time.perf_counter(); out = [solve(p) for p in P[:args.check]]
        return (_time.perf_counter() - t) * K / args.check, out
    tb, to = [], []
    for _ in range(args.repeat):
        tb.append(batch(long_)[0] - batch(short)[0])
        to.append(alone(long_)[0] - alone(short)[0])
    rb, r1 = batch(long_)[1], alone(long_)[1]
    dF = max(np.abs(a.contact_force - b.contact_force).max() / np.abs(b.contact_force).max() for a, b in zip(rb, r1))
    dF1 = max(np.abs(a.contact_force[1] - b.contact_force[1]).max() / np.abs(b.contact_force).max()
              for a, b in zip(rb, r1))
    dY = max(np.abs(a.displacement["a"] - b.displacement["a"]).max() / np.abs(b.displacement["a"]).max()
             for a, b in zip(rb, r1))
    per_b, per_1 = min(tb) / 2000 / K * 1e6, min(to) / 2000 / K * 1e6
    print(f"bench_batch: {platform.machine()}, {os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f}, "
          f"min of {args.repeat}")
    print(f"  {nv} + {npd} modes, 24 contact rows, {K} cases, 2,000 steps (slope of 500 -> 2,500)")
    print(f"  per case-step: batched {per_b:.1f} us, one by one {per_1:.1f} us; speed-up {per_1 / per_b:.2f}"
          " (issue 28 asked >= 3)")
    print(f"  contact force difference, batched vs one by one, of the peak: step 1 {dF1:.1e}, whole run {dF:.1e}; "
          f"vehicle outputs {dY:.1e}")


if __name__ == "__main__":
    main()
