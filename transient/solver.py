"""Two-body transient driver: step size (2.5), static initial conditions (2.6), time loop (2.3-2.7)."""
from __future__ import annotations

import time as _time
import warnings
from dataclasses import dataclass

import numpy as np

from liftoff.core.errors import ConvergenceError, InputError
from liftoff.core.locks import ForkSafeLock
from liftoff.core.scratch import release_rows, scratch_array

from .assembly import contact_rows, feedback_at, feedback_factors, interp_columns, modal_load
from .body import ModalBody
from .coefficients import StepCoefficients, step_coefficients
from .contact_laws import initial_slip, initial_soft
from .guard import GrowthGuard
from .kernel import (
    BOLTED,
    CLOSED,
    CYCLING,
    FRICTION_SINGULAR,
    NO_CONVERGENCE,
    OPEN,
    SINGULAR,
    OUT_BLOCK,
    Cache,
    Contact,
    History,
    Modal,
    OutputRows,
    State,
    Stepping,
    march,
)
from .model import Forcing, InitialState, TransientProblem
from .result import RecoveryItem, TransientResult
from .stepping import STABILITY, StepChoice, check_memory, choose_step, estimate_step  # noqa: F401 (re-exported)

CHUNK = 5000  # steps per compiled call (progress and the growth guard between chunks)


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
    direction (0 where not coupled). Feedback matrices enter the stiffness as -matrix (eq. 27).
    The solve is reduced to the interface (:func:`_static_solve`): linear in the number of modes."""
    if not isinstance(forcing, Forcing):
        raise InputError("forcing must be a Forcing object")
    rows = contact_rows(body_a, body_b, contacts)
    act = _active_rows(rows, t)
    released = ~(t < rows.release[rows.contact])
    # stiffness and load of the bodies alone: the same for every active set tried below
    na, nb = body_a.n_modes, body_b.n_modes
    lam = np.concatenate([body_a.omega ** 2, body_b.omega ** 2])
    (Ua, Va), (Ub, Vb) = feedback_at(na, "a", forcing, t), feedback_at(nb, "b", forcing, t)
    Va, Vb = Va[:, :na], Vb[:, :nb]               # statics: the displacement part of the feedback
    U = np.zeros((na + nb, Ua.shape[1] + Ub.shape[1]))
    V = np.zeros((U.shape[1], na + nb))
    U[:na, :Ua.shape[1]], V[:Ua.shape[1], :na] = Ua, Va
    U[na:, Ua.shape[1]:], V[Ua.shape[1]:, na:] = Ub, Vb
    P0 = np.concatenate([modal_load(body_a, "a", forcing).at(t), modal_load(body_b, "b", forcing).at(t)])
    for _ in range(rows.n + 1):
        state, f = _static_solve(na, rows, (lam, U, V), P0, t, act)
        tension = act & released & (rows.sign * f < 0)
        if rows.rtravel.size:  # a released soft point holds a tension up to F(s) (contact_laws.py)
            from .contact_laws import soft_static_hold

            tension &= ~soft_static_hold(rows, f)
        if not tension.any():
            return state, f
        act = act & ~tension
    raise ConvergenceError(f"static equilibrium at t = {t:g} s: the released contact set did not settle")


def _static_solve(na, rows, body_terms, P0, t, act):
    """One static solve with the rows ``act`` coupled, reduced to the interface.

    The stiffness is K = diag(lam) - U V (bodies and feedback) plus the active penalty rows
    Dp^T K_C Dp, with the rigid rows Dr q = -c_r as constraints. The unknowns kept are
    z = [g; s; lam_r] (penalty forces on A, feedback coordinates s = V q, rigid-row forces)
    and the rigid-body modal coordinates q_R (lam = 0); the elastic ones are
    q_E = diag(lam_E)^-1 (P_E + A_E z) with A = [Dp^T, U, Dr^T], T = [Dp; V; Dr]:

        [C + T_E diag(1/lam_E) A_E   T_R] [z  ]   [-c - T_E diag(1/lam_E) P_E]
        [A_R                          0 ] [q_R] = [-P_R                      ]

    (C = diag(1/K_C, -1, 0)): size (rows + rank of the feedback + rigid modes), built in
    O(n m^2). Its LU factors (partial pivoting, rows and columns equilibrated) give the
    singularity test: a pivot below 1e-11 of the largest means a body not held by enough
    closed/bolted contact directions or redundant rigid contacts."""
    lam, U, V = body_terms
    n = lam.size
    nb = n - na
    D = _coupled_operator(rows, act)
    comp, off = rows.compliance[act], rows.offset[act]
    pen, rig = comp > 0, comp == 0
    npen, nfb = int(pen.sum()), V.shape[0]
    T = np.vstack([D[pen], V, D[rig]])
    A = np.hstack([D[pen].T, U, D[rig].T])
    C = np.concatenate([comp[pen], -np.ones(nfb), np.zeros(int(rig.sum()))])
    c = np.concatenate([off[pen], np.zeros(nfb), off[rig]])
    E = lam > 1e-12 * max(float(lam.max(initial=0.0)), 1e-300)
    R = np.flatnonzero(~E)
    Li = 1.0 / lam[E]
    m, nr = C.size, R.size
    M = np.zeros((m + nr, m + nr))
    M[:m, :m] = np.diag(C) + T[:, E] @ (Li[:, None] * A[E])
    M[:m, m:] = T[:, R]
    M[m:, :m] = A[R]
    rhs = np.concatenate([-c - T[:, E] @ (Li * P0[E]), -P0[R]])
    kmax = float(np.max(1.0 / comp[pen])) if pen.any() else 0.0
    x = _pivoted_solve(M, rhs, t, kmax) if m + nr else np.zeros(0)
    z = x[:m]
    q = np.zeros(n)
    q[E] = Li * (P0[E] + A[E] @ z)
    q[R] = x[m:]
    f = np.zeros(rows.n)
    idx = np.flatnonzero(act)
    fa = np.zeros(idx.size)
    fa[pen] = z[:npen]
    fa[rig] = z[npen + nfb:]
    f[idx] = fa
    state = InitialState(q[:na], np.zeros(na), q[na:], np.zeros(nb))
    return state, f


#: catch_warnings swaps the process's one warnings filter list: two threads (the error
#: estimate's h and h/2 runs) in it at once could leave "ignore" in place for the process
_WARNINGS_LOCK = ForkSafeLock()


def _pivoted_solve(M: np.ndarray, rhs: np.ndarray, t: float, kmax: float = 0.0) -> np.ndarray:
    """Solve M x = rhs by LU with partial pivoting after equilibrating rows and columns (so
    the test does not depend on units); InputError when a pivot falls below 1e-11 of the
    largest (singular statics) or is not finite."""
    import scipy.linalg as sla

    r = np.abs(M).max(axis=1)
    r = np.where(r > 0, 1.0 / np.where(r > 0, r, 1.0), 1.0)
    Ms = r[:, None] * M
    cs = np.abs(Ms).max(axis=0)
    cs = np.where(cs > 0, 1.0 / np.where(cs > 0, cs, 1.0), 1.0)
    Ms *= cs[None, :]
    with _WARNINGS_LOCK, warnings.catch_warnings():   # an exactly zero pivot is reported below, as an InputError
        warnings.simplefilter("ignore", sla.LinAlgWarning)   # (the lock: the h and h/2 runs' statics at once
        lu, piv = sla.lu_factor(Ms, check_finite=False)     # could leave the filter set: catch_warnings is global)
    d = np.abs(np.diag(lu))
    if not np.all(np.isfinite(d)) or d.min() <= 1e-11 * d.max():
        raise InputError(f"static equilibrium at t = {t:g} s is singular or too ill-conditioned to solve "
                         f"(smallest LU pivot {d.min() / max(d.max(), 1e-300):.3g} of the largest): a free body is "
                         "not held by enough closed/bolted contact directions, rigid contacts are redundant, or the "
                         f"contact stiffness (up to {kmax:.3g} N/m) is too many orders above the bodies' own")
    return cs * sla.lu_solve((lu, piv), r * rhs, check_finite=False)


def static_equilibrium(body_a: ModalBody, body_b: ModalBody, contacts, forcing: Forcing,
                       t: float = 0.0) -> InitialState:
    """Modal displacements of both bodies in static equilibrium at time t (section 2.6), zero velocities."""
    return static_solution(body_a, body_b, contacts, forcing, t)[0]


# ------------------------------------------------------------- initial force
def _acceleration(body: ModalBody, key: str, forcing: Forcing, load, t: float, q, v, Pc,
                  static: np.ndarray | None = None) -> np.ndarray:
    """Modal acceleration at time t from the equation of motion: applied load (``load``, the
    body's ModalLoad) + feedback + contact force Pc, less damping and stiffness; 0 for the
    residual-flexibility modes ``static`` (a mask; they have no acceleration)."""
    if body.n_modes == 0:
        return np.zeros(0)
    U, V = feedback_at(body.n_modes, key, forcing, t)
    P = load.at(t) + U @ (V @ np.concatenate([q, v])) + Pc
    acc = P - 2 * body.zeta * body.omega * v - body.omega ** 2 * q
    if static is not None:
        acc[static] = 0.0
    return acc


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
    if rows.laws:  # dashpots: f = -K_C (u + tau u'), a closed normal not in tension; sliding friction points
        from .contact_laws import initial_friction, soft_initial_force

        ud = rows.Phi_a @ state.v_a - rows.Phi_b @ state.v_b
        ap = active & pen
        f[ap] -= rows.tau[ap] * ud[ap] / rows.compliance[ap]
        tension = ap & rows.axial & ~bolted & (rows.sign * f < 0)
        active &= ~tension
        f[tension] = 0.0
        initial_friction(rows, f, active, ud, bolted[rows.axial_column])
        soft_initial_force(rows, f, active, u, bolted[rows.axial_column])
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


def initial_state(problem: TransientProblem) -> InitialState:
    """The state at t0: the one given, zero, or static equilibrium (section 2.6)."""
    pa, pb = problem.body_a, problem.body_b
    if isinstance(problem.initial, InitialState):
        return problem.initial
    if problem.initial == "zero":
        return InitialState(np.zeros(pa.n_modes), np.zeros(pa.n_modes), np.zeros(pb.n_modes), np.zeros(pb.n_modes))
    return static_equilibrium(pa, pb, problem.contacts, problem.forcing, problem.t0)


# ---------------------------------------------------------------- outputs
@dataclass
class OutputPlan:
    """Output rows of one body for the kernel, and where each history lands in its Y (n_t, ntarg):
    columns [0, k) displacement, [k, 2k) velocity, [2k, 3k) acceleration of the labelled
    outputs, then the rigid-body motion (``rb``) and the recoveries (``rec``)."""

    L: np.ndarray                   # (n_rows, n_modes), rows sorted by kind
    kind: np.ndarray                # (n_rows,) 0: q, 1: qdot, 2: qddot
    targ: np.ndarray                # (n_rows,) column of Y each row adds to
    ntarg: int
    k: int                          # number of labelled outputs
    rb: tuple[int, int] | None      # columns of the rigid-body motion (Tx..Rz), None if not defined
    rb_sel: np.ndarray | None       # rigid-body components the body's rigid-body mass determines
    rec: dict                       # recovery name -> (first, last + 1) columns
    const: dict                     # recovery name -> its const (added to its history by split), if any

    def first_row(self, q, v, acc, Y) -> None:
        """Y[0] from the state at t0 (the kernel fills the rows after)."""
        for row in range(self.L.shape[0]):
            x = (q, v, acc)[self.kind[row]]
            Y[0, self.targ[row]] += self.L[row] @ x

    def kernel_rows(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(L, kind, targ) without the rows that are zero throughout (a rigid-body component the
        body's mass does not determine, a recovery's component that no mode loads: 48 of the
        default vehicle's 148 rows): the kernel zeroes each output row before it adds the rows'
        products, so their targets stay exactly 0; the other rows' sums are the same (BLAS may
        split a product with fewer rows otherwise: round-off; the default run's histories came
        out bit for bit). The products skipped were a third of the default's output recovery:
        a default case's solve 0.78 -> 0.70 s (one thread, least of 3, 2026-12-07)."""
        keep = np.flatnonzero(np.any(self.L != 0.0, axis=1))
        if keep.size == self.L.shape[0]:
            return self.L, self.kind, self.targ
        return np.ascontiguousarray(self.L[keep]), self.kind[keep], self.targ[keep]

    def split(self, Y):
        """(displacement, velocity, acceleration, rigid-body motion or None, {recovery: history})."""
        k = self.k
        d, v, a = Y[:, :k], Y[:, k:2 * k], Y[:, 2 * k:3 * k]
        rb = None
        if self.rb is not None:
            rb = Y[:, self.rb[0]:self.rb[1]].copy()
            rb[:, np.setdiff1d(np.arange(6), self.rb_sel)] = np.nan
        rec = {name: Y[:, s0:s1] + self.const[name] if name in self.const else Y[:, s0:s1].copy()
               for name, (s0, s1) in self.rec.items()}
        return d.copy(), v.copy(), a.copy(), rb, rec


def _rigid_body_rows(body: ModalBody):
    """(R (6, n), sel): R q is the rigid-body motion about ref_point, (RB^T M RB)^-1 Phi^T M RB q
    on the components ``sel`` the rigid-body mass determines; (None, None) when it is not defined."""
    if not body.n_modes:
        return None, None
    Mrb = body.rigid_body_mass
    sel = np.flatnonzero(np.abs(np.diag(Mrb)) > 0)
    if not sel.size:
        return None, None
    sub = Mrb[np.ix_(sel, sel)]
    if not np.linalg.cond(sub) < 1e12:
        return None, None
    R = np.full((6, body.n_modes), np.nan)
    R[sel] = np.linalg.solve(sub, body.participation[:, sel].T)
    return R, sel


def output_plan(problem: TransientProblem, key: str) -> OutputPlan:
    """Stacked output rows of body ``key``: labelled outputs, rigid-body motion, recoveries."""
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
    R, rb_sel = _rigid_body_rows(body)
    rb = None
    if R is not None:
        rb = (ntarg, ntarg + 6)
        for d in range(6):
            L.append(np.zeros(n) if d not in rb_sel else R[d]); kind.append(0); targ.append(ntarg + d)
        ntarg += 6
    rec, const = {}, {}
    for r in problem.recoveries:
        if r.body != key:
            continue
        m = len(r.labels)
        for kd, mat in enumerate((r.disp, r.vel, r.acc)):
            if mat is None:
                continue
            for i in range(m):
                L.append(mat[i]); kind.append(kd); targ.append(ntarg + i)
        rec[r.name] = (ntarg, ntarg + m)
        if r.const is not None:
            const[r.name] = r.const
        ntarg += m
    L = np.array(L).reshape(len(kind), n) if kind else np.zeros((0, n))
    order = np.argsort(np.array(kind, dtype=np.int64), kind="stable")  # the kernel wants rows grouped by kind
    return OutputPlan(np.ascontiguousarray(L[order]), np.array(kind, dtype=np.int64)[order],
                      np.array(targ, dtype=np.int64)[order], ntarg, k, rb, rb_sel, rec, const)


# ------------------------------------------------------------- kernel inputs
def step_flexibility(coefs: tuple[StepCoefficients, StepCoefficients], rows, kind: str = "Bc") -> np.ndarray:
    """Relative step flexibility of the contact rows, both bodies: Phi_ca diag(c_a) Phi_ca^T +
    Phi_cb diag(c_b) Phi_cb^T (e = x_a - x_b per unit force on A and its reaction on B)."""
    return coefs[0].flexibility(rows.Phi_a, kind) + coefs[1].flexibility(rows.Phi_b, kind)


def _contact_inputs(rows, coefs) -> tuple[Contact, np.ndarray]:
    """The kernel's contact bundle and W, the step flexibility of the rows (end force -> end
    displacement). With rigid rows the unknowns are x = [f1; g] (kernel.py) and the step
    matrix [[C + W_Bc, W_Ac], [W_Bcd, W_Acd]]; penalty only: C + W on f1 alone. Dashpots
    (tau = c/K_C per row) add diag(tau) times the velocity flexibility to the penalty rows
    (transient/contact_laws.py)."""
    W = step_flexibility(coefs, rows, "Bc")
    rigid = (rows.compliance == 0).any()
    if rigid:
        W2 = np.block([[W, step_flexibility(coefs, rows, "Ac")],
                       [step_flexibility(coefs, rows, "Bcd"), step_flexibility(coefs, rows, "Acd")]])
        C2 = np.concatenate([rows.compliance, np.zeros(rows.n)])
    else:
        W2, C2 = W, rows.compliance.copy()
    Wv = np.zeros((0, W2.shape[0]))
    if rows.laws and (rows.tau > 0).any():
        Wv = step_flexibility(coefs, rows, "Bcd")
        if rigid:
            Wv = np.hstack([Wv, step_flexibility(coefs, rows, "Acd")])
        W2 = W2.copy()
        W2[:rows.n] += rows.tau[:, None] * Wv
    Phi_c = np.ascontiguousarray(np.hstack([rows.Phi_a, -rows.Phi_b]))  # both bodies as one modal set
    axrow = rows.axial_column[rows.contact]
    return Contact(Phi_c, rows.compliance, rows.offset, rows.contact, rows.axial, rows.sign, rows.release,
                   np.ascontiguousarray(W2), C2, bool(rows.laws), rows.tau.copy(), np.ascontiguousarray(Wv),
                   rows.mu.copy(), axrow, rows.axial_column.copy(), rows.latch.copy(), rows.rtravel.copy(),
                   rows.rforce.copy(), rows.rptr.copy()), W


def _modal_inputs(problem: TransientProblem, coefs, loads) -> Modal:
    """The kernel's modal bundle: both bodies as one modal set (a then b), their step
    coefficients, applied loads on one merged time grid and rank-factored feedback."""
    C = np.ascontiguousarray
    pa, pb = problem.body_a, problem.body_b
    na, n = pa.n_modes, pa.n_modes + pb.n_modes
    load_a, load_b = loads
    coef = C(np.hstack([C(coefs[0].packed()), C(coefs[1].packed())]))
    w2 = np.concatenate([pa.omega, pb.omega]) ** 2
    zw2 = 2 * np.concatenate([pa.zeta * pa.omega, pb.zeta * pb.omega])
    const = np.concatenate([load_a.const, load_b.const])
    tk = np.union1d(load_a.times, load_b.times)
    Pk = np.zeros((tk.size, n))
    for ld, cols in ((load_a, slice(0, na)), (load_b, slice(na, None))):
        if ld.times.size:  # exact: each body's table is linear between its own breakpoints
            Pk[:, cols] = interp_columns(tk, ld.times, ld.table)
    U_a, V_a, since_a, until_a = feedback_factors(pa.n_modes, "a", problem.forcing, problem.t0)
    U_b, V_b, since_b, until_b = feedback_factors(pb.n_modes, "b", problem.forcing, problem.t0)
    ra = U_a.shape[1]
    U = np.zeros((n, ra + U_b.shape[1]))
    V = np.zeros((U.shape[1], 2 * n))        # over [q; v] of both bodies
    U[:na, :ra], U[na:, ra:] = U_a, U_b
    V[:ra, :na], V[:ra, n:n + na] = V_a[:, :na], V_a[:, na:]
    V[ra:, na:n], V[ra:, n + na:] = V_b[:, :pb.n_modes], V_b[:, pb.n_modes:]
    since = np.concatenate([since_a, since_b]).astype(float)
    until = np.concatenate([until_a, until_b]).astype(float)
    return Modal(na, coef, w2, zw2, const, tk, C(Pk), C(U), C(V), since, until)


def _histories(problem: TransientProblem, rows, n_t: int, plans) -> History:
    """Zeroed time histories; the modal ones only with ``keep_modal`` (True: q, v, acc of
    both bodies; "q": the modal displacements alone, O(n) per step)."""
    keep = bool(problem.keep_modal)
    full = problem.keep_modal is True
    na, nb = problem.body_a.n_modes, problem.body_b.n_modes
    folder = problem.modal_scratch
    zeros = np.zeros if folder is None else (lambda shape: scratch_array(shape, folder))  # on disk: core/scratch.py
    Qa, Qb = zeros((n_t if keep else 0, na)), zeros((n_t if keep else 0, nb))
    Va, Aa = (zeros((n_t if full else 0, na)) for _ in range(2))
    Vb, Ab = (zeros((n_t if full else 0, nb)) for _ in range(2))
    return History(np.zeros((n_t, plans[0].ntarg)), np.zeros((n_t, plans[1].ntarg)), np.zeros((n_t, rows.n)),
                   np.zeros((n_t, len(rows.names)), dtype=np.int8), np.zeros(n_t, dtype=np.int32), keep,
                   Qa, Va, Aa, Qb, Vb, Ab, np.zeros((3, OUT_BLOCK, na)), np.zeros((3, OUT_BLOCK, nb)),
                   np.zeros(1, dtype=np.int64))


def _start(problem: TransientProblem, rows, contact: Contact, init: InitialState, f0, active0, loads,
           plans, hist: History) -> State:
    """Row 0 of the histories and the kernel state at t0 (contact force f0, active set active0)."""
    pa, pb, fo, t0 = problem.body_a, problem.body_b, problem.forcing, problem.t0
    q_a, v_a, q_b, v_b = (np.array(x, dtype=float) for x in (init.q_a, init.v_a, init.q_b, init.v_b))
    sa, sb = problem.static_modes("a"), problem.static_modes("b")
    v_a[sa], v_b[sb] = 0.0, 0.0              # residual-flexibility modes: no velocity, no acceleration
    a_a0 = _acceleration(pa, "a", fo, loads[0], t0, q_a, v_a, rows.Phi_a.T @ f0, sa)
    a_b0 = _acceleration(pb, "b", fo, loads[1], t0, q_b, v_b, -(rows.Phi_b.T @ f0), sb)
    plans[0].first_row(q_a, v_a, a_a0, hist.Y_a)
    plans[1].first_row(q_b, v_b, a_b0, hist.Y_b)
    hist.Fc[0] = f0
    bolted0 = t0 < rows.release
    hist.state[0] = np.where(bolted0, BOLTED, OPEN)
    for c in range(len(rows.names)):
        if not bolted0[c] and active0[rows.axial_column[c]]:
            hist.state[0, c] = CLOSED
    if hist.keep:
        hist.Qa[0], hist.Qb[0] = q_a, q_b
        if hist.Va.shape[0]:
            hist.Va[0], hist.Aa[0], hist.Vb[0], hist.Ab[0] = v_a, a_a0, v_b, a_b0
    pen0 = np.where(rows.compliance > 0, f0, 0.0)  # rigid rows start each step from their own g
    q0 = np.concatenate([q_a, q_b])
    e0 = contact.Phi @ q0
    anchor, slip, sdir = initial_slip(rows, f0, e0, active0, bolted0)   # contact_laws.py
    soft = initial_soft(rows, f0, e0, bolted0)
    # a point released and open at t0, or closing (a docking begun in contact), may be captured;
    # one at rest in contact (a post released under the vehicle's weight) only after it opens
    ed0 = contact.Phi @ np.concatenate([v_a, v_b])
    opened = np.array([not bolted0[c] and (not active0[a] or rows.sign[a] * ed0[a] < 0.0)
                       for c, a in enumerate(rows.axial_column)], dtype=np.bool_)
    return State(q0, np.concatenate([v_a, v_b]), f0.copy(), active0.copy(),
                 contact.Phi.T @ pen0, np.concatenate([loads[0].at(t0), loads[1].at(t0)]),
                 np.zeros(1, dtype=np.int64), anchor, np.zeros(len(rows.names), dtype=np.bool_), slip, sdir,
                 *soft, opened)


def _new_cache(n2: int, cap: int = 64) -> Cache:
    """Room for ``cap`` active-set patterns of the (n2, n2) step matrix."""
    return Cache(np.zeros((cap, 2 * n2), dtype=np.bool_), np.zeros((cap, n2, n2)), np.zeros(2, dtype=np.int64))


# -------------------------------------------------------------------- solve
def solve(problem: TransientProblem) -> TransientResult:
    """Integrate the two-body problem (see :func:`_solve`) with one BLAS thread.

    The BLAS products of a step are tiny (n_contact_dirs x n_modes) and the set-up products
    a few hundred square: a multi-threaded BLAS only adds synchronisation
    (benchmarks/bench_transient.py: 0.87 s CPU with 2 OpenBLAS threads, 0.65 s with one).
    """
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1, user_api="blas"):
        if problem.accuracy is not None:  # the step is chosen by halving (transient/accuracy.py)
            from .accuracy import solve_estimated

            return solve_estimated(problem).result
        return _solve(problem)


def _solve(problem: TransientProblem, step: StepChoice | None = None, runs: int = 1,
           stop=None, gate=None) -> TransientResult:
    """Run the two-body transient (sections 2.3-2.7) in the steps ``step`` (None: the
    problem's, stepping.choose_step) and return its time histories; ``runs``: results held
    in memory at once (for the memory estimate); ``stop``: a threading.Event that ends the
    run between chunks (Cancelled), for a run marched beside another (accuracy.py);
    ``gate``: offered at each chunk boundary (``gate.checkpoint()``, accuracy.PauseGate), where
    another thread may hold this run while it forks."""
    started = _time.perf_counter()
    pa, pb, fo = problem.body_a, problem.body_b, problem.forcing
    rows = contact_rows(pa, pb, problem.contacts)
    step = step or choose_step(problem, rows)
    check_memory(problem, step.n_steps, runs, f" of h = {step.h:.3g} s; 0.25/f_h = {step.h_default:.3g} s with the "
                                              f"contact frequency f_h = {step.f_h:.4g} Hz",
                 modal_runs=runs if problem.accuracy is not None else 1)   # (accuracy: the pair keeps both runs')
    init = initial_state(problem)
    f0, active0 = initial_contact_force(pa, pb, rows, fo, init, problem.t0)
    coefs = (step_coefficients(pa.omega, pa.zeta, step.h, problem.static_modes("a")),
             step_coefficients(pb.omega, pb.zeta, step.h, problem.static_modes("b")))
    loads = (modal_load(pa, "a", fo), modal_load(pb, "b", fo))
    plans = (output_plan(problem, "a"), output_plan(problem, "b"))
    contact, W = _contact_inputs(rows, coefs)
    hist = _histories(problem, rows, step.n_steps + 1, plans)
    state = _start(problem, rows, contact, init, f0, active0, loads, plans, hist)
    cache = _new_cache(contact.W.shape[0])
    steps = Stepping(float(problem.t0), float(step.h), 0 if problem.method == "direct" else 1,
                     float(problem.tol), int(problem.max_iter))
    out_rows = OutputRows(*plans[0].kernel_rows(), *plans[1].kernel_rows())
    modal = _modal_inputs(problem, coefs, loads)
    inputs = (steps, modal, contact, out_rows)
    guard = GrowthGuard(rows, modal, state, step.h, step.margin)
    guard.start(step.t0, step.t_end)
    _drive(problem, step, inputs, state, cache, hist, lambda: _spectral_radius(W, rows, state.active), guard, stop,
           gate)
    return _result(problem, rows, step, plans, hist, int(cache.used[0]), started, state)


class Cancelled(Exception):
    """A run ended by its ``stop`` event (the other run of its pair failed)."""


def _drive(problem: TransientProblem, step: StepChoice, inputs, state: State, cache: Cache, hist: History,
           radius, guard: GrowthGuard, stop=None, gate=None) -> None:
    """March every step in compiled chunks of CHUNK steps (a progress bar between chunks);
    a failed chunk raises (``radius()``: spectral radius of K_C W for the message), and so
    does a chunk whose energy or contact forces outgrow the bounds of ``guard``; ``gate``:
    its ``checkpoint()`` is called before each chunk (accuracy.PauseGate)."""

    bar = None
    laws = True if inputs[2].laws else None      # the kernel's path (march: compiled without the laws if None)
    if problem.progress and step.n_steps > 4 * CHUNK:
        from tqdm import tqdm

        bar = tqdm(total=step.n_steps, unit="step", desc="transient", leave=False)
    try:
        i = 0
        while i < step.n_steps:
            if gate is not None:
                gate.checkpoint()
            if stop is not None and stop.is_set():
                raise Cancelled(f"stopped at t = {step.t0 + i * step.h:.6g} s")
            i1 = min(i + CHUNK, step.n_steps)
            status, at, info1, info2 = march(i, i1, *inputs, state, cache, hist, laws)
            if status != 0:
                _failure(status, step.t0 + at * step.h, info1, info2, radius)
            if not (np.all(np.isfinite(state.q)) and np.all(np.isfinite(state.v))):
                bad = np.flatnonzero(~np.all(np.isfinite(hist.Fc[i + 1:i1 + 1]), axis=1))
                t_bad = step.t0 + step.h * (i + 1 + (bad[0] if bad.size else 0))
                raise ConvergenceError(f"the solution diverged (non-finite values) at t = {t_bad:.6g} s with "
                                       f"h = {step.h:.4g} s; reduce h")
            guard.check(step.t0 + step.h * i1, state, hist.Fc[i + 1:i1 + 1], step.t0 + step.h * np.arange(i + 1, i1 + 1))
            if problem.modal_scratch is not None:   # the chunk's modal rows to the page cache (core/scratch.py)
                for a in (hist.Qa, hist.Va, hist.Aa, hist.Qb, hist.Vb, hist.Ab):
                    release_rows(a, i, i1 + 1)
            if bar is not None:
                bar.update(i1 - i)
            i = i1
    finally:
        if bar is not None:
            bar.close()


def _failure(status: int, t_fail: float, info1: float, info2: float, radius) -> None:
    """Raise the error of a kernel status code."""
    if status == NO_CONVERGENCE:
        raise ConvergenceError(
            f"contact fixed-point iteration did not converge at t = {t_fail:.6g} s "
            f"(|dF| = {info1:.3g} N after {int(info2)} iterations; spectral radius of K_C W = {radius():.3g})")
    if status == CYCLING:
        raise ConvergenceError(f"contact active set did not settle at t = {t_fail:.6g} s "
                               f"({int(info1)} active-set changes in one step)")
    if status == SINGULAR:
        raise InputError(f"singular contact system at t = {t_fail:.6g} s: rigid contact directions are redundant "
                         "or act on DOFs with no flexibility, or the step matrix is not finite")
    if status == FRICTION_SINGULAR:
        raise ConvergenceError(f"the slip forces mu N make the contact system singular at t = {t_fail:.6g} s "
                               "(friction coefficient too large for this contact geometry)")
    raise ConvergenceError(f"the time loop stopped at t = {t_fail:.6g} s with status {status}")


def _spectral_radius(W, rows, active) -> float:
    """rho(K_C W) on the rows coupled at failure (penalty rows)."""
    act = active & (rows.compliance > 0)
    if not act.any():
        act = rows.compliance > 0
    k = 1.0 / rows.compliance[act]
    return float(np.max(np.abs(np.linalg.eigvals(k[:, None] * W[np.ix_(act, act)]))))


# ------------------------------------------------------------------- result
def contact_events(state: np.ndarray, time: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per contact point: time of the first opening (NaN if never) and the number of recontacts,
    the closings (open -> closed) after that first opening, from the state histories
    (n_t, n_contacts). A contact that starts open and lands once has not recontacted."""
    ncon = state.shape[1]
    sep = np.full(ncon, np.nan)
    rec = np.zeros(ncon, dtype=np.int64)
    for c in range(ncon):
        s = state[:, c]
        opened = np.flatnonzero((s[1:] == OPEN) & (s[:-1] != OPEN)) + 1
        if opened.size:
            sep[c] = time[opened[0]]
            closings = np.flatnonzero((s[1:] == CLOSED) & (s[:-1] == OPEN)) + 1
            rec[c] = int(np.sum(closings > opened[0]))
    return sep, rec


def capture_times(state: np.ndarray, time: np.ndarray, rows) -> dict:
    """{latch contact: first time it is bolted after having been free (None: never captured)}."""
    out = {}
    for c in np.flatnonzero(np.isfinite(rows.latch)):
        s = state[:, c]
        hit = np.flatnonzero((s[1:] == BOLTED) & (s[:-1] != BOLTED)) + 1
        out[rows.names[c]] = float(time[hit[0]]) if hit.size else None
    return out


def _time_or_none(t: float):
    return None if np.isnan(t) else float(t)


def _result(problem: TransientProblem, rows, step: StepChoice, plans, hist: History, n_patterns: int,
            started: float, state: State) -> TransientResult:
    """The TransientResult of a finished run: histories split per body, events, metadata."""
    time = step.time
    sep, rec = contact_events(hist.state, time)
    da, va, aa, rba, reca = plans[0].split(hist.Y_a)
    db, vb, ab, rbb, recb = plans[1].split(hist.Y_b)
    modal = {}
    if hist.keep:
        modal = {"q_a": hist.Qa, "v_a": hist.Va, "acc_a": hist.Aa, "q_b": hist.Qb, "v_b": hist.Vb, "acc_b": hist.Ab}
        modal = {k: v for k, v in modal.items() if v.shape[0]}
    meta = {"h": step.h, "method": problem.method, "tol": problem.tol, "max_iter": problem.max_iter,
            "f_h": step.f_h, "h_default": step.h_default, "f_s": step.f_s, "h_requested": step.h_requested,
            "mode_samples": step.mode_samples if step.h_requested is None else None,   # a given h: no effect
            "stability_margin": step.margin, "n_steps": step.n_steps, "t0": problem.t0,
            "step_governed_by": step.governed_by, "stability_halvings": step.stability_halvings,
            "static_above_hz": problem.static_above_hz,     # residual-flexibility modes above it (None: none)
            "static_modes": [int(problem.static_modes("a").sum()), int(problem.static_modes("b").sum())],
            "t_end": problem.t_end, "body_a": problem.body_a.name, "body_b": problem.body_b.name,
            "wall_time_s": _time.perf_counter() - started, "active_set_patterns": n_patterns,
            "gravity": [float(g) for g in problem.forcing.gravity]}     # m/s^2, the uniform field applied (eq. 14)
    if np.isfinite(rows.latch).any():
        meta["capture_time"] = capture_times(hist.state, time, rows)
    if rows.rtravel.size:
        soft = np.flatnonzero(np.diff(rows.rptr) > 0)
        meta["soft_release"] = {rows.names[c]: {"first_yield": _time_or_none(state.tyield[c]),
                                                "drawn_out": _time_or_none(state.tdrawn[c])} for c in soft}
    items = {r.name: RecoveryItem(r.name, r.body, r.category, r.labels, r.units, r.description,
                                  r.disp is None and r.vel is None) for r in problem.recoveries}
    return TransientResult(
        time=time, contact_names=rows.names, contact_directions=rows.directions, contact_force=hist.Fc,
        contact_state=hist.state, separation_time=sep, recontact_count=rec, release_time=rows.release.copy(),
        output_labels={"a": tuple(problem.outputs["a"]), "b": tuple(problem.outputs["b"])},
        displacement={"a": da, "b": db}, velocity={"a": va, "b": vb}, acceleration={"a": aa, "b": ab},
        recovered={**reca, **recb}, recovery_items=items, rigid_body_motion_a=rba, rigid_body_motion_b=rbb,
        iterations=hist.iters, modal=modal, metadata=meta)
