"""Beam stick models of a Space-Shuttle-like stack and its pad (``[model] source = "stick"``).

The loads engineer's classic: each component is a line of 3-D Euler-Bernoulli beams
(reduction.models.frame_element) along its axis, with stiff links out to the named
points it shares with its neighbours (attach points, hold-down points, engine mounts).
No gmsh or dolfinx: this is the fast model of the tests and of quick studies; the
``fe`` source meshes the same stack in 3-D. Point names and positions are those of the
FE stack: they come from meshes.layout.StackLayout and meshes.pad.PadParams (frame of
meshes/layout.py: z up, origin on the core axis at the hold-down level; SI units).

The parameters (meshes.stick.StickParams) are section properties (thin-walled cylinders
I = pi R^3 t, A = 2 pi R t) and masses; the mass of propellant and equipment is smeared on
the beams (a line density, documented per component in docs/workflow.md), so the beam
"density" is not a material density.
"""
from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp
from liftoff.meshes.stick import StickParams
from liftoff.reduction.component import Component
from liftoff.reduction import beam_stick
from liftoff.reduction.models import assemble_frame, frame_element

from liftoff.core.errors import InputError, ResourceError
from liftoff.core.labels import COMPONENTS

LINK = {**beam_stick.LINK, "link": True}    # stiff steel links (skirts, fittings): the beam component's


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
        K, M = assemble_frame(len(nodes), ((a, b, *frame_element(nodes[a], nodes[b], E, E / 2.6, A, I, I, 2 * I,
                                                                   mpl / A if mpl > 0 else 1e-6))
                                           for a, b, E, A, I, mpl, _ in self.elems))
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


def attach_points(p: StickParams) -> dict[str, np.ndarray]:
    """Core-booster and core-orbiter attach points of the layout (booster left, right; orbiter)."""
    lay = p.layout
    return {**lay.srb_attach_points("left"), **lay.srb_attach_points("right"), **lay.orbiter_attach_points()}


def core(p: StickParams, h: float) -> _Frame:
    f = _Frame("core")
    bottom = p.layout.core_bottom_z
    A, I = _tube(p.layout.core_radius, p.core_wall)
    att = attach_points(p)
    ids, zs = f.axis(0, 0, bottom, p.core_top_z, h, [v[2] for v in att.values()] + [p.lox_bottom_z])
    for a, b, za, zb in zip(ids, ids[1:], zs, zs[1:]):
        lox = za >= p.lox_bottom_z - 1e-9
        mpl = p.core_mass_lox / (p.core_top_z - p.lox_bottom_z) if lox else \
            p.core_mass_aft / (p.lox_bottom_z - bottom)
        f.beam(a, b, p.core_E, A, I, mpl)
    f.rename(ids[-1], "stack_top")
    at = dict(zip(zs, ids))
    for name, xyz in att.items():
        f.beam(at[round(xyz[2], 6)], f.node(xyz, name), **LINK)
    return f


def srb(p: StickParams, h: float, side: str) -> _Frame:
    f = _Frame(f"srb_{side}")
    x = p.layout.srb_axis(side)[0]
    A, I = _tube(p.layout.srb_radius, p.srb_wall)
    ids, zs = f.axis(x, 0, 0.0, p.srb_length, h,
                     (p.layout.srb_aft_attach_z, p.layout.srb_fwd_attach_z, p.gimbal_z))
    for a, b in zip(ids, ids[1:]):
        f.beam(a, b, p.srb_E, A, I, p.srb_mass / p.srb_length)
    at = dict(zip(zs, ids))
    f.rename(at[round(p.gimbal_z, 6)], f"srb_{side}_gimbal")       # nozzle gimbal on the axis
    for name, xyz in p.layout.srb_attach_points(side).items():
        f.beam(at[round(xyz[2], 6)], f.node(xyz, name), **LINK)
    for name, xyz in p.layout.holddown_points(side).items():          # aft skirt
        f.beam(ids[0], f.node(xyz, name), **LINK)
    return f


def orbiter(p: StickParams, h: float) -> _Frame:
    f = _Frame("orbiter")
    y = p.layout.orbiter_axis_y
    z0, z1 = p.layout.orbiter_bottom_z, p.layout.orbiter_bottom_z + p.orbiter_length
    att = p.layout.orbiter_attach_points()
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


def pad(p: StickParams, h: float) -> _Frame:
    """Deck girder grillage (mid-depth) on the pad's clamped pedestals; hold-down posts up to
    z = 0 (deck, pedestals and posts where meshes.pad.PadParams puts them)."""
    f = _Frame("pad")
    pp = p.pad
    posts = pp.post_points()
    lo, hi = pp.deck_bounds()
    zd = hi[2] - 0.5 * pp.deck_thickness
    xs = sorted({round(v, 6) for v in [lo[0], hi[0]] + [xy[0] for xy in pp.pedestal_xy]
                 + [v[0] for v in posts.values()]})
    ys = sorted({round(v, 6) for v in [lo[1], hi[1]] + [xy[1] for xy in pp.pedestal_xy]
                 + [v[1] for v in posts.values()]})
    grid = {(x, y): f.node((x, y, zd)) for x in xs for y in ys}
    length = (xs[-1] - xs[0]) * len(ys) + (ys[-1] - ys[0]) * len(xs)
    mpl = (pp.mlp_mass - len(posts) * p.post_mass) / length
    for i, x in enumerate(xs):
        for j, y in enumerate(ys):
            if i + 1 < len(xs):
                f.beam(grid[(x, y)], grid[(xs[i + 1], y)], p.steel_E, p.deck_A, p.deck_I, mpl)
            if j + 1 < len(ys):
                f.beam(grid[(x, y)], grid[(x, ys[j + 1])], p.steel_E, p.deck_A, p.deck_I, mpl)
    for x, y in pp.pedestal_xy:
        g = f.node((x, y, lo[2] - pp.pedestal_height))
        f.beam(g, grid[(round(x, 6), round(y, 6))], p.steel_E, p.pedestal_A, p.pedestal_I, 0.0)
        f.clamped.append(g)
    for name, xyz in posts.items():
        top = f.node(xyz, name)
        f.beam(grid[(round(xyz[0], 6), round(xyz[1], 6))], top, p.steel_E, p.post_A, p.post_I,
               p.post_mass / (xyz[2] - zd))
    return f


def stack_components(params: StickParams | None = None, element_length: float = 4.0) -> dict[str, Component]:
    """The four vehicle components and the pad, keyed core, srb_left, srb_right, orbiter, pad."""
    return {name: build(name, params, element_length)[0] for name in FRAMES}


def axis_length(name: str, p: StickParams) -> float:
    """Length (m) of the beam axis of component ``name`` (0 for the pad, whose grillage is
    laid out on its pedestals and posts, not on the element length)."""
    return {"core": p.core_top_z - p.layout.core_bottom_z, "srb_left": p.srb_length, "srb_right": p.srb_length,
            "orbiter": p.orbiter_length}.get(name, 0.0)


def build(name: str, params: StickParams | None = None, element_length: float = 4.0,
          max_elements: int = 2_000) -> tuple[Component, dict]:
    """Component ``name`` (core, srb_left, srb_right, orbiter or pad) and its {volume: nodal
    load of a unit free axial strain}; the stick model's only 'volume' of a component is its
    wall, ``<name>_wall`` (as the FE core's). ResourceError when its axis would have more
    than ``max_elements`` beams."""
    p = params or StickParams()
    if not isinstance(p, StickParams):
        raise InputError(f"stick model: expected StickParams, got {type(p).__name__}")
    if name not in FRAMES:
        raise InputError(f"stick model: unknown component {name!r} (one of {', '.join(FRAMES)})")
    p.check()
    if not element_length > 0:
        raise InputError(f"stick model: element length must be positive, got {element_length}")
    n = axis_length(name, p) / element_length
    if n > max_elements:
        raise ResourceError(f"stick component {name!r}: element length {element_length:g} m gives {n:.3g} beams on "
                            f"its {axis_length(name, p):.4g} m axis, beyond the limit of {max_elements}; use a larger "
                            "mesh_size or raise [model] max_elements")
    f = FRAMES[name](p, element_length)
    return f.component(f.clamped), {f"{name}_wall": f.thermal(f.clamped)}


FRAMES = {"core": core, "srb_left": lambda p, h: srb(p, h, "left"), "srb_right": lambda p, h: srb(p, h, "right"),
          "orbiter": orbiter, "pad": pad}

__all__ = ["StickParams", "build", "stack_components"]
