"""Modal effective mass tables: what each mode of a body carries of its rigid-body mass
(issue 24's modal deliverables; Nastran MEFFMASS).

* **Grounded body** (the pad, no rigid-body modes): mode k under the rigid translation of
  its ground, L_k = phi_k^T M r (eq. 14's participation, unit modal mass), effective mass
  L_k^2; summed over every mode of the whole space it is r^T M r less the mass that sits on
  the ground DOFs themselves.
* **Free-free body** (the vehicle): its elastic modes are M-orthogonal to the rigid-body
  ones, so their effective mass about any point is zero; what a loads engineer tabulates is
  the body **held at its contact DOFs** (the vehicle on its posts), excited by their rigid
  translation. The held model is built in the body's modal coordinates (unit modal mass,
  stiffness diag(omega^2)): with ``rows`` the contact DOFs' mode-shape rows, N an
  orthonormal basis of the motions that leave them fixed and q_s the least-strain-energy
  shape that moves them by u (a rigid translation, so q_s is the rigid translation itself),
  q = q_s u_b + N eta gives  eta'' + (N^T Lambda N) eta = -N^T q_s u_b''.  With
  N^T Lambda N = V diag(omega_h^2) V^T, mode k of the held body has participation
  L_k = v_k^T N^T q_s and effective mass L_k^2; the sum over the held modes is |N^T q_s|^2
  (:func:`held_effective_mass`, the truncation check's figure) and the rest, |q_s|^2 minus
  it, sits on the held DOFs.

numpy/scipy only; SI units (Hz, kg).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from liftoff.core.labels import TRANSLATIONS
from liftoff.core.rigid import rb_rows

from .assembly import label_transform
from .system import SystemModes, rigid_inertia


def _held(omega: np.ndarray, rows: np.ndarray, u: np.ndarray):
    """(N, q_s, A): the basis of motions leaving the held DOFs fixed, the least-strain-energy
    shape with rows q_s = u (module docstring) and the held stiffness A = N^T Lambda N."""
    n = omega.size
    U, s, Vt = np.linalg.svd(rows, full_matrices=True)
    r = int(np.sum(s > 1e-12 * max(float(s.max(initial=0.0)), 1e-300)))
    N, Vr = Vt[r:].T, Vt[:r].T
    q_p = Vr @ ((U[:, :r].T @ u) / s[:r, None])               # rows q_p = u (least squares)
    lam = omega ** 2
    A = N.T @ (lam[:, None] * N)
    A = 0.5 * (A + A.T)
    z = _solve_held(A, -N.T @ (lam[:, None] * q_p)) if N.shape[1] else np.zeros((0, u.shape[1]))
    q_s = q_p + N @ z if n else np.zeros((0, u.shape[1]))
    return N, q_s, A


def _solve_held(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    """A^-1 b for the held stiffness A (symmetric): by Cholesky when A is positive definite
    (the held DOFs restrain every rigid-body motion: the vehicle on its posts; 30x faster than
    the SVD at 1,400 modes), else the least-squares (minimum-norm) solution, which leaves a
    motion the held DOFs do not restrain unstrained. A pivot below ``HELD_PIVOT`` of A's
    largest diagonal entry is such a motion left at round-off (coupled or not to the rest),
    and takes the least-squares path too."""
    try:
        c = sla.cho_factor(A, lower=True, check_finite=False)
        if np.diag(c[0]).min(initial=np.inf) ** 2 > HELD_PIVOT * np.abs(np.diag(A)).max(initial=0.0):
            return sla.cho_solve(c, b, check_finite=False)
    except sla.LinAlgError:
        pass
    return sla.lstsq(A, b)[0]


#: a Cholesky pivot of the held stiffness (omega^2, rad^2/s^2) below this fraction of its
#: largest diagonal entry is a motion the held DOFs do not restrain: its eigenvalue is then at
#: round-off of the stiffest (lstsq's own cut-off is eps ~ 2e-16 of it), while a held mode
#: this soft would be 1e-6 of the highest frequency (3 mHz against the default's 2.8 kHz)
HELD_PIVOT = 1e-12


def held_effective_mass(omega: np.ndarray, rows: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Effective mass (kg, one per column of ``u``) of a modal model (unit modal masses,
    stiffness diag(omega^2)) held at the DOFs whose mode-shape rows are ``rows`` and excited
    by their motion ``u``: |N^T q_s|^2 summed over the held model's modes (module docstring).
    This is the mass that follows the held DOFs' motion dynamically; the rest sits on them."""
    N, q_s, _ = _held(omega, rows, u)
    y = N.T @ q_s
    return np.einsum("ij,ij->j", y, y)


def held_modes(omega: np.ndarray, rows: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(omega_h rad/s, effective mass per held mode and column of ``u`` (kg), |q_s|^2 per
    column (kg)) of the modal model held at ``rows`` (module docstring)."""
    N, q_s, A = _held(omega, rows, u)
    if not N.shape[1]:
        return np.zeros(0), np.zeros((0, u.shape[1])), np.einsum("ij,ij->j", q_s, q_s)
    w2, V = np.linalg.eigh(A)
    L = V.T @ (N.T @ q_s)
    return np.sqrt(np.maximum(w2, 0.0)), L ** 2, np.einsum("ij,ij->j", q_s, q_s)


@dataclass
class ModalMassTable:
    """The modes of one body and the effective mass each carries (x, y, z translations, kg).
    ``condition``: 'grounded' or 'held at its contact DOFs'; ``total_mass``: the rigid-body
    mass in x, y, z (kg); ``on_supports``: the part of it that sits on the ground or held
    DOFs and no mode carries (kg)."""

    body: str
    condition: str
    freq_hz: np.ndarray
    effective_mass: np.ndarray       # (n_modes, 3) kg
    total_mass: np.ndarray           # (3,) kg
    on_supports: np.ndarray          # (3,) kg

    def rows(self) -> list[dict]:
        """One dict per mode: mode (1-based), f_hz, m_eff_x/y/z (kg), percent and cumulative
        percent of the total mass per direction."""
        tot = np.where(self.total_mass > 0, self.total_mass, np.nan)
        pct = 100 * self.effective_mass / tot
        cum = np.cumsum(pct, axis=0)
        out = []
        for k, f in enumerate(self.freq_hz):
            r = {"mode": k + 1, "f_hz": float(f)}
            for j, ax in enumerate("xyz"):
                r[f"m_eff_{ax}"] = float(self.effective_mass[k, j])
                r[f"pct_{ax}"] = float(pct[k, j])
                r[f"cum_pct_{ax}"] = float(cum[k, j])
            out.append(r)
        return out


def modal_mass_table(modes: SystemModes, contact_labels, body: str) -> ModalMassTable:
    """The modal effective mass table of a body's modes: grounded (no rigid-body modes) under
    its ground's rigid translation; free-free held at ``contact_labels`` (module docstring)."""
    asm = modes.assembly
    nt = len(TRANSLATIONS)
    if not modes.n_rigid:                   # (the ground's rigid field: reduction.system.rigid_inertia)
        inertia, rigid_mass = rigid_inertia(asm)
        L = modes.phi.T @ inertia[:, :nt]
        total = np.diag(rigid_mass)[:nt].copy()
        m_eff = L ** 2
        return ModalMassTable(body, "grounded", modes.freq_hz.copy(), m_eff, total, total - m_eff.sum(axis=0))
    contact = list(dict.fromkeys(contact_labels))
    u = rb_rows(contact, asm.points, asm.point_coords, np.zeros(3))[:, :nt]
    w, m_eff, total = held_modes(modes.omega, label_transform(asm, contact) @ modes.phi, u)
    return ModalMassTable(body, "held at its contact DOFs", w / (2 * np.pi), m_eff, total,
                          total - m_eff.sum(axis=0))
