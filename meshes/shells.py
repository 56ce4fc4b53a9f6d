"""Shell-wall variants of the vehicle builders (``walls = "shell"``): the thin walls as
mid-surfaces meshed with flat triangles for fem.shell, instead of thickened tetrahedra.

What becomes a shell: the core-stage tank walls, domes and intertank skirt
(:func:`build_shell_tank`), the booster case with its domes (the thick aft skirt with the
hold-down posts stays a solid, tied to the case over a band of the case wall:
:func:`build_shell_booster`), the orbiter's fuselage skin with its aft bulkhead and nose
(the wing slab stays a solid, tied to the skin over its root: :func:`build_shell_orbiter`).

Geometry: the mid-surface of the solid variant's wall (outer radius R, thickness t of the
parameters: radius R - t/2, dome heights a - t/2), so that layout, patches, cavities and
liquid masses are those of the solid variant. Section: the real material with the
thickness that weighs the part's mass (or ``*_shell_thickness``, the material then scaled
to the mass with E/rho kept, like ``spec.equivalent``). Group names are the solid
variant's (a wall group is a surface group here) except the orbiter's wing volume
``orbiter_wing``, split from ``orbiter_structure`` with the solid variant's share of the
structure mass. Units SI.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from liftoff.core.errors import InputError

from . import _occ
from ._occ import occ
from .spec import BeamGroup, Geometry, Material, Patch, SmearedMass, check_attach, equivalent
from .tank import TankParams, tank_layout

#: elements per 2 pi of curvature on shell walls (gmsh Mesh.MeshSizeFromCurvature), at most:
#: 24 keeps the facets within 1 % of the radius (sag 1 - cos(pi/24)); at least 12 (sag 3.4 %)
SHELL_CURVATURE_ELEMENTS = 24


def shell_curvature_elements(radius: float, mesh_size: float) -> int:
    """Elements per 2 pi of curvature for a shell wall of main radius ``radius``: what
    ``mesh_size`` gives around that radius, kept within [12, SHELL_CURVATURE_ELEMENTS], so
    that a coarse mesh_size coarsens the whole wall while the sharper curvature of dome
    equators and noses stays resolved."""
    return int(min(SHELL_CURVATURE_ELEMENTS, max(12, math.ceil(2 * math.pi * radius / mesh_size))))


def shell_patch_tool(name: str, ref, axis_xy, r: float, z_lo_apex: float, z_hi_apex: float,
                     cyl_ranges: list[tuple[float, float]], w: float, a_lo: float, a_hi: float) -> _occ.Tool:
    """Tool imprinting patch ``name`` on a mid-surface of radius r (see TankParams.patches):
    a cylinder about the axis cutting the apex cap of radius w, or a radial box on the wall."""
    ref = np.asarray(ref, float)
    d = ref[:2] - np.asarray(axis_xy, float)
    if np.hypot(*d) < 1e-6:
        top = ref[2] >= 0.5 * (z_lo_apex + z_hi_apex)
        a = a_hi if top else a_lo
        if w >= 0.9 * r:
            raise InputError(f"patch {name}: apex patch of half-width {w} m too wide for the dome")
        reach = 1.5 * a * (1 - math.sqrt(1 - (w / r) ** 2)) + 0.02 * r     # past the cap's drop
        z = z_hi_apex if top else z_lo_apex
        return _occ.cylinder_tool(name, axis_xy, w, *((z - reach, z + 1.0) if top else (z - 1.0, z + reach)))
    z = float(ref[2])
    if not any(lo + w <= z <= hi - w for lo, hi in cyl_ranges):
        raise InputError(f"patch {name}: height z = {z} m is not on the cylindrical wall "
                         f"(ranges {[(round(a, 3), round(b, 3)) for a, b in cyl_ranges]})")
    return _occ.shell_wall_patch(name, axis_xy, math.atan2(d[1], d[0]), z, r, w, w)


#: an attach ring spreads a point's loads over the wall nodes within RING_REACH x the wall
#: radius of it: about half the circumference (+-86 to +-94 degrees on the core stage, whose
#: attach points sit between the walls, outside its wall)
RING_REACH = 1.5


def ring_heights(refs: dict, axis_xy, cyl_ranges: list[tuple[float, float]]) -> dict[float, list[str]]:
    """The off-axis reference points of ``refs`` grouped by height (m): one attach ring per
    height. InputError for a point off the cylindrical wall's height ranges."""
    out: dict[float, list[str]] = {}
    for name, ref in refs.items():
        ref = np.asarray(ref, float)
        if np.hypot(*(ref[:2] - np.asarray(axis_xy, float))) < 1e-6:
            continue
        z = round(float(ref[2]), 6)
        if not any(lo < z < hi for lo, hi in cyl_ranges):
            raise InputError(f"patch {name}: height z = {z} m is not on the cylindrical wall "
                             f"(ranges {[(round(a, 3), round(b, 3)) for a, b in cyl_ranges]})")
        out.setdefault(z, []).append(name)
    return out


def ring_edges(wall_faces: list[int], z: float, axis_xy, radius: float) -> list[int]:
    """The wall's edges of radius ``radius`` about the axis at height ``z`` (imprinted by
    ``_occ.plane_cut``, or a rim)."""
    import gmsh

    tol = 1e-5 * max(1.0, radius)          # heights are keyed rounded to 1e-6 m

    def on_ring(e: int) -> bool:
        lo, hi = gmsh.model.getParametrizationBounds(1, e)
        x = np.asarray(gmsh.model.getValue(1, e, [0.5 * (lo[0] + hi[0])]))
        b = gmsh.model.getBoundingBox(1, e)
        return (abs(b[2] - z) < tol and abs(b[5] - z) < tol
                and abs(np.hypot(*(x[:2] - np.asarray(axis_xy, float))) - radius) < 1e-3 * radius)

    return [e for e in wall_edges(wall_faces) if on_ring(e)]


def wall_edges(wall_faces: list[int]) -> list[int]:
    """The edges of the wall's faces, sorted (each once)."""
    import gmsh

    return sorted({abs(t) for _, t in gmsh.model.getBoundary([(2, f) for f in wall_faces], combined=False,
                                                             oriented=False)})


def ring_patches(wall_faces: list[int], prefix: str, heights: dict[float, list[str]], refs: dict, axis_xy,
                 radius: float, reach: dict | None = None) -> list[Patch]:
    """Interpolation patches (fem: RBE3) of the attach rings: the wall's ring edges at each
    height (:func:`ring_edges`) become the curve group ``<prefix>_ring_<k>``; each point at
    that height interpolates its nodes within RING_REACH x ``radius`` of it (``reach[name]``
    (m) where given)."""
    out, reach = [], reach or {}
    for k, (z, names) in enumerate(sorted(heights.items())):
        group = f"{prefix}_ring_{k}"
        _occ.add_physical(1, group, ring_edges(wall_faces, z, axis_xy, radius))
        out += [Patch(n, np.asarray(refs[n], float), nodes=group, reach=reach.get(n, RING_REACH * radius))
                for n in names]
    return out


def stringer_angles(p) -> list[float]:
    """Each stringer's azimuth (rad) about ``p.axis_xy``: ``p.stringers`` equally spaced from
    ``p.stringer_azimuth`` (deg), or from half a pitch (180 / p.stringers deg) where it is None."""
    first = float(p.stringer_azimuth) if p.stringer_azimuth is not None else 180.0 / max(p.stringers, 1)
    return [math.radians(first) + 2 * math.pi * k / p.stringers for k in range(p.stringers)]


def stringer_xy(p, radius: float) -> list[tuple[float, float]]:
    """(x, y) of each stringer on the wall of radius ``radius`` (:func:`stringer_angles`)."""
    x0, y0 = p.axis_xy
    return [(x0 + radius * math.cos(a), y0 + radius * math.sin(a)) for a in stringer_angles(p)]


def stringer_tools(p, radius: float, z0: float, z1: float) -> list:
    """One straight line (an OCC tool) per stringer along the cylindrical wall of radius
    ``radius`` from z0 to z1 (:func:`stringer_xy`)."""
    out = []
    for x, y in stringer_xy(p, radius):
        line = occ.addLine(occ.addPoint(x, y, z0), occ.addPoint(x, y, z1))
        out.append(_occ.Tool(None, (1, line), (x, y, z0, x, y, z1)))
    return out


def stringer_edges(p, wall_faces: list[int], radius: float) -> list[int]:
    """The wall's straight edges along the axis at the stringers' azimuths."""
    import gmsh

    xs, ys = np.array(stringer_xy(p, radius)).T
    tol = 1e-5 * max(1.0, radius)
    out = []
    for e in wall_edges(wall_faces):
        b = gmsh.model.getBoundingBox(1, e)
        if b[5] - b[2] > tol and b[3] - b[0] < tol and b[4] - b[1] < tol \
                and np.min(np.hypot(xs - b[0], ys - b[1])) < tol:
            out.append(e)
    return out


def wall_beams(p, wall_faces: list[int], radius: float, wall_thickness: float,
               wall_mass: float | None, owner: str, wall: str) -> tuple[dict, dict, float | None]:
    """A wall's ring frames (``p.frames``, ``p.frame_section``, ``p.frame_material``) and
    stringers (``p.stringers``, ``p.stringer_azimuth``, ``p.stringer_section``,
    ``p.stringer_material``) as beams on the wall's inner face (``p`` a TankParams or an
    OrbiterParams, with ``axis_xy``, ``name`` and ``material``): the wall's ring edges at the frame heights become the curve
    group ``<name>_frames``, its edges at the stringers' azimuths ``<name>_stringers``, each a
    BeamGroup of its section with the axis offset inward from the mid-surface by half the
    geometric ``wall_thickness`` and the section's base to centroid distance, local z
    radial (frames: y along the axis; stringers: y tangential), on the shell group ``wall``
    (BeamGroup.wall: its thermal strain is theirs). Returns ({group: BeamGroup},
    {group: length of the members' centroid lines, m}, the wall's own share of ``wall_mass``
    (the members' mass taken off it; None stays None))."""
    from liftoff.core.beam import standard_section

    beams, lengths, members_mass = {}, {}, 0.0
    axis = (p.axis_xy[0], p.axis_xy[1], 0.0)
    for kind, edges, spec, mat, vref in (
            ("frames", lambda: [e for z in p.frames for e in ring_edges(wall_faces, float(z), p.axis_xy, radius)],
             p.frame_section, p.frame_material, (0.0, 0.0, 1.0)),
            ("stringers", lambda: stringer_edges(p, wall_faces, radius), p.stringer_section, p.stringer_material,
             "tangential")):
        if not (p.frames if kind == "frames" else p.stringers):
            continue
        group = f"{p.name}_{kind}"
        _occ.add_physical(1, group, edges())
        length = _occ.physical_measures(1)[group]
        mat = mat or p.material
        section, base = standard_section(spec, f"{owner}.{kind[:-1]}_section", mat.nu)
        offset = -(0.5 * wall_thickness + base)
        beams[group] = BeamGroup(mat, section, vref=vref, radial_offset=offset, axis_point=axis, wall=wall)
        lengths[group] = length * (radius + offset) / radius if kind == "frames" else length
        members_mass += mat.rho * section.A * lengths[group]
    if wall_mass is None or not beams:
        return beams, lengths, wall_mass
    if members_mass >= wall_mass:
        raise InputError(f"{owner}: the frames and stringers weigh {members_mass:.0f} kg, not less than "
                         f"the mass {wall_mass:.0f} kg they are part of")
    return beams, lengths, wall_mass - members_mass


def shell_section(material: Material, area: float, dry_mass: float | None, thickness: float | None,
                  default_thickness: float) -> tuple[Material, float]:
    """(material, thickness) of a shell wall of mid-surface ``area`` (m^2): the given
    thickness (material scaled to dry_mass, E/rho kept, if one is given), else the thickness
    of ``material`` that weighs dry_mass, else ``default_thickness``."""
    if thickness is not None:
        return (material if dry_mass is None else equivalent(material, dry_mass, thickness * area)), float(thickness)
    if dry_mass is not None:
        return material, dry_mass / (material.rho * area)
    return material, float(default_thickness)


def mid_cavities(p: TankParams) -> list:
    """The cavities bounded by the shell's mid-surface (radius R - t/2, dome heights a - t/2).
    Smeared liquids keep the solid variant's fill heights; a hydroelastic liquid is filled to
    the height at which it holds the solid variant's liquid volume (the same liquid mass)."""
    from .tank import Cavity, fill_height, inner_cavities

    t = p.wall_thickness
    out = []
    for c, inner in zip(tank_layout(p), inner_cavities(p)):
        cav = Cavity(c.name, p.radius - 0.5 * t, c.a_bottom - 0.5 * t, c.a_top - 0.5 * t, c.z_cyl_bottom,
                     c.z_cyl_top, c.z_fill)
        if p.liquid == "hydroelastic":
            cav.z_fill = cav.z_bottom + fill_height(cav.r, cav.a_bottom, cav.a_top, cav.z_cyl_top - cav.z_cyl_bottom,
                                                    inner.liquid_volume())
        out.append(cav)
    return out


def build_shell_tank(p: TankParams, out_dir: Path) -> Geometry:
    """build_tank for walls = "shell": the wall's mid-surface (module docstring), with the
    hydroelastic liquids meshed against it (meshes.tank.compartment_groups)."""
    from .tank import compartment_groups, inner_cavities, liquid_solids

    lay = tank_layout(p)
    R, t, w = p.radius, p.wall_thickness, p.patch_half_width
    rm, wall = R - 0.5 * t, f"{p.name}_wall"
    cavities = mid_cavities(p)
    with _occ.gmsh_session(p.name):
        faces = []
        for c in lay:
            faces += _occ.capsule_surface(rm, c.a_bottom - 0.5 * t, c.a_top - 0.5 * t, c.z_cyl_bottom, c.cyl_length,
                                          p.axis_xy)
        for lo, hi in zip(lay[:-1], lay[1:]):
            faces += _occ.cylinder_surface(rm, lo.z_cyl_top, hi.z_cyl_bottom, p.axis_xy)
        cyl = [(lay[0].z_cyl_bottom, lay[-1].z_cyl_top)]
        rings = ring_heights(p.patches, p.axis_xy, cyl) if check_attach(p.name, p.walls, p.attach) == "ring" else {}
        tools = [shell_patch_tool(n, ref, p.axis_xy, rm, p.z_bottom + 0.5 * t, lay[-1].z_cyl_top + lay[-1].a_top - 0.5 * t,
                                  cyl, w, lay[0].a_bottom - 0.5 * t, lay[-1].a_top - 0.5 * t)
                 for n, ref in p.patches.items() if not any(n in names for names in rings.values())]
        tools += [_occ.plane_cut(z) for z in rings]
        fills = [cav.z_fill for c, cav in zip(lay, cavities)
                 if c.fill_height < (c.z_inner_top - c.z_inner_bottom) and round(cav.z_fill, 6) not in rings]
        tools += [_occ.plane_cut(z) for z in fills]                                   # (one cut per height)
        cut = set(rings) | {round(z, 6) for z in fills}
        tools += [_occ.plane_cut(float(z)) for z in p.frames if round(float(z), 6) not in cut]
        tools += stringer_tools(p, rm, *cyl[0])
        wall_faces = _occ.imprint_surfaces({wall: faces}, tools)[wall]
        liquids = liquid_solids(p, cavities)
        if liquids:
            _, new_faces, liquids = _occ.add_liquids({}, {wall: wall_faces}, liquids)
            wall_faces = new_faces[wall]
        patches = _occ.patch_groups(wall_faces, tools, p.patches, lambda _: min(p.mesh_size, 0.6 * w))
        patches += ring_patches(wall_faces, p.name, rings, p.patches, p.axis_xy, rm)
        smeared, specs = compartment_groups(p, cavities, wall_faces, liquids, inner_cavities(p))
        _occ.add_physical(2, wall, wall_faces)
        areas = _occ.physical_measures(2)
        volumes = {g: _occ.group_volume(v) for g, v in liquids.items()}
        beams, lengths, wall_mass = wall_beams(p, wall_faces, rm, t, p.dry_mass, f"TankParams({p.name})", wall)
        mat, ts = shell_section(p.material, areas[wall], wall_mass, p.shell_thickness, t)
        n_nodes = _occ.mesh_and_write(out_dir / f"{p.name}.msh", p.mesh_size, shell_curvature_elements(rm, p.mesh_size))
    geo = Geometry(p.name, str(out_dir / f"{p.name}.msh"), {wall: mat}, patches, [], smeared, [],
                   volumes, n_nodes, areas, shells={wall: ts}, shell_bending={wall: p.shell_bending_ratio},
                   liquids=specs, beams=beams, curve_lengths=lengths)
    geo.save(out_dir / f"{p.name}.json")
    return geo


def _patches_on(faces: list[int], tools, refs: dict, size_of) -> list[Patch]:
    """Physical surface groups of the tools' patches on the candidate faces (refined)."""
    found: dict[str, list[int]] = {}
    for tl in tools:
        if tl.name is not None:
            found.setdefault(tl.name, []).extend(_occ.faces_inside(faces, tl.bbox))
    out = []
    for name, pf in found.items():
        _occ.add_physical(2, name, pf)
        _occ.refine_faces(pf, size_of(name))
        out.append(Patch(name, np.asarray(refs[name], float)))
    return out


def _apex_tool(name: str, axis, w: float, r: float, a: float, z_apex: float, top: bool) -> _occ.Tool:
    """Cylinder about the axis cutting a cap of radius w from a dome (mid-surface r, height a)."""
    if w >= 0.9 * r:
        raise InputError(f"patch {name}: apex patch of half-width {w} m too wide for the dome")
    reach = 1.5 * a * (1 - math.sqrt(1 - (w / r) ** 2)) + 0.02 * r
    return _occ.cylinder_tool(name, axis, w, *((z_apex - reach, z_apex + 1.0) if top else (z_apex - 1.0, z_apex + reach)))


def _wall_tools(attach: dict, rings: dict, axis, rm: float, w: float) -> list[_occ.Tool]:
    """Imprint tools of attach points on a cylindrical mid-surface of radius rm: a plane cut
    per ring height, a (2w x 2w) patch for each point not on a ring."""
    on_ring = {n for names in rings.values() for n in names}
    tools = [_occ.plane_cut(z) for z in rings]
    for name, pt in attach.items():
        if name not in on_ring:
            d = np.asarray(pt[:2], float) - axis
            tools.append(_occ.shell_wall_patch(name, axis, math.atan2(d[1], d[0]), pt[2], rm, w, w))
    return tools


def booster_skirt_section(p) -> list[tuple[float, float]]:
    """Meridian polygon of the solid aft skirt of a shell-cased booster: the solid variant's
    skirt, its top end reaching the case mid-surface (radius R - t/2) over the joint band
    [case_bottom_z, case_bottom_z + skirt_joint_height], where the two share nodes."""
    R, t = p.radius, p.case_thickness
    Rb, ts, hf = p.skirt_radius, p.skirt_thickness, p.skirt_foot_height
    zc, zj = p.case_bottom_z, p.case_bottom_z + p.skirt_joint_height
    return [(Rb - ts, 0.0), (Rb, 0.0), (Rb, hf), (R, zj), (R - 0.5 * t, zj), (R - 0.5 * t, zc), (Rb - ts, hf)]


def build_shell_booster(p, out_dir: Path) -> Geometry:
    """build_booster for walls = "shell": case (cylinder, aft dome, nose) as a shell surface
    ``srb_<side>_case`` (also ``srb_<side>_case_inner``, the propellant's), aft skirt
    ``srb_<side>_skirt`` a solid; same patches and masses as the solid variant."""
    from .vehicle import AL2219, STEEL_D6AC, booster_point_masses

    R, t = p.radius, p.case_thickness
    rm, am_b, am_t = R - 0.5 * t, p.aft_dome_ratio * R - 0.5 * t, p.nose_ratio * R - 0.5 * t
    axis = p.axis
    case_g, skirt_g, grain_g = f"{p.name}_case", f"{p.name}_skirt", f"{p.name}_grain"
    w = p.attach_patch_half_width
    with _occ.gmsh_session(p.name):
        skirt = _occ.revolve_to_z(_occ.polygon(booster_skirt_section(p)), axis)
        case = _occ.capsule_surface(rm, am_b, am_t, p.case_bottom_z, p.cyl_top_z - p.case_bottom_z, axis)
        tools, refs = [], {}
        holddown = p.holddown_points()
        for name, pt in holddown.items():
            tools.append(_occ.cylinder_tool(name, pt[:2], p.holddown_patch_radius, -1.0, 0.5 * p.skirt_foot_height))
            refs[name] = pt
        gimbal = f"{p.name}_gimbal"
        tools.append(_apex_tool(gimbal, axis, w, rm, am_b, p.case_bottom_z - am_b, top=False))
        refs[gimbal] = np.array([axis[0], axis[1], p.case_bottom_z - p.aft_dome_ratio * R])
        attach = p.attach_points()
        rings = ring_heights(attach, axis, [(p.case_bottom_z, p.cyl_top_z)]) \
            if check_attach(p.name, p.walls, p.attach) == "ring" else {}
        tools += _wall_tools(attach, rings, axis, rm, w)
        refs.update(attach)
        parts = {skirt_g: skirt}
        if p.grain:                     # the propellant grain: a bored cylinder bonded to the case's barrel
            zc, zt, rb = p.case_bottom_z, p.cyl_top_z, p.grain_bore_radius
            parts[grain_g] = _occ.revolve_to_z(_occ.polygon([(rb, zc), (rm, zc), (rm, zt), (rb, zt)]), axis)
        vols, faces = _occ.imprint_parts(parts, {case_g: case}, tools)
        cand = _occ.boundary_faces(vols[skirt_g]) + faces[case_g]
        patches = _patches_on(cand, tools, refs, lambda n: min(p.mesh_size, 0.6 * (
            p.holddown_patch_radius if n in holddown else w)))
        patches += ring_patches(faces[case_g], p.name, rings, attach, axis, rm)
        _occ.add_physical(2, f"{p.name}_case_inner", faces[case_g])
        _occ.add_physical(2, case_g, faces[case_g])
        _occ.add_physical(3, skirt_g, [tg for _, tg in vols[skirt_g]])
        volume = _occ.group_volume(vols[skirt_g])
        group_volumes = {skirt_g: volume}
        if p.grain:
            _occ.add_physical(3, grain_g, [tg for _, tg in vols[grain_g]])
            group_volumes[grain_g] = _occ.group_volume(vols[grain_g])
        areas = _occ.physical_measures(2)
        n_curv = max(shell_curvature_elements(rm, p.mesh_size),
                     _occ.curvature_elements(p.skirt_thickness, p.skirt_radius))
        n_nodes = _occ.mesh_and_write(out_dir / f"{p.name}.msh", p.mesh_size, n_curv)
    case_mat, tc = shell_section(STEEL_D6AC, areas[case_g], p.case_mass, p.case_shell_thickness, t)
    mats = {case_g: case_mat, skirt_g: equivalent(AL2219, p.skirt_mass, volume, "Al2219-equivalent-skirt")}
    smeared = [SmearedMass(f"{p.name}_case_inner", p.propellant_mass)]
    if p.grain:                         # the propellant's mass is the grain's: its density from the CAD volume
        mats[grain_g] = Material("propellant-grain", p.grain_E, p.grain_nu, p.propellant_mass / group_volumes[grain_g])
        smeared = []
    geo = Geometry(p.name, str(out_dir / f"{p.name}.msh"), mats, patches, booster_point_masses(p),
                   smeared, [], group_volumes, n_nodes, areas,
                   shells={case_g: tc}, shell_bending={case_g: p.case_shell_bending_ratio})
    geo.save(out_dir / f"{p.name}.json")
    return geo


def build_shell_orbiter(p, out_dir: Path) -> Geometry:
    """build_orbiter for walls = "shell": fuselage skin, aft bulkhead and nose as the shell
    surface ``orbiter_structure``, the wing slab the solid ``orbiter_wing``, carried through
    the fuselage (the wing carry-through structure: the skin crosses the slab, sharing its
    nodes there; a wing held by a band of bare skin alone flaps at 0.76 Hz); same patches and
    lumped masses as the solid variant. The wing's density is the solid variant's (structure
    mass over its volume), so the outboard wing is the solid variant's; the skin weighs the
    rest of the structure mass."""
    from .vehicle import AL2219, orbiter_part_volumes, orbiter_point_masses

    lay = p.layout
    R, t, z0 = lay.orbiter_radius, p.wall_thickness, lay.orbiter_bottom_z
    rm, am = R - 0.5 * t, p.nose_ratio * R - 0.5 * t
    axis = np.array([0.0, lay.orbiter_axis_y])
    skin, wing_g = "orbiter_structure", "orbiter_wing"
    w = p.attach_patch_half_width
    with _occ.gmsh_session(p.name):
        inside = _occ.revolve_to_z(_occ.half(_occ.capsule_profile(rm, 0.0, am, z0 + 0.5 * t, p.cyl_length - 0.5 * t)),
                                   axis)
        wings = [(3, _occ.occ.addBox(-0.5 * p.wing_span, axis[1] - 0.5 * p.wing_thickness, z0 + p.wing_bottom_offset,
                                     p.wing_span, p.wing_thickness, p.wing_root_chord))]
        _occ.occ.synchronize()
        faces = _occ.boundary_faces(inside)
        _occ.occ.remove(inside)
        _occ.occ.synchronize()
        att = lay.orbiter_attach_points()
        refs = {"ssme_mount": np.array([axis[0], axis[1], z0 - p.ssme_cg_below_bulkhead]),
                "payload_station": np.array([axis[0], axis[1], p.payload_z]), **att}
        rings, reach = {}, {}
        if check_attach(p.name, p.walls, p.attach) == "ring":     # engines' thrust structure, payload trunnions
            rings = ring_heights(att, axis, [(z0 + 0.5 * t, z0 + p.cyl_length)])
            rings.setdefault(round(p.payload_z, 6), []).append("payload_station")
            tools = _wall_tools(att, rings, axis, rm, w)
            rings[round(z0 + 0.5 * t, 6)] = ["ssme_mount"]          # the aft bulkhead's rim (no cut needed)
            reach = {"ssme_mount": math.inf, "payload_station": math.inf}
        else:
            tools = [_occ.cylinder_tool("ssme_mount", axis, 1.0, z0 - 1.0, z0 + 0.5 * t + 0.25)]
            tools += [_occ.shell_wall_patch("payload_station", axis, phi, p.payload_z, rm, 0.5, 0.5)
                      for phi in (0.0, math.pi)]
            tools += _wall_tools(att, rings, axis, rm, w)
        tools += [_occ.plane_cut(float(z)) for z in p.frames if round(float(z), 6) not in rings]
        tools += stringer_tools(p, rm, z0 + 0.5 * t, z0 + p.cyl_length)
        vols, faces = _occ.imprint_parts({wing_g: wings}, {skin: faces}, tools)
        patches = _patches_on(faces[skin], tools, refs, lambda n: min(p.mesh_size, 0.6 * w))
        patches += ring_patches(faces[skin], p.name, rings, refs, axis, rm, reach)
        _occ.add_physical(2, skin, faces[skin])
        _occ.add_physical(3, wing_g, [tg for _, tg in vols[wing_g]])
        volume = _occ.group_volume(vols[wing_g])
        areas = _occ.physical_measures(2)
        m_wing = p.structure_mass * volume / sum(orbiter_part_volumes(p))         # the solid variant's density
        if m_wing >= p.structure_mass:
            raise InputError(f"OrbiterParams: the wing slab ({volume:.1f} m^3) weighs the whole structure_mass")
        beams, lengths, m_skin = wall_beams(p, faces[skin], rm, t, p.structure_mass - m_wing, "OrbiterParams", skin)
        n_nodes = _occ.mesh_and_write(out_dir / f"{p.name}.msh", p.mesh_size, shell_curvature_elements(rm, p.mesh_size))
    skin_mat, ts = shell_section(AL2219, areas[skin], m_skin, p.skin_shell_thickness, t)
    mats = {skin: skin_mat, wing_g: equivalent(AL2219, m_wing, volume, "Al2219-equivalent-wing")}
    geo = Geometry(p.name, str(out_dir / f"{p.name}.msh"), mats, patches, orbiter_point_masses(p), [], [],
                   {wing_g: volume}, n_nodes, areas, shells={skin: ts},
                   shell_bending={skin: p.skin_shell_bending_ratio}, beams=beams, curve_lengths=lengths)
    geo.save(out_dir / f"{p.name}.json")
    return geo
