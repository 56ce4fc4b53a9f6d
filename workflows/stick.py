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
from liftoff.reduction.component import Component
from liftoff.reduction.models import frame_element

from liftoff.core.errors import InputError
from liftoff.core.labels import COMPONENTS

LINK = dict(E=2.0e11, A=0.5, I=0.05, mass_per_length=500.0, link=True)   # stiff steel links (skirts, fittings)


@dataclass
class StackParams:
    """Shuttle-like stack (m, kg, Pa) in the frame of meshes.layout.StackLayout: z up, origin
    on the core axis at the hold-down level, x along the booster-booster line (left at
    x < 0), y towards the orbiter. Positions equal the StackLayout defaults (checked by a
    test); masses follow the meshes/ defaults; see docs/workflow.md."""

    core_radius: float = 4.2
    core_bottom_z: float = 9.2
    core_top_z: float = 56.1
    core_wall: float = 0.012           # equivalent skin for EA, EI (thin-walled tube)
    core_E: float = 7.0e10
    lox_bottom_z: float = 42.0         # LOX tank (forward) carries most of the propellant
    core_mass_lox: float = 630.0e3
    core_mass_aft: float = 126.0e3     # LH2, intertank, dry structure below lox_bottom_z
    srb_radius: float = 1.855
    srb_axis_x: float = 6.36
    srb_length: float = 45.46
    srb_wall: float = 0.0127
    srb_E: float = 2.0e11
    srb_mass: float = 590.0e3
    holddown_radius: float = 2.45      # StackLayout: skirt radius 2.7 - thickness 0.5 / 2
    holddown_azimuths_deg: tuple = (45.0, 135.0, 225.0, 315.0)
    gimbal_z: float = 1.30             # aft dome apex
    srb_fwd_attach_z: float = 40.5
    srb_aft_attach_z: float = 13.2
    orbiter_radius: float = 2.6
    orbiter_axis_y: float = 7.8
    orbiter_bottom_z: float = 8.0
    orbiter_length: float = 37.24
    orbiter_fwd_attach_z: float = 37.0
    orbiter_aft_attach_z: float = 13.2
    orbiter_aft_attach_x: float = 1.5
    orbiter_mass: float = 84.46e3      # structure (smeared on the fuselage beam)
    orbiter_I: float = 3.0             # m^4, fuselage bending
    orbiter_A: float = 0.4
    orbiter_E: float = 7.0e10
    ssme_mass: float = 3 * 3180.0
    ssme_cg_below_bulkhead: float = 1.8
    payload_mass: float = 16.0e3
    payload_z: float = 25.0
    pad_mass: float = 3.73e6
    deck_top_z: float = -2.0           # post tops at z = 0, posts 2 m tall
    deck_thickness: float = 7.6
    deck_I: float = 10.0               # m^4 per girder (0.05 m flanges, 7.6 m deep, ~10 m strips)
    deck_A: float = 1.0
    steel_E: float = 2.0e11
    pedestal_height: float = 6.7
    pedestal_I: float = 2.0
    pedestal_A: float = 0.4
    pedestal_xy: tuple = ((-20.0, -16.5), (0.0, -16.5), (20.0, -16.5),
                          (-20.0, 18.5), (0.0, 18.5), (20.0, 18.5))
    post_A: float = 1.0                # 1 m square steel posts
    post_I: float = 0.083
    post_mass: float = 15.7e3          # kg per post (1 x 1 x 2 m steel)


def _tube(R: float, t: float) -> tuple[float, float]:
    return 2 * math.pi * R * t, math.pi * R ** 3 * t


class _Frame:
    """Accumulates nodes (named or not), beam elements and lumped masses."""

    def __init__(self, name: str):
        self.name, self.nodes, self.names, self.elems = name, [], [], []
        self.named: dict[str, int] = {}
        self.clamped: list[int] = []
        self.masses: dict[int, float] = {}

    def rename(self, i: int, name: str) -> None:
        self.names[i] = name
        self.named[name] = i

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
            rho = mpl / A if mpl > 0 else 1e-6
            ke, me = frame_element(nodes[a], nodes[b], E, E / 2.6, A, I, I, 2 * I, rho)
            d = np.r_[6 * a:6 * a + 6, 6 * b:6 * b + 6]
            rows.append(np.repeat(d, 12)), cols.append(np.tile(d, 12))
            kv.append(ke.ravel()), mv.append(me.ravel())
        r, c = np.concatenate(rows), np.concatenate(cols)
        K = sp.csr_matrix((np.concatenate(kv), (r, c)), shape=(n, n))
        M = sp.csr_matrix((np.concatenate(mv), (r, c)), shape=(n, n))
        if self.masses:                  # lumped masses (translations; small rotary inertia)
            d = np.zeros(n)
            for i, m in self.masses.items():
                d[6 * i:6 * i + 3] += m
                d[6 * i + 3:6 * i + 6] += m * 1.0
            M = M + sp.diags(d)
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
    return -1.0 if side == "left" else 1.0


def holddown_points(p: StackParams, side: str) -> dict[str, np.ndarray]:
    x0 = _side(side) * p.srb_axis_x
    return {f"srb_{side}_hd_{k + 1}": np.array([x0 + p.holddown_radius * math.cos(math.radians(a)),
                                               p.holddown_radius * math.sin(math.radians(a)), 0.0])
            for k, a in enumerate(p.holddown_azimuths_deg)}


def attach_points(p: StackParams) -> dict[str, np.ndarray]:
    out = {}
    for side in ("left", "right"):
        xm = _side(side) * 0.5 * (p.core_radius + p.srb_axis_x - p.srb_radius)
        out[f"att_srb_{side}_fwd"] = np.array([xm, 0.0, p.srb_fwd_attach_z])
        out[f"att_srb_{side}_aft"] = np.array([xm, 0.0, p.srb_aft_attach_z])
    ym = 0.5 * (p.core_radius + p.orbiter_axis_y - p.orbiter_radius)
    out["att_orb_fwd"] = np.array([0.0, ym, p.orbiter_fwd_attach_z])
    out["att_orb_aft_left"] = np.array([-p.orbiter_aft_attach_x, ym, p.orbiter_aft_attach_z])
    out["att_orb_aft_right"] = np.array([p.orbiter_aft_attach_x, ym, p.orbiter_aft_attach_z])
    return out


def core(p: StackParams, h: float) -> _Frame:
    f = _Frame("core")
    A, I = _tube(p.core_radius, p.core_wall)
    att = {k: v for k, v in attach_points(p).items()}
    ids, zs = f.axis(0, 0, p.core_bottom_z, p.core_top_z, h,
                     [v[2] for v in att.values()] + [p.lox_bottom_z])
    for a, b, za, zb in zip(ids, ids[1:], zs, zs[1:]):
        lox = za >= p.lox_bottom_z - 1e-9
        mpl = p.core_mass_lox / (p.core_top_z - p.lox_bottom_z) if lox else \
            p.core_mass_aft / (p.lox_bottom_z - p.core_bottom_z)
        f.beam(a, b, p.core_E, A, I, mpl)
    f.rename(ids[-1], "stack_top")
    at = dict(zip(zs, ids))
    for name, xyz in att.items():
        f.beam(at[round(xyz[2], 6)], f.node(xyz, name), **LINK)
    return f


def srb(p: StackParams, h: float, side: str) -> _Frame:
    f = _Frame(f"srb_{side}")
    x = _side(side) * p.srb_axis_x
    A, I = _tube(p.srb_radius, p.srb_wall)
    ids, zs = f.axis(x, 0, 0.0, p.srb_length, h, (p.srb_aft_attach_z, p.srb_fwd_attach_z, p.gimbal_z))
    for a, b in zip(ids, ids[1:]):
        f.beam(a, b, p.srb_E, A, I, p.srb_mass / p.srb_length)
    at = dict(zip(zs, ids))
    f.rename(at[round(p.gimbal_z, 6)], f"srb_{side}_gimbal")       # nozzle gimbal on the axis
    for name, xyz in attach_points(p).items():
        if name.startswith(f"att_srb_{side}_"):
            f.beam(at[round(xyz[2], 6)], f.node(xyz, name), **LINK)
    for name, xyz in holddown_points(p, side).items():                # aft skirt
        f.beam(ids[0], f.node(xyz, name), **LINK)
    return f


def orbiter(p: StackParams, h: float) -> _Frame:
    f = _Frame("orbiter")
    y = p.orbiter_axis_y
    z0, z1 = p.orbiter_bottom_z, p.orbiter_bottom_z + p.orbiter_length
    att = {k: v for k, v in attach_points(p).items() if k.startswith("att_orb")}
    ids, zs = f.axis(0, y, z0, z1, h, [v[2] for v in att.values()] + [p.payload_z])
    for a, b in zip(ids, ids[1:]):
        f.beam(a, b, p.orbiter_E, p.orbiter_A, p.orbiter_I, p.orbiter_mass / p.orbiter_length)
    at = dict(zip(zs, ids))
    f.rename(at[round(p.payload_z, 6)], "payload_station")
    f.masses[at[round(p.payload_z, 6)]] = p.payload_mass
    for name, xyz in att.items():
        f.beam(at[round(xyz[2], 6)], f.node(xyz, name), **LINK)
    m = f.node((0, y, z0 - p.ssme_cg_below_bulkhead), "ssme_mount")  # SSME cluster c.g.
    f.masses[m] = p.ssme_mass
    f.beam(ids[0], m, **LINK)
    return f


def post_points(p: StackParams) -> dict[str, np.ndarray]:
    return {k.replace(f"srb_{side}_hd_", f"pad_post_{side}_"): v
            for side in ("left", "right") for k, v in holddown_points(p, side).items()}


def pad(p: StackParams, h: float) -> _Frame:
    """Deck girder grillage (mid-depth) on six clamped pedestals; hold-down posts up to z = 0."""
    f = _Frame("pad")
    posts = post_points(p)
    zd = p.deck_top_z - 0.5 * p.deck_thickness
    xs = sorted({round(v, 6) for v in [-24.5, 24.5] + [xy[0] for xy in p.pedestal_xy]
                 + [v[0] for v in posts.values()]})
    ys = sorted({round(v, 6) for v in [-18.5, 22.5] + [xy[1] for xy in p.pedestal_xy]
                 + [v[1] for v in posts.values()]})
    grid = {(x, y): f.node((x, y, zd)) for x in xs for y in ys}
    length = (xs[-1] - xs[0]) * len(ys) + (ys[-1] - ys[0]) * len(xs)
    mpl = (p.pad_mass - len(posts) * p.post_mass) / length
    for i, x in enumerate(xs):
        for j, y in enumerate(ys):
            if i + 1 < len(xs):
                f.beam(grid[(x, y)], grid[(xs[i + 1], y)], p.steel_E, p.deck_A, p.deck_I, mpl)
            if j + 1 < len(ys):
                f.beam(grid[(x, y)], grid[(x, ys[j + 1])], p.steel_E, p.deck_A, p.deck_I, mpl)
    for x, y in p.pedestal_xy:
        g = f.node((x, y, p.deck_top_z - p.deck_thickness - p.pedestal_height))
        f.beam(g, grid[(round(x, 6), round(y, 6))], p.steel_E, p.pedestal_A, p.pedestal_I, 0.0)
        f.clamped.append(g)
    for name, xyz in posts.items():
        top = f.node(xyz, name)
        f.beam(grid[(round(xyz[0], 6), round(xyz[1], 6))], top, p.steel_E, p.post_A, p.post_I,
               p.post_mass / (xyz[2] - zd))
    return f


def stack_components(params: dict | None = None, element_length: float = 4.0) -> dict[str, Component]:
    """The four vehicle components and the pad, keyed core, srb_left, srb_right, orbiter, pad."""
    return {k: f.component(f.clamped) for k, f in _frames(params, element_length).items()}


def stack_thermal(params: dict | None = None, element_length: float = 4.0) -> dict[str, dict[str, np.ndarray]]:
    """Per component, {volume: nodal load of a unit free axial strain}; the stick model's
    only 'volume' of a component is its wall, ``<component>_wall`` (as the FE core's)."""
    return {k: {f"{k}_wall": f.thermal(f.clamped)} for k, f in _frames(params, element_length).items()}


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


__all__ = ["StackParams", "stack_components", "post_points"]
