"""Growth guard: a diverged run stops with an error instead of being saved as a result.

Energy of the two bodies and the penalty springs (modal coordinates mass-normalised):

    E = |v|^2/2 + q^T Omega^2 q/2 + sum over coupled penalty rows f^2/(2 K_C).

Contacts are internal (a penalty spring stores what it takes, a rigid row does no work,
a row opens at zero force or, at release, loses its spring energy) and damping only
removes energy, so along the exact solution dE/dt <= |v| (|P(t)| + beta |q|), P the
applied modal load and beta >= ||B|| the norm of the modal feedback (eq. 26, on while
t < until). With y = sqrt(2 E) and x = |q0| + int y, y' <= |P| + beta x and x' = y;
comparison with the linear system gives

    sqrt(2 E(t)) <= cosh(sqrt(beta) t_b) (sqrt(2 E0) + int_t0^t |P|) + sqrt(beta) |q0| sinh(sqrt(beta) t_b)

with t_b the time the feedback is on. A penalty row then carries at most
|f| <= sqrt(2 K_C E). After every chunk of steps the solver checks the energy of its
state and every penalty force of the chunk against these bounds times a safety factor
(SAFETY on the energy, sqrt(SAFETY) on forces) and the discrete scheme's amplitude
distortion near the stability limit, 1/(1 + margin) (stepping.coupling_margin): a
stable run stays orders of magnitude inside, a diverging one grows geometrically and is
stopped within a few steps of crossing them.

Residual-flexibility modes (TransientProblem.static_above_hz) carry strain energy
P^2/(2 omega^2) with no velocity, which the power bound above does not count; it is tiny
against the bound (omega above the cut, the bound growing with int |P| from the first
step), so a stable run with them stays inside it, but the bound is then no longer a
proof for their share.
"""
from __future__ import annotations

import math

import numpy as np

from liftoff.core.errors import ConvergenceError

from .assembly import interp_columns

SAFETY = 100.0  # on the energy: the discrete scheme's energy differs from the exact one by O((omega h)^2)


class GrowthGuard:
    """Energy and force bounds of one run (module docstring); :meth:`check` after each chunk."""

    def __init__(self, rows, modal, state, h: float, margin: float):
        """``modal``: the kernel's Modal bundle (merged loads, feedback factors); ``state``:
        the kernel State at t0; ``margin``: stepping.coupling_margin at h."""
        self.t0 = 0.0
        self.pts, self.cum = np.zeros(1), np.zeros(1)
        self.comp = rows.compliance
        self.pen = rows.compliance > 0
        self.w2 = np.asarray(modal.w2, dtype=float)
        self.elastic = self.w2 != 0.0            # (a rigid mode's 0 x an overflowed q^2 would be NaN)
        self.x0 = float(np.linalg.norm(state.q))
        self.y0 = math.sqrt(2.0 * self._energy(state))
        U, V = modal.U, modal.V
        norms = np.linalg.norm(U, axis=0) * np.linalg.norm(V, axis=1) if V.shape[0] else np.zeros(0)
        self.beta = float(norms.sum())
        self.until = float(np.max(modal.until)) if modal.until.size else -math.inf
        self.const, self.tk, self.Pk = modal.const, modal.tk, modal.Pk
        # the discrete invariant exceeds the energy by up to 1/(1 + margin) near the limit; never below 1
        self.distortion = 1.0 / max(min(1.0 + margin, 1.0), 1e-3) if math.isfinite(margin) else 1.0

    def _energy(self, state) -> float:
        """Energy of a kernel state (module docstring)."""
        act = np.asarray(state.active, dtype=bool) & self.pen
        q = np.asarray(state.q)
        with np.errstate(over="ignore", invalid="ignore"):
            e = 0.5 * float(state.v @ state.v) + 0.5 * float(np.sum(self.w2[self.elastic] * q[self.elastic] ** 2))
        if act.any():
            e += 0.5 * float(np.sum(state.f[act] ** 2 * self.comp[act]))
        return e

    def start(self, t0: float, t_end: float) -> None:
        """Cumulative bound of int |P| dt at the load breakpoints within [t0, t_end] (the
        load is piecewise linear between them, |P| convex there: the trapezoid bounds it)."""
        self.t0 = t0
        pts = np.unique(np.concatenate([[t0, t_end], self.tk[(self.tk > t0) & (self.tk < t_end)]]))
        if self.tk.size:
            P = self.const[None, :] + interp_columns(pts, self.tk, self.Pk)
        else:
            P = np.broadcast_to(self.const, (pts.size, self.const.size))
        with np.errstate(over="ignore", invalid="ignore"):
            p = np.linalg.norm(P, axis=1)
            self.pts = pts
            self.cum = np.concatenate([[0.0], np.cumsum(0.5 * np.diff(pts) * (p[1:] + p[:-1]))])

    def energy_bound(self, t: float) -> float:
        """Bound of the exact energy at time t (J)."""
        j = min(int(np.searchsorted(self.pts, t - 1e-12 * max(abs(t), 1.0))), self.pts.size - 1)
        work = float(self.cum[j])
        tb = max(0.0, min(t, self.until) - self.t0)
        s = math.sqrt(self.beta)
        with np.errstate(over="ignore"):
            y = float(np.cosh(s * tb)) * (self.y0 + work) + s * self.x0 * float(np.sinh(s * tb))
        return 0.5 * y * y

    def check(self, t: float, state, forces: np.ndarray, times: np.ndarray) -> None:
        """ConvergenceError when the energy of ``state`` (at time t, the chunk's end) or a
        penalty force of the chunk (``forces`` at ``times``, rows x contact rows) exceeds its bound."""
        bad = ~np.isfinite(forces)
        if bad.any():                               # any row, rigid ones too: nothing bounds a NaN
            i, j = np.argwhere(bad)[0]
            raise ConvergenceError(f"the solution diverged: a contact force is {forces[i, j]} at t = {times[i]:.6g} s "
                                   "(transient/guard.py); reduce h")
        eb = self.energy_bound(t)
        if not math.isfinite(eb):
            return
        allowed = max(SAFETY * self.distortion * eb, np.finfo(float).tiny)
        if forces.size and self.pen.any():
            with np.errstate(over="ignore"):         # a bound beyond any float: no force exceeds it
                fmax = np.sqrt(2.0 * allowed / self.comp[self.pen])
            over = np.abs(forces[:, self.pen]) > fmax[None, :]
            if over.any():
                i, j = np.argwhere(over)[0]
                raise ConvergenceError(f"the solution diverged: a contact force of {abs(forces[i, self.pen][j]):.3g} N "
                                       f"at t = {times[i]:.6g} s exceeds {fmax[j]:.3g} N, the most its spring can "
                                       "carry with the energy "
                                       "the initial state and the applied loads can give the bodies "
                                       "(transient/guard.py); reduce h")
        e = self._energy(state)
        if not e <= allowed:                        # (NaN: diverged past any float)
            raise ConvergenceError(f"the solution diverged: its energy {e:.3g} J at t = {t:.6g} s exceeds "
                                   f"{allowed:.3g} J, {SAFETY:g} x the most the initial state and the applied "
                                   "loads can give it (transient/guard.py); reduce h")
