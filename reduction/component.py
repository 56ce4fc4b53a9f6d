"""FE component matrices: what a finite-element model (this project's fem/, or a user's
Nastran/other export) hands to the Craig-Bampton reducer, and its file format.

A component is a sparse stiffness K and mass M (n x n, SI: N/m, N, N m/rad ...; kg, kg m,
kg m^2) over its physical DOFs, of which some are *labelled* (``point:Tx`` ...), usually
the 6 DOFs of rigid-spider reference points (interfaces, hold-down points, engine
mounts, recovery stations). Labelled points carry coordinates, so that the geometric
rigid-body shape RB of any DOF set can be built. Optionally the component carries its
mesh and a sparse ``field_map`` (3 n_nodes x n) from its DOF vector to nodal
displacements (x, y, z interleaved per node), for full-field recovery and pictures.

File format (``.npz``, no pickle, SI units):

==================  ===============  ================================================
name                shape / type     meaning (unit)
==================  ===============  ================================================
format              str              "liftoff-component"
version             int              1
name                str              component name
units               str              "SI"
K_data/indices/     CSR arrays       stiffness (N/m, N/rad, N m/rad)
  indptr/shape
M_data/...          CSR arrays       mass (kg, kg m, kg m^2)
dof_labels          (n_l,) str       labels of the labelled DOFs
label_dofs          (n_l,) int       their indices into K and M
points              (n_p,) str       names of labelled points
point_coords        (n_p, 3)         their coordinates (m)
nodes               (n_nodes, 3)     mesh node coordinates (m)            [optional]
cells               (n_cells, k)     cell connectivity into nodes         [optional]
cell_type           str              meshio cell type, e.g. "tetra"       [optional]
field_map_*         CSR arrays       (3 n_nodes, n) DOF vector -> nodal u [optional]
==================  ===============  ================================================
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from liftoff.transient.atomic import atomic_path
from liftoff.transient.body import split_label
from liftoff.transient.errors import InputError

FORMAT = "liftoff-component"
VERSION = 1


@dataclass
class Component:
    """Sparse FE matrices of one component with labelled DOFs and point coordinates."""

    name: str
    K: sp.csr_matrix
    M: sp.csr_matrix
    dof_labels: tuple[str, ...]
    label_dofs: np.ndarray
    points: tuple[str, ...] = ()
    point_coords: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    nodes: np.ndarray | None = None
    cells: np.ndarray | None = None
    cell_type: str = ""
    field_map: sp.csr_matrix | None = None

    def __post_init__(self) -> None:
        self.K = sp.csr_matrix(self.K, dtype=float)
        self.M = sp.csr_matrix(self.M, dtype=float)
        self.dof_labels = tuple(str(s) for s in self.dof_labels)
        self.label_dofs = np.asarray(self.label_dofs, dtype=np.int64).reshape(-1)
        self.points = tuple(str(s) for s in self.points)
        self.point_coords = np.asarray(self.point_coords, dtype=float).reshape(-1, 3)
        if self.field_map is not None:
            self.field_map = sp.csr_matrix(self.field_map, dtype=float)
        self.validate()

    @property
    def n_dof(self) -> int:
        return self.K.shape[0]

    def validate(self) -> None:
        who = f"component {self.name!r}"
        n = self.K.shape[0]
        if self.K.shape != (n, n) or self.M.shape != (n, n):
            raise InputError(f"{who}: K {self.K.shape} and M {self.M.shape} must be square and equal")
        for nm in ("K", "M"):
            if not np.all(np.isfinite(getattr(self, nm).data)):
                raise InputError(f"{who}: {nm} contains NaN or inf")
        if len(self.dof_labels) != self.label_dofs.size:
            raise InputError(f"{who}: {len(self.dof_labels)} dof_labels but {self.label_dofs.size} label_dofs")
        if self.label_dofs.size and (self.label_dofs.min() < 0 or self.label_dofs.max() >= n):
            raise InputError(f"{who}: label_dofs out of range 0..{n - 1}")
        if len(set(self.dof_labels)) != len(self.dof_labels):
            raise InputError(f"{who}: duplicate DOF labels")
        for lab in self.dof_labels:
            pt, _ = split_label(lab)
            if pt not in self.points:
                raise InputError(f"{who}: DOF label {lab!r} names a point without coordinates")
        if len(self.points) != self.point_coords.shape[0]:
            raise InputError(f"{who}: {len(self.points)} points but {self.point_coords.shape[0]} coordinates")
        if self.field_map is not None and self.field_map.shape[1] != n:
            raise InputError(f"{who}: field_map has {self.field_map.shape[1]} columns, expected {n}")

    def dofs_of(self, labels) -> np.ndarray:
        """Indices into K of the given DOF labels; InputError naming the first unknown label."""
        index = {lab: i for lab, i in zip(self.dof_labels, self.label_dofs)}
        out = []
        for lab in labels:
            split_label(lab)
            if lab not in index:
                raise InputError(f"boundary label {lab!r} is not in component {self.name!r}")
            out.append(index[lab])
        return np.asarray(out, dtype=np.int64)

    def point_coord(self, point: str) -> np.ndarray:
        try:
            return self.point_coords[self.points.index(point)]
        except ValueError:
            raise InputError(f"unknown point {point!r} in component {self.name!r}") from None

    def save(self, path) -> Path:
        return save_component(self, path)


def _csr_record(prefix: str, A: sp.csr_matrix) -> dict:
    return {f"{prefix}_data": A.data, f"{prefix}_indices": A.indices,
            f"{prefix}_indptr": A.indptr, f"{prefix}_shape": np.array(A.shape)}


def _csr_from(prefix: str, z) -> sp.csr_matrix:
    return sp.csr_matrix((z[f"{prefix}_data"], z[f"{prefix}_indices"], z[f"{prefix}_indptr"]),
                         shape=tuple(z[f"{prefix}_shape"]))


def save_component(c: Component, path) -> Path:
    """Write atomically as .npz (temporary file + rename)."""
    path = Path(path)
    if path.suffix != ".npz":
        raise InputError(f"component file {str(path)!r}: use the .npz extension")
    rec = {"format": np.array(FORMAT), "version": np.array(VERSION), "name": np.array(c.name),
           "units": np.array("SI"), "dof_labels": np.array(c.dof_labels, dtype="U"),
           "label_dofs": c.label_dofs, "points": np.array(c.points, dtype="U"),
           "point_coords": c.point_coords, **_csr_record("K", c.K), **_csr_record("M", c.M)}
    if c.nodes is not None:
        rec["nodes"] = np.asarray(c.nodes, float)
    if c.cells is not None:
        rec["cells"] = np.asarray(c.cells, np.int64)
        rec["cell_type"] = np.array(c.cell_type)
    if c.field_map is not None:
        rec.update(_csr_record("field_map", c.field_map))
    with atomic_path(path) as tmp, open(tmp, "wb") as fh:
        np.savez(fh, **rec)
    return path


def load_component(path) -> Component:
    path = Path(path)
    if not path.is_file():
        raise InputError(f"component file not found: {str(path)!r}")
    try:
        with np.load(path, allow_pickle=False) as z:
            if "format" not in z.files or z["format"].item() != FORMAT:
                raise InputError(f"component file {str(path)!r}: not a {FORMAT!r} file")
            return Component(
                name=z["name"].item(), K=_csr_from("K", z), M=_csr_from("M", z),
                dof_labels=tuple(z["dof_labels"]), label_dofs=z["label_dofs"],
                points=tuple(z["points"]), point_coords=z["point_coords"],
                nodes=z["nodes"] if "nodes" in z.files else None,
                cells=z["cells"] if "cells" in z.files else None,
                cell_type=z["cell_type"].item() if "cell_type" in z.files else "",
                field_map=_csr_from("field_map", z) if "field_map_data" in z.files else None)
    except InputError:
        raise
    except Exception as exc:
        raise InputError(f"component file {str(path)!r} cannot be read: {exc}") from None
