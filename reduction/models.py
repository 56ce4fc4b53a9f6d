"""Small reference FE models written with numpy/scipy only: a 3-D Euler-Bernoulli frame
and a trilinear hexahedral solid block with rigid spiders (RBE2). They give the tests and
benchmarks of reduction/ structures whose physics is known in closed form, without
dolfinx. SI units (m, kg, N, Pa).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from liftoff.core.beam import assemble_frame
from liftoff.core.errors import InputError
from liftoff.core.labels import COMPONENTS
from liftoff.core.rigid import nodal_rb

from .component import Component


# ----------------------------------------------------------------------------- frame
def frame_element(x1, x2, E, G, A, Iy, Iz, J, rho, vref=(0.0, 0.0, 1.0)):
    """Global 12 x 12 stiffness and consistent mass of a straight 3-D Euler-Bernoulli beam
    (DOFs ux uy uz rx ry rz at each end; Przemieniecki's matrices): liftoff.core.beam's
    element without shear areas or rotary inertia."""
    from liftoff.core.beam import Section, beam_element

    return beam_element(x1, x2, E, G, Section(A, Iy, Iz, J), rho, vref, rotary=False)


def frame_matrices(nodes, elements, E, G, A, Iy, Iz, J, rho, vref=(0.0, 0.0, 1.0)):
    """Assembled sparse K, M (6 DOFs per node, node-major) of a frame of identical beams."""
    nodes = np.asarray(nodes, float)
    return assemble_frame(nodes.shape[0], ((a, b, *frame_element(nodes[a], nodes[b], E, G, A, Iy, Iz, J, rho, vref))
                                           for a, b in elements))


def frame_component(name, nodes, elements, point_names, E=70e9, nu=0.3, A=1e-3, Iy=1e-6,
                    Iz=1e-6, J=2e-6, rho=2700.0, vref=(0.0, 0.0, 1.0)) -> Component:
    """A frame as a Component: every node is a labelled 6-DOF point ``point_names[i]``."""
    nodes = np.asarray(nodes, float)
    K, M = frame_matrices(nodes, elements, E, E / (2 * (1 + nu)), A, Iy, Iz, J, rho, vref)
    labels = [f"{p}:{c}" for p in point_names for c in COMPONENTS]
    return Component(name=name, K=K, M=M, dof_labels=labels, label_dofs=np.arange(len(labels)),
                     points=tuple(point_names), point_coords=nodes)


def line_component(name: str, X: np.ndarray, point_names, K, M, cells) -> Component:
    """A model of beams as a Component: node i the labelled 6-DOF point ``point_names[i]``
    at ``X[i]`` (m), drawn as the 2-node ``cells``, its field map the nodes' translations
    (the beam stick, the strut)."""
    X = np.asarray(X, float)
    n = X.shape[0]
    fmap = sp.csr_matrix((np.ones(3 * n), (np.arange(3 * n), (6 * np.arange(n)[:, None] + np.arange(3)).ravel())),
                         shape=(3 * n, 6 * n))
    return Component(name=name, K=K, M=M, dof_labels=[f"{p}:{c}" for p in point_names for c in COMPONENTS],
                     label_dofs=np.arange(6 * n), points=tuple(point_names), point_coords=X, nodes=X,
                     cells=np.asarray(cells, np.int64), cell_type="line", field_map=fmap)


# ----------------------------------------------------------------------------- solid
def hex8_element(hx, hy, hz, E, nu, rho):
    """24 x 24 stiffness and consistent mass of a trilinear brick hx x hy x hz (2x2x2 Gauss)."""
    lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
    D = np.zeros((6, 6))
    D[:3, :3] = lam
    D[np.arange(3), np.arange(3)] += 2 * mu
    D[np.arange(3, 6), np.arange(3, 6)] = mu
    corners = np.array([[i, j, k] for k in (0, 1) for j in (0, 1) for i in (0, 1)], float) * 2 - 1
    g = 1 / np.sqrt(3.0)
    h = np.array([hx, hy, hz])
    detJ = np.prod(h) / 8
    ke, me = np.zeros((24, 24)), np.zeros((24, 24))
    for xi in corners * g:
        N = np.prod(1 + corners * xi, axis=1) / 8
        dN = np.empty((8, 3))
        for d in range(3):
            others = [e for e in range(3) if e != d]
            dN[:, d] = corners[:, d] * np.prod(1 + corners[:, others] * xi[others], axis=1) / 8 / (h[d] / 2)
        B = np.zeros((6, 24))
        for a in range(8):
            bx, by, bz = dN[a]
            B[:, 3 * a:3 * a + 3] = [[bx, 0, 0], [0, by, 0], [0, 0, bz], [by, bx, 0], [0, bz, by], [bz, 0, bx]]
        ke += B.T @ D @ B * detJ
        me += rho * np.kron(np.outer(N, N), np.eye(3)) * detJ
    return ke, me


def hex_block(n_cells, size, E=70e9, nu=0.3, rho=2700.0):
    """Structured block [0, Lx] x [0, Ly] x [0, Lz] of n_cells = (nx, ny, nz) bricks.
    Returns sparse K, M over nodal translations (3 per node, node-major) and the nodes."""
    nx, ny, nz = n_cells
    Lx, Ly, Lz = size
    ke, me = hex8_element(Lx / nx, Ly / ny, Lz / nz, E, nu, rho)
    gx, gy, gz = (np.linspace(0, L, m + 1) for L, m in ((Lx, nx), (Ly, ny), (Lz, nz)))
    nodes = np.stack(np.meshgrid(gx, gy, gz, indexing="ij"), axis=-1).reshape(-1, 3)
    nid = np.arange(nodes.shape[0]).reshape(nx + 1, ny + 1, nz + 1)
    base = nid[:-1, :-1, :-1].ravel()
    offs = np.array([nid[i, j, k] - nid[0, 0, 0] for k in (0, 1) for j in (0, 1) for i in (0, 1)])
    conn = base[:, None] + offs[None, :]                        # (n_el, 8) same order as hex8_element
    dofs = (3 * conn[:, :, None] + np.arange(3)).reshape(-1, 24)
    r = np.repeat(dofs, 24, axis=1).ravel()
    c = np.tile(dofs, (1, 24)).ravel()
    n = 3 * nodes.shape[0]
    K = sp.csr_matrix((np.tile(ke.ravel(), conn.shape[0]), (r, c)), shape=(n, n))
    M = sp.csr_matrix((np.tile(me.ravel(), conn.shape[0]), (r, c)), shape=(n, n))
    return K, M, nodes


def spider_component(name, K, M, nodes, spiders: dict) -> Component:
    """Tie node groups rigidly to 6-DOF reference points (Nastran RBE2, by elimination):
    ``spiders = {point_name: (node_ids, ref_coord)}``. Returns a Component whose DOFs are
    the free nodal translations followed by 6 DOFs per reference point, with a field_map
    back to all nodal translations."""
    nodes = np.asarray(nodes, float)
    n_nodes = nodes.shape[0]
    owner = -np.ones(n_nodes, dtype=int)
    for s, (ids, _) in enumerate(spiders.values()):
        ids = np.asarray(ids)
        if np.any(owner[ids] >= 0):
            raise InputError(f"spider {list(spiders)[s]!r}: node already tied to another spider")
        owner[ids] = s
    free = np.flatnonzero(owner < 0)
    n_free = 3 * free.size
    rows, cols, vals = [], [], []
    fdofs = (3 * free[:, None] + np.arange(3)).ravel()
    rows.append(fdofs)
    cols.append(np.arange(n_free))
    vals.append(np.ones(n_free))
    for s, (ids, ref) in enumerate(spiders.values()):
        ids = np.asarray(ids)
        rb = nodal_rb(nodes[ids], ref)                 # (3 len(ids), 6), x y z per node
        rr, cc = np.nonzero(rb)
        rows.append(3 * ids[rr // 3] + rr % 3)
        cols.append(n_free + 6 * s + cc)
        vals.append(rb[rr, cc])
    n_red = n_free + 6 * len(spiders)
    T = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                      shape=(3 * n_nodes, n_red))
    Kr = (T.T @ K @ T).tocsr()
    Mr = (T.T @ M @ T).tocsr()
    labels = [f"{p}:{c}" for p in spiders for c in COMPONENTS]
    return Component(name=name, K=Kr, M=Mr, dof_labels=labels,
                     label_dofs=n_free + np.arange(len(labels)), points=tuple(spiders),
                     point_coords=np.array([ref for _, ref in spiders.values()], float),
                     nodes=nodes, field_map=T)


# ----------------------------------------------------------------------------- helpers
def six_labels(point: str) -> list[str]:
    """The six DOF labels ``point:Tx`` ... ``point:Rz`` of a point."""
    return [f"{point}:{c}" for c in COMPONENTS]


def chain_component(name, nodes, first_index=0, **section) -> Component:
    """A frame of beams between consecutive ``nodes``, points named n<first_index + i>."""
    nodes = np.asarray(nodes, float)
    n = nodes.shape[0]
    return frame_component(name, nodes, [(i, i + 1) for i in range(n - 1)],
                           [f"n{first_index + i}" for i in range(n)], **section)


# ----------------------------------------------------------------------------- rigid mass
@dataclass
class RigidMass:
    """A rigid body joined to the rest at one point (``[model.component.<name>] type =
    "rigid_mass"``): ``point`` (its name, the joint's), ``at`` (m), ``mass`` (kg), ``cg``
    (m; empty: at the point), ``inertia`` (kg m^2 about the c.g., [Ixx, Iyy, Izz] or
    [Ixx, Iyy, Izz, Ixy, Ixz, Iyz], products of inertia as the tensor's off-diagonal
    terms)."""

    point: str = "cg"
    at: tuple = (0.0, 0.0, 0.0)
    mass: float = 0.0
    cg: tuple = ()
    inertia: tuple = (0.0, 0.0, 0.0)

    def check(self) -> None:
        if not isinstance(self.point, str) or not self.point:
            raise InputError("rigid mass: point must be a non-empty name")
        for nm in ("at", "cg"):
            v = np.asarray(getattr(self, nm), float).reshape(-1)
            if not ((v.size == 3 or (nm == "cg" and v.size == 0)) and np.all(np.isfinite(v))):
                raise InputError(f"rigid mass: {nm} must be [x, y, z] m (got {list(getattr(self, nm))!r})")
        self.at = tuple(float(x) for x in self.at)
        self.cg = self.at if len(self.cg) == 0 else tuple(float(x) for x in self.cg)
        if not (np.isfinite(self.mass) and self.mass > 0):
            raise InputError(f"rigid mass: mass must be > 0 kg (got {self.mass!r})")
        I = np.asarray(self.inertia, float).reshape(-1)
        if I.size not in (3, 6) or not np.all(np.isfinite(I)):
            raise InputError(f"rigid mass: inertia is [Ixx, Iyy, Izz] or [Ixx, Iyy, Izz, Ixy, Ixz, Iyz] kg m^2 "
                             f"(got {list(self.inertia)!r})")
        T = self.tensor()
        w = np.linalg.eigvalsh(T)
        scale = max(float(np.abs(w).max()), 1e-300)
        if w.min() < -1e-12 * scale or any(w[i] + w[j] < w[k] * (1 - 1e-12) - 1e-12 * scale
                                           for i, j, k in ((0, 1, 2), (0, 2, 1), (1, 2, 0))):
            raise InputError(f"rigid mass: inertia {list(self.inertia)!r} kg m^2 is not a body's (principal "
                             f"moments {np.round(w, 6).tolist()}: each >= 0 and none above the sum of the other two)")

    def tensor(self) -> np.ndarray:
        """The 3 x 3 inertia tensor about the c.g. (kg m^2); the given products Ixy, Ixz, Iyz are
        its off-diagonal entries (-integral of x y dm: a Nastran CONM2's I21, I31, I32 negated)."""
        I = np.asarray(self.inertia, float).reshape(-1)
        xx, yy, zz = I[:3]
        xy, xz, yz = I[3:] if I.size == 6 else (0.0, 0.0, 0.0)
        return np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])


def rigid_mass_cb(params: RigidMass, name: str = "rigid_mass"):
    """The Craig-Bampton model of a rigid mass: no modes, its point's six DOFs the boundary,
    M = RB^T diag(m, m, m, I_cg) RB with RB the rigid motion of the c.g. from the point's
    (liftoff.core.rigid.dof_rb), K = 0."""
    from liftoff.core.rigid import dof_rb

    from .craig_bampton import CBModel

    at, cg = np.asarray(params.at, float), np.asarray(params.cg, float)
    RB = dof_rb(np.repeat((cg - at)[None, :], 6, axis=0), np.arange(6))
    Mc = np.zeros((6, 6))
    Mc[:3, :3] = params.mass * np.eye(3)
    Mc[3:, 3:] = params.tensor()
    M = RB.T @ Mc @ RB
    labels = tuple(f"{params.point}:{c}" for c in COMPONENTS)
    return CBModel(name=name, boundary_labels=labels, fixed_omega=np.zeros(0), M=0.5 * (M + M.T), K=np.zeros((6, 6)),
                   points=(params.point,), point_coords=at[None, :].copy(), dof_labels=labels,
                   label_transform=np.eye(6), n_dof=6, constraint_modes=np.eye(6),
                   fixed_interface_modes=np.zeros((6, 0)))


# ----------------------------------------------------------------------------- rigid ground
@dataclass
class RigidGround:
    """Immovable ground as the pad (``[model.pad] type = "rigid_ground"``): named points
    (``points = {name: (x, y, z)}``, m) that never move, for the posts to hold the vehicle
    to."""

    points: dict = None

    def check(self) -> None:
        if not isinstance(self.points, dict) or not self.points:
            raise InputError("rigid ground: give its points = {name = [x, y, z]} (the posts' pad points)")
        out = {}
        for name, xyz in self.points.items():
            v = np.asarray(xyz, float).reshape(-1)
            if v.size != 3 or not np.all(np.isfinite(v)):
                raise InputError(f"rigid ground: point {name!r} must be [x, y, z] m (got {xyz!r})")
            out[str(name)] = tuple(float(x) for x in v)
        self.points = out


def rigid_ground_cb(params: RigidGround, name: str = "pad"):
    """The Craig-Bampton model of immovable ground: no DOFs at all; its points are labelled
    DOFs whose displacement is identically zero (label_transform rows of zeros)."""
    from .craig_bampton import CBModel

    names = tuple(params.points)
    labels = tuple(f"{p}:{c}" for p in names for c in COMPONENTS)
    return CBModel(name=name, boundary_labels=(), fixed_omega=np.zeros(0), M=np.zeros((0, 0)), K=np.zeros((0, 0)),
                   points=names, point_coords=np.array([params.points[p] for p in names], float).reshape(-1, 3),
                   dof_labels=labels, label_transform=np.zeros((len(labels), 0)), n_dof=len(labels),
                   constraint_modes=np.zeros((len(labels), 0)), fixed_interface_modes=np.zeros((len(labels), 0)))
