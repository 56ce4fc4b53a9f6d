"""The contact-coupled step map and its spectral radius: the stability of a step h.

With a set of contact rows coupled (:func:`step_map` takes them as given; the sets a run
passes through: :func:`coupled_sets`) and no load, one step of the kernel (eq. 9-10, the
direct contact solve of section 2.3, transient/kernel.py) is a linear map of the state
x = (q, v, f_P) -- the modal displacements and velocities of both bodies and the penalty
rows' end-of-step forces, which the next step starts from:

    q1 = F q0 + G v0 + Ac (Phi_P^T f0_P + Phi_R^T g) + Bc (Phi_P^T f1_P + Phi_R^T f1_R)
    v1 = Fd q0 + Gd v0 + Acd (...) + Bcd (...)                        (the same loads)

with the unknowns y = (f1_P, f1_R, g) from the rows' conditions at the step end:

    penalty (and dashpot tau = c/K_C):  C f1_P + Phi_P q1 + tau Phi_P v1 = 0
    rigid (Lagrange) rows:              Phi_R q1 = 0,  Phi_R v1 = 0

(g: a rigid row's own start value, kernel.py's module docstring). The step is stable when
every eigenvalue of that map lies in the closed unit disc: :func:`spectral_radius`. This
holds for damping, dashpots and rigid rows, where stepping.coupling_margin (a root at -1
of the undamped penalty coupling) proves nothing.

Modes that carry no contact row and residual-flexibility modes (their q follows the loads,
with no state of its own) are left out: the map's other eigenvalues are theirs alone (a
free mode's exact step: |lambda| <= 1; a static mode's: 0).

The map is formed densely, (2 n_d + n_P)^2 entries (n_d coupled dynamic modes, n_P penalty
rows), and its eigenvalues by LAPACK (with balancing): 4.4 s at the default's 2,924 on
this machine. :data:`DENSE_LIMIT` bounds the size.
"""
from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np

from liftoff.core.records import content_sha256

from .coefficients import step_coefficients

#: the largest map (states) whose eigenvalues are computed (about 40 s on 2 cores)
DENSE_LIMIT = 6000
#: the growth of a spurious step-map mode over a run tolerated as round-off: the eigenvalues of
#: rigid-body modes (lambda = 1, Jordan blocks) scatter by about sqrt(eps |M|) in floating point
GROWTH_TOLERANCE = 1.1


def _tau(rows) -> np.ndarray:
    """The rows' dashpot time constants c/K_C (s; 0 where none: ContactRows.tau may be None)."""
    return np.zeros(rows.n) if rows.tau is None else np.asarray(rows.tau, dtype=float)


def coupled_modes(rows, static=None) -> np.ndarray:
    """Boolean mask over both bodies' modes (a's first) of those in the step map: modes with
    a non-zero entry in a contact row, less the residual-flexibility ones (``static``)."""
    Phi = np.hstack([rows.Phi_a, rows.Phi_b])
    keep = np.any(Phi != 0.0, axis=0)
    if static is not None:
        keep &= ~np.asarray(static, dtype=bool)
    return keep


def map_size(rows, static=None) -> int:
    """The number of states of the step map: 2 coupled dynamic modes + the penalty rows."""
    return 2 * int(coupled_modes(rows, static).sum()) + int(np.sum(rows.compliance > 0))


def step_map(rows, omega: np.ndarray, zeta: np.ndarray, h: float, static=None) -> np.ndarray:
    """The linear step map M (x1 = M x0) of the module docstring, every row of ``rows`` coupled, over the
    state x = (q_d, v_d, f_P): the coupled dynamic modes (:func:`coupled_modes`) and the
    penalty rows. ``omega``, ``zeta``, ``static``: both bodies' modes, a's first."""
    omega, zeta = np.asarray(omega, dtype=float), np.asarray(zeta, dtype=float)
    static = np.zeros(omega.size, bool) if static is None else np.asarray(static, dtype=bool)
    c = step_coefficients(omega, zeta, h, static)
    Phi = np.hstack([rows.Phi_a, -rows.Phi_b])
    pen = rows.compliance > 0
    rig = ~pen
    tau = _tau(rows)
    PP, PR = Phi[pen], Phi[rig]
    nP, nR, n = int(pen.sum()), int(rig.sum()), omega.size
    # the loads of the unknowns y = (f1_P, f1_R, g) on the modes: end values (Bc, Bcd), start (Ac, Acd)
    LB = np.hstack([PP.T, PR.T, np.zeros((n, nR))])      # (n, ny) modal end load per unit y
    LA = np.hstack([np.zeros((n, nP + nR)), PR.T])       # (n, ny) modal start load per unit y
    Yq = c.Bc[:, None] * LB + c.Ac[:, None] * LA         # q1 per unit y
    Yv = c.Bcd[:, None] * LB + c.Acd[:, None] * LA       # v1 per unit y
    # the conditions E (q1, v1) + D y = 0: penalty rows, rigid gaps, rigid velocities
    Eq = np.vstack([PP, PR, np.zeros((nR, n))])
    Ev = np.vstack([tau[pen, None] * PP, np.zeros((nR, n)), PR])
    D = np.zeros((nP + 2 * nR, nP + 2 * nR))
    D[np.arange(nP), np.arange(nP)] = rows.compliance[pen]
    A = D + Eq @ Yq + Ev @ Yv
    # the free step (f1 = 0, g = 0) from x0 = (q0, v0, f0_P): q_free = F q0 + G v0 + Ac Phi_P^T f0_P
    keep = coupled_modes(rows, static)
    d = np.flatnonzero(keep)
    nd = d.size
    N = 2 * nd + nP
    Xq = np.zeros((n, N))     # q_free per unit x0 (all modes; the static ones' F = G = Ac = 0)
    Xv = np.zeros((n, N))
    Xq[d, np.arange(nd)] = c.F[d]
    Xq[d, nd + np.arange(nd)] = c.G[d]
    Xv[d, np.arange(nd)] = c.Fd[d]
    Xv[d, nd + np.arange(nd)] = c.Gd[d]
    Xq[:, 2 * nd:] = c.Ac[:, None] * PP.T
    Xv[:, 2 * nd:] = c.Acd[:, None] * PP.T
    Y = -np.linalg.solve(A, Eq @ Xq + Ev @ Xv)           # (ny, N): y per unit x0
    M = np.empty((N, N))
    M[:nd] = Xq[d] + Yq[d] @ Y
    M[nd:2 * nd] = Xv[d] + Yv[d] @ Y
    M[2 * nd:] = Y[:nP]
    return M


def coupled_sets(rows, contacts, t0: float, t_end: float, h: float) -> list:
    """The active sets a run from t0 to t_end passes through, by the contacts' release
    schedule: [(name, row mask, steps)]. Between consecutive release times in the run a
    contact still bolted couples all its rows, a released one its normal row (in contact),
    with its tangent rows where it has friction (sticking) and all its rows where it has a
    latch (it may be captured); ``steps``: the steps of the run in that set (phases with the
    same set added). Sets with some released rows open, and friction slipping, are not
    among them."""
    contacts = list(contacts)
    rel = np.array([float(c.release_time) for c in contacts])
    cuts = sorted({float(r) for r in rel if t0 < r < t_end})
    edges = [float(t0)] + cuts + [float(t_end)]
    out: dict = {}
    for ts, te in zip(edges[:-1], edges[1:]):
        if not te > ts:
            continue
        mid = 0.5 * (ts + te)
        keep = np.zeros(rows.n, dtype=bool)
        for ci, c in enumerate(contacts):
            on = np.asarray(rows.contact) == ci
            if mid < rel[ci] or c.latch_force is not None:
                keep |= on
            else:
                keep |= on & (np.asarray(rows.axial, dtype=bool) | (c.friction > 0))
        if not keep.any():
            continue
        name = "bolted" if all(mid < r for r in rel) else ("released" if all(mid >= r for r in rel) else
                                                            f"from t = {ts:.6g} s")
        key = keep.tobytes()
        steps = int(math.ceil((te - ts) / h - 1e-9))
        if key in out:
            out[key] = (out[key][0], keep, out[key][2] + steps)
        else:
            out[key] = (name, keep, steps)
    return list(out.values())


def rows_subset(rows, mask: np.ndarray) -> SimpleNamespace:
    """The rows ``mask`` of ``rows`` (what :func:`step_map` reads of them)."""
    tau = _tau(rows)
    return SimpleNamespace(Phi_a=rows.Phi_a[mask], Phi_b=rows.Phi_b[mask], compliance=rows.compliance[mask],
                           tau=tau[mask], n=int(np.sum(mask)))


#: radii computed, by the digest of what they depend on: the cases of a campaign, or an error
#: estimate's runs, share bodies, rows and step, and the default's map takes about 5 s
_RADII: dict = {}
_RADII_KEPT = 32


def spectral_radius(rows, omega: np.ndarray, zeta: np.ndarray, h: float, static=None) -> float:
    """max |lambda| of :func:`step_map` (1 for a map with no state: nothing is coupled); kept
    by the digest of its inputs, so that cases sharing bodies, rows and step compute it once."""
    key = content_sha256((repr(float(h)), rows.Phi_a, rows.Phi_b, rows.compliance,
                          _tau(rows), omega, zeta, static))
    if key in _RADII:
        return _RADII[key]
    M = step_map(rows, omega, zeta, h, static)
    if M.size == 0:
        radius = 1.0
    elif not np.all(np.isfinite(M)):
        radius = math.inf
    else:
        radius = float(np.abs(np.linalg.eigvals(M)).max())
    if len(_RADII) >= _RADII_KEPT:
        _RADII.pop(next(iter(_RADII)))
    _RADII[key] = radius
    return radius
