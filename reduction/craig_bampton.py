"""Craig-Bampton reduction of one component (section 3.0, eq. 13 of Prabhakar & Palermo).

The component's DOFs split into boundary b (kept physically, by label) and interior i.
Constraint modes Psi = -K_ii^-1 K_ib and fixed-interface modes Phi (K_ii Phi = M_ii Phi
omega^2, Phi^T M_ii Phi = I) come from ONE sparse factorisation of K_ii: it solves for the
constraint modes and is the shift-invert operator (shift 0) of the eigensolve. With
u = [[Phi, Psi], [0, I]] [q; x_b] the reduced matrices are eq. 13:

    M = [[I, C_M], [C_M^T, M_B]]      K = [[diag(omega^2), 0], [0, K_B]]

C_M = Phi^T (M_ii Psi + M_ib), M_B = T_c^T M T_c, K_B = K_bb + K_bi Psi (T_c the
constraint modes on all DOFs). Units SI: omega rad/s, M kg (kg m, kg m^2), K N/m ...

Residual vectors (``residual_vectors=True``, Nastran's RESVEC for a superelement; the
"modal truncation augmentation" of Dickens, Nakagawa & Wittbrodt, Comput. Struct. 62,
1997): the interior's static response to the inertia loads of unit boundary accelerations,
X = K_ii^-1 (M_ii Psi + M_ib), from the same factor, made M_ii-orthogonal to the kept
modes and diagonalised on the subspace that is left (Rayleigh-Ritz), are appended to
them as modes of their own. Since K_ii Phi = M_ii Phi Lambda, Phi^T K_ii X = Lambda
Phi^T M_ii X = 0 as well, so eq. 13 keeps its form: the residual modes are more
fixed-interface modes, above the cut. What the cut leaves out then answers boundary
motion (and any load in the span of M T_c: gravity, a rigid body's inertia) statically
and exactly instead of not at all.
"""
from __future__ import annotations

import re
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Callable, Protocol

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from liftoff.core.errors import InputError, ResourceError
from liftoff.core.labels import split_label
from liftoff.core.memory import MEMORY_FRACTION, available_memory
from liftoff.core.records import read_record, write_record

from .component import Component

FORMAT = "liftoff-cb-model"
VERSION = 2                # 2: optional source_units attribute and recovery items (version 1 still read)
BAND_MODE_LIMIT = 2000  # most modes a frequency band may select from a sparse eigensolve (the default
                        # core has 684 below 60 Hz; 2000 x 100 k DOFs of dense modes is 1.6 GB)
DENSE_LIMIT = 600          # interior size below which the fixed-interface eigensolve is dense
ORDERING = "COLAMD"        # SuperLU column ordering (benchmarks/bench_reduction.py: COLAMD had
                           # 1.5x less fill and a 6x faster factor than MMD_AT_PLUS_A on a
                           # 39k-DOF hex solid, and was within 1.6x of it on an 18.8k-DOF tet model)


@dataclass
class CBRecovery:
    """A named linear output of one CB component (a DTM/ATM/LTM row block, SI units):
    ``y = disp @ x + vel @ xdot + acc @ xddot`` with x = [q; x_b] the component's CB DOFs
    (CBModel order). ``labels`` and ``units`` name each row (``units`` an SI unit per row:
    "m", "rad", "N", "N m", "Pa", "m/s^2" ...)."""

    name: str
    labels: tuple[str, ...]
    units: tuple[str, ...]
    disp: np.ndarray | None = None
    vel: np.ndarray | None = None
    acc: np.ndarray | None = None

    def __post_init__(self) -> None:
        who = f"recovery item {self.name!r}"
        if not isinstance(self.name, str) or not re.fullmatch(r"[A-Za-z0-9_.+-]+", self.name):
            raise InputError(f"{who}: a name is letters, digits and _ . + - only")
        self.labels = tuple(str(s) for s in self.labels)
        self.units = tuple(str(s) for s in self.units)
        if len(self.units) != len(self.labels):
            raise InputError(f"{who}: {len(self.labels)} labels but {len(self.units)} units")
        if all(getattr(self, k) is None for k in RECOVERY_PARTS):
            raise InputError(f"{who}: needs at least one of disp, vel, acc")
        for key in RECOVERY_PARTS:
            m = getattr(self, key)
            if m is not None:
                m = np.asarray(m, dtype=float)
                if m.ndim != 2 or m.shape[0] != len(self.labels):
                    raise InputError(f"{who}: {key} has shape {m.shape}, expected ({len(self.labels)}, n)")
                setattr(self, key, m)

    @property
    def parts(self) -> dict:
        """The matrices present, by name (disp, vel, acc)."""
        return {k: getattr(self, k) for k in RECOVERY_PARTS if getattr(self, k) is not None}


RECOVERY_PARTS = ("disp", "vel", "acc")


@dataclass
class CBModel:
    """Craig-Bampton model of one component: eq. 13 matrices plus recovery data.

    DOF order of ``M`` and ``K``: n_modes modal coordinates q, then the boundary DOFs in
    the order of ``boundary_labels``. ``label_transform`` (n_labelled x (n_modes + n_b))
    gives the physical displacement of every labelled DOF of the component (``dof_labels``)
    from [q; x_b]; ``fixed_interface_modes`` (n x n_modes) and ``constraint_modes``
    (n x n_b, identity on the boundary rows) do the same for all n DOFs (optional: they
    may be dropped from files to save space). ``source_units`` says which unit system the
    model came in (it is SI now); ``recovery`` holds named output matrices over [q; x_b]
    (Nastran DTM/ATM/LTM, :class:`CBRecovery`)."""

    name: str
    boundary_labels: tuple[str, ...]
    fixed_omega: np.ndarray
    M: np.ndarray
    K: np.ndarray
    points: tuple[str, ...]
    point_coords: np.ndarray
    dof_labels: tuple[str, ...]
    label_transform: np.ndarray
    n_dof: int
    constraint_modes: np.ndarray | None = None
    fixed_interface_modes: np.ndarray | None = None
    timings: dict = field(default_factory=dict)
    source_units: str = "SI"
    recovery: tuple[CBRecovery, ...] = ()
    n_residual: int = 0        # the last n_residual modal coordinates are residual vectors (module docstring)

    def recovery_item(self, name: str) -> CBRecovery:
        for item in self.recovery:
            if item.name == name:
                return item
        have = ", ".join(it.name for it in self.recovery) or "none"
        raise InputError(f"CB model {self.name!r}: no recovery item {name!r} (has {have})")

    @property
    def n_modes(self) -> int:
        return self.fixed_omega.size

    @property
    def n_eigenmodes(self) -> int:
        """The fixed-interface eigenmodes kept: the modal coordinates less the residual vectors."""
        return self.n_modes - self.n_residual

    def select_modes(self, n_modes: int | None = None, f_max: float | None = None) -> "CBModel":
        """The same component keeping only its first ``n_modes`` fixed-interface modes at or
        below ``f_max`` Hz (None: no limit): rows and columns of the dropped modal
        coordinates removed from M, K, the label transform, the mode shapes and the
        recovery items (eq. 13 is block-diagonal in K, so this is the CB model a smaller
        selection would have given). A model with residual vectors keeps every mode (they
        are orthogonal to the modes it was reduced with, not to a subset)."""
        keep = np.arange(self.n_eigenmodes)
        if f_max is not None:
            keep = keep[self.fixed_freq_hz[keep] <= f_max * (1 + 1e-12)]
        if n_modes is not None:
            keep = keep[:n_modes]
        if self.n_residual and keep.size < self.n_eigenmodes:
            raise InputError(f"CB model {self.name!r}: its {self.n_residual} residual vectors are orthogonal to all "
                             f"{self.n_eigenmodes} of its fixed-interface modes; reduce it again with "
                             "the cut you want instead of selecting fewer modes")
        keep = np.concatenate([keep, np.arange(self.n_eigenmodes, self.n_modes)])
        if keep.size == self.n_modes:
            return self
        cols = np.concatenate([keep, self.n_modes + np.arange(self.n_boundary)])
        rec = tuple(CBRecovery(it.name, it.labels, it.units, **{k: m[:, cols] for k, m in it.parts.items()})
                    for it in self.recovery)
        fim = None if self.fixed_interface_modes is None else self.fixed_interface_modes[:, keep]
        return replace(self, fixed_omega=self.fixed_omega[keep], M=self.M[np.ix_(cols, cols)],
                       K=self.K[np.ix_(cols, cols)], label_transform=self.label_transform[:, cols],
                       fixed_interface_modes=fim, recovery=rec)

    @property
    def n_boundary(self) -> int:
        return len(self.boundary_labels)

    @property
    def C_M(self) -> np.ndarray:
        """Modal-boundary mass coupling (n_modes x n_b), eq. 13."""
        return self.M[: self.n_modes, self.n_modes:]

    @property
    def M_B(self) -> np.ndarray:
        return self.M[self.n_modes:, self.n_modes:]

    @property
    def K_B(self) -> np.ndarray:
        return self.K[self.n_modes:, self.n_modes:]

    @property
    def boundary_points(self) -> tuple[str, ...]:
        """Points of the boundary DOFs, in order of first appearance."""
        return tuple(dict.fromkeys(lab.split(":")[0] for lab in self.boundary_labels))

    @property
    def fixed_freq_hz(self) -> np.ndarray:
        return self.fixed_omega / (2 * np.pi)

    def point_coord(self, point: str) -> np.ndarray:
        try:
            return self.point_coords[self.points.index(point)]
        except ValueError:
            raise InputError(f"unknown point {point!r} in CB model {self.name!r}") from None

    def _need_recovery(self, what: str) -> None:
        if self.constraint_modes is None or self.fixed_interface_modes is None:
            raise InputError(f"CB model {self.name!r}: {what} needs the recovery arrays, "
                             "which were not saved (save with recovery=True)")

    def _full_vector(self, f) -> np.ndarray:
        f = np.asarray(f, dtype=float)
        if f.shape[0] != self.n_dof:
            raise InputError(f"CB model {self.name!r}: load has {f.shape[0]} rows, component has {self.n_dof} DOFs")
        return f

    def boundary_load(self, f) -> np.ndarray:
        """Static reduction of a component load (all n DOFs, N) to the boundary DOFs:
        f_b + Psi^T f_i = T_c^T f, with no modal part (the cryo loads of section 4.3)."""
        self._need_recovery("boundary_load")
        return self.constraint_modes.T @ self._full_vector(f)

    def generalized_load(self, f) -> np.ndarray:
        """Full CB generalised force [Phi^T f; T_c^T f] of a component load (all n DOFs)."""
        self._need_recovery("generalized_load")
        f = self._full_vector(f)
        return np.concatenate([self.fixed_interface_modes.T @ f, self.constraint_modes.T @ f])

    def save(self, path, recovery: bool = True) -> Path:
        return save_cb(self, path, recovery)

    @classmethod
    def load(cls, path) -> "CBModel":
        return load_cb(path)


# ------------------------------------------------------------------------ solvers
class CBSolver(Protocol):
    """The linear algebra of a Craig-Bampton reduction, injected into :func:`craig_bampton`
    (scikit-fem style ``solver=``): ONE factorisation of K_ii serves both the constraint
    modes and the shift-invert fixed-interface eigensolve.

    Called on every process with the component's whole K and M (scipy CSR), the interior
    and boundary DOF indices and the mode selection; returns, on every process,
    ``(lam, phi, psi, timings)``: the lowest fixed-interface eigenvalues omega^2 (rad^2/s^2,
    ascending; the first ``n_modes``, those <= (2 pi f_max)^2, or both), their modes
    Phi (n_i x n_q, Phi^T M_ii Phi = I), the constraint modes Psi = -K_ii^-1 K_ib
    (n_i x n_b) and a dict of wall times (s). ``who`` names the component in messages and
    ``dof_name(dof)`` a DOF (its label if it has one). A band (``n_modes`` None) holding more than
    ``band_limit`` modes is an InputError; so is a singular K_ii (the component floats
    once its boundary is fixed). :func:`scipy_solver` is the default; ``liftoff.fem``
    provides the PETSc/SLEPc one (``fem.petsc_cb.petsc_solver``). Called with
    ``inertia_residuals=True`` it returns a fifth item, X = K_ii^-1 (M_ii Psi + M_ib)
    (n_i x n_b, the same factor), for the residual vectors; a solver that does not take the
    keyword cannot give them."""

    def __call__(self, K: sp.csr_matrix, M: sp.csr_matrix, interior: np.ndarray, boundary: np.ndarray, *,
                 n_modes: int | None, f_max: float | None, band_limit: int, who: str,
                 dof_name: Callable[[int], str] = str) -> tuple: ...


@dataclass(frozen=True)
class ScipySolver:
    """SuperLU factor of K_ii (``ordering``: COLAMD, MMD_AT_PLUS_A, ...) shared by the
    constraint-mode solves and ARPACK shift-invert at sigma = 0 (dense ``eigh`` for
    interiors of at most DENSE_LIMIT DOFs or when (nearly) all modes are asked for);
    a band grows the mode count until it is covered. Serial."""

    ordering: str = ORDERING

    def __call__(self, K, M, interior, boundary, *, n_modes, f_max, band_limit, who, dof_name=str,
                 added_mass=None, inertia_residuals: bool = False):
        timings = {}
        t0 = time.perf_counter()
        K, M = K.tocsc(), M.tocsc()
        Ki, Mi = K[interior], M[interior]                                  # interior rows, sliced once
        Kii, Kib, Mii = Ki[:, interior].tocsc(), Ki[:, boundary], Mi[:, interior].tocsc()
        timings["partition_s"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        lu = _factor(Kii, who, lambda j: dof_name(int(interior[j])), self.ordering)
        timings["factor_s"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        psi = -lu.solve(np.asarray(Kib.todense()))                        # constraint modes
        timings["constraint_solve_s"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        if added_mass is not None:          # hydroelastic liquid: M_ii + G_i^T H^-1 G_i (reduction.liquid)
            Mii = added_mass.operator(Mii, interior)
        lam, phi = fixed_interface_eig(Kii, Mii, lu, n_modes, f_max, who, band_limit)
        timings["eigensolve_s"] = time.perf_counter() - t0
        if not inertia_residuals:
            return lam, phi, psi, timings
        if added_mass is not None:
            raise InputError(f"{who}: residual vectors of a component with a hydroelastic liquid are not implemented")
        t0 = time.perf_counter()
        X = lu.solve(np.asarray(Mii @ psi) + np.asarray(Mi[:, boundary].todense()))
        timings["residual_solve_s"] = time.perf_counter() - t0
        return lam, phi, psi, timings, X


def scipy_solver(ordering: str = ORDERING) -> ScipySolver:
    """The numpy/scipy CB solver (default of :func:`craig_bampton`)."""
    return ScipySolver(ordering)


# ------------------------------------------------------------------------ reduction
def craig_bampton(component: Component, boundary_labels, n_modes: int | None = None,
                  f_max: float | None = None, solver: CBSolver | None = None,
                  residual_vectors: bool = False) -> CBModel:
    """Craig-Bampton model of ``component`` with the given boundary DOF labels, keeping
    fixed-interface modes by count (``n_modes``), by band (below ``f_max`` Hz), or both
    (the first n_modes below f_max). n_modes=0 gives a Guyan (static) reduction.
    ``solver``: the factorisation + eigensolver (:class:`CBSolver`); default
    :func:`scipy_solver`, ``liftoff.fem.petsc_solver()`` for PETSc/SLEPc under MPI.
    ``residual_vectors``: the kept modes augmented with the static response to the boundary
    accelerations' inertia loads (module docstring; :func:`residual_modes`)."""
    who = f"component {component.name!r}"
    boundary_labels = _check_request(who, boundary_labels, n_modes, f_max)
    b = component.dofs_of(boundary_labels)
    n = component.n_dof
    is_b = np.zeros(n, bool)
    is_b[b] = True
    i = np.flatnonzero(~is_b)
    if i.size == 0:
        raise InputError(f"{who}: every DOF is a boundary DOF; nothing to reduce")
    if n_modes is not None:             # the dense modes (n x n_modes) and their products, before any solve
        # (n_modes beyond the interior DOFs means all of them)
        need = 3.0 * 8.0 * n * (min(n_modes, i.size) + b.size * (2 if residual_vectors else 1))
        limit = MEMORY_FRACTION * available_memory()
        if need > limit:
            raise ResourceError(f"{who}: {min(n_modes, i.size)} fixed-interface modes of {n} DOFs need about "
                                f"{need / 1e9:.3g} GB of dense mode shapes, more than the {limit / 1e9:.3g} GB "
                                "available: keep fewer (n_modes, f_max) or mesh coarser")
    solver = scipy_solver() if solver is None else solver
    liquid = component.liquid              # hydroelastic liquid (reduction.liquid.LiquidMass) or None
    if residual_vectors and (liquid is not None or component.slosh is not None):
        raise InputError(f"{who}: residual vectors of a component with a hydroelastic liquid or slosh pendulums are "
                         "not implemented (its mass is not M alone); reduce it without them")
    extra = {} if liquid is None else {"added_mass": liquid}
    if residual_vectors:
        extra["inertia_residuals"] = True
    try:
        got = solver(component.K, component.M, i, b, n_modes=n_modes, f_max=f_max, band_limit=BAND_MODE_LIMIT,
                     who=who, dof_name=lambda d: _dof_name(component, d), **extra)
    except TypeError as exc:
        if residual_vectors and "inertia_residuals" in str(exc):
            raise InputError(f"{who}: CB solver {type(solver).__name__} does not give residual vectors") from None
        raise
    if residual_vectors and len(got) < 5:
        raise InputError(f"{who}: CB solver {type(solver).__name__} does not give residual vectors")
    lam, phi, psi, timings = got[:4]
    timings = dict(timings)
    lam, phi = _select(np.asarray(lam, float), np.asarray(phi, float), n_modes, f_max)
    psi = np.asarray(psi, float)
    n_res = 0
    if residual_vectors:
        t0 = time.perf_counter()
        Kii, Mii = component.K[i][:, i], component.M[i][:, i]
        lam_r, res = residual_modes(Kii, Mii, phi, np.asarray(got[4], float), float(lam[-1]) if lam.size else 0.0)
        lam, phi, n_res = np.concatenate([lam, lam_r]), np.hstack([phi, res]), lam_r.size
        timings["residual_modes_s"] = time.perf_counter() - t0
    if phi.shape != (i.size, lam.size) or psi.shape != (i.size, b.size):
        raise InputError(f"{who}: CB solver {type(solver).__name__} returned modes {phi.shape} and "
                         f"constraint modes {psi.shape}, expected ({i.size}, {lam.size}) and ({i.size}, {b.size})")
    _check_not_floating(lam, component.K.diagonal()[i], component.M.diagonal()[i], who)

    t0 = time.perf_counter()
    nq, nb = lam.size, b.size
    fim = np.zeros((n, nq))
    fim[i] = phi
    cm = np.zeros((n, nb))
    cm[i] = psi
    cm[b, np.arange(nb)] = 1.0
    del phi, psi
    # eq. 13 with T_c = cm: K_B = K_bb + K_bi Psi = (K T_c)_b,  M_B = T_c^T M T_c,
    # C_M = Phi^T (M_ii Psi + M_ib) = fim^T (M T_c)  (fim is zero on the boundary rows)
    K_B = np.asarray(component.K[b] @ cm)
    M_cm = np.asarray(component.M @ cm)
    if liquid is not None:                 # M + M_a (one multi-right-hand-side fluid solve)
        M_cm = M_cm + liquid.apply(cm)
    M_B = cm.T @ M_cm
    C_M = fim.T @ M_cm
    del M_cm
    Mcb = np.block([[np.eye(nq), C_M], [C_M.T, M_B]])
    Kcb = np.zeros((nq + nb, nq + nb))
    Kcb[:nq, :nq] = np.diag(lam)
    Kcb[nq:, nq:] = K_B
    timings["matrices_s"] = time.perf_counter() - t0
    return CBModel(name=component.name, boundary_labels=boundary_labels,
                   fixed_omega=np.sqrt(lam), M=0.5 * (Mcb + Mcb.T), K=0.5 * (Kcb + Kcb.T),
                   points=component.points, point_coords=component.point_coords.copy(),
                   dof_labels=component.dof_labels,
                   label_transform=np.hstack([fim[component.label_dofs], cm[component.label_dofs]]),
                   n_dof=n, constraint_modes=cm, fixed_interface_modes=fim, timings=timings, n_residual=n_res,
                   recovery=(() if liquid is None else liquid.cb_recovery(fim, cm, rigid=cm @ _axial(boundary_labels)))
                   + (() if component.slosh is None else component.slosh.cb_recovery(fim, cm)))


#: residual directions whose squared M_ii-norm after the projection on the kept modes is below
#: this (each column scaled to a unit norm first: boundary translations and rotations differ in
#: units) are dropped. Two Gram-Schmidt passes leave a leftover orthogonal to the kept modes to
#: working precision relative to its own size, so a leftover however small is a valid Ritz
#: direction, and a small one in M_ii can carry a large force (K z ~ omega^2 z: an L-frame cut at
#: 100 of its 234 modes kept 7 of 12 at 1e-14 and its clamped reactions were 2e-6 off, 1e-10 with
#: all 12); what the projection itself leaves of a unit vector is its round-off, ~n eps ~ 1e-13 in
#: size: 1e-20 (a size of 1e-10) stays 1000x above it
RESIDUAL_RTOL = 1e-20


def residual_modes(Kii, Mii, phi: np.ndarray, X: np.ndarray, lam_kept: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """(omega^2, modes) of the residual vectors ``X`` (n_i x k: K_ii^-1 of the inertia loads,
    module docstring) against the kept, M_ii-normalised modes ``phi`` (the highest of their
    eigenvalues ``lam_kept``): X made M_ii-orthogonal to them (Gram-Schmidt twice), its
    independent directions (those above RESIDUAL_RTOL) M_ii-orthonormalised, made orthogonal to
    phi twice again (a combination of nearly dependent columns magnifies their round-off) and
    diagonalised, K_ii Z = M_ii Z omega^2 on their span (Rayleigh-Ritz), so Z^T M_ii Z = I,
    Z^T K_ii Z = diag(omega^2), and both zero against phi. A direction M_ii-orthogonal to every
    kept mode has a Rayleigh quotient above them all; a Ritz value that is not (round-off left
    in a direction nearly inside the kept modes' span) is dropped."""
    empty = np.zeros(0), np.zeros((X.shape[0], 0))
    if X.size == 0:
        return empty

    def orthonormal(A, tol):            # A made M_ii-orthogonal to phi, its directions above tol, M_ii-orthonormal
        for _ in range(2):
            A = A - phi @ (phi.T @ (Mii @ A))
        G = A.T @ (Mii @ A)
        s, U = sla.eigh(0.5 * (G + G.T))
        keep = s > tol
        return A @ (U[:, keep] / np.sqrt(s[keep]))

    norms = np.sqrt(np.einsum("ij,ij->j", X, Mii @ X))
    Y = orthonormal(X[:, norms > 0] / norms[norms > 0], RESIDUAL_RTOL)
    if Y.shape[1]:
        Y = orthonormal(Y, 0.5)         # once more on the unit directions: only round-off to remove
    if not Y.shape[1]:
        return empty
    Kr = Y.T @ (Kii @ Y)
    lam, V = sla.eigh(0.5 * (Kr + Kr.T))
    above = lam > lam_kept * (1 + 1e-8) if lam_kept > 0 else lam > 0
    if not above.any():
        return empty
    lam, Z = lam[above], Y @ V[:, above]
    return lam, Z / np.sqrt(np.einsum("ij,ij->j", Z, Mii @ Z))


def _axial(boundary_labels) -> np.ndarray:
    """The boundary DOFs' values in a unit rigid translation along z (the tank axis)."""
    return np.array([1.0 if split_label(lab)[1] == 2 else 0.0 for lab in boundary_labels])


def _check_request(who: str, boundary_labels, n_modes, f_max) -> tuple[str, ...]:
    boundary_labels = tuple(str(s) for s in boundary_labels)
    if not boundary_labels:
        raise InputError(f"{who}: no boundary labels given")
    dup = [s for s in boundary_labels if boundary_labels.count(s) > 1]
    if dup:
        raise InputError(f"{who}: boundary label {dup[0]!r} given twice")
    if n_modes is None and f_max is None:
        raise InputError(f"{who}: give n_modes or f_max (Hz) to select fixed-interface modes")
    if n_modes is not None and n_modes < 0:
        raise InputError(f"{who}: n_modes must be >= 0, got {n_modes}")
    if f_max is not None and not f_max > 0:
        raise InputError(f"{who}: f_max must be > 0 Hz, got {f_max}")
    return boundary_labels


def _select(lam: np.ndarray, phi: np.ndarray, n_modes, f_max) -> tuple[np.ndarray, np.ndarray]:
    """The selection rule, whatever the solver returned: ascending, first n_modes, <= f_max."""
    order = np.argsort(lam, kind="stable")
    lam, phi = lam[order], phi[:, order]
    keep = np.ones(lam.size, bool)
    if n_modes is not None:
        keep &= np.arange(lam.size) < n_modes
    if f_max is not None:
        keep &= lam <= (2 * np.pi * f_max) ** 2
    return lam[keep], phi[:, keep]


def _dof_name(component: Component, dof: int) -> str:
    hit = np.flatnonzero(component.label_dofs == dof)
    return component.dof_labels[hit[0]] if hit.size else f"DOF {dof}"


def _factor(Kii: sp.csc_matrix, who: str, name_of, ordering: str = ORDERING):
    """Sparse LU of K_ii (SuperLU, symmetric mode, no pivoting: K_ii is SPD for a
    restrained component); singular K_ii -> InputError naming the DOF (``name_of(j)``
    for interior index j)."""
    try:
        lu = spla.splu(Kii, permc_spec=ordering, diag_pivot_thresh=0.0,
                       options={"SymmetricMode": True})
    except RuntimeError as exc:   # "Factor is exactly singular"
        raise InputError(f"{who} floats (or has a mechanism) once its boundary DOFs are fixed: "
                         f"K_ii is singular ({exc}); add boundary DOFs that restrain it") from None
    # a floating part or mechanism leaves a pivot at round-off level relative to the
    # diagonal entry it came from (a well-posed but ill-conditioned model does not)
    pivots = np.abs(lu.U.diagonal())
    diag = np.abs(Kii.diagonal())[lu.perm_c]
    ratio = pivots / np.maximum(diag, 1e-300)
    if ratio.size and ratio.min() < 1e-10:
        raise InputError(f"{who} floats (or has a mechanism) once its boundary DOFs are fixed: "
                         f"K_ii is singular near {name_of(lu.perm_c[np.argmin(ratio)])} (pivot/diagonal "
                         f"{ratio.min():.1e}); add boundary DOFs that restrain it")
    return lu


def fixed_interface_eig(Kii, Mii, lu, n_modes, f_max, who="component", band_limit=None):
    """Lowest fixed-interface eigenpairs (omega^2, M_ii-normalised modes), by count and/or
    band, from shift-invert at zero shift with the factor ``lu`` of K_ii."""
    band_limit = BAND_MODE_LIMIT if band_limit is None else band_limit
    n_i = Kii.shape[0]
    lam_max = None if f_max is None else (2 * np.pi * f_max) ** 2
    want = n_i if n_modes is None else min(n_modes, n_i)
    if want == 0:
        return np.zeros(0), np.zeros((n_i, 0))
    # dense only for small interiors or an explicit request for (nearly) all modes; a band
    # alone (n_modes None) must never fall through to a dense n_i x n_i eigensolve
    if n_i <= DENSE_LIMIT or (n_modes is not None and want >= n_i - 1):
        lam, phi = sla.eigh(Kii.toarray(), Mii.toarray() if sp.issparse(Mii) else Mii @ np.eye(n_i))
    else:
        op = spla.LinearOperator(Kii.shape, matvec=lu.solve, dtype=float)
        k = want if lam_max is None else min(want, 20)
        while True:
            lam, phi = spla.eigsh(Kii, k=k, M=Mii, sigma=0.0, which="LM", OPinv=op)
            order = np.argsort(lam)
            lam, phi = lam[order], phi[:, order]
            if k >= want or lam_max is None or lam[-1] > lam_max:
                break
            if k >= n_i - 2:
                raise InputError(f"{who}: f_max covers (nearly) all {n_i} fixed-interface modes; "
                                 "give n_modes instead")
            if n_modes is None and k >= band_limit:
                # A band that holds this many modes of a solid mesh is mostly local wall modes;
                # growing the Lanczos basis further costs GBs (k x n_i vectors and ARPACK work).
                raise InputError(band_error(who, band_limit, f_max, f"mode {k} at "
                                            f"{np.sqrt(lam[-1]) / (2 * np.pi):.1f} Hz"))
            k = min(2 * k, want, n_i - 2)
            if n_modes is None:
                k = min(k, band_limit)
    lam, phi = _select(lam, phi, want, f_max)
    norms = np.sqrt(np.einsum("ij,ij->j", phi, Mii @ phi))
    phi = phi / norms
    return lam, phi


def band_error(who: str, band_limit: int, f_max: float, found: str) -> str:
    """The one-line message of a band holding more than ``band_limit`` modes."""
    return (f"{who}: more than {band_limit} fixed-interface modes lie below f_max = {f_max:g} Hz "
            f"({found}); lower f_max or give n_modes")


def _check_not_floating(lam, k_diag, m_diag, who):
    if lam.size == 0:
        return
    # a floating part left after the pivot test of the factorisation has an eigenvalue at
    # round-off, ~eps lambda_max ~ 1e-16 scale; a restrained but finely meshed component has
    # lambda_1/scale ~ (h/L)^4 (a 47 m beam in 1 cm elements: 9e-13), hence 1e-14
    scale = k_diag.sum() / max(m_diag.sum(), 1e-300)
    if lam[0] < 1e-14 * abs(scale):
        raise InputError(f"{who} floats (or has a mechanism) once its boundary DOFs are fixed: "
                         f"lowest fixed-interface eigenvalue {lam[0]:.3e} is zero; add boundary DOFs")


# ---------------------------------------------------------------------------- file
def save_cb(cb: CBModel, path, recovery: bool = True) -> Path:
    """Write a CB model atomically as .npz (no pickle). Format in docs/reduction.md."""
    data = {"boundary_labels": np.array(cb.boundary_labels, dtype="U"),
            "fixed_omega": cb.fixed_omega, "M": cb.M, "K": cb.K,
            "points": np.array(cb.points, dtype="U"), "point_coords": cb.point_coords,
            "dof_labels": np.array(cb.dof_labels, dtype="U"), "label_transform": cb.label_transform,
            "n_dof": np.array(cb.n_dof)}
    if cb.n_residual:
        data["n_residual"] = np.array(cb.n_residual)
    if recovery and cb.constraint_modes is not None and cb.fixed_interface_modes is not None:
        data["constraint_modes"] = cb.constraint_modes
        data["fixed_interface_modes"] = cb.fixed_interface_modes
    if cb.recovery:
        data["recovery_names"] = np.array([it.name for it in cb.recovery], dtype="U")
        data["recovery"] = {it.name: {"labels": np.array(it.labels, dtype="U"),
                                      "units": np.array(it.units, dtype="U"), **it.parts}
                            for it in cb.recovery}
    return write_record(path, FORMAT, VERSION, data, units="SI", suffixes=(".npz",),
                        attrs={"name": cb.name, "source_units": cb.source_units})


def load_cb(path, mmap: bool = False) -> CBModel:
    """A CB model file (:meth:`CBModel.save`); ``mmap``: its large arrays mapped read-only
    (liftoff.core.records.read_record), for files checked otherwise (the stage cache)."""
    rec = read_record(path, FORMAT, (1, VERSION), what="CB model file", mmap=mmap)
    z = rec.data
    try:
        items = tuple(CBRecovery(name=str(nm), labels=tuple(z["recovery"][nm]["labels"]),
                                 units=tuple(z["recovery"][nm]["units"]),
                                 **{k: z["recovery"][nm].get(k) for k in RECOVERY_PARTS})
                      for nm in z.get("recovery_names", ()))
        cb = CBModel(name=str(rec.attrs["name"]), boundary_labels=tuple(z["boundary_labels"]),
                     fixed_omega=z["fixed_omega"], M=z["M"], K=z["K"], points=tuple(z["points"]),
                     point_coords=z["point_coords"], dof_labels=tuple(z["dof_labels"]),
                     label_transform=z["label_transform"], n_dof=int(z["n_dof"]),
                     constraint_modes=z.get("constraint_modes"), fixed_interface_modes=z.get("fixed_interface_modes"),
                     source_units=str(rec.attrs.get("source_units", "SI")), recovery=items,
                     n_residual=int(z.get("n_residual", 0)))
    except InputError as exc:
        raise InputError(f"CB model file {str(path)!r}: {exc}") from None
    except Exception as exc:
        raise InputError(f"CB model file {str(path)!r} cannot be read: {exc}") from None
    validate_cb(cb, str(path))
    return cb


#: the largest |A - A^T| of a CB model's M or K, relative to its largest entry (the round-off of
#: a congruence P^T A P is about 1e-15 of it; an input file's printed digits more)
SYMMETRY_TOL = 1e-8


def validate_cb(cb: CBModel, where: str = "") -> None:
    """Shapes and labels of a CB model (e.g. one from outside this project)."""
    who = f"CB model {cb.name!r}" + (f" ({where})" if where else "")
    nq, nb = cb.fixed_omega.size, len(cb.boundary_labels)
    if cb.M.shape != (nq + nb, nq + nb) or cb.K.shape != (nq + nb, nq + nb):
        raise InputError(f"{who}: M {cb.M.shape} and K {cb.K.shape} must be ({nq + nb}, {nq + nb})")
    for lab in cb.boundary_labels:
        pt, _ = split_label(lab)
        if pt not in cb.points:
            raise InputError(f"{who}: boundary label {lab!r} names a point without coordinates")
    if cb.point_coords.shape != (len(cb.points), 3):
        raise InputError(f"{who}: point_coords has shape {cb.point_coords.shape}, expected ({len(cb.points)}, 3)")
    if not 0 <= cb.n_residual <= nq:
        raise InputError(f"{who}: n_residual = {cb.n_residual} must lie in [0, {nq}] (the modal coordinates)")
    if cb.label_transform.shape != (len(cb.dof_labels), nq + nb):
        raise InputError(f"{who}: label_transform has shape {cb.label_transform.shape}")
    for nm in ("M", "K", "fixed_omega", "point_coords", "label_transform"):
        if not np.all(np.isfinite(getattr(cb, nm))):
            raise InputError(f"{who}: {nm} contains NaN or inf")
    for nm in ("M", "K"):             # the eigensolvers read one triangle: an unsymmetric matrix is ambiguous
        A = np.asarray(getattr(cb, nm))
        big = float(np.abs(A).max()) if A.size else 0.0
        skew = float(np.abs(A - A.T).max()) if A.size else 0.0
        if skew > SYMMETRY_TOL * big:
            i, j = np.unravel_index(int(np.argmax(np.abs(A - A.T))), A.shape)
            raise InputError(f"{who}: {nm} is not symmetric: |{nm} - {nm}^T| reaches {skew:.3g} at "
                             f"({i}, {j}), {skew / big:.2g} of its largest entry (more than {SYMMETRY_TOL:g}); "
                             "a mass or stiffness matrix must be symmetric")
    names = [it.name for it in cb.recovery]
    for it in cb.recovery:
        if names.count(it.name) > 1:
            raise InputError(f"{who}: recovery item {it.name!r} given twice")
        for key, m in it.parts.items():
            if m.shape[1] != nq + nb:
                raise InputError(f"{who}: recovery item {it.name!r}: {key} has {m.shape[1]} columns, "
                                 f"expected {nq + nb} (n_modes + n_boundary)")
            if not np.all(np.isfinite(m)):
                raise InputError(f"{who}: recovery item {it.name!r}: {key} contains NaN or inf")
