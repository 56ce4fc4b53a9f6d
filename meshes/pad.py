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

import numpy as np

from liftoff.core.errors import InputError

from .layout import SIDES, StackLayout
from .spec import Geometry, Material, require_positive, require_range

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
    deck: str = "solid"                   # or "girders": beams (meshes.platform.build_girder_platform)
    girder_section: dict = field(default_factory=dict)

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
        if self.deck != "solid":        # the deck's kind and girders: the platform's own check
            self.platform().check()

    def deck_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        c = np.asarray(self.deck_center_xy, float)
        lo = np.array([c[0] - self.deck_length_x / 2, c[1] - self.deck_width_y / 2,
                       -self.post_height - self.deck_thickness])
        hi = np.array([c[0] + self.deck_length_x / 2, c[1] + self.deck_width_y / 2, -self.post_height])
        return lo, hi

    def platform(self):
        """The launch table as a platform (meshes.platform.PlatformParams): posts under the
        layout's booster hold-down points, the boosters' round exhaust holes and the
        orbiter engines' square one."""
        from .platform import PlatformParams

        lo, hi = self.deck_bounds()
        return PlatformParams(
            name=self.name, deck_size=(self.deck_length_x, self.deck_width_y),
            deck_center_xy=tuple(self.deck_center_xy), deck_thickness=self.deck_thickness, deck_top_z=float(hi[2]),
            posts={n: tuple(float(v) for v in pt) for n, pt in self.post_points().items()}, post_size=self.post_size,
            holes=tuple((*(float(v) for v in self.layout.srb_axis(side)), self.srb_hole_radius) for side in SIDES),
            square_holes=((0.0, float(self.layout.orbiter_axis_y), self.ssme_hole_half_size),),
            pedestals=tuple(self.pedestal_xy), pedestal_size=self.pedestal_size, pedestal_height=self.pedestal_height,
            pedestal_wall_thickness=self.pedestal_wall_thickness, mass=self.mlp_mass,
            flange_thickness=self.deck_flange_thickness, mesh_size=self.mesh_size, post_mesh_size=self.post_mesh_size,
            deck=self.deck, girder_section=dict(self.girder_section))

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
    surfaces ``pad_pedestal_<k>_base``: the platform (meshes/platform.py) the layout places,
    :meth:`PadParams.platform`."""
    if not isinstance(p, PadParams):
        raise InputError(f"build_pad expects PadParams, got {type(p).__name__}")
    p.check()
    from .platform import build_platform

    return build_platform(p.platform(), out_dir, deck_material_name="MLP-deck-equivalent")


def default_pad(mesh_size: float | None = None, out_dir="out/meshes", layout: StackLayout | None = None) -> Geometry:
    """Build the default pad (``mesh_size`` overrides the deck's default size)."""
    kw = {} if mesh_size is None else {"mesh_size": mesh_size}
    return build_pad(PadParams(layout=layout or StackLayout(), **kw), out_dir)
