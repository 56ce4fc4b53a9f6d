"""The fixed step of a run (section 2.5): its size, its stability and the run's size.

Rules (documented in docs/transient.md, "Step size"):

* automatic step: h_max = min(0.25/f_h (eq. 12), 1/(m f_s), t_end - t0), f_h the contact
  frequency (:func:`estimate_step`), f_s the highest natural frequency of the two bodies
  (of their dynamic modes: residual-flexibility modes, TransientProblem.static_above_hz, are
  solved quasi-statically and neither set f_s nor carry interface mass in f_h),
  m the problem's ``mode_samples`` (steps a period of that mode: 4 by default, 2 to 64; 2
  is the Nyquist rate, at which that mode's own peaks are not resolved). The modal step
  integrates every mode exactly for forces linear over the step (eq. 9-10), so m does not
  limit the modes' integration: it sets how the highest mode is sampled in the histories
  and guards against a soft contact's huge f_h-step;
  the run then takes n = ceil((t_end - t0)/h_max) equal steps of h = (t_end - t0)/n, so
  that the last step ends exactly at t_end;
* a given h is a largest step: when it does not divide t_end - t0 the run takes the same
  n = ceil((t_end - t0)/h) equal steps of (t_end - t0)/n (<= h), with a warning;
* the penalty coupling is stable while every eigenvalue of K_C^1/2 H(-1) K_C^1/2 exceeds
  -1 (:func:`coupling_margin`); a given h beyond that limit is refused, an automatic one
  is halved until stable;
* a given h above 0.25/f_h is also checked through the spectral radius of the
  contact-coupled step map in the active sets of the release schedule (:func:`check_step_map`,
  transient/step_map.py): damped pairs and rigid rows, which the margin does not cover,
  and the h/2 runs of such a step; refused when a mode of the map grows by more than
  step_map.GROWTH_TOLERANCE over the run, or when the map is too large to be checked;
* the time axis must resolve the step: the spacing of floats at max(|t0|, |t_end|) must
  be below 1e-6 h;
* the run's memory (histories, step matrices, dense statics) is estimated before it
  starts (:func:`memory_estimate`) and refused beyond ``memory_limit`` (default: 80 % of
  the memory available when the run starts) with a :class:`ResourceError`.
"""
from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, replace

import numpy as np

from liftoff.core.errors import InputError, ResourceError
from liftoff.core.memory import MEMORY_FRACTION, available_memory  # noqa: F401  (also imported from here)
from liftoff.core.scratch import on_disk

from .assembly import contact_rows
from .body import ModalBody
from .coefficients import step_coefficients
from .model import DEFAULT_MODE_SAMPLES, TransientProblem, static_mask

STABILITY = math.sqrt(3) / math.pi  # rigid bodies: 2 pi f_h h < 2 sqrt(3) (0.551/f_h), the linear-acceleration limit
TIME_RESOLUTION = 1e-6              # the float spacing of the time axis must stay below this fraction of h
DIVIDES = 1e-6                      # a step that overshoots t_end by less than this fraction of h divides the span


# ----------------------------------------------------------------- frequencies
def estimate_step(body_a: ModalBody, body_b: ModalBody, contacts,
                  static_above_hz: float | None = None) -> tuple[float, float]:
    """(f_h in Hz, h = 0.25/f_h in s) from the bodies reduced to the contact DOFs (eq. 12);
    without contacts (a plain modal transient) f_h is the highest dynamic modal frequency.

    Penalty directions: the interface masses (Phi_c Phi_c^T)^-1 of both bodies coupled by
    K_C, i.e. omega_h^2 = lambda_max(K_C^1/2 (Phi_ca Phi_ca^T + Phi_cb Phi_cb^T) K_C^1/2)
    (body stiffness negligible against K_C). Rigid directions: the highest frequency of the
    coupled modal system with those directions constrained (conservative).

    ``static_above_hz``: the residual-flexibility modes above it (TransientProblem) carry no
    interface mass; their static flexibility Phi_s Omega_s^-2 Phi_s^T is in series with the
    contact springs: omega_h^2 = lambda_max of W0_dyn x = lambda (K_C^-1 + that) x. The
    rigid directions' estimate keeps the dynamic modes only (static modes taken as rigid:
    stiffer, so conservative)."""
    rows = contact_rows(body_a, body_b, contacts)
    sa, sb = static_mask(body_a.omega, static_above_hz), static_mask(body_b.omega, static_above_hz)
    if rows.n == 0:       # a plain modal transient: resolve the highest mode instead
        f_h = highest_frequency(body_a, body_b, static_above_hz)
        return f_h, (0.25 / f_h if f_h > 0 else math.inf)     # rigid bodies only: any h is exact
    da, db = ~sa, ~sb
    W0 = rows.Phi_a[:, da] @ rows.Phi_a[:, da].T + rows.Phi_b[:, db] @ rows.Phi_b[:, db].T
    pen = rows.compliance > 0
    w2 = 0.0
    with np.errstate(all="ignore"):
        if pen.any():
            k = np.sqrt(1.0 / rows.compliance[pen])
            Wk = k[:, None] * W0[np.ix_(pen, pen)] * k[None, :]
            if sa.any() or sb.any():      # K_C^1/2 (K_C^-1 + C_s) K_C^1/2 = I + K_C^1/2 C_s K_C^1/2 (SPD)
                Cs = ((rows.Phi_a[:, sa] / body_a.omega[sa] ** 2) @ rows.Phi_a[:, sa].T
                      + (rows.Phi_b[:, sb] / body_b.omega[sb] ** 2) @ rows.Phi_b[:, sb].T)[np.ix_(pen, pen)]
                from scipy.linalg import eigh

                S = np.eye(k.size) + k[:, None] * Cs * k[None, :]
                w2 = max(w2, float(eigh(0.5 * (Wk + Wk.T), 0.5 * (S + S.T), eigvals_only=True).max()))
            else:
                w2 = max(w2, float(np.linalg.eigvalsh(Wk).max()))
        if (~pen).any():
            D = np.hstack([rows.Phi_a[:, da], -rows.Phi_b[:, db]])
            Om2 = np.concatenate([body_a.omega[da] ** 2, body_b.omega[db] ** 2])
            w2 = max(w2, _constrained_max_eig(Om2, D[pen], 1.0 / rows.compliance[pen], D[~pen]))
    if not math.isfinite(w2):
        raise InputError("cannot estimate the step size: the contact frequency overflows (stiffness "
                         f"{np.max(1.0 / rows.compliance[pen]) if pen.any() else 0:.3g} N/m against mode-shape "
                         f"entries up to {np.abs(W0).max() ** 0.5:.3g})")
    if not w2 > 0 and (sa.any() or sb.any()):     # the contact rows see static modes only: quasi-static
        f_h = highest_frequency(body_a, body_b, static_above_hz)
        return f_h, (0.25 / f_h if f_h > 0 else math.inf)
    if not w2 > 0:
        raise InputError("cannot estimate the step size: the contact model has no frequency; give h explicitly")
    f_h = math.sqrt(w2) / (2 * math.pi)
    return f_h, 0.25 / f_h


DENSE_EIG = 400  # modes: below this the constrained eigenproblem is solved densely


def _constrained_max_eig(Om2: np.ndarray, Dp: np.ndarray, kp: np.ndarray, Dr: np.ndarray) -> float:
    """Largest eigenvalue of K = diag(Om2) + Dp^T diag(kp) Dp (mass-normalised modes) on the
    null space of the rigid rows Dr. Small problems: dense, on an orthonormal null-space
    basis. Otherwise Lanczos (scipy eigsh, rtol 1e-10, fixed start vector) on the operator
    P K P with the projector P = I - Dr^+ Dr applied through Dr's rows: O(n) per product,
    no n x n matrix."""
    n = Om2.size
    if n <= DENSE_EIG:
        Kfull = np.diag(Om2) + Dp.T @ (kp[:, None] * Dp)
        u, s, vt = np.linalg.svd(Dr)
        r = int(np.sum(s > 1e-12 * max(s[0], 1e-300)))
        N = vt[r:].T
        return float(np.linalg.eigvalsh(N.T @ Kfull @ N).max()) if N.shape[1] else 0.0
    from scipy.sparse.linalg import LinearOperator, eigsh

    Q, s, _ = np.linalg.svd(Dr.T, full_matrices=False)       # (n, n_r): orthonormal basis of Dr's rows
    Q = Q[:, s > 1e-12 * max(s[0], 1e-300)]

    def project(x):
        return x - Q @ (Q.T @ x)

    def matvec(x):
        y = project(np.ravel(x))
        return project(Om2 * y + Dp.T @ (kp * (Dp @ y)))

    op = LinearOperator((n, n), matvec=matvec, dtype=float)
    v0 = project(np.cos(np.arange(n) + 0.5))
    return float(eigsh(op, k=1, which="LA", tol=1e-10, v0=v0, return_eigenvectors=False)[0])


def highest_frequency(body_a: ModalBody, body_b: ModalBody, static_above_hz: float | None = None) -> float:
    """f_s (Hz): the highest natural frequency of the two bodies' dynamic modes (those not
    above ``static_above_hz``; 0 if all modes are rigid)."""
    w = np.concatenate([body_a.omega[~static_mask(body_a.omega, static_above_hz)],
                        body_b.omega[~static_mask(body_b.omega, static_above_hz)]])
    return float(w.max()) / (2 * math.pi) if w.size else 0.0


def coupling_margin(rows, omega: np.ndarray, zeta: np.ndarray, h: float, static=None) -> float:
    """lambda_min(K^1/2 Phi_c diag(r(h)) Phi_c^T K^1/2) over the penalty rows, all coupled.

    A step alternating in sign, x_k = (-1)^k x, solves the step recursion of a mode
    (eq. 9-10: s1 = A s0 + a P0 + b P1, s = (q, v)) when s = (A + I)^-1 (b - a) P: its
    displacement is r(h) P with r = ((Gd + 1)(Bc - Ac) - G (Bcd - Acd)) / det(A + I). The
    penalty rows f = -K_C e then have such a solution, and the scheme a root at -1, when an
    eigenvalue of K^1/2 Phi diag(r) Phi^T K^1/2 is -1: the step is stable while the margin
    is > -1 (a rigid mass: r = -h^2/12, margin -omega^2 h^2/12, Newmark's linear-acceleration
    limit omega h < 2 sqrt(3)). Coupling fewer rows (released or open) gives a principal
    submatrix, whose smallest eigenvalue is not smaller (Cauchy interlacing): the
    all-coupled set is the worst one. Rigid rows are left out. Returns +inf when there is
    no penalty row. ``static``: the residual-flexibility modes (mask over ``omega``): r = 1/omega^2
    (their coefficients, transient/coefficients.py), which only adds to the margin."""
    pen = rows.compliance > 0
    if not pen.any():
        return math.inf
    c = step_coefficients(omega, zeta, h, static)
    bad = ~np.all(np.isfinite(c.packed()), axis=0)
    if bad.any():
        m = int(np.argmax(bad))
        raise InputError(f"the step coefficients of mode {m} (omega = {omega[m]:.4g} rad/s, zeta = {zeta[m]:.4g}) "
                         f"are not finite at h = {h:.4g} s")
    with np.errstate(all="ignore"):
        det = (c.F + 1.0) * (c.Gd + 1.0) - c.G * c.Fd
        r = ((c.Gd + 1.0) * (c.Bc - c.Ac) - c.G * (c.Bcd - c.Acd)) / det
        Phi = np.hstack([rows.Phi_a, -rows.Phi_b])[pen]
        k = np.sqrt(1.0 / rows.compliance[pen])
        H = k[:, None] * ((Phi * r) @ Phi.T) * k[None, :]
        if not np.all(np.isfinite(H)):
            return -math.inf
        return float(np.linalg.eigvalsh(0.5 * (H + H.T)).min())


def stability_limit(rows, omega, zeta, h_stable: float, h_unstable: float, static=None) -> float:
    """A step between h_stable (margin > -1) and h_unstable (margin <= -1) at the edge of
    stability, by bisection (30 halvings: 1e-9 of the bracket)."""
    lo, hi = h_stable, h_unstable
    for _ in range(30):
        mid = 0.5 * (lo + hi)
        if coupling_margin(rows, omega, zeta, mid, static) > -1.0:
            lo = mid
        else:
            hi = mid
    return lo


# ----------------------------------------------------------------- the step
@dataclass
class StepChoice:
    """The fixed step of a run (section 2.5): n_steps equal steps of h from t0 to t_end.

    f_h: the contact frequency (Hz) and h_default = 0.25/f_h (eq. 12); f_s: the highest
    natural frequency of the bodies (Hz); h_requested: the step given (None: automatic);
    margin: :func:`coupling_margin` at h (> -1: stable); mode_samples: the automatic step's
    steps a period of the f_s mode (TransientProblem.mode_samples); governed_by: the rule
    that set h ("eq. 12": 0.25/f_h, "mode samples": 1/(m f_s), "run": the run's length,
    "given": the problem's h); stability_halvings: how often the automatic step was halved
    for the stability of the penalty coupling."""

    h: float
    f_h: float
    h_default: float
    n_steps: int
    t0: float
    t_end: float
    f_s: float = 0.0
    h_requested: float | None = None
    margin: float = math.inf
    mode_samples: float = DEFAULT_MODE_SAMPLES
    governed_by: str = "given"
    stability_halvings: int = 0

    @property
    def time(self) -> np.ndarray:
        """(n_steps + 1,) the time of every step end (s); the last one is t_end exactly."""
        t = self.t0 + self.h * np.arange(self.n_steps + 1)
        t[-1] = self.t_end
        return t

    def halved(self, problem: TransientProblem | None = None, governed_by: str | None = None) -> "StepChoice":
        """The same run in steps of h/2 (twice as many); with ``problem``, the coupling's
        stability margin at h/2 (:func:`coupling_margin`: the results file and the growth
        guard took the one at h) and ``governed_by`` (the accuracy halvings' "accuracy")."""
        half = replace(self, h=0.5 * self.h, n_steps=2 * self.n_steps)
        if problem is not None:
            omega, zeta, static = _modes(problem)
            rows = contact_rows(problem.body_a, problem.body_b, problem.contacts)
            half = replace(half, margin=coupling_margin(rows, omega, zeta, half.h, static))
            if above_eq12(half.h, half.h_default, rows):    # a given step's halving: as choose_step
                check_step_map(problem, rows, omega, zeta, half.h, static, half.f_h, half.h_default)
        return half if governed_by is None else replace(half, governed_by=governed_by)


def _modes(problem: TransientProblem) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """omega, zeta and the residual-flexibility mask of both bodies' modes, a's first."""
    pa, pb = problem.body_a, problem.body_b
    return (np.concatenate([pa.omega, pb.omega]), np.concatenate([pa.zeta, pb.zeta]),
            np.concatenate([problem.static_modes("a"), problem.static_modes("b")]))


def _steps(span: float, h_max: float) -> int:
    """The number of equal steps of at most h_max (up to DIVIDES of a step) that span the run."""
    n = math.ceil(span / h_max - DIVIDES)
    return max(int(n), 1)


#: frequencies (Hz) a structure's modes and contact springs may set; a step set by higher ones
#: points at the stiffnesses or frequencies given, a lower one at the run's length
PLAUSIBLE_HZ = 1e6


def _check_resolution(t0: float, t_end: float, h: float, f_h: float | None = None, f_s: float | None = None) -> None:
    """InputError when floats near the run's times are coarser than TIME_RESOLUTION h. Said
    as what can be changed: a run far from t = 0 (shift it), or a step that bodies with
    frequencies far beyond any structure's set (check the stiffnesses and modes, SI units)."""
    t_big = max(abs(t0), abs(t_end))
    ulp = float(np.spacing(t_big))
    if ulp <= TIME_RESOLUTION * h:
        return
    span = t_end - t0
    head = (f"time step h = {h:.4g} s is below the resolution of the time axis: floats near t = {t_big:.6g} s are "
            f"{ulp:.3g} s apart (more than {TIME_RESOLUTION:g} h); ")
    if abs(t0) > span:             # a run far from t = 0: shifting it helps
        raise InputError(head + "start the run near t0 = 0 (shift the times of the scenario)")
    fast = max(f for f in (f_h, f_s, 0.0) if f is not None and math.isfinite(f))
    if fast <= PLAUSIBLE_HZ:        # a structure's step: the run is what is too long
        raise InputError(head + f"the run to t_end = {t_end:.6g} s would take {span / h:.3g} steps of it: give a "
                         "shorter run (t_end)")
    which = (f"the contact stiffnesses set f_h = {f_h:.4g} Hz" if f_h and fast == f_h else
             f"the bodies' highest mode is {fast:.4g} Hz") if fast > 0 else "the step given is that small"
    raise InputError(head + f"{which}, far beyond a structure's: check the stiffnesses and mode frequencies "
                     "(SI units: N/m, rad/s) or give a shorter run")


def _no_contact_frequency(problem: TransientProblem, rows) -> bool:
    """Whether the contact model has no frequency at all: no elastic mode and no penalty row
    (rigid rows on rigid-body modes)."""
    elastic = np.any(problem.body_a.omega > 0) or np.any(problem.body_b.omega > 0)
    return not elastic and not np.any(rows.compliance > 0)


def choose_step(problem: TransientProblem, rows=None) -> StepChoice:
    """The step of ``problem`` by the rules of the module docstring. Warns when a given h is
    larger than 0.25/f_h (eq. 12) or does not divide the run; InputError when it exceeds
    the stability limit of the penalty coupling or the resolution of the time axis."""
    rows = rows if rows is not None else contact_rows(problem.body_a, problem.body_b, problem.contacts)
    try:
        f_h, h_default = estimate_step(problem.body_a, problem.body_b, problem.contacts, problem.static_above_hz)
    except InputError:
        if problem.h is None or not _no_contact_frequency(problem, rows):
            raise
        f_h, h_default = 0.0, math.inf       # rigid rows on rigid-body modes alone: no frequency, h given (any is exact)
    f_s = highest_frequency(problem.body_a, problem.body_b, problem.static_above_hz)
    t0, t_end = float(problem.t0), float(problem.t_end)
    span = t_end - t0
    if not math.isfinite(span):
        raise InputError(f"the run from t0 = {t0:g} s to t_end = {t_end:g} s is too long for floats")
    omega, zeta, static = _modes(problem)
    if problem.h is None:
        if not math.isfinite(h_default):
            raise InputError("cannot choose the step: no contacts and no dynamic elastic modes (any above "
                             "static_above_hz are solved quasi-statically); give h explicitly")
        limits = {"eq. 12": h_default, "mode samples": 1.0 / (problem.mode_samples * f_s) if f_s > 0 else math.inf,
                  "run": span}
        governed_by = min(limits, key=limits.get)
        n = _steps(span, limits[governed_by])
        margin = coupling_margin(rows, omega, zeta, span / n, static)
        halvings = 0
        for _ in range(60):  # the automatic step is halved until the coupling is stable
            if margin > -1.0:
                break
            n *= 2
            halvings += 1
            margin = coupling_margin(rows, omega, zeta, span / n, static)
        _check_resolution(t0, t_end, span / n, f_h, f_s)
        return StepChoice(span / n, f_h, h_default, n, t0, t_end, f_s, None, margin, problem.mode_samples,
                          governed_by, halvings)
    h_req = float(problem.h)
    n = _steps(span, h_req)
    h = span / n
    _check_resolution(t0, t_end, h, f_h, f_s)
    margin = coupling_margin(rows, omega, zeta, h, static)
    if not margin > -1.0:
        h_ok = _stable_below(rows, omega, zeta, min(h_default, h), h, static)
        raise InputError(f"time step h = {h:.4g} s exceeds the stability limit of the penalty contact coupling, "
                         f"about {h_ok:.4g} s for these bodies and contact stiffnesses ({STABILITY:.3f}/f_h = "
                         f"{STABILITY / f_h:.4g} s for rigid bodies, f_h = {f_h:.4g} Hz): the run would diverge; "
                         f"give h below {h_ok:.4g} s or h = \"auto\"")
    if above_eq12(h, h_default, rows):
        # the penalty test above proves no more than that no mode alternates in sign step to step:
        # with damping a complex pair can leave the unit circle at a step it passes, and rigid rows
        # have no such test; the step map's spectral radius covers both (transient/step_map.py)
        radius = check_step_map(problem, rows, omega, zeta, h, static, f_h, h_default)
        warnings.warn(f"time step h = {h:.4g} s is larger than 0.25/f_h = {h_default:.4g} s (f_h = {f_h:.4g} Hz, "
                      f"eq. 12): the contact force may be under-resolved (the contact coupling is stable by its step "
                      f"map in the release schedule's active sets, spectral radius {radius:.6f}; feedback loads, "
                      "eq. 26, are not in the map): check the peaks against a run at h = \"auto\"", stacklevel=4)
    if abs(h - h_req) > 1e-9 * h_req:
        warnings.warn(f"time step h = {h_req:.6g} s does not divide the run ({span:.6g} s): using {n} equal steps "
                      f"of {h:.6g} s so that the last one ends at t_end = {t_end:.6g} s", stacklevel=4)
    return StepChoice(h, f_h, h_default, n, t0, t_end, f_s, h_req, margin, problem.mode_samples)


def above_eq12(h: float, h_default: float, rows) -> bool:
    """Whether a step is above 0.25/f_h (eq. 12, to 1e-9) with contact rows (without them
    every h is exact): warned of, and checked by the step map (:func:`check_step_map`)."""
    return h > h_default * (1 + 1e-9) and rows.n > 0


def check_step_map(problem: TransientProblem, rows, omega, zeta, h: float, static, f_h: float,
                   h_default: float) -> float:
    """The largest spectral radius of the contact-coupled step map at h (transient/step_map.py)
    over the active sets the run passes through (step_map.coupled_sets: by the contacts'
    release schedule); InputError when a mode of a set grows by more than
    step_map.GROWTH_TOLERANCE over the steps the run spends in it, or when the map is too
    large (step_map.DENSE_LIMIT states) to be checked. For steps above 0.25/f_h only
    (eq. 12): the automatic step is held to it."""
    from .step_map import DENSE_LIMIT, GROWTH_TOLERANCE, coupled_sets, map_size, rows_subset, spectral_radius

    size = map_size(rows, static)
    keep = f"give h at most 0.25/f_h = {h_default:.4g} s (f_h = {f_h:.4g} Hz, eq. 12) or h = \"auto\""
    if size > DENSE_LIMIT:
        raise InputError(f"time step h = {h:.4g} s is above 0.25/f_h, where the stability of the contact coupling "
                         f"is checked through the step map's eigenvalues, and this model's map has {size} states "
                         f"(more than {DENSE_LIMIT} cannot be checked here): {keep}")
    worst = 0.0
    for name, mask, steps in coupled_sets(rows, problem.contacts, float(problem.t0), float(problem.t_end), h):
        radius = spectral_radius(rows_subset(rows, mask), omega, zeta, h, static)
        growth = radius ** steps if radius > 1.0 else 1.0
        if not growth <= GROWTH_TOLERANCE:
            which = {"bolted": "every contact bolted", "released": "every contact released, in contact"}.get(
                name, f"the contacts as they are {name}")
            raise InputError(f"time step h = {h:.4g} s is unstable with these contacts: the contact-coupled step map "
                             f"({which}) has spectral radius {radius:.6g}, a growth of {growth:.3g} over the "
                             f"{steps} steps the run spends so; {keep}")
        worst = max(worst, radius)
    return worst


def _stable_below(rows, omega, zeta, h_try: float, h_bad: float, static=None) -> float:
    """The first edge of stability above a stable step below h_bad: from h_try (halved
    until stable) up in steps of 5 % to the first unstable step, then bisection (the
    margin need not be monotone in h; this is the edge nearest the stable step)."""
    lo = min(h_try, 0.5 * h_bad)
    for _ in range(60):
        if coupling_margin(rows, omega, zeta, lo, static) > -1.0:
            break
        lo *= 0.5
    hi = lo
    while hi < h_bad:
        hi = min(1.05 * hi, h_bad)
        if not coupling_margin(rows, omega, zeta, hi, static) > -1.0:
            return stability_limit(rows, omega, zeta, hi / 1.05, hi, static)
    return stability_limit(rows, omega, zeta, lo, h_bad, static)


# ----------------------------------------------------------------- run size
def memory_estimate(problem: TransientProblem, n_steps: int, runs: float = 1,
                    modal_runs: float = 1) -> dict[str, float]:
    """Bytes the transient needs, by item: time histories (n_t x columns, 8 bytes each;
    ``runs`` of them held at once, e.g. 3 for a run with its h/2 error-estimate run), the
    modal histories of ``keep_modal`` (q, v and acc per mode, or q alone for ``"q"``;
    ``modal_runs`` of them: one for a run with its error estimate, whose h/2 run keeps none,
    as many as ``runs`` with an accuracy target, whose finer run keeps them too, as it may
    become the result: accuracy.solve_estimated; none in memory with ``modal_scratch`` on
    disk: liftoff.core.scratch.on_disk), the copies of the output and recovery histories made
    as a run ends, the
    active-set cache of the step matrix (64 patterns) and the dense static solve (about
    five (n + n_rigid)^2 arrays)."""
    pa, pb = problem.body_a, problem.body_b
    n_t = float(n_steps) + 1.0
    nc = sum(c.n_dirs for c in problem.contacts)
    nrig = sum(c.n_dirs for c in problem.contacts if c.rigid)
    cols = nc + 1 + 0.125 * len(problem.contacts) + 0.5  # forces, time, state (int8), iterations (int32)
    out_cols = 0.0                   # output and recovery columns: the result's copies of the kernel's (split)
    for key, body in (("a", pa), ("b", pb)):
        out_cols += 3 * len(problem.outputs.get(key, ())) + (6 if body.n_modes else 0)
    out_cols += sum(len(r.labels) for r in problem.recoveries)
    cols += out_cols
    n = pa.n_modes + pb.n_modes
    n2 = 2 * nc if nrig else nc
    return {"histories": 8.0 * n_t * cols * runs,
            # the result's output and recovery histories are copied out of the kernel's arrays while
            # those are held (solver.OutputPlan.split), once, as a run ends: the largest copy is the
            # h/2 run's, twice this run's steps where ``runs`` counts a pair at h (3), this run's
            # own otherwise (a toy run of 300 recovery columns peaked at 116 MB against 52 MB
            # counted without it)
            "output copies": 8.0 * n_t * out_cols * (2.0 if runs >= 3 else 1.0),
            "modal histories (keep_modal)": 8.0 * n_t * (3 if problem.keep_modal is True else 1) * n * modal_runs
            if problem.keep_modal and not _modal_on_disk(problem) else 0.0,
            "active-set cache": 8.0 * 64 * n2 * n2,
            "dense statics": 8.0 * 5 * (n + nrig) ** 2}


def _modal_on_disk(problem: TransientProblem) -> bool:
    """Whether the modal histories live in a scratch file out of memory (modal_scratch on disk)."""
    return problem.modal_scratch is not None and on_disk(problem.modal_scratch)


def check_memory(problem: TransientProblem, n_steps: int, runs: float = 1, step: str = "",
                 modal_runs: float = 1) -> float:
    """The estimate of :func:`memory_estimate` (bytes); ResourceError beyond the limit
    (``problem.memory_limit`` bytes, None: MEMORY_FRACTION of the memory available);
    ``step``: how the step came about, for the message."""
    parts = memory_estimate(problem, n_steps, runs, modal_runs)
    total = sum(parts.values())
    limit = problem.memory_limit
    if limit is None:
        limit = MEMORY_FRACTION * available_memory()
    if total > limit:
        big = max(parts, key=parts.get)
        raise ResourceError(f"the transient needs about {total / 1e9:.3g} GB ({big} {parts[big] / 1e9:.3g} GB: "
                            f"{n_steps + 1} time points{step}) but the limit is {limit / 1e9:.3g} GB; use fewer steps "
                            "(a larger h or a shorter run), fewer outputs or modes, or raise the limit "
                            "(--max-memory GB on the command line, memory_limit of TransientProblem)")
    return total
