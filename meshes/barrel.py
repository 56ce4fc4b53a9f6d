"""A thin-walled barrel: an interstage, skirt, fairing or payload adapter, cylindrical or
conical, as a Reissner-Mindlin shell surface (fem.shell), joined to the stages it connects
at named points on its end rings.

Each end ring is split into arcs: around each joint azimuth an arc of ``2 * arc_deg``,
tied rigidly (RBE2) to its point at the ring's radius and height (where a tank stage's
patch of the same name sits, meshes.tank), and free arcs between them. An end may instead
tie its whole ring to one point on the axis (``top_point`` / ``bottom_point``: a payload
adapter's separation plane carrying the payload as a point mass). Units SI. The wall's
material is ``material``; ``mass`` (kg), if given, sets its density (E/rho kept: the
stringers and frames of a stiffened barrel smeared into its skin at the skin's mass).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from liftoff.core.errors import InputError

from . import _occ
from ._occ import occ
from .spec import Geometry, Material, Patch, PointMass, require_positive

AL7075 = Material("Al7075", 71.7e9, 0.33, 2810.0)


@dataclass
class BarrelParams:
    """Barrel geometry (SI): axis at ``axis_xy``, from ``z_bottom`` (radius ``radius_bottom``)
    to ``z_top`` (``radius_top``), wall ``thickness``; ``joints_bottom``/``joints_top``:
    {point name: azimuth (deg)}; ``bottom_point``/``top_point``: {name: z} of one axis point
    the whole ring ties to instead (at most one per end); ``point_masses``: {point name:
    [mass kg, Ixx, Iyy, Izz kg m^2]} at any of its points."""

    name: str = "barrel"
    radius_bottom: float = 1.83
    radius_top: float = 1.83
    z_bottom: float = 0.0
    z_top: float = 4.0
    thickness: float = 0.01
    axis_xy: tuple = (0.0, 0.0)
    material: Material = field(default_factory=lambda: replace(AL7075))
    mass: float | None = None
    joints_bottom: dict = field(default_factory=dict)
    joints_top: dict = field(default_factory=dict)
    bottom_point: dict = field(default_factory=dict)
    top_point: dict = field(default_factory=dict)
    point_masses: dict = field(default_factory=dict)
    arc_deg: float = 15.0
    mesh_size: float = 0.5

    def check(self) -> None:
        o = f"BarrelParams({self.name})"
        require_positive(o, radius_bottom=self.radius_bottom, radius_top=self.radius_top,
                         thickness=self.thickness, arc_deg=self.arc_deg, mesh_size=self.mesh_size)
        if self.mass is not None:
            require_positive(o, mass=self.mass)
        if not self.z_top > self.z_bottom:
            raise InputError(f"{o}: z_top {self.z_top} m must be above z_bottom {self.z_bottom} m")
        for end in ("bottom", "top"):
            joints, axis = getattr(self, f"joints_{end}"), getattr(self, f"{end}_point")
            if joints and axis:
                raise InputError(f"{o}: the {end} ring has joints and an axis point: one or the other")
            if len(axis) > 1:
                raise InputError(f"{o}.{end}_point: one axis point per end (got {len(axis)})")
            az = sorted(float(a) % 360.0 for a in joints.values())
            gaps = [(b - a) % 360.0 for a, b in zip(az, az[1:] + az[:1])] if len(az) > 1 else [360.0]
            if az and min(gaps) <= 2 * self.arc_deg + 1e-6:
                raise InputError(f"{o}.joints_{end}: joint arcs of +-{self.arc_deg} deg overlap (azimuths {az})")
        names = self.point_names()
        if len(set(names)) != len(names):
            raise InputError(f"{o}: point names repeat: {names}")
        for n, spec in self.point_masses.items():
            if n not in names:
                raise InputError(f"{o}.point_masses: {n!r} is not one of its points ({', '.join(names)})")
            if len(spec) != 4 or not all(math.isfinite(float(x)) and float(x) >= 0 for x in spec) or spec[0] <= 0:
                raise InputError(f"{o}.point_masses.{n}: expected [mass > 0 kg, Ixx, Iyy, Izz >= 0 kg m^2]")

    def point_names(self) -> list[str]:
        return [*self.joints_bottom, *self.joints_top, *self.bottom_point, *self.top_point]

    def points(self) -> dict[str, np.ndarray]:
        """Reference points (m): joints on their ring, axis points on the axis."""
        x0, y0 = self.axis_xy
        out = {}
        for joints, r, z in ((self.joints_bottom, self.radius_bottom, self.z_bottom),
                             (self.joints_top, self.radius_top, self.z_top)):
            for n, a in joints.items():
                out[n] = np.array([x0 + r * math.cos(math.radians(a)), y0 + r * math.sin(math.radians(a)), z])
        for pts in (self.bottom_point, self.top_point):
            for n, z in pts.items():
                out[n] = np.array([x0, y0, float(z)])
        return out

    def wall_area(self) -> float:
        """Lateral area of the frustum (m^2)."""
        r1, r2, h = self.radius_bottom, self.radius_top, self.z_top - self.z_bottom
        return math.pi * (r1 + r2) * math.hypot(h, r2 - r1)


def _breaks(joints: dict, arc: float) -> list[float]:
    """Azimuths (deg) splitting a ring: both ends of each joint's arc (or four quarters)."""
    if not joints:
        return [0.0, 90.0, 180.0, 270.0]
    return sorted(((float(a) + s) % 360.0) for a in joints.values() for s in (-arc, arc))


def build_barrel(p: BarrelParams, out_dir) -> Geometry:
    """Shell surface ``<name>_wall``; curve groups named after the points (joint arcs, or a
    whole ring tied to an axis point)."""
    if not isinstance(p, BarrelParams):
        raise InputError(f"build_barrel expects BarrelParams, got {type(p).__name__}")
    p.check()
    out_dir = Path(out_dir)
    x0, y0 = p.axis_xy
    az = sorted(set(_breaks(p.joints_bottom, p.arc_deg)) | set(_breaks(p.joints_top, p.arc_deg)))
    with _occ.gmsh_session(p.name):
        def ring(r, z):
            c = occ.addPoint(x0, y0, z)
            pts = [occ.addPoint(x0 + r * math.cos(math.radians(a)), y0 + r * math.sin(math.radians(a)), z) for a in az]
            return [occ.addCircleArc(pts[k], c, pts[(k + 1) % len(pts)]) for k in range(len(pts))]

        low, up = ring(p.radius_bottom, p.z_bottom), ring(p.radius_top, p.z_top)
        for a, b in zip(low, up):
            occ.addThruSections([occ.addWire([a]), occ.addWire([b])], makeSolid=False, makeRuled=True)
        occ.removeAllDuplicates()
        occ.synchronize()
        wall = f"{p.name}_wall"
        _occ.add_physical(2, wall, [t for _, t in _occ.gmsh.model.getEntities(2)])

        def arcs_at(z, r, centre_deg=None, half=None):
            out = []
            for _, c in _occ.gmsh.model.getEntities(1):
                cx, cy, cz = occ.getCenterOfMass(1, c)
                if abs(cz - z) > 1e-6 * max(1.0, abs(z)) or math.hypot(cx - x0, cy - y0) < 1e-3 * r:
                    continue
                if centre_deg is None:
                    out.append(c)
                    continue
                a = math.degrees(math.atan2(cy - y0, cx - x0))
                if abs((a - centre_deg + 180.0) % 360.0 - 180.0) < half:
                    out.append(c)
            return out

        for joints, axis, r, z in ((p.joints_bottom, p.bottom_point, p.radius_bottom, p.z_bottom),
                                   (p.joints_top, p.top_point, p.radius_top, p.z_top)):
            for n, a in joints.items():
                # the ring is split at both ends' breaks, so a joint's arc may be in pieces: every piece
                # inside its +-arc_deg (whose ends are breaks of this ring) is its, by the piece's middle
                _occ.add_physical(1, n, arcs_at(z, r, float(a), p.arc_deg))
            for n in axis:
                _occ.add_physical(1, n, arcs_at(z, r))
        refs = p.points()
        patches = [Patch(n, refs[n]) for n in p.point_names()]
        n_nodes = _occ.mesh_and_write(out_dir / f"{p.name}.msh", p.mesh_size)
    area = p.wall_area()
    mat = p.material if p.mass is None else Material(
        f"{p.material.name}-smeared", p.material.E * (p.mass / (area * p.thickness)) / p.material.rho,
        p.material.nu, p.mass / (area * p.thickness))
    masses = [PointMass(f"{n}_mass", n, m[0], np.diag([float(x) for x in m[1:]])) for n, m in p.point_masses.items()]
    geo = Geometry(p.name, str(out_dir / f"{p.name}.msh"), {wall: mat}, patches, masses, [], [], {}, n_nodes,
                   {wall: area}, {wall: p.thickness})
    geo.save(out_dir / f"{p.name}.json")
    return geo
