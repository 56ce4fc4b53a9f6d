"""Rigid spiders (Nastran RBE2 equivalent) and grounding as one sparse transformation.

The full DOF vector of a model part (solid: 3 translations per node; shell: 3
translations per node and 3 rotations per edge-midpoint node, see fem.shell) is written in
terms of the model's independent DOFs x: x_full = T x. For a DOF of a node on a patch with
reference point p the rigid-body kinematics of liftoff.core.rigid apply, translations
u = t_p + theta_p x (x_node - x_p) and rotations theta = theta_p (small rotations: the
spider ties shell rotations too); a clamped node's DOFs are zero (an empty row of T: the
DOF is removed, not penalised); any other DOF is one independent DOF. Then
K_r = T^T K T, M_r = T^T M T and a load f_full reduces to T^T f_full, so that a force at a
reference point is statically equivalent to the resultant over the patch.
Pure numpy/scipy: the rows built here are turned into a PETSc matrix by petsc_backend.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from liftoff.core.rigid import dof_rb

FREE, CLAMPED = -1, -2


def transformation_rows(dof_coords: np.ndarray, dof_comp: np.ndarray, dof_role: np.ndarray,
                        dof_col: np.ndarray, ref_coords: np.ndarray, ref_first_dof: int,
                        n_cols: int) -> sp.csr_matrix:
    """Rows of T for a list of DOFs (one row each), global column indices.

    dof_comp[i] in 0..5 (Tx..Rz); dof_role[i] = FREE, CLAMPED, or the patch number p >= 0
    of DOF i's node; dof_col[i] = the independent DOF of a FREE DOF (ignored otherwise; < 0:
    none, an empty row the caller fills, e.g. a DOF tied to other nodes' DOFs);
    reference point p owns the independent DOFs ref_first_dof + 6 p + (0..5).
    """
    dof_coords = np.asarray(dof_coords, float).reshape(-1, 3)
    dof_comp, dof_role = np.asarray(dof_comp, np.int64), np.asarray(dof_role, np.int64)
    n = dof_comp.size
    dof_col = np.asarray(dof_col, np.int64)
    free = np.flatnonzero((dof_role == FREE) & (dof_col >= 0))
    rows, cols, vals = [free], [dof_col[free]], [np.ones(free.size)]
    for p in np.unique(dof_role[dof_role >= 0]):
        i = np.flatnonzero(dof_role == p)
        rb = dof_rb(dof_coords[i] - ref_coords[p], dof_comp[i])          # (len(i), 6)
        r, c = np.nonzero(rb)
        rows.append(i[r])
        cols.append(ref_first_dof + 6 * p + c)
        vals.append(rb[r, c])
    r, c, v = (np.concatenate(a) for a in (rows, cols, vals))
    return sp.csr_matrix((v, (r.astype(np.int64), c.astype(np.int64))), shape=(n, n_cols))
