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
    deck_size: tuple = (40.0, 40.0)
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

    def check(self) -> None:
        o = f"PlatformParams({self.name})"
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
