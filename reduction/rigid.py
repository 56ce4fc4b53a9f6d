"""Geometric rigid-body shapes and mass properties (used by eq. 14 and by the CB checks).

RB (n_dof x 6) maps a rigid motion of the reference point (3 translations, m; 3 small
rotations, rad) to the labelled DOFs: a translation DOF of a point at p moves by
t + theta x (p - ref), a rotation DOF by theta.
"""
from __future__ import annotations

import numpy as np

from liftoff.transient.body import split_label
from liftoff.transient.errors import InputError


def rb_rows(labels, points, point_coords, ref_point=(0.0, 0.0, 0.0)) -> np.ndarray:
    """Geometric rigid-body shape (len(labels) x 6) of labelled DOFs about ``ref_point``."""
    index = {p: i for i, p in enumerate(points)}
    coords = np.asarray(point_coords, dtype=float).reshape(-1, 3)
    ref = np.asarray(ref_point, dtype=float).reshape(3)
    rb = np.zeros((len(labels), 6))
    for row, lab in enumerate(labels):
        pt, comp = split_label(lab)
        if pt not in index:
            raise InputError(f"DOF label {lab!r}: point {pt!r} has no coordinates")
        rb[row] = point_rb(coords[index[pt]] - ref)[comp]
    return rb


def point_rb(d: np.ndarray) -> np.ndarray:
    """6 x 6 rigid-body shape of one 6-DOF point at offset d = p - ref."""
    dx, dy, dz = d
    rb = np.eye(6)
    # translation = t + theta x d
    rb[0, 4], rb[0, 5] = dz, -dy
    rb[1, 3], rb[1, 5] = -dz, dx
    rb[2, 3], rb[2, 4] = dy, -dx
    return rb


def nodal_rb(nodes: np.ndarray, ref_point=(0.0, 0.0, 0.0)) -> np.ndarray:
    """Rigid-body shape (3 n_nodes x 6) of nodal translations, x y z interleaved per node."""
    d = np.asarray(nodes, dtype=float).reshape(-1, 3) - np.asarray(ref_point, dtype=float)
    n = d.shape[0]
    rb = np.zeros((n, 3, 6))
    rb[:, 0, 0] = rb[:, 1, 1] = rb[:, 2, 2] = 1.0
    rb[:, 0, 4], rb[:, 0, 5] = d[:, 2], -d[:, 1]
    rb[:, 1, 3], rb[:, 1, 5] = -d[:, 2], d[:, 0]
    rb[:, 2, 3], rb[:, 2, 4] = d[:, 1], -d[:, 0]
    return rb.reshape(3 * n, 6)


def mass_properties(rb_mass: np.ndarray, ref_point=(0.0, 0.0, 0.0)) -> dict:
    """Mass (kg), c.g. (m) and inertia about the c.g. (kg m^2) from a 6 x 6 rigid-body mass
    RB^T M RB taken about ``ref_point``. The c.g. is averaged over the three translational
    directions (they agree for a consistent model; their spread is returned too)."""
    m6 = 0.5 * (rb_mass + rb_mass.T)
    ref = np.asarray(ref_point, dtype=float)
    masses = np.diag(m6)[:3]
    mass = float(np.mean(masses))
    if mass <= 0:
        return {"mass": mass, "mass_xyz": masses.tolist(), "cg": [np.nan] * 3, "cg_spread": np.nan,
                "inertia_cg": np.full((3, 3), np.nan).tolist()}
    # coupling block m6[0:3, 3:6] = -m [r]x for a c.g. at offset r: read each offset
    # component from the two translations where it appears.
    c = m6[:3, 3:]
    est = np.array([[c[1, 2] / masses[1], -c[2, 1] / masses[2]],   # x from Ty-Rz, Tz-Ry
                    [-c[0, 2] / masses[0], c[2, 0] / masses[2]],   # y from Tx-Rz, Tz-Rx
                    [c[0, 1] / masses[0], -c[1, 0] / masses[1]]])  # z from Tx-Ry, Ty-Rx
    r = est.mean(axis=1)
    rx = np.array([[0, -r[2], r[1]], [r[2], 0, -r[0]], [-r[1], r[0], 0]])
    inertia_cg = m6[3:, 3:] + mass * rx @ rx     # parallel axis: I_ref = I_cg - m [r]x^2
    return {"mass": mass, "mass_xyz": masses.tolist(), "cg": (ref + r).tolist(),
            "cg_spread": float(np.max(np.ptp(est, axis=1))), "inertia_cg": inertia_cg.tolist()}
