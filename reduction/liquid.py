"""A component's hydroelastic liquid as sparse matrices (issue 10): the added mass
M_a = G^T H^-1 G over the component's DOFs and the liquid's recovery rows, never formed
densely. numpy/scipy only; the matrices come from fem.liquid (or from elsewhere).

``H`` (n_p x n_p, SPD): the liquid's Laplacian over its pressure DOFs, each liquid's
entries divided by its density, the free-surface (p = 0) DOFs removed; ``G`` (n_p x n_dof):
the wall-normal coupling int N_i psi_j . n dS over the wetted surfaces, mapped to the
component's DOFs. Then (fem.liquid, eq. 2-5)

    p = -H^-1 G x'',   M_a = G^T H^-1 G,   (M + M_a) x'' + K x = f,
    p_k = r_k . x'',   r_k = -G^T H^-1 e_k            (pressure at liquid node k, Pa)
    dV_c = v_c . x                                       (volume change of cavity c, m^3)

``factor()`` factors H once (SuperLU); M_a X for a block X is one multi-right-hand-side
solve. A uniform apparent acceleration a of the component (gravity: a = -g) is the rigid
translation x'' = RB_t a, so the hydrostatic head at k is r_k . RB_t a. Units SI.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from liftoff.core.errors import InputError


@dataclass
class LiquidMass:
    """Sparse added-mass data of a component's liquids (module docstring)."""

    H: sp.csr_matrix                     # (n_p, n_p) m / kg ... (Laplacian / rho)
    G: sp.csr_matrix                     # (n_p, n_dof) m^2
    pressure_points: tuple[str, ...] = ()
    pressure_dofs: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    volume_names: tuple[str, ...] = ()
    volume_rows: sp.csr_matrix | None = None     # (n_v, n_dof) m^3 per m
    mass: float = 0.0                    # kg, the liquids' mass
    centroid: np.ndarray = field(default_factory=lambda: np.zeros(3))
    liquids: tuple[str, ...] = ()        # the liquids (volume groups); H is block diagonal over them
    pressure_liquid: np.ndarray | None = None    # (n_p,) index into liquids of each pressure DOF
    _lu: object = field(default=None, repr=False, compare=False)

    def __post_init__(self) -> None:
        self.H = sp.csr_matrix(self.H, dtype=float)
        self.G = sp.csr_matrix(self.G, dtype=float)
        self.pressure_points = tuple(str(s) for s in self.pressure_points)
        self.pressure_dofs = np.asarray(self.pressure_dofs, np.int64).reshape(-1)
        self.volume_names = tuple(str(s) for s in self.volume_names)
        n_p = self.H.shape[0]
        if self.volume_rows is None:
            self.volume_rows = sp.csr_matrix((0, self.G.shape[1]))
        self.volume_rows = sp.csr_matrix(self.volume_rows, dtype=float)
        self.centroid = np.asarray(self.centroid, float).reshape(3)
        self.liquids = tuple(str(s) for s in self.liquids)
        if self.pressure_liquid is None:
            self.pressure_liquid = np.zeros(n_p, np.int64)
        self.pressure_liquid = np.asarray(self.pressure_liquid, np.int64).reshape(-1)
        if self.pressure_liquid.size != n_p or (n_p and self.liquids and self.pressure_liquid.max() >= len(self.liquids)):
            raise InputError(f"liquid: pressure_liquid must give one of the {len(self.liquids)} liquids per "
                             f"pressure DOF ({n_p})")
        if self.H.shape != (n_p, n_p) or self.G.shape[0] != n_p:
            raise InputError(f"liquid: H {self.H.shape} must be square with G's {self.G.shape[0]} rows")
        if len(self.pressure_points) != self.pressure_dofs.size or \
                (self.pressure_dofs.size and (self.pressure_dofs.min() < 0 or self.pressure_dofs.max() >= n_p)):
            raise InputError("liquid: pressure points and their DOFs (0..n_p-1) do not match")
        if self.volume_rows.shape != (len(self.volume_names), self.G.shape[1]):
            raise InputError(f"liquid: volume rows {self.volume_rows.shape} for {len(self.volume_names)} names "
                             f"and {self.G.shape[1]} DOFs")
        for nm in ("H", "G", "volume_rows"):
            if not np.all(np.isfinite(getattr(self, nm).data)):
                raise InputError(f"liquid: {nm} contains NaN or inf")

    @property
    def n_dof(self) -> int:
        return self.G.shape[1]

    def factor(self):
        """The SuperLU factor of H (computed once)."""
        if self._lu is None:
            try:
                self._lu = spla.splu(self.H.tocsc())
            except RuntimeError as exc:
                raise InputError(f"liquid: H is singular ({exc}): a liquid without a free surface") from None
        return self._lu

    def solve(self, B: np.ndarray) -> np.ndarray:
        B = np.asarray(B, float)
        return self.factor().solve(B) if B.size else B.copy()

    def _g(self, dofs) -> sp.csr_matrix:
        return self.G if dofs is None else self.G[:, np.asarray(dofs, np.int64)]

    def apply(self, X: np.ndarray, dofs=None) -> np.ndarray:
        """M_a X over all DOFs, or over the DOF subset ``dofs`` (rows and columns)."""
        G = self._g(dofs)
        return G.T @ self.solve(G @ np.asarray(X, float))

    def project(self, X: np.ndarray, dofs=None) -> np.ndarray:
        """X^T M_a X (one multi-right-hand-side solve)."""
        G = self._g(dofs)
        GX = G @ np.asarray(X, float).reshape(G.shape[1], -1)
        out = GX.T @ self.solve(GX)
        return 0.5 * (out + out.T)

    def operator(self, M: sp.spmatrix, dofs=None) -> spla.LinearOperator:
        """M + M_a (restricted to ``dofs``) as a scipy LinearOperator (M already restricted)."""
        M, G = sp.csr_matrix(M), sp.csr_matrix(self._g(dofs))      # sliced once

        def mass(X):
            return M @ X + G.T @ self.solve(G @ X)

        return spla.LinearOperator(M.shape, matvec=mass, matmat=mass, dtype=float)

    def pressure_rows(self) -> np.ndarray:
        """(n_points, n_dof): p_k = r_k . x'' (Pa per m/s^2)."""
        E = np.zeros((self.H.shape[0], len(self.pressure_points)))
        E[self.pressure_dofs, np.arange(self.pressure_dofs.size)] = 1.0
        return -(self.G.T @ self.solve(E)).T

    def axial_inertia_rows(self, rigid: np.ndarray) -> np.ndarray:
        """(n_liquids, n_dof) rows f_c = (M_a,c r)^T with F_c = f_c . x'' the force that
        accelerates liquid c (N) along the rigid translation field ``rigid`` (n_dof,: a unit
        translation of the component); M_a,c = G_c^T H_c^-1 G_c uses liquid c's pressure DOFs
        only (H is block diagonal over the liquids). Under x'' = a r, F_c = m_c a for any tank
        along its axis (the whole liquid moves axially with the tank, fem.liquid)."""
        Y = self.solve(self.G @ np.asarray(rigid, float))            # H^-1 G r, all liquids at once
        rows = []
        for c in range(max(len(self.liquids), 1)):
            on = (self.pressure_liquid == c).astype(float)
            rows.append(self.G.T @ (on * Y))
        return np.vstack(rows)

    def cb_recovery(self, fim: np.ndarray, cm: np.ndarray, prefix: str = "", rigid: np.ndarray | None = None) -> tuple:
        """The liquid's recovery items over a CB model's DOFs [q; x_b] (u = fim q + cm x_b):
        ``<prefix>ullage_volume`` (disp rows, m^3: each cavity's volume change),
        ``<prefix>liquid_pressure`` (acc rows, Pa: the pressure at each pressure point from
        the accelerations; the head under gravity is the same row times the rigid
        translation -g) and, with ``rigid`` (the component's unit axial translation),
        ``<prefix>liquid_axial_inertia`` (acc rows, N, :meth:`axial_inertia_rows`). Empty
        items are left out."""
        from .craig_bampton import CBRecovery

        T = np.hstack([fim, cm])
        out = []
        if self.volume_names:
            out.append(CBRecovery(f"{prefix}ullage_volume", self.volume_names, ("m^3",) * len(self.volume_names),
                                  disp=np.asarray(self.volume_rows @ T)))
        if self.pressure_points:
            out.append(CBRecovery(f"{prefix}liquid_pressure", self.pressure_points,
                                  ("Pa",) * len(self.pressure_points), acc=self.pressure_rows() @ T))
        if rigid is not None and self.liquids:
            out.append(CBRecovery(f"{prefix}liquid_axial_inertia", self.liquids, ("N",) * len(self.liquids),
                                  acc=self.axial_inertia_rows(rigid) @ T))
        return tuple(out)

    # ---- file fields (reduction.component) ----------------------------------------------
    def record(self) -> dict:
        from .component import _csr_record

        return {"liquid_H": _csr_record(self.H), "liquid_G": _csr_record(self.G),
                "liquid_volume_rows": _csr_record(self.volume_rows),
                "liquid_pressure_points": np.array(self.pressure_points, dtype="U"),
                "liquid_pressure_dofs": self.pressure_dofs,
                "liquid_volume_names": np.array(self.volume_names, dtype="U"),
                "liquid_mass": np.array(self.mass), "liquid_centroid": self.centroid,
                "liquid_liquids": np.array(self.liquids, dtype="U"), "liquid_pressure_liquid": self.pressure_liquid}

    @classmethod
    def from_record(cls, z: dict) -> "LiquidMass | None":
        from .component import _csr_from

        if "liquid_H" not in z:
            return None
        return cls(_csr_from(z["liquid_H"]), _csr_from(z["liquid_G"]), tuple(z["liquid_pressure_points"]),
                   z["liquid_pressure_dofs"], tuple(z["liquid_volume_names"]), _csr_from(z["liquid_volume_rows"]),
                   float(z["liquid_mass"]), z["liquid_centroid"], tuple(z.get("liquid_liquids", ())),
                   z.get("liquid_pressure_liquid"))
