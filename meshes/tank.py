"""Propellant tank: thick-walled cylinder with half-ellipsoidal end domes, optionally several
compartments stacked on one axis and joined by cylindrical intertank skirts (an external-
tank-like core stage is two compartments: LH2 aft, LOX forward).

Liquid (``TankParams.liquid``): ``"smeared"``, non-structural mass spread uniformly over the
wetted inner wall up to the fill level (``SmearedMass`` on the group
``<tank>_<compartment>_wetted``), mass = liquid density x liquid volume (closed form below);
or ``"hydroelastic"``, the liquid meshed with tetrahedra inside each compartment up to its
fill level (volume group ``<tank>_<compartment>_liquid``, a ``spec.Liquid``), sharing the
wetted surface ``<tank>_<compartment>_wetted`` with the wall (the solid wall's inner face,
or the shell surface); its free surface ``<tank>_<compartment>_free_surface`` faces the
empty ullage; ``<tank>_<compartment>_cavity`` is the compartment's whole inner wall (ullage
volume) and the point group ``<tank>_<compartment>_bottom`` the liquid's lowest point
(tank-bottom pressure). fem.liquid turns it into an added mass. Units SI. See docs/meshes.md.

Walls (``TankParams.walls``): ``"solid"``, a thick wall of tetrahedra (outer radius R,
thickness ``wall_thickness``, thickened: density and E scaled to the dry mass); or
``"shell"``, the wall's mid-surface (radius R - t/2, dome heights a - t/2) meshed with
triangles for fem.shell, with the real material and the thickness that gives the dry mass
(``shell_thickness`` to set it). The two share everything else: group names (the wall
group ``<name>_wall`` is a volume or a surface group), patches, fill cuts, the cavity and
hence the liquid mass. The closed shell surface bounds each compartment's cavity, so
liquid volumes can later be meshed against the same faces.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from liftoff.core.errors import InputError

from . import _occ
from ._occ import occ
from .spec import (Geometry, Liquid, Material, SmearedMass, check_attach, check_ring_frames, check_stringers, check_walls,
                   equivalent, require_positive)

#: liquid models of a tank (TankParams.liquid)
LIQUIDS = ("smeared", "hydroelastic")

#: Aluminium alloy 2219 (the Shuttle external tank's alloy): E 73.8 GPa, nu 0.33, 2840 kg/m^3
AL2219 = Material("Al2219", 73.8e9, 0.33, 2840.0)


@dataclass
class Compartment:
    """One liquid compartment. Dome ratios are outer dome height / outer radius (1 =
    hemisphere, < 1 oblate, > 1 prolate); the inner dome height is the outer one minus the
    wall thickness. ``fill_level`` is the wetted fraction (0, 1] of the cavity's inner
    height, measured from the inner bottom apex."""

    name: str = "lox"
    cyl_length: float = 4.6
    dome_bottom: float = 0.72
    dome_top: float = 1.6
    fill_level: float = 0.97
    liquid_density: float = 1141.0  # LOX at its boiling point, kg/m^3
    ullage_pressure: float = 0.0    # gauge pressure of the ullage gas, Pa (shell walls, hydroelastic: prestress)

    def check(self, owner: str = "Compartment") -> None:
        require_positive(f"{owner}.{self.name}", cyl_length=self.cyl_length, dome_bottom=self.dome_bottom,
                         dome_top=self.dome_top, liquid_density=self.liquid_density)
        u = self.ullage_pressure
        if isinstance(u, bool) or not isinstance(u, (int, float)) or not (math.isfinite(u) and u >= 0):
            raise InputError(f"{owner}.{self.name}.ullage_pressure must be a gauge pressure >= 0 Pa (got {u!r})")
        f = self.fill_level
        if not (isinstance(f, (int, float)) and 0.0 < f <= 1.0):
            raise InputError(f"{owner}.{self.name}.fill_level must be in (0, 1] (got {f!r})")


@dataclass
class TankParams:
    """Tank geometry (SI). ``z_bottom`` is the outer apex of the lowest dome; compartments
    are listed bottom to top; consecutive ones are joined by an intertank skirt (the wall
    continued as a cylinder) of ``intertank_length`` between their cylinder ends.
    ``patches``: reference points; a point on the axis gives a disk patch on the nearest
    dome apex, any other point a (2w x 2w) patch on the outer cylindrical wall at the
    point's azimuth and height; with shell walls and ``attach="ring"`` an off-axis point
    instead interpolates (RBE3) the wall's nodes on the ring at its height over a half
    circumference (meshes.shells.ring_patches). ``dry_mass`` (kg): if given, the wall density is set so that
    the structure weighs this much and E is scaled with it (E/rho of ``material`` kept)."""

    name: str = "tank"
    radius: float = 4.2
    wall_thickness: float = 0.15
    compartments: tuple = (Compartment(),)
    intertank_length: float = 6.9
    z_bottom: float = 0.0
    axis_xy: tuple = (0.0, 0.0)
    material: Material = field(default_factory=lambda: replace(AL2219))
    dry_mass: float | None = 5500.0
    patches: dict = field(default_factory=lambda: {"tank_bottom": (0.0, 0.0, 0.0),
                                                    "tank_top": (0.0, 0.0, 4.6 + 0.72 * 4.2 + 1.6 * 4.2)})
    patch_half_width: float = 0.5
    mesh_size: float = 0.6
    walls: str = "solid"                  # "solid" (thickened tetrahedra) or "shell" (mid-surface)
    shell_thickness: float | None = None  # shell walls: None = the thickness of `material` that weighs dry_mass
    shell_bending_ratio: float = 1.0      # shell walls: 12 I / t^3 (frames, stringers smeared; 1 = bare skin)
    liquid: str = "smeared"               # "smeared" (wetted-wall mass) or "hydroelastic" (liquid volumes, fem.liquid)
    slosh_modes: int = 0                  # hydroelastic: gravity slosh modes kept per compartment (0: p = 0 free surface)
    attach: str = "patch"                 # shell walls: wall points as rigid "patch"es or "ring" interpolations (RBE3)
    frames: tuple = ()                    # shell walls: heights z (m) of ring frames on the cylindrical wall (beams)
    frame_section: dict = field(default_factory=dict)   # their {shape, dims} (liftoff.core.beam.standard_section)
    frame_material: Material | None = None  # the frames' material (None: `material`)
    stringers: int = 0                    # shell walls: stringers (beams) along the whole cylindrical wall
    stringer_azimuth: float = 0.0         # azimuth (deg) of the first; the others equally spaced
    stringer_section: dict = field(default_factory=dict)   # their {shape, dims}, web radial
    stringer_material: Material | None = None  # (None: `material`)

    def check(self) -> None:
        o = f"TankParams({self.name})"
        check_walls(o, self.walls)
        if self.liquid not in LIQUIDS:
            raise InputError(f"{o}.liquid must be one of {', '.join(map(repr, LIQUIDS))} (got {self.liquid!r})")
        if isinstance(self.slosh_modes, bool) or not isinstance(self.slosh_modes, (int, float)) \
                or self.slosh_modes != int(self.slosh_modes) or self.slosh_modes < 0:
            raise InputError(f"{o}.slosh_modes must be an integer >= 0 (got {self.slosh_modes!r})")
        self.slosh_modes = int(self.slosh_modes)
        check_attach(o, self.walls, self.attach)
        if self.shell_thickness is not None:
            require_positive(o, shell_thickness=self.shell_thickness)
        require_positive(o, shell_bending_ratio=self.shell_bending_ratio)
        require_positive(o, radius=self.radius, wall_thickness=self.wall_thickness,
                         intertank_length=self.intertank_length, mesh_size=self.mesh_size,
                         patch_half_width=self.patch_half_width)
        if self.dry_mass is not None:
            require_positive(o, dry_mass=self.dry_mass)
        if not self.compartments:
            raise InputError(f"{o}.compartments is empty")
        if self.wall_thickness >= 0.5 * self.radius:
            raise InputError(f"{o}.wall_thickness {self.wall_thickness} m must be < radius/2")
        for c in self.compartments:
            c.check(o)
            if c.ullage_pressure > 0 and (self.walls != "shell" or self.liquid != "hydroelastic"):
                raise InputError(f"{o}.{c.name}.ullage_pressure: the pressure prestress needs walls = 'shell' and "
                                 f"liquid = 'hydroelastic' (got {self.walls!r}, {self.liquid!r}); set it to 0")
            if self.liquid == "hydroelastic" and c.fill_level >= 1.0:
                raise InputError(f"{o}.{c.name}.fill_level {c.fill_level!r} reaches the tank top: a hydroelastic "
                                 "liquid needs an ullage above its free surface (fill_level < 1)")
            for which in ("dome_bottom", "dome_top"):
                if getattr(c, which) * self.radius <= 2 * self.wall_thickness:
                    raise InputError(f"{o}.{c.name}.{which}: dome height must exceed 2 x wall_thickness")
        for lo, hi in zip(self.compartments[:-1], self.compartments[1:]):
            need = (lo.dome_top + hi.dome_bottom) * self.radius
            if self.intertank_length <= need + self.wall_thickness:
                raise InputError(f"{o}.intertank_length {self.intertank_length} m: domes collide "
                                 f"(needs > {need + self.wall_thickness:.3f} m)")
        if len({c.name for c in self.compartments}) != len(self.compartments):
            raise InputError(f"{o}.compartments: duplicate names")
        self.check_frames()

    def check_frames(self) -> None:
        """Ring frames and stringers: shell walls, a section, frame heights strictly inside
        the cylindrical wall, a whole number of stringers."""
        o = f"TankParams({self.name})"
        self.stringers = check_stringers(o, self.walls, self.stringers, self.stringer_section, self.stringer_material)
        lay = tank_layout(self)
        check_ring_frames(o, self.walls, self.frames, self.frame_section, self.frame_material,
                          lay[0].z_cyl_bottom, lay[-1].z_cyl_top)


# ---- closed forms (inner cavity of one compartment; heights h from the inner bottom apex) ----
def dome_volume(r: float, a: float) -> float:
    """Half-ellipsoid of radius r and height a."""
    return 2.0 / 3.0 * math.pi * r * r * a


def capsule_volume(r: float, a_bottom: float, a_top: float, length: float) -> float:
    return math.pi * r * r * length + dome_volume(r, a_bottom) + dome_volume(r, a_top)


def liquid_volume(r: float, a_b: float, a_t: float, length: float, h: float) -> float:
    """Volume of the capsule (r, a_b, a_t, length) below height h above its bottom apex."""
    hb = min(max(h, 0.0), a_b)
    v = math.pi * r * r * (hb * hb / a_b - hb ** 3 / (3 * a_b * a_b))
    v += math.pi * r * r * min(max(h - a_b, 0.0), length)
    s = min(max(h - a_b - length, 0.0), a_t)
    return v + math.pi * r * r * (s - s ** 3 / (3 * a_t * a_t))


def _zone(r: float, a: float, u: float) -> float:
    """Lateral area of the spheroid (radius r, half-height a) between its equator and |z| = u."""
    c = (r * r - a * a) / a ** 4
    if abs(c) * u * u < 1e-12:
        f = u
    elif c > 0:
        k = math.sqrt(c)
        f = 0.5 * u * math.sqrt(1 + c * u * u) + math.asinh(k * u) / (2 * k)
    else:
        k = math.sqrt(-c)
        f = 0.5 * u * math.sqrt(1 + c * u * u) + math.asin(min(k * u, 1.0)) / (2 * k)
    return 2 * math.pi * r * f


def wetted_area(r: float, a_b: float, a_t: float, length: float, h: float) -> float:
    """Area of the capsule's wall below height h above its bottom apex."""
    hb = min(max(h, 0.0), a_b)
    area = _zone(r, a_b, a_b) - _zone(r, a_b, a_b - hb)
    area += 2 * math.pi * r * min(max(h - a_b, 0.0), length)
    return area + _zone(r, a_t, min(max(h - a_b - length, 0.0), a_t))


# ---- layout ---------------------------------------------------------------------------------
@dataclass
class CompartmentLayout:
    """Heights (m, global z) of one compartment: cylinder ends, inner apices, fill level."""

    name: str
    z_cyl_bottom: float
    z_cyl_top: float
    a_bottom: float  # outer dome heights
    a_top: float
    r_inner: float
    a_bottom_inner: float
    a_top_inner: float
    z_fill: float
    fill_height: float

    @property
    def z_inner_bottom(self) -> float:
        return self.z_cyl_bottom - self.a_bottom_inner

    @property
    def z_inner_top(self) -> float:
        return self.z_cyl_top + self.a_top_inner

    @property
    def cyl_length(self) -> float:
        return self.z_cyl_top - self.z_cyl_bottom

    def liquid_volume(self) -> float:
        return liquid_volume(self.r_inner, self.a_bottom_inner, self.a_top_inner, self.cyl_length, self.fill_height)

    def wetted_area(self) -> float:
        return wetted_area(self.r_inner, self.a_bottom_inner, self.a_top_inner, self.cyl_length, self.fill_height)


def tank_layout(p: TankParams) -> list[CompartmentLayout]:
    """Global heights of each compartment (bottom to top)."""
    R, t = p.radius, p.wall_thickness
    out, z = [], p.z_bottom
    for i, c in enumerate(p.compartments):
        ab, at = c.dome_bottom * R, c.dome_top * R
        z_cb = z + ab if i == 0 else z
        z_ct = z_cb + c.cyl_length
        h_in = (ab - t) + c.cyl_length + (at - t)
        fill_h = c.fill_level * h_in
        out.append(CompartmentLayout(c.name, z_cb, z_ct, ab, at, R - t, ab - t, at - t,
                                     z_cb - (ab - t) + fill_h, fill_h))
        z = z_ct + p.intertank_length
    return out


def tank_height(p: TankParams) -> float:
    """Overall outer height (m) from the bottom apex to the top apex."""
    lay = tank_layout(p)
    return lay[-1].z_cyl_top + lay[-1].a_top - p.z_bottom


def wall_volume(p: TankParams) -> float:
    """Closed-form volume of the tank wall (shells + intertank skirts), m^3."""
    R, t = p.radius, p.wall_thickness
    v = 0.0
    lay = tank_layout(p)
    for c in lay:
        v += capsule_volume(R, c.a_bottom, c.a_top, c.cyl_length)
        v -= capsule_volume(c.r_inner, c.a_bottom_inner, c.a_top_inner, c.cyl_length)
    for lo, hi in zip(lay[:-1], lay[1:]):
        # skirt annulus between the cylinder ends, minus its overlap with the two domes'
        # shells (the annulus R-t < rho < R intersected with each dome shell, by quadrature
        # of the exact cross-section: independent of gmsh)
        v += math.pi * (R * R - (R - t) ** 2) * (hi.z_cyl_bottom - lo.z_cyl_top)
        v -= _dome_annulus_overlap(R, t, lo.a_top, lo.a_top_inner) + _dome_annulus_overlap(
            R, t, hi.a_bottom, hi.a_bottom_inner)
    return v


def _dome_annulus_overlap(R: float, t: float, a: float, a_i: float, n: int = 4000) -> float:
    """Volume of {R - t < rho < R} inside a dome shell (outer (R, a), inner (R - t, a_i))."""
    from scipy.integrate import quad

    def area(s: float) -> float:
        ro = R * math.sqrt(max(1 - (s / a) ** 2, 0.0))
        ri = (R - t) * math.sqrt(max(1 - (s / a_i) ** 2, 0.0)) if s < a_i else 0.0
        lo, hi = max(ri, R - t), ro
        return math.pi * (hi * hi - lo * lo) if hi > lo else 0.0

    return quad(area, 0.0, a, limit=200, points=[a_i])[0]


# ---- builder ---------------------------------------------------------------------------------
def _profile(p: TankParams) -> list:
    R, t = p.radius, p.wall_thickness
    pieces = []
    lay = tank_layout(p)
    for c in lay:
        pieces += _occ.shell_profile(R, t, c.a_bottom, c.a_top, c.z_cyl_bottom, c.cyl_length)
    for lo, hi in zip(lay[:-1], lay[1:]):
        for x0 in (R - t, -R):
            pieces.append((2, occ.addRectangle(x0, lo.z_cyl_top, 0, t, hi.z_cyl_bottom - lo.z_cyl_top)))
    if len(pieces) > 1:
        pieces, _ = occ.fuse(pieces[:1], pieces[1:])
    return _occ.half(pieces)


def patch_tool(name: str, ref, axis_xy, r_out: float, r_in: float, z_lo_apex: float, z_hi_apex: float,
               cyl_ranges: list[tuple[float, float]], t: float, w: float, a_lo: float, a_hi: float) -> _occ.Tool:
    """Tool imprinting patch ``name`` for reference point ``ref`` (see TankParams.patches)."""
    ref = np.asarray(ref, float)
    d = ref[:2] - np.asarray(axis_xy, float)
    if np.hypot(*d) < 1e-6:  # apex disk; cut deeper than the dome's drop over the disk, < t
        top = ref[2] >= 0.5 * (z_lo_apex + z_hi_apex)
        a = a_hi if top else a_lo
        drop = a * (1 - math.sqrt(max(1 - (w / r_out) ** 2, 0.0)))
        if drop >= t:
            raise InputError(f"patch {name}: apex patch of half-width {w} m too wide for the dome")
        depth = 0.5 * (drop + t)
        z = z_hi_apex if top else z_lo_apex
        z0, z1 = (z - depth, z + 1.0) if top else (z - 1.0, z + depth)
        return _occ.cylinder_tool(name, axis_xy, w, z0, z1)
    z = float(ref[2])
    if not any(lo + w <= z <= hi - w for lo, hi in cyl_ranges):
        raise InputError(f"patch {name}: height z = {z} m is not on the cylindrical wall "
                         f"(ranges {[(round(a, 3), round(b, 3)) for a, b in cyl_ranges]})")
    return _occ.wall_patch(name, axis_xy, math.atan2(d[1], d[0]), z, r_out, r_in, w, w)


@dataclass
class Cavity:
    """The liquid's cavity in one compartment (m, global z): radius, dome heights and
    cylinder of the surface the liquid touches (the solid wall's inner face, or the shell's
    mid-surface), and its fill height z_fill."""

    name: str
    r: float
    a_bottom: float
    a_top: float
    z_cyl_bottom: float
    z_cyl_top: float
    z_fill: float

    @property
    def z_bottom(self) -> float:
        return self.z_cyl_bottom - self.a_bottom

    def distance(self, axis_xy):
        return _occ.capsule_distance(axis_xy, self.r, self.z_cyl_bottom, self.z_cyl_top, self.a_bottom, self.a_top)

    def liquid_volume(self) -> float:
        return liquid_volume(self.r, self.a_bottom, self.a_top, self.z_cyl_top - self.z_cyl_bottom,
                             self.z_fill - self.z_bottom)


def inner_cavities(p: TankParams) -> list[Cavity]:
    """The cavities bounded by the solid wall's inner faces (fill heights of tank_layout)."""
    return [Cavity(c.name, c.r_inner, c.a_bottom_inner, c.a_top_inner, c.z_cyl_bottom, c.z_cyl_top, c.z_fill)
            for c in tank_layout(p)]


def fill_height(r: float, a_b: float, a_t: float, length: float, volume: float) -> float:
    """Height h above the bottom apex of the capsule (r, a_b, a_t, length) below which it
    holds ``volume`` (m^3): the inverse of :func:`liquid_volume` (bisection to 1e-12 m)."""
    lo, hi = 0.0, a_b + length + a_t
    if not 0.0 < volume < liquid_volume(r, a_b, a_t, length, hi):
        raise InputError(f"a liquid volume of {volume:.6g} m^3 does not fit below the top of its cavity")
    while hi - lo > 1e-12 * (1.0 + hi):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if liquid_volume(r, a_b, a_t, length, mid) < volume else (lo, mid)
    return 0.5 * (lo + hi)


def liquid_solids(p: TankParams, cavities: list[Cavity]) -> dict:
    """The OCC liquid volumes of a hydroelastic tank, one per cavity filled to its level
    (``{<name>_<compartment>_liquid: dimTags}``; empty for smeared liquids)."""
    if p.liquid != "hydroelastic":
        return {}
    out = {f"{p.name}_{c.name}_liquid": _occ.liquid_solid(c.r, c.a_bottom, c.a_top, c.z_cyl_bottom,
                                                          c.z_cyl_top - c.z_cyl_bottom, c.z_fill, p.axis_xy)
           for c in cavities}
    occ.synchronize()
    return out


def compartment_groups(p: TankParams, cavities: list[Cavity], wall_faces: list[int], liquids: dict,
                       mass_cavities: list[Cavity] | None = None):
    """Physical groups of each compartment on the meshed wall: ``<name>_<c>_wetted`` and
    either its smeared liquid mass (``liquids`` empty; the liquid volume of ``mass_cavities``
    if given: a shell's mid-surface cavity is larger than the liquid the tank holds) or, for hydroelastic liquids
    (``liquids``: liquid group -> volume dimTags), the liquid volume, its free surface,
    the compartment's whole cavity wall and its bottom point. Returns (smeared masses,
    {liquid group: spec.Liquid})."""
    ax, ay = p.axis_xy
    tol = 1e-3 * p.radius
    smeared, specs, on_wall = [], {}, set(wall_faces)
    for i, cav in enumerate(cavities):
        liquid = next(k for k in p.compartments if k.name == cav.name)
        base = f"{p.name}_{cav.name}"
        box = (ax - cav.r, ay - cav.r, cav.z_bottom, ax + cav.r, ay + cav.r, cav.z_cyl_top + cav.a_top)
        cavity = _occ.faces_on(_occ.faces_inside(wall_faces, box, tol=tol), cav.distance(p.axis_xy), tol=1e-4 * p.radius)
        if not liquids:
            wet = _occ.faces_inside(cavity, box[:5] + (cav.z_fill,), tol=tol)
            _occ.add_physical(2, f"{base}_wetted", wet)
            held = (mass_cavities or cavities)[i].liquid_volume()
            smeared.append(SmearedMass(f"{base}_wetted", liquid.liquid_density * held))
            continue
        group = f"{base}_liquid"
        wet, free = _occ.liquid_faces(liquids[group], on_wall, group)
        _occ.add_physical(3, group, [t for _, t in liquids[group]])
        _occ.add_physical(2, f"{base}_wetted", wet)
        _occ.add_physical(2, f"{base}_free_surface", free)
        _occ.add_physical(2, f"{base}_cavity", cavity)
        bottom = (ax, ay, cav.z_bottom)
        _occ.add_physical(0, f"{base}_bottom", [_occ.point_at(bottom, tol)])
        specs[group] = Liquid(liquid.liquid_density, f"{base}_wetted", f"{base}_free_surface", f"{base}_cavity",
                              (ax, ay, 0.5 * (cav.z_bottom + cav.z_cyl_top + cav.a_top)),
                              {f"{base}_bottom": bottom}, p.slosh_modes, ullage_pressure=liquid.ullage_pressure)
    return smeared, specs


def build_tank(p: TankParams, out_dir) -> Geometry:
    """Build, mesh and write ``<out_dir>/<name>.msh`` (+ ``.json`` sidecar); return the Geometry.

    Physical groups: ``<name>_wall`` (volume, or surface for shell walls); surfaces
    ``<name>_<compartment>_wetted`` and one per patch; hydroelastic liquids add the volume
    ``<name>_<compartment>_liquid``, the surfaces ``..._free_surface`` and ``..._cavity``
    and the point ``..._bottom`` (module docstring)."""
    if not isinstance(p, TankParams):
        raise InputError(f"build_tank expects TankParams, got {type(p).__name__}")
    p.check()
    if p.walls == "shell":
        from .shells import build_shell_tank
        return build_shell_tank(p, Path(out_dir))
    out_dir = Path(out_dir)
    lay = tank_layout(p)
    R, t, w = p.radius, p.wall_thickness, p.patch_half_width
    wall = f"{p.name}_wall"
    cavities = inner_cavities(p)
    with _occ.gmsh_session(p.name):
        vols = _occ.revolve_to_z(_profile(p), p.axis_xy)
        occ.synchronize()
        cyl_ranges = [(lay[0].z_cyl_bottom, lay[-1].z_cyl_top)]
        tools = [patch_tool(n, ref, p.axis_xy, R, R - t, p.z_bottom, lay[-1].z_cyl_top + lay[-1].a_top,
                            cyl_ranges, t, w, lay[0].a_bottom, lay[-1].a_top) for n, ref in p.patches.items()]
        tools += [_occ.plane_cut(c.z_fill) for c in lay if c.fill_height < (c.z_inner_top - c.z_inner_bottom)]
        for tl in tools:
            if tl.dimtag[0] == 2:
                occ.translate([tl.dimtag], p.axis_xy[0], p.axis_xy[1], 0)
        occ.synchronize()
        groups = _occ.imprint({wall: vols}, tools)
        liquids = liquid_solids(p, cavities)
        if liquids:
            groups, _, liquids = _occ.add_liquids(groups, {}, liquids)
        bfaces = _occ.boundary_faces(groups[wall])
        patches = _occ.patch_groups(bfaces, tools, p.patches, lambda _: min(p.mesh_size, 0.6 * w))
        smeared, specs = compartment_groups(p, cavities, bfaces, liquids)
        _occ.add_physical(3, wall, [tg for _, tg in groups[wall]])
        volume = _occ.group_volume(groups[wall])
        mat = p.material if p.dry_mass is None else equivalent(p.material, p.dry_mass, volume)
        areas = _occ.physical_measures(2)
        volumes = {wall: volume, **{g: _occ.group_volume(v) for g, v in liquids.items()}}
        rho_max = max([R] + [R * R / c.a_bottom for c in lay] + [R * R / c.a_top for c in lay]
                      + [c.a_bottom ** 2 / R for c in lay] + [c.a_top ** 2 / R for c in lay])
        n_nodes = _occ.mesh_and_write(out_dir / f"{p.name}.msh", p.mesh_size,
                                      _occ.curvature_elements(t, rho_max))
    geo = Geometry(p.name, str(out_dir / f"{p.name}.msh"), {wall: mat}, patches, [], smeared, [],
                   volumes, n_nodes, areas, liquids=specs)
    geo.save(out_dir / f"{p.name}.json")
    return geo


__all__ = ["AL2219", "LIQUIDS", "Cavity", "Compartment", "TankParams", "build_tank", "tank_layout", "tank_height",
           "wall_volume", "liquid_volume", "wetted_area", "capsule_volume", "dome_volume", "CompartmentLayout",
           "inner_cavities", "fill_height", "compartment_groups"]
