"""Read a gmsh ``.msh`` file into a distributed dolfinx mesh with *named* tags.

dolfinx 0.5.2's ``gmshio.read_from_msh`` is broken (it returns an undefined name) and its
``model_to_mesh`` duplicates cells that belong to two physical groups and keeps a single
facet tag per facet. This reader does the same job (rank 0 reads, dolfinx distributes)
but keeps one tag set per named surface group, so that a facet may belong to a patch and
to a smeared-mass surface at once, and it checks the input:

* every physical group must have a name (names are the user's handles);
* a mesh with no 3-D physical group is rejected (InputError naming the file);
* a volume entity may belong to one physical volume only.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import ufl
from mpi4py import MPI

from liftoff.core.errors import InputError


@dataclass
class TaggedMesh:
    """A dolfinx mesh with per-cell volume ids and one facet tag set per surface group."""

    mesh: object                      # dolfinx.mesh.Mesh
    cell_tags: object                 # MeshTags over cells, value = volume id
    volume_ids: dict[str, int]        # physical volume name -> id in cell_tags
    surface_tags: dict[str, object]   # physical surface name -> MeshTags (facets, value 1)
    path: str


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


def _read_rank0(path: str):
    """On the reading rank: nodes, cells per volume group, facets per surface group."""
    import gmsh

    was_initialized = _gmsh_is_initialized(gmsh)
    if not was_initialized:
        gmsh.initialize(["-nopopup"])
    gmsh.option.setNumber("General.Terminal", 0)
    previous = gmsh.model.getCurrent() if was_initialized else None
    gmsh.model.add("liftoff_fem_reader")
    try:
        gmsh.merge(path)
        gmsh.model.mesh.renumberNodes()
        tags, coords, _ = gmsh.model.mesh.getNodes()
        x = np.zeros((len(tags), 3))
        x[np.asarray(tags, dtype=np.int64) - 1] = coords.reshape(-1, 3)
        groups = gmsh.model.getPhysicalGroups()
        names = {}
        for dim, tag in groups:
            name = gmsh.model.getPhysicalName(dim, tag)
            if not name:
                raise InputError(f"mesh {path!r}: physical group (dim {dim}, tag {tag}) has no name")
            names[(dim, tag)] = name
        vols = [(t, names[(3, t)]) for d, t in groups if d == 3]
        if not vols:
            raise InputError(f"mesh {path!r} has no volume (3-D) physical group: nothing to model")
        cell_type, cells, cell_vals, seen = None, [], [], {}
        for vid, (tag, name) in enumerate(vols):
            for ent in gmsh.model.getEntitiesForPhysicalGroup(3, tag):
                if ent in seen:
                    raise InputError(f"mesh {path!r}: volume entity {ent} is in physical volumes "
                                     f"{seen[ent]!r} and {name!r}; a cell needs one material")
                seen[ent] = name
                etypes, _, enodes = gmsh.model.mesh.getElements(3, ent)
                for et, en in zip(etypes, enodes):
                    if cell_type is None:
                        cell_type = int(et)
                    elif int(et) != cell_type:
                        raise InputError(f"mesh {path!r}: mixed 3-D element types {cell_type} and {et}")
                    nn = gmsh.model.mesh.getElementProperties(et)[3]
                    cells.append(np.asarray(en, dtype=np.int64).reshape(-1, nn) - 1)
                    cell_vals.append(np.full(cells[-1].shape[0], vid, dtype=np.int32))
        if cell_type is None:
            raise InputError(f"mesh {path!r}: the volume groups hold no 3-D elements (was it meshed in 3-D?)")
        surfaces = {}
        for d, tag in groups:
            if d != 2:
                continue
            tris, ftype = [], None
            for ent in gmsh.model.getEntitiesForPhysicalGroup(2, tag):
                etypes, _, enodes = gmsh.model.mesh.getElements(2, ent)
                for et, en in zip(etypes, enodes):
                    ftype = int(et)
                    nn = gmsh.model.mesh.getElementProperties(et)[3]
                    tris.append(np.asarray(en, dtype=np.int64).reshape(-1, nn) - 1)
            if tris:
                surfaces[names[(2, tag)]] = (ftype, np.vstack(tris))
            else:
                surfaces[names[(2, tag)]] = (None, np.zeros((0, 3), dtype=np.int64))
        return x, cell_type, np.vstack(cells), np.concatenate(cell_vals), [n for _, n in vols], surfaces
    finally:
        gmsh.model.remove()
        if was_initialized and previous:
            gmsh.model.setCurrent(previous)
        if not was_initialized:
            gmsh.finalize()


def read_msh(path, comm: MPI.Comm = MPI.COMM_WORLD, rank: int = 0) -> TaggedMesh:
    """Read ``path`` on ``rank`` and distribute it over ``comm``; see the module docstring."""
    import dolfinx.mesh as dmesh
    from dolfinx import cpp
    from dolfinx.io.gmshio import cell_perm_array, ufl_mesh

    path = str(path)
    payload, err = None, None
    if comm.rank == rank:
        try:
            if not Path(path).is_file():
                raise InputError(f"mesh file not found: {path!r}")
            payload = _read_rank0(path)
        except InputError as exc:
            err = str(exc)
        except Exception as exc:  # gmsh raises plain Exception on unreadable files
            err = f"mesh {path!r} cannot be read by gmsh: {exc}"
    err = comm.bcast(err, root=rank)
    if err:
        raise InputError(err)
    if comm.rank == rank:
        x, cell_type, cells, cell_vals, vol_names, surfaces = payload
        meta = (cell_type, cells.shape[1], vol_names,
                [(n, s[0], s[1].shape[1]) for n, s in surfaces.items()])
    else:
        meta = None
    cell_type, nn, vol_names, surf_meta = comm.bcast(meta, root=rank)
    if comm.rank != rank:
        x = np.zeros((0, 3))
        cells = np.zeros((0, nn), dtype=np.int64)
        cell_vals = np.zeros(0, dtype=np.int32)
        surfaces = {n: (ft, np.zeros((0, fnn), dtype=np.int64)) for n, ft, fnn in surf_meta}

    domain = ufl_mesh(cell_type, 3)
    dcell = cpp.mesh.to_type(str(domain.ufl_cell()))
    cells = cells[:, cell_perm_array(dcell, nn)]       # gmsh -> dolfinx node order
    mesh = dmesh.create_mesh(comm, cells, x, domain)
    cpp_mesh = mesh._mesh if hasattr(mesh, "_mesh") else mesh
    tdim = mesh.topology.dim
    ents, vals = cpp.io.distribute_entity_data(cpp_mesh, tdim, cells, cell_vals)
    mesh.topology.create_connectivity(tdim, 0)
    cell_tags = dmesh.meshtags_from_entities(mesh, tdim, cpp.graph.AdjacencyList_int32(ents),
                                             vals.astype(np.int32))
    mesh.topology.create_connectivity(tdim - 1, tdim)
    ftype = cpp.mesh.cell_entity_type(dcell, tdim - 1, 0)
    surface_tags = {}
    for name, fgtype, fnn in surf_meta:
        facets = surfaces[name][1]
        if fgtype is not None:
            facets = facets[:, cell_perm_array(ftype, fnn)]
        ents, vals = cpp.io.distribute_entity_data(cpp_mesh, tdim - 1, facets, np.ones(facets.shape[0], np.int32))
        surface_tags[name] = dmesh.meshtags_from_entities(
            mesh, tdim - 1, cpp.graph.AdjacencyList_int32(ents), vals.astype(np.int32))
    return TaggedMesh(mesh, cell_tags, {n: i for i, n in enumerate(vol_names)}, surface_tags, path)


def triangle_mesh(comm: MPI.Comm, x: np.ndarray, cells: np.ndarray, rank: int = 0):
    """A dolfinx mesh of flat (3-node) triangles embedded in 3-D, for shells: nodes ``x``
    (n, 3) m and ``cells`` (m, 3) node indices, given on ``rank`` (other ranks' arrays are
    ignored) and distributed over ``comm``."""
    import dolfinx.mesh as dmesh

    x = np.asarray(x, float).reshape(-1, 3) if comm.rank == rank else np.zeros((0, 3))
    cells = np.asarray(cells, np.int64).reshape(-1, 3) if comm.rank == rank else np.zeros((0, 3), np.int64)
    domain = ufl.Mesh(ufl.VectorElement("Lagrange", ufl.Cell("triangle", geometric_dimension=3), 1))
    return dmesh.create_mesh(comm, cells, x, domain)

