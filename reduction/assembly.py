"""Assembly of Craig-Bampton components by overlaying common boundary DOFs (section 3.0).

Same label = same DOF. The system coordinate vector is the modal coordinates of each
component in turn, then the physical boundary DOFs in ``boundary_labels`` order.

A released DOF (``released``: (component, label) pairs) is not overlaid: that component
keeps it as a DOF of its own, labelled ``point@component:C`` at the same place, so no force
passes between the components in that direction (a pin flag, Nastran's CBAR PA/PB or a
joint's unconnected component).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from liftoff.core.errors import InputError
from liftoff.core.labels import COMPONENTS, split_label

from .craig_bampton import CBModel, validate_cb

COORD_TOL = 1e-6      # shared points must agree to 1e-6 x max(1 m, model size)


@dataclass
class Assembly:
    """Assembled CB components: dense M, K over [q_1, q_2, ..., x_b] (SI units)."""

    name: str
    components: tuple[CBModel, ...]
    boundary_labels: tuple[str, ...]
    M: np.ndarray
    K: np.ndarray
    modal_slices: dict
    boundary_index: dict
    points: tuple[str, ...]
    point_coords: np.ndarray
    released: frozenset = frozenset()     # (component, label) pairs kept apart (module docstring)
    #: (n_dof, 6), (6, 6) about the origin: the rigid-body inertia loads M RB and the rigid-body mass
    #: RB^T M RB of the components' own physical rigid-body field (reduction.system.rigid_inertia), where
    #: the boundary's geometric RB is not that field's image: a grounded component, clamped inside its
    #: interior, whose constraint modes do not carry its interior rigidly (None: the boundary's is)
    inertia: np.ndarray | None = None
    rigid_mass: np.ndarray | None = None

    def system_label(self, component: str, label: str) -> str:
        """The system label of ``component``'s boundary DOF ``label`` (its own where released)."""
        return _system_label(self.released, component, label)

    def released_apart(self, component: str, label: str) -> bool:
        """Whether a release leaves ``component``'s boundary DOF ``label`` joined to no other
        component (no force passes there between components; False where the label was never
        shared or is still shared)."""
        if not any(lab == label for _, lab in self.released):
            return False
        own = self.system_label(component, label)
        return not any(cb.name != component and label in cb.boundary_labels
                       and self.system_label(cb.name, label) == own for cb in self.components)

    @property
    def n_dof(self) -> int:
        return self.M.shape[0]

    @property
    def n_modal(self) -> int:
        return self.n_dof - len(self.boundary_labels)

    def component(self, name: str) -> CBModel:
        for cb in self.components:
            if cb.name == name:
                return cb
        raise InputError(f"no component {name!r} in assembly {self.name!r} "
                         f"(has {', '.join(c.name for c in self.components)})")

    def cb_index(self, name: str) -> np.ndarray:
        """System DOF index of each DOF [q; x_b] of component ``name``."""
        self.component(name)                      # InputError naming an unknown component
        s = self.modal_slices[name]
        return np.concatenate([np.arange(s.start, s.stop), self.n_modal + self.boundary_index[name]])

    def boundary_dof(self, label: str) -> int:
        try:
            return self.n_modal + self.boundary_labels.index(label)
        except ValueError:
            raise InputError(f"label {label!r} is not a boundary DOF of assembly {self.name!r}") from None

    def point_coord(self, point: str) -> np.ndarray:
        try:
            return self.point_coords[self.points.index(point)]
        except ValueError:
            raise InputError(f"unknown point {point!r} in assembly {self.name!r}") from None

    def scatter(self, name: str, cb_vector) -> np.ndarray:
        """A vector over component ``name``'s CB DOFs [q; x_b] (e.g. a generalised load)
        placed into a zero system vector."""
        v = np.asarray(cb_vector, dtype=float)
        out = np.zeros((self.n_dof,) + v.shape[1:])
        idx = self.cb_index(name)
        if v.shape[0] != idx.size:
            raise InputError(f"vector for component {name!r} has {v.shape[0]} rows, expected {idx.size}")
        out[idx] += v
        return out


def released_label(label: str, component: str) -> str:
    """The system label of ``component``'s own DOF ``label`` where it is released:
    ``'att:Tz'`` of ``'srb_left'`` -> ``'att@srb_left:Tz'``."""
    point, k = split_label(label)
    return f"{point}@{component}:{COMPONENTS[k]}"


def _system_label(released, component: str, label: str) -> str:
    return released_label(label, component) if (component, label) in released else label


def assemble(cb_models, name: str, released=()) -> Assembly:
    """Overlay the CB models' boundary DOFs by label, except the ``released`` (component,
    label) pairs, each its component's own DOF (module docstring). Shared points must have
    the same coordinates (InputError otherwise: mismatched units or wrong geometry)."""
    cbs = tuple(cb_models)
    if not cbs:
        raise InputError(f"assembly {name!r}: no components")
    released = set(released)
    for comp, lab in sorted(released):
        cb = next((c for c in cbs if c.name == comp), None)
        if cb is None or lab not in cb.boundary_labels:
            raise InputError(f"assembly {name!r}: cannot release {lab!r} of {comp!r}: "
                             + ("no such component" if cb is None else "not one of its boundary DOFs"))
    names = [cb.name for cb in cbs]
    for nm in names:
        if names.count(nm) > 1:
            raise InputError(f"assembly {name!r}: component name {nm!r} used twice")
    for cb in cbs:
        validate_cb(cb)
    # points: one coordinate per name, checked across components
    coords: dict[str, np.ndarray] = {}
    owner: dict[str, str] = {}
    all_xyz = np.vstack([cb.point_coords for cb in cbs if cb.point_coords.size] or [np.zeros((1, 3))])
    tol = COORD_TOL * max(1.0, float(np.max(np.ptp(all_xyz, axis=0))))
    for cb in cbs:
        for p, x in zip(cb.points, cb.point_coords):
            if p in coords:
                if np.linalg.norm(coords[p] - x) > tol:
                    raise InputError(
                        f"assembly {name!r}: point {p!r} is at {np.round(coords[p], 6).tolist()} m in "
                        f"{owner[p]!r} but at {np.round(x, 6).tolist()} m in {cb.name!r} "
                        "(mismatched units or geometry?)")
            else:
                coords[p], owner[p] = np.asarray(x, float), cb.name
    # boundary labels: union in order of first appearance (a released one under its own name);
    # a label may not be interior elsewhere
    boundary: list[str] = []
    for cb in cbs:
        for lab in cb.boundary_labels:
            lab = _system_label(released, cb.name, lab)
            if lab not in boundary:
                boundary.append(lab)
    for comp, lab in sorted(released):
        coords[split_label(released_label(lab, comp))[0]] = coords[split_label(lab)[0]]
    bset = set(boundary)
    for cb in cbs:
        interior = set(cb.dof_labels) - set(cb.boundary_labels)
        clash = sorted(interior & bset)
        if clash:
            other = next(c.name for c in cbs if clash[0] in c.boundary_labels)
            raise InputError(f"assembly {name!r}: {clash[0]!r} is a boundary DOF of {other!r} but an "
                             f"interior DOF of {cb.name!r}; make it a boundary DOF of both")
    n_modal = sum(cb.n_modes for cb in cbs)
    n = n_modal + len(boundary)
    M, K = np.zeros((n, n)), np.zeros((n, n))
    modal_slices, boundary_index = {}, {}
    pos = {lab: k for k, lab in enumerate(boundary)}
    start = 0
    for cb in cbs:
        modal_slices[cb.name] = slice(start, start + cb.n_modes)
        bidx = np.array([pos[_system_label(released, cb.name, lab)] for lab in cb.boundary_labels], dtype=np.int64)
        boundary_index[cb.name] = bidx
        idx = np.concatenate([np.arange(start, start + cb.n_modes), n_modal + bidx])
        M[np.ix_(idx, idx)] += cb.M
        K[np.ix_(idx, idx)] += cb.K
        start += cb.n_modes
    points = tuple(coords)
    return Assembly(name=name, components=cbs, boundary_labels=tuple(boundary), M=M, K=K,
                    modal_slices=modal_slices, boundary_index=boundary_index, points=points,
                    point_coords=np.array([coords[p] for p in points]).reshape(-1, 3), released=frozenset(released))


def label_transform(assembly: Assembly, labels) -> np.ndarray:
    """(len(labels) x n_sys_dof) map from system DOFs to physical labelled DOFs."""
    out = np.zeros((len(labels), assembly.n_dof))
    bpos = {lab: k for k, lab in enumerate(assembly.boundary_labels)}
    for r, lab in enumerate(labels):
        if lab in bpos:
            out[r, assembly.n_modal + bpos[lab]] = 1.0
            continue
        hits = [cb for cb in assembly.components if lab in cb.dof_labels]
        if not hits:
            raise InputError(f"label {lab!r} is not a labelled DOF of assembly {assembly.name!r}")
        if len(hits) > 1:
            raise InputError(f"label {lab!r} is an interior DOF of both {hits[0].name!r} and "
                             f"{hits[1].name!r}: ambiguous (make it a boundary DOF of both)")
        cb = hits[0]
        out[r, assembly.cb_index(cb.name)] = cb.label_transform[cb.dof_labels.index(lab)]
    return out
