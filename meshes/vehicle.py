"""Twin-booster stack like the Space Shuttle: core stage, two boosters, orbiter-like body.

Each component is its own gmsh model / ``.msh`` + JSON sidecar (reduced on its own by
Craig-Bampton), all in the global frame of :mod:`meshes.layout`. Attach patches of two
components that connect carry the SAME name and the SAME reference point (from the
shared :class:`StackLayout`), so assembly overlays them by label. Thin walls are
thickened to keep meshes small; density and E are then scaled so that mass and membrane
(beam) stiffness stay right (E/rho kept). Defaults and sources: docs/meshes.md.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from liftoff.core.errors import InputError

from . import _occ
from ._occ import occ
from .layout import StackLayout
from .shells import stringer_angles
from .spec import (Geometry, Material, PointMass, SmearedMass, check_attach, check_ring_frames, check_stringers,
                   check_walls, equivalent, require_positive)
from .tank import AL2219, Compartment, TankParams, build_tank, tank_height

#: D6AC steel (SRB case): E 205 GPa, nu 0.29, 7850 kg/m^3
STEEL_D6AC = Material("D6AC", 205e9, 0.29, 7850.0)


def _cylinder_inertia(m: float, r: float, length: float) -> np.ndarray:
    """Solid cylinder (axis z) about its centre (kg m^2)."""
    t = m * (3 * r * r + length * length) / 12.0
    return np.diag([t, t, 0.5 * m * r * r])


def _point_inertia(m: float, offsets) -> np.ndarray:
    """Point masses m at offsets (n, 3) about the origin: sum m (|r|^2 I - r r^T)."""
    J = np.zeros((3, 3))
    for r in np.asarray(offsets, float):
        J += m * (r @ r * np.eye(3) - np.outer(r, r))
    return J


# ---- core stage ---------------------------------------------------------------------------
PSI = 6894.757
#: ullage gauge pressures at lift-off, the lower ends of the external tank's operating ranges
#: (NSTS 1988 News Reference Manual, "External Tank": LO2 20-22 psig, LH2 32-34 psig), Pa
ULLAGE_PRESSURE = {"lh2": 32.0 * PSI, "lox": 20.0 * PSI}


def core_stage_params(layout: StackLayout | None = None, mesh_size: float = 0.9, walls: str = "solid",
                      shell_bending_ratio: float = 1.0, liquid: str = "smeared",
                      ullage_pressure: dict | None = None, attach: str | None = None, **beams) -> TankParams:
    """External-tank-like core stage: LH2 tank (aft), intertank skirt, LOX tank (forward),
    Al 2219 wall thickened to 0.15 m (``walls="solid"``) or its mid-surface as an Al 2219
    shell of the thickness that weighs the dry mass, 6.8 mm (``walls="shell"``, bending
    stiffness ratio 12 I/t^3 ``shell_bending_ratio``), dry mass 26.5 t, propellants as
    wetted-wall mass (``liquid="smeared"``) or as hydroelastic liquid volumes
    (``liquid="hydroelastic"``, fem.liquid). Shell walls with hydroelastic liquids carry
    ullage pressures as a prestress (fem.prestress): ``ullage_pressure`` {"lh2": Pa, "lox":
    Pa} gauge, by default :data:`ULLAGE_PRESSURE` there and none otherwise. ``attach``: the
    booster and orbiter attach points as rigid 1 m x 1 m ``"patch"``es or, shell walls only,
    as ``"ring"`` interpolations over half the wall's circumference at their station (the
    ring frames there: the LH2 tank's aft frame, the intertank's booster beam frame);
    None: ``"ring"`` with shell walls, ``"patch"`` with solid ones. ``beams``: TankParams'
    ring frames and stringers (``frames``, ``frame_section``, ``frame_material``,
    ``stringers``, ``stringer_azimuth``, ``stringer_section``, ``stringer_material``; shell
    walls), none by default."""
    lay = layout or StackLayout()
    lay.check()
    patches = {}
    for side in ("left", "right"):
        patches.update(lay.srb_core_points(side))
    patches.update(lay.orbiter_core_points())
    pressure = ullage_pressure if ullage_pressure is not None else \
        ULLAGE_PRESSURE if (walls, liquid) == ("shell", "hydroelastic") else {"lh2": 0.0, "lox": 0.0}
    p = TankParams(
        name="core", radius=lay.core_radius, wall_thickness=0.15,
        compartments=(Compartment("lh2", 25.6, 0.72, 0.72, 0.97, 70.85, ullage_pressure=pressure["lh2"]),
                      Compartment("lox", 4.65, 0.72, 1.6, 0.90, 1141.0, ullage_pressure=pressure["lox"])),
        intertank_length=6.9, z_bottom=lay.core_bottom_z, axis_xy=(0.0, 0.0),
        material=replace(AL2219), dry_mass=26_500.0, patches=patches, patch_half_width=0.5,
        mesh_size=mesh_size, walls=walls, shell_bending_ratio=shell_bending_ratio, liquid=liquid,
        attach=check_attach("core_stage_params", walls, attach), **beams)
    p.patches["stack_top"] = np.array([0.0, 0.0, lay.core_bottom_z + tank_height(p)])
    return p


# ---- booster ----------------------------------------------------------------------------------
@dataclass
class BoosterParams:
    """Solid-rocket-booster-like component (SI). The case is a thick-walled cylinder with an
    oblate aft dome and a prolate nose (the real nose cone/frustum); the conical aft skirt
    carries the hold-down points at its bottom (z = 0). Propellant: non-structural mass
    smeared over the case inner wall (``srb_<side>_case_inner``); the grain's stiffness is
    neglected. Nozzle + TVC: a point mass at the gimbal (aft dome apex)."""

    side: str = "left"
    layout: StackLayout = field(default_factory=StackLayout)
    length: float = 45.46               # skirt bottom to nose tip
    case_thickness: float = 0.15        # thickened (real case ~13 mm); shell walls: sets the mid-surface radius
    case_bottom_z: float = 2.6          # case cylinder bottom (aft dome equator)
    aft_dome_ratio: float = 0.7
    nose_ratio: float = 1.9
    skirt_joint_height: float = 0.5     # skirt outer surface meets the case this far above case_bottom_z
    skirt_foot_height: float = 0.4      # vertical foot ring at the skirt bottom (hold-down pads)
    case_mass: float = 75_000.0         # case, nose, forward skirt, attach rings, SRB avionics (kg)
    skirt_mass: float = 5_000.0
    propellant_mass: float = 499_000.0
    nozzle_mass: float = 11_000.0
    nozzle_cg_below_gimbal: float = 1.8
    holddown_patch_radius: float = 0.2
    attach_patch_half_width: float = 0.45
    mesh_size: float = 0.6
    walls: str = "solid"                # "solid" (thickened tetrahedra) or "shell" (case as a shell, meshes.shells)
    case_shell_thickness: float | None = None   # shell case: None = the D6AC thickness that weighs case_mass
    case_shell_bending_ratio: float = 1.0       # shell case: 12 I / t^3 (1 = bare skin)
    attach: str | None = None           # shell case: core attach points as rigid "patch"es or "ring"s (None: ring)
    grain: bool = False                 # shell case: the propellant as a bonded solid grain, not smeared mass
    grain_bore_radius: float = 0.6      # the grain's perforation (m): a cylindrical bore on the axis
    grain_E: float = 7.5e6              # Pa: a composite propellant's order (docs/fem.md)
    grain_nu: float = 0.4999            # nearly incompressible (fem.elasticity: one-point volumetric term)

    # ---- placement: the StackLayout's booster position ``side`` (SolidMotorParams: its own)
    @property
    def name(self) -> str:
        return f"srb_{self.side}"

    @property
    def radius(self) -> float:
        """Outer radius of the case (m)."""
        return self.layout.srb_radius

    @property
    def axis(self) -> np.ndarray:
        """(x, y) of the motor's axis (m)."""
        return self.layout.srb_axis(self.side)

    @property
    def skirt_radius(self) -> float:
        """Outer radius of the aft skirt's bottom (m)."""
        return self.layout.srb_skirt_radius

    @property
    def skirt_thickness(self) -> float:
        """Radial thickness of the aft skirt's foot ring (m)."""
        return self.layout.srb_skirt_thickness

    def holddown_points(self) -> dict[str, np.ndarray]:
        """{name: (x, y, 0)}: hold-down points on the skirt's bottom (z = 0)."""
        return self.layout.holddown_points(self.side)

    def attach_points(self) -> dict[str, np.ndarray]:
        """{name: (x, y, z)}: points tied to a patch of the case wall facing them (the
        layout's attach points and, with its aft attach as struts, the struts' ends)."""
        return self.layout.srb_booster_points(self.side)

    def _check_placement(self, o: str) -> None:
        self.layout.check()
        self.layout.srb_axis(self.side)
        if self.cyl_top_z <= max(self.layout.srb_fwd_attach_z, self.case_bottom_z) + 1.0:
            raise InputError(f"{o}.length: case too short for the forward attach at z = {self.layout.srb_fwd_attach_z}")

    def check(self) -> None:
        o = f"{type(self).__name__}({self.name})"
        check_walls(o, self.walls)
        check_attach(o, self.walls, self.attach)
        if self.case_shell_thickness is not None:
            require_positive(o, case_shell_thickness=self.case_shell_thickness)
        require_positive(o, case_shell_bending_ratio=self.case_shell_bending_ratio)
        if self.grain:
            if self.walls != "shell":
                raise InputError(f"{o}.grain needs walls = 'shell' (the grain is bonded to the case's mid-surface)")
            require_positive(o, grain_bore_radius=self.grain_bore_radius)
            if self.grain_bore_radius >= self.radius - self.case_thickness:
                raise InputError(f"{o}.grain_bore_radius {self.grain_bore_radius:g} m leaves no grain inside the "
                                 f"case (inner radius {self.radius - self.case_thickness:g} m)")
            try:                        # grain_E, grain_nu: the one material check, before any meshing
                Material("propellant-grain", self.grain_E, self.grain_nu, 1.0)
            except InputError as exc:
                raise InputError(f"{o}: {exc}") from None
        require_positive(o, length=self.length, case_thickness=self.case_thickness,
                         case_bottom_z=self.case_bottom_z, aft_dome_ratio=self.aft_dome_ratio,
                         nose_ratio=self.nose_ratio, skirt_joint_height=self.skirt_joint_height,
                         skirt_foot_height=self.skirt_foot_height,
                         case_mass=self.case_mass, skirt_mass=self.skirt_mass,
                         propellant_mass=self.propellant_mass, nozzle_mass=self.nozzle_mass,
                         nozzle_cg_below_gimbal=self.nozzle_cg_below_gimbal,
                         holddown_patch_radius=self.holddown_patch_radius,
                         attach_patch_half_width=self.attach_patch_half_width, mesh_size=self.mesh_size)
        R, t = self.radius, self.case_thickness
        if t >= 0.5 * R:
            raise InputError(f"{o}.case_thickness must be < the case radius/2 ({R:g} m)")
        if self.aft_dome_ratio * R <= 2 * t or self.nose_ratio * R <= 2 * t:
            raise InputError(f"{o}: dome heights must exceed 2 x case_thickness")
        if self.case_bottom_z - self.aft_dome_ratio * R <= 0.2:
            raise InputError(f"{o}.case_bottom_z: the aft dome reaches below the skirt bottom")
        if self.cyl_top_z <= self.case_bottom_z + 1.0:
            raise InputError(f"{o}.length: the case's cylinder would be shorter than 1 m")
        self._check_placement(o)
        if self.skirt_foot_height >= self.case_bottom_z - self.aft_dome_ratio * R:
            raise InputError(f"{o}.skirt_foot_height must be below the aft dome apex")
        if self.skirt_radius - self.skirt_thickness <= R:
            raise InputError(f"{o}: skirt bottom inner radius must exceed the case radius")
        if 2 * self.holddown_patch_radius >= self.skirt_thickness:
            raise InputError(f"{o}.holddown_patch_radius must be < skirt thickness / 2")

    @property
    def cyl_top_z(self) -> float:
        return self.length - self.nose_ratio * self.radius


def booster_closed_form_volumes(p: BoosterParams) -> dict[str, float]:
    """Closed-form volumes (m^3) of the case shell and of the skirt's part outside the case."""
    from scipy.integrate import quad

    from .tank import capsule_volume
    R, t = p.radius, p.case_thickness
    L = p.cyl_top_z - p.case_bottom_z
    a_b, a_t = p.aft_dome_ratio * R, p.nose_ratio * R
    case = capsule_volume(R, a_b, a_t, L) - capsule_volume(R - t, a_b - t, a_t - t, L)
    zc, z3 = p.case_bottom_z, p.case_bottom_z + p.skirt_joint_height
    hf, Rb, ts = p.skirt_foot_height, p.skirt_radius, p.skirt_thickness

    def skirt_area(z: float) -> float:  # skirt cross-section outside the case solid at height z
        ro = np.interp(z, [0.0, hf, z3], [Rb, Rb, R])
        ri = np.interp(z, [0.0, hf, zc, z3], [Rb - ts, Rb - ts, R - 0.5 * t, R])
        s = zc - z
        case_o = R if s <= 0 else (R * math.sqrt(1 - (s / a_b) ** 2) if s < a_b else 0.0)
        lo = max(ri, case_o)
        return math.pi * (ro * ro - lo * lo) if ro > lo else 0.0

    skirt = quad(skirt_area, 0.0, z3, limit=400, points=[hf, zc - a_b, zc])[0]
    return {f"{p.name}_case": case, f"{p.name}_skirt": skirt}


def _skirt_quad(p: BoosterParams):
    R, t = p.radius, p.case_thickness
    Rb, ts = p.skirt_radius, p.skirt_thickness
    hf = p.skirt_foot_height
    return [(Rb - ts, 0.0), (Rb, 0.0), (Rb, hf), (R, p.case_bottom_z + p.skirt_joint_height),
            (R - 0.5 * t, p.case_bottom_z), (Rb - ts, hf)]


def booster_point_masses(p: BoosterParams) -> list[PointMass]:
    """Nozzle + TVC lumped at the gimbal (its c.g. nozzle_cg_below_gimbal below)."""
    d = np.array([0.0, 0.0, -p.nozzle_cg_below_gimbal])
    inertia = _cylinder_inertia(p.nozzle_mass, 1.5, 4.0) + _point_inertia(p.nozzle_mass, [d])
    return [PointMass(f"{p.name}_nozzle", f"{p.name}_gimbal", p.nozzle_mass, inertia)]


def build_booster(p: BoosterParams, out_dir) -> Geometry:
    """Booster ``srb_<side>``: volumes ``srb_<side>_case``, ``srb_<side>_skirt``; surfaces
    ``srb_<side>_case_inner`` (propellant), hold-down patches ``srb_<side>_hd_<k>`` (skirt
    bottom), ``srb_<side>_gimbal`` (aft dome apex), ``att_srb_<side>_fwd/aft``."""
    if not isinstance(p, BoosterParams):
        raise InputError(f"build_booster expects BoosterParams, got {type(p).__name__}")
    p.check()
    if p.walls == "shell":
        from .shells import build_shell_booster
        return build_shell_booster(p, Path(out_dir))
    out_dir = Path(out_dir)
    R, t = p.radius, p.case_thickness
    a_b, a_t = p.aft_dome_ratio * R, p.nose_ratio * R
    axis = p.axis
    case_g, skirt_g = f"{p.name}_case", f"{p.name}_skirt"
    gimbal = np.array([axis[0], axis[1], p.case_bottom_z - a_b])
    with _occ.gmsh_session(p.name):
        case2d = _occ.shell_profile(R, t, a_b, a_t, p.case_bottom_z, p.cyl_top_z - p.case_bottom_z)
        case2d = _occ.half(case2d)
        skirt2d = _occ.polygon(_skirt_quad(p))
        out, omap = occ.fragment(case2d, skirt2d)
        case_f = sorted({d for ch in omap[: len(case2d)] for d in ch})
        skirt_f = sorted({d for ch in omap[len(case2d):] for d in ch} - set(case_f))
        occ.synchronize()
        vol_case = _occ.revolve_to_z(case_f, axis)
        vol_skirt = _occ.revolve_to_z(skirt_f, axis)
        occ.synchronize()
        tools, refs = [], {}
        holddown = p.holddown_points()
        for name, pt in holddown.items():
            tools.append(_occ.cylinder_tool(name, pt[:2], p.holddown_patch_radius, -1.0, 0.5 * p.skirt_foot_height))
            refs[name] = pt
        w = p.attach_patch_half_width
        drop = a_b * (1 - math.sqrt(1 - (w / R) ** 2))
        tools.append(_occ.cylinder_tool(f"{p.name}_gimbal", axis, w, gimbal[2] - 1.0, gimbal[2] + 0.5 * (drop + t)))
        refs[f"{p.name}_gimbal"] = gimbal
        for name, pt in p.attach_points().items():
            d = pt[:2] - axis
            tools.append(_occ.wall_patch(name, axis, math.atan2(d[1], d[0]), pt[2], R, R - t, w, w))
            refs[name] = pt
        groups = _occ.imprint({case_g: vol_case, skirt_g: vol_skirt}, tools)
        allv = groups[case_g] + groups[skirt_g]
        bfaces = _occ.boundary_faces(allv)
        patches = _occ.patch_groups(bfaces, tools, refs,
                                    lambda n: min(p.mesh_size, 0.6 * (p.holddown_patch_radius if n in holddown else w)))
        ri = R - t
        inner = _occ.faces_inside(bfaces, (axis[0] - ri, axis[1] - ri, p.case_bottom_z - (a_b - t),
                                           axis[0] + ri, axis[1] + ri, p.cyl_top_z + a_t - t), tol=1e-3 * R)
        inner = _occ.faces_on(inner, _occ.capsule_distance(axis, ri, p.case_bottom_z, p.cyl_top_z, a_b - t, a_t - t),
                              tol=1e-4 * R)
        _occ.add_physical(2, f"{p.name}_case_inner", inner)
        _occ.add_physical(3, case_g, [tg for _, tg in groups[case_g]])
        _occ.add_physical(3, skirt_g, [tg for _, tg in groups[skirt_g]])
        vols = {case_g: _occ.group_volume(groups[case_g]), skirt_g: _occ.group_volume(groups[skirt_g])}
        areas = _occ.physical_measures(2)
        rho_max = max(R, R * R / a_b, a_b ** 2 / R, R * R / a_t, a_t ** 2 / R)
        n_nodes = _occ.mesh_and_write(out_dir / f"{p.name}.msh", p.mesh_size, _occ.curvature_elements(t, rho_max))
    mats = {case_g: equivalent(STEEL_D6AC, p.case_mass, vols[case_g], "D6AC-equivalent-case"),
            skirt_g: equivalent(AL2219, p.skirt_mass, vols[skirt_g], "Al2219-equivalent-skirt")}
    geo = Geometry(p.name, str(out_dir / f"{p.name}.msh"), mats, patches, booster_point_masses(p),
                   [SmearedMass(f"{p.name}_case_inner", p.propellant_mass)], [], vols, n_nodes, areas)
    geo.save(out_dir / f"{p.name}.json")
    return geo


# ---- orbiter ------------------------------------------------------------------------------------
@dataclass
class OrbiterParams:
    """Orbiter-like body (SI): thick-walled cylindrical fuselage with a prolate nose and a
    flat aft bulkhead (SSME thrust structure), plus a flat wing slab. Lumped: SSME cluster at
    ``ssme_mount`` (its c.g., below the bulkhead), payload at ``payload_station`` (on the
    axis, tied to two trunnion patches on the inner wall)."""

    layout: StackLayout = field(default_factory=StackLayout)
    length: float = 37.24
    wall_thickness: float = 0.15
    nose_ratio: float = 2.0
    wing_span: float = 23.79
    wing_root_chord: float = 12.0
    wing_thickness: float = 0.5
    wing_bottom_offset: float = 0.5     # wing trailing edge above the aft bulkhead
    structure_mass: float = 84_460.0    # airframe, TPS, OMS/RCS, consumables (kg)
    ssme_mass: float = 3_180.0          # each of 3
    ssme_cg_below_bulkhead: float = 1.8
    payload_mass: float = 16_000.0
    payload_z: float = 25.0
    attach_patch_half_width: float = 0.45
    mesh_size: float = 0.7
    walls: str = "solid"                # "solid" or "shell" (fuselage skin as a shell, meshes.shells)
    skin_shell_thickness: float | None = None   # shell skin: None = the Al 2219 thickness that weighs its mass share
    skin_shell_bending_ratio: float = 1.0       # shell skin: 12 I / t^3 (1 = bare skin)
    attach: str | None = None           # shell skin: attach points, engines, payload as rigid "patch"es or "ring"s (None: ring)
    frames: tuple = ()                  # shell skin: heights z (m) of ring frames on the fuselage cylinder (beams)
    frame_section: dict = field(default_factory=dict)   # their {shape, dims} (liftoff.core.beam.standard_section)
    frame_material: Material | None = None  # (None: Al 2219)
    stringers: int = 0                  # shell skin: stringers (beams) along the fuselage cylinder, equally spaced
    stringer_azimuth: float | None = None   # azimuth (deg, from +x about the fuselage axis) of the first;
    #                                         None: half a pitch (180/stringers), clear of the wing roots at 0 and 180
    stringer_section: dict = field(default_factory=dict)   # their {shape, dims}, web radial
    stringer_material: Material | None = None  # (None: Al 2219)

    name = "orbiter"

    def check(self) -> None:
        o = "OrbiterParams"
        check_walls(o, self.walls)
        check_attach(o, self.walls, self.attach)
        if self.skin_shell_thickness is not None:
            require_positive(o, skin_shell_thickness=self.skin_shell_thickness)
        require_positive(o, skin_shell_bending_ratio=self.skin_shell_bending_ratio)
        require_positive(o, length=self.length, wall_thickness=self.wall_thickness, nose_ratio=self.nose_ratio,
                         wing_span=self.wing_span, wing_root_chord=self.wing_root_chord,
                         wing_thickness=self.wing_thickness, wing_bottom_offset=self.wing_bottom_offset,
                         structure_mass=self.structure_mass, ssme_mass=self.ssme_mass,
                         ssme_cg_below_bulkhead=self.ssme_cg_below_bulkhead, payload_mass=self.payload_mass,
                         attach_patch_half_width=self.attach_patch_half_width, mesh_size=self.mesh_size)
        self.layout.check()
        R = self.layout.orbiter_radius
        if self.wall_thickness >= 0.5 * R:
            raise InputError(f"{o}.wall_thickness must be < orbiter_radius/2")
        if self.cyl_length <= 2.0:
            raise InputError(f"{o}.length too short for nose_ratio {self.nose_ratio}")
        if self.wing_span <= 2 * R:
            raise InputError(f"{o}.wing_span must exceed the fuselage diameter {2 * R} m")
        z0 = self.layout.orbiter_bottom_z
        for nm, z in (("payload_z", self.payload_z), ("layout.orbiter_fwd_attach_z", self.layout.orbiter_fwd_attach_z),
                      ("layout.orbiter_aft_attach_z", self.layout.orbiter_aft_attach_z)):
            if not z0 + 1.0 < z < z0 + self.cyl_length - 1.0:
                raise InputError(f"{o}.{nm} = {z} m is not on the fuselage cylinder")
        check_ring_frames(o, self.walls, self.frames, self.frame_section, self.frame_material,
                          z0 + self.wall_thickness, z0 + self.cyl_length, "skin", "the fuselage cylinder")
        self.stringers = check_stringers(o, self.walls, self.stringers, self.stringer_section, self.stringer_material)
        a0 = self.stringer_azimuth
        if a0 is not None and (isinstance(a0, bool) or not isinstance(a0, (int, float)) or not math.isfinite(a0)):
            raise InputError(f"{o}.stringer_azimuth must be a finite number of degrees (got {a0!r})")
        rm = R - 0.5 * self.wall_thickness
        clear = 0.5 * self.wing_thickness + 0.05 * self.mesh_size     # outside the wing root, not a sliver
        band = math.degrees(math.asin(min(1.0, clear / rm)))
        for k, a in enumerate(stringer_angles(self)):
            if abs(rm * math.sin(a)) < clear:
                raise InputError(f"{o}.stringer_azimuth: stringer {k + 1} of {self.stringers}, at "
                                 f"{math.degrees(a) % 360:g} deg, runs "
                                 f"through the wing root (the wing meets the skin within {band:.3g} deg of 0 and "
                                 "180 deg); choose stringer_azimuth so that none lies there")

    @property
    def axis_xy(self) -> tuple:
        """The fuselage axis (x, y), m (the frames' radial reference)."""
        return (0.0, float(self.layout.orbiter_axis_y))

    @property
    def material(self) -> Material:
        """The frames' default material: the skin's Al 2219."""
        return AL2219

    @property
    def cyl_length(self) -> float:
        return self.length - self.nose_ratio * self.layout.orbiter_radius


def orbiter_part_volumes(p: OrbiterParams) -> tuple[float, float]:
    """Closed-form volumes (m^3) of the fuselage wall and of the wing slab outside the
    fuselage cylinder (solid variant)."""
    from .tank import capsule_volume
    R, t, L, a = p.layout.orbiter_radius, p.wall_thickness, p.cyl_length, p.nose_ratio * p.layout.orbiter_radius
    shell = capsule_volume(R, 0.0, a, L) - capsule_volume(R - t, 0.0, a - t, L - t)
    y = 0.5 * p.wing_thickness
    strip = 2 * (y * math.sqrt(R * R - y * y) + R * R * math.asin(y / R))  # slab x circle area
    return shell, (p.wing_span * p.wing_thickness - strip) * p.wing_root_chord


def orbiter_closed_form_volumes(p: OrbiterParams) -> dict[str, float]:
    """Closed-form volume (m^3): fuselage shell + wing slab outside the fuselage cylinder."""
    return {"orbiter_structure": sum(orbiter_part_volumes(p))}


def orbiter_point_masses(p: OrbiterParams) -> list[PointMass]:
    """SSME cluster (three engines in a triangle about the cluster c.g.: upper one at +y,
    lower two at -/+x) at ``ssme_mount``, payload at ``payload_station``."""
    offs = [(0.0, 1.2, 0.0), (-1.3, -0.6, 0.0), (1.3, -0.6, 0.0)]
    J_ssme = 3 * _cylinder_inertia(p.ssme_mass, 1.1, 4.3) + _point_inertia(p.ssme_mass, offs)
    J_pl = _cylinder_inertia(p.payload_mass, 2.0, 10.0)
    return [PointMass("ssme_cluster", "ssme_mount", 3 * p.ssme_mass, J_ssme),
            PointMass("payload", "payload_station", p.payload_mass, J_pl)]


def build_orbiter(p: OrbiterParams, out_dir) -> Geometry:
    """Orbiter: volume ``orbiter_structure`` (fuselage + wings); patches ``ssme_mount``,
    ``payload_station`` (two faces), ``att_orb_fwd``, ``att_orb_aft_left/right``."""
    if not isinstance(p, OrbiterParams):
        raise InputError(f"build_orbiter expects OrbiterParams, got {type(p).__name__}")
    p.check()
    if p.walls == "shell":
        from .shells import build_shell_orbiter
        return build_shell_orbiter(p, Path(out_dir))
    lay, out_dir = p.layout, Path(out_dir)
    R, t, z0 = lay.orbiter_radius, p.wall_thickness, lay.orbiter_bottom_z
    axis = np.array([0.0, lay.orbiter_axis_y])
    g = "orbiter_structure"
    a_n = p.nose_ratio * R
    with _occ.gmsh_session(p.name):
        fus = _occ.revolve_to_z(_occ.half(_occ.shell_profile(R, t, 0.0, a_n, z0, p.cyl_length)), axis)
        solid = _occ.revolve_to_z(_occ.half(_occ.capsule_profile(R, 0.0, a_n, z0, p.cyl_length)), axis)
        wing = occ.addBox(-0.5 * p.wing_span, axis[1] - 0.5 * p.wing_thickness, z0 + p.wing_bottom_offset,
                          p.wing_span, p.wing_thickness, p.wing_root_chord)
        wings, _ = occ.cut([(3, wing)], solid)
        occ.synchronize()
        w = p.attach_patch_half_width
        tools, refs = [], {}
        ssme_ref = np.array([axis[0], axis[1], z0 - p.ssme_cg_below_bulkhead])
        tools.append(_occ.cylinder_tool("ssme_mount", axis, 1.0, z0 - 1.0, z0 + 0.5 * t))
        refs["ssme_mount"] = ssme_ref
        for phi in (0.0, math.pi):  # payload trunnions, inner wall at +-x
            tools.append(_occ.wall_patch("payload_station", axis, phi, p.payload_z, R - t, R, 0.5, 0.5))
        refs["payload_station"] = np.array([axis[0], axis[1], p.payload_z])
        for name, pt in lay.orbiter_attach_points().items():
            d = pt[:2] - axis
            tools.append(_occ.wall_patch(name, axis, math.atan2(d[1], d[0]), pt[2], R, R - t, w, w))
            refs[name] = pt
        groups = _occ.imprint({g: fus + wings}, tools)
        bfaces = _occ.boundary_faces(groups[g])
        patches = _occ.patch_groups(bfaces, tools, refs, lambda _: min(p.mesh_size, 0.6 * w))
        _occ.add_physical(3, g, [tg for _, tg in groups[g]])
        vols = {g: _occ.group_volume(groups[g])}
        areas = _occ.physical_measures(2)
        rho_max = max(R, R * R / a_n, a_n ** 2 / R)
        n_nodes = _occ.mesh_and_write(out_dir / f"{p.name}.msh", p.mesh_size, _occ.curvature_elements(t, rho_max))
    mat = equivalent(AL2219, p.structure_mass, vols[g], "Al2219-equivalent-orbiter")
    geo = Geometry(p.name, str(out_dir / f"{p.name}.msh"), {g: mat}, patches, orbiter_point_masses(p),
                   [], [], vols, n_nodes, areas)
    geo.save(out_dir / f"{p.name}.json")
    return geo


# ---- the stack --------------------------------------------------------------------------------
def build_core_stage(out_dir, layout: StackLayout | None = None, mesh_size: float = 0.9, walls: str = "solid",
                     shell_bending_ratio: float = 1.0, attach: str | None = None) -> Geometry:
    """Core stage ``core`` built with the tank builder (see :func:`core_stage_params`)."""
    return build_tank(core_stage_params(layout, mesh_size, walls, shell_bending_ratio, attach=attach), out_dir)


def default_stack(mesh_size: float | None = None, out_dir="out/meshes",
                  layout: StackLayout | None = None, walls: str = "solid") -> dict[str, Geometry]:
    """Build all four components (``core``, ``srb_left``, ``srb_right``, ``orbiter``) with
    their default parameters (``mesh_size`` overrides every component's default; ``walls``
    = "solid" or "shell" sets every component's walls, see meshes.shells)."""
    lay = layout or StackLayout()
    if mesh_size is not None:
        require_positive("default_stack", mesh_size=mesh_size)
    check_walls("default_stack", walls)
    kw = {"walls": walls} if mesh_size is None else {"mesh_size": mesh_size, "walls": walls}
    out = {"core": build_core_stage(out_dir, lay, **kw)}
    for side in ("left", "right"):
        b = build_booster(BoosterParams(side=side, layout=lay, **kw), out_dir)
        out[b.name] = b
    out["orbiter"] = build_orbiter(OrbiterParams(layout=lay, **kw), out_dir)
    return out
