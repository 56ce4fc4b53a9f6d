"""Two-body transient driver: step size (2.5), static initial conditions (2.6), time loop (2.3-2.7)."""
from __future__ import annotations

import math
import time as _time
import warnings

import numpy as np

from liftoff.core.errors import ConvergenceError, InputError

from .assembly import contact_rows, feedback_factors, feedback_matrix, modal_load
from .body import ModalBody
from .coefficients import step_coefficients
from .kernel import CLOSED, CYCLING, NO_CONVERGENCE, OPEN, SINGULAR, march
from .model import Forcing, InitialState, TransientProblem
from .result import TransientResult

CHUNK = 5000  # steps per compiled call (progress updated between chunks)
STABILITY = math.sqrt(3) / math.pi  # 2 pi f_h h < 2 sqrt(3): stability of penalty coupling (0.551/f_h)


# --------------------------------------------------------------------- statics
def _active_rows(rows, t: float) -> np.ndarray:
    """Rows coupled 'closed/bolted' at time t: all rows of bolted points, axial rows of released ones."""
    bolted = t < rows.release[rows.contact]
    return bolted | rows.axial


def _coupled_operator(rows, active):
    """D (n_act, n_a+n_b) such that x_a - x_b = D q on the active rows."""
    D = np.hstack([rows.Phi_a, -rows.Phi_b])
    return D[active]


def static_solution(body_a: ModalBody, body_b: ModalBody, contacts, forcing: Forcing, t: float = 0.0):
    """Static equilibrium (section 2.6) with contacts closed/bolted; returns (InitialState, f).

    Bolted points (t < release_time) couple all directions; released points couple their
    axial direction while it is in compression (a released point found in tension is opened
    and the problem solved again). f (n_dirs,) is the contact force on A (N) on every
    direction (0 where not coupled). Feedback matrices enter the stiffness as -matrix (eq. 27)."""
    if not isinstance(forcing, Forcing):
        raise InputError("forcing must be a Forcing object")
    rows = contact_rows(body_a, body_b, contacts)
    act = _active_rows(rows, t)
    released = ~(t < rows.release[rows.contact])
    # stiffness and load of the bodies alone: the same for every active set tried below
    na, nb = body_a.n_modes, body_b.n_modes
    K0 = np.zeros((na + nb, na + nb))
    K0[:na, :na] = np.diag(body_a.omega ** 2) - feedback_matrix(na, "a", forcing, t)
    if nb:
        K0[na:, na:] = np.diag(body_b.omega ** 2) - feedback_matrix(nb, "b", forcing, t)
    P0 = np.concatenate([modal_load(body_a, "a", forcing).at(t), modal_load(body_b, "b", forcing).at(t)])
    for _ in range(rows.n + 1):
        state, f = _static_solve(na, rows, K0, P0, t, act)
        tension = act & released & (rows.sign * f < 0)
        if not tension.any():
            return state, f
        act = act & ~tension
    raise ConvergenceError(f"static equilibrium at t = {t:g} s: the released contact set did not settle")


def _static_solve(na, rows, K0, P0, t, act):
    """One static solve with the rows ``act`` coupled; K0, P0: stiffness and load of the bodies alone."""
    n = K0.shape[0]
    nb = n - na
    D = _coupled_operator(rows, act)
    comp = rows.compliance[act]
    off = rows.offset[act]
    pen, rig = comp > 0, comp == 0
    Kp = 1.0 / comp[pen]
    Dp = D[pen]
    K = K0 + Dp.T @ (Kp[:, None] * Dp)
    P = P0 - Dp.T @ (Kp * off[pen])
    Dr = D[rig]
    nr = Dr.shape[0]
    S = np.zeros((n + nr, n + nr))
    S[:n, :n] = K
    S[:n, n:] = Dr.T
    S[n:, :n] = Dr
    rhs = np.concatenate([P, -off[rig]])
    # Jacobi-type scaling so that the singularity test does not depend on units
    d = np.abs(np.diag(K)).copy()
    sc = np.where(d > 0, 1.0 / np.sqrt(np.where(d > 0, d, 1.0)), 1.0)
    if nr:
        rn = np.linalg.norm(Dr * sc[None, :], axis=1)
        sc = np.concatenate([sc, np.where(rn > 0, 1.0 / np.where(rn > 0, rn, 1.0), 1.0)])
    Ss = sc[:, None] * S * sc[None, :]
    sv = np.linalg.svd(Ss, compute_uv=False)
    if sv.size and (sv[-1] <= 1e-11 * sv[0] or not np.isfinite(sv[0])):
        raise InputError(f"static equilibrium at t = {t:g} s is singular (scaled condition number "
                         f"{sv[0] / max(sv[-1], 1e-300):.3g}): a free body is not held by enough closed/bolted "
                         "contact directions (or rigid contacts are redundant)")
    x = sc * np.linalg.solve(Ss, sc * rhs)
    q = x[:n]
    f = np.zeros(rows.n)
    idx = np.flatnonzero(act)
    fa = np.zeros(idx.size)
    fa[pen] = -Kp * (off[pen] + Dp @ q)
    fa[rig] = -x[n:]
    f[idx] = fa
    state = InitialState(q[:na], np.zeros(na), q[na:], np.zeros(nb))
    return state, f


def static_equilibrium(body_a: ModalBody, body_b: ModalBody, contacts, forcing: Forcing,
                       t: float = 0.0) -> InitialState:
    """Modal displacements of both bodies in static equilibrium at time t (section 2.6), zero velocities."""
    return static_solution(body_a, body_b, contacts, forcing, t)[0]


# ----------------------------------------------------------------- step size
def estimate_step(body_a: ModalBody, body_b: ModalBody, contacts) -> tuple[float, float]:
    """(f_h in Hz, h = 0.25/f_h in s) from the bodies reduced to the contact DOFs (eq. 12).

    Penalty directions: the interface masses (Phi_c Phi_c^T)^-1 of both bodies coupled by
    K_C, i.e. omega_h^2 = lambda_max(K_C^1/2 (Phi_ca Phi_ca^T + Phi_cb Phi_cb^T) K_C^1/2)
    (body stiffness negligible against K_C). Rigid directions: the highest frequency of the
    coupled modal system with those directions constrained (conservative)."""
    rows = contact_rows(body_a, body_b, contacts)
    W0 = rows.Phi_a @ rows.Phi_a.T + rows.Phi_b @ rows.Phi_b.T
    pen = rows.compliance > 0
    w2 = 0.0
    if pen.any():
        k = np.sqrt(1.0 / rows.compliance[pen])
        w2 = max(w2, float(np.linalg.eigvalsh(k[:, None] * W0[np.ix_(pen, pen)] * k[None, :]).max()))
    if (~pen).any():
        D = np.hstack([rows.Phi_a, -rows.Phi_b])
        Om2 = np.concatenate([body_a.omega ** 2, body_b.omega ** 2])
        Kfull = np.diag(Om2)
        if pen.any():
            Kfull = Kfull + D[pen].T @ ((1.0 / rows.compliance[pen])[:, None] * D[pen])
        u, s, vt = np.linalg.svd(D[~pen])
        r = int(np.sum(s > 1e-12 * max(s[0], 1e-300)))
        N = vt[r:].T
        if N.shape[1]:
            w2 = max(w2, float(np.linalg.eigvalsh(N.T @ Kfull @ N).max()))
    if not w2 > 0:
        raise InputError("cannot estimate the step size: the contact model has no frequency; give h explicitly")
    f_h = math.sqrt(w2) / (2 * math.pi)
    return f_h, 0.25 / f_h


# ------------------------------------------------------------- initial force
def _acceleration(body: ModalBody, key: str, forcing: Forcing, load, t: float, q, v, Pc) -> np.ndarray:
    """Modal acceleration at time t from the equation of motion: applied load (``load``, the
    body's ModalLoad) + feedback + contact force Pc, less damping and stiffness."""
    if body.n_modes == 0:
        return np.zeros(0)
    P = load.at(t) + feedback_matrix(body.n_modes, key, forcing, t) @ q + Pc
    return P - 2 * body.zeta * body.omega * v - body.omega ** 2 * q


def initial_contact_force(body_a, body_b, rows, forcing, state: InitialState, t0: float):
    """Contact force (on A, per row) and active set consistent with a given state at t0."""
    e = rows.Phi_a @ state.q_a - rows.Phi_b @ state.q_b
    u = rows.offset + e
    bolted = t0 < rows.release[rows.contact]
    pen = rows.compliance > 0
    active = bolted | (rows.axial & (rows.sign * u < 0))
    active |= rows.axial & ~bolted & ~pen & (rows.sign * u <= 0)
    f = np.zeros(rows.n)
    f[active & pen] = -u[active & pen] / rows.compliance[active & pen]
    rig = active & ~pen
    if rig.any():
        # rigid rows: zero relative acceleration at t0 given the penalty forces
        load_a, load_b = modal_load(body_a, "a", forcing), modal_load(body_b, "b", forcing)
        for _ in range(2):
            fr = f.copy()
            fr[rig] = 0.0
            acc_rel = rows.Phi_a @ _acceleration(body_a, "a", forcing, load_a, t0, state.q_a, state.v_a,
                                                 rows.Phi_a.T @ fr) \
                - rows.Phi_b @ _acceleration(body_b, "b", forcing, load_b, t0, state.q_b, state.v_b,
                                             -rows.Phi_b.T @ fr)
            M = (rows.Phi_a @ rows.Phi_a.T + rows.Phi_b @ rows.Phi_b.T)[np.ix_(rig, rig)]
            try:
                f[rig] = np.linalg.solve(M, -acc_rel[rig])
            except np.linalg.LinAlgError:
                raise InputError("rigid contact directions are redundant (singular constraint)") from None
            tension = rig & ~bolted & (rows.sign * f < 0)
            if not tension.any():
                break
            active &= ~tension
            f[tension] = 0.0
            rig = active & ~pen
    return f, active


# ---------------------------------------------------------------- outputs
def _output_matrices(problem: TransientProblem, key: str):
    """Stacked output rows (L, kind, target), labels per target group."""
    body = problem.body(key)
    n = body.n_modes
    labels = problem.outputs[key]
    L, kind, targ = [], [], []
    k = len(labels)
    for i, lab in enumerate(labels):
        row = body.phi[body.dof_index(lab)]
        for kd in range(3):
            L.append(row); kind.append(kd); targ.append(kd * k + i)
    ntarg = 3 * k
    rb_slice = None
    if n:
        Mrb = body.rigid_body_mass
        sel = np.flatnonzero(np.abs(np.diag(Mrb)) > 0)
        R = None
        if sel.size:
            sub = Mrb[np.ix_(sel, sel)]
            if np.linalg.cond(sub) < 1e12:
                R = np.full((6, n), np.nan)
                R[sel] = np.linalg.solve(sub, body.participation[:, sel].T)
        if R is not None:
            rb_slice = (ntarg, ntarg + 6)
            for d in range(6):
                L.append(np.zeros(n) if d not in sel else R[d]); kind.append(0); targ.append(ntarg + d)
            rb_sel = sel
            ntarg += 6
    rec_slices = {}
    for r in problem.recoveries:
        if r.body != key:
            continue
        m = len(r.labels)
        for kd, mat in enumerate((r.disp, r.vel, r.acc)):
            if mat is None:
                continue
            for i in range(m):
                L.append(mat[i]); kind.append(kd); targ.append(ntarg + i)
        rec_slices[r.name] = (ntarg, ntarg + m)
        ntarg += m
    L = np.array(L).reshape(len(kind), n) if kind else np.zeros((0, n))
    order = np.argsort(np.array(kind, dtype=np.int64), kind="stable")  # the kernel wants rows grouped by kind
    L, kind, targ = L[order], np.array(kind, dtype=np.int64)[order], np.array(targ, dtype=np.int64)[order]
    out = dict(L=np.ascontiguousarray(L), kind=kind, targ=targ,
               ntarg=ntarg, k=k, rb=rb_slice, rec=rec_slices)
    out["rb_sel"] = rb_sel if rb_slice is not None else None
    return out


def _initial_outputs(outm, body, q, v, acc, Y):
    for row in range(outm["L"].shape[0]):
        x = (q, v, acc)[outm["kind"][row]]
        Y[0, outm["targ"][row]] += outm["L"][row] @ x


# -------------------------------------------------------------------- solve
def solve(problem: TransientProblem) -> TransientResult:
    """Integrate the two-body problem (see :func:`_solve`) with one BLAS thread.

    The BLAS products of a step are tiny (n_contact_dirs x n_modes) and the set-up products
    a few hundred square: a multi-threaded BLAS only adds synchronisation
    (benchmarks/bench_transient.py: 0.87 s CPU with 2 OpenBLAS threads, 0.65 s with one).
    """
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1, user_api="blas"):
        return _solve(problem)


def _solve(problem: TransientProblem) -> TransientResult:
    """Run the two-body transient (sections 2.3-2.7) and return its time histories."""
    started = _time.perf_counter()
    pa, pb = problem.body_a, problem.body_b
    fo = problem.forcing
    rows = contact_rows(pa, pb, problem.contacts)
    f_h, h_default = estimate_step(pa, pb, problem.contacts)
    if problem.h is None:
        h = h_default
    else:
        h = float(problem.h)
        if h > h_default * (1 + 1e-9):
            extra = ""
            if (rows.compliance > 0).any() and h > STABILITY * h_default / 0.25:
                extra = (f"; it also exceeds about {STABILITY:.2f}/f_h = {STABILITY / f_h:.4g} s, the stability limit "
                         "of the penalty coupling (linear-acceleration scheme), so the run may diverge")
            warnings.warn(f"time step h = {h:.4g} s is larger than 0.25/f_h = {h_default:.4g} s "
                          f"(f_h = {f_h:.4g} Hz, eq. 12): the contact force may be under-resolved{extra}",
                          stacklevel=2)
    span = problem.t_end - problem.t0
    n_steps = int(math.ceil(span / h - 1e-9))
    if n_steps < 1:
        raise InputError(f"time step h = {h:g} s is longer than the run ({span:g} s)")
    if n_steps > 2e8:
        raise InputError(f"{n_steps} steps of h = {h:g} s: too many; use a larger h or a shorter run")
    n_t = n_steps + 1
    time = problem.t0 + h * np.arange(n_t)

    # initial state
    if isinstance(problem.initial, InitialState):
        init = problem.initial
    elif problem.initial == "zero":
        init = InitialState(np.zeros(pa.n_modes), np.zeros(pa.n_modes), np.zeros(pb.n_modes), np.zeros(pb.n_modes))
    else:
        init = static_equilibrium(pa, pb, problem.contacts, fo, problem.t0)
    f0, active0 = initial_contact_force(pa, pb, rows, fo, init, problem.t0)

    # per-body arrays
    def body_arrays(body, key):
        c = step_coefficients(body.omega, body.zeta, h)
        coef = np.ascontiguousarray(np.vstack([c.F, c.G, c.Ac, c.Bc, c.Fd, c.Gd, c.Acd, c.Bcd]))
        load = modal_load(body, key, fo)
        U, V, until = feedback_factors(body.n_modes, key, fo, problem.t0)
        return c, coef, load, U, V, until

    ca, coef_a, load_a, U_a, V_a, until_a = body_arrays(pa, "a")
    cb, coef_b, load_b, U_b, V_b, until_b = body_arrays(pb, "b")
    def flex(ka, kb):  # Phi diag(coefficient) Phi^T summed over both bodies
        return (rows.Phi_a * getattr(ca, ka)) @ rows.Phi_a.T + (rows.Phi_b * getattr(cb, kb)) @ rows.Phi_b.T

    W = flex("Bc", "Bc")  # step flexibility (end-of-step force -> end-of-step displacement)
    # kernel matrix for x = [f1; g] (g: start values of rigid rows, see kernel.py)
    if (rows.compliance == 0).any():
        W2 = np.block([[W, flex("Ac", "Ac")], [flex("Bcd", "Bcd"), flex("Acd", "Acd")]])
        C2 = np.concatenate([rows.compliance, np.zeros(rows.n)])
    else:  # penalty only: unknowns f1 alone
        W2, C2 = W, rows.compliance.copy()
    out_a, out_b = _output_matrices(problem, "a"), _output_matrices(problem, "b")

    # outputs
    nc, ncon = rows.n, len(problem.contacts)
    Y_a = np.zeros((n_t, out_a["ntarg"]))
    Y_b = np.zeros((n_t, out_b["ntarg"]))
    Fc = np.zeros((n_t, nc))
    state = np.zeros((n_t, ncon), dtype=np.int8)
    iters = np.zeros(n_t, dtype=np.int32)
    keep = bool(problem.keep_modal)
    shp = lambda n: (n_t, n) if keep else (0, n)  # noqa: E731
    Qa, Va, Aa = np.zeros(shp(pa.n_modes)), np.zeros(shp(pa.n_modes)), np.zeros(shp(pa.n_modes))
    Qb, Vb, Ab = np.zeros(shp(pb.n_modes)), np.zeros(shp(pb.n_modes)), np.zeros(shp(pb.n_modes))

    # state at t0
    q_a, v_a, q_b, v_b = (np.array(x, dtype=float) for x in (init.q_a, init.v_a, init.q_b, init.v_b))
    Pc_a, Pc_b = rows.Phi_a.T @ f0, -(rows.Phi_b.T @ f0)
    pen0 = np.where(rows.compliance > 0, f0, 0.0)  # rigid rows start each step from their own g

    a_a0 = _acceleration(pa, "a", fo, load_a, problem.t0, q_a, v_a, Pc_a)
    a_b0 = _acceleration(pb, "b", fo, load_b, problem.t0, q_b, v_b, Pc_b)
    _initial_outputs(out_a, pa, q_a, v_a, a_a0, Y_a)
    _initial_outputs(out_b, pb, q_b, v_b, a_b0, Y_b)
    Fc[0] = f0
    bolted0 = problem.t0 < rows.release
    state[0] = np.where(bolted0, 0, 2)
    for c in range(ncon):
        if not bolted0[c] and active0[rows.axial_column[c]]:
            state[0, c] = CLOSED
    if keep:
        Qa[0], Va[0], Aa[0], Qb[0], Vb[0], Ab[0] = q_a, v_a, a_a0, q_b, v_b, a_b0

    f = f0.copy()
    active = active0.copy()
    cap = 64
    n2 = W2.shape[0]
    keys = np.zeros((cap, 2 * n2), dtype=np.bool_)
    invs = np.zeros((cap, n2, n2))
    ncache = np.zeros(1, dtype=np.int64)
    last = np.zeros(1, dtype=np.int64)
    ptr = np.zeros(1, dtype=np.int64)
    method = 0 if problem.method == "direct" else 1
    C = np.ascontiguousarray
    # both bodies as one modal set (a then b): one BLAS product per contact projection
    na = pa.n_modes
    Phi_c = C(np.hstack([rows.Phi_a, -rows.Phi_b]))
    q = np.concatenate([q_a, q_b])
    v = np.concatenate([v_a, v_b])
    Pc = Phi_c.T @ pen0  # contact force of the penalty rows at t0 (rigid rows start from their own g)
    Pext = np.concatenate([load_a.at(problem.t0), load_b.at(problem.t0)])  # applied load at the step start
    coef = C(np.hstack([coef_a, coef_b]))
    w2 = np.concatenate([pa.omega, pb.omega]) ** 2
    zw2 = 2 * np.concatenate([pa.zeta * pa.omega, pb.zeta * pb.omega])
    const = np.concatenate([load_a.const, load_b.const])
    tk = np.union1d(load_a.times, load_b.times)
    Pk = np.zeros((tk.size, na + pb.n_modes))
    for ld, cols in ((load_a, slice(0, na)), (load_b, slice(na, None))):
        if ld.times.size:  # exact: each body's table is linear between its own breakpoints
            Pk[:, cols] = np.column_stack([np.interp(tk, ld.times, ld.table[:, m]) for m in range(ld.table.shape[1])])
    U = np.zeros((na + pb.n_modes, U_a.shape[1] + U_b.shape[1]))
    V = np.zeros((U.shape[1], na + pb.n_modes))
    U[:na, :U_a.shape[1]], V[:U_a.shape[1], :na] = U_a, V_a
    U[na:, U_a.shape[1]:], V[U_a.shape[1]:, na:] = U_b, V_b
    fb_until = np.concatenate([until_a, until_b]).astype(float)
    args = (na, coef, w2, zw2, const, tk, C(Pk), C(U), C(V), fb_until,
            out_a["L"], out_a["kind"], out_a["targ"], out_b["L"], out_b["kind"], out_b["targ"],
            Phi_c, rows.compliance, rows.offset, rows.contact, rows.axial, rows.sign, rows.release, C(W2), C2)

    bar = None
    if problem.progress and n_steps > 4 * CHUNK:
        from tqdm import tqdm

        bar = tqdm(total=n_steps, unit="step", desc="transient", leave=False)
    try:
        i = 0
        while i < n_steps:
            i1 = min(i + CHUNK, n_steps)
            st, step, info1, info2 = march(
                i, i1, float(problem.t0), float(h), method, float(problem.tol), int(problem.max_iter),
                *args, q, v, f, active, Pc, Pext, ptr, keys, invs, ncache, last,
                Y_a, Y_b, Fc, state, iters, keep, Qa, Va, Aa, Qb, Vb, Ab)
            if st != 0:
                t_fail = problem.t0 + step * h
                if st == NO_CONVERGENCE:
                    rho = _spectral_radius(W, rows, active)
                    raise ConvergenceError(
                        f"contact fixed-point iteration did not converge at t = {t_fail:.6g} s "
                        f"(|dF| = {info1:.3g} N after {int(info2)} iterations; spectral radius of K_C W = {rho:.3g})")
                if st == CYCLING:
                    raise ConvergenceError(f"contact active set did not settle at t = {t_fail:.6g} s "
                                           f"({int(info1)} active-set changes in one step)")
                if st == SINGULAR:
                    raise InputError(f"singular contact system at t = {t_fail:.6g} s: rigid contact directions "
                                     "are redundant or act on DOFs with no flexibility")
            if not np.all(np.isfinite(q)):
                bad = np.flatnonzero(~np.all(np.isfinite(Fc[i + 1:i1 + 1]), axis=1))
                t_bad = time[i + 1 + (bad[0] if bad.size else 0)]
                raise ConvergenceError(
                    f"the solution diverged (non-finite contact force) at t = {t_bad:.6g} s: h = {h:.4g} s; the "
                    f"penalty coupling is stable only for h below about {STABILITY / f_h:.4g} s ({STABILITY:.2f}/f_h)")
            if bar is not None:
                bar.update(i1 - i)
            i = i1
    finally:
        if bar is not None:
            bar.close()

    # events
    sep = np.full(ncon, np.nan)
    rec = np.zeros(ncon, dtype=np.int64)
    for c in range(ncon):
        s = state[:, c]
        opened = np.flatnonzero((s[1:] == OPEN) & (s[:-1] != OPEN)) + 1
        if opened.size:
            sep[c] = time[opened[0]]
        rec[c] = int(np.sum((s[1:] == CLOSED) & (s[:-1] == OPEN)))

    def split(Y, outm):
        k = outm["k"]
        d, v, a = Y[:, :k], Y[:, k:2 * k], Y[:, 2 * k:3 * k]
        rb = None
        if outm["rb"] is not None:
            rb = Y[:, outm["rb"][0]:outm["rb"][1]].copy()
            missing = np.setdiff1d(np.arange(6), outm["rb_sel"])
            rb[:, missing] = np.nan
        recd = {name: Y[:, s0:s1].copy() for name, (s0, s1) in outm["rec"].items()}
        return d.copy(), v.copy(), a.copy(), rb, recd

    da, va, aa, rba, reca = split(Y_a, out_a)
    db, vb, ab, rbb, recb = split(Y_b, out_b)
    modal = {}
    if keep:
        modal = {"q_a": Qa, "v_a": Va, "acc_a": Aa, "q_b": Qb, "v_b": Vb, "acc_b": Ab}
    meta = {"h": h, "method": problem.method, "tol": problem.tol, "max_iter": problem.max_iter,
            "f_h": f_h, "h_default": h_default, "n_steps": n_steps, "t0": problem.t0, "t_end": problem.t_end,
            "body_a": pa.name, "body_b": pb.name, "wall_time_s": _time.perf_counter() - started,
            "axial_columns": [int(x) for x in rows.axial_column],
            "normal_signs": [float(x) for x in rows.normal_sign],
            "active_set_patterns": int(ncache[0])}
    return TransientResult(
        time=time, contact_names=rows.names, contact_labels=rows.labels, contact_force=Fc, contact_state=state,
        separation_time=sep, recontact_count=rec, release_time=rows.release.copy(),
        output_labels={"a": tuple(problem.outputs["a"]), "b": tuple(problem.outputs["b"])},
        displacement={"a": da, "b": db}, velocity={"a": va, "b": vb}, acceleration={"a": aa, "b": ab},
        recovered={**reca, **recb}, recovered_units={r.name: r.units for r in problem.recoveries},
        rigid_body_motion_a=rba, rigid_body_motion_b=rbb, iterations=iters, modal=modal, metadata=meta)


def _spectral_radius(W, rows, active) -> float:
    """rho(K_C W) on the rows coupled at failure (penalty rows)."""
    act = active & (rows.compliance > 0)
    if not act.any():
        act = rows.compliance > 0
    k = 1.0 / rows.compliance[act]
    return float(np.max(np.abs(np.linalg.eigvals(k[:, None] * W[np.ix_(act, act)]))))
