"""A launch platform for any vehicle: a deck on pedestals clamped to the ground, with
hold-down posts (or arms) whose tops are the named points the vehicle's hold-down points
stand on, and exhaust holes through the deck (``type = "platform"``).

As the Shuttle's mobile launcher platform (meshes/pad.py), the deck is a solid box of an
equivalent density (the platform's ``mass`` less the posts', over the deck's volume) and an
equivalent modulus giving the bending stiffness of two steel flanges of thickness
``flange_thickness`` at its top and bottom, E_eq = 6 E_steel t_f / H; posts are steel, the
pedestals hollow steel columns smeared into boxes. Units SI.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from liftoff.core.errors import InputError

from . import _occ
from ._occ import occ
from .pad import STEEL, check_pedestals, deck_material, pedestal_material
from .spec import Geometry, Patch, require_positive, require_range


@dataclass
class PlatformParams:
    """Platform geometry and mass (SI): deck ``deck_size`` (x, y) centred at
    ``deck_center_xy``, ``deck_thickness``, its top at ``deck_top_z``; ``posts``: {point
    name: [x, y, z]} of each post top (square posts of side ``post_size`` rising from the
    deck top to z); ``holes``: [[x, y, radius]] exhaust holes through the deck,
    ``square_holes``: [[x, y, half side]] square ones;
    ``pedestals``: [[x, y]] square columns of side ``pedestal_size`` and height
    ``pedestal_height`` under the deck, their bottoms fixed to ground; ``mass``: deck and
    posts (kg)."""

    name: str = "pad"
    deck_size: tuple = field(default=(40.0, 40.0), metadata={"length": 2})
    deck_center_xy: tuple = (0.0, 0.0)
    deck_thickness: float = 7.6
    deck_top_z: float = -2.0
    posts: dict = field(default_factory=dict)
    post_size: float = 1.0
    holes: tuple = ()
    square_holes: tuple = ()
    pedestals: tuple = ((-15.0, -15.0), (15.0, -15.0), (-15.0, 15.0), (15.0, 15.0))
    pedestal_size: float = 2.0
    pedestal_height: float = 6.7
    pedestal_wall_thickness: float = 0.05
    mass: float = 3.0e6
    flange_thickness: float = 0.05
    mesh_size: float = 2.0
    post_mesh_size: float = 0.5
    deck: str = "solid"                   # "solid" (an equivalent box) or "girders" (beams, fem.beam)
    girder_section: dict = field(default_factory=dict)   # deck = "girders": {shape, dims} (core.beam.standard_section)

    def check(self) -> None:
        o = f"PlatformParams({self.name})"
        if self.deck not in ("solid", "girders"):
            raise InputError(f"{o}.deck must be 'solid' or 'girders' (got {self.deck!r})")
        if self.deck == "girders":
            from liftoff.core.beam import standard_section

            standard_section(self.girder_section, f"{o}.girder_section")
        require_positive(o, deck_thickness=self.deck_thickness, post_size=self.post_size,
                         pedestal_size=self.pedestal_size, pedestal_height=self.pedestal_height,
                         pedestal_wall_thickness=self.pedestal_wall_thickness, mass=self.mass,
                         flange_thickness=self.flange_thickness, mesh_size=self.mesh_size,
                         post_mesh_size=self.post_mesh_size)
        require_positive(o, **{f"deck_size[{i}]": v for i, v in enumerate(self.deck_size)})
        require_range(o, "mass", self.mass, 1.0e3, 1.0e9, "kg", "the deck and posts of a launch platform")
        if not self.posts:
            raise InputError(f"{o}.posts is empty: the vehicle would stand on nothing")
        if not self.pedestals:
            raise InputError(f"{o}.pedestals is empty: the platform would float")
        lo, hi = self.deck_bounds()
        for n, pt in self.posts.items():
            x, y, z = (float(v) for v in pt)
            if not z > self.deck_top_z:
                raise InputError(f"{o}.posts.{n}: its top z = {z} m must be above the deck top {self.deck_top_z} m")
            h = self.post_size / 2
            if not (lo[0] < x - h and x + h < hi[0] and lo[1] < y - h and y + h < hi[1]):
                raise InputError(f"{o}.posts.{n}: the post at ({x}, {y}) is off the deck")
            for k, (hx, hy, r) in enumerate(self.holes):
                if math.hypot(x - hx, y - hy) - h * math.sqrt(2) <= r:
                    raise InputError(f"{o}.holes[{k}]: the exhaust hole undercuts the post {n!r}")
            for k, (hx, hy, a) in enumerate(self.square_holes):
                if abs(x - hx) < a + h and abs(y - hy) < a + h:
                    raise InputError(f"{o}.square_holes[{k}]: the exhaust hole undercuts the post {n!r}")
        check_pedestals(o, "pedestals", self.pedestals, self.pedestal_size, self.pedestal_wall_thickness, lo, hi)
        if self.flange_thickness >= 0.5 * self.deck_thickness:
            raise InputError(f"{o}.flange_thickness must be < deck_thickness/2")

    def deck_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        (cx, cy), (sx, sy) = self.deck_center_xy, self.deck_size
        return (np.array([cx - sx / 2, cy - sy / 2, self.deck_top_z - self.deck_thickness]),
                np.array([cx + sx / 2, cy + sy / 2, self.deck_top_z]))


def build_platform(p: PlatformParams, out_dir, deck_material_name: str | None = None) -> Geometry:
    """Volumes ``<name>_deck``, ``<name>_posts``, ``<name>_pedestals``; post-top patches
    named after the posts; clamped pedestal bases ``<name>_pedestal_<k>_base``. The deck's
    material is named ``deck_material_name`` (default ``<name>-deck-equivalent``)."""
    if not isinstance(p, PlatformParams):
        raise InputError(f"build_platform expects PlatformParams, got {type(p).__name__}")
    p.check()
    if p.deck == "girders":
        return build_girder_platform(p, Path(out_dir))
    out_dir = Path(out_dir)
    lo, hi = p.deck_bounds()
    H, s, ps, n = p.deck_thickness, p.post_size, p.pedestal_size, p.name
    posts = {k: np.asarray(v, float) for k, v in p.posts.items()}
    with _occ.gmsh_session(n):
        deck = [(3, occ.addBox(*lo, *(hi - lo)))]
        holes = [(3, occ.addCylinder(x, y, lo[2] - 1, 0, 0, H + 2, r)) for x, y, r in p.holes]
        holes += [(3, occ.addBox(x - a, y - a, lo[2] - 1, 2 * a, 2 * a, H + 2)) for x, y, a in p.square_holes]
        if holes:
            deck, _ = occ.cut(deck, holes)
        post_vols = [(3, occ.addBox(x - s / 2, y - s / 2, hi[2], s, s, z - hi[2])) for x, y, z in posts.values()]
        peds = [(3, occ.addBox(x - ps / 2, y - ps / 2, lo[2] - p.pedestal_height, ps, ps, p.pedestal_height))
                for x, y in p.pedestals]
        occ.synchronize()
        groups = _occ.imprint({f"{n}_deck": deck, f"{n}_posts": post_vols, f"{n}_pedestals": peds}, [])
        bfaces = _occ.boundary_faces([d for ds in groups.values() for d in ds])
        patches, clamped, tol = [], [], 1e-3
        for name, (x, y, z) in posts.items():
            _occ.add_physical(2, name, _occ.faces_inside(bfaces, (x - s / 2, y - s / 2, z - tol,
                                                                  x + s / 2, y + s / 2, z + tol)))
            patches.append(Patch(name, np.array([x, y, z])))
        _occ.refine_faces(_occ.boundary_faces(groups[f"{n}_posts"], combined=False), min(p.mesh_size, p.post_mesh_size))
        zb = lo[2] - p.pedestal_height
        for k, (x, y) in enumerate(p.pedestals):
            name = f"{n}_pedestal_{k + 1}_base"
            _occ.add_physical(2, name, _occ.faces_inside(bfaces, (x - ps / 2, y - ps / 2, zb - tol,
                                                                  x + ps / 2, y + ps / 2, zb + tol)))
            clamped.append(name)
        for g, ds in groups.items():
            _occ.add_physical(3, g, [tg for _, tg in ds])
        vols = {g: _occ.group_volume(ds) for g, ds in groups.items()}
        areas = _occ.physical_measures(2)
        n_nodes = _occ.mesh_and_write(out_dir / f"{n}.msh", p.mesh_size)
    post_mass = STEEL.rho * vols[f"{n}_posts"]
    if p.mass <= post_mass:
        raise InputError(f"PlatformParams({n}).mass {p.mass} kg is less than the posts' mass {post_mass:.0f} kg")
    mats = {f"{n}_deck": deck_material(deck_material_name or f"{n}-deck-equivalent", p.mass - post_mass,
                                       vols[f"{n}_deck"], p.flange_thickness, H),
            f"{n}_posts": STEEL, f"{n}_pedestals": pedestal_material(ps, p.pedestal_wall_thickness)}
    geo = Geometry(n, str(out_dir / f"{n}.msh"), mats, patches, [], [], clamped, vols, n_nodes, areas)
    geo.save(out_dir / f"{n}.json")
    return geo


def _crosses_hole(p: PlatformParams, a: np.ndarray, b: np.ndarray) -> bool:
    """Whether the deck segment a-b (x, y) passes through an exhaust hole."""
    d = b - a
    for hx, hy, r in p.holes:
        s = np.clip(np.dot(np.array([hx, hy]) - a, d) / np.dot(d, d), 0.0, 1.0)
        if np.hypot(*(a + s * d - np.array([hx, hy]))) < r:
            return True
    return any(_segment_enters_square(a, d, (hx, hy), h) for hx, hy, h in p.square_holes)


def _segment_enters_square(a: np.ndarray, d: np.ndarray, centre, h: float) -> bool:
    """Whether the segment a + s d (0 <= s <= 1) enters the open square |x - cx| < h,
    |y - cy| < h: the intersection of its parameter intervals (Liang-Barsky clipping)."""
    lo, hi = -math.inf, math.inf
    for i in range(2):
        if d[i] == 0.0:
            if abs(a[i] - centre[i]) >= h:
                return False
            continue
        s1, s2 = sorted(((centre[i] - h - a[i]) / d[i], (centre[i] + h - a[i]) / d[i]))
        lo, hi = max(lo, s1), min(hi, s2)
    return lo < hi and lo < 1.0 and hi > 0.0


def girder_grid(p: PlatformParams) -> tuple[list, list]:
    """The deck's girders as segments [(x0, y0), (x1, y1)] between consecutive grid points:
    a girder along x through every post's and pedestal's y, and one along y through every
    post's and pedestal's x, each spanning between the outermost crossing girders (no
    overhangs: the deck beyond them is carried as their non-structural mass), less the
    segments through an exhaust hole; (girders along x, girders along y). InputError if a post or
    a pedestal is left without a girder."""
    pts = [(float(v[0]), float(v[1])) for v in p.posts.values()] + [(float(q[0]), float(q[1])) for q in p.pedestals]
    ys = sorted({round(y, 9) for _, y in pts})          # girders along x at these y, along y at these x:
    xs = sorted({round(x, 9) for x, _ in pts})          # each ends on the outermost crossing girders
    along_x = [((x0, y), (x1, y)) for y in ys for x0, x1 in zip(xs[:-1], xs[1:])
               if not _crosses_hole(p, np.array([x0, y]), np.array([x1, y]))]
    along_y = [((x, y0), (x, y1)) for x in xs for y0, y1 in zip(ys[:-1], ys[1:])
               if not _crosses_hole(p, np.array([x, y0]), np.array([x, y1]))]
    ends = {e for seg in along_x + along_y for e in seg}
    for what, named in (("post", {n: (v[0], v[1]) for n, v in p.posts.items()}),
                        ("pedestal", {str(k): (q[0], q[1]) for k, q in enumerate(p.pedestals)})):
        for n, (x, y) in named.items():
            if (round(float(x), 9), round(float(y), 9)) not in ends:
                raise InputError(f"PlatformParams({p.name}): the {what} {n} at ({x}, {y}) has no girder (every grid "
                                 "line to it crosses an exhaust hole)")
    return along_x, along_y


def build_girder_platform(p: PlatformParams, out_dir: Path) -> Geometry:
    """``deck = "girders"``: the deck as a grid of girders (beams of ``girder_section`` at
    the deck's mid-depth; :func:`girder_grid`), the posts as square steel bars of
    ``post_size`` from the grid up to their tops and the pedestals as hollow square steel
    columns (``pedestal_size``, ``pedestal_wall_thickness``) from the grid down to the
    ground, all beams (fem.beam) on the curve groups ``<name>_girders_x``,
    ``<name>_girders_y``, ``<name>_posts``, ``<name>_pedestals``. Each post top is a physical
    point, the post's patch (its one node, six DOFs); each pedestal base the physical point
    ``<name>_pedestal_<k>_base``, clamped. All steel; the deck's mass beyond its posts' and
    girders' steel (``mass`` less theirs) is carried by the girders as non-structural mass
    per length (translational: no rotary inertia)."""
    from liftoff.core.beam import box_section, rectangle, standard_section

    from .spec import BeamGroup

    lo, hi = p.deck_bounds()
    zm = 0.5 * (lo[2] + hi[2])
    zb = lo[2] - p.pedestal_height
    n = p.name
    along_x, along_y = girder_grid(p)
    with _occ.gmsh_session(n):
        def line(a, b):
            return occ.addLine(occ.addPoint(*a), occ.addPoint(*b))

        gx = [line((x0, y0, zm), (x1, y1, zm)) for (x0, y0), (x1, y1) in along_x]
        gy = [line((x0, y0, zm), (x1, y1, zm)) for (x0, y0), (x1, y1) in along_y]
        posts = {k: line((v[0], v[1], zm), tuple(float(c) for c in v)) for k, v in p.posts.items()}
        peds = [line((x, y, zb), (x, y, zm)) for x, y in p.pedestals]
        every = [(1, t) for t in gx + gy + list(posts.values()) + peds]
        _, pieces = occ.fragment(every, [])
        occ.synchronize()
        new = {t: [c for d, c in kids if d == 1] for (_, t), kids in zip(every, pieces)}
        for group, tags in ((f"{n}_girders_x", gx), (f"{n}_girders_y", gy), (f"{n}_posts", list(posts.values())),
                            (f"{n}_pedestals", peds)):
            if tags:                   # (a grid may have no girder along y, or along x)
                _occ.add_physical(1, group, sorted({c for t in tags for c in new[t]}))
        lengths = _occ.physical_measures(1)
        patches, clamped = [], []
        for name, v in p.posts.items():
            _occ.add_physical(0, name, [_occ.point_at(v, 1e-6)])
            patches.append(Patch(name, np.asarray(v, float)))
        for k, (x, y) in enumerate(p.pedestals):
            name = f"{n}_pedestal_{k + 1}_base"
            _occ.add_physical(0, name, [_occ.point_at((x, y, zb), 1e-6)])
            clamped.append(name)
        n_nodes = _occ.mesh_and_write(out_dir / f"{n}.msh", p.mesh_size)
    girder, _ = standard_section(p.girder_section, f"PlatformParams({n}).girder_section", STEEL.nu)
    post = rectangle(p.post_size, p.post_size, STEEL.nu)
    girder_length = lengths.get(f"{n}_girders_x", 0.0) + lengths.get(f"{n}_girders_y", 0.0)
    steel = STEEL.rho * (post.A * lengths[f"{n}_posts"] + girder.A * girder_length)
    if p.mass <= steel:
        raise InputError(f"PlatformParams({n}).mass {p.mass:.0f} kg is less than its posts' and girders' steel, "
                         f"{steel:.0f} kg (girder_section {p.girder_section})")
    nsm = (p.mass - steel) / girder_length            # the deck's other mass, carried by its girders (kg/m)
    beams = {g: BeamGroup(STEEL, girder, vref=v, nsm=nsm) for g, v in ((f"{n}_girders_x", (0.0, 1.0, 0.0)),
                                                                     (f"{n}_girders_y", (1.0, 0.0, 0.0)))
             if g in lengths}
    beams[f"{n}_posts"] = BeamGroup(STEEL, post, vref=(1.0, 0.0, 0.0))
    beams[f"{n}_pedestals"] = BeamGroup(STEEL, box_section(p.pedestal_size, p.pedestal_size, p.pedestal_wall_thickness),
                                        vref=(1.0, 0.0, 0.0))
    geo = Geometry(n, str(out_dir / f"{n}.msh"), {}, patches, [], [], clamped, {}, n_nodes, {},
                   beams=beams, curve_lengths=lengths)
    geo.save(out_dir / f"{n}.json")
    return geo
