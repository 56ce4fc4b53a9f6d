"""A component as a stick of beams along its axis (``type = "beam"``): any launcher's stage,
booster or payload as the loads engineer's classic beam model, in an FE scenario beside
meshed, Nastran and rigid components (the Shuttle-only ``[model] source = "stick"`` builds
its four components this way from one layout).

The axis runs at ``axis_xy`` through ``stations`` (z, m, increasing); segment i, from
station i to i + 1, is a thin-walled tube of outer ``radius[i]`` and wall ``thickness[i]``
(one value: every segment), material ``E``, ``nu``, ``rho``, its line density
``mass_per_length[i]`` (kg/m: the wall, the smeared propellant and equipment; none given:
rho A). Each segment is cut into elements no longer than ``element_length``: 3-D Timoshenko
beams with rotary inertia (liftoff.core.beam, tube sections with Cowper's shear areas;
``shear = False``: Euler-Bernoulli, neither shear deformation nor rotary inertia).

Named points (the component's CB boundary, where joints, posts, engines and outputs sit):
``points = {name = z}`` on the axis, or ``{name = [x, y, z]}`` off it, joined to the axis
node at its z by a link (:data:`LINK`: a stiff steel fitting, as the Shuttle stick's skirts
and attach fittings; a rigid link would make several points at one station dependent, and
a post or joint needs each point's own DOFs). ``masses = {point = [kg, Ixx, Iyy, Izz]}``:
lumped masses (kg, kg m^2 about the point) at named points. SI units throughout.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from liftoff.core.beam import Section, assemble_frame, beam_element, tube
from liftoff.core.elastic import check_elastic
from liftoff.core.errors import InputError, ResourceError

from .component import Component
from .models import line_component

#: the link from the axis to an off-axis point: a stiff steel fitting (E Pa, section m^2/m^4,
#: line density kg/m), also the Shuttle stick's skirts and attach fittings (workflows/stick.py)
LINK = dict(E=2.0e11, A=0.5, I=0.05, mass_per_length=500.0)


@dataclass
class BeamStick:
    """A stick of beams (module docstring); every length in m, mass in kg, modulus in Pa."""

    name: str = "stick"
    axis_xy: tuple = (0.0, 0.0)
    stations: tuple = (0.0, 10.0)
    radius: tuple = (1.0,)
    thickness: tuple = (0.01,)
    mass_per_length: tuple = ()
    E: float = 70e9
    nu: float = 0.33
    rho: float = 2800.0
    shear: bool = True
    points: dict = field(default_factory=dict)
    masses: dict = field(default_factory=dict)
    element_length: float = 1.0
    max_elements: int = 2_000

    @property
    def n_segments(self) -> int:
        return len(self.stations) - 1

    def per_segment(self, key: str) -> np.ndarray:
        v = np.asarray(getattr(self, key), dtype=float).reshape(-1)
        return np.full(self.n_segments, v[0]) if v.size == 1 else v

    def check(self) -> None:
        o = f"BeamStick({self.name})"
        z = np.asarray(self.stations, dtype=float)
        if z.ndim != 1 or z.size < 2 or not np.all(np.isfinite(z)) or np.any(np.diff(z) <= 0):
            raise InputError(f"{o}.stations: at least two z (m), strictly increasing")
        for key in ("radius", "thickness", "mass_per_length"):
            v = np.asarray(getattr(self, key), dtype=float).reshape(-1)
            if key == "mass_per_length" and v.size == 0:
                continue
            if v.size not in (1, self.n_segments):
                raise InputError(f"{o}.{key}: one value or one per segment ({self.n_segments}), got {v.size}")
            if not (np.all(np.isfinite(v)) and np.all(v > 0)):
                raise InputError(f"{o}.{key}: every value must be > 0")
        if np.any(self.per_segment("thickness") > self.per_segment("radius")):
            raise InputError(f"{o}.thickness: a wall thicker than its radius")
        self.E, self.nu, self.rho = check_elastic(o, self.E, self.nu, self.rho)
        if not (math.isfinite(self.element_length) and self.element_length > 0):
            raise InputError(f"{o}.element_length must be > 0 m (got {self.element_length!r})")
        if not self.points:
            raise InputError(f"{o}.points: none: a stick needs named points to join or hold it")
        for n, p in self.points.items():
            if np.size(p) not in (1, 3) or not np.all(np.isfinite(p)):
                raise InputError(f"{o}.points.{n}: a z (on the axis) or [x, y, z] (m)")
            zp = float(np.asarray(p, dtype=float).reshape(-1)[-1])
            if not z[0] <= zp <= z[-1]:
                raise InputError(f"{o}.points.{n}: z = {zp:g} m is off the stick ({z[0]:g} .. {z[-1]:g} m)")
        for n, m in self.masses.items():
            m = np.asarray(m, dtype=float).reshape(-1)
            if n not in self.points:
                raise InputError(f"{o}.masses.{n}: not one of the points ({', '.join(self.points)})")
            if m.size != 4 or not np.all(np.isfinite(m)) or m[0] <= 0 or np.any(m[1:] < 0):
                raise InputError(f"{o}.masses.{n}: [kg > 0, Ixx, Iyy, Izz >= 0 kg m^2]")
        n_el = sum(max(1, math.ceil(L / self.element_length)) for L in np.diff(z))
        if n_el > self.max_elements:
            raise ResourceError(f"{o}: element length {self.element_length:g} m gives {n_el} beams, beyond the "
                                f"limit of {self.max_elements}; use a larger mesh_size")

    def sections(self) -> list[Section]:
        """Each segment's tube section."""
        ts = self.per_segment("thickness")
        out = [tube(r, t, self.nu) for r, t in zip(self.per_segment("radius"), ts)]
        return out if self.shear else [dataclasses.replace(s, Ay=None, Az=None) for s in out]

    def line_density(self) -> np.ndarray:
        """kg/m of each segment: mass_per_length, or rho A."""
        if len(self.mass_per_length):
            return self.per_segment("mass_per_length")
        return self.rho * np.array([s.A for s in self.sections()])

    def mass(self) -> float:
        """The segments' and the lumped masses (kg), without the links to off-axis points, which
        the model has too (LINK's line density times each link's length: a user's stick with
        three points 2 m off its axis weighs 3 t more than this)."""
        return float(self.line_density() @ np.diff(np.asarray(self.stations, float))
                     + sum(float(np.asarray(m).reshape(-1)[0]) for m in self.masses.values()))


def beam_stick_component(p: BeamStick, name: str | None = None) -> tuple[Component, dict]:
    """The stick's Component (every node 6 DOFs; named points labelled by name, the others
    ``<name>_n<k>``) and its {volume: unit thermal load} (none: a stick has no volumes)."""
    p.check()
    name = name or p.name
    x0, y0 = (float(v) for v in p.axis_xy)
    zs = set(np.asarray(p.stations, float).round(9))
    for za, zb in zip(p.stations[:-1], p.stations[1:]):
        n = max(1, math.ceil((zb - za) / p.element_length))
        zs |= set(np.linspace(za, zb, n + 1).round(9))
    on_axis = {n: float(np.asarray(v).reshape(-1)[-1]) for n, v in p.points.items()}
    zs |= {round(z, 9) for z in on_axis.values()}
    zs = np.array(sorted(zs))
    coords = [np.array([x0, y0, z]) for z in zs]
    names = [f"{name}_n{k}" for k in range(len(zs))]
    for n, v in p.points.items():                 # an on-axis point names its node
        if np.size(v) == 1:
            k = int(np.argmin(np.abs(zs - on_axis[n])))
            if names[k] != f"{name}_n{k}":
                raise InputError(f"BeamStick({name}).points.{n}: the axis node at z = {zs[k]:g} m is "
                                 f"already {names[k]!r}")
            names[k] = n
    seg = np.searchsorted(np.asarray(p.stations, float), 0.5 * (zs[:-1] + zs[1:])) - 1
    sections, rho_line, G = p.sections(), p.line_density(), p.E / (2 * (1 + p.nu))
    elems = [(k, k + 1, p.E, G, sections[s], rho_line[s] / sections[s].A) for k, s in enumerate(seg)]
    link_sec = Section(LINK["A"], LINK["I"], LINK["I"], 2 * LINK["I"])
    for n, v in p.points.items():                 # an off-axis point: a link from the axis node at its z
        if np.size(v) == 3:
            k = int(np.argmin(np.abs(zs - on_axis[n])))
            coords.append(np.asarray(v, float))
            names.append(n)
            if np.linalg.norm(coords[-1] - coords[k]) == 0:
                raise InputError(f"BeamStick({name}).points.{n}: on the axis; give its z alone")
            elems.append((k, len(coords) - 1, LINK["E"], LINK["E"] / 2.6, link_sec, LINK["mass_per_length"] / LINK["A"]))
    X = np.array(coords)
    ndof = 6 * len(X)

    def element(a, b, E, G_, sec, rho):
        d = X[b] - X[a]
        vref = (1.0, 0.0, 0.0) if abs(d[2]) < 0.9 * np.linalg.norm(d) else (0.0, 1.0, 0.0)
        return (a, b, *beam_element(X[a], X[b], E, G_, sec, rho, vref, rotary=p.shear))

    K, M = assemble_frame(len(X), (element(*e) for e in elems))
    lumped = np.zeros(ndof)
    for n, m in p.masses.items():
        i = names.index(n)
        m = np.asarray(m, float).reshape(-1)
        lumped[6 * i:6 * i + 3] += m[0]
        lumped[6 * i + 3:6 * i + 6] += m[1:]
    M = M + sp.diags(lumped)
    return line_component(name, X, names, K, M, [[a, b] for a, b, *_ in elems]), {}


__all__ = ["BeamStick", "LINK", "beam_stick_component"]
