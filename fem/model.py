"""Build a grounded or free-free FE model from a ``meshes`` Geometry: mesh, materials, K and
M assembled once (PETSc) on each *part*, rigid spiders to 6-DOF reference points, clamped
groups removed, lumped masses at reference points, smeared non-structural mass on surfaces.

Parts (one dispatch, :data:`PART_BUILDERS`): the **solid** part (tetrahedra of the volume
groups, P1/P2 elasticity, fem.elasticity) and the **shell** part (the triangles of the
surface groups in ``Geometry.shells``, P2 x Crouzeix-Raviart Reissner-Mindlin shells,
fem.shell). A model has one or both. Their DOFs are gathered into *nodes* by position: a
node shared by a shell and a solid (a shell meshed onto a solid face) has one set of
translations, so the two are tied; the shell's rotations there stay the shell's own (a
solid has no rotational stiffness to tie them to; the shell is held through the
translations of its neighbouring nodes, as in a shell-to-solid mesh of any FE program).

Independent DOFs of the model (its K and M, size n_dof), in PETSc's rank order: the DOFs of
every node that is neither clamped nor on a patch, node by node (Tx Ty Tz, then Rx Ry Rz on
shell nodes that carry rotations), then six DOFs per patch reference point (Tx Ty Tz Rx Ry
Rz, in patch order) at the end. Patches and clamps are surface groups (tet facets or shell
triangles) or, on shells, curve groups (shell edges); a patch ties every DOF of its nodes,
rotations included, to its reference point (fem.spiders). Checks run on data gathered on
every rank, so every rank raises the same InputError (no MPI deadlock). Units SI (m, kg, N, rad).
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
from .jit_log import quiet_compiler_log
from .mesh import TaggedMesh, read_mesh_parts
from .spiders import CLAMPED, FREE, eliminate_interpolations, interpolation_fit, transformation_rows

quiet_compiler_log()    # no gcc command lines on the terminal when forms compile


@dataclass
class Part:
    """One dolfinx space of a model and its link to the model's DOFs."""

    kind: str                      # "solid", "shell" or "beam" (fem.beam.BeamPart)
    tagged: TaggedMesh             # beam: fem.mesh.BeamLines
    V: object                      # solid: VectorFunctionSpace P1/P2; shell: fem.shell.shell_space; beam: None
    fields: object                 # solid: (E, nu, rho) DG0 Functions; shell: fem.shell.ShellFields;
    #                                beam: its meshes.spec.BeamGroup list
    coords: np.ndarray             # (n_local, 3) position of each local DOF (owned first, then ghosts)
    comp: np.ndarray               # (n_local,) 0..5 = Tx..Rz
    n_own: int                     # owned DOFs (this rank's PETSc rows)
    K: object = None               # PETSc Mat on V (released once the model is reduced)
    M: object = None
    T: object = None               # PETSc Mat (part DOFs x model DOFs): x_part = T x

    def global_dofs(self, local: np.ndarray) -> np.ndarray:
        """Global DOF numbers (PETSc rows of K) of local DOF indices (owned or ghost)."""
        imap, bs = self.V.dofmap.index_map, self.V.dofmap.index_map_bs
        local = np.asarray(local, np.int64)
        return imap.local_to_global((local // bs).astype(np.int32)).astype(np.int64) * bs + local % bs

    def group_dofs(self, name: str) -> np.ndarray | None:
        """Local DOFs on the entities of surface or curve group ``name``; None if the part lacks it."""
        from dolfinx import fem

        tm = self.tagged
        tags = tm.surface_tags.get(name, tm.curve_tags.get(name))
        if tags is None:
            return None
        dim = 2 if name in tm.surface_tags else 1
        dofs = fem.locate_dofs_topological(self.V, dim, tags.indices[tags.values == 1])
        bs = self.V.dofmap.index_map_bs
        return (np.asarray(dofs, np.int64)[:, None] * bs + np.arange(bs)).ravel()


@dataclass
class FEModel:
    """A reduced (spiders eliminated, clamps removed) FE model; see the module docstring."""

    name: str
    comm: MPI.Comm
    parts: tuple[Part, ...]
    degree: int                    # Lagrange degree of the solid part (shells are always P2 x CR)
    K: object                      # PETSc Mat, n_dof x n_dof (N/m ...)
    M: object                      # PETSc Mat (kg ...)
    points: tuple[str, ...]        # patch reference points
    point_coords: np.ndarray       # (n_points, 3) m
    dof_coords: np.ndarray         # (n_dof, 3): node or reference-point position of each DOF
    dof_comp: np.ndarray           # (n_dof,) 0..5 = Tx..Rz
    dof_node: np.ndarray           # (n_dof,) index into nodes, -1 for reference-point DOFs
    nodes: np.ndarray              # (n_nodes, 3) all nodes (P2: incl. edge midpoints)
    cells: np.ndarray              # (n_cells, k) into nodes, VTK/meshio order
    cell_type: str                 # "tetra", "tetra10", "triangle6" (shells) or "triangle" (P1 + shells)
    T: sp.csr_matrix               # field map (3 n_nodes x n_dof): nodal translations = T x
    clamped: tuple[str, ...] = ()
    line_cells: np.ndarray | None = None   # (k, 2) beams beside shells or solids (drawn as lines), or None
    liquid: object = None          # fem.liquid.LiquidOperator of the geometry's liquids (coupled), or None
    liquid_volume_rows: dict = field(default_factory=dict)   # liquid group -> cavity volume-change row (m^3/m)
    slosh: object = None           # fem.slosh.SloshPendulums (convective = "slosh"): DOFs after the model's n_dof
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

    def part(self, kind: str) -> Part | None:
        return next((p for p in self.parts if p.kind == kind), None)

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
        """The three translation DOF indices (x, y, z) of the free mesh node nearest ``xyz``."""
        free = np.flatnonzero(self.dof_comp == 0)
        free = free[(self.dof_node[free] >= 0) & (free + 2 < self.dof_comp.size)]
        free = free[(self.dof_comp[free + 2] == 2) & (self.dof_node[free + 2] == self.dof_node[free])]
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
        """T (3 n_nodes x n_dof): DOF vector -> nodal displacement (x,y,z interleaved), every rank."""
        return self.T

    def nodal_displacement(self, x: np.ndarray) -> np.ndarray:
        """(n_nodes, 3) nodal displacements of DOF vector(s) ``x`` (n_dof,)."""
        return (self.field_map() @ np.asarray(x, float)).reshape(-1, 3)

    def component_fields(self) -> dict:
        """Keyword fields of ``reduction.component.Component`` (all but ``name`` and
        ``liquid``; :meth:`liquid_fields` gives the latter's)."""
        K, M = self.matrices()
        T = self.field_map()
        if self.slosh is not None:          # the slosh pendulums' DOFs after the model's (fem.slosh)
            K, M = self.slosh.augment(K, M)
            T = _pad_columns(T, self.slosh.n)
        return dict(K=K, M=M, dof_labels=self.dof_labels, label_dofs=self.label_dofs,
                    points=self.points, point_coords=self.point_coords.copy(), nodes=self.nodes.copy(),
                    cells=self.cells.copy(), cell_type=self.cell_type, field_map=T,
                    line_cells=None if self.line_cells is None else self.line_cells.copy())

    def pad_dofs(self, x: np.ndarray) -> np.ndarray:
        """A vector (n_dof,) or rows (k, n_dof) over the model's DOFs extended with zeros over
        the slosh pendulums' DOFs (the component's DOF vector)."""
        x = np.asarray(x, float)
        if self.slosh is None:
            return x
        return np.concatenate([x, np.zeros(x.shape[:-1] + (self.slosh.n,))], axis=-1)

    def slosh_fields(self) -> dict | None:
        """Keyword fields of ``reduction.slosh.SloshDOFs`` of the model's slosh pendulums
        (their DOFs after the model's n_dof), or None without them."""
        S = self.slosh
        if S is None:
            return None
        n = self.n_dof
        stretch = sp.hstack([-S.R, sp.identity(S.n, format="csr")], format="csr")
        return dict(names=S.names, liquid=S.liquid, dofs=n + np.arange(S.n), mass=S.mass.copy(),
                    stiffness=S.stiffness.copy(), frequency=S.frequency.copy(),
                    gravity=np.array([S.gravity[g] for g in S.liquid]), direction=S.direction.copy(),
                    position=S.position.copy(), stretch=stretch, wave_per_force=S.wave_per_force.copy())

    def liquid_fields(self) -> dict | None:
        """Keyword fields of ``reduction.liquid.LiquidMass`` of the model's hydroelastic
        liquids (cavity volume rows named by liquid group), over the component's DOFs, or
        None without liquids."""
        if self.liquid is None:
            return None
        out = self.liquid.liquid_fields(self.liquid_volume_rows)
        if self.slosh is not None:
            for key in ("G", "volume_rows"):
                out[key] = _pad_columns(out[key], self.slosh.n)
        return out


def _pad_columns(A: sp.spmatrix, k: int) -> sp.csr_matrix:
    """A with k zero columns appended (the slosh pendulums' DOFs): the same CSR arrays, a
    wider shape."""
    A = sp.csr_matrix(A)
    return sp.csr_matrix((A.data, A.indices, A.indptr), shape=(A.shape[0], A.shape[1] + k))


# ---- parts -------------------------------------------------------------------------------
def _solid_part(tm: TaggedMesh, materials: dict, degree: int) -> Part:
    from dolfinx import fem

    from .elasticity import NEARLY_INCOMPRESSIBLE_NU, mass_form, material_fields, stiffness_form

    E, nu, rho = material_fields(tm, materials)          # checks every material first
    for name, mat in materials.items():
        if degree < 2 and float(mat.nu) >= NEARLY_INCOMPRESSIBLE_NU:
            raise InputError(f"volume {name!r}: material {mat.name!r} (nu = {float(mat.nu):g}) is nearly "
                             "incompressible and needs degree 2 ([model] degree = 2): P1 tetrahedra lock")
    V = fem.VectorFunctionSpace(tm.mesh, ("CG", degree))
    imap = V.dofmap.index_map
    n_all = imap.size_local + imap.num_ghosts
    X = V.tabulate_dof_coordinates()[:n_all]
    part = Part("solid", tm, V, (E, nu, rho), np.repeat(X, 3, axis=0), np.tile(np.arange(3), n_all),
                3 * imap.size_local, pb.assemble_matrix(stiffness_form(V, E, nu)),
                pb.assemble_matrix(mass_form(V, rho)))
    if part.K.getOwnershipRange() != (3 * imap.local_range[0], 3 * imap.local_range[1]):
        raise RuntimeError("unexpected PETSc row layout of the assembled stiffness")
    return part


def _shell_part(tm: TaggedMesh, materials: dict, thickness: dict, bending: dict) -> Part:
    from . import shell

    fields = shell.shell_fields(tm, materials, thickness, bending)
    W = shell.shell_space(tm.mesh)
    coords, comp = shell.dof_table(W)
    return Part("shell", tm, W, fields, coords, comp, W.dofmap.index_map.size_local,
                pb.assemble_matrix(shell.stiffness_form(W, fields)), pb.assemble_matrix(shell.mass_form(W, fields)))


#: how each kind of part is built from its TaggedMesh and the geometry
PART_BUILDERS = {
    "solid": lambda tm, geo, degree: _solid_part(tm, {g: m for g, m in geo.volumes.items() if g not in geo.shells},
                                                 degree),
    "shell": lambda tm, geo, degree: _shell_part(tm, {g: geo.volumes[g] for g in geo.shells}, geo.shells,
                                                 geo.shell_bending),
}


def _smeared_masses(parts: list[Part], geometry, comm: MPI.Comm, lumped: bool) -> None:
    """Add each smeared mass (mass / total area per unit area) to the parts' M: on the
    shell triangles of the surface where it has any, else on the solid's exterior facets."""
    import ufl
    from dolfinx import fem

    from . import elasticity, shell

    for sm in geometry.smeared_masses:
        if not np.isfinite(sm.mass) or sm.mass < 0:
            raise InputError(f"smeared mass on {sm.surface!r}: mass {sm.mass!r} kg must be >= 0")
        on = [p for p in parts if sm.surface in p.tagged.surface_tags]
        if not on:
            names = sorted({n for p in parts for n in p.tagged.surface_tags})
            raise InputError(f"smeared mass surface {sm.surface!r}: no physical surface {sm.surface!r} in mesh "
                             f"{parts[0].tagged.path!r} (has: {', '.join(names) or 'none'})")
        measures, area = {}, {}
        for p in on:
            tags = p.tagged.surface_tags[sm.surface]
            m = ufl.Measure("dx" if p.kind == "shell" else "ds", domain=p.tagged.mesh, subdomain_data=tags)(1)
            measures[p.kind] = m
            area[p.kind] = comm.allreduce(fem.assemble_scalar(fem.form(fem.Constant(p.tagged.mesh, 1.0) * m)),
                                          op=MPI.SUM)
        use = "shell" if area.get("shell", 0.0) > 0 else "solid"
        if area.get(use, 0.0) <= 0.0:
            raise InputError(f"smeared mass surface {sm.surface!r}: zero exterior area "
                             "(an interior solid surface cannot carry surface mass here)")
        p = next(q for q in on if q.kind == use)
        if use == "shell":
            if lumped:
                raise InputError(f"smeared mass on {sm.surface!r}: lumped smeared mass needs P1 solids, "
                                 "not shells (P2 row sums vanish at vertices)")
            pb.add_subset(p.M, pb.assemble_matrix(shell.surface_mass_form(p.V, sm.mass / area[use], measures[use])))
            continue
        Ms = pb.assemble_matrix(elasticity.surface_mass_form(p.V, p.tagged.surface_tags[sm.surface],
                                                             sm.mass / area[use]))
        if lumped:
            pb.add_row_sums_to_diagonal(p.M, Ms)     # P1 row sums = mass/3 per triangle vertex
        else:
            pb.add_subset(p.M, Ms)


# ---- nodes and independent DOFs ------------------------------------------------------------
@dataclass
class _Nodes:
    """The parts' DOFs gathered into nodes by position, nodes in PETSc rank order."""

    xyz: np.ndarray                # (n_nodes, 3) m
    comps: np.ndarray              # (n_nodes, 6) bool: components the node carries
    owner: np.ndarray              # (n_nodes,) rank that owns the node's independent DOFs
    label: list                    # per part: node of each of the part's global DOFs
    in_part: np.ndarray            # (n_nodes, n_parts) bool: the node has DOFs of the part
    parent: np.ndarray = None      # (n_nodes, 2): translations = mean of these two nodes' (-1: own)
    dependent: tuple = None        # interpolation patches: (DOF ids node*6+comp, their rows of T)

    @property
    def n(self) -> int:
        return self.xyz.shape[0]


def _gather_nodes(comm: MPI.Comm, parts: list[Part]) -> _Nodes:
    """Cluster the owned DOFs of all parts and ranks by position (every rank, same result).

    Node order = order of first appearance with DOFs sorted by (rank, part, DOF): for one
    solid part that is the dolfinx node order, so the DOF numbering is the plain one."""
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    X, C, key = [], [], []
    for k, p in enumerate(parts):
        for r, (x, c) in enumerate(comm.allgather((p.coords[:p.n_own], p.comp[:p.n_own]))):
            X.append(np.asarray(x).reshape(-1, 3))
            C.append(np.asarray(c, np.int64))
            key.append(np.column_stack([np.full(c.size, r), np.full(c.size, k), np.arange(c.size)]))
    X, C, key = np.vstack(X), np.concatenate(C), np.vstack(key)
    n = C.size
    tol = 1e-9 * max(float(np.linalg.norm(X.max(axis=0) - X.min(axis=0))), 1e-300) if n else 1.0
    pairs = cKDTree(X).query_pairs(tol, output_type="ndarray")
    graph = sp.coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    n_lab, lab = connected_components(graph, directed=False)
    seq = np.lexsort((key[:, 2], key[:, 1], key[:, 0]))
    first = np.full(n_lab, n, dtype=np.int64)
    np.minimum.at(first, lab[seq], np.arange(n))
    new = np.empty(n_lab, dtype=np.int64)
    new[np.argsort(first)] = np.arange(n_lab)
    lab = new[lab]
    head = seq[np.sort(first)]                      # first DOF of each node, in node order
    rows, counts = np.unique(np.column_stack([lab, key[:, 1], C]), axis=0, return_counts=True)
    if np.any(counts > 1):
        where = X[head[rows[np.argmax(counts > 1), 0]]]
        raise InputError(f"mesh {parts[0].tagged.path!r}: coincident nodes within one part at "
                         f"{np.round(where, 6).tolist()} m (parts are joined by node position)")
    comps = np.zeros((n_lab, 6), bool)
    comps[lab, C] = True
    in_part = np.zeros((n_lab, len(parts)), bool)
    in_part[lab, key[:, 1]] = True
    sizes = np.concatenate([[0], np.cumsum(np.bincount(key[:, 1], minlength=len(parts)))])
    return _Nodes(X[head], comps, key[head, 0], [lab[sizes[k]:sizes[k + 1]] for k in range(len(parts))], in_part,
                  np.full((n_lab, 2), -1, dtype=np.int64))


def _tie_midpoints(nodes: _Nodes, parts: list[Part], cells: dict) -> None:
    """P1 solids with shells: a shell edge-midpoint node on an edge of the solid mesh has no
    solid node to share, so its translations are tied to the mean of the edge's two end
    nodes (the P1 solid's own displacement there): nodes.parent."""
    if "shell" not in cells or "solid" not in cells or cells["solid"].shape[1] != 4:
        return
    solid = [k for k, p in enumerate(parts) if p.kind == "solid"][0]
    tets = cells["solid"]
    edges = np.unique(np.sort(np.vstack([tets[:, [i, j]] for i in range(4) for j in range(i + 1, 4)]), axis=1), axis=0)
    tri = cells["shell"]
    trip = np.vstack([tri[:, [3, 0, 1]], tri[:, [4, 1, 2]], tri[:, [5, 2, 0]]])      # (midpoint, a, b)
    on = nodes.in_part[:, solid]
    cand = trip[~on[trip[:, 0]] & on[trip[:, 1]] & on[trip[:, 2]]]
    if cand.size:
        from .mesh import _rows_in

        cand = cand[_rows_in(cand[:, 1:], edges)]
        nodes.parent[cand[:, 0]] = cand[:, 1:]


def _group_nodes(comm: MPI.Comm, parts: list[Part], nodes: _Nodes, name: str, role: str) -> np.ndarray:
    """Nodes (every rank) on the entities of surface or curve group ``name`` in any part."""
    found, local = False, [np.zeros(0, np.int64)]
    for k, p in enumerate(parts):
        dofs = p.group_dofs(name)
        if dofs is not None:
            found = True
            local.append(nodes.label[k][p.global_dofs(dofs)])
    if not found:
        have = sorted({n for p in parts for n in (*p.tagged.surface_tags, *p.tagged.curve_tags)})
        raise InputError(f"{role} {name!r}: no physical surface {name!r} in mesh {parts[0].tagged.path!r} "
                         f"(has: {', '.join(have) or 'none'})")
    return np.unique(np.concatenate(comm.allgather(np.unique(np.concatenate(local)))))


def _roles(comm: MPI.Comm, parts: list[Part], nodes: _Nodes, patches: list, clamped: tuple) -> np.ndarray:
    """FREE, CLAMPED or the rigid patch number of every node; InputError on overlaps."""
    role = np.full(nodes.n, FREE, dtype=np.int64)
    pnames = [pt.name for pt in patches]
    for p, name in enumerate(pnames):
        if patches[p].nodes is not None:
            continue
        on = _group_nodes(comm, parts, nodes, name, "patch")
        if on.size < 3 and not (on.size and nodes.comps[on].all()):      # (one beam node carries all six)
            raise InputError(f"patch {name!r}: its surface has {on.size} nodes; a rigid spider needs >= 3 "
                             "(or a node with rotations: a beam's)")
        clash = role[on][role[on] >= 0]
        if clash.size:
            raise InputError(f"patches {pnames[int(clash[0])]!r} and {name!r} share nodes; "
                             "a node can hang on one rigid spider only")
        role[on] = p
    for surface in clamped:
        on = _group_nodes(comm, parts, nodes, surface, "clamped surface")
        if on.size == 0:
            raise InputError(f"clamped surface {surface!r} has no nodes in mesh {parts[0].tagged.path!r}")
        on_patch = role[on][role[on] >= 0]
        if on_patch.size:
            raise InputError(f"clamped surface {surface!r} shares nodes with patch {pnames[int(on_patch[0])]!r}; "
                             "a node is either clamped or on a spider")
        role[on] = CLAMPED
    return role


def _interpolation_nodes(comm, parts, nodes: _Nodes, role, patches: list) -> list:
    """(patch number, nodes) of every interpolation patch: its group's nodes within reach
    but tied midpoints (they follow their edge's end nodes); InputError if one of them is
    clamped or on a rigid spider."""
    out = []
    for p, pt in enumerate(patches):
        if pt.nodes is None:
            continue
        on = _group_nodes(comm, parts, nodes, pt.nodes, f"patch {pt.name!r}: nodes group")
        on = on[(np.linalg.norm(nodes.xyz[on] - pt.ref_point, axis=1) <= pt.reach) & (nodes.parent[on, 0] < 0)]
        bad = on[role[on] != FREE]
        if bad.size:
            raise InputError(f"patch {pt.name!r}: node at {np.round(nodes.xyz[bad[0]], 4).tolist()} m of group "
                             f"{pt.nodes!r} is clamped or on a rigid spider; an interpolation needs free nodes")
        out.append((p, on))
    return out


def _dependent_dofs(comm: MPI.Comm, interp: list, nodes: _Nodes, patches: list) -> tuple:
    """The interpolation patches' dependent DOFs (fem.spiders.eliminate_interpolations):
    (their ids node*6+comp, the elimination (Dr, n ids, Dn)), or None without any. Chosen on
    rank 0 and broadcast: a pivoted QR on a symmetric ring ties columns, and every rank must
    make the same choice; an InputError is raised on every rank."""
    if not interp:
        return None
    out = None
    if comm.rank == 0:
        try:
            fits = [interpolation_fit(nodes.xyz[on], patches[p].ref_point, f"patch {patches[p].name!r}")
                    for p, on in interp]
            ring = [(on[:, None] * 6 + np.arange(3)).ravel() for _, on in interp]
            out = eliminate_interpolations(fits, ring, "interpolation patches "
                                           + ", ".join(repr(patches[p].name) for p, _ in interp))
        except InputError as exc:
            out = str(exc)
    out = comm.bcast(out, root=0)
    if isinstance(out, str):
        raise InputError(out)
    m, n, Dr, Dn = out
    return m, (Dr, n, Dn, [p for p, _ in interp])


def _dependent_rows(elim: tuple, slot: np.ndarray, n_keep: int, n_dof: int) -> sp.csr_matrix:
    """Rows of T of the dependent DOFs: u_m = Dr u_ref + Dn u_n."""
    Dr, n, Dn, pnum = elim
    n_cols = slot.ravel()[n]
    if np.any(n_cols < 0):
        raise RuntimeError("interpolation patch: an independent ring DOF has no model DOF")
    cols = np.concatenate([(n_keep + 6 * np.asarray(pnum)[:, None] + np.arange(6)).ravel(), n_cols])
    A = sp.coo_matrix(np.hstack([Dr, Dn]))
    return sp.csr_matrix((A.data, (A.row, cols[A.col])), shape=(Dr.shape[0], n_dof))


def _slots(nodes: _Nodes, role: np.ndarray, dependent: np.ndarray | None = None) -> np.ndarray:
    """(n_nodes, 6) independent DOF of each (free node, component), -1 elsewhere;
    ``dependent``: DOF ids node*6+comp that interpolation patches eliminate."""
    carried = nodes.comps & (role == FREE)[:, None]
    carried[nodes.parent[:, 0] >= 0, :3] = False           # tied midpoint translations
    if dependent is not None:
        carried.ravel()[dependent] = False
    slot = np.cumsum(carried.ravel()).reshape(-1, 6) - 1
    return np.where(carried, slot, -1)


def build_model(geometry, degree: int = 1, comm: MPI.Comm = MPI.COMM_WORLD,
                lumped_smeared_mass: bool = False, liquid_degree: int = 1, convective: str = "free") -> FEModel:
    """FE model of a ``meshes.spec.Geometry`` (or the path of its JSON file).

    ``degree``: 1 or 2 (Lagrange, solid part; shells are P2 x CR). ``lumped_smeared_mass``:
    non-structural surface mass on solids lumped to the nodes by row sums (P1 only: P2 row
    sums vanish at vertices) instead of the consistent surface mass. Hydroelastic liquids
    (``Geometry.liquids``) become ``FEModel.liquid`` (fem.liquid: pressure P_``liquid_degree``,
    coupled through the wall's P1 (P1 solids) or P2 translations), an added mass that K and M
    do not hold; ``convective``: ``"free"`` (the p = 0 liquid's sloshing part moves freely of
    the tank laterally), ``"wall"`` (that part is lumped on the wetted wall laterally, in
    M, so that the liquid's rigid-body mass and c.g. are a rigid liquid's) or ``"slosh"``
    (that part is the liquids' slosh modes, as tank-referenced pendulums on extra DOFs after
    the model's: fem.slosh.SloshPendulums, ``FEModel.slosh``; what the modes kept do not carry
    is lumped on the wall as with "wall").
    """
    if convective not in ("free", "wall", "slosh"):
        raise InputError(f"model: convective must be 'free', 'wall' or 'slosh' (got {convective!r})")
    if isinstance(geometry, (str, Path)):
        from liftoff.meshes.spec import Geometry
        geometry = Geometry.load(geometry)
    name = str(geometry.name)
    if degree not in (1, 2):
        raise InputError(f"model {name!r}: degree {degree!r} not supported (use 1 or 2)")
    if lumped_smeared_mass and degree != 1:
        raise InputError(f"model {name!r}: lumped smeared mass needs degree 1")
    solid_tm = shell_tm = liquid_tm = None
    if geometry.volumes or geometry.liquids:
        solid_tm, shell_tm, liquid_tm = read_mesh_parts(geometry.msh_path, comm, tuple(geometry.shells),
                                                        liquids=tuple(geometry.liquids))
    meshes = {"solid": solid_tm, "shell": shell_tm}
    solids = [g for g in geometry.volumes if g not in geometry.shells]
    if meshes["solid"] is None and solids:
        raise InputError(f"volume group {solids[0]!r} is not a physical volume of mesh {geometry.msh_path!r} "
                         "(it has none)")
    parts = [PART_BUILDERS[k](tm, geometry, degree) for k, tm in meshes.items() if tm is not None]
    if geometry.beams:
        from .beam import beam_part
        parts.append(beam_part(geometry, comm, midpoints=bool(geometry.shells) or degree == 2))
    _smeared_masses(parts, geometry, comm, lumped_smeared_mass)
    patches = list(geometry.patches)
    pnames = [p.name for p in patches]
    if len(set(pnames)) != len(pnames):
        raise InputError(f"model {name!r}: duplicate patch names in {pnames}")
    clamped = tuple(str(s) for s in geometry.clamped)
    nodes = _gather_nodes(comm, parts)
    part_cells = {p.kind: _part_cells(comm, p, nodes.label[k]) for k, p in enumerate(parts)}
    _tie_midpoints(nodes, parts, part_cells)
    role = _roles(comm, parts, nodes, patches, clamped)
    dep = _dependent_dofs(comm, _interpolation_nodes(comm, parts, nodes, role, patches), nodes, patches)
    slot = _slots(nodes, role, None if dep is None else dep[0])
    n_keep = int(slot.max()) + 1 if slot.size and slot.max() >= 0 else 0
    ref_coords = np.array([np.asarray(p.ref_point, float).reshape(3) for p in patches]).reshape(-1, 3)
    n_dof = n_keep + 6 * len(patches)
    if dep is not None:
        nodes.dependent = (dep[0], _dependent_rows(dep[1], slot, n_keep, n_dof))
    pressurised = _pressure_stiffened(parts, geometry)
    K, M = _reduce(comm, parts, nodes, role, slot, ref_coords, n_keep, n_dof)
    _point_masses(M, geometry, pnames, n_keep)
    T = _field_map(nodes, role, slot, ref_coords, n_keep, n_dof)
    free = np.flatnonzero(slot.ravel() >= 0)
    dof_node, dof_comp = free // 6, free % 6
    dof_coords = np.vstack([nodes.xyz[dof_node], np.repeat(ref_coords, 6, axis=0)])
    dof_comp = np.concatenate([dof_comp, np.tile(np.arange(6), len(patches))]).astype(np.int64)
    if pressurised and not clamped:       # rigid modes exactly free (fem.prestress)
        from .prestress import relative_to_reference
        K = relative_to_reference(K, dof_rb(dof_coords - ref_coords[0], dof_comp), n_keep + np.arange(6))
    dof_node = np.concatenate([dof_node, -np.ones(6 * len(patches), dtype=np.int64)])
    cells, cell_type, line_cells = _output_cells(part_cells, nodes.xyz)
    liquid, rows, slosh = None, {}, None
    if liquid_tm is not None:
        liquid, rows, slosh = _liquid(comm, geometry, liquid_tm, parts, nodes.xyz, T, M, dof_coords, dof_comp,
                                      2 if solid_tm is None or degree == 2 else 1, liquid_degree, convective)
    return FEModel(name=name, comm=comm, parts=tuple(parts), degree=degree, K=K, M=M, points=tuple(pnames),
                   point_coords=ref_coords, dof_coords=dof_coords, dof_comp=dof_comp, dof_node=dof_node,
                   nodes=nodes.xyz, cells=cells, cell_type=cell_type, T=T, clamped=clamped, liquid=liquid,
                   liquid_volume_rows=rows, slosh=slosh, line_cells=line_cells)


def _pressure_stiffened(parts: list[Part], geometry) -> bool:
    """Add K_G + K_L of the liquids' ullage pressures (fem.prestress) to the shell part's K;
    whether there were any. A free model needs a reference point (its K is then taken
    relative to the first one's rigid motion)."""
    from .prestress import prestress_stiffness, pressurised

    if not pressurised(geometry):
        return False
    if not geometry.patches and not geometry.clamped:
        raise InputError(f"model {geometry.name!r}: ullage pressures on a free-free model need a reference point "
                         "(patch)")
    wall = next((p for p in parts if p.kind == "shell"), None)
    if wall is None:
        raise InputError(f"geometry {geometry.name!r}: ullage pressures need a shell wall (it has none)")
    wall.K = pb.add(wall.K, prestress_stiffness(wall, geometry))
    return True


def _liquid(comm, geometry, liquid_tm, parts, nodes, T, M, dof_coords, dof_comp, coupling_degree: int,
            liquid_degree: int, convective: str):
    """The model's liquids (fem.liquid.model_liquid), their cavity rows and, with ``convective
    = "slosh"``, their slosh pendulums (fem.slosh); with "wall" or "slosh", their convective
    part (less what the pendulums carry) as lateral mass on the wetted wall added to M
    (fem.liquid.convective_mass)."""
    from liftoff.core.rigid import dof_rb

    from .liquid import convective_mass, model_liquid

    if comm.size > 1:       # the liquid is small: every process holds all of it (serial operator)
        liquid_tm = read_mesh_parts(geometry.msh_path, MPI.COMM_SELF, tuple(geometry.shells),
                                    liquids=tuple(geometry.liquids))[2]
    liquid, rows = model_liquid(liquid_tm, geometry, parts, nodes, T, coupling_degree, liquid_degree,
                                slosh=convective == "slosh")
    slosh = None
    if convective == "slosh":
        from .slosh import slosh_pendulums

        slosh = slosh_pendulums(liquid_tm, geometry, nodes, T)
    if convective in ("wall", "slosh"):
        pb.add_csr(M, convective_mass(liquid, liquid_tm, geometry, nodes, T, dof_rb(dof_coords, dof_comp),
                                      None if slosh is None else slosh.carried()))
    return liquid, rows, slosh


def _reduce(comm, parts, nodes, role, slot, ref_coords, n_keep, n_dof):
    """K_r = sum T_p^T K_p T_p (and M_r) over the parts; sets each part's T, frees K_p, M_p."""
    counts = np.bincount(nodes.owner[slot.max(axis=1) >= 0],
                         weights=(slot >= 0).sum(axis=1)[slot.max(axis=1) >= 0], minlength=comm.size)
    n_cols_local = int(counts[comm.rank]) + (6 * len(ref_coords) if comm.rank == comm.size - 1 else 0)
    K = M = None
    for k, p in enumerate(parts):
        lab = nodes.label[k][p.global_dofs(np.arange(p.n_own))]
        rows = _rows(nodes, role, slot, ref_coords, n_keep, n_dof, lab, p.comp[:p.n_own])
        p.T = pb.csr_matrix(comm, p.n_own, n_cols_local, n_dof, rows)
        Kp, Mp = pb.ptap(p.K, p.T), pb.ptap(p.M, p.T)
        p.K.destroy()
        p.M.destroy()
        p.K = p.M = None
        K, M = (Kp, Mp) if K is None else (pb.add(K, Kp), pb.add(M, Mp))
    return K, M


def _point_masses(M, geometry, pnames: list[str], ref_first: int) -> None:
    for pm in geometry.point_masses:
        if pm.patch not in pnames:
            raise InputError(f"point mass {pm.name!r}: unknown patch {pm.patch!r} (has: {', '.join(pnames) or 'none'})")
        J = np.asarray(pm.inertia, float).reshape(3, 3)
        if not np.isfinite(pm.mass) or pm.mass < 0:
            raise InputError(f"point mass {pm.name!r}: mass {pm.mass!r} kg must be >= 0")
        if not np.allclose(J, J.T) or np.linalg.eigvalsh(0.5 * (J + J.T)).min() < -1e-12 * max(1.0, np.abs(J).max()):
            raise InputError(f"point mass {pm.name!r}: inertia must be symmetric positive semi-definite (kg m^2)")
        block = np.zeros((6, 6))
        block[:3, :3] = pm.mass * np.eye(3)
        block[3:, 3:] = J
        pb.add_block(M, ref_first + 6 * pnames.index(pm.patch) + np.arange(6), block)


def _own_rows(nodes: _Nodes, role, slot, ref_coords, n_keep: int, n_dof: int, node, comp) -> sp.csr_matrix:
    """Rows of T for the DOFs (node, comp) by the node's own role: spiders and clamps
    (fem.spiders), interpolation patches' dependent DOFs, else one independent DOF."""
    rows = transformation_rows(nodes.xyz[node], comp, role[node], slot[node, comp], ref_coords, n_keep, n_dof)
    if nodes.dependent is not None:
        ids, D = nodes.dependent
        key = node * 6 + comp
        j = np.minimum(np.searchsorted(ids, key), ids.size - 1)
        hit = np.flatnonzero(ids[j] == key)
        if hit.size:
            pick = sp.csr_matrix((np.ones(hit.size), (hit, np.arange(hit.size))), shape=(node.size, hit.size))
            rows = sp.csr_matrix(rows + pick @ D[j[hit]])
    return rows


def _rows(nodes: _Nodes, role, slot, ref_coords, n_keep: int, n_dof: int, node, comp) -> sp.csr_matrix:
    """Rows of T for the DOFs (node, comp): :func:`_own_rows`, and a tied midpoint's
    translations as the mean of its two parents' rows."""
    rows = _own_rows(nodes, role, slot, ref_coords, n_keep, n_dof, node, comp)
    i = np.flatnonzero((nodes.parent[node, 0] >= 0) & (comp < 3) & (role[node] == FREE))
    if i.size:
        half = [_own_rows(nodes, role, slot, ref_coords, n_keep, n_dof, a, comp[i])
                for a in (nodes.parent[node[i], 0], nodes.parent[node[i], 1])]
        pick = sp.csr_matrix((np.full(i.size, 0.5), (i, np.arange(i.size))), shape=(node.size, i.size))
        rows = sp.csr_matrix(rows + pick @ (half[0] + half[1]))
    return rows


def _field_map(nodes: _Nodes, role, slot, ref_coords, n_keep: int, n_dof: int) -> sp.csr_matrix:
    """T (3 n_nodes x n_dof): the nodal translations of every node (every rank)."""
    return _rows(nodes, role, slot, ref_coords, n_keep, n_dof, np.repeat(np.arange(nodes.n), 3),
                 np.tile(np.arange(3), nodes.n))


_TET10_EDGE = {(0, 1): 4, (1, 2): 5, (0, 2): 6, (0, 3): 7, (1, 3): 8, (2, 3): 9}    # VTK quadratic tet


def _part_cells(comm: MPI.Comm, part: Part, label: np.ndarray) -> np.ndarray:
    """All cells of a part (VTK order, every rank) as node indices."""
    from dolfinx.plot import create_vtk_mesh

    if part.kind == "beam":           # every rank holds the elements; rank 0 the DOFs
        cells = label[part.global_dofs(6 * part.elements.ravel())].reshape(-1, 2) if part.n_own else None
        return comm.bcast(cells, root=0)

    V, to_parent = (part.V, None) if part.kind == "solid" else part.V.sub(0).collapse()
    topology, _, _ = create_vtk_mesh(V)
    k = V.dofmap.dof_layout.num_dofs
    blocks = np.asarray(topology).reshape(-1, k + 1)[:, 1:].astype(np.int64)
    local = 3 * blocks if to_parent is None else np.asarray(to_parent, np.int64)[3 * blocks]
    cells = label[part.global_dofs(local.ravel())].reshape(-1, k)
    return np.vstack(comm.allgather(cells)).reshape(-1, k)


def _boundary_faces(tets: np.ndarray, xyz: np.ndarray) -> np.ndarray:
    """Exterior faces of tetra/tetra10 cells as triangle/triangle6 (VTK order), numbered
    anticlockwise seen from outside (the tet's fourth node behind the face), so that
    renderers see one consistent outward surface."""
    faces = []
    for a, b, c, d in ((0, 1, 2, 3), (0, 1, 3, 2), (0, 2, 3, 1), (1, 2, 3, 0)):
        f = [a, b, c] + ([_TET10_EDGE[(a, b)], _TET10_EDGE[(b, c)], _TET10_EDGE[(a, c)]] if tets.shape[1] == 10 else [])
        g = [a, c, b] + ([_TET10_EDGE[(a, c)], _TET10_EDGE[(b, c)], _TET10_EDGE[(a, b)]] if tets.shape[1] == 10 else [])
        p = xyz[tets[:, [a, b, c, d]]]
        inward = np.einsum("ij,ij->i", np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), p[:, 3] - p[:, 0]) > 0
        faces.append(np.where(inward[:, None], tets[:, g], tets[:, f]))
    faces = np.vstack(faces)
    _, inv, count = np.unique(np.sort(faces[:, :3], axis=1), axis=0, return_inverse=True, return_counts=True)
    return faces[count[inv.ravel()] == 1]


def _output_cells(cells: dict, xyz: np.ndarray) -> tuple[np.ndarray, str, np.ndarray | None]:
    """(cells, meshio cell type, line cells) for pictures and VTU from {part kind: cells}:
    the solid's tets, the shell's triangle6, or, for both, the solid's exterior faces
    (outward) with the shell triangles (split into four 3-node triangles next to P1
    solids); a model of beams alone: its 2-node lines as the cells; beams beside shells or
    solids: their lines as the third item (a second block), else None."""
    lines = None
    if "beam" in cells:
        cells = dict(cells)
        lines = cells.pop("beam")
        if not cells:
            return lines, "line", None
    if len(cells) == 1:
        kind, c = next(iter(cells.items()))
        return c, {4: "tetra", 10: "tetra10", 6: "triangle6"}[c.shape[1]], lines
    faces, shells = _boundary_faces(cells["solid"], xyz), cells["shell"]
    if faces.shape[1] == 6:
        return np.vstack([faces, shells]), "triangle6", lines
    split = np.vstack([shells[:, s] for s in ((0, 3, 5), (3, 1, 4), (5, 4, 2), (3, 4, 5))])
    return np.vstack([faces, split]), "triangle", lines
