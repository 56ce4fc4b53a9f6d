"""Structured triangle meshes of parametric surfaces and a small direct-solve harness for the
shell benchmark tests (tests/fem/test_shell_*.py). The element under test is
liftoff.fem.shell; boundary conditions are imposed by removing DOFs (rows and columns),
the way the model builder removes clamped DOFs.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as sla
from mpi4py import MPI

from liftoff.fem import petsc_backend as pb
from liftoff.fem import shell as sh
from liftoff.fem.mesh import triangle_mesh


def param_grid(nx: int, ny: int, periodic_y: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Nodes (s, r) of an nx x ny grid on [0, 1]^2 and its triangles (each square cut along
    the same diagonal). ``periodic_y``: the row r = 1 is the row r = 0 (closed surfaces)."""
    s, r = np.meshgrid(np.linspace(0, 1, nx + 1), np.linspace(0, 1, ny + 1))
    P = np.column_stack([s.ravel(), r.ravel()])
    idx = np.arange((nx + 1) * (ny + 1)).reshape(ny + 1, nx + 1)
    if periodic_y:
        idx[-1] = idx[0]
    a, b, c, d = idx[:-1, :-1], idx[:-1, 1:], idx[1:, 1:], idx[1:, :-1]
    cells = np.vstack([np.column_stack([a.ravel(), b.ravel(), c.ravel()]),
                       np.column_stack([a.ravel(), c.ravel(), d.ravel()])])
    if periodic_y:
        used = np.unique(cells)
        new = np.full(P.shape[0], -1)
        new[used] = np.arange(used.size)
        P, cells = P[used], new[cells]
    return P, cells


class ShellCase:
    """Shell space, K, M (scipy CSR) and the DOF table of one mesh, homogeneous material."""

    def __init__(self, X, cells, E, nu, t, rho=1.0, traction=None):
        from dolfinx import fem

        self.mesh = triangle_mesh(MPI.COMM_SELF, X, cells)
        self.W = sh.shell_space(self.mesh)
        c = lambda v: fem.Constant(self.mesh, float(v))  # noqa: E731
        self.fields = sh.ShellFields(c(E), c(nu), c(rho), c(t))
        self.K = pb.gather_csr(pb.assemble_matrix(sh.stiffness_form(self.W, self.fields)))
        self.M = pb.gather_csr(pb.assemble_matrix(sh.mass_form(self.W, self.fields)))
        self.coords, self.comp = sh.dof_table(self.W)
        self.b = np.zeros(self.K.shape[0])
        if traction is not None:
            q = fem.Constant(self.mesh, np.asarray(traction, float))
            self.b = pb.gather_vec(pb.assemble_vector(sh.load_form(self.W, q)))

    @property
    def n_dof(self) -> int:
        return self.K.shape[0]

    def where(self, mask, comps) -> np.ndarray:
        """DOF indices at the DOF points selected by ``mask`` with component in ``comps``."""
        return np.flatnonzero(mask & np.isin(self.comp, comps))

    def dof_at(self, point, comp: int, tol: float = 1e-8) -> int:
        d = np.linalg.norm(self.coords - np.asarray(point, float), axis=1)
        hit = np.flatnonzero((d < tol * max(1.0, np.abs(point).max())) & (self.comp == comp))
        assert hit.size == 1, f"no unique DOF {comp} at {point}"
        return int(hit[0])

    def solve(self, fixed, b=None) -> np.ndarray:
        """K x = b with x[fixed] = 0 (direct, SuperLU)."""
        b = self.b if b is None else b
        free = np.setdiff1d(np.arange(self.n_dof), fixed)
        x = np.zeros(self.n_dof)
        x[free] = sla.spsolve(sp.csc_matrix(self.K[free][:, free]), b[free])
        return x


def orders(values, ratios) -> np.ndarray:
    """Observed convergence orders from successive differences of three or more values on
    meshes refined by ``ratios`` (h_i / h_{i+1}); no reference value needed."""
    v = np.asarray(values, float)
    d = np.abs(np.diff(v))
    r = np.asarray(ratios, float)
    return np.log(d[:-1] / d[1:]) / np.log(r[1:])
