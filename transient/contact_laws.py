"""Contact laws beyond the reference's: Coulomb friction, dashpots in parallel with K_C,
capture latches, soft (controlled) release. The method is described here; the compiled step
is in kernel.py (``_laws_candidates``, ``_solve_laws``, ``_laws_after_step``: beside ``march``, whose
numba cache is keyed on that file alone), entered only when a problem has one of these
laws (``Contact.laws``); the reference's contact law keeps its own path
(kernel._solve_direct), unchanged. This module holds the initial state (numpy).

Per step, as in the kernel: end-of-step relative displacement e = e_free + W f, velocity
e' = e'_free + W_v f (W_v: the velocity step flexibility, coefficients Bcd/Acd).

* **Dashpot** c per direction (tau = c / K_C): while coupled f = -K_C (c0 + e - a) - c e',
  i.e. (C + W + tau W_v)_SS f_S = -(c0 + e_free - a + tau e'_free)_S, the same active-set
  solve with a constant step matrix (folded into W by the solver). A closed normal row
  carries max(0, K_C d + c d'), and only while it penetrates: it opens when that force
  is tensile or when the position has separated, and closes only when both the position
  penetrates and the would-be force is compressive (Kelvin-Voigt with a unilateral clip,
  as Code_Aster's DIS_CHOC with its normal damping).
* **Coulomb friction** mu on the tangent rows T of a released, closed point (normal force
  N = normal_sign f_n > 0), with the tangent K_C as the stick spring anchored at a:
  stick: f_T = -K_T (e_T - a_T) (+ dashpot), kept while |f_T| <= mu N;
  slip:  f_T = mu N d, d the unit direction of the elastic trial force
  g_T = -K_T (e_T - a_T + tau e'_T) at the end of the step (the backward-Euler return
  map of the elastic-plastic analogy; exact for one tangent direction, iterated for
  two), then a_T moves so that the stick relation holds with the slip force. Slip rows
  leave the cached pattern; their forces mu N d, linear in the unknown normal force,
  enter by a rank-k update (k = slipping points) of the pattern's inverse, so N is
  implicit (no lag). Stick <-> slip with a 1e-9 hysteresis on |f_T| / mu N.
* **Latch**: a released point whose normal closes with compression >= latch_force is
  bolted from the next step on (all its directions, tension and compression), its
  tangent rows anchored where they are (no jump in force).
* **Soft release** (``release_force``: a table F(s) of travel s, m -> N; Saturn V's
  controlled-release pins drawn through dies): s = nsign (c0 + e) is the separation of the
  normal row (> 0 open). After release and until the point is *drawn out* (s >= travel[-1]
  at a step end, for good: an ordinary released point from then on) the normal row is
  carried by the pin, in one of three states per row (State.pin, State.yld):
  elastic: in the pattern with u' = u - p_a (p_a = State.panchor, the pin's drawn travel in
  row units; 0 until it yields), so that f = -K_C (c0 + e - p_a): compression, and tension
  up to F; yielding: out of the pattern (like a slipping row) with the known force
  f_P = -nsign F(s_a), s_a the separation at the step start (explicit: F varies over
  centimetres, dF/ds << K_C, so this lag is stable and costs O(h), one step of F's change);
  its force enters the other rows' solve as u' = u + W[:, P] f_P (u kept as it was for the
  residuals) and after the solve fn[P] = f_P; slack: a pin pushed back (compression with
  p_a on the open side) leaves the row to the ordinary released rules (the post closes at
  s < 0) and takes it back when the position passes p_a again.
  Elastic -> yielding when its tension exceeds F(s_a) (1e-9 hysteresis); yielding ->
  elastic when the elastic trial -K_C (c0 + e_end - p_a) (the row's end position with all
  the solved forces, the return map as for slip) is a tension below F or a compression.
  After a yielding step p_a moves so that K_C times the stretch is F (the elastic-plastic
  analogy: the pin is drawn plastically, the work F ds is dissipated, and a mass that stops
  in the dies is held there rather than pulled back). Before its first yield the pin is the
  spring of a closed post: tension K_C s while K_C s <= F(s). Statics (section 2.6) keeps a
  released soft point coupled while its tension is at most F; at t0 a released point's
  tension is capped at F(s0) (yielding if it exceeds it).
* Order of the checks in one solve: stick/slip on the solved pattern first (a point that
  closes in stick with a large trial tangent force must slip before its normal is judged),
  then the normal rows; a point's stick/slip state survives a normal change within the
  step (a point closing while sliding keeps sliding) and is reset only after a step end
  found it open. The soft-release checks come last (pin rows are skipped by the normal
  rules).
"""
from __future__ import annotations

import numpy as np


# ------------------------------------------------------------------ initial state (numpy, not compiled)
def initial_friction(rows, f: np.ndarray, active: np.ndarray, ud: np.ndarray, bolted: np.ndarray) -> None:
    """At t0, a released point that is closed and sliding (tangent relative velocity ud_T != 0)
    already carries its slip force f_T = -mu N ud_T / |ud_T| (in place on f, active): the
    force history then starts right instead of ramping from zero over the first step."""
    for c, a in enumerate(rows.axial_column):
        T = np.flatnonzero((rows.contact == c) & (rows.mu > 0))
        if not T.size or bolted[c] or not active[a]:
            continue
        N = rows.sign[a] * f[a]
        speed = np.linalg.norm(ud[T])
        active[T] = True
        if N > 0 and speed > 0:
            f[T] = -rows.mu[T] * N * ud[T] / speed


def initial_slip(rows, f0: np.ndarray, e0: np.ndarray, active0: np.ndarray, bolted0: np.ndarray):
    """(anchor, slip, sdir) at t0 from the initial contact force: friction rows of released
    points are anchored so that the stick relation holds with their force (unstressed when
    it is zero); those carrying a force are slipping in its direction."""
    anchor = np.zeros(rows.n)
    slip = np.zeros(rows.n, dtype=np.bool_)
    sdir = np.zeros(rows.n)
    for c in range(len(rows.names)):
        T = np.flatnonzero((rows.contact == c) & (rows.mu > 0))
        if not T.size or bolted0[c]:
            continue
        anchor[T] = e0[T] + rows.compliance[T] * f0[T]
        s = np.linalg.norm(f0[T])
        if s > 0 and active0[T].all():
            slip[T] = True
            sdir[T] = f0[T] / s
    return anchor, slip, sdir


# ------------------------------------------------------------------ soft release (numpy, not compiled)
def _soft_points(rows):
    """(contact, normal row, travel, force) of every point with a release_force table."""
    for c in np.flatnonzero(np.diff(rows.rptr) > 0):
        k0, k1 = rows.rptr[c], rows.rptr[c + 1]
        yield int(c), int(rows.axial_column[c]), rows.rtravel[k0:k1], rows.rforce[k0:k1]


def soft_initial_force(rows, f: np.ndarray, active: np.ndarray, u: np.ndarray, bolted: np.ndarray) -> None:
    """At t0, a released soft point not drawn out (separation s0 = normal_sign u below the
    table's end) keeps its normal row coupled: the spring's force, its tension capped at
    F(s0) (in place on f, active; u = c0 + e at t0 per row)."""
    for c, a, travel, force in _soft_points(rows):
        s0 = rows.sign[a] * u[a]
        if bolted[c] or s0 >= travel[-1]:
            continue
        tension = s0 / rows.compliance[a]
        active[a] = True
        f[a] = -rows.sign[a] * min(tension, float(np.interp(s0, travel, force)))


def soft_static_hold(rows, f: np.ndarray) -> np.ndarray:
    """Rows of released soft points that hold their static tension (at most F(s), s = its
    stretch): they stay coupled in static_solution instead of opening."""
    hold = np.zeros(rows.n, dtype=bool)
    for c, a, travel, force in _soft_points(rows):
        tension = -rows.sign[a] * f[a]
        hold[a] = tension <= float(np.interp(tension * rows.compliance[a], travel, force))
    return hold


def initial_soft(rows, f0: np.ndarray, e0: np.ndarray, bolted0: np.ndarray):
    """The kernel's soft-release state at t0 (kernel.State: pin, yld, panchor, fsoft, drawn,
    sep, tyield, tdrawn) from the initial force f0 and relative displacement e0: points not
    drawn out are carried by their pins, yielding where the spring's tension exceeds F(s0)
    (then anchored so that K_C times the stretch is f0)."""
    nc, ncon = rows.n, len(rows.names)
    pin, yld = np.zeros(nc, dtype=np.bool_), np.zeros(nc, dtype=np.bool_)
    panchor, fsoft = np.zeros(nc), np.zeros(nc)
    drawn, sep = np.zeros(ncon, dtype=np.bool_), np.zeros(ncon)
    for c, a, travel, force in _soft_points(rows):
        u = rows.offset[a] + e0[a]
        sep[c] = rows.sign[a] * u
        fsoft[a] = float(np.interp(sep[c], travel, force))
        if not bolted0[c] and sep[c] >= travel[-1]:
            drawn[c] = True
            continue
        pin[a] = True
        if not bolted0[c] and sep[c] / rows.compliance[a] > fsoft[a]:
            yld[a] = True
            panchor[a] = u + rows.compliance[a] * f0[a]
    return pin, yld, panchor, fsoft, drawn, sep, np.full(ncon, np.nan), np.full(ncon, np.nan)
