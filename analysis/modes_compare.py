"""Which modes moved between two load cycles: the modal assurance criterion (MAC) between the
mode shapes of two models at the DOFs they share, and a one-to-one pairing of their modes by
it (issue 24, cycle-to-cycle comparison).

MAC_ij = (phi_i . psi_j)^2 / ((phi_i . phi_i) (psi_j . psi_j))  (Allemang; pyyeti's ``ytools.mac``
without a mass matrix): 1 for the same shape, 0 for orthogonal ones. The pairing maximises
the sum of the MAC of the pairs (scipy's ``linear_sum_assignment``, the Hungarian method),
so two new modes never claim one old mode; a pair whose MAC is below ``MAC_PAIRED`` is
reported as unmatched (a mode that changed its shape, or a new one). Rigid-body modes (below
``rigid_hz``) are left out: any basis of them is as good as another.

numpy/scipy only; shapes as (n_dof, n_modes) arrays at labelled DOFs, frequencies in Hz.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from liftoff.core.errors import InputError

MAC_PAIRED = 0.9          # a pair below this MAC is reported unmatched


def mac(phi: np.ndarray, psi: np.ndarray) -> np.ndarray:
    """(n_phi, n_psi) MAC between the columns of ``phi`` and of ``psi`` (same DOFs, rows)."""
    phi, psi = np.asarray(phi, float), np.asarray(psi, float)
    if phi.ndim != 2 or psi.ndim != 2 or phi.shape[0] != psi.shape[0]:
        raise InputError(f"MAC: shapes {phi.shape} and {psi.shape} are not on the same DOFs")
    num = (phi.T @ psi) ** 2
    a = np.einsum("ij,ij->j", phi, phi)
    b = np.einsum("ij,ij->j", psi, psi)
    den = np.outer(a, b)
    return np.divide(num, den, out=np.zeros_like(num), where=den > 0)


@dataclass
class ModePair:
    """Mode ``new`` (0-based) of the new model paired with mode ``old`` of the old one (None:
    unmatched), their frequencies (Hz), the MAC and the frequency change (%)."""

    new: int
    f_new: float
    old: int | None
    f_old: float
    mac: float
    change_pct: float


def pair_modes(f_new: np.ndarray, phi_new: np.ndarray, f_old: np.ndarray, phi_old: np.ndarray,
               rigid_hz: float = 0.05, f_max: float | None = None) -> list[ModePair]:
    """Pair each elastic mode of the new model (below ``f_max``, Hz) with one of the old (any
    frequency) by the largest total MAC; shapes on the same DOFs (rows)."""
    from scipy.optimize import linear_sum_assignment

    f_new, f_old = np.asarray(f_new, float), np.asarray(f_old, float)
    if phi_new.shape[1] != f_new.size or phi_old.shape[1] != f_old.size:
        raise InputError(f"pair_modes: {phi_new.shape[1]} and {phi_old.shape[1]} shapes for {f_new.size} and "
                         f"{f_old.size} frequencies")
    sel_new = np.flatnonzero((f_new > rigid_hz) & (f_new <= (np.inf if f_max is None else f_max)))
    sel_old = np.flatnonzero(f_old > rigid_hz)
    M = mac(phi_new[:, sel_new], phi_old[:, sel_old])
    rows, cols = linear_sum_assignment(-M) if M.size else (np.zeros(0, int), np.zeros(0, int))
    match = dict(zip(rows.tolist(), cols.tolist()))
    out = []
    for r, i in enumerate(sel_new):
        c = match.get(r)
        m = float(M[r, c]) if c is not None else 0.0
        if c is None or m < MAC_PAIRED:
            out.append(ModePair(int(i), float(f_new[i]), None, float("nan"), m, float("nan")))
        else:
            j = int(sel_old[c])
            out.append(ModePair(int(i), float(f_new[i]), j, float(f_old[j]), m,
                                100.0 * (f_new[i] - f_old[j]) / f_old[j]))
    return out
