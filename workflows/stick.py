"""Beam stick models of a Space-Shuttle-like stack and its pad (``[model] source = "stick"``).

The loads engineer's classic: each component is a line of 3-D Euler-Bernoulli beams
(reduction.models.frame_element) along its axis, with stiff links out to the named
points it shares with its neighbours (attach points, hold-down points, engine mounts).
No gmsh or dolfinx: this is the fast model of the tests and of quick studies; the
``fe`` source meshes the same stack in 3-D. Point names and coordinates are those of
the default scenario (z up, origin at the booster base; SI units).

Section properties are thin-walled cylinders (I = pi R^3 t, A = 2 pi R t); the mass of
propellant and equipment is smeared on the beams (a line density, documented per
component in docs/workflow.md), so the beam "density" is not a material density.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
import scipy.sparse as sp

from reduction.component import Component
from reduction.models import frame_element
from transient.body import COMPONENTS
from transient.errors import InputError

LINK = dict(E=2.0e11, A=0.5, I=0.05, mass_per_length=500.0, link=True)   # stiff steel links (skirts, fittings)


@dataclass
class StackParams:
    """Shuttle-like dimensions (m), masses (kg), moduli (Pa). Defaults: see docs/workflow.md."""

    core_length: float = 47.0
    core_radius: float = 4.2
    core_base: float = 3.0
    core_mass: float = 756.0e3
    core_wall: float = 0.012
    core_E: float = 7.0e10
    srb_length: float = 45.5
    srb_radius: float = 1.85
    srb_offset: float = 6.35          # booster axis from the core axis (y)
    srb_mass: float = 590.0e3
    srb_wall: float = 0.0127
    srb_E: float = 2.0e11
    skirt_radius: float = 2.6         # hold-down points around the booster axis
    orbiter_length: float = 37.0
    orbiter_offset: float = 8.0       # orbiter axis from the core axis (x)
    orbiter_base: float = 6.0
    orbiter_mass: float = 110.0e3
    orbiter_I: float = 3.0            # m^4, fuselage bending
    orbiter_A: float = 0.4
    orbiter_E: float = 7.0e10
    attach_aft_z: float = 9.0
    attach_fwd_z: float = 38.0
    orbiter_fwd_z: float = 35.0
    gimbal_z: float = 1.5
    payload_z: float = 25.0
    pad_mass: float = 3.73e6
    pad_depth: float = -3.8           # deck girder plane (z)
    pad_I: float = 4.0
    pad_A: float = 1.0
    pad_E: float = 2.0e11
    post_height: float = 3.8          # hold-down posts from the deck to z = 0
    post_A: float = 0.3
    post_I: float = 0.02
    post_mass: float = 20.0e3          # kg per hold-down post
    pedestal_height: float = 8.0


def _tube(R: float, t: float) -> tuple[float, float]:
    return 2 * math.pi * R * t, math.pi * R ** 3 * t


class _Frame:
    """Accumulates nodes (named or not), beam elements and lumped masses."""

    def __init__(self, name: str):
        self.name, self.nodes, self.names, self.elems = name, [], [], []
        self.named: dict[str, int] = {}
        self.clamped: list[int] = []

    def node(self, xyz, name: str | None = None) -> int:
        self.nodes.append(np.asarray(xyz, float))
        self.names.append(name or f"{self.name}_n{len(self.nodes) - 1}")
        if name:
            self.named[name] = len(self.nodes) - 1
        return len(self.nodes) - 1

    def beam(self, a: int, b: int, E, A, I, mass_per_length=0.0, link=False):
        self.elems.append((a, b, E, A, I, mass_per_length, link))

    def axis(self, x, y, z0, z1, h, stations=()) -> list[int]:
        zs = set(np.linspace(z0, z1, max(2, int(math.ceil((z1 - z0) / h)) + 1)).round(6))
        zs |= {round(z, 6) for z in stations}
        zs = sorted(zs)
        return [self.node((x, y, z)) for z in zs], zs

    def thermal(self, clamped=()) -> np.ndarray:
        """Nodal forces of a unit free axial strain in the structural beams (links excluded):
        EA * 1 pulling each element's ends apart (a shrinking strain pulls them together)."""
        nodes = np.array(self.nodes)
        f = np.zeros(6 * len(nodes))
        for a, b, E, A, I, mpl, link in self.elems:
            if not link:
                e = (nodes[b] - nodes[a]) / np.linalg.norm(nodes[b] - nodes[a])
                f[6 * a:6 * a + 3] -= E * A * e
                f[6 * b:6 * b + 3] += E * A * e
        keep = [i for i in range(len(nodes)) if i not in set(clamped)]
        return np.concatenate([f[6 * i:6 * i + 6] for i in keep])

    def component(self, clamped=()) -> Component:
        nodes = np.array(self.nodes)
        n = 6 * len(nodes)
        rows, cols, kv, mv = [], [], [], []
        for a, b, E, A, I, mpl, _ in self.elems:
            L = float(np.linalg.norm(nodes[b] - nodes[a]))
            rho = mpl / A if mpl > 0 else 1e-6
            ke, me = frame_element(nodes[a], nodes[b], E, E / 2.6, A, I, I, 2 * I, rho)
            d = np.r_[6 * a:6 * a + 6, 6 * b:6 * b + 6]
            rows.append(np.repeat(d, 12)), cols.append(np.tile(d, 12))
            kv.append(ke.ravel()), mv.append(me.ravel())
        r, c = np.concatenate(rows), np.concatenate(cols)
        K = sp.csr_matrix((np.concatenate(kv), (r, c)), shape=(n, n))
        M = sp.csr_matrix((np.concatenate(mv), (r, c)), shape=(n, n))
        keep_nodes = [i for i in range(len(nodes)) if i not in set(clamped)]
        keep = np.concatenate([np.arange(6 * i, 6 * i + 6) for i in keep_nodes])
        K, M = K[keep][:, keep].tocsr(), M[keep][:, keep].tocsr()
        labels = [f"{self.names[i]}:{c}" for i in keep_nodes for c in COMPONENTS]
        # field map: nodal translations of every node (clamped ones stay zero)
        fr, fc = [], []
        for j, i in enumerate(keep_nodes):
            fr += [3 * i, 3 * i + 1, 3 * i + 2]
            fc += [6 * j, 6 * j + 1, 6 * j + 2]
        fmap = sp.csr_matrix((np.ones(len(fr)), (fr, fc)), shape=(3 * len(nodes), keep.size))
        cells = np.array([[a, b] for a, b, *_ in self.elems], dtype=np.int64)
        return Component(name=self.name, K=K, M=M, dof_labels=labels, label_dofs=np.arange(len(labels)),
                         points=tuple(self.names[i] for i in keep_nodes),
                         point_coords=nodes[keep_nodes], nodes=nodes, cells=cells, cell_type="line",
                         field_map=fmap)


def _side(side: str) -> float:
    return 1.0 if side == "left" else -1.0


def _attach_y(p: StackParams, side: str) -> float:
    return _side(side) * 0.5 * (p.core_radius + p.srb_offset - p.srb_radius)


def core(p: StackParams, h: float) -> Component:
    f = _Frame("core")
    A, I = _tube(p.core_radius, p.core_wall)
    z0, z1 = p.core_base, p.core_base + p.core_length
    ids, zs = f.axis(0, 0, z0, z1, h, (p.attach_aft_z, p.attach_fwd_z, p.orbiter_fwd_z))
    mpl = p.core_mass / p.core_length
    for a, b in zip(ids, ids[1:]):
        f.beam(a, b, p.core_E, A, I, mpl)
    f.names[ids[-1]] = "core_nose"
    f.named["core_nose"] = ids[-1]
    at = dict(zip(zs, ids))
    for side in ("left", "right"):
        for tag, z in (("aft", p.attach_aft_z), ("fwd", p.attach_fwd_z)):
            q = f.node((0, _attach_y(p, side), z), f"et_srb_{tag}_{side}")
            f.beam(at[round(z, 6)], q, **LINK)
    for tag, z in (("aft", p.attach_aft_z), ("fwd", p.orbiter_fwd_z)):
        q = f.node((0.5 * (p.core_radius + p.orbiter_offset - 1.5), 0, z), f"et_orb_{tag}")
        f.beam(at[round(z, 6)], q, **LINK)
    return f


def srb(p: StackParams, h: float, side: str) -> Component:
    f = _Frame(f"srb_{side}")
    y = _side(side) * p.srb_offset
    A, I = _tube(p.srb_radius, p.srb_wall)
    ids, zs = f.axis(0, y, 0.0, p.srb_length, h, (p.attach_aft_z, p.attach_fwd_z, p.gimbal_z))
    for a, b in zip(ids, ids[1:]):
        f.beam(a, b, p.srb_E, A, I, p.srb_mass / p.srb_length)
    at = dict(zip(zs, ids))
    for tag, z in (("aft", p.attach_aft_z), ("fwd", p.attach_fwd_z)):
        q = f.node((0, _attach_y(p, side), z), f"et_srb_{tag}_{side}")
        f.beam(at[round(z, 6)], q, **LINK)
    f.names[at[round(p.gimbal_z, 6)]] = f"srb_{side}_gimbal"       # nozzle gimbal on the axis
    for k in range(4):
        ang = math.pi / 4 + k * math.pi / 2
        q = f.node((p.skirt_radius * math.cos(ang), y + p.skirt_radius * math.sin(ang), 0.0),
                   f"srb_{side}_hd_{k + 1}")
        f.beam(ids[0], q, **LINK)
    return f


def orbiter(p: StackParams, h: float) -> Component:
    f = _Frame("orbiter")
    x = p.orbiter_offset
    z0, z1 = p.orbiter_base, p.orbiter_base + p.orbiter_length
    ids, zs = f.axis(x, 0, z0, z1, h, (p.attach_aft_z, p.orbiter_fwd_z, p.payload_z))
    for a, b in zip(ids, ids[1:]):
        f.beam(a, b, p.orbiter_E, p.orbiter_A, p.orbiter_I, p.orbiter_mass / p.orbiter_length)
    at = dict(zip(zs, ids))
    f.names[at[round(p.payload_z, 6)]] = "orbiter_payload"
    f.named["orbiter_payload"] = at[round(p.payload_z, 6)]
    for tag, z in (("aft", p.attach_aft_z), ("fwd", p.orbiter_fwd_z)):
        q = f.node((0.5 * (p.core_radius + p.orbiter_offset - 1.5), 0, z), f"et_orb_{tag}")
        f.beam(at[round(z, 6)], q, **LINK)
    for k, (dx, dy, dz) in enumerate(((1.5, 0.0, 1.0), (0.0, 1.4, -0.5), (0.0, -1.4, -0.5))):
        q = f.node((x + dx, dy, z0 + dz), f"ssme_{k + 1}")
        f.beam(ids[0] if dz < 0.5 else ids[1], q, **LINK)
    return f


def post_points(p: StackParams) -> dict[str, np.ndarray]:
    out = {}
    for side in ("left", "right"):
        y = _side(side) * p.srb_offset
        for k in range(4):
            ang = math.pi / 4 + k * math.pi / 2
            out[f"pad_post_{side}_{k + 1}"] = np.array(
                [p.skirt_radius * math.cos(ang), y + p.skirt_radius * math.sin(ang), 0.0])
    return out


def pad(p: StackParams, h: float) -> Component:
    """Deck girder grillage at z = pad_depth on six clamped pedestals; posts up to z = 0."""
    f = _Frame("pad")
    xs = np.array([-12.0, -2.6, 2.6, 12.0])
    ys = np.array([-15.0, -p.srb_offset, 0.0, p.srb_offset, 15.0])
    grid = {(i, j): f.node((x, y, p.pad_depth)) for i, x in enumerate(xs) for j, y in enumerate(ys)}
    length = (xs.ptp() * len(ys) + ys.ptp() * len(xs))
    mpl = p.pad_mass / length
    for (i, j), a in grid.items():
        if (i + 1, j) in grid:
            f.beam(a, grid[(i + 1, j)], p.pad_E, p.pad_A, p.pad_I, mpl)
        if (i, j + 1) in grid:
            f.beam(a, grid[(i, j + 1)], p.pad_E, p.pad_A, p.pad_I, mpl)
    clamped = []
    for i in (0, len(xs) - 1):
        for j in (0, 2, len(ys) - 1):
            g = f.node((xs[i], ys[j], p.pad_depth - p.pedestal_height))
            f.beam(g, grid[(i, j)], p.pad_E, 2 * p.pad_A, 2 * p.pad_I, 0.0)
            clamped.append(g)
    for name, xyz in post_points(p).items():
        i = 1 if xyz[0] < 0 else 2
        j = 3 if xyz[1] > 0 else 1
        q = f.node(xyz, name)
        f.beam(grid[(i, j)], q, p.pad_E, p.post_A, p.post_I, p.post_mass / p.post_height)
    f.clamped = clamped
    return f


def stack_components(params: dict | None = None, element_length: float = 4.0) -> dict[str, Component]:
    """The four vehicle components and the pad, keyed core, srb_left, srb_right, orbiter, pad."""
    return {k: f.component(f.clamped) for k, f in _frames(params, element_length).items()}


def stack_thermal(params: dict | None = None, element_length: float = 4.0) -> dict[str, dict[str, np.ndarray]]:
    """Per component, {volume: nodal load of a unit free axial strain}; the stick model's
    only 'volume' of a component is the component itself."""
    return {k: {k: f.thermal(f.clamped)} for k, f in _frames(params, element_length).items()}


def _frames(params: dict | None, element_length: float) -> dict[str, _Frame]:
    try:
        p = StackParams(**(params or {}))
    except TypeError as exc:
        known = ", ".join(asdict(StackParams()))
        raise InputError(f"stick model: unknown parameter ({exc}); known: {known}") from None
    if not element_length > 0:
        raise InputError(f"stick model: element length must be positive, got {element_length}")
    return {"core": core(p, element_length), "srb_left": srb(p, element_length, "left"),
            "srb_right": srb(p, element_length, "right"), "orbiter": orbiter(p, element_length),
            "pad": pad(p, element_length)}


def named_points(component: Component) -> list[str]:
    """The component's named points (interfaces, posts, mounts, stations): its CB boundary."""
    return [pt for pt in component.points if not _is_auto(pt)]


def _is_auto(point: str) -> bool:
    head, _, tail = point.rpartition("_n")
    return bool(head) and tail.isdigit()


__all__ = ["StackParams", "stack_components", "named_points", "post_points"]
