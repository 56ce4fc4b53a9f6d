"""Rigid spiders (Nastran RBE2 equivalent) and grounding as one sparse transformation.

The full nodal DOF vector x_full (3 per mesh node: ux, uy, uz) is written in terms of the
model's independent DOFs x: x_full = T x. For a node of a patch with reference point p,
u_node = t_p + theta_p x (x_node - x_p) (small rotations); a clamped node has u = 0 (an
empty row of T, the DOF is removed, not penalised); any other node keeps its own three
DOFs. Then K_r = T^T K T, M_r = T^T M T and a load f_full reduces to T^T f_full, so that a
force at a reference point is statically equivalent to the resultant over the patch.
Pure numpy/scipy: the rows built here are turned into a PETSc matrix by petsc_backend.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from liftoff.core.rigid import TRANSLATION_COLUMNS, translation_coefficients

FREE, CLAMPED = -1, -2


def transformation_rows(node_coords: np.ndarray, node_role: np.ndarray, keep_index: np.ndarray,
                        ref_coords: np.ndarray, ref_first_dof: int, n_cols: int) -> sp.csr_matrix:
    """This rank's rows of T (3 per owned node, x,y,z interleaved), global column indices.

    node_role[i] = FREE, CLAMPED, or the patch number p (>= 0) of node i;
    keep_index[i] = global index of node i's x DOF among the independent DOFs (FREE nodes);
    reference point p owns independent DOFs ref_first_dof + 6 p + (0..5).
    """
    n = node_coords.shape[0]
    rows, cols, vals = [], [], []
    free = np.flatnonzero(node_role == FREE)
    for c in range(3):
        rows.append(3 * free + c)
        cols.append(keep_index[free] + c)
        vals.append(np.ones(free.size))
    for p in np.unique(node_role[node_role >= 0]):
        nodes = np.flatnonzero(node_role == p)
        d = node_coords[nodes] - ref_coords[p]
        for c in range(3):
            cc, coef = TRANSLATION_COLUMNS[c], translation_coefficients(d, c)
            for k in range(3):
                rows.append(3 * nodes + c)
                cols.append(np.full(nodes.size, ref_first_dof + 6 * p + cc[k]))
                vals.append(coef[:, k])
    r, cidx, v = (np.concatenate(a) if a else np.zeros(0) for a in (rows, cols, vals))
    return sp.csr_matrix((v, (r.astype(np.int64), cidx.astype(np.int64))), shape=(3 * n, n_cols))
