"""Parameters of the beam stick model of the stack (``[model] source = "stick"``; the beam
builder is liftoff.workflows.stick).

Positions are not repeated here: the stick model takes every interface position (attach,
hold-down and post points, the deck, the pedestals) from :class:`meshes.layout.StackLayout`
and :class:`meshes.pad.PadParams`, the objects the FE builders use, so the stack layout
exists once. What is here: the beams' section properties (thin-walled tubes I = pi R^3 t,
A = 2 pi R t, or given A and I) and the masses smeared on them or lumped at points (m, kg,
Pa; defaults and sources in docs/workflow.md). A beam "density" is a line density, not a
material density.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from liftoff.core.errors import InputError

from .layout import StackLayout
from .pad import PadParams
from .spec import require_positive, require_range

# Physical ranges of the parameters (SI), by the field's kind (from its name); a value
# outside is a slip (units, exponent) that would make the beams' K and M numerically
# singular far from the key (issue 27: srb_mass = 1e-30 "floats (or has a mechanism)").
# Walls: 0.1 mm up to a tenth of the tube's radius (the thin-walled I = pi R^3 t, A = 2 pi R t).
RANGES = {  # kind: (low, high, unit, what)
    "mass": (1.0, 1.0e7, "kg", "the span of a stick-model mass (a kilogram to 10,000 t; the heaviest launch "
                               "vehicles weigh 3,000-5,000 t)"),
    "length": (0.01, 1000.0, "m", "the span of a stick-model length or height (a centimetre to a kilometre)"),
    "modulus": (1.0e9, 1.2e12, "Pa", "the span of a structural Young's modulus (plastics to diamond)"),
    "area": (1.0e-4, 100.0, "m^2", "the span of a beam's section area (1 cm^2 to 100 m^2)"),
    "inertia": (1.0e-6, 1.0e4, "m^4", "the span of a beam's section moment of inertia (a small steel beam to a "
                                     "girder tens of metres deep)"),
}
_KIND = (("_E", "modulus"), ("_A", "area"), ("_I", "inertia"))


def _kind(name: str) -> str:
    """The kind of the StickParams field ``name``: a mass (``*_mass*``), a modulus, area or
    inertia (``*_E``, ``*_A``, ``*_I``), else a length (walls are checked against their tube)."""
    if "_mass" in name:
        return "mass"
    return next((kind for end, kind in _KIND if name.endswith(end)), "length")


@dataclass
class StickParams:
    """Beam stick model of the Shuttle-like stack; positions from ``pad.layout`` and ``pad``."""

    pad: PadParams = field(default_factory=PadParams)   # pad geometry; pad.layout is the stack's layout
    core_top_z: float = 56.1
    core_wall: float = 0.012           # equivalent skin for EA, EI (thin-walled tube)
    core_E: float = 7.0e10
    lox_bottom_z: float = 42.0         # LOX tank (forward) carries most of the propellant
    core_mass_lox: float = 630.0e3
    core_mass_aft: float = 126.0e3     # LH2, intertank, dry structure below lox_bottom_z
    srb_length: float = 45.46
    srb_wall: float = 0.0127
    srb_E: float = 2.0e11
    srb_mass: float = 590.0e3
    gimbal_z: float = 1.30             # aft dome apex
    orbiter_length: float = 37.24
    orbiter_mass: float = 84.46e3      # structure (smeared on the fuselage beam)
    orbiter_I: float = 3.0             # m^4, fuselage bending
    orbiter_A: float = 0.4
    orbiter_E: float = 7.0e10
    ssme_mass: float = 3 * 3180.0
    ssme_cg_below_bulkhead: float = 1.8
    payload_mass: float = 16.0e3
    payload_z: float = 25.0
    deck_I: float = 10.0               # m^4 per girder (0.05 m flanges, 7.6 m deep, ~10 m strips)
    deck_A: float = 1.0
    steel_E: float = 2.0e11
    pedestal_I: float = 2.0
    pedestal_A: float = 0.4
    post_A: float = 1.0                # 1 m square steel posts
    post_I: float = 0.083
    post_mass: float = 15.7e3          # kg per post (1 x 1 x 2 m steel)

    @property
    def layout(self) -> StackLayout:
        return self.pad.layout

    def check(self) -> None:
        o = "StickParams"
        require_positive(o, **{k: getattr(self, k) for k in self.__dataclass_fields__ if k != "pad"})
        self.pad.check()
        lay = self.layout
        walls = {"core_wall": lay.core_radius, "srb_wall": lay.srb_radius}
        for k in self.__dataclass_fields__:
            if k in walls:
                require_range(o, k, getattr(self, k), 1.0e-4, walls[k] / 10, "m",
                              f"a thin wall: 0.1 mm to a tenth of the tube's radius ({walls[k]:g} m)")
            elif k != "pad":
                require_range(o, k, getattr(self, k), *RANGES[_kind(k)])
        if not lay.core_bottom_z < self.lox_bottom_z < self.core_top_z:
            raise InputError(f"{o}.lox_bottom_z = {self.lox_bottom_z} m is not between the core's bottom "
                             f"({lay.core_bottom_z} m) and top ({self.core_top_z} m)")
        if not self.gimbal_z < lay.srb_aft_attach_z < lay.srb_fwd_attach_z < self.srb_length:
            raise InputError(f"{o}: booster stations out of order (gimbal_z < srb_aft_attach_z < "
                             f"srb_fwd_attach_z < srb_length)")
        top = lay.orbiter_bottom_z + self.orbiter_length
        for name, z in (("payload_z", self.payload_z), ("layout.orbiter_fwd_attach_z", lay.orbiter_fwd_attach_z),
                        ("layout.orbiter_aft_attach_z", lay.orbiter_aft_attach_z)):
            if not lay.orbiter_bottom_z < z < top:
                raise InputError(f"{o}.{name} = {z} m is not on the orbiter beam")
        if self.pad.mlp_mass <= len(self.pad.post_points()) * self.post_mass:
            raise InputError(f"{o}.post_mass: the posts weigh more than the pad's mlp_mass")
