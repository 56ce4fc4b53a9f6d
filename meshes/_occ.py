"""Small gmsh/OCC helpers shared by the builders (gmsh 4.8 API; no dolfinx).

Conventions: axisymmetric parts are drawn as a meridian profile in the gmsh xy plane
(x = radius >= 0, y = axial coordinate) and revolved about the y axis, then rotated so
that the axis becomes the global z axis and translated to the part's axis position.
Patches are imprinted by ``occ.fragment`` of the structural volumes with small tool
solids (boxes, cylinders); the tool parts outside the structure are removed again.
"""
from __future__ import annotations

import importlib
import math
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from liftoff.core.errors import InputError, ResourceError
from liftoff.core.records import atomic_path

# (most tetrahedra, what is meshed) for mesh_and_write; None: no limit (the builders alone)
_ELEMENT_LIMIT: ContextVar[tuple[float, str] | None] = ContextVar("liftoff_element_limit", default=None)
REGULAR_TET = 1.0 / (6.0 * math.sqrt(2.0))  # volume of a regular tetrahedron of edge h, over h^3


@contextmanager
def element_limit(max_elements: float, what: str):
    """Refuse (ResourceError) to mesh, inside this block, a model whose tetrahedra would
    number more than ``max_elements`` by the estimate of :func:`check_element_count`."""
    token = _ELEMENT_LIMIT.set((float(max_elements), what))
    try:
        yield
    finally:
        _ELEMENT_LIMIT.reset(token)


def check_element_count(mesh_size: float) -> float:
    """The fewest tetrahedra of size <= mesh_size that fill the model's volumes,
    V / (h^3 / (6 sqrt 2)) (regular tetrahedra of edge h: gmsh's are no larger); a
    ResourceError beyond the limit of :func:`element_limit`, before gmsh meshes."""
    volume = float(sum(occ.getMass(3, tag) for _, tag in gmsh.model.getEntities(3)))
    estimate = volume / (REGULAR_TET * mesh_size ** 3)
    limit = _ELEMENT_LIMIT.get()
    if limit is not None and estimate > limit[0]:
        raise ResourceError(f"{limit[1]}: mesh size {mesh_size:g} m would give at least {estimate:.3g} tetrahedra "
                            f"(volume {volume:.4g} m^3), beyond the limit of {limit[0]:.3g}; use a larger mesh_size "
                            "or raise [model] max_elements")
    return estimate


class _Lazy:
    """A module attribute path (``gmsh``, ``gmsh.model.occ``) imported on first use, so the
    parameter classes and closed forms of meshes/ load without gmsh."""

    def __init__(self, path: str):
        self._path = path

    def __getattr__(self, name: str):
        head, *rest = self._path.split(".")
        obj = importlib.import_module(head)
        for part in rest:
            obj = getattr(obj, part)
        return getattr(obj, name)


gmsh = _Lazy("gmsh")
occ = _Lazy("gmsh.model.occ")
SEAM_AZIMUTH = math.radians(-20.0)  # azimuth of the seam of revolved surfaces


@contextmanager
def gmsh_session(model_name: str):
    """Initialise gmsh quietly, add a model, and always finalise (builders are re-entrant
    one after another in one process; do not call a builder inside an open gmsh session)."""
    gmsh.initialize([], False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add(model_name)
        yield gmsh.model
    finally:
        gmsh.finalize()


# ---- 2D meridian profiles (x = radius, y = axial) ---------------------------------------
def _half_ellipse_disk(yc: float, r: float, a: float) -> int:
    """Elliptic disk centred on the axis at y = yc, radial semi-axis r, axial semi-axis a."""
    if r >= a:
        return occ.addDisk(0, yc, 0, r, a)
    d = occ.addDisk(0, yc, 0, a, r)
    occ.rotate([(2, d)], 0, yc, 0, 0, 0, 1, math.pi / 2)
    return d


def capsule_profile(r: float, a_bottom: float, a_top: float, y0: float, length: float) -> list:
    """Full (both-sided) section of a cylinder of radius r from y0 to y0+length closed by
    half-ellipsoid domes of axial heights a_bottom, a_top (0 = flat end). Returns dimTags."""
    parts = [(2, occ.addRectangle(-r, y0, 0, 2 * r, length))]
    if a_bottom > 0:
        parts.append((2, _half_ellipse_disk(y0, r, a_bottom)))
    if a_top > 0:
        parts.append((2, _half_ellipse_disk(y0 + length, r, a_top)))
    if len(parts) == 1:
        return parts
    out, _ = occ.fuse(parts[:1], parts[1:])
    return out


def shell_profile(r: float, t: float, a_bottom: float, a_top: float, y0: float, length: float) -> list:
    """Section of a thick-walled capsule: outer (r, a) minus inner (r - t, a - t) capsule.
    A flat end (a = 0) becomes a flat bulkhead of thickness t."""
    outer = capsule_profile(r, a_bottom, a_top, y0, length)
    ab_i = a_bottom - t if a_bottom > 0 else 0.0
    at_i = a_top - t if a_top > 0 else 0.0
    y0_i = y0 if a_bottom > 0 else y0 + t
    len_i = length - (0 if a_bottom > 0 else t) - (0 if a_top > 0 else t)
    inner = capsule_profile(r - t, ab_i, at_i, y0_i, len_i)
    out, _ = occ.cut(outer, inner)
    return out


def polygon(points) -> list:
    """Plane surface through the given (x, y) points (closed automatically)."""
    pts = [occ.addPoint(x, y, 0) for x, y in points]
    lines = [occ.addLine(pts[i], pts[(i + 1) % len(pts)]) for i in range(len(pts))]
    return [(2, occ.addPlaneSurface([occ.addCurveLoop(lines)]))]


def half(profile: list) -> list:
    """Keep the x >= 0 half of a profile (the meridian section to revolve)."""
    big = 1e4
    out, _ = occ.intersect(profile, [(2, occ.addRectangle(0, -big, 0, big, 2 * big))])
    return out


def revolve_to_z(profile: list, axis_xy=(0.0, 0.0), z_shift: float = 0.0) -> list:
    """Revolve a meridian profile (xy plane, axis = y) by 2 pi, map y -> z, move the axis to
    axis_xy and shift by z_shift. Returns the volume dimTags."""
    out = occ.revolve(profile, 0, 0, 0, 0, 1, 0, 2 * math.pi)
    vols = [d for d in out if d[0] == 3]
    occ.remove(profile, recursive=True)  # the leftover generating faces
    occ.rotate(vols, 0, 0, 0, 1, 0, 0, math.pi / 2)
    occ.rotate(vols, 0, 0, 0, 0, 0, 1, SEAM_AZIMUTH)  # keep the seam away from patches
    occ.translate(vols, axis_xy[0], axis_xy[1], z_shift)
    return vols


# ---- mid-surfaces (shell walls) ------------------------------------------------------------
def capsule_surface(r: float, a_bottom: float, a_top: float, z0: float, length: float, axis_xy=(0.0, 0.0)) -> list[int]:
    """Face tags of the closed surface of revolution about a vertical axis: cylinder of
    radius r from z0 to z0 + length closed by half-ellipsoid domes of heights a_bottom,
    a_top (0 = flat disk). Built as the boundary of the revolved solid, which is removed."""
    vols = revolve_to_z(half(capsule_profile(r, a_bottom, a_top, z0, length)), axis_xy)
    occ.synchronize()
    faces = boundary_faces(vols)
    occ.remove(vols)                       # not recursive: the faces stay
    occ.synchronize()
    return faces


def cylinder_surface(r: float, z0: float, z1: float, axis_xy=(0.0, 0.0)) -> list[int]:
    """Face tags of an open cylinder (skirt) of radius r from z0 to z1 about a vertical
    axis (seam at SEAM_AZIMUTH, like the revolved parts)."""
    c = occ.addCircle(0, 0, z0, r)
    occ.rotate([(1, c)], 0, 0, 0, 0, 0, 1, SEAM_AZIMUTH)
    occ.translate([(1, c)], axis_xy[0], axis_xy[1], 0)
    faces = [t for d, t in occ.extrude([(1, c)], 0, 0, z1 - z0) if d == 2]
    occ.synchronize()
    return faces


def remove_faces(faces: list[int]) -> None:
    """Remove faces (and what only they use) from the model."""
    if faces:
        occ.remove([(2, f) for f in faces], recursive=True)
        occ.synchronize()


def imprint_parts(volumes: dict[str, list], faces: dict[str, list[int]], tools: list["Tool"]) -> tuple[dict, dict]:
    """Fragment solid volumes (group -> volume dimTags) and shell faces (group -> face tags)
    together and with the tools (volumes or surfaces): conforming junctions (a shell face
    lying on a solid's face becomes that face: shared nodes), patch outlines and fill lines
    imprinted. Returns the new (volume dimTags per group, face tags per group); everything
    else (tool pieces) is removed."""
    order = [(g, d) for g, ds in volumes.items() for d in ds] + [(g, (2, f)) for g, fs in faces.items() for f in fs]
    if tools:
        out, outmap = occ.fragment([d for _, d in order], [t.dimtag for t in tools])
    else:                                      # fragment the parts among themselves
        out, outmap = occ.fragment([d for _, d in order[:1]], [d for _, d in order[1:]])
    new_v: dict[str, list] = {g: [] for g in volumes}
    new_f: dict[str, list[int]] = {g: [] for g in faces}
    for (g, d), children in zip(order, outmap[: len(order)]):
        if d[0] == 3:
            new_v[g].extend(c for c in children if c[0] == 3 and c not in new_v[g])
        else:
            new_f[g].extend(t for dd, t in children if dd == 2 and t not in new_f[g])
    occ.synchronize()
    keep_v = {d for ds in new_v.values() for d in ds}
    extra = [d for d in gmsh.model.getEntities(3) if d not in keep_v]
    if extra:
        occ.remove(extra)
        occ.synchronize()
    keep_f = {f for fs in new_f.values() for f in fs}
    if keep_v:
        keep_f |= {abs(t) for d, t in gmsh.model.getBoundary(list(keep_v), combined=False, oriented=False)}
    remove_faces([t for _, t in gmsh.model.getEntities(2) if t not in keep_f])
    stray = [d for d in gmsh.model.getEntities(1) if not gmsh.model.getAdjacencies(1, d[1])[0].size]
    if stray:
        occ.remove(stray, recursive=True)
        occ.synchronize()
    return new_v, new_f


def imprint_surfaces(groups: dict[str, list[int]], tools: list["Tool"]) -> dict[str, list[int]]:
    """imprint_parts for shell faces only: the new face tags per group."""
    return imprint_parts({}, groups, tools)[1]


# ---- liquids ----------------------------------------------------------------------------------
def liquid_solid(r: float, a_bottom: float, a_top: float, z0: float, length: float, z_fill: float,
                 axis_xy=(0.0, 0.0)) -> list:
    """The liquid of a capsule cavity (cylinder of radius r from z0 to z0 + length, domes of
    heights a_bottom, a_top; 0 = flat) filled up to the height z_fill: volume dimTags."""
    big = 1e4
    profile = capsule_profile(r, a_bottom, a_top, z0, length)
    below, _ = occ.intersect(profile, [(2, occ.addRectangle(-big, -big, 0, 2 * big, z_fill + big))])
    return revolve_to_z(half(below), axis_xy)


def add_liquids(volumes: dict[str, list], faces: dict[str, list[int]],
                liquids: dict[str, list]) -> tuple[dict, dict, dict]:
    """Fragment the structure (volume dimTags and shell face tags per group) with the
    liquid volumes (dimTags per liquid group): the liquids then share the faces they touch
    with the walls (conforming: common nodes). Returns (structural volumes, shell faces,
    liquid volumes), each per group, with the new tags."""
    new_v, new_f = imprint_parts({**volumes, **liquids}, faces, [])
    return {g: new_v[g] for g in volumes}, new_f, {g: new_v[g] for g in liquids}


def liquid_faces(liquid: list, wall_faces: set[int], name: str) -> tuple[list[int], list[int]]:
    """(wetted, free) faces of a liquid volume: its boundary faces that are wall faces (the
    wetted surface) and the others (its free surface). InputError if either is empty."""
    bnd = boundary_faces(liquid)
    wet = [f for f in bnd if f in wall_faces]
    free = [f for f in bnd if f not in wall_faces]
    if not wet:
        raise InputError(f"liquid {name!r}: the liquid volume does not touch the wall (no shared face)")
    if not free:
        raise InputError(f"liquid {name!r}: the liquid fills its cavity completely (no free surface; "
                         "a hydroelastic liquid needs an ullage above it)")
    return wet, free


def point_at(xyz, tol: float) -> int:
    """Tag of the model point (vertex) at xyz (InputError if there is none)."""
    x, y, z = (float(v) for v in xyz)
    hits = gmsh.model.getEntitiesInBoundingBox(x - tol, y - tol, z - tol, x + tol, y + tol, z + tol, 0)
    if not hits:
        raise InputError(f"no geometry vertex at {[round(v, 6) for v in (x, y, z)]} m (pressure point)")
    return int(hits[0][1])


# ---- patch tools ---------------------------------------------------------------------------
@dataclass
class Tool:
    """A tool solid imprinting a patch; faces of the structure's boundary whose bounding
    box lies inside ``bbox`` become the patch ``name`` (``name=None``: a split only)."""

    name: str | None
    dimtag: tuple
    bbox: tuple


def radial_box(name, axis_xy, phi: float, rho0: float, rho1: float, z0: float, z1: float, w: float) -> Tool:
    """Box spanning radii [rho0, rho1] along azimuth phi (rad) about a vertical axis at
    axis_xy, tangential half-width w, heights [z0, z1]."""
    b = occ.addBox(rho0, -w, z0, rho1 - rho0, 2 * w, z1 - z0)
    occ.rotate([(3, b)], 0, 0, 0, 0, 0, 1, phi)
    occ.translate([(3, b)], axis_xy[0], axis_xy[1], 0)
    return Tool(name, (3, b), occ.getBoundingBox(3, b))


def wall_patch(name, axis_xy, phi: float, z: float, r_surface: float, r_other: float, w: float, h: float) -> Tool:
    """Tool imprinting a (2w x 2h) patch on the cylindrical wall surface of radius r_surface
    (r_other = radius of the wall's other surface) at azimuth phi and height z, cutting only
    into the wall (never through it)."""
    if r_surface > r_other:  # outer surface: cut from inside the wall outwards
        lo, hi = r_other, math.sqrt(r_surface ** 2 - w ** 2)
        if hi <= lo:
            raise InputError(f"patch {name}: half-width {w} m too wide for a wall of radius {r_surface} m")
        return radial_box(name, axis_xy, phi, 0.5 * (lo + hi), r_surface + 1.0, z - h, z + h, w)
    lo, hi = r_surface, math.sqrt(r_other ** 2 - w ** 2)  # inner surface
    if hi <= lo:
        raise InputError(f"patch {name}: half-width {w} m too wide for a wall of radius {r_surface} m")
    return radial_box(name, axis_xy, phi, max(r_surface - 1.0, 0.0), 0.5 * (lo + hi), z - h, z + h, w)


def shell_wall_patch(name, axis_xy, phi: float, z: float, r: float, w: float, h: float) -> Tool:
    """Tool imprinting a (2w x 2h) patch on a cylindrical mid-surface of radius r at azimuth
    phi and height z: a radial box reaching just past the patch's sagitta on both sides."""
    if w >= r:
        raise InputError(f"patch {name}: half-width {w} m too wide for a wall of radius {r} m")
    d = 2 * (r - math.sqrt(r * r - w * w)) + 0.05 * r
    return radial_box(name, axis_xy, phi, r - d, r + d, z - h, z + h, w)


def cylinder_tool(name, center, radius: float, z0: float, z1: float) -> Tool:
    """Vertical cylinder (disk patches on horizontal faces)."""
    c = occ.addCylinder(center[0], center[1], z0, 0, 0, z1 - z0, radius)
    return Tool(name, (3, c), occ.getBoundingBox(3, c))


def plane_cut(z: float, half_size: float = 1e3) -> Tool:
    """Horizontal plane at height z (splits walls, e.g. at a fill level)."""
    s = occ.addRectangle(-half_size, -half_size, z, 2 * half_size, 2 * half_size)
    return Tool(None, (2, s), occ.getBoundingBox(2, s))


def imprint(groups: dict[str, list], tools: list[Tool]) -> dict[str, list]:
    """Fragment the structural volumes (group name -> volume dimTags) with the tools;
    return the new volume dimTags per group, all tool remnants outside removed."""
    order = [(g, d) for g, ds in groups.items() for d in ds]
    obj = [d for _, d in order]
    if not tools and len(obj) == 1:  # nothing to make conforming
        occ.synchronize()
        return {g: list(ds) for g, ds in groups.items()}
    out, outmap = occ.fragment(obj, [t.dimtag for t in tools])
    new: dict[str, list] = {g: [] for g in groups}
    for (g, _), children in zip(order, outmap[: len(order)]):
        new[g].extend(c for c in children if c not in new[g])
    occ.synchronize()
    keep = {d for ds in new.values() for d in ds}
    extra = [d for d in gmsh.model.getEntities(3) if d not in keep]
    if extra:
        occ.remove(extra, recursive=True)
        occ.synchronize()
    faces = set(gmsh.model.getBoundary(list(keep), combined=False, oriented=False))
    loose = [d for d in gmsh.model.getEntities(2) if d not in faces]
    if loose:
        occ.remove(loose, recursive=True)
    occ.synchronize()
    return new


def boundary_faces(vols: list, combined: bool = True) -> list[int]:
    """Tags of the faces on the outer boundary of the union of the volumes
    (``combined=False``: all faces of every volume, shared ones included)."""
    return sorted({abs(t) for d, t in gmsh.model.getBoundary(vols, combined=combined, oriented=False) if d == 2})


def faces_inside(faces: list[int], bbox, tol: float = 1e-3) -> list[int]:
    """Faces whose bounding box lies inside bbox (xmin, ymin, zmin, xmax, ymax, zmax) +- tol."""
    lo, hi = np.array(bbox[:3]) - tol, np.array(bbox[3:]) + tol
    sel = []
    for f in faces:
        b = np.array(gmsh.model.getBoundingBox(2, f))
        if np.all(b[:3] >= lo) and np.all(b[3:] <= hi):
            sel.append(f)
    return sel


def faces_on(faces: list[int], distance, tol: float, n: int = 4) -> list[int]:
    """Faces whose sample points (an n x n grid inside the parametric domain) all satisfy
    |distance(x, y, z)| <= tol, e.g. lie on a given analytic surface."""
    sel = []
    u = (np.arange(n) + 0.5) / n
    for f in faces:
        lo, hi = gmsh.model.getParametrizationBounds(2, f)
        uv = np.array([[lo[0] + a * (hi[0] - lo[0]), lo[1] + b * (hi[1] - lo[1])] for a in u for b in u])
        pts = np.asarray(gmsh.model.getValue(2, f, uv.ravel())).reshape(-1, 3)
        if all(abs(distance(*p)) <= tol for p in pts):
            sel.append(f)
    return sel


def capsule_distance(axis_xy, r: float, z_cb: float, z_ct: float, a_b: float, a_t: float):
    """Signed level-set function (~distance, m) of a capsule surface about a vertical axis:
    cylinder of radius r from z_cb to z_ct, half-ellipsoid domes of heights a_b, a_t."""
    def d(x, y, z):
        rho = math.hypot(x - axis_xy[0], y - axis_xy[1])
        if z < z_cb:
            return r * (math.hypot(rho / r, (z - z_cb) / a_b) - 1)
        if z > z_ct:
            return r * (math.hypot(rho / r, (z - z_ct) / a_t) - 1)
        return rho - r
    return d


def refine_faces(faces: list[int], size: float) -> None:
    """Impose a mesh size at the points bounding the given faces."""
    pts = gmsh.model.getBoundary([(2, f) for f in faces], combined=False, oriented=False, recursive=True)
    gmsh.model.mesh.setSize(list({(0, abs(t)) for d, t in pts if d == 0}), size)


def patch_groups(faces: list[int], tools: list[Tool], refs: dict, size) -> list:
    """Spider patches of the named tools: the faces (of ``faces``) inside the boxes of the
    tools of one name become the physical surface of that name, meshed at ``size(name)``
    (m); returns the ``meshes.spec.Patch`` list with the reference points ``refs[name]``."""
    from .spec import Patch

    faces_of: dict[str, list] = {}
    for tl in tools:
        if tl.name is not None:
            faces_of.setdefault(tl.name, []).extend(faces_inside(faces, tl.bbox))
    for name, inside in faces_of.items():
        add_physical(2, name, inside)
        refine_faces(inside, size(name))
    return [Patch(name, np.asarray(refs[name], float)) for name in faces_of]


def add_physical(dim: int, name: str, tags: list[int]) -> int:
    if not tags:
        raise InputError(f"physical group {name!r}: no entities selected (geometry parameters?)")
    tag = gmsh.model.addPhysicalGroup(dim, sorted(set(tags)))
    gmsh.model.setPhysicalName(dim, tag, name)
    return tag


def curvature_elements(thickness: float, max_curvature_radius: float) -> int:
    """Elements per 2 pi of curvature so that the facet sag rho (1 - cos(pi/n)) of a curved
    wall stays below thickness/2 (else the inner and outer surface meshes of a thin wall can
    cross and the 3D mesher fails): n >= pi sqrt(rho / t)."""
    return int(math.ceil(math.pi * math.sqrt(max_curvature_radius / thickness)))


def mesh_and_write(path: Path, mesh_size: float, curvature_n: int = 0) -> int:
    """Mesh in 3D (P1 tets, sizes <= mesh_size, and <= 2 pi rho / curvature_n on walls of
    curvature radius rho when curvature_n > 0) and write ``path`` atomically. Returns node count.
    The element count is estimated first (:func:`check_element_count`)."""
    check_element_count(mesh_size)
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", int(curvature_n))
    gmsh.option.setNumber("Mesh.MeshSizeMax", mesh_size)
    gmsh.option.setNumber("Mesh.MeshSizeMin", 0.0)
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 1)
    gmsh.option.setNumber("Mesh.Optimize", 1)
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.model.mesh.generate(3)
    n_nodes = len(gmsh.model.mesh.getNodes()[0])
    with atomic_path(path, suffix=".msh") as tmp:     # gmsh picks the format by the suffix
        gmsh.write(str(tmp))
    return n_nodes


def physical_measures(dim: int) -> dict[str, float]:
    """CAD measure (area for dim 2, volume for dim 3; m^2, m^3) of every physical group of dim."""
    out = {}
    for d, tag in gmsh.model.getPhysicalGroups(dim):
        ents = gmsh.model.getEntitiesForPhysicalGroup(d, tag)
        out[gmsh.model.getPhysicalName(d, tag)] = float(sum(occ.getMass(d, e) for e in ents))
    return out


def group_volume(vols: list) -> float:
    return float(sum(occ.getMass(3, t) for _, t in vols))
