"""Launch pad: a mobile-launcher-platform-like deck on pedestals clamped to the ground, with
hold-down posts where the boosters stand (global frame of :mod:`meshes.layout`).

The real deck is a two-storey steel box-girder structure; here it is a solid box with
exhaust holes, with an *equivalent* density (deck mass / box volume) and an equivalent
modulus that gives the bending stiffness of two steel flange layers of effective thickness
``deck_flange_thickness`` at the deck's top and bottom: E_eq = 6 E_steel t_f / H
(solid plate E_eq H^3/12 = steel flanges E t_f H^2/2). Shear stiffness and local
stiffness under the posts are only approximate. Defaults and sources: docs/meshes.md.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from liftoff.core.errors import InputError

from . import _occ
from ._occ import occ
from .layout import SIDES, StackLayout
from .spec import Geometry, Material, Patch, require_positive, require_range

STEEL = Material("steel", 200e9, 0.29, 7850.0)


@dataclass
class PadParams:
    """Pad geometry and masses (SI). The deck top is at z = -post_height (post tops at z = 0,
    the hold-down level); pedestals stand under the deck, their bottoms fixed to ground."""

    layout: StackLayout = field(default_factory=StackLayout)
    deck_length_x: float = 49.0
    deck_width_y: float = 41.0
    deck_thickness: float = 7.6
    deck_center_xy: tuple = (0.0, 2.0)
    mlp_mass: float = 3_730_000.0         # deck + hold-down posts (kg)
    deck_flange_thickness: float = 0.05   # effective steel flange thickness for E_eq (m)
    post_height: float = 2.0
    post_size: float = 1.0                # square posts, side (m)
    srb_hole_radius: float = 1.4
    ssme_hole_half_size: float = 2.5
    pedestal_size: float = 2.0
    pedestal_height: float = 6.7
    pedestal_wall_thickness: float = 0.05  # hollow steel columns smeared into solid boxes
    pedestal_xy: tuple = ((-20.0, -16.5), (0.0, -16.5), (20.0, -16.5),
                          (-20.0, 18.5), (0.0, 18.5), (20.0, 18.5))
    mesh_size: float = 1.6
    post_mesh_size: float = 0.35

    name = "pad"

    def check(self) -> None:
        o = "PadParams"
        require_positive(o, deck_length_x=self.deck_length_x, deck_width_y=self.deck_width_y,
                         deck_thickness=self.deck_thickness, mlp_mass=self.mlp_mass,
                         deck_flange_thickness=self.deck_flange_thickness, post_height=self.post_height,
                         post_size=self.post_size, srb_hole_radius=self.srb_hole_radius,
                         ssme_hole_half_size=self.ssme_hole_half_size, pedestal_size=self.pedestal_size,
                         pedestal_height=self.pedestal_height,
                         pedestal_wall_thickness=self.pedestal_wall_thickness, mesh_size=self.mesh_size,
                         post_mesh_size=self.post_mesh_size)
        # a platform's mass: beyond this span the pad's stiffness and mass matrices lose the
        # digits the static start needs (1e30 kg gave "static equilibrium singular")
        require_range(o, "mlp_mass", self.mlp_mass, 1.0e3, 1.0e9, "kg",
                      "the deck and posts of a launch platform (the Shuttle's MLP: 3.7e6 kg)")
        self.layout.check()
        if not self.pedestal_xy:
            raise InputError(f"{o}.pedestal_xy is empty: the pad would float")
        lo, hi = self.deck_bounds()
        for side in SIDES:
            for name, pt in self.layout.holddown_points(side).items():
                if not (np.all(pt[:2] - self.post_size / 2 > lo[:2]) and np.all(pt[:2] + self.post_size / 2 < hi[:2])):
                    raise InputError(f"{o}: hold-down post under {name} is off the deck")
                if np.hypot(*(pt[:2] - self.layout.srb_axis(side))) - self.post_size / np.sqrt(2) <= self.srb_hole_radius:
                    raise InputError(f"{o}.srb_hole_radius: the exhaust hole undercuts the post under {name}")
        check_pedestals(o, "pedestal_xy", self.pedestal_xy, self.pedestal_size, self.pedestal_wall_thickness, lo, hi)
        if self.deck_flange_thickness >= 0.5 * self.deck_thickness:
            raise InputError(f"{o}.deck_flange_thickness must be < deck_thickness/2")

    def deck_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        c = np.asarray(self.deck_center_xy, float)
        lo = np.array([c[0] - self.deck_length_x / 2, c[1] - self.deck_width_y / 2,
                       -self.post_height - self.deck_thickness])
        hi = np.array([c[0] + self.deck_length_x / 2, c[1] + self.deck_width_y / 2, -self.post_height])
        return lo, hi

    def post_points(self) -> dict[str, np.ndarray]:
        """``{"pad_post_<side>_<k>": point}``: the booster hold-down points of the layout."""
        out = {}
        for side in SIDES:
            for name, pt in self.layout.holddown_points(side).items():
                out[name.replace(f"srb_{side}_hd_", f"pad_post_{side}_")] = pt
        return out


def pad_closed_form_volumes(p: PadParams) -> dict[str, float]:
    """Closed-form volumes (m^3) of deck (box minus exhaust holes), posts and pedestals."""
    H = p.deck_thickness
    deck = p.deck_length_x * p.deck_width_y * H - 2 * np.pi * p.srb_hole_radius ** 2 * H \
        - (2 * p.ssme_hole_half_size) ** 2 * H
    posts = len(p.post_points()) * p.post_size ** 2 * p.post_height
    peds = len(p.pedestal_xy) * p.pedestal_size ** 2 * p.pedestal_height
    return {"pad_deck": float(deck), "pad_posts": float(posts), "pad_pedestals": float(peds)}


def check_pedestals(owner: str, key: str, pedestals, size: float, wall: float, lo, hi) -> None:
    """InputError naming ``owner.key[k]`` unless every square pedestal of side ``size`` at
    (x, y) lies under the deck (bounds ``lo``, ``hi``), or its hollow ``wall`` is too thick."""
    for k, (x, y) in enumerate(pedestals):
        if not (lo[0] < x - size / 2 and x + size / 2 < hi[0] and lo[1] < y - size / 2 and y + size / 2 < hi[1]):
            raise InputError(f"{owner}.{key}[{k}] = ({x}, {y}) is not under the deck")
    if wall >= 0.5 * size:
        raise InputError(f"{owner}.pedestal_wall_thickness must be < pedestal_size/2")


def deck_material(name: str, mass: float, volume: float, flange_thickness: float, thickness: float) -> Material:
    """A platform deck as a solid box: density mass / volume, and the modulus that gives the
    bending stiffness of two steel flanges of ``flange_thickness`` at its top and bottom,
    E_eq = 6 E_steel t_f / H (module docstring)."""
    return Material(name, 6 * STEEL.E * flange_thickness / thickness, 0.3, mass / volume)


def pedestal_material(size: float, wall: float) -> Material:
    """A hollow square steel column of side ``size`` and ``wall`` smeared into a solid box:
    E and rho times the steel's share of the box's area."""
    fill = 1 - (1 - 2 * wall / size) ** 2
    return Material("steel-column-equivalent", STEEL.E * fill, STEEL.nu, STEEL.rho * fill)


def build_pad(p: PadParams, out_dir) -> Geometry:
    """Pad: volumes ``pad_deck``, ``pad_posts``, ``pad_pedestals``; post-top patches
    ``pad_post_<side>_<k>`` (reference points = booster hold-down points); clamped
    surfaces ``pad_pedestal_<k>_base``."""
    if not isinstance(p, PadParams):
        raise InputError(f"build_pad expects PadParams, got {type(p).__name__}")
    p.check()
    out_dir = Path(out_dir)
    lo, hi = p.deck_bounds()
    H, s, ps = p.deck_thickness, p.post_size, p.pedestal_size
    with _occ.gmsh_session(p.name):
        deck = [(3, occ.addBox(*lo, *(hi - lo)))]
        holes = [(3, occ.addCylinder(*p.layout.srb_axis(side), lo[2] - 1, 0, 0, H + 2, p.srb_hole_radius))
                 for side in SIDES]
        oy = p.layout.orbiter_axis_y
        hs = p.ssme_hole_half_size
        holes.append((3, occ.addBox(-hs, oy - hs, lo[2] - 1, 2 * hs, 2 * hs, H + 2)))
        deck, _ = occ.cut(deck, holes)
        posts = {n: (3, occ.addBox(pt[0] - s / 2, pt[1] - s / 2, hi[2], s, s, p.post_height))
                 for n, pt in p.post_points().items()}
        peds = [(3, occ.addBox(x - ps / 2, y - ps / 2, lo[2] - p.pedestal_height, ps, ps, p.pedestal_height))
                for x, y in p.pedestal_xy]
        occ.synchronize()
        groups = _occ.imprint({"pad_deck": deck, "pad_posts": list(posts.values()), "pad_pedestals": peds}, [])
        allv = [d for ds in groups.values() for d in ds]
        bfaces = _occ.boundary_faces(allv)
        patches, clamped = [], []
        tol = 1e-3
        for name, pt in p.post_points().items():
            faces = _occ.faces_inside(bfaces, (pt[0] - s / 2, pt[1] - s / 2, -tol, pt[0] + s / 2, pt[1] + s / 2, tol))
            _occ.add_physical(2, name, faces)
            patches.append(Patch(name, pt))
        post_faces = _occ.boundary_faces(groups["pad_posts"], combined=False)
        _occ.refine_faces(post_faces, min(p.mesh_size, p.post_mesh_size))
        zb = lo[2] - p.pedestal_height
        for k, (x, y) in enumerate(p.pedestal_xy):
            faces = _occ.faces_inside(bfaces, (x - ps / 2, y - ps / 2, zb - tol, x + ps / 2, y + ps / 2, zb + tol))
            name = f"pad_pedestal_{k + 1}_base"
            _occ.add_physical(2, name, faces)
            clamped.append(name)
        for g, ds in groups.items():
            _occ.add_physical(3, g, [tg for _, tg in ds])
        vols = {g: _occ.group_volume(ds) for g, ds in groups.items()}
        areas = _occ.physical_measures(2)
        n_nodes = _occ.mesh_and_write(out_dir / f"{p.name}.msh", p.mesh_size)
    post_mass = STEEL.rho * vols["pad_posts"]
    if p.mlp_mass <= post_mass:
        raise InputError(f"PadParams.mlp_mass {p.mlp_mass} kg is less than the posts' mass {post_mass:.0f} kg")
    mats = {"pad_deck": deck_material("MLP-deck-equivalent", p.mlp_mass - post_mass, vols["pad_deck"],
                                      p.deck_flange_thickness, H),
            "pad_posts": STEEL, "pad_pedestals": pedestal_material(ps, p.pedestal_wall_thickness)}
    geo = Geometry(p.name, str(out_dir / f"{p.name}.msh"), mats, patches, [], [], clamped, vols, n_nodes, areas)
    geo.save(out_dir / f"{p.name}.json")
    return geo


def default_pad(mesh_size: float | None = None, out_dir="out/meshes", layout: StackLayout | None = None) -> Geometry:
    """Build the default pad (``mesh_size`` overrides the deck's default size)."""
    kw = {} if mesh_size is None else {"mesh_size": mesh_size}
    return build_pad(PadParams(layout=layout or StackLayout(), **kw), out_dir)
