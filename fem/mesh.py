"""Read a gmsh ``.msh`` file into distributed dolfinx meshes with *named* tags.

dolfinx 0.5.2's ``gmshio.read_from_msh`` is broken (it returns an undefined name) and its
``model_to_mesh`` duplicates cells that belong to two physical groups and keeps a single
facet tag per facet. This reader does the same job (rank 0 reads, dolfinx distributes)
but keeps one tag set per named group, so that a facet may belong to a patch and to a
smeared-mass surface at once. A file may hold two parts that share nodes:

* the **solid** part: tetrahedra of the physical VOLUME groups;
* the **shell** part: the flat 3-node triangles of the physical SURFACE groups named in
  ``shells`` (a triangle mesh in 3-D, for fem.shell);
* the **liquid** part: the tetrahedra of the physical VOLUME groups named in ``liquids``
  (fem.liquid; they are not structure, and share the wetted faces' nodes with it).

Each part is a :class:`TaggedMesh` whose ``surface_tags`` tag the part's 2-D entities (tet
facets, or shell cells) of every surface group, and ``curve_tags`` (shell part only) its
1-D entities (shell edges) of every curve group. Checks (InputError naming the file):

* every physical group must have a name (names are the user's handles);
* a mesh with neither a 3-D physical group nor a shell surface is rejected;
* a volume entity may belong to one physical volume only, a shell triangle to one shell
  group only (one material, one thickness).
"""
from __future__ import annotations

from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import ufl
from mpi4py import MPI

from liftoff.core.errors import InputError


@dataclass
class TaggedMesh:
    """A dolfinx mesh with per-cell group ids and one tag set per named lower-dimensional group."""

    mesh: object                      # dolfinx.mesh.Mesh
    cell_tags: object                 # MeshTags over cells, value = group id
    volume_ids: dict[str, int]        # cell group name (volume, or shell surface) -> id in cell_tags
    surface_tags: dict[str, object]   # physical surface name -> MeshTags (2-D entities, value 1)
    path: str
    curve_tags: dict[str, object] = field(default_factory=dict)   # curve name -> MeshTags (1-D, value 1)


def _gmsh_is_initialized(gmsh) -> bool:
    """gmsh 4.8 has no isInitialized(): before initialize() model.list() is empty, after
    finalize() it raises."""
    import os

    saved = os.dup(2)
    try:
        with open(os.devnull, "w") as null:   # hide gmsh's "not initialized" message
            os.dup2(null.fileno(), 2)
            try:
                return len(gmsh.model.list()) > 0
            except Exception:
                return False
    finally:
        os.dup2(saved, 2)
        os.close(saved)


def _elements(gmsh, dim: int, tag: int) -> tuple[int | None, np.ndarray]:
    """(gmsh element type, (n, nodes) 0-based node indices) of physical group (dim, tag)."""
    etype, out, width = None, [], {0: 1, 1: 2, 2: 3, 3: 4}[dim]
    for ent in gmsh.model.getEntitiesForPhysicalGroup(dim, tag):
        etypes, _, enodes = gmsh.model.mesh.getElements(dim, ent)
        for et, en in zip(etypes, enodes):
            etype = int(et)
            width = gmsh.model.mesh.getElementProperties(et)[3]
            out.append(np.asarray(en, dtype=np.int64).reshape(-1, width) - 1)
    return etype, (np.vstack(out) if out else np.zeros((0, width), dtype=np.int64))


#: the gmsh element type read per dimension: 4-node tetrahedra, 3-node triangles (docs/fem.md "Limits")
LINEAR_CELL = {3: 4, 2: 2}


def _cell_groups(gmsh, path: str, groups: list, what: str):
    """(gmsh type, cells, group index per cell) of the named groups [(dim, tag, name)],
    each element in one group only."""
    cell_type, cells, vals, seen = None, [], [], {}
    for gid, (dim, tag, name) in enumerate(groups):
        for ent in gmsh.model.getEntitiesForPhysicalGroup(dim, tag):
            if ent in seen:
                raise InputError(f"mesh {path!r}: {what} entity {ent} is in groups {seen[ent]!r} and "
                                 f"{name!r}; a cell needs one material")
            seen[ent] = name
        et, c = _elements(gmsh, dim, tag)
        if et is not None and et != LINEAR_CELL.get(dim, et):
            raise InputError(f"mesh {path!r}: {what} group {name!r} has {gmsh.model.mesh.getElementProperties(et)[0]} "
                             f"elements (gmsh type {et}); only {'4-node tetrahedra' if dim == 3 else '3-node triangles'} "
                             "are read (mesh it first order: gmsh -order 1)")
        if et is not None:
            if cell_type is not None and et != cell_type:
                raise InputError(f"mesh {path!r}: mixed {what} element types {cell_type} and {et}")
            cell_type = et
        cells.append(c)
        vals.append(np.full(c.shape[0], gid, dtype=np.int32))
    return cell_type, np.vstack(cells), np.concatenate(vals)


def _sub_entities(cells: np.ndarray, k: int) -> np.ndarray:
    """Sorted vertex k-tuples (rows) of the sub-entities of tets or triangles (vertices first)."""
    from itertools import combinations

    nv = 4 if cells.shape[1] in (4, 10) else 3
    return np.vstack([np.sort(cells[:, list(c)], axis=1) for c in combinations(range(nv), k)])


def _rows_in(rows: np.ndarray, table: np.ndarray) -> np.ndarray:
    """Mask of the rows of ``rows`` (vertex tuples, any order) that are rows of ``table`` (sorted)."""
    if rows.shape[0] == 0:
        return np.zeros(0, bool)
    k = table.shape[1]
    a = np.ascontiguousarray(np.sort(rows[:, :k], axis=1))
    b = np.ascontiguousarray(table)
    view = np.dtype((np.void, a.dtype.itemsize * k))
    return np.isin(a.view(view).ravel(), b.view(view).ravel())


@contextmanager
def _merged(path: str, model_name: str):
    """(gmsh, x): ``path`` merged into a gmsh model of its own (nodes renumbered 1..n) and its
    node coordinates x (n, 3); gmsh's earlier state restored afterwards."""
    import gmsh

    was_initialized = _gmsh_is_initialized(gmsh)
    if not was_initialized:
        gmsh.initialize(["-nopopup"])
    gmsh.option.setNumber("General.Terminal", 0)
    previous = gmsh.model.getCurrent() if was_initialized else None
    gmsh.model.add(model_name)
    try:
        gmsh.merge(path)
        gmsh.model.mesh.renumberNodes()
        tags, coords, _ = gmsh.model.mesh.getNodes()
        x = np.zeros((len(tags), 3))
        x[np.asarray(tags, dtype=np.int64) - 1] = coords.reshape(-1, 3)
        yield gmsh, x
    finally:
        gmsh.model.remove()
        if was_initialized and previous:
            gmsh.model.setCurrent(previous)
        if not was_initialized:
            gmsh.finalize()


def _read_rank0(path: str, shells: tuple[str, ...], liquids: tuple[str, ...] = ()):
    """On the reading rank: nodes, the solid and shell parts, and the groups' entities."""
    with _merged(path, "liftoff_fem_reader") as (gmsh, x):
        groups = []
        for dim, tag in gmsh.model.getPhysicalGroups():
            name = gmsh.model.getPhysicalName(dim, tag)
            if not name:
                raise InputError(f"mesh {path!r}: physical group (dim {dim}, tag {tag}) has no name")
            groups.append((dim, tag, name))
        surf_names = {n for d, _, n in groups if d == 2}
        missing = [s for s in shells if s not in surf_names]
        if missing:
            raise InputError(f"mesh {path!r}: shell surface {missing[0]!r} is not a physical surface "
                             f"(has: {', '.join(sorted(surf_names)) or 'none'})")
        vol_names = {n for d, _, n in groups if d == 3}
        missing = [v for v in liquids if v not in vol_names]
        if missing:
            raise InputError(f"mesh {path!r}: liquid {missing[0]!r} is not a physical volume "
                             f"(has: {', '.join(sorted(vol_names)) or 'none'})")
        vols = [g for g in groups if g[0] == 3 and g[2] not in liquids]
        if not vols and not shells and not liquids:
            raise InputError(f"mesh {path!r} has no volume (3-D) physical group and no shell surface: "
                             "nothing to model")
        parts = {"solid": None, "shell": None, "liquid": None}
        if vols:
            ct, cells, vals = _cell_groups(gmsh, path, vols, "volume")
            if ct is None:
                raise InputError(f"mesh {path!r}: the volume groups hold no 3-D elements (was it meshed in 3-D?)")
            parts["solid"] = (ct, cells, vals, [n for _, _, n in vols])
        if shells:
            sg = [next(g for g in groups if g[0] == 2 and g[2] == s) for s in shells]
            ct, cells, vals = _cell_groups(gmsh, path, sg, "shell surface")
            if ct != 2:
                raise InputError(f"mesh {path!r}: shell surfaces must be meshed with flat 3-node triangles "
                                 f"(gmsh element type 2, got {ct})")
            parts["shell"] = (ct, cells, vals, list(shells))
        if liquids:
            lg = [next(g for g in groups if g[0] == 3 and g[2] == v) for v in liquids]
            ct, cells, vals = _cell_groups(gmsh, path, lg, "liquid volume")
            if ct is None:
                raise InputError(f"mesh {path!r}: the liquid volumes hold no 3-D elements (was it meshed in 3-D?)")
            parts["liquid"] = (ct, cells, vals, list(liquids))
        entities = {d: {n: _elements(gmsh, d, t) for dd, t, n in groups if dd == d} for d in (1, 2)}
        return x, parts, entities


def _part_entities(kind: str, cells: np.ndarray, entities: dict, hybrid: bool) -> dict:
    """The groups' entities that belong to a part: in a file with several parts, surface
    triangles that are tet faces (solid, liquid) or shell cells (shell), curve segments that
    are shell edges; curves are tagged on the shell part only."""
    out = {2: dict(entities[2]), 1: dict(entities[1]) if kind == "shell" else {}}
    if hybrid:
        for d in (2, 1) if kind == "shell" else (2,):
            table = _sub_entities(cells, d + 1)
            out[d] = {n: (t, e[_rows_in(e, table)]) for n, (t, e) in out[d].items()}
    return out


def _tagged_mesh(comm, rank: int, path: str, x, cell_type: int, cells, cell_vals, names, entities) -> TaggedMesh:
    """Distribute one part (arrays given on ``rank``; shapes from ``cell_type``/``entities``)."""
    import dolfinx.mesh as dmesh
    from dolfinx import cpp
    from dolfinx.io.gmshio import cell_perm_array, ufl_mesh

    domain = ufl_mesh(cell_type, 3)
    dcell = cpp.mesh.to_type(str(domain.ufl_cell()))
    nn = cells.shape[1]
    cells = cells[:, cell_perm_array(dcell, nn)]       # gmsh -> dolfinx node order
    mesh = dmesh.create_mesh(comm, cells, x, domain)
    cpp_mesh = mesh._mesh if hasattr(mesh, "_mesh") else mesh
    tdim = mesh.topology.dim

    def tags(dim, ents, vals):
        mesh.topology.create_connectivity(dim, tdim)
        e, v = cpp.io.distribute_entity_data(cpp_mesh, dim, ents, vals)
        return dmesh.meshtags_from_entities(mesh, dim, cpp.graph.AdjacencyList_int32(e), v.astype(np.int32))

    mesh.topology.create_connectivity(tdim, 0)
    cell_tags = tags(tdim, cells, cell_vals)
    groups = {}
    for dim in (2, 1):
        etype = cpp.mesh.cell_entity_type(dcell, dim, 0)
        groups[dim] = {}
        for name, (gtype, ents) in entities.get(dim, {}).items():
            if gtype is not None:
                ents = ents[:, cell_perm_array(etype, ents.shape[1])]
            groups[dim][name] = tags(dim, ents, np.ones(ents.shape[0], np.int32))
    return TaggedMesh(mesh, cell_tags, {n: i for i, n in enumerate(names)}, groups[2], path, groups[1])


def read_mesh_parts(path, comm: MPI.Comm = MPI.COMM_WORLD, shells=(), rank: int = 0, liquids=()):
    """(solid, shell, liquid) TaggedMesh or None each, of ``path``; ``shells``: the physical
    surface groups modelled as shells, ``liquids``: the physical volume groups that are
    liquid. See the module docstring."""
    path, shells, liquids = str(path), tuple(str(s) for s in shells), tuple(str(v) for v in liquids)
    payload, err = None, None
    if comm.rank == rank:
        try:
            if not Path(path).is_file():
                raise InputError(f"mesh file not found: {path!r}")
            payload = _read_rank0(path, shells, liquids)
        except InputError as exc:
            err = str(exc)
        except Exception as exc:  # gmsh raises plain Exception on unreadable files
            err = f"mesh {path!r} cannot be read by gmsh: {exc}"
    err = comm.bcast(err, root=rank)
    if err:
        raise InputError(err)
    meta = None
    if comm.rank == rank:
        x, parts, entities = payload
        hybrid = sum(p is not None for p in parts.values()) > 1
        ents = {k: _part_entities(k, p[1], entities, hybrid) for k, p in parts.items() if p is not None}
        meta = {k: None if p is None else (p[0], p[1].shape[1], p[3],
                                           {d: {n: (t, e.shape[1]) for n, (t, e) in ents[k][d].items()} for d in (1, 2)})
                for k, p in parts.items()}
    meta = comm.bcast(meta, root=rank)
    out = []
    for kind in ("solid", "shell", "liquid"):
        if meta[kind] is None:
            out.append(None)
            continue
        cell_type, nn, names, emeta = meta[kind]
        if comm.rank == rank:          # each part gets only its own nodes (dolfinx needs every node used)
            _, cells, vals, _ = parts[kind]
            used = np.unique(cells)
            new = np.full(payload[0].shape[0], -1, dtype=np.int64)
            new[used] = np.arange(used.size)
            x, cells = payload[0][used], new[cells]
            e = {d: {n: (t, new[a]) for n, (t, a) in ents[kind][d].items()} for d in (1, 2)}
        else:
            x, cells, vals = np.zeros((0, 3)), np.zeros((0, nn), np.int64), np.zeros(0, np.int32)
            e = {d: {n: (t, np.zeros((0, w), np.int64)) for n, (t, w) in emeta[d].items()} for d in (1, 2)}
        out.append(_tagged_mesh(comm, rank, path, x, cell_type, cells, vals, names, e))
    return out[0], out[1], out[2]


@dataclass
class BeamLines:
    """The line elements of a mesh's beam curve groups (fem.beam), on every rank: ``x``
    (n, 3) m, the nodes they use; ``lines`` (m, 2) into x; ``group`` (m,) index into
    ``names``; ``node_groups``: every physical point or curve group -> its nodes among x
    (clamps and patches may name them)."""

    path: str
    x: np.ndarray
    lines: np.ndarray
    group: np.ndarray
    names: tuple
    node_groups: dict
    surface_tags: dict = field(default_factory=dict)     # none (the TaggedMesh interface of fem.model's parts)
    volume_ids: dict = field(default_factory=dict)       # none

    @property
    def curve_tags(self) -> dict:
        return self.node_groups


def _read_lines_rank0(path: str, names: tuple[str, ...]) -> BeamLines:
    with _merged(path, "liftoff_beam_reader") as (gmsh, x):
        groups = {(d, gmsh.model.getPhysicalName(d, t)): t for d, t in gmsh.model.getPhysicalGroups()}
        lines, group = [], []
        for k, name in enumerate(names):
            if (1, name) not in groups:
                have = sorted(n for d, n in groups if d == 1)
                raise InputError(f"mesh {path!r}: beam curve {name!r} is not a physical curve "
                                 f"(has: {', '.join(have) or 'none'})")
            et, c = _elements(gmsh, 1, groups[(1, name)])
            if et is not None and et != 1:
                raise InputError(f"mesh {path!r}: beam curve {name!r} must be meshed with 2-node lines "
                                 f"(gmsh element type 1, got {et})")
            if c.shape[0] == 0:
                raise InputError(f"mesh {path!r}: beam curve {name!r} holds no line elements (was it meshed?)")
            lines.append(c)
            group.append(np.full(c.shape[0], k, dtype=np.int64))
        lines, group = np.vstack(lines), np.concatenate(group)
        used = np.unique(lines)
        new = np.full(x.shape[0], -1, dtype=np.int64)
        new[used] = np.arange(used.size)
        node_groups = {}
        for (d, name), t in groups.items():
            if d <= 1:
                on = new[np.unique(_elements(gmsh, d, t)[1])]
                node_groups[name] = on[on >= 0]
        return BeamLines(path, x[used], new[lines], group, tuple(names), node_groups)


def read_beam_lines(path, names, comm: MPI.Comm = MPI.COMM_WORLD, rank: int = 0) -> BeamLines:
    """The line elements of the physical curve groups ``names`` of ``path`` (every rank:
    beams are small, rank ``rank`` reads and broadcasts); InputError naming the file and
    the group if one is not a physical curve of 2-node lines."""
    out = None
    if comm.rank == rank:
        try:
            if not Path(path).is_file():
                raise InputError(f"mesh file not found: {str(path)!r}")
            out = _read_lines_rank0(str(path), tuple(names))
        except InputError as exc:
            out = str(exc)
        except Exception as exc:  # gmsh raises plain Exception on unreadable files
            out = f"mesh {str(path)!r} cannot be read by gmsh: {exc}"
    out = comm.bcast(out, root=rank)
    if isinstance(out, str):
        raise InputError(out)
    return out


def read_msh(path, comm: MPI.Comm = MPI.COMM_WORLD, rank: int = 0) -> TaggedMesh:
    """The solid part of ``path`` (InputError if it has no 3-D physical group)."""
    return read_mesh_parts(path, comm, (), rank)[0]


def triangle_mesh(comm: MPI.Comm, x: np.ndarray, cells: np.ndarray, rank: int = 0):
    """A dolfinx mesh of flat (3-node) triangles embedded in 3-D, for shells: nodes ``x``
    (n, 3) m and ``cells`` (m, 3) node indices, given on ``rank`` (other ranks' arrays are
    ignored) and distributed over ``comm``."""
    import dolfinx.mesh as dmesh

    x = np.asarray(x, float).reshape(-1, 3) if comm.rank == rank else np.zeros((0, 3))
    cells = np.asarray(cells, np.int64).reshape(-1, 3) if comm.rank == rank else np.zeros((0, 3), np.int64)
    domain = ufl.Mesh(ufl.VectorElement("Lagrange", ufl.Cell("triangle", geometric_dimension=3), 1))
    return dmesh.create_mesh(comm, cells, x, domain)

