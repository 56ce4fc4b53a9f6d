"""Contact laws beyond the reference's: Coulomb friction, dashpots in parallel with K_C,
capture latches. The method is described here; the compiled step is in kernel.py
(``_laws_candidates``, ``_solve_laws``, ``_laws_after_step``: beside ``march``, whose
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
* Order of the checks in one solve: stick/slip on the solved pattern first (a point that
  closes in stick with a large trial tangent force must slip before its normal is judged),
  then the normal rows; a point's stick/slip state survives a normal change within the
  step (a point closing while sliding keeps sliding) and is reset only after a step end
  found it open.
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
