"""Build a grounded or free-free FE model from a ``meshes`` Geometry: mesh, materials,
P1/P2 elasticity, K and M assembled once (PETSc), rigid spiders to 6-DOF reference
points, clamped surfaces removed, lumped masses at reference points, smeared
non-structural mass on surfaces.

Independent DOFs of the model (its K and M, size n_dof), in PETSc's rank order:
the three translations of every mesh node that is neither clamped nor on a patch (x, y, z
consecutive), then six DOFs per patch reference point (Tx Ty Tz Rx Ry Rz, in patch order)
at the end. Units SI (m, kg, N, rad).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import scipy.sparse as sp
from mpi4py import MPI

from liftoff.core.errors import InputError
from liftoff.core.labels import COMPONENTS, split_label
from liftoff.core.rigid import dof_rb

from . import petsc_backend as pb
from .elasticity import area_form, mass_form, material_fields, stiffness_form, surface_mass_form
from .mesh import TaggedMesh, read_msh
from .spiders import CLAMPED, FREE, transformation_rows


@dataclass
class FEModel:
    """A reduced (spiders eliminated, clamps removed) FE model; see the module docstring."""

    name: str
    comm: MPI.Comm
    tagged: TaggedMesh
    V: object                      # dolfinx VectorFunctionSpace
    degree: int
    E: object                      # DG0 material fields (dolfinx Functions)
    nu: object
    rho: object
    K: object                      # PETSc Mat, n_dof x n_dof (N/m ...)
    M: object                      # PETSc Mat (kg ...)
    T: object                      # PETSc Mat, 3 n_nodes x n_dof: full nodal u = T x
    points: tuple[str, ...]        # patch reference points
    point_coords: np.ndarray       # (n_points, 3) m
    dof_coords: np.ndarray         # (n_dof, 3): node or reference-point position of each DOF
    dof_comp: np.ndarray           # (n_dof,) 0..5 = Tx..Rz
    dof_node: np.ndarray           # (n_dof,) global node index, -1 for reference-point DOFs
    nodes: np.ndarray              # (n_nodes, 3) all DOF nodes (P2: incl. edge midpoints)
    cells: np.ndarray              # (n_cells, 4 or 10) into nodes, VTK/meshio order
    cell_type: str                 # "tetra" or "tetra10"
    clamped: tuple[str, ...] = ()
    _cache: dict = field(default_factory=dict, repr=False)

    @property
    def n_dof(self) -> int:
        return int(self.dof_comp.size)

    @property
    def grounded(self) -> bool:
        return bool(self.clamped)

    @property
    def ref_first_dof(self) -> int:
        return self.n_dof - 6 * len(self.points)

    @property
    def dof_labels(self) -> tuple[str, ...]:
        return tuple(f"{p}:{c}" for p in self.points for c in COMPONENTS)

    @property
    def label_dofs(self) -> np.ndarray:
        return self.ref_first_dof + np.arange(6 * len(self.points), dtype=np.int64)

    def dof_index(self, label: str) -> int:
        """Index of ``point:Tx``-style label among the model's DOFs."""
        point, comp = split_label(label)
        if point not in self.points:
            raise InputError(f"model {self.name!r} has no reference point {point!r} "
                             f"(has: {', '.join(self.points) or 'none'})")
        return self.ref_first_dof + 6 * self.points.index(point) + comp

    def rigid_body_shape(self, about=(0.0, 0.0, 0.0)) -> np.ndarray:
        """Geometric rigid-body shape RB (n_dof, 6) of the model's DOFs about ``about`` (m)."""
        return dof_rb(self.dof_coords - np.asarray(about, float), self.dof_comp)

    def node_dofs(self, xyz) -> np.ndarray:
        """The three DOF indices (x, y, z) of the free mesh node nearest ``xyz``."""
        free = np.flatnonzero(self.dof_comp == 0)
        free = free[self.dof_node[free] >= 0]
        if free.size == 0:
            raise InputError(f"model {self.name!r} has no free mesh node")
        i = free[np.argmin(np.linalg.norm(self.dof_coords[free] - np.asarray(xyz, float), axis=1))]
        return np.array([i, i + 1, i + 2])

    def matrices(self) -> tuple[sp.csr_matrix, sp.csr_matrix]:
        """(K, M) as scipy CSR on every rank (gathered once)."""
        if "KM" not in self._cache:
            self._cache["KM"] = (pb.gather_csr(self.K), pb.gather_csr(self.M))
        return self._cache["KM"]

    def field_map(self) -> sp.csr_matrix:
        """T as scipy CSR (3 n_nodes x n_dof): DOF vector -> nodal displacement (x,y,z interleaved)."""
        if "T" not in self._cache:
            self._cache["T"] = pb.gather_csr(self.T)
        return self._cache["T"]

    def nodal_displacement(self, x: np.ndarray) -> np.ndarray:
        """(n_nodes, 3) nodal displacements of DOF vector(s) ``x`` (n_dof,)."""
        return (self.field_map() @ np.asarray(x, float)).reshape(-1, 3)

    def component_fields(self) -> dict:
        """Keyword fields of ``reduction.component.Component`` (all but ``name``)."""
        K, M = self.matrices()
        return dict(K=K, M=M, dof_labels=self.dof_labels, label_dofs=self.label_dofs,
                    points=self.points, point_coords=self.point_coords.copy(), nodes=self.nodes.copy(),
                    cells=self.cells.copy(), cell_type=self.cell_type, field_map=self.field_map())


def _raise_collective(comm: MPI.Comm, message: str | None) -> None:
    """Raise InputError on every rank if any rank found a problem (avoids MPI deadlocks)."""
    msgs = [m for m in comm.allgather(message) if m]
    if msgs:
        raise InputError(msgs[0])


def _surface_tags(tm: TaggedMesh, surface: str, role: str):
    """The facet tags of physical surface ``surface``; InputError naming ``role`` if absent."""
    if surface not in tm.surface_tags:
        raise InputError(f"{role} {surface!r}: no physical surface {surface!r} in mesh {tm.path!r} "
                         f"(has: {', '.join(sorted(tm.surface_tags)) or 'none'})")
    return tm.surface_tags[surface]


def _surface_blocks(V, tm: TaggedMesh, surface: str, role: str) -> np.ndarray:
    from dolfinx import fem

    tags = _surface_tags(tm, surface, role)
    return fem.locate_dofs_topological(V, V.mesh.topology.dim - 1, tags.indices[tags.values == 1])


def build_model(geometry, degree: int = 1, comm: MPI.Comm = MPI.COMM_WORLD,
                lumped_smeared_mass: bool = False) -> FEModel:
    """FE model of a ``meshes.spec.Geometry`` (or the path of its JSON file).

    ``degree``: 1 or 2 (Lagrange). ``lumped_smeared_mass``: non-structural surface mass
    lumped to the nodes by row sums (P1 only: P2 row sums vanish at vertices) instead of
    the consistent surface mass. Steps: mesh and materials, K and M (with smeared mass),
    the role of every node (free, on a spider, clamped), the reduction x_full = T x, the
    lumped masses, and the per-DOF description gathered on every rank.
    """
    from dolfinx import fem

    if isinstance(geometry, (str, Path)):
        from liftoff.meshes.spec import Geometry
        geometry = Geometry.load(geometry)
    name = str(geometry.name)
    if degree not in (1, 2):
        raise InputError(f"model {name!r}: degree {degree!r} not supported (use 1 or 2)")
    if lumped_smeared_mass and degree != 1:
        raise InputError(f"model {name!r}: lumped smeared mass needs degree 1")
    tm = read_msh(geometry.msh_path, comm)
    E, nu, rho = material_fields(tm, dict(geometry.volumes))
    V = fem.VectorFunctionSpace(tm.mesh, ("CG", degree))
    K = pb.assemble_matrix(stiffness_form(V, E, nu))
    M = pb.assemble_matrix(mass_form(V, rho))
    _add_smeared_masses(M, V, tm, geometry.smeared_masses, lumped_smeared_mass)
    imap = V.dofmap.index_map
    if K.getOwnershipRange() != (3 * imap.local_range[0], 3 * imap.local_range[1]):
        raise RuntimeError("unexpected PETSc row layout of the assembled stiffness")
    coords = V.tabulate_dof_coordinates()[: imap.size_local + imap.num_ghosts]
    pnames = [p.name for p in geometry.patches]
    role = _node_roles(V, tm, pnames, [str(s) for s in geometry.clamped], comm)
    ref_coords = np.array([np.asarray(p.ref_point, float).reshape(3) for p in geometry.patches]).reshape(-1, 3)
    red = _reduction(V, coords, role, ref_coords, comm)
    Kr, Mr = pb.ptap(K, red.T), pb.ptap(M, red.T)
    K.destroy()
    M.destroy()
    _add_point_masses(Mr, geometry.point_masses, pnames, red.n_keep_total)
    dof_coords, dof_comp, dof_node = _dof_table(comm, coords, red, ref_coords, imap.local_range[0])
    nodes, cells, cell_type = _global_mesh(V, comm, coords[: imap.size_local])
    return FEModel(name=name, comm=comm, tagged=tm, V=V, degree=degree, E=E, nu=nu, rho=rho,
                   K=Kr, M=Mr, T=red.T, points=tuple(pnames), point_coords=ref_coords,
                   dof_coords=dof_coords, dof_comp=dof_comp, dof_node=dof_node, nodes=nodes,
                   cells=cells, cell_type=cell_type, clamped=tuple(str(s) for s in geometry.clamped))


def _add_smeared_masses(M, V, tm: TaggedMesh, smeared, lumped: bool) -> None:
    """Non-structural mass (kg) spread uniformly over surface groups, consistent or lumped."""
    from dolfinx import fem

    comm = tm.mesh.comm
    for sm in smeared:
        if not np.isfinite(sm.mass) or sm.mass < 0:
            raise InputError(f"smeared mass on {sm.surface!r}: mass {sm.mass!r} kg must be >= 0")
        tags = _surface_tags(tm, sm.surface, "smeared mass surface")
        area = comm.allreduce(fem.assemble_scalar(fem.form(area_form(tm.mesh, tags))), op=MPI.SUM)
        if area <= 0.0:
            raise InputError(f"smeared mass surface {sm.surface!r}: zero exterior area "
                             "(an interior surface cannot carry surface mass here)")
        Ms = pb.assemble_matrix(surface_mass_form(V, tags, sm.mass / area))
        if lumped:
            pb.add_row_sums_to_diagonal(M, Ms)     # P1 row sums = mass/3 per triangle vertex
        else:
            pb.add_subset(M, Ms)


def _node_roles(V, tm: TaggedMesh, patches: list[str], clamped: list[str], comm: MPI.Comm) -> np.ndarray:
    """Role of every local node (owned and ghost): FREE, CLAMPED or its patch number."""
    imap = V.dofmap.index_map
    n_own = imap.size_local
    role = np.full(n_own + imap.num_ghosts, FREE, dtype=np.int64)
    problem = None
    for p, patch in enumerate(patches):
        blocks = _surface_blocks(V, tm, patch, "patch")
        n_nodes = comm.allreduce(int(np.sum(blocks < n_own)), op=MPI.SUM)
        if n_nodes < 3:
            raise InputError(f"patch {patch!r}: its surface has {n_nodes} nodes; a rigid spider needs >= 3")
        clash = role[blocks][role[blocks] >= 0]
        if clash.size and problem is None:
            problem = (f"patches {patches[int(clash[0])]!r} and {patch!r} share nodes; "
                       "a node can hang on one rigid spider only")
        role[blocks] = p
    _raise_collective(comm, problem)
    for surface in clamped:
        blocks = _surface_blocks(V, tm, surface, "clamped surface")
        if comm.allreduce(int(np.sum(blocks < n_own)), op=MPI.SUM) == 0:
            raise InputError(f"clamped surface {surface!r} has no nodes in mesh {tm.path!r}")
        on_patch = role[blocks][role[blocks] >= 0]
        if on_patch.size and problem is None:
            problem = (f"clamped surface {surface!r} shares nodes with patch {patches[int(on_patch[0])]!r}; "
                       "a node is either clamped or on a spider")
        role[blocks] = CLAMPED
    _raise_collective(comm, problem)
    return role


@dataclass
class _Reduction:
    """x_full = T x: the independent DOFs (free nodes' translations, then 6 per patch point)."""

    T: object                  # PETSc Mat, 3 n_nodes x n_dof
    free_blocks: np.ndarray    # owned free nodes (local indices)
    n_keep_total: int          # free translations over all ranks
    n_dof: int


def _reduction(V, coords: np.ndarray, role: np.ndarray, ref_coords: np.ndarray, comm: MPI.Comm) -> _Reduction:
    """The spider/clamp transformation T (fem/spiders.py) in PETSc's rank order."""
    n_own = V.dofmap.index_map.size_local
    role_own = role[:n_own]
    free_blocks = np.flatnonzero(role_own == FREE)
    n_keep = 3 * free_blocks.size
    offset = comm.exscan(n_keep) or 0
    n_keep_total = comm.allreduce(n_keep, op=MPI.SUM)
    n_ref = 6 * ref_coords.shape[0]
    n_dof = n_keep_total + n_ref
    last = comm.rank == comm.size - 1
    keep_index = np.full(n_own, -1, dtype=np.int64)
    keep_index[free_blocks] = offset + 3 * np.arange(free_blocks.size)
    T_local = transformation_rows(coords[:n_own], role_own, keep_index, ref_coords, n_keep_total, n_dof)
    T = pb.csr_matrix(comm, 3 * n_own, n_keep + (n_ref if last else 0), n_dof, T_local)
    return _Reduction(T, free_blocks, n_keep_total, n_dof)


def _add_point_masses(Mr, point_masses, patches: list[str], ref_first_dof: int) -> None:
    """Lumped mass and inertia (about the patch point) on the six DOFs of a patch point."""
    for pm in point_masses:
        if pm.patch not in patches:
            raise InputError(f"point mass {pm.name!r}: unknown patch {pm.patch!r} "
                             f"(has: {', '.join(patches) or 'none'})")
        J = np.asarray(pm.inertia, float).reshape(3, 3)
        if not np.isfinite(pm.mass) or pm.mass < 0:
            raise InputError(f"point mass {pm.name!r}: mass {pm.mass!r} kg must be >= 0")
        if not np.allclose(J, J.T) or np.linalg.eigvalsh(0.5 * (J + J.T)).min() < -1e-12 * max(1.0, np.abs(J).max()):
            raise InputError(f"point mass {pm.name!r}: inertia must be symmetric positive semi-definite (kg m^2)")
        block = np.zeros((6, 6))
        block[:3, :3] = pm.mass * np.eye(3)
        block[3:, 3:] = J
        pb.add_block(Mr, ref_first_dof + 6 * patches.index(pm.patch) + np.arange(6), block)


def _dof_table(comm: MPI.Comm, coords: np.ndarray, red: _Reduction, ref_coords: np.ndarray, node0: int):
    """(dof_coords, dof_comp, dof_node) of every independent DOF, gathered on every rank."""
    fb = red.free_blocks
    loc = (np.repeat(coords[fb], 3, axis=0), np.tile(np.arange(3), fb.size), np.repeat(node0 + fb, 3))
    n_ref = 6 * ref_coords.shape[0]
    if comm.rank == comm.size - 1 and n_ref:
        loc = (np.vstack([loc[0], np.repeat(ref_coords, 6, axis=0)]),
               np.concatenate([loc[1], np.tile(np.arange(6), ref_coords.shape[0])]),
               np.concatenate([loc[2], -np.ones(n_ref, dtype=np.int64)]))
    parts = comm.allgather(loc)
    return (np.vstack([p[0] for p in parts]).reshape(-1, 3),
            np.concatenate([p[1] for p in parts]).astype(np.int64),
            np.concatenate([p[2] for p in parts]).astype(np.int64))


def _global_mesh(V, comm: MPI.Comm, own_coords: np.ndarray):
    """All DOF nodes (global node order) and owned cells in VTK order, on every rank."""
    from dolfinx.plot import create_vtk_mesh

    topology, _, _ = create_vtk_mesh(V)
    k = V.dofmap.dof_layout.num_dofs
    local_cells = np.asarray(topology).reshape(-1, k + 1)[:, 1:]
    gcells = V.dofmap.index_map.local_to_global(local_cells.ravel().astype(np.int32)).reshape(-1, k)
    nodes = np.vstack(comm.allgather(np.asarray(own_coords))).reshape(-1, 3)
    cells = np.vstack(comm.allgather(np.asarray(gcells, dtype=np.int64))).reshape(-1, k)
    cell_type = {4: "tetra", 10: "tetra10"}.get(k)
    if cell_type is None:
        raise InputError(f"unsupported cell with {k} nodes: fem supports tetrahedral meshes (P1/P2)")
    return nodes, cells, cell_type
