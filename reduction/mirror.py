"""Mirror-image components: a component that is the reflection of another in a coordinate
plane through the origin (a strap-on booster of a symmetric pair), its FE matrices and
Craig-Bampton model derived from the other's instead of being meshed and reduced again
(Nastran's mirrored superelements do the same; issue 28: the default's two boosters are
such a pair).

Reflection R = I - 2 e e^T (e the plane's normal axis). A displacement u becomes R u (its
e component changes sign), a small rotation, a pseudovector, det(R) R theta = -R theta (its
two other components change sign). The mirror's labelled DOFs (``point:Tx`` ...) are those
of the global frame, so each takes the sign ``t`` of its component; its other DOFs are kept
as the source's own variables (nothing outside the component reads them: a change of
variables y = T x, T = diag(t) on the labelled DOFs and 1 elsewhere, is exact), so

    K' = T K T,   M' = T M T,   field_map' = R_nodes field_map T,

and the Craig-Bampton model of K', M' is the source's with [q; x_b] -> [q; t_b x_b]: the
same fixed-interface modes and frequencies (their shapes T Phi), constraint modes T Psi T_b.
Point coordinates and mesh nodes are reflected, point and volume names renamed (the
source's component name replaced by the mirror's: ``att_srb_left_fwd`` ->
``att_srb_right_fwd``), cells reordered so that they keep a positive orientation.
numpy/scipy only.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import scipy.sparse as sp

from liftoff.core.errors import InputError
from liftoff.core.labels import split_label

from .component import Component
from .craig_bampton import CBModel, CBRecovery

AXES = ("x", "y", "z")
#: node orders that keep a reflected cell's orientation positive (vertices 1 and 2 swapped,
#: and the edge nodes with them; meshio's orders)
REORIENT = {"tetra": [0, 2, 1, 3], "tetra10": [0, 2, 1, 3, 6, 5, 4, 7, 9, 8],
            "triangle": [0, 2, 1], "triangle6": [0, 2, 1, 5, 4, 3]}


def axis_index(normal: str) -> int:
    """0, 1 or 2 for the plane's normal ``"x"``, ``"y"`` or ``"z"``."""
    if normal not in AXES:
        raise InputError(f"mirror normal {normal!r}: give one of {', '.join(AXES)} (the plane through the origin "
                         "normal to that axis)")
    return AXES.index(normal)


def label_signs(labels, axis: int) -> np.ndarray:
    """Sign of each DOF label under the reflection: a translation along ``axis`` and a
    rotation about the two other axes change sign."""
    out = np.empty(len(labels))
    for i, lab in enumerate(labels):
        _, c = split_label(lab)
        out[i] = (-1.0 if c == axis else 1.0) if c < 3 else (1.0 if c - 3 == axis else -1.0)
    return out


def renamer(source: str, name: str):
    """The name map of a mirror: ``source`` replaced by ``name`` in a point or volume name."""
    return lambda s: str(s).replace(source, name)


def _rename_label(rename, label: str) -> str:
    point, comp = label.rsplit(":", 1)
    return f"{rename(point)}:{comp}"


def _reflect(coords: np.ndarray, axis: int) -> np.ndarray:
    out = np.array(coords, dtype=float, copy=True)
    out[..., axis] *= -1.0
    return out


def mirror_component(comp: Component, name: str, normal: str, rename=None) -> Component:
    """Component ``comp`` reflected in the plane normal to ``normal`` through the origin
    (module docstring), named ``name``, its points renamed by ``rename`` (default: the
    source's name replaced by ``name``). A hydroelastic liquid or slosh pendulums are
    refused (their own geometry is not reflected here)."""
    if comp.liquid is not None or comp.slosh is not None:
        raise InputError(f"component {name!r}: a mirror of {comp.name!r}, which carries a hydroelastic liquid or slosh "
                         "pendulums; build it from its own geometry instead")
    axis = axis_index(normal)
    rename = rename or renamer(comp.name, name)
    t = np.ones(comp.n_dof)
    t[comp.label_dofs] = label_signs(comp.dof_labels, axis)
    T = sp.diags(t)
    field_map = None
    if comp.field_map is not None:
        rows = np.ones(comp.field_map.shape[0])
        rows[axis::3] = -1.0
        field_map = sp.csr_matrix(sp.diags(rows) @ comp.field_map @ T)
    cells = comp.cells
    if cells is not None and comp.cell_type in REORIENT and cells.shape[1] == len(REORIENT[comp.cell_type]):
        cells = np.ascontiguousarray(np.asarray(cells)[:, REORIENT[comp.cell_type]])
    return Component(
        name=name, K=sp.csr_matrix(T @ comp.K @ T), M=sp.csr_matrix(T @ comp.M @ T),
        dof_labels=tuple(_rename_label(rename, lab) for lab in comp.dof_labels), label_dofs=comp.label_dofs,
        points=tuple(rename(p) for p in comp.points), point_coords=_reflect(comp.point_coords, axis),
        nodes=None if comp.nodes is None else _reflect(comp.nodes, axis), cells=cells, cell_type=comp.cell_type,
        field_map=field_map, line_cells=comp.line_cells, values_checked=comp.values_checked)


def mirror_load(comp: Component, f: np.ndarray, normal: str) -> np.ndarray:
    """A load over ``comp``'s DOFs (a unit thermal load) as it acts on the mirror's DOFs."""
    t = np.ones(comp.n_dof)
    t[comp.label_dofs] = label_signs(comp.dof_labels, axis_index(normal))
    return t * np.asarray(f, dtype=float)


def mirror_cb(cb: CBModel, name: str, normal: str, rename=None, source_component: Component | None = None) -> CBModel:
    """The Craig-Bampton model of the mirror (module docstring) from the source's ``cb``,
    without an eigensolve: boundary DOFs renamed and signed, the modal coordinates kept.
    ``source_component``: the source's Component, needed to sign the rows of the
    fixed-interface and constraint modes (the labelled DOFs among all its DOFs) when ``cb``
    keeps them."""
    axis = axis_index(normal)
    rename = rename or renamer(cb.name, name)
    tb = label_signs(cb.boundary_labels, axis)
    tc = np.concatenate([np.ones(cb.n_modes), tb])            # [q; x_b] -> [q; t_b x_b]
    tl = label_signs(cb.dof_labels, axis)
    fim, cm = cb.fixed_interface_modes, cb.constraint_modes
    if fim is not None or cm is not None:
        if source_component is None or source_component.n_dof != cb.n_dof:
            raise InputError(f"mirror of CB model {cb.name!r}: its mode shapes need the source component's DOFs")
        t = np.ones(cb.n_dof)
        t[source_component.label_dofs] = label_signs(source_component.dof_labels, axis)
        fim = None if fim is None else t[:, None] * fim
        cm = None if cm is None else t[:, None] * cm * tb[None, :]
    rec = tuple(CBRecovery(it.name, it.labels, it.units, **{k: m * tc[None, :] for k, m in it.parts.items()})
                for it in cb.recovery)
    return replace(cb, name=name, boundary_labels=tuple(_rename_label(rename, lab) for lab in cb.boundary_labels),
                   M=tc[:, None] * cb.M * tc[None, :], K=tc[:, None] * cb.K * tc[None, :],
                   points=tuple(rename(p) for p in cb.points), point_coords=_reflect(cb.point_coords, axis),
                   dof_labels=tuple(_rename_label(rename, lab) for lab in cb.dof_labels),
                   label_transform=tl[:, None] * cb.label_transform * tc[None, :],
                   constraint_modes=cm, fixed_interface_modes=fim, recovery=rec, timings={})
