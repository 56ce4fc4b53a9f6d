"""Data-recovery matrices in system modal coordinates q (y = D q + V qdot + A qddot).

- displacement / acceleration at labelled DOFs (boundary DOFs of the assembly, or
  labelled interior DOFs of a component through its CB transformation);
- net c.g. acceleration of a component: the resultant of its inertia forces over its
  rigid-body mass, per direction (what its net c.g. load factor is made from);
- interface forces: the force the rest of the vehicle applies to a component at its
  boundary DOFs, F_b = [C_M^T M_B] [qdd_cb; xdd_b] + K_B x_b (eq. 13, lower rows), which
  is what the component carries there. It excludes loads applied to the component
  itself (subtract its ``boundary_load``) and damping;
- full-field nodal displacement of a component through its ``field_map``;
- a component's own recovery items (Nastran DTM/ATM/LTM, ``CBModel.recovery``) through
  the system modes, as transient ``Recovery`` rows.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from liftoff.core.errors import InputError
from liftoff.core.records import take_rows
from liftoff.core.rigid import rb_rows

from .assembly import Assembly, label_transform
from .component import Component
from .craig_bampton import RECOVERY_PARTS, CBRecovery
from .system import SystemModes


def displacement_recovery(sysm: SystemModes, labels) -> np.ndarray:
    """D (len(labels) x n_modes): displacement (m, rad) at labelled DOFs = D q."""
    return label_transform(sysm.assembly, tuple(labels)) @ sysm.phi


def acceleration_recovery(sysm: SystemModes, labels) -> np.ndarray:
    """A (len(labels) x n_modes): acceleration (m/s^2, rad/s^2) at labelled DOFs = A qddot."""
    return displacement_recovery(sysm, labels)


def interface_force_recovery(assembly: Assembly, sysm: SystemModes, component_name: str,
                             labels=None) -> tuple[np.ndarray, np.ndarray]:
    """(D, A): D q + A qddot (N, N m) is the component's boundary rows ``labels`` (default all
    of them) of M xddot + K x in its CB coordinates. The force the rest of the structure
    applies to ``component_name`` there is that less the loads applied to the component
    itself at those rows: Craig-Bampton lumps part of its distributed loads on its boundary
    DOFs, under gravity g its weight share A Phi^T M RB g (eq. 14), which the caller takes
    out (workflows.loads.recoveries: ``Recovery.const``)."""
    cb = assembly.component(component_name)
    labels = cb.boundary_labels if labels is None else tuple(labels)
    rows = []
    for lab in labels:
        if lab not in cb.boundary_labels:
            raise InputError(f"label {lab!r} is not a boundary DOF of component {cb.name!r}")
        rows.append(cb.n_modes + cb.boundary_labels.index(lab))
    T = sysm.phi[assembly.cb_index(cb.name)]           # [q_cb; x_b] = T q
    return cb.K[rows] @ T, cb.M[rows] @ T


def cg_acceleration_recovery(assembly: Assembly, sysm: SystemModes, component_name: str) -> tuple[np.ndarray, np.ndarray]:
    """(A (3 x n_modes), mass (3,) kg): the net acceleration of ``component_name``'s c.g. (m/s^2,
    x y z) = A qddot, the resultant of the component's inertia forces R^T M_CB qddot_cb (eq.
    13: M_CB in its CB coordinates [q_cb; x_b], R the rigid translation there: the boundary
    DOFs translating rigidly, q_cb = 0, which the constraint modes carry exactly) over its
    rigid-body mass in that direction, diag(R^T M_CB R). On a rigid component it is the c.g.
    acceleration; by Newton it is the net force on the component (interfaces, applied loads,
    gravity) over its mass. With a hydroelastic liquid the mass per direction is what moves
    with the tank in that direction (the liquid's impulsive part laterally, all of it axially)."""
    cb = assembly.component(component_name)
    rb = rb_rows(cb.boundary_labels, cb.points, cb.point_coords, np.zeros(3))[:, :3]
    R = np.zeros((cb.n_modes + len(cb.boundary_labels), 3))
    R[cb.n_modes:] = rb
    mass = np.einsum("ij,ij->j", R, cb.M @ R)
    if not np.all(mass > 0):
        raise InputError(f"component {cb.name!r}: rigid-body mass {mass.tolist()} kg (x, y, z) is not positive; "
                         "no c.g. acceleration")
    T = sysm.phi[assembly.cb_index(cb.name)]           # [q_cb; x_b] = T q
    return (R.T @ (cb.M @ T)) / mass[:, None], mass


def _field_rows(assembly: Assembly, sysm: SystemModes, component_name: str, component: Component):
    """(CB model, T): the component's CB model and its rows of the system modes, [q_cb; x_b] = T q."""
    cb = assembly.component(component_name)
    if component.field_map is None:
        raise InputError(f"component {component.name!r} has no field_map: no full-field recovery")
    if component.n_dof != cb.n_dof:
        raise InputError(f"component {component.name!r} has {component.n_dof} DOFs but CB model "
                         f"{cb.name!r} was reduced from {cb.n_dof}")
    cb._need_recovery("field_recovery")
    return cb, sysm.phi[assembly.cb_index(cb.name)]


def _nodal(component: Component, cb, X: np.ndarray, nodes: np.ndarray | None = None) -> np.ndarray:
    """Nodal displacements of CB coordinates X = [q_cb; x_b] (a vector or columns): the
    fixed-interface and constraint modes (eq. 13) through the component's field_map; with
    ``nodes``, of those nodes only, from the rows of the modes they need (the modes' other
    rows, most of a large component's mapped model, are not read)."""
    if nodes is None:
        physical = cb.fixed_interface_modes @ X[: cb.n_modes] + cb.constraint_modes @ X[cb.n_modes:]
        return np.asarray(component.field_map @ physical)
    rows = (3 * np.asarray(nodes, np.int64)[:, None] + np.arange(3)).ravel()
    F = component.field_map[rows]
    dofs = np.unique(F.indices)
    F = sp.csr_matrix((F.data, np.searchsorted(dofs, F.indices), F.indptr), shape=(rows.size, dofs.size))
    physical = (take_rows(cb.fixed_interface_modes, dofs) @ X[: cb.n_modes]
                + take_rows(cb.constraint_modes, dofs) @ X[cb.n_modes:])
    return np.asarray(F @ physical)


def field_recovery(assembly: Assembly, sysm: SystemModes, component_name: str,
                   component: Component) -> np.ndarray:
    """(3 n_nodes x n_modes): nodal displacement (m) of ``component`` (the FE component that
    was reduced) per unit system modal coordinate, through its field_map. For the
    displacements of given modal coordinates, :func:`field_displacement` is far cheaper."""
    cb, T = _field_rows(assembly, sysm, component_name, component)
    return _nodal(component, cb, T)


def field_displacement(assembly: Assembly, sysm: SystemModes, component_name: str, component: Component,
                       q: np.ndarray, nodes: np.ndarray | None = None) -> np.ndarray:
    """Nodal displacement (m, 3 n_nodes; or 3 n_nodes x k for k columns of ``q``) of
    ``component`` for the system modal coordinates ``q``: field_recovery(...) @ q, with T q
    formed first, so that the component's modes multiply a vector, not the system's modes.
    ``nodes``: those nodes' displacements only (3 len(nodes) rows, in their order)."""
    cb, T = _field_rows(assembly, sysm, component_name, component)
    return _nodal(component, cb, T @ np.asarray(q, float), nodes)


def component_recovery(assembly: Assembly, sysm: SystemModes, component_name: str, names=None) -> list:
    """The recovery items of component ``component_name`` (``CBModel.recovery``, over its CB
    DOFs [q; x_b]) in system modal coordinates, as :class:`CBRecovery` items named
    ``<component>_<item>``: with [q_cb; x_b] = T q (T the component's rows of the system
    modes), each part is ``item.part @ T``. ``names`` picks items (default all). The
    workflow turns them into the transient's Recovery rows (name, labels, units, disp, vel, acc)."""
    cb = assembly.component(component_name)
    items = cb.recovery if names is None else tuple(cb.recovery_item(nm) for nm in names)
    T = sysm.phi[assembly.cb_index(cb.name)]
    return [CBRecovery(f"{cb.name}_{it.name}", it.labels, it.units,
                       **{k: getattr(it, k) @ T for k in RECOVERY_PARTS if getattr(it, k) is not None})
            for it in items]
