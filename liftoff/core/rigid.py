"""Rigid-body kinematics: the geometric rigid-body shape RB and the mass properties of a
6x6 rigid-body mass (section 4.2, eq. 14 of Prabhakar & Palermo; pyyeti's ``cb.cgmass``).

A unit rigid motion of a reference point (translations t in m, small rotations theta in
rad) moves a point at offset d = p - ref by u = t + theta x d, i.e.

    u_x = t_x + theta_y d_z - theta_z d_y
    u_y = t_y + theta_z d_x - theta_x d_z
    u_z = t_z + theta_x d_y - theta_y d_x

and turns a rotation DOF by theta. Column j of RB is the motion of every DOF for a unit
motion j (Tx Ty Tz Rx Ry Rz) of the reference point. Everything here is numpy.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import InputError
from .labels import split_label

# u_c = t_c + a theta_j + b theta_k: the columns (c, j, k) of RB that a translation c uses
TRANSLATION_COLUMNS = np.array([[0, 4, 5], [1, 5, 3], [2, 3, 4]])


def skew(v) -> np.ndarray:
    """Cross-product matrix: ``skew(a) @ b == np.cross(a, b)``."""
    x, y, z = np.asarray(v, dtype=float)
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


def translation_coefficients(d: np.ndarray, comp: int) -> np.ndarray:
    """(n, 3) coefficients of translation ``comp`` (0..2) at offsets d (n, 3) on the RB
    columns ``TRANSLATION_COLUMNS[comp]``: (1, d_z, -d_y) for x, (1, d_x, -d_z) for y,
    (1, d_y, -d_x) for z."""
    d = np.asarray(d, dtype=float).reshape(-1, 3)
    one = np.ones(d.shape[0])
    a, b = {0: (2, 1), 1: (0, 2), 2: (1, 0)}[int(comp)]
    return np.column_stack([one, d[:, a], -d[:, b]])


def dof_rb(offsets: np.ndarray, comps: np.ndarray) -> np.ndarray:
    """RB (n, 6) of DOFs at offsets (n, 3) from the reference point with components
    ``comps`` (n,) in 0..5 (Tx..Rz)."""
    offsets = np.asarray(offsets, dtype=float).reshape(-1, 3)
    comps = np.asarray(comps, dtype=np.int64).reshape(-1)
    rb = np.zeros((comps.size, 6))
    for c in range(3):
        rows = np.flatnonzero(comps == c)
        rb[rows[:, None], TRANSLATION_COLUMNS[c]] = translation_coefficients(offsets[rows], c)
    rot = np.flatnonzero(comps >= 3)
    rb[rot, comps[rot]] = 1.0
    return rb


def point_rb(d) -> np.ndarray:
    """RB (6, 6) of the six DOFs of one point at offset d = p - ref."""
    return dof_rb(np.tile(np.asarray(d, float), (6, 1)), np.arange(6))


def nodal_rb(nodes: np.ndarray, ref_point=(0.0, 0.0, 0.0)) -> np.ndarray:
    """RB (3 n_nodes, 6) of nodal translations, x y z interleaved per node."""
    d = np.asarray(nodes, dtype=float).reshape(-1, 3) - np.asarray(ref_point, dtype=float)
    return dof_rb(np.repeat(d, 3, axis=0), np.tile(np.arange(3), d.shape[0]))


def rb_rows(labels, points, point_coords, ref_point=(0.0, 0.0, 0.0)) -> np.ndarray:
    """RB (len(labels), 6) of labelled DOFs ``point:comp`` about ``ref_point``; the points'
    coordinates are ``point_coords[points.index(point)]``."""
    index = {p: i for i, p in enumerate(points)}
    coords = np.asarray(point_coords, dtype=float).reshape(-1, 3)
    offsets, comps = np.zeros((len(labels), 3)), np.zeros(len(labels), dtype=np.int64)
    for row, lab in enumerate(labels):
        pt, comps[row] = split_label(lab)
        if pt not in index:
            raise InputError(f"DOF label {lab!r}: point {pt!r} has no coordinates")
        offsets[row] = coords[index[pt]]
    return dof_rb(offsets - np.asarray(ref_point, dtype=float).reshape(3), comps)


def shift_rb(d) -> np.ndarray:
    """T (6, 6) with RB about (ref + d) = (RB about ref) @ T: moving the reference point by d."""
    T = np.eye(6)
    T[:3, 3:] = skew(d)
    return T


@dataclass
class MassProperties:
    """Mass properties of a 6x6 rigid-body mass. SI: kg, m, kg m^2."""

    mass: float                 # kg (Tx entry of the 6x6)
    mass_xyz: np.ndarray        # (3,) the three translational diagonal entries (equal if consistent)
    cg: np.ndarray              # (3,) c.g. in the frame of the reference point, m
    cg_spread: float            # m: largest difference between the two readings of each c.g. coordinate
    inertia: np.ndarray         # (3, 3) inertia tensor about the c.g., kg m^2
    mass_cg: np.ndarray         # (6, 6) the rigid-body mass about the c.g.
    rigid_mass: np.ndarray      # (6, 6) the rigid-body mass about ref_point (symmetrised input)
    ref_point: np.ndarray       # (3,) m

    def as_dict(self) -> dict:
        """JSON-able form (lists of floats)."""
        return {"mass": self.mass, "mass_xyz": self.mass_xyz.tolist(), "cg": self.cg.tolist(),
                "cg_spread": self.cg_spread, "inertia_cg": self.inertia.tolist()}


def cg_mass(rb_mass: np.ndarray, ref_point=(0.0, 0.0, 0.0)) -> MassProperties:
    r"""Mass, c.g. and inertia about the c.g. from the 6x6 rigid-body mass RB^T M RB about
    ``ref_point`` (pyyeti ``cb.cgmass``). For a body of mass m_x = m_y = m_z = m whose c.g.
    lies at d = (d_x, d_y, d_z) from the reference point, with I the inertia tensor about
    the c.g. (I_xy = -int x y dm ...):

        [ m_x    0      0      0         m_x d_z  -m_x d_y ]
        [ 0      m_y    0     -m_y d_z   0         m_y d_x ]
        [ 0      0      m_z    m_z d_y  -m_z d_x   0       ]
        [ 0     -m_y d_z m_z d_y   I + m ([d]x^T [d]x)           ]
        [ m_x d_z 0    -m_z d_x                                  ]
        [-m_x d_y m_y d_x 0                                      ]

    so d_x = M[1, 5]/m_y, d_y = M[2, 3]/m_z, d_z = M[0, 4]/m_x (pyyeti's reading; the other
    reading, -M[2, 4]/m_z, -M[0, 5]/m_x, -M[1, 3]/m_y, gives ``cg_spread``), and the
    inertia about the c.g. is M[3:, 3:] - m [d]x^T [d]x (parallel axis theorem).
    A massless 6x6 gives mass 0 and NaN c.g. and inertia.
    """
    M = 0.5 * (np.asarray(rb_mass, dtype=float) + np.asarray(rb_mass, dtype=float).T)
    if M.shape != (6, 6):
        raise InputError(f"rigid-body mass has shape {M.shape}, expected (6, 6)")
    ref = np.asarray(ref_point, dtype=float).reshape(3)
    mxyz = np.diag(M)[:3].copy()
    mass = float(mxyz[0])
    if not mass > 0 or not np.all(mxyz > 0):
        nan = np.full(3, np.nan)
        return MassProperties(mass, mxyz, nan, np.nan, np.full((3, 3), np.nan), np.full((6, 6), np.nan), M, ref)
    d = np.array([M[1, 5] / mxyz[1], M[2, 3] / mxyz[2], M[0, 4] / mxyz[0]])
    other = np.array([-M[2, 4] / mxyz[2], -M[0, 5] / mxyz[0], -M[1, 3] / mxyz[1]])
    R = shift_rb(d)
    mass_cg = R.T @ M @ R
    return MassProperties(mass, mxyz, ref + d, float(np.max(np.abs(d - other))), mass_cg[3:, 3:].copy(), mass_cg,
                          M, ref)
