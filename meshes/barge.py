"""Barge, cargo and dock: the reference's other problem (Prabhakar & Palermo, section 5,
figures 7-9: an external-tank barge hitting a dock at Vandenberg).

Frame: x along the barge (bow at x = +length/2, facing the dock), y across, z up, keel at
z = 0. Units SI (m, kg, Pa).

* :class:`BargeParams`, :func:`build_barge`: a box hull of plates: deck, bottom, two sides,
  two end plates (stern, bow) and transverse bulkheads, with a transporter cradle (two
  saddles) on the deck. Plates are thickened solids of thickness ``wall`` with an
  *equivalent* material per plate group: rho_eq = rho t f / wall and E_eq = E t f / wall
  (t the real plate thickness, f the framing factor: stiffeners and frames not modelled),
  so membrane stiffness, mass and the in-plane wave speed sqrt(E/rho) of the real hull are
  kept; plate bending is too stiff (as for the tank walls, docs/meshes.md). Ballast and
  outfit are non-structural mass on the inner bottom. Named points (patches): the two
  cargo interfaces ``cargo_<k>`` (saddle tops), the fender contact points on the bow
  ``bow_<k>``, deck response stations ``deck_<k>`` (figure 7's response locations) and
  ``stern`` (where a wave force may act).
* :class:`CargoParams`, :func:`build_cargo`: an external-tank-like cylinder lying along x
  (thick wall, flat ends, empty), on the cradle: patches ``cargo_<k>`` on its bottom at the
  saddles, with the same reference points as the barge's (the assembly overlays them).
* :class:`DockParams`, :func:`build_dock`: a quay deck on square piles clamped at the
  seabed, with fender blocks on its face (patches ``fender_<k>`` at the bow points). Its
  stiffness is set by the piles (size, wall, length, count) and the deck; the rubber
  fender itself is the contact spring of the scenario.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from liftoff.core.errors import InputError

from . import _occ
from ._occ import Tool, occ
from .spec import Geometry, Material, Patch, SmearedMass, equivalent, require_positive

STEEL = Material("steel", 210e9, 0.3, 7850.0)
AL2219 = Material("Al2219", 73.8e9, 0.33, 2840.0)
CONCRETE = Material("concrete", 30e9, 0.2, 2400.0)


# ------------------------------------------------------------------ barge
@dataclass
class BargeParams:
    """Barge hull, cradle and named points (SI). Plate thicknesses are the real ones (m);
    ``wall`` is the modelled (thickened) thickness of every plate."""

    length: float = 80.0
    beam: float = 16.0
    depth: float = 4.5
    deck_thickness: float = 0.014
    bottom_thickness: float = 0.016
    side_thickness: float = 0.014
    bulkhead_thickness: float = 0.010
    n_bulkheads: int = 5
    framing_factor: float = 1.4        # stiffeners and frames, not modelled: mass and stiffness factor
    wall: float = 0.35
    ballast_mass: float = 900e3        # kg, non-structural on the inner bottom (ballast, outfit)
    saddle_x: tuple = (-12.0, 12.0)    # cradle saddles (cargo interfaces) along x, on the centreline
    saddle_size: tuple = field(default=(2.0, 5.0, 1.5), metadata={"length": 3})   # length x, width y, height z
    cradle_mass: float = 40e3          # transporter, kg, spread over the saddles' volume
    fender_yz: tuple = ((-4.0, 2.25), (4.0, 2.25))  # bow contact points on the bow plate (y, z)
    fender_patch: float = 1.5          # side of the square bow patches (m)
    n_stations: int = 9                # deck response stations, stern to bow, at y = station_y
    station_y: float = 6.0
    mesh_size: float = 2.0

    name = "barge"

    def check(self) -> None:
        o = "BargeParams"
        require_positive(o, length=self.length, beam=self.beam, depth=self.depth,
                         deck_thickness=self.deck_thickness, bottom_thickness=self.bottom_thickness,
                         side_thickness=self.side_thickness, bulkhead_thickness=self.bulkhead_thickness,
                         framing_factor=self.framing_factor, wall=self.wall, ballast_mass=self.ballast_mass,
                         cradle_mass=self.cradle_mass, fender_patch=self.fender_patch, mesh_size=self.mesh_size)
        if int(self.n_bulkheads) != self.n_bulkheads or self.n_bulkheads < 0:
            raise InputError(f"{o}.n_bulkheads must be an integer >= 0 (got {self.n_bulkheads!r})")
        if int(self.n_stations) != self.n_stations or self.n_stations < 2:
            raise InputError(f"{o}.n_stations must be an integer >= 2 (got {self.n_stations!r})")
        if not 3 * self.wall < min(self.depth, self.beam, self.length / (self.n_bulkheads + 1)):
            raise InputError(f"{o}.wall = {self.wall} m is too thick for the hull's depth, beam and bulkhead spacing")
        for k, (y, z) in enumerate(self.fender_yz):
            h = self.fender_patch / 2
            if not (-self.beam / 2 + self.wall < y - h and y + h < self.beam / 2 - self.wall
                    and self.wall < z - h and z + h < self.depth - self.wall):
                raise InputError(f"{o}.fender_yz[{k}] = ({y}, {z}): the bow patch is off the bow plate")
        if len(self.saddle_size) != 3 or min(self.saddle_size) <= 0:
            raise InputError(f"{o}.saddle_size must be 3 lengths > 0 (x, y, z)")
        sx, sy, _ = self.saddle_size
        for k, x in enumerate(self.saddle_x):
            if not -self.length / 2 < x - sx / 2 < x + sx / 2 < self.length / 2:
                raise InputError(f"{o}.saddle_x[{k}] = {x}: the saddle is off the deck")
        if not sy / 2 + 1.0 < abs(self.station_y) < self.beam / 2 - 0.5:
            raise InputError(f"{o}.station_y = {self.station_y}: stations must clear the cradle and the side")

    # named points ------------------------------------------------------------------
    def cargo_points(self) -> dict[str, np.ndarray]:
        """Saddle tops: the cargo interface points ``cargo_<k>``."""
        z = self.depth + self.saddle_size[2]
        return {f"cargo_{k + 1}": np.array([x, 0.0, z]) for k, x in enumerate(self.saddle_x)}

    def bow_points(self) -> dict[str, np.ndarray]:
        """Fender contact points ``bow_<k>`` on the bow plate's outer face."""
        return {f"bow_{k + 1}": np.array([self.length / 2, y, z]) for k, (y, z) in enumerate(self.fender_yz)}

    def station_points(self) -> dict[str, np.ndarray]:
        """Deck response stations ``deck_<k>`` from stern (1) to bow, 4 m in from the ends."""
        xs = np.linspace(-self.length / 2 + 4.0, self.length / 2 - 4.0, int(self.n_stations))
        return {f"deck_{k + 1}": np.array([x, self.station_y, self.depth]) for k, x in enumerate(xs)}

    def stern_point(self) -> np.ndarray:
        return np.array([-self.length / 2, 0.0, self.depth / 2])

    def bulkhead_x(self) -> np.ndarray:
        n = int(self.n_bulkheads)
        return -self.length / 2 + self.length * np.arange(1, n + 1) / (n + 1)

    def plate_material(self, group: str, t: float) -> Material:
        return Material(f"{group}-equivalent", STEEL.E * t * self.framing_factor / self.wall, STEEL.nu,
                        STEEL.rho * t * self.framing_factor / self.wall)


def barge_closed_form_volumes(p: BargeParams) -> dict[str, float]:
    """CAD volume (m^3) of each volume group, from the plate layout of :func:`build_barge`."""
    L, B, D, w = p.length, p.beam, p.depth, p.wall
    inner = (B - 2 * w) * (D - 2 * w) * w
    sx, sy, sz = p.saddle_size
    return {"barge_deck": L * B * w, "barge_bottom": L * B * w, "barge_sides": 2 * L * (D - 2 * w) * w,
            "barge_ends": 2 * inner, "barge_bulkheads": int(p.n_bulkheads) * inner,
            "barge_cradle": len(p.saddle_x) * sx * sy * sz}


def hull_axial_stiffness(p: BargeParams) -> float:
    """EA (N) of the hull girder in x: deck, bottom and sides with their equivalent moduli."""
    B, D, w = p.beam, p.depth, p.wall
    E = {g: p.plate_material(g, t).E for g, t in (("deck", p.deck_thickness), ("bottom", p.bottom_thickness),
                                                  ("sides", p.side_thickness))}
    return E["deck"] * B * w + E["bottom"] * B * w + E["sides"] * 2 * (D - 2 * w) * w


def _hull_boxes(p: BargeParams) -> dict[str, list]:
    """The plate solids of the hull and the saddles, touching face to face (made conforming later)."""
    L, B, D, w = p.length, p.beam, p.depth, p.wall
    box = lambda x0, y0, z0, dx, dy, dz: (3, occ.addBox(x0, y0, z0, dx, dy, dz))  # noqa: E731
    inner = (B - 2 * w, D - 2 * w)
    groups = {"barge_deck": [box(-L / 2, -B / 2, D - w, L, B, w)],
              "barge_bottom": [box(-L / 2, -B / 2, 0.0, L, B, w)],
              "barge_sides": [box(-L / 2, -B / 2, w, L, w, D - 2 * w), box(-L / 2, B / 2 - w, w, L, w, D - 2 * w)],
              "barge_ends": [box(-L / 2, -B / 2 + w, w, w, *inner), box(L / 2 - w, -B / 2 + w, w, w, *inner)],
              "barge_bulkheads": [box(x - w / 2, -B / 2 + w, w, w, *inner) for x in p.bulkhead_x()]}
    sx, sy, sz = p.saddle_size
    groups["barge_cradle"] = [box(x - sx / 2, -sy / 2, D, sx, sy, sz) for x in p.saddle_x]
    return {g: ds for g, ds in groups.items() if ds}


def _barge_tools(p: BargeParams) -> list[Tool]:
    """Tool boxes imprinting the bow, deck-station and stern patches (cut half into the wall)."""
    tools = []
    w, h = p.wall, p.fender_patch / 2

    def tool(name, lo, hi):
        b = occ.addBox(*lo, *(np.asarray(hi) - np.asarray(lo)))
        tools.append(Tool(name, (3, b), occ.getBoundingBox(3, b)))

    for name, pt in p.bow_points().items():
        tool(name, (pt[0] - w / 2, pt[1] - h, pt[2] - h), (pt[0] + 1.0, pt[1] + h, pt[2] + h))
    for name, pt in p.station_points().items():
        tool(name, (pt[0] - 0.4, pt[1] - 0.4, pt[2] - w / 2), (pt[0] + 0.4, pt[1] + 0.4, pt[2] + 1.0))
    s = p.stern_point()
    tool("stern", (s[0] - 1.0, s[1] - h, s[2] - h), (s[0] + w / 2, s[1] + h, s[2] + h))
    return tools


def build_barge(p: BargeParams, out_dir) -> Geometry:
    """Barge hull with its cradle: volumes barge_deck, _bottom, _sides, _ends, _bulkheads,
    _cradle; patches cargo_<k>, bow_<k>, deck_<k>, stern; ballast smeared on the surface
    group ``barge_bottom_inner``."""
    if not isinstance(p, BargeParams):
        raise InputError(f"build_barge expects BargeParams, got {type(p).__name__}")
    p.check()
    out_dir = Path(out_dir)
    with _occ.gmsh_session(p.name):
        groups = _hull_boxes(p)
        tools = _barge_tools(p)
        groups = _occ.imprint(groups, tools)
        allv = [d for ds in groups.values() for d in ds]
        bfaces = _occ.boundary_faces(allv)
        patches = _patches(p, tools, bfaces)
        w, tol = p.wall, 1e-3
        inner = _occ.faces_inside(bfaces, (-p.length / 2 + w - tol, -p.beam / 2 + w - tol, w - tol,
                                           p.length / 2 - w + tol, p.beam / 2 - w + tol, w + tol))
        _occ.add_physical(2, "barge_bottom_inner", inner)
        for g, ds in groups.items():
            _occ.add_physical(3, g, [tg for _, tg in ds])
        vols = {g: _occ.group_volume(ds) for g, ds in groups.items()}
        areas = _occ.physical_measures(2)
        n_nodes = _occ.mesh_and_write(out_dir / f"{p.name}.msh", p.mesh_size)
    thick = {"barge_deck": p.deck_thickness, "barge_bottom": p.bottom_thickness, "barge_sides": p.side_thickness,
             "barge_ends": p.side_thickness, "barge_bulkheads": p.bulkhead_thickness}
    mats = {g: p.plate_material(g, t) for g, t in thick.items() if g in vols}
    mats["barge_cradle"] = equivalent(STEEL, p.cradle_mass, vols["barge_cradle"], "cradle-equivalent")
    geo = Geometry(p.name, str(out_dir / f"{p.name}.msh"), mats, patches, [],
                   [SmearedMass("barge_bottom_inner", p.ballast_mass)], [], vols, n_nodes, areas)
    geo.save(out_dir / f"{p.name}.json")
    return geo


def _patches(p: BargeParams, tools: list[Tool], bfaces: list[int]) -> list[Patch]:
    """Physical surface groups and reference points of every named point of the barge."""
    out = []
    for t in tools:
        _occ.add_physical(2, t.name, _occ.faces_inside(bfaces, t.bbox))
    refs = {**p.bow_points(), **p.station_points(), "stern": p.stern_point()}
    out += [Patch(t.name, refs[t.name]) for t in tools]
    sx, sy, sz = p.saddle_size
    for name, pt in p.cargo_points().items():
        faces = _occ.faces_inside(bfaces, (pt[0] - sx / 2, -sy / 2, pt[2] - 1e-3, pt[0] + sx / 2, sy / 2, pt[2] + 1e-3))
        _occ.add_physical(2, name, faces)
        out.append(Patch(name, pt))
    return out


# ------------------------------------------------------------------ cargo
@dataclass
class CargoParams:
    """An empty external-tank-like cylinder on the barge's cradle (SI): axis along x at the
    height where it rests on the saddle tops; ``dry_mass`` sets the wall's equivalent
    density (E/rho of Al 2219 kept)."""

    length: float = 40.0
    radius: float = 4.2
    wall: float = 0.3
    dry_mass: float = 30e3
    x_center: float = 0.0
    saddle_x: tuple = (-12.0, 12.0)     # must equal the barge's cradle
    saddle_top_z: float = 6.0           # barge depth + saddle height
    pad_size: float = 1.6               # side of the interface patches on the tank bottom
    mesh_size: float = 1.6

    name = "cargo"

    def check(self) -> None:
        o = "CargoParams"
        require_positive(o, length=self.length, radius=self.radius, wall=self.wall, dry_mass=self.dry_mass,
                         pad_size=self.pad_size, mesh_size=self.mesh_size)
        if not 3 * self.wall < self.radius:
            raise InputError(f"{o}.wall = {self.wall} m is too thick for radius {self.radius} m")
        for k, x in enumerate(self.saddle_x):
            if not abs(x - self.x_center) + self.pad_size < self.length / 2:
                raise InputError(f"{o}.saddle_x[{k}] = {x}: the saddle is beyond the tank's ends")

    def axis_z(self) -> float:
        return self.saddle_top_z + self.radius

    def interface_points(self) -> dict[str, np.ndarray]:
        return {f"cargo_{k + 1}": np.array([x, 0.0, self.saddle_top_z]) for k, x in enumerate(self.saddle_x)}


def build_cargo(p: CargoParams, out_dir) -> Geometry:
    """Cargo tank: volume ``cargo_wall``; patches ``cargo_<k>`` on its bottom over the saddles."""
    if not isinstance(p, CargoParams):
        raise InputError(f"build_cargo expects CargoParams, got {type(p).__name__}")
    p.check()
    out_dir = Path(out_dir)
    R, w, L, zc = p.radius, p.wall, p.length, p.axis_z()
    x0 = p.x_center - L / 2
    with _occ.gmsh_session(p.name):
        outer = occ.addCylinder(x0, 0.0, zc, L, 0.0, 0.0, R)
        inner = occ.addCylinder(x0 + w, 0.0, zc, L - 2 * w, 0.0, 0.0, R - w)
        shell, _ = occ.cut([(3, outer)], [(3, inner)])
        h = p.pad_size / 2
        tools = []
        for name, pt in p.interface_points().items():
            b = occ.addBox(pt[0] - h, -h, pt[2] - 1.0, 2 * h, 2 * h, 1.0 + w / 2)
            tools.append(Tool(name, (3, b), occ.getBoundingBox(3, b)))
        groups = _occ.imprint({"cargo_wall": shell}, tools)
        bfaces = _occ.boundary_faces(groups["cargo_wall"])
        patches = []
        for t in tools:
            _occ.add_physical(2, t.name, _occ.faces_inside(bfaces, t.bbox))
            patches.append(Patch(t.name, p.interface_points()[t.name]))
        _occ.add_physical(3, "cargo_wall", [tg for _, tg in groups["cargo_wall"]])
        vols = {"cargo_wall": _occ.group_volume(groups["cargo_wall"])}
        areas = _occ.physical_measures(2)
        n_nodes = _occ.mesh_and_write(out_dir / f"{p.name}.msh", p.mesh_size,
                                      curvature_n=_occ.curvature_elements(w, R))
    mat = equivalent(AL2219, p.dry_mass, vols["cargo_wall"], "cargo-wall-equivalent")
    geo = Geometry(p.name, str(out_dir / f"{p.name}.msh"), {"cargo_wall": mat}, patches, [], [], [], vols,
                   n_nodes, areas)
    geo.save(out_dir / f"{p.name}.json")
    return geo


# ------------------------------------------------------------------ dock
@dataclass
class DockParams:
    """A pile-supported quay (SI): a deck (``deck_size`` x, y, z; top at ``deck_top``) whose
    face is at x = ``face_x``, on ``pile_grid`` square hollow steel piles (side ``pile_size``,
    wall ``pile_wall``, smeared into solid boxes) from the deck's underside down to the
    seabed at ``seabed_z``, clamped there; fender blocks (``fender_size``: depth x, width
    y, height z) on the face at ``fender_yz``, each carrying a contact point ``fender_<k>``
    on its front face (x = face_x - fender depth = the barge's bow)."""

    face_x: float = 40.6
    deck_size: tuple = field(default=(12.0, 30.0, 4.5), metadata={"length": 3})
    deck_top: float = 5.0
    pile_grid: tuple = field(default=(3, 5), metadata={"length": 2})
    pile_size: float = 2.4
    pile_wall: float = 0.08
    seabed_z: float = -6.0
    fender_size: tuple = field(default=(0.6, 2.0, 2.0), metadata={"length": 3})
    fender_yz: tuple = ((-4.0, 2.25), (4.0, 2.25))
    mesh_size: float = 2.0

    name = "dock"

    def check(self) -> None:
        o = "DockParams"
        require_positive(o, pile_size=self.pile_size, pile_wall=self.pile_wall, mesh_size=self.mesh_size)
        if len(self.deck_size) != 3 or min(self.deck_size) <= 0 or len(self.fender_size) != 3 \
                or min(self.fender_size) <= 0:
            raise InputError(f"{o}: deck_size and fender_size must be 3 lengths > 0 (x, y, z)")
        nx, ny = self.pile_grid
        if int(nx) != nx or int(ny) != ny or nx < 1 or ny < 1:
            raise InputError(f"{o}.pile_grid must be two integers >= 1")
        if self.pile_wall >= self.pile_size / 2:
            raise InputError(f"{o}.pile_wall must be < pile_size / 2")
        z_under = self.deck_top - self.deck_size[2]
        if not self.seabed_z < z_under - self.pile_size:
            raise InputError(f"{o}.seabed_z = {self.seabed_z}: the piles would be shorter than their width")
        fy, fz = self.fender_size[1] / 2, self.fender_size[2] / 2
        for k, (y, z) in enumerate(self.fender_yz):
            if not (abs(y) + fy < self.deck_size[1] / 2 and z_under < z - fz and z + fz < self.deck_top):
                raise InputError(f"{o}.fender_yz[{k}] = ({y}, {z}): the fender is off the quay's face")

    def fender_points(self) -> dict[str, np.ndarray]:
        x = self.face_x - self.fender_size[0]
        return {f"fender_{k + 1}": np.array([x, y, z]) for k, (y, z) in enumerate(self.fender_yz)}

    def pile_xy(self) -> list[tuple[float, float]]:
        nx, ny = (int(v) for v in self.pile_grid)
        dx, dy = self.deck_size[0], self.deck_size[1]
        xs = self.face_x + dx * (np.arange(nx) + 0.5) / nx
        ys = -dy / 2 + dy * (np.arange(ny) + 0.5) / ny
        return [(float(x), float(y)) for x in xs for y in ys]


def build_dock(p: DockParams, out_dir) -> Geometry:
    """Dock: volumes dock_deck, dock_piles, dock_fenders; patches fender_<k>; clamped pile bases."""
    if not isinstance(p, DockParams):
        raise InputError(f"build_dock expects DockParams, got {type(p).__name__}")
    p.check()
    out_dir = Path(out_dir)
    (dx, dy, dz), (fx, fy, fz), s = p.deck_size, p.fender_size, p.pile_size
    z_under = p.deck_top - dz
    with _occ.gmsh_session(p.name):
        deck = [(3, occ.addBox(p.face_x, -dy / 2, z_under, dx, dy, dz))]
        piles = [(3, occ.addBox(x - s / 2, y - s / 2, p.seabed_z, s, s, z_under - p.seabed_z)) for x, y in p.pile_xy()]
        fenders = [(3, occ.addBox(p.face_x - fx, y - fy / 2, z - fz / 2, fx, fy, fz)) for y, z in p.fender_yz]
        groups = _occ.imprint({"dock_deck": deck, "dock_piles": piles, "dock_fenders": fenders}, [])
        bfaces = _occ.boundary_faces([d for ds in groups.values() for d in ds])
        patches, clamped, tol = [], [], 1e-3
        for (name, pt), (y, z) in zip(p.fender_points().items(), p.fender_yz):
            faces = _occ.faces_inside(bfaces, (pt[0] - tol, y - fy / 2, z - fz / 2, pt[0] + tol, y + fy / 2, z + fz / 2))
            _occ.add_physical(2, name, faces)
            patches.append(Patch(name, pt))
        for k, (x, y) in enumerate(p.pile_xy()):
            faces = _occ.faces_inside(bfaces, (x - s / 2, y - s / 2, p.seabed_z - tol, x + s / 2, y + s / 2,
                                               p.seabed_z + tol))
            _occ.add_physical(2, f"dock_pile_{k + 1}_base", faces)
            clamped.append(f"dock_pile_{k + 1}_base")
        for g, ds in groups.items():
            _occ.add_physical(3, g, [tg for _, tg in ds])
        vols = {g: _occ.group_volume(ds) for g, ds in groups.items()}
        areas = _occ.physical_measures(2)
        n_nodes = _occ.mesh_and_write(out_dir / f"{p.name}.msh", p.mesh_size)
    fill = 1 - (1 - 2 * p.pile_wall / s) ** 2
    mats = {"dock_deck": CONCRETE, "dock_fenders": CONCRETE,
            "dock_piles": Material("steel-pile-equivalent", STEEL.E * fill, STEEL.nu, STEEL.rho * fill)}
    geo = Geometry(p.name, str(out_dir / f"{p.name}.msh"), mats, patches, [], [], clamped, vols, n_nodes, areas)
    geo.save(out_dir / f"{p.name}.json")
    return geo


def pile_stiffness(p: DockParams) -> float:
    """Closed-form lateral (x) stiffness of the pile group, N/m: each pile a fixed-guided
    column 12 E I / L^3 (deck rigid, in rotation and in plane), hollow square section."""
    s, t = p.pile_size, p.pile_wall
    I = (s ** 4 - (s - 2 * t) ** 4) / 12
    L = p.deck_top - p.deck_size[2] - p.seabed_z
    return len(p.pile_xy()) * 12 * STEEL.E * I / L ** 3


def default_positions(barge: BargeParams, gap_free: float = 0.0) -> dict:
    """Dock and cargo parameters that fit a barge: fender points facing the bow points, the
    cargo's saddles on the cradle. (``gap_free`` is a geometric gap, m; the contact gap is
    the scenario's.)"""
    fx = DockParams().fender_size[0]
    return {"dock": {"face_x": barge.length / 2 + fx + gap_free, "fender_yz": tuple(barge.fender_yz)},
            "cargo": {"saddle_x": tuple(barge.saddle_x), "saddle_top_z": barge.depth + barge.saddle_size[2]}}

