"""Turn a problem description into the small dense arrays the kernel marches on.

Contact rows: one row per coupled direction (``contact/label_a``), with the mode-shape
rows Phi_ca, Phi_cb (zero row for ground), the compliance 1/K_C (0 for a rigid bolt)
and the offset c (normal_sign * gap on the axial row), so that while coupled the force
on A is f = -K_C (c + x_a - x_b) (eq. 3).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from liftoff.core.errors import InputError
from liftoff.core.labels import COMPONENTS, split_label

from .body import ModalBody
from .model import Forcing
from .result import ContactDirection


@dataclass
class ContactRows:
    directions: tuple      # (n_c,) ContactDirection: what each row is
    names: tuple           # (n_contacts,) contact names
    Phi_a: np.ndarray      # (n_c, n_a)
    Phi_b: np.ndarray      # (n_c, n_b)
    compliance: np.ndarray  # (n_c,) 1/K_C, 0 for rigid
    offset: np.ndarray     # (n_c,) c
    contact: np.ndarray    # (n_c,) index of the contact point
    axial: np.ndarray      # (n_c,) bool
    sign: np.ndarray       # (n_c,) normal_sign of the contact
    release: np.ndarray    # (n_contacts,)
    axial_column: np.ndarray  # (n_contacts,)
    normal_sign: np.ndarray   # (n_contacts,)

    @property
    def n(self) -> int:
        return self.compliance.size

    @property
    def labels(self) -> tuple:
        """``contact/label_a`` per row."""
        return tuple(d.label for d in self.directions)


def contact_rows(body_a: ModalBody, body_b: ModalBody, contacts) -> ContactRows:
    """One row per coupled direction of every contact point, in contact order."""
    na, nb = body_a.n_modes, body_b.n_modes
    dirs, Pa, Pb, comp, off, cidx, ax, sgn, axcol = [], [], [], [], [], [], [], [], []
    for ci, c in enumerate(contacts):
        for d, (la, lb) in enumerate(zip(c.labels_a, c.labels_b)):
            if d == c.axial:
                axcol.append(len(dirs))
            dirs.append(ContactDirection(c.name, ci, la, lb, COMPONENTS[split_label(la)[1]], d == c.axial,
                                         c.normal_sign))
            Pa.append(body_a.phi[body_a.dof_index(la)])
            Pb.append(np.zeros(nb) if lb is None else body_b.phi[body_b.dof_index(lb)])
            comp.append(0.0 if c.rigid else 1.0 / c.stiffness[d])
            off.append(c.normal_sign * c.gap if d == c.axial else 0.0)
            cidx.append(ci)
            ax.append(d == c.axial)
            sgn.append(c.normal_sign)
    n = len(dirs)
    return ContactRows(directions=tuple(dirs), names=tuple(c.name for c in contacts),
                       Phi_a=np.array(Pa).reshape(n, na), Phi_b=np.array(Pb).reshape(n, nb),
                       compliance=np.array(comp), offset=np.array(off), contact=np.array(cidx, dtype=np.int64),
                       axial=np.array(ax, dtype=np.bool_), sign=np.array(sgn),
                       release=np.array([c.release_time for c in contacts]),
                       axial_column=np.array(axcol, dtype=np.int64),
                       normal_sign=np.array([c.normal_sign for c in contacts]))


@dataclass
class ModalLoad:
    """Modal force of one body: const + piecewise-linear table on a merged time grid."""

    const: np.ndarray   # (n,)
    times: np.ndarray   # (n_k,)
    table: np.ndarray   # (n_k, n)

    def at(self, t: float) -> np.ndarray:
        if self.times.size == 0:
            return self.const.copy()
        return self.const + np.array([np.interp(t, self.times, self.table[:, m]) for m in range(self.const.size)])


def modal_load(body: ModalBody, key: str, forcing: Forcing) -> ModalLoad:
    """Constant point forces + gravity (eq. 14) + tabulated point and modal forces, in modal form."""
    n = body.n_modes
    const = np.zeros(n)
    if n == 0:
        return ModalLoad(const, np.zeros(0), np.zeros((0, 0)))
    const += body.modal_gravity(forcing.gravity)
    for p in forcing.constant:
        if p.body == key:
            const += body.phi[body.dof_index(p.label)] * p.value
    tables = [t for t in forcing.tables if t.body == key]
    modal = [m for m in forcing.modal if m.body == key]
    if not tables and not modal:
        return ModalLoad(const, np.zeros(0), np.zeros((0, n)))
    grid = np.unique(np.concatenate([t.time for t in tables] + [m.time for m in modal]))
    if grid.size * n > 5e8:
        raise InputError(f"body {body.name!r}: merged force tables need {grid.size} x {n} values; "
                         "resample the tables on a common, coarser grid")
    table = np.zeros((grid.size, n))
    for t in tables:  # exact: every table is linear between its own breakpoints, a subset of grid
        table += np.outer(np.interp(grid, t.time, t.value), body.phi[body.dof_index(t.label)])
    for m in modal:
        for k in range(n):
            table[:, k] += np.interp(grid, m.time, m.values[:, k])
    return ModalLoad(const, grid, table)


def feedback_factors(n: int, key: str, forcing: Forcing, t0: float):
    """Feedback matrices of a body as rank-factored terms: (U (n, r), V (r, n), until (r,)).

    A feedback given with its ``factors`` is used as it is (O(n r)); any other matrix is
    factored by SVD (singular values below 1e-14 of the largest dropped: exact to rounding),
    so force = sum_k U[:, k] (V[k] . q) over the terms with t < until[k]."""
    Us, Vs, untils = [np.zeros((n, 0))], [np.zeros((0, n))], [np.zeros(0)]
    for fb in forcing.feedback:
        if fb.body != key or n == 0:
            continue
        if fb.factors is not None:
            U, V = fb.factors
            Us.append(U)
            Vs.append(V)
            untils.append(np.full(U.shape[1], fb.until))
            continue
        U, s, Vt = np.linalg.svd(fb.matrix)
        r = int(np.sum(s > 1e-14 * max(s[0], 1e-300))) if s.size else 0
        Us.append(U[:, :r] * s[:r])
        Vs.append(Vt[:r])
        untils.append(np.full(r, fb.until))
    return np.hstack(Us), np.vstack(Vs), np.concatenate(untils)


def feedback_at(n: int, key: str, forcing: Forcing, t: float):
    """(U, V) of the feedback terms of a body active at time t (t < until): force U (V q)."""
    U, V, until = feedback_factors(n, key, forcing, t)
    on = t < until
    return U[:, on], V[on]


def feedback_matrix(n: int, key: str, forcing: Forcing, t: float) -> np.ndarray:
    """Sum of the feedback matrices active at time t (for static equilibrium)."""
    M = np.zeros((n, n))
    for fb in forcing.feedback:
        if fb.body == key and t < fb.until:
            M += fb.matrix
    return M
