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
K/data,indices,     CSR arrays       stiffness (N/m, N/rad, N m/rad)
  indptr,shape
M/data,...          CSR arrays       mass (kg, kg m, kg m^2)
dof_labels          (n_l,) str       labels of the labelled DOFs
label_dofs          (n_l,) int       their indices into K and M
points              (n_p,) str       names of labelled points
point_coords        (n_p, 3)         their coordinates (m)
nodes               (n_nodes, 3)     mesh node coordinates (m)            [optional]
cells               (n_cells, k)     cell connectivity into nodes         [optional]
cell_type           str              meshio cell type, e.g. "tetra"       [optional]
line_cells          (n_lines, 2)     beams beside the cells, into nodes   [optional]
field_map/*         CSR arrays       (3 n_nodes, n) DOF vector -> nodal u [optional]
liquid_*            CSR and arrays   hydroelastic liquid (reduction.liquid):  [optional]
                                     H, G, volume_rows (CSR), pressure_points,
                                     pressure_dofs, volume_names, mass, centroid
slosh_*             arrays, CSR      slosh pendulums (reduction.slosh):       [optional]
                                     names, liquid, dofs, mass (kg), stiffness (N/m),
                                     frequency (Hz), gravity (m/s^2), direction,
                                     position (m), stretch (CSR, n x n_dof)
==================  ===============  ================================================
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from liftoff.core.errors import InputError
from liftoff.core.labels import split_label
from liftoff.core.records import read_record, write_record

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
    line_cells: np.ndarray | None = None   # (k, 2) beams beside ``cells`` (drawn as lines), or None
    liquid: object = None          # reduction.liquid.LiquidMass: the added mass of the liquids, or None
    slosh: object = None           # reduction.slosh.SloshDOFs: the liquids' slosh pendulums, or None
    #: K and M are already known finite (a stage-cache file: validated when built, its bytes
    #: checksummed since), so validate() does not read every stored value
    values_checked: bool = field(default=False, repr=False, compare=False)

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
        for nm in () if self.values_checked else ("K", "M"):
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
        if self.liquid is not None and self.liquid.n_dof != n:
            raise InputError(f"{who}: the liquid's coupling has {self.liquid.n_dof} columns, expected {n}")
        if self.slosh is not None and (self.slosh.n_dof != n or (self.slosh.n and (self.slosh.dofs.min() < 0
                                                                                   or self.slosh.dofs.max() >= n))):
            raise InputError(f"{who}: the slosh pendulums' rows have {self.slosh.n_dof} columns or DOFs outside "
                             f"0..{n - 1}")

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


def _csr_record(A: sp.csr_matrix) -> dict:
    return {"data": A.data, "indices": A.indices, "indptr": A.indptr, "shape": np.array(A.shape)}


def _csr_from(g: dict) -> sp.csr_matrix:
    return sp.csr_matrix((g["data"], g["indices"], g["indptr"]), shape=tuple(g["shape"]))


def save_component(c: Component, path) -> Path:
    """Write atomically as .npz (temporary file + rename)."""
    data = {"dof_labels": np.array(c.dof_labels, dtype="U"), "label_dofs": c.label_dofs,
            "points": np.array(c.points, dtype="U"), "point_coords": c.point_coords,
            "K": _csr_record(c.K), "M": _csr_record(c.M)}
    if c.nodes is not None:
        data["nodes"] = np.asarray(c.nodes, float)
    if c.cells is not None:
        data["cells"] = np.asarray(c.cells, np.int64)
        data["cell_type"] = np.array(c.cell_type)
    if c.line_cells is not None:
        data["line_cells"] = np.asarray(c.line_cells, np.int64)
    if c.field_map is not None:
        data["field_map"] = _csr_record(c.field_map)
    if c.liquid is not None:
        data.update(c.liquid.record())
    if c.slosh is not None:
        data.update(c.slosh.record())
    return write_record(path, FORMAT, VERSION, data, units="SI", attrs={"name": c.name}, suffixes=(".npz",))


def load_component(path, mmap: bool = False) -> Component:
    """A component file (:meth:`Component.save`); ``mmap``: its large arrays mapped read-only
    (liftoff.core.records.read_record), for files checked otherwise (the stage cache), and
    K and M not scanned for NaN or inf: a worker that never uses them (a generated case)
    then never reads them (0.6 GB of the default's pages per process, 2026-11-27)."""
    from .liquid import LiquidMass
    from .slosh import SloshDOFs

    rec = read_record(path, FORMAT, (VERSION,), what="component file", mmap=mmap)
    z = rec.data
    try:
        return Component(
            name=str(rec.attrs["name"]), K=_csr_from(z["K"]), M=_csr_from(z["M"]),
            dof_labels=tuple(z["dof_labels"]), label_dofs=z["label_dofs"],
            points=tuple(z["points"]), point_coords=z["point_coords"],
            nodes=z.get("nodes"), cells=z.get("cells"),
            cell_type=str(z["cell_type"]) if "cell_type" in z else "",
            field_map=_csr_from(z["field_map"]) if "field_map" in z else None,
            line_cells=z.get("line_cells"), liquid=LiquidMass.from_record(z), slosh=SloshDOFs.from_record(z),
            values_checked=mmap)
    except InputError:
        raise
    except Exception as exc:
        raise InputError(f"component file {str(path)!r} cannot be read: {exc}") from None
