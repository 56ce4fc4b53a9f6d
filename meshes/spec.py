"""What a geometry builder hands to fem/: a gmsh ``.msh`` plus a JSON sidecar (this module).

Contract (DESIGN.md, issue 3). Units SI throughout: m, kg, Pa, kg/m^3, kg m^2.

- ``volumes``: physical group name -> :class:`Material`: every VOLUME group (solid
  tetrahedra), and every SURFACE group listed in ``shells``.
- ``shells``: physical SURFACE group name -> thickness (m): the group's triangles are
  Reissner-Mindlin shells (fem.shell) on the mid-surface, with the material of
  ``volumes[name]``. Shells and solids meshed together share nodes (translations tie).
- ``shell_bending``: shell group -> bending stiffness ratio 12 I / t^3 (Nastran PSHELL's
  12I/T**3; absent = 1, a homogeneous plate): frames and stringers smeared into the
  bending stiffness of a wall whose membrane stiffness and mass are the skin's.
- ``patches``: a physical SURFACE group (dim 2) named ``Patch.name``, tied by a rigid
  spider (Nastran RBE2) to one 6-DOF reference point at ``Patch.ref_point``; the point's
  DOFs are labelled ``"<name>:Tx" ... "<name>:Rz"``. Interfaces, hold-downs, engine
  mounts and load-recovery stations are all patches.
- ``point_masses``: lumped mass (with inertia about the patch reference point) at the
  reference point of a patch.
- ``smeared_masses``: non-structural mass spread uniformly (per unit area) over a
  physical surface group (propellant on the wetted wall).
- ``clamped``: surface groups fixed to ground (pad pedestal bottoms); empty for free-free.
- ``liquids``: physical VOLUME group name -> :class:`Liquid`: an incompressible, inviscid
  liquid (fem.liquid) meshed with tetrahedra that share the ``wetted`` surface with the
  structure (a solid wall's inner face, or a shell surface); its ``free_surface`` (p = 0)
  faces the empty ullage. A liquid group is not a structural volume (it has no entry
  in ``volumes``).

JSON sidecar layout (``format = "liftoff-geometry"``, ``version = 1``, ``units = "SI"``):
the fields above as plain JSON; ``msh_path`` is stored relative to the sidecar's folder
when the mesh lies in or below it, and is returned absolute by :meth:`Geometry.load`.
Optional extras: ``shells`` and ``shell_bending`` (absent = no shells), ``liquids``
(absent = none; each ``{density, wetted, free_surface, cavity, center, points,
slosh_modes, gravity}``), ``group_volumes``
(CAD volume of each physical volume group, m^3, from ``gmsh.model.occ.getMass``),
``surface_areas`` (CAD area of each physical surface group, m^2) and ``mesh_nodes`` (node
count of the written mesh); ``beams`` (absent = none; each ``{material, section, vref,
offset, radial_offset, axis_point, axis_direction, rotary, nsm}``, :class:`BeamGroup`) and
``curve_lengths`` (CAD length of each beam curve group, m).

- ``beams``: physical CURVE group name -> :class:`BeamGroup`: the group's line elements are
  3-D Timoshenko beams (fem.beam, liftoff.core.beam), 6 DOFs a node, with their own
  material and section; they share nodes with the shells and solids they lie on.
"""
from __future__ import annotations

import json
import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from liftoff.core.elastic import check_elastic
from liftoff.core.errors import InputError
from liftoff.core.records import write_text
from liftoff.core.units import G0


def require_positive(owner: str, **values: float) -> None:
    """InputError naming the first parameter that is not a finite number > 0."""
    for name, v in values.items():
        try:
            ok = math.isfinite(float(v)) and float(v) > 0
        except (TypeError, ValueError):
            ok = False
        if not ok:
            raise InputError(f"{owner}.{name} must be a finite number > 0 (got {v!r})")


def require_range(owner: str, name: str, value: float, lo: float, hi: float, unit: str, why: str) -> None:
    """InputError naming ``owner.name`` unless ``lo <= value <= hi`` (in ``unit``); ``why``
    says what the range is (the physical span of such a quantity)."""
    if not lo <= value <= hi:
        raise InputError(f"{owner}.{name} = {value:g} {unit} is outside [{lo:g}, {hi:g}] {unit}, {why}")


WALLS = ("solid", "shell")


def check_walls(owner: str, walls) -> None:
    """InputError unless ``walls`` is "solid" (thickened tetrahedra) or "shell" (mid-surface)."""
    if walls not in WALLS:
        raise InputError(f"{owner}.walls must be one of {', '.join(map(repr, WALLS))} (got {walls!r})")


def check_ring_frames(owner: str, walls: str, frames, section, material, lo: float, hi: float,
                      wall: str = "wall", surface: str = "the cylindrical wall") -> None:
    """Ring frames (beams on a shell ``wall``): none, or shell walls, a standard section
    (liftoff.core.beam.standard_section), heights strictly between ``lo`` and ``hi`` (m, on
    ``surface``), none repeated, and a Material or None; InputError naming ``owner``."""
    if not frames:
        return
    from liftoff.core.beam import standard_section

    if walls != "shell":
        raise InputError(f"{owner}.frames: ring frames are beams on a shell {wall}; they need walls = 'shell' "
                         f"(got {walls!r})")
    standard_section(section, f"{owner}.frame_section")
    for z in frames:
        if isinstance(z, bool) or not isinstance(z, (int, float)) or not lo < z < hi:
            raise InputError(f"{owner}.frames: height {z!r} m is not on {surface} ({lo:.3f} to {hi:.3f} m)")
    if len({round(float(z), 6) for z in frames}) != len(frames):
        raise InputError(f"{owner}.frames: heights repeat ({list(frames)})")
    if material is not None and not isinstance(material, Material):
        raise InputError(f"{owner}.frame_material must be a Material (E, nu, rho)")


def check_stringers(owner: str, walls: str, stringers, section, material) -> int:
    """Stringers (beams along a shell wall): a whole number >= 0; if any, shell walls, a
    standard section and a Material or None. Returns the number; InputError naming ``owner``."""
    if isinstance(stringers, bool) or not isinstance(stringers, (int, float)) \
            or stringers != int(stringers) or stringers < 0:
        raise InputError(f"{owner}.stringers must be a whole number >= 0 (got {stringers!r})")
    if stringers:
        from liftoff.core.beam import standard_section

        if walls != "shell":
            raise InputError(f"{owner}.stringers: stringers are beams on a shell wall; they need walls = 'shell' "
                             f"(got {walls!r})")
        standard_section(section, f"{owner}.stringer_section")
        if material is not None and not isinstance(material, Material):
            raise InputError(f"{owner}.stringer_material must be a Material (E, nu, rho)")
    return int(stringers)


#: how a shell wall carries its off-axis attach points: rigid patches or interpolation rings
ATTACH = ("patch", "ring")


def check_attach(owner: str, walls: str, attach) -> str:
    """``attach`` checked: "patch" or "ring" (the latter with shell walls only); None gives
    "ring" with shell walls and "patch" with solid ones."""
    if attach is None:
        return "ring" if walls == "shell" else "patch"
    if attach not in ATTACH:
        raise InputError(f"{owner}.attach must be one of {', '.join(map(repr, ATTACH))} (got {attach!r})")
    if attach == "ring" and walls != "shell":
        raise InputError(f"{owner}.attach = 'ring' needs walls = 'shell' (got {walls!r})")
    return attach


FORMAT = "liftoff-geometry"
VERSION = 1
_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_.\-]*$")


def _check_name(kind: str, name) -> None:
    if not isinstance(name, str) or not _NAME.match(name):
        raise InputError(f"{kind} name {name!r} is not a plain identifier (letters, digits, _ . -)")


@dataclass
class Material:
    """Linear isotropic elastic material: E (Pa), nu (-), rho (kg/m^3)."""

    name: str
    E: float
    nu: float
    rho: float

    def __post_init__(self) -> None:
        self.check()

    def check(self, where: str = "") -> None:
        """InputError naming the material (and ``where``, e.g. its volume) and the value if
        E, nu or rho is not physical: the one material check of the project."""
        who = f"material {self.name!r}" + (f" of {where}" if where else "")
        self.E, self.nu, self.rho = check_elastic(who, self.E, self.nu, self.rho)


def equivalent(base: Material, mass: float, volume: float, name: str | None = None) -> Material:
    """Material of a thickened part: density so that rho * volume = mass, E scaled with it
    (E/rho of ``base`` kept: membrane/beam stiffness and wave speeds of the real wall)."""
    rho = mass / volume
    return Material(name or f"{base.name}-equivalent", base.E * rho / base.rho, base.nu, rho)


@dataclass
class Patch:
    """A 6-DOF reference point ``ref_point`` (m) tied to mesh nodes. ``nodes=None``: the
    surface (or shell curve) group ``name`` hangs on it rigidly (rigid spider, RBE2).
    ``nodes`` = a group name: the point follows the least-squares rigid fit of the
    translations of that group's nodes within ``reach`` (m) of it, unit weights, and adds
    no stiffness (interpolation, Nastran RBE3: a frame's attach fitting spreading its loads
    over a sector of the wall; several points may share a group's nodes)."""

    name: str
    ref_point: np.ndarray
    nodes: str | None = None
    reach: float = math.inf

    def __post_init__(self) -> None:
        _check_name("patch", self.name)
        self.ref_point = np.asarray(self.ref_point, dtype=float).reshape(-1)
        if self.ref_point.shape != (3,) or not np.all(np.isfinite(self.ref_point)):
            raise InputError(f"patch {self.name!r}: ref_point must be 3 finite coordinates (m)")
        if self.nodes is not None:
            _check_name(f"patch {self.name!r}: nodes group", self.nodes)
        self.reach = float(self.reach)
        if not self.reach > 0:
            raise InputError(f"patch {self.name!r}: reach must be > 0 m (got {self.reach!r})")

    def to_dict(self) -> dict:
        d = {"name": self.name, "ref_point": self.ref_point.tolist()}
        if self.nodes is not None:
            d.update(nodes=self.nodes, reach=None if math.isinf(self.reach) else self.reach)
        return d

    @classmethod
    def from_dict(cls, d: dict) -> "Patch":
        reach = d.get("reach")
        return cls(d["name"], np.array(d["ref_point"]), d.get("nodes"), math.inf if reach is None else reach)


@dataclass
class PointMass:
    """Lumped mass (kg) and inertia (kg m^2, about the reference point of ``patch``)."""

    name: str
    patch: str
    mass: float
    inertia: np.ndarray = field(default_factory=lambda: np.zeros((3, 3)))

    def __post_init__(self) -> None:
        self.mass = float(self.mass)
        self.inertia = np.asarray(self.inertia, dtype=float)
        if not (np.isfinite(self.mass) and self.mass > 0):
            raise InputError(f"point mass {self.name!r}: mass must be > 0 kg (got {self.mass})")
        if self.inertia.shape != (3, 3) or not np.allclose(self.inertia, self.inertia.T):
            raise InputError(f"point mass {self.name!r}: inertia must be a symmetric 3x3 (kg m^2)")
        if np.linalg.eigvalsh(self.inertia).min() < -1e-9 * max(1.0, np.abs(self.inertia).max()):
            raise InputError(f"point mass {self.name!r}: inertia is not positive semi-definite")


@dataclass
class SmearedMass:
    """Non-structural mass (kg) spread uniformly over the surface group ``surface``."""

    surface: str
    mass: float

    def __post_init__(self) -> None:
        self.mass = float(self.mass)
        if not (np.isfinite(self.mass) and self.mass >= 0):
            raise InputError(f"smeared mass on {self.surface!r}: mass must be >= 0 kg (got {self.mass})")


@dataclass
class Liquid:
    """An incompressible, inviscid liquid filling a physical volume group (fem.liquid).

    ``density`` (kg/m^3); ``wetted``: the surface group it shares with the structure (the
    added mass couples through it); ``free_surface``: its surface facing the ullage, p = 0
    (the liquid's perturbation pressure; hydrostatic head added by the run);
    ``cavity``: the whole inner wall of its compartment (wetted and dry), whose volume change
    is the ullage volume change (None: no ullage output); ``center``: a point inside that
    convex cavity (m; orients the cavity's normals outwards); ``points``: pressure recovery
    points {name: (x, y, z) m} (the tank bottom), each at a node of the liquid mesh;
    ``slosh_modes``: the lowest gravity slosh modes kept (0: the free surface stays at p = 0,
    the high-frequency limit); ``gravity``: the apparent acceleration (m/s^2, along the free
    surface's outward normal reversed) of those slosh modes; ``ullage_pressure``: the gauge
    pressure (Pa) of the ullage gas, uniform on the whole ``cavity`` wall (needs it): the
    pressure prestress of a shell wall (fem.prestress; 0 = none)."""

    density: float
    wetted: str
    free_surface: str
    cavity: str | None = None
    center: np.ndarray = field(default_factory=lambda: np.zeros(3))
    points: dict = field(default_factory=dict)
    slosh_modes: int = 0
    gravity: float = G0
    ullage_pressure: float = 0.0

    def __post_init__(self) -> None:
        self.check()

    def check(self, where: str = "liquid") -> None:
        """One-line InputError naming ``where`` and the bad value."""
        try:
            self.density = float(self.density)
        except (TypeError, ValueError):
            raise InputError(f"{where}: density {self.density!r} kg/m^3 is not a number") from None
        if not (math.isfinite(self.density) and self.density > 0):
            raise InputError(f"{where}: density {self.density!r} kg/m^3 must be > 0")
        for key in ("wetted", "free_surface") + (("cavity",) if self.cavity is not None else ()):
            _check_name(f"{where}: {key} surface", getattr(self, key))
        self.center = np.asarray(self.center, float).reshape(-1)
        if self.center.shape != (3,) or not np.all(np.isfinite(self.center)):
            raise InputError(f"{where}: center must be 3 finite coordinates (m)")
        pts = {}
        for name, xyz in dict(self.points).items():
            _check_name(f"{where}: pressure point", name)
            xyz = np.asarray(xyz, float).reshape(-1)
            if xyz.shape != (3,) or not np.all(np.isfinite(xyz)):
                raise InputError(f"{where}: pressure point {name!r} must be 3 finite coordinates (m)")
            pts[name] = xyz
        self.points = pts
        if isinstance(self.slosh_modes, bool) or not isinstance(self.slosh_modes, (int, np.integer)) \
                or self.slosh_modes < 0:
            raise InputError(f"{where}: slosh_modes must be an integer >= 0 (got {self.slosh_modes!r})")
        self.slosh_modes = int(self.slosh_modes)
        require_positive(where, gravity=self.gravity)
        self.gravity = float(self.gravity)
        try:
            self.ullage_pressure = float(self.ullage_pressure)
        except (TypeError, ValueError):
            raise InputError(f"{where}: ullage_pressure {self.ullage_pressure!r} Pa is not a number") from None
        if not (math.isfinite(self.ullage_pressure) and self.ullage_pressure >= 0):
            raise InputError(f"{where}: ullage_pressure {self.ullage_pressure!r} Pa must be >= 0 (gauge)")
        if self.ullage_pressure > 0 and self.cavity is None:
            raise InputError(f"{where}: ullage_pressure needs the cavity surface it acts on")

    def to_dict(self) -> dict:
        out = {"density": self.density, "wetted": self.wetted, "free_surface": self.free_surface,
               "cavity": self.cavity, "center": self.center.tolist(),
               "points": {k: v.tolist() for k, v in self.points.items()}, "slosh_modes": self.slosh_modes,
               "gravity": self.gravity}
        if self.ullage_pressure:         # written only when set: unpressurised files stay as they were
            out["ullage_pressure"] = self.ullage_pressure
        return out


@dataclass
class BeamGroup:
    """Beams on a physical curve group (fem.beam): ``material`` (E, nu, rho), ``section``
    (liftoff.core.beam.Section: A, Iy, Iz, J, shear areas; m^2, m^4), the orientation
    vector ``vref`` (global 3-vector, Nastran CBEAM's v: local y towards it, z = x cross
    vref; a given one along a member is refused; None, the default: global z, or for a
    member along z an axis off it, liftoff.core.beam), ``"radial"`` (the direction away from the axis through ``axis_point`` along
    ``axis_direction``, at each element: local y radial) or ``"tangential"`` (axis_direction
    x radial: local y tangential, so a stringer along the axis has local z radial, its web's
    depth), and the offset of the beam's axis from its nodes
    (Nastran's WA/WB): a global vector ``offset`` (m) plus ``radial_offset`` (m, away from
    that axis; a frame inside a wall has a negative one). ``rotary``: the sections' bending
    rotary inertia in the consistent mass; ``nsm``: non-structural mass per length (kg/m,
    translational only: equipment or a deck carried by a girder). ``wall``: the shell group the
    members lie on (a wall's frames and stringers, meshes.shells.wall_beams): a thermal strain
    of that wall is theirs too (fem.static.thermal_load, the cryo preload)."""

    material: Material
    section: object
    vref: object = None
    offset: tuple = (0.0, 0.0, 0.0)
    radial_offset: float = 0.0
    axis_point: tuple = (0.0, 0.0, 0.0)
    axis_direction: tuple = (0.0, 0.0, 1.0)
    rotary: bool = True
    nsm: float = 0.0
    wall: str | None = None

    def __post_init__(self) -> None:
        from liftoff.core.beam import Section

        if isinstance(self.section, dict):
            self.section = Section(**self.section)
        if not isinstance(self.section, Section):
            raise InputError(f"beam group: section must be a liftoff.core.beam.Section (got {self.section!r})")
        if not isinstance(self.material, Material):
            self.material = Material(**self.material)
        if isinstance(self.vref, str):
            if self.vref not in ("radial", "tangential"):
                raise InputError(f"beam group: vref must be a 3-vector, 'radial' or 'tangential' (got {self.vref!r})")
        elif self.vref is not None:
            self.vref = _vector("beam group: vref", self.vref, nonzero=True)
        self.offset = _vector("beam group: offset", self.offset)
        self.axis_point = _vector("beam group: axis_point", self.axis_point)
        self.axis_direction = _vector("beam group: axis_direction", self.axis_direction, nonzero=True)
        self.radial_offset = float(self.radial_offset)
        if not math.isfinite(self.radial_offset):
            raise InputError(f"beam group: radial_offset must be finite (got {self.radial_offset!r} m)")
        self.rotary = bool(self.rotary)
        self.nsm = float(self.nsm)
        if not (math.isfinite(self.nsm) and self.nsm >= 0):
            raise InputError(f"beam group: nsm must be >= 0 kg/m (got {self.nsm!r})")
        if self.wall is not None:
            _check_name("beam group: wall", self.wall)

    def to_dict(self) -> dict:
        m, s = self.material, self.section
        return {"material": {"name": m.name, "E": m.E, "nu": m.nu, "rho": m.rho},
                "section": {k: getattr(s, k) for k in ("A", "Iy", "Iz", "J", "Ay", "Az")},
                "vref": self.vref if isinstance(self.vref, str) or self.vref is None else list(self.vref),
                "offset": list(self.offset), "radial_offset": self.radial_offset,
                "axis_point": list(self.axis_point), "axis_direction": list(self.axis_direction),
                "rotary": self.rotary, "nsm": self.nsm, **({"wall": self.wall} if self.wall is not None else {})}


def _vector(what: str, v, nonzero: bool = False) -> tuple:
    try:
        a = np.asarray(v, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        a = np.zeros(0)
    if a.shape != (3,) or not np.all(np.isfinite(a)) or (nonzero and not np.any(a)):
        raise InputError(f"{what} must be 3 finite numbers{' not all zero' if nonzero else ''} (got {v!r})")
    return tuple(float(x) for x in a)


@dataclass
class Geometry:
    """A meshed component: ``.msh`` path, materials per volume group, patches and masses (SI)."""

    name: str
    msh_path: str
    volumes: dict[str, Material]
    patches: list[Patch] = field(default_factory=list)
    point_masses: list[PointMass] = field(default_factory=list)
    smeared_masses: list[SmearedMass] = field(default_factory=list)
    clamped: list[str] = field(default_factory=list)
    group_volumes: dict[str, float] = field(default_factory=dict)  # CAD volumes (m^3)
    mesh_nodes: int = 0
    surface_areas: dict[str, float] = field(default_factory=dict)  # CAD areas of surface groups (m^2)
    shells: dict[str, float] = field(default_factory=dict)         # shell surface group -> thickness (m)
    shell_bending: dict[str, float] = field(default_factory=dict)  # shell surface group -> 12 I / t^3
    liquids: dict[str, Liquid] = field(default_factory=dict)      # liquid volume group -> Liquid
    beams: dict[str, BeamGroup] = field(default_factory=dict)     # beam curve group -> BeamGroup
    curve_lengths: dict[str, float] = field(default_factory=dict)  # CAD lengths of beam curve groups (m)

    def __post_init__(self) -> None:
        self.msh_path = str(self.msh_path)
        if not self.volumes and not self.beams:
            raise InputError(f"geometry {self.name!r}: no volume groups and no beams")
        for g, b in self.beams.items():
            _check_name("beam curve", g)
            if not isinstance(b, BeamGroup):
                raise InputError(f"geometry {self.name!r}: beams[{g!r}] is not a BeamGroup")
            if g in self.volumes or g in self.liquids:
                raise InputError(f"geometry {self.name!r}: {g!r} is both a beam curve and a volume or shell")
        for g, liq in self.liquids.items():
            _check_name("liquid volume", g)
            if not isinstance(liq, Liquid):
                raise InputError(f"geometry {self.name!r}: liquids[{g!r}] is not a Liquid")
            liq.check(f"geometry {self.name!r}: liquid {g!r}")
            if g in self.volumes:
                raise InputError(f"geometry {self.name!r}: {g!r} is both a structural volume and a liquid")
        for g, t in self.shells.items():
            _check_name("shell surface", g)
            require_positive(f"geometry {self.name!r}: shells", **{g: t})
        self.shells = {g: float(t) for g, t in self.shells.items()}
        for g, b in self.shell_bending.items():
            if g not in self.shells:
                raise InputError(f"geometry {self.name!r}: shell_bending names {g!r}, which is not in shells")
            require_positive(f"geometry {self.name!r}: shell_bending", **{g: b})
        self.shell_bending = {g: float(b) for g, b in self.shell_bending.items()}
        for g in self.shells:
            if g not in self.volumes:
                raise InputError(f"geometry {self.name!r}: shell surface {g!r} has no material in volumes")
        names = [p.name for p in self.patches]
        dup = {n for n in names if names.count(n) > 1}
        if dup:
            raise InputError(f"geometry {self.name!r}: duplicate patch names {sorted(dup)}")
        for pm in self.point_masses:
            if pm.patch not in names:
                raise InputError(f"point mass {pm.name!r}: patch {pm.patch!r} not in geometry {self.name!r}")

    def patch(self, name: str) -> Patch:
        """The patch called ``name`` (InputError if absent)."""
        for p in self.patches:
            if p.name == name:
                return p
        raise InputError(f"geometry {self.name!r} has no patch {name!r}")

    def nominal_mass(self) -> float:
        """Sum of rho * CAD volume over volume groups and liquids, rho * thickness * CAD area
        over shell surfaces, rho * A * CAD length over beam curves, + smeared + point masses
        (kg)."""
        missing = [g for g in (*self.volumes, *self.liquids) if g not in self.shells and g not in self.group_volumes]
        missing += [g for g in self.shells if g not in self.surface_areas]
        missing += [g for g in self.beams if g not in self.curve_lengths]
        if missing:
            raise InputError(f"geometry {self.name!r}: no CAD volume/area recorded for groups {missing}")
        structural = sum(m.rho * (self.shells[g] * self.surface_areas[g] if g in self.shells else self.group_volumes[g])
                         for g, m in self.volumes.items())
        liquid = sum(liq.density * self.group_volumes[g] for g, liq in self.liquids.items())
        structural += sum((b.material.rho * b.section.A + b.nsm) * self.curve_lengths[g] for g, b in self.beams.items())
        return structural + liquid + sum(s.mass for s in self.smeared_masses) + sum(p.mass for p in self.point_masses)

    # ---- JSON sidecar ----------------------------------------------------------------
    def to_dict(self, base: Path | None = None) -> dict:
        msh = Path(self.msh_path)
        if base is not None:
            try:
                msh = Path(os.path.relpath(msh.resolve(), base.resolve()))
                if msh.parts and msh.parts[0] == "..":
                    msh = Path(self.msh_path).resolve()
            except ValueError:  # different drive
                msh = Path(self.msh_path).resolve()
        return {
            "format": FORMAT, "version": VERSION, "units": "SI (m, kg, Pa, kg/m^3, kg m^2)",
            "name": self.name, "msh_path": str(msh),
            "volumes": {g: {"name": m.name, "E": m.E, "nu": m.nu, "rho": m.rho} for g, m in self.volumes.items()},
            "patches": [p.to_dict() for p in self.patches],
            "point_masses": [{"name": p.name, "patch": p.patch, "mass": p.mass, "inertia": p.inertia.tolist()}
                             for p in self.point_masses],
            "smeared_masses": [{"surface": s.surface, "mass": s.mass} for s in self.smeared_masses],
            "clamped": list(self.clamped),
            "group_volumes": dict(self.group_volumes),
            "mesh_nodes": int(self.mesh_nodes),
            "surface_areas": dict(self.surface_areas),
            "shells": dict(self.shells),
            "shell_bending": dict(self.shell_bending),
            "liquids": {g: liq.to_dict() for g, liq in self.liquids.items()},
            "beams": {g: b.to_dict() for g, b in self.beams.items()},
            "curve_lengths": dict(self.curve_lengths),
        }

    def save(self, path) -> Path:
        """Write the JSON sidecar atomically (temp file + os.replace); returns the path."""
        path = Path(path)
        return write_text(path, json.dumps(self.to_dict(path.parent), indent=1))

    @classmethod
    def load(cls, path) -> "Geometry":
        """Read a JSON sidecar written by :meth:`save` (``msh_path`` returned absolute)."""
        path = Path(path)
        try:
            d = json.loads(path.read_text())
        except (OSError, json.JSONDecodeError) as e:
            raise InputError(f"cannot read geometry sidecar {path}: {e}") from None
        if not isinstance(d, dict) or d.get("format") != FORMAT:
            raise InputError(f"{path}: not a {FORMAT} file")
        if d.get("version") != VERSION:
            raise InputError(f"{path}: unsupported {FORMAT} version {d.get('version')!r}")
        try:
            msh = Path(d["msh_path"])
            if not msh.is_absolute():
                msh = (path.parent / msh).resolve()
            return cls(
                name=d["name"], msh_path=str(msh),
                volumes={g: Material(**m) for g, m in d["volumes"].items()},
                patches=[Patch.from_dict(p) for p in d["patches"]],
                point_masses=[PointMass(p["name"], p["patch"], p["mass"], np.array(p["inertia"]))
                              for p in d["point_masses"]],
                smeared_masses=[SmearedMass(s["surface"], s["mass"]) for s in d["smeared_masses"]],
                clamped=list(d["clamped"]),
                group_volumes={g: float(v) for g, v in d.get("group_volumes", {}).items()},
                mesh_nodes=int(d.get("mesh_nodes", 0)),
                surface_areas={g: float(v) for g, v in d.get("surface_areas", {}).items()},
                shells={g: float(v) for g, v in d.get("shells", {}).items()},
                shell_bending={g: float(v) for g, v in d.get("shell_bending", {}).items()},
                liquids={g: Liquid(**v) for g, v in d.get("liquids", {}).items()},
                beams={g: BeamGroup(**v) for g, v in d.get("beams", {}).items()},
                curve_lengths={g: float(v) for g, v in d.get("curve_lengths", {}).items()},
            )
        except (KeyError, TypeError) as e:
            raise InputError(f"{path}: malformed {FORMAT} file ({e!r})") from None
