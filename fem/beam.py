"""The beam part of a model (issue 26): 3-D Timoshenko beams on the line elements of a
mesh's beam curve groups (``Geometry.beams``, meshes.spec.BeamGroup), 6 DOFs a node
(Tx Ty Tz Rx Ry Rz, global frame), element matrices of liftoff.core.beam (Przemieniecki's
exact Timoshenko stiffness and consistent mass, rotary inertia included).

Ties. The beam's nodes are gathered with the other parts' nodes by position (fem.model),
as in any FE program: on a shell the beam shares the translations of the nodes it runs
through and, because each gmsh line is split at its midpoint when the model has shells
(or P2 solids), the shell's edge-midpoint rotations too (fem.shell keeps its
Crouzeix-Raviart rotations there): the beam is welded to the wall along its length. On a
P1 solid it shares translations only (a solid has no rotations); a straight beam on a
solid whose twist nothing else holds is a mechanism the eigensolver reports. Clamps and
patches may name the beam's curve groups or physical points.

Offsets (Nastran CBEAM's WA/WB): the beam's axis runs ``e = offset + radial_offset e_r``
from its nodes (e_r: away from the BeamGroup's axis at the node); the element's matrices
are those of the offset axis, carried to the nodes by the rigid link of each end,
u_axis = u_node + theta x e, i.e. k = B^T k_axis B with B = [[I, -[e]x], [0, I]] per node
(Przemieniecki, ch. 5; the same rigid-body kinematics as fem.spiders).

Orientation: ``vref`` global, or "radial" (e_r at the element's midpoint: local y radial)
or "tangential" (axis x e_r: local y tangential, z radial: a stringer along a wall with its
web's depth radial). Units SI: m, Pa, kg/m^3.

Layout: rank 0 holds every beam DOF (beams are small next to the shells and solids);
other ranks hold none. Node j of the part owns local DOFs 6 j .. 6 j + 5.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from mpi4py import MPI

from liftoff.core.beam import assemble_frame, beam_element
from liftoff.core.errors import InputError
from liftoff.core.rigid import skew

from . import petsc_backend as pb
from .mesh import BeamLines, read_beam_lines
from .model import Part


@dataclass
class BeamPart(Part):
    """The beam part: ``elements`` (m, 2) its 2-node elements as part nodes (every rank),
    ``xyz`` (n, 3) its nodes (m, every rank), ``element_group`` each element's group."""

    elements: np.ndarray = None
    xyz: np.ndarray = None
    element_group: np.ndarray = None     # (m,) each element's group index into ``fields``

    def global_dofs(self, local: np.ndarray) -> np.ndarray:
        """Rank 0 owns every beam DOF: local = global there (other ranks have none)."""
        return np.asarray(local, np.int64)

    def group_dofs(self, name: str) -> np.ndarray | None:
        """DOFs of the beam nodes on curve or point group ``name`` (with the midpoints of a
        beam curve's lines); None if no such group."""
        on = self.tagged.node_groups.get(name)
        if on is None:
            return None
        on = np.asarray(on, np.int64)
        if name in self.tagged.names and self.xyz.shape[0] > self.tagged.x.shape[0]:
            g = self.tagged.names.index(name)
            on = np.concatenate([on, self.tagged.x.shape[0] + np.flatnonzero(self.tagged.group == g)])
        if self.n_own == 0:
            return np.zeros(0, np.int64)
        return (on[:, None] * 6 + np.arange(6)).ravel()


def _radial(p: np.ndarray, grp, what: str) -> np.ndarray:
    """Unit vectors (k, 3) away from ``grp``'s axis at points ``p`` (k, 3)."""
    d = np.asarray(grp.axis_direction) / np.linalg.norm(grp.axis_direction)
    r = p - np.asarray(grp.axis_point)
    r = r - np.outer(r @ d, d)
    n = np.linalg.norm(r, axis=1)
    if np.any(n < 1e-9 * max(1.0, float(np.abs(p).max()))):
        bad = p[np.argmin(n)]
        raise InputError(f"{what}: a node at {np.round(bad, 4).tolist()} m lies on the axis, where 'radial' "
                         "(vref or radial_offset) has no direction")
    return r / n[:, None]


def beam_matrices(x: np.ndarray, elements: np.ndarray, element_group: np.ndarray, groups: list,
                  names: tuple) -> tuple[sp.csr_matrix, sp.csr_matrix]:
    """(K, M) (6 n x 6 n, CSR) of beam elements ``elements`` (m, 2) on nodes ``x`` (n, 3);
    element k has BeamGroup ``groups[element_group[k]]`` (module docstring: offsets,
    orientation)."""
    return assemble_frame(x.shape[0], (el for g, grp in enumerate(groups)
                                       for el in _group_elements(x, elements[element_group == g], grp, names[g])))


def _axis_offsets(x: np.ndarray, el: np.ndarray, grp, what: str) -> np.ndarray:
    """(n, 3) the offset of one BeamGroup's axis from each node (module docstring: offset plus
    radial_offset e_r, at the nodes ``el`` uses)."""
    e = np.broadcast_to(np.asarray(grp.offset, float), x.shape).copy()
    if grp.radial_offset != 0.0:
        used = np.unique(el)
        e[used] += grp.radial_offset * _radial(x[used], grp, what)
    return e


def _offset_link(ea: np.ndarray, eb: np.ndarray) -> np.ndarray:
    """B (12 x 12): axis DOFs from node DOFs, u_axis = u_node + theta x e at each end."""
    B = np.eye(12)
    B[0:3, 3:6], B[6:9, 9:12] = -skew(ea), -skew(eb)
    return B


def thermal_forces(part: "BeamPart", strain_by_group: dict) -> np.ndarray:
    """(6 n,) the part's nodal forces of a uniform free thermal strain eps per beam group
    (``strain_by_group``: {group index into part.fields: eps}): f = k u_free for each
    element, k its stiffness at the nodes (offset links included) and u_free the
    homogeneous expansion of its nodes, eps (x - x_a), no rotation. By construction that
    field is stress-free (K u = f), for a member alone and for a member with the wall it lies
    on (whose own thermal load is that of the same field): the rigid offset links do not
    expand, so an offset axis is loaded by what it stretches in it (a frame inside a wall of
    radius r, offset e: N = E A eps r/(r + e), and the small bending of a polygon of offset
    chords). For a straight member whose axis is parallel to its nodes' line it is E A eps
    along the axis. A member's own bending from a through-depth gradient is not modelled
    (uniform temperature)."""
    lines = part.tagged
    x, el, grp_of = part.xyz, part.elements, part.element_group
    f = np.zeros(6 * x.shape[0])
    for g, eps in strain_by_group.items():
        mine = el[grp_of == g]
        if mine.size == 0 or eps == 0.0:
            continue
        for a, b, k, _ in _group_elements(x, mine, part.fields[g], lines.names[g]):
            u = np.zeros(12)
            u[6:9] = float(eps) * (x[b] - x[a])
            fe = k @ u
            f[6 * a:6 * a + 6] += fe[:6]
            f[6 * b:6 * b + 6] += fe[6:]
    return f


def _group_elements(x: np.ndarray, el: np.ndarray, grp, name: str):
    """(a, b, k, m) of the beam elements ``el`` (k, 2) of one BeamGroup, in global axes,
    the axis offsets carried to the nodes (module docstring)."""
    if el.size == 0:
        return
    what = f"beam curve {name!r}"
    mat, sec = grp.material, grp.section
    G = mat.E / (2 * (1 + mat.nu))
    e = _axis_offsets(x, el, grp, what)
    if isinstance(grp.vref, str):             # "radial" or "tangential", at each element's midpoint
        vref = _radial(0.5 * (x[el[:, 0]] + x[el[:, 1]]), grp, what)
        if grp.vref == "tangential":
            vref = np.cross(np.asarray(grp.axis_direction, float), vref)
    else:                                     # None: global z, or an axis off the member where it lies along z
        vref = np.broadcast_to(np.asarray((0.0, 0.0, 1.0) if grp.vref is None else grp.vref, float), (el.shape[0], 3))
    for (a, b), v in zip(el, vref):
        d = (x[b] + e[b]) - (x[a] + e[a])
        if grp.vref is not None and np.linalg.norm(np.cross(d, v)) < 1e-8 * np.linalg.norm(d) * np.linalg.norm(v):
            raise InputError(f"{what}: its orientation vref ({grp.vref if isinstance(grp.vref, str) else list(v)}) "
                             f"lies along the element from {np.round(x[a] + e[a], 4).tolist()} to "
                             f"{np.round(x[b] + e[b], 4).tolist()} m, so it sets no plane: give a vref off the "
                             "member's axis ('tangential' is for members along the axis, 'radial' for members "
                             "across it)")
        k, m = beam_element(x[a] + e[a], x[b] + e[b], mat.E, G, sec, mat.rho, v, grp.rotary, grp.nsm)
        if e[a].any() or e[b].any():
            B = _offset_link(e[a], e[b])
            k, m = B.T @ k @ B, B.T @ m @ B
        yield a, b, k, m


def split_at_midpoints(x: np.ndarray, lines: np.ndarray, group: np.ndarray):
    """Each line a-b as two elements a-m, m-b with m = (a + b)/2 appended to the nodes (the
    P2 edge-midpoint node of the shells and solids the line runs along)."""
    mid = x.shape[0] + np.arange(lines.shape[0])
    xm = np.vstack([x, 0.5 * (x[lines[:, 0]] + x[lines[:, 1]])])
    el = np.vstack([np.column_stack([lines[:, 0], mid]), np.column_stack([mid, lines[:, 1]])])
    return xm, el, np.concatenate([group, group])


def beam_part(geometry, comm: MPI.Comm, midpoints: bool) -> BeamPart:
    """The beam part of ``geometry`` (module docstring); ``midpoints``: split every line at
    its midpoint (models with shells or P2 solids)."""
    lines: BeamLines = read_beam_lines(geometry.msh_path, tuple(geometry.beams), comm)
    x, el, grp = lines.x, lines.lines, lines.group
    if midpoints:
        x, el, grp = split_at_midpoints(x, el, grp)
    n = x.shape[0]
    groups = [geometry.beams[nm] for nm in lines.names]
    own = comm.rank == 0
    if own:
        K, M = beam_matrices(x, el, grp, groups, lines.names)
    else:
        K = M = sp.csr_matrix((0, 6 * n))
    n_own = 6 * n if own else 0
    coords = np.repeat(x, 6, axis=0) if own else np.zeros((0, 3))
    comp = np.tile(np.arange(6), n) if own else np.zeros(0, np.int64)
    return BeamPart("beam", lines, None, groups, coords, comp, n_own,
                    pb.csr_matrix(comm, n_own, n_own, 6 * n, K), pb.csr_matrix(comm, n_own, n_own, 6 * n, M),
                    elements=el, xyz=x, element_group=grp)
