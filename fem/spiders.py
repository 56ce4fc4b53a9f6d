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

from liftoff.core.errors import InputError
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


def interpolation_fit(node_xyz: np.ndarray, ref: np.ndarray, what: str) -> np.ndarray:
    """G (6 x 3n): the motion (Tx..Rz) of reference point ``ref`` as the least-squares rigid
    fit of the translations (x, y, z interleaved) of n nodes, unit weights: Nastran's RBE3
    (REFC = 123456, C_i = 123). With A (3n x 6) the rigid-body rows of the node translations
    about ``ref`` (liftoff.core.rigid), G = (A^T A)^-1 A^T; a force F at ``ref`` goes to the
    nodes as G^T F, statically equivalent, and a rigid motion of the nodes moves ``ref``
    rigidly with them. InputError if the nodes do not fix a rigid motion (fewer than three,
    or collinear)."""
    xyz = np.asarray(node_xyz, float).reshape(-1, 3)
    n = xyz.shape[0]
    A = dof_rb(np.repeat(xyz - np.asarray(ref, float), 3, axis=0), np.tile(np.arange(3), n))
    AtA = A.T @ A
    w = np.linalg.eigvalsh(AtA)
    if n < 3 or w[0] <= 1e-10 * w[-1]:
        raise InputError(f"{what}: its {n} nodes do not fix a rigid motion (need >= 3, not collinear)")
    return np.linalg.solve(AtA, A.T)


def eliminate_interpolations(fits: list[np.ndarray], ring_dofs: list[np.ndarray], what: str):
    """Choose the dependent DOFs of a set of interpolation constraints and write them in
    terms of the independent ones (Nastran's m-set, solved jointly so that constraints
    sharing nodes need no ordering).

    Constraint k reads u_ref_k = fits[k] @ u[ring_dofs[k]] (ring_dofs[k]: candidate DOF
    ids, 3 per node). Stacked, C u_ring = u_ref; 6K columns of C picked by QR with column
    pivoting (well conditioned) become the dependent set m: u_m = C_m^-1 (u_ref - C_n u_n).
    Returns (m DOF ids, n DOF ids, Dr = C_m^-1 (len(m) x 6K), Dn = -C_m^-1 C_n)."""
    from scipy.linalg import qr

    ids = np.unique(np.concatenate(ring_dofs))
    k6 = 6 * len(fits)
    if ids.size < k6:
        raise InputError(f"{what}: {ids.size // 3} nodes in all cannot carry {len(fits)} interpolations "
                         f"(each needs 6 node DOFs of its own; {k6 // 3} nodes at least)")
    C = np.zeros((k6, ids.size))
    for k, (G, d) in enumerate(zip(fits, ring_dofs)):
        C[6 * k: 6 * k + 6, np.searchsorted(ids, d)] += G
    _, R, piv = qr(C, mode="economic", pivoting=True)
    if abs(R[k6 - 1, k6 - 1]) <= 1e-10 * abs(R[0, 0]):
        raise InputError(f"{what}: the interpolation constraints are dependent (two reference "
                         "points on the same nodes with the same fit?)")
    m, n = np.sort(piv[:k6]), np.sort(piv[k6:])
    Cm_inv = np.linalg.inv(C[:, m])
    return ids[m], ids[n], Cm_inv, -Cm_inv @ C[:, n]
