"""The modes an assembly keeps: the cut, residual vectors and the truncation check (section 3.0).

The reference keeps every mode of the assembled vehicle (section 3.0: "all modes from this
final eigensolution are retained"); that is the default here. A user may still cut the
system modes (``f_max`` / ``n_modes``); then

* **residual vectors** (Nastran RESVEC, modal truncation augmentation) restore the static
  flexibility the cut loses at the loaded DOFs: for unit loads F at every boundary DOF of
  the assembly (contact, attach, engine-mount and output points: all of them are boundary
  DOFs, pipeline.boundary_points) and the rigid-body inertia loads M RB (eq. 14), the
  static shapes  psi = (G - Phi_k Lambda_k^-1 Phi_k^T) F  (G the exact elastic static
  flexibility, Phi_k the kept elastic modes) are M- and K-orthogonal to every kept mode;
  within their span an eigensolution makes them M-orthonormal and K-diagonal, and they are
  appended as modes with those (Rayleigh) frequencies. With them, Phi G_k Phi^T F = G F for
  every such F to round-off, so the static start (section 2.6) and the static part of every
  load equal those of the un-truncated CB models.
* the **truncation check** (:func:`truncation_check`) compares, for one body, the static
  flexibility at its contact and attach DOFs from the kept modes against the exact one
  (largest relative shortfall of a diagonal entry: G - G_k is positive semi-definite, so
  its diagonal vanishes only with the whole difference), and the effective mass of the
  body held at its contact DOFs in the kept modes against the whole space's.

G is exact, from a solve with K, not from the modes: grounded G = K^-1; free-free the
inertia-relief flexibility about the mean axes, G = (K + c M R R^T M)^-1 - R R^T / c for
the M-orthonormal rigid-body modes R and any c > 0 (c = the first elastic eigenvalue keeps
the solve as well conditioned as K's elastic part): it maps a load to the elastic
deflection of the free body under that load and the inertia forces that balance it, and
equals the sum over every elastic mode of phi phi^T / omega^2.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from liftoff.core.errors import InputError
from liftoff.core.labels import TRANSLATIONS
from liftoff.core.rigid import rb_rows

from .assembly import label_transform
from .modal_mass import held_effective_mass
from .system import MASSLESS_TOL, SystemModes, rigid_inertia

#: a residual direction whose share of a loaded DOF's static flexibility is below this is
#: round-off (what the kept modes already carry, computed twice): not a vector. The check's
#: own resolution is far finer than its 1 % warning.
RESVEC_TOL = 1e-11
TRUNCATION_WARN = 0.01   # a body misses more than 1 % of a checked flexibility or effective mass: warn


# ------------------------------------------------------------------ exact statics
class StaticFlexibility:
    """The exact elastic static flexibility G of an assembly (module docstring), factored once."""

    def __init__(self, full: SystemModes):
        asm = full.assembly
        self.K = 0.5 * (asm.K + asm.K.T)
        self.M = 0.5 * (asm.M + asm.M.T)
        self.R = full.phi[:, : full.n_rigid]
        Kd = self.K
        self.c = 1.0
        if full.n_rigid:
            elastic = full.omega[full.n_rigid:]
            self.c = float(elastic[0] ** 2) if elastic.size else 1.0
            MR = self.M @ self.R
            Kd = self.K + self.c * (MR @ MR.T)
        try:
            self._cho = sla.cho_factor(Kd, check_finite=False)
        except (np.linalg.LinAlgError, ValueError):
            raise InputError(f"assembly {asm.name!r}: the stiffness (with the rigid-body modes deflated) is not "
                             "positive definite: no static flexibility to check or restore") from None

    def solve(self, F: np.ndarray) -> np.ndarray:
        """x = G F (columns of F: loads on the assembly's DOFs)."""
        return self.solve_with_scale(F)[0]

    def solve_with_scale(self, F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(G F, the norm of each column before the rigid part is taken out): a column whose
        G F is round-off of that norm is a load the free body takes as rigid-body inertia alone."""
        X = sla.cho_solve(self._cho, F, check_finite=False)
        scale = np.linalg.norm(X, axis=0)
        if self.R.shape[1]:
            X = X - self.R @ (self.R.T @ F) / self.c
        return X, scale


def load_vectors(full: SystemModes) -> np.ndarray:
    """The loads whose static response residual vectors restore: a unit load at every boundary
    DOF of the assembly, and the rigid-body inertia loads M RB (eq. 14: gravity)."""
    asm = full.assembly
    unit = np.zeros((asm.n_dof, len(asm.boundary_labels)))
    unit[asm.n_modal + np.arange(len(asm.boundary_labels)), np.arange(len(asm.boundary_labels))] = 1.0
    return np.hstack([unit, rigid_inertia(asm)[0]])


# ------------------------------------------------------------------ the cut
def residual_vectors(full: SystemModes, omega: np.ndarray, phi: np.ndarray, loads: np.ndarray,
                     flex: StaticFlexibility | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(omega_r, phi_r) of the residual vectors of the kept modes (omega, phi) of ``full``'s
    assembly for the load columns ``loads`` (module docstring): M-orthonormal, K-diagonal,
    M- and K-orthogonal to the kept modes, ascending. Directions that add less than
    RESVEC_TOL of a load's static flexibility, or carry no mass, are left out."""
    flex = flex or StaticFlexibility(full)
    M, K = flex.M, flex.K
    X, scale = flex.solve_with_scale(loads)                  # exact static response G F
    total = np.einsum("ij,ij->j", loads, X)                  # F^T G F per load (>= 0)
    use = (np.linalg.norm(X, axis=0) > 1e-10 * scale) & (total > 0)   # else rigid-body inertia alone
    if not use.any():
        return np.zeros(0), np.zeros((phi.shape[0], 0))
    F, X = loads[:, use], X[:, use]
    el = omega > 0
    X = X - phi[:, el] @ ((phi[:, el].T @ F) / omega[el, None] ** 2)   # less what the kept modes carry
    X = X - phi @ (phi.T @ (M @ X))                          # M-orthogonal to every kept mode (round-off)
    X = X / np.sqrt(total[use])                              # column j: share of load j's flexibility
    S = X.T @ K @ X                                          # its diagonal: the shares missing
    s, U = np.linalg.eigh(0.5 * (S + S.T))
    keep = s > RESVEC_TOL
    if not keep.any():
        return np.zeros(0), np.zeros((phi.shape[0], 0))
    V = X @ (U[:, keep] / np.sqrt(s[keep]))                  # V^T K V = I
    B = V.T @ M @ V
    mu, W = np.linalg.eigh(0.5 * (B + B.T))                  # 1 / omega^2 of the residual modes
    massive = mu > MASSLESS_TOL * max(float(mu.max(initial=0.0)), 1e-300)
    mu, W = mu[massive], W[:, massive]
    phi_r = V @ (W / np.sqrt(mu))
    order = np.argsort(-mu)                                  # ascending frequency
    return 1.0 / np.sqrt(mu[order]), phi_r[:, order]


def keep_modes(full: SystemModes, f_max: float | None = None, n_modes: int | None = None,
               residual: bool = True) -> SystemModes:
    """The modes a body keeps of the complete eigensolution ``full``: those up to ``f_max`` Hz
    and the first ``n_modes`` (None: no limit; the rigid-body modes always), and, when that
    cuts any and ``residual`` is set, the residual vectors of :func:`load_vectors`."""
    keep = np.ones(full.n_modes, dtype=bool)
    if f_max is not None:
        keep &= full.omega <= 2 * np.pi * f_max
    if n_modes is not None:
        keep[int(n_modes):] = False
    keep[: full.n_rigid] = True
    if keep.all():
        return full
    omega, phi = full.omega[keep], full.phi[:, keep]
    n_res = 0
    if residual:
        w_r, phi_r = residual_vectors(full, omega, phi, load_vectors(full))
        omega, phi, n_res = np.concatenate([omega, w_r]), np.hstack([phi, phi_r]), w_r.size
    return SystemModes(full.assembly, omega, phi, full.n_rigid, n_residual=n_res, n_space=full.n_modes)


# ------------------------------------------------------------------ the check
def effective_mass(modes: SystemModes, contact_labels) -> np.ndarray:
    """Effective mass (kg; x, y, z) that the modes carry: of a free-free body held at its
    contact DOFs (:func:`held_effective_mass`; nan without contacts), of a grounded one
    under its rigid-body (gravity) load, sum (Phi^T M RB)^2 (eq. 14)."""
    asm = modes.assembly
    if not modes.n_rigid:
        L = modes.phi.T @ rigid_inertia(asm)[0][:, : len(TRANSLATIONS)]
        return np.einsum("ij,ij->j", L, L)
    contact = list(dict.fromkeys(contact_labels))
    if not contact:
        return np.full(len(TRANSLATIONS), np.nan)
    u = rb_rows(contact, asm.points, asm.point_coords, np.zeros(3))[:, : len(TRANSLATIONS)]
    return held_effective_mass(modes.omega, label_transform(asm, contact) @ modes.phi, u)


@dataclass(frozen=True)
class TruncationCheck:
    """How much a body's kept modes miss (module docstring). SI units; fractions 0..1."""

    body: str
    n_kept: int                  # eigenmodes kept (rigid included)
    n_residual: int              # residual vectors appended
    n_space: int                 # eigenmodes of the whole CB space
    f_cut: float | None          # Hz: the highest kept eigenmode when some are cut, else None
    n_checked: int               # DOFs checked
    flex_error: float            # largest relative shortfall of a checked DOF's static flexibility
    flex_label: str              # ... at this DOF
    mass_kept: tuple             # effective mass (:func:`effective_mass`), kept / whole (x, y, z); nan: none
    static_error: float = 0.0    # flex_error counting the residual vectors too (they make it ~0 at the boundary)

    @property
    def worst_mass(self) -> float:
        m = [v for v in self.mass_kept if v == v]
        return min(m) if m else 1.0

    @property
    def ok(self) -> bool:
        return self.flex_error <= TRUNCATION_WARN and self.worst_mass >= 1.0 - TRUNCATION_WARN

    def line(self) -> str:
        if self.n_space == 0:
            return f"{self.body}: rigid ground, no modes (nothing to truncate)"
        kept = (f"all {self.n_space} modes" if self.f_cut is None else
                f"{self.n_kept} of {self.n_space} modes (to {self.f_cut:.1f} Hz)"
                + (f" + {self.n_residual} residual vectors (not counted below: they make the static "
                   "flexibility exact, not the dynamics)" if self.n_residual else ", no residual vectors"))
        mass = "/".join("-" if v != v else f"{100 * v:.1f}" for v in self.mass_kept)
        with_rv = f" ({self.static_error:.2g} with the residual vectors)" if self.n_residual else ""
        return (f"{self.body}: {kept}; static flexibility at {self.n_checked} contact/attach DOFs short by at most "
                f"{self.flex_error:.2g} ({self.flex_label}){with_rv}; effective mass kept {mass} % (x/y/z)")

    def warning(self) -> str | None:
        """One line when the kept modes miss more than 1 % of a checked flexibility or of the
        effective mass, with what to change; None otherwise."""
        if self.ok:
            return None
        missed = []
        if self.flex_error > TRUNCATION_WARN:
            missed.append(f"{100 * self.flex_error:.3g} % of the static flexibility at {self.flex_label}")
        if self.worst_mass < 1.0 - TRUNCATION_WARN:
            axis = "xyz"[[v if v == v else 1.0 for v in self.mass_kept].index(self.worst_mass)]
            missed.append(f"{100 * (1 - self.worst_mass):.3g} % of the effective mass in {axis}")
        fix = "keep every system mode (no [model.system] f_max / n_modes) or raise the cut"
        if self.flex_error > TRUNCATION_WARN and not self.n_residual:
            fix += " (residual vectors, [model.system] residual_vectors = true, correct the static part only)"
        return (f"warning: {self.body}: the kept modes miss {' and '.join(missed)} (over 1 %): the loads are not "
                f"converged in the modes kept; {fix}")

    def as_dict(self) -> dict:
        return {"body": self.body, "n_kept": self.n_kept, "n_residual": self.n_residual, "n_space": self.n_space,
                "f_cut_hz": self.f_cut, "n_checked": self.n_checked, "flexibility_shortfall": self.flex_error,
                "flexibility_dof": self.flex_label,
                **({"flexibility_shortfall_with_residual_vectors": self.static_error} if self.n_residual else {}),
                "effective_mass_kept_xyz": [None if v != v else v for v in self.mass_kept],
                "warn_above": TRUNCATION_WARN, "ok": self.ok}


def truncation_check(full: SystemModes, kept: SystemModes, labels, contact_labels, body: str | None = None,
                     flex: StaticFlexibility | None = None) -> TruncationCheck:
    """The truncation check of ``kept`` (a body's modes) against the whole eigensolution
    ``full`` of the same assembly, at the DOFs ``labels`` (contact and attach DOFs) for the
    flexibility and ``contact_labels`` (held) for the effective mass."""
    asm = full.assembly
    labels = list(dict.fromkeys(labels))
    flex = flex or StaticFlexibility(full)
    L = label_transform(asm, labels)
    g = np.einsum("ij,ji->i", L, flex.solve(L.T)) if labels else np.zeros(0)
    # the eigenmodes only: residual vectors built from unit loads at the boundary DOFs make the
    # static flexibility there exact whatever the cut, and each carries its whole mass, so
    # counting them passed cuts whose loads were 6.6 % off (a review, 2026-12-07); they
    # correct the static part of the response, not the dynamic one the cut leaves out
    n_eig = kept.n_modes - kept.n_residual
    ok = g > 1e-14 * max(float(g.max(initial=0.0)), 1e-300)

    def shortfall(modes: SystemModes) -> np.ndarray:
        rows = L @ modes.phi
        el = modes.omega > 0
        gk = np.einsum("ij,ij->i", rows[:, el], rows[:, el] / modes.omega[el] ** 2)
        return np.where(ok, (g - gk) / np.where(ok, g, 1.0), 0.0)

    static = float(np.abs(shortfall(kept)).max(initial=0.0)) if labels else 0.0    # residual vectors included
    eig = (SystemModes(asm, kept.omega[:n_eig], kept.phi[:, :n_eig], kept.n_rigid, n_residual=0, n_space=kept.n_space)
           if kept.n_residual else kept)
    short = shortfall(eig) if labels else np.zeros(0)
    j = int(np.argmax(np.abs(short))) if short.size else 0
    whole = effective_mass(full, contact_labels)
    part = whole if eig is full else effective_mass(eig, contact_labels)       # every mode kept: the same
    held = whole > 1e-9 * max(float(whole.max(initial=0.0)), 1e-300)
    mass = tuple(float(p / w) if h else np.nan for p, w, h in zip(part, whole, held))
    cut = n_eig < full.n_modes
    return TruncationCheck(body=body or asm.name, n_kept=n_eig, n_residual=kept.n_residual,
                           n_space=full.n_modes, f_cut=float(eig.freq_hz.max()) if cut else None,
                           n_checked=len(labels), flex_error=float(abs(short[j])) if short.size else 0.0,
                           flex_label=labels[j] if labels else "-", mass_kept=mass, static_error=static)
