"""Normal modes of an FE model: K phi = omega^2 M phi, mass-normalised (Phi^T M Phi = I).

Shift-and-invert about a small *negative* shift sigma = -(2 pi shift_hz)^2 so that
K - sigma M is positive definite for a free-free body as for a clamped one (a shift of 0
relies on round-off in the factorisation of a singular K; FENICSX-NOTES.md). The modes
nearest sigma are then the lowest ones. A mode below ``rigid_tol_hz`` is "near-zero":
a free-free body must have exactly six (its rigid-body modes, reported with omega = 0),
a clamped body none; anything else is a floating part or a missing tie and is an error.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from liftoff.core.errors import InputError

from . import petsc_backend as pb
from .model import FEModel


@dataclass
class Modes:
    """Eigenvalues omega^2 (rad^2/s^2, raw, rigid ones ~ round-off) and shapes (n_dof, n)."""

    eigenvalues: np.ndarray
    shapes: np.ndarray
    n_rigid: int

    @property
    def omega(self) -> np.ndarray:
        """Circular frequencies (rad/s); exactly 0 for the rigid-body modes."""
        w = np.sqrt(np.clip(self.eigenvalues, 0.0, None))
        w[: self.n_rigid] = 0.0
        return w

    @property
    def freq_hz(self) -> np.ndarray:
        return self.omega / (2 * np.pi)

    def __len__(self) -> int:
        return self.eigenvalues.size


def _check_singular(model: FEModel, lam: np.ndarray, rigid_tol_hz: float, floor: float = 0.0) -> int:
    """Near-zero modes of ``lam`` (those below ``rigid_tol_hz``, or within ``floor``, the
    round-off of the geometric rigid modes' Rayleigh quotients: :func:`_rigid_modes`);
    InputError where their number does not fit the model (6 free-free, 0 clamped)."""
    f = np.sqrt(np.abs(lam)) / (2 * np.pi)
    zero = (f < rigid_tol_hz) | (np.abs(lam) <= floor)
    n_zero = int(np.sum(zero))
    count = f"at least {n_zero}" if n_zero == lam.size else str(n_zero)
    if model.grounded and n_zero:
        raise InputError(f"model {model.name!r} (clamped on {', '.join(model.clamped)}) has {count} "
                         f"near-zero modes (< {rigid_tol_hz:g} Hz): a floating part, a missing tie or clamp")
    if not model.grounded and n_zero > 6:
        raise InputError(f"free-free model {model.name!r} has {count} near-zero modes (< {rigid_tol_hz:g} Hz), "
                         "more than its 6 rigid-body modes: a floating part or a missing tie")
    if not model.grounded and n_zero < 6 and lam.size >= 6:
        raise InputError(f"free-free model {model.name!r} shows only {n_zero} rigid-body modes below "
                         f"{rigid_tol_hz:g} Hz (lowest frequencies {np.round(f[:7], 4)} Hz): "
                         "rigid-body modes not clean; raise rigid_tol_hz or check the model")
    return n_zero


def _rigid_modes(model: FEModel) -> tuple[np.ndarray, np.ndarray, float]:
    """Geometric rigid-body modes, M-orthonormalised (eigenvalues = Rayleigh quotients), and
    the round-off of those quotients: eps |phi|^T |K| |phi| (the largest over the six). K RB
    is zero only to the round-off of K's entries, each about eps of its own magnitude, so a
    rigid mode's quotient is of that order, not zero: a shell glued on a block 1000 x stiffer
    (tests/fem/test_shell_model.py) gave 0.0108 Hz in one run of the suite and 0.0069 Hz in
    another (2026-12-01, one machine: its 0.01 Hz tolerance alone refused it), its quotients
    0.05-4 % of this bound; the bound's worst case, every error of one sign, is the nonzeros
    of a row times larger."""
    K, M = model.matrices()
    RB = model.rigid_body_shape(model.dof_coords.mean(axis=0))
    Mr = RB.T @ (M @ RB)
    w, V = np.linalg.eigh(0.5 * (Mr + Mr.T))
    if w.min() <= 1e-12 * w.max():
        raise InputError(f"model {model.name!r}: rigid-body mass matrix is singular (massless model?)")
    Phi = RB @ (V / np.sqrt(w))
    lam = np.einsum("ij,ij->j", Phi, K @ Phi)
    A = np.abs(Phi)
    floor = float(np.finfo(float).eps * np.max(np.einsum("ij,ij->j", A, abs(K) @ A)))
    return lam, Phi, floor


def _solve(model: FEModel, nev: int, sigma: float, tol: float) -> tuple[np.ndarray, np.ndarray, float]:
    """Lowest ``nev`` modes, and the round-off of the rigid modes' eigenvalues (0 clamped).
    Free-free: the six rigid-body modes are the geometric ones and SLEPc works in their
    M-orthogonal complement (deflation), so none can be missed."""
    what = f"model {model.name!r}"
    if model.grounded:
        return (*pb.eigensolve(model.K, model.M, nev, sigma, tol=tol, what=what), 0.0)
    lam_r, Phi_r, floor = _rigid_modes(model)
    lam_f, Phi_f = pb.eigensolve(model.K, model.M, max(nev - 6, 1), sigma, tol=tol, what=what, deflation=Phi_r)
    # SLEPc keeps them M-orthogonal to ~1e-8 (K RB = 0 only to round-off): one exact
    # Gram-Schmidt step against the rigid modes, then renormalise
    _, M = model.matrices()
    Phi_f = Phi_f - Phi_r @ (Phi_r.T @ (M @ Phi_f))
    Phi_f /= np.sqrt(np.einsum("ij,ij->j", Phi_f, M @ Phi_f))
    lam, Phi = np.concatenate([lam_r, lam_f]), np.hstack([Phi_r, Phi_f])
    order = np.argsort(lam, kind="stable")[:nev]
    return lam[order], Phi[:, order], floor


def eigenmodes(model: FEModel, n_modes: int | None = None, band_hz: tuple[float, float] | None = None,
               shift_hz: float = 1.0, rigid_tol_hz: float = 0.01, tol: float = 1e-10) -> Modes:
    """Lowest ``n_modes`` modes (rigid-body modes included for a free-free model), or all
    modes with frequency in ``band_hz`` = (f_lo, f_hi) Hz. Exactly one of the two."""
    if (n_modes is None) == (band_hz is None):
        raise InputError("eigenmodes: give either n_modes or band_hz")
    if shift_hz <= 0:
        raise InputError(f"eigenmodes: shift_hz = {shift_hz!r} must be > 0 (the shift is -(2 pi shift_hz)^2)")
    sigma = -(2 * np.pi * shift_hz) ** 2
    n_check = 1 if model.grounded else 7     # enough modes to see an extra near-zero mode
    n_max = model.n_dof - 1
    if n_modes is not None:
        if n_modes < 1:
            raise InputError(f"eigenmodes: n_modes = {n_modes!r} must be >= 1")
        nev = min(max(n_modes, n_check), n_max)
        lam, Phi, floor = _solve(model, nev, sigma, tol)
        n_rigid = _check_singular(model, lam, rigid_tol_hz, floor)
        return Modes(lam[:n_modes], Phi[:, :n_modes], min(n_rigid, n_modes))
    f_lo, f_hi = map(float, band_hz)
    if not (0 <= f_lo < f_hi):
        raise InputError(f"eigenmodes: band {band_hz!r} Hz must satisfy 0 <= f_lo < f_hi")
    nev = min(max(12, n_check), n_max)
    while True:
        lam, Phi, floor = _solve(model, nev, sigma, tol)
        if np.sqrt(max(lam[-1], 0)) / (2 * np.pi) > f_hi or nev >= n_max:
            break
        nev = min(2 * nev, n_max)
    n_rigid = _check_singular(model, lam, rigid_tol_hz, floor)
    f = Modes(lam, Phi, n_rigid).freq_hz
    keep = (f >= f_lo) & (f <= f_hi)
    return Modes(lam[keep], Phi[:, keep], int(np.sum(keep[:n_rigid])))


def beam_content(model: FEModel, shape: np.ndarray, n_slices: int = 60) -> float:
    """Share (0..1) of the lateral (x, y) nodal displacement of ``shape`` that is a uniform
    translation of each of ``n_slices`` slices along z: ~1 for a beam-bending mode of a
    vertical body, ~0 for lobar (n >= 2) shell modes. Picks the beam modes of a shell model
    whose spectrum is dense with shell modes."""
    u = model.nodal_displacement(shape)
    z = model.nodes[:, 2]
    k = np.minimum(((z - z.min()) / max(np.ptp(z), 1e-300) * n_slices).astype(int), n_slices - 1)
    count = np.bincount(k, minlength=n_slices)
    beam = 0.0
    for c in range(2):
        s = np.bincount(k, weights=u[:, c], minlength=n_slices)
        beam += np.sum(s[count > 0] ** 2 / count[count > 0])
    return float(beam / max(np.sum(u[:, :2] ** 2), 1e-300))
