"""System modes of an assembled CB model and the modal body they make (eq. 4, 13, 14).

Free-free (n_rigid=6): the six rigid-body modes are built explicitly from the geometric
rigid-body shape RB of the boundary DOFs (modal DOFs have zero RB rows, section 4.2),
mass-orthonormalised; the elastic modes are the eigenvectors of the deflated pencil
(K + a (M R)(M R)^T, M), a = -1 s^-2, which moves the rigid modes to -1 rad^2/s^2 and leaves
every elastic eigenpair exact and M-orthogonal to them. Grounded (n_rigid=0): plain
dense eigh; a zero-frequency mode is an error. All modes are kept unless f_max is given
(a plain cut: reduction/truncation.py's keep_modes cuts with residual vectors and checks).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
from liftoff.transient.body import ModalBody

from liftoff.core.errors import InputError
from liftoff.core.rigid import rb_rows, shift_rb

from .assembly import Assembly, label_transform

RB_TOL = 1e-6         # relative K RB residual above which an assembly is not free-free
MASSLESS_TOL = 1e-12  # mass eigenvalues below this x the largest span the massless subspace
                      # (round-off of a singular M is ~eps x max = 2e-16; a real inertia is far above)


@dataclass
class SystemModes:
    """Mass-normalised modes of an assembly: phi (n_sys_dof x n_modes), omega (rad/s). The
    last ``n_residual`` are residual vectors (reduction/truncation.py); ``n_space``: the
    eigenmodes of the whole space when some were cut (None: all are here)."""

    assembly: Assembly
    omega: np.ndarray
    phi: np.ndarray
    n_rigid: int
    n_residual: int = 0
    n_space: int | None = None

    @property
    def freq_hz(self) -> np.ndarray:
        return self.omega / (2 * np.pi)

    @property
    def n_modes(self) -> int:
        return self.omega.size

    def rb_shape(self, ref_point=(0.0, 0.0, 0.0)) -> np.ndarray:
        return system_rb(self.assembly, ref_point)

    def to_body(self, labels=None, ref_point=(0.0, 0.0, 0.0), zeta=0.0, name: str | None = None) -> ModalBody:
        """The transient core's modal body: phi rows at ``labels`` (default: every boundary
        DOF), participation Phi^T M RB about ref_point (eq. 14), rigid_body_mass RB^T M RB
        (:func:`rigid_inertia`: a grounded component's own rigid-body field),
        all labelled points. A scalar ``zeta`` applies to the elastic modes (rigid modes get
        0); an array gives one ratio per mode."""
        a = self.assembly
        labels = a.boundary_labels if labels is None else tuple(labels)
        rows = label_transform(a, labels) @ self.phi
        if a.inertia is None:               # (the expressions of before: the free-free vehicle's bits unchanged)
            rb = system_rb(a, ref_point)
            participation, rigid_mass = self.phi.T @ a.M @ rb, rb.T @ a.M @ rb
        else:
            inertia, rigid_mass = rigid_inertia(a, ref_point)
            participation = self.phi.T @ inertia
        zeta = np.asarray(zeta, dtype=float)
        if zeta.ndim == 0:
            z = np.full(self.n_modes, float(zeta))
            z[: self.n_rigid] = 0.0
        elif zeta.shape == (self.n_modes,):
            z = zeta.copy()
        else:
            raise InputError(f"zeta has shape {zeta.shape}: give a scalar or one ratio per mode ({self.n_modes})")
        return ModalBody(name=name or a.name, omega=self.omega, zeta=z, dof_labels=labels, phi=rows,
                         participation=participation, ref_point=np.asarray(ref_point, float),
                         points=a.points, point_coords=a.point_coords, rigid_body_mass=rigid_mass)


def rigid_inertia(assembly: Assembly, ref_point=(0.0, 0.0, 0.0)) -> tuple[np.ndarray, np.ndarray]:
    """(M RB (n_dof, 6), RB^T M RB (6, 6)) about ``ref_point``: the rigid-body inertia loads of
    the system DOFs (gravity, eq. 14) and the rigid-body mass. For free components the
    geometric RB of the boundary (:func:`system_rb`) is the image of the components' rigid
    motion (their constraint modes carry the interior along rigidly); a grounded component,
    clamped inside its interior, has no such image: its loads are the physical field's,
    T^T M r, held by the assembly (``Assembly.inertia`` about the origin, moved here:
    r_ref = r_0 X with t_0 = t + ref x theta)."""
    if assembly.inertia is None:
        rb = system_rb(assembly, ref_point)
        return assembly.M @ rb, rb.T @ assembly.M @ rb
    X = shift_rb(ref_point)                 # t_0 = t + ref x theta
    return assembly.inertia @ X, X.T @ assembly.rigid_mass @ X


def system_rb(assembly: Assembly, ref_point=(0.0, 0.0, 0.0)) -> np.ndarray:
    """Geometric rigid-body shape of the system DOFs (zero on modal DOFs, eq. 14)."""
    rb = np.zeros((assembly.n_dof, 6))
    rb[assembly.n_modal:] = rb_rows(assembly.boundary_labels, assembly.points, assembly.point_coords, ref_point)
    return rb


def eigh_massless(K: np.ndarray, M: np.ndarray, who: str = "model") -> tuple[np.ndarray, np.ndarray]:
    """Finite eigenpairs of K x = lam M x for symmetric K and positive *semi*-definite M
    (massless DOFs, common in Nastran models: boundary rotations without inertia).

    With M = U diag(w) U^T split into a massive part A (w > MASSLESS_TOL max w) and a
    massless part Z, the massless coordinates follow the massive ones statically,
    y_z = -(Z^T K Z)^-1 Z^T K A y_a (exact: they carry no inertia force), so
    x = T y_a with T = A + Z G and (T^T K T) y = lam diag(w_A) y. The modes satisfy
    K x = lam M x and x^T M x = I; there are rank(M) of them. When M is positive
    definite this is plain ``eigh``."""
    try:
        return sla.eigh(K, M)
    except np.linalg.LinAlgError:
        pass
    w, U = sla.eigh(0.5 * (M + M.T))
    if w[-1] <= 0 or w[0] < -MASSLESS_TOL * w[-1]:
        raise InputError(f"{who}: mass matrix is not positive semi-definite "
                         f"(eigenvalues {w[0]:.3e} .. {w[-1]:.3e})")
    zero = w <= MASSLESS_TOL * w[-1]
    A, Z = U[:, ~zero], U[:, zero]
    Kz = Z.T @ K @ Z
    try:
        G = -sla.solve(0.5 * (Kz + Kz.T), Z.T @ K @ A, assume_a="sym")
    except (np.linalg.LinAlgError, sla.LinAlgWarning):
        raise InputError(f"{who}: {int(zero.sum())} massless DOF combinations without stiffness "
                         "(a massless mechanism)") from None
    T = A + Z @ G
    Kr = T.T @ K @ T
    lam, y = sla.eigh(0.5 * (Kr + Kr.T), np.diag(w[~zero]))
    return lam, T @ y


def system_modes(assembly: Assembly, n_rigid: int = 6, f_max: float | None = None) -> SystemModes:
    """Eigensolution of the assembled model (dense; CB sizes are a few hundred)."""
    who = f"assembly {assembly.name!r}"
    K = 0.5 * (assembly.K + assembly.K.T)
    M = 0.5 * (assembly.M + assembly.M.T)
    scale = np.trace(K) / max(np.trace(M), 1e-300)
    if n_rigid == 6:
        center = assembly.point_coords.mean(axis=0) if assembly.point_coords.size else np.zeros(3)
        rb = system_rb(assembly, center)
        m6 = rb.T @ M @ rb
        try:
            L = np.linalg.cholesky(0.5 * (m6 + m6.T))
        except np.linalg.LinAlgError:
            raise InputError(f"{who}: the boundary DOFs cannot describe all six rigid-body motions "
                             "(rigid-body mass RB^T M RB is singular)") from None
        R = sla.solve_triangular(L, rb.T, lower=True).T       # R^T M R = I
        res = np.linalg.norm(K @ R, axis=0) / (np.linalg.norm(K, 2) * np.linalg.norm(R, axis=0))
        if res.max() > RB_TOL:
            raise InputError(f"{who} is not free-free: K RB / (|K| |RB|) = {res.max():.1e} for rigid "
                             f"motion {int(np.argmax(res))} (constrained or non-geometric stiffness, or the round-off of "
                             "a very finely meshed, badly conditioned component)")
        MR = M @ R
        lam, vec = eigh_massless(K - MR @ MR.T, M, who)
        elastic = lam[6:]
        if elastic.size and elastic[0] < 1e-10 * abs(scale):
            raise InputError(f"{who}: more than six zero-frequency modes (a mechanism or an "
                             f"unconnected part); lowest elastic eigenvalue {elastic[0]:.2e}")
        omega = np.concatenate([np.zeros(6), np.sqrt(elastic)])
        phi = np.hstack([R, vec[:, 6:]])
    elif n_rigid == 0 and K.shape[0] == 0:          # immovable ground (rigid_ground): no DOFs, no modes
        omega, phi = np.zeros(0), np.zeros((0, 0))
    elif n_rigid == 0:
        lam, phi = eigh_massless(K, M, who)
        if lam[0] < 1e-10 * abs(scale):
            raise InputError(f"{who}: zero-frequency mode in a grounded model (eigenvalue {lam[0]:.2e}); "
                             "is it really grounded?")
        omega = np.sqrt(lam)
    else:
        raise InputError(f"{who}: n_rigid must be 6 (free-free) or 0 (grounded), got {n_rigid}")
    n_space = None
    if f_max is not None:
        keep = omega <= 2 * np.pi * f_max
        keep[:n_rigid] = True
        if not keep.all():
            n_space = omega.size
            omega, phi = omega[keep], phi[:, keep]
    return SystemModes(assembly=assembly, omega=omega, phi=phi, n_rigid=n_rigid, n_space=n_space)
