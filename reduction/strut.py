"""A component that is one straight member between two named points (``type = "strut"``):
an attach strut, a thrust beam, a truss member joining two other components, as the
3-D Timoshenko beams of liftoff.core.beam (numpy only; reduced by the CB stage like any
component, its two end points its boundary).

``ends = {name = [x, y, z], other = [x, y, z]}`` (m): the two end points, named as the
joints the strut shares with the components it links (each end's six DOFs are the joint's);
``section``: a liftoff.core.beam.Section or a standard shape's table (``{shape = "tube",
r_out = ..., t = ...}``, liftoff.core.beam.standard_section); material ``E`` (Pa), ``nu``,
``rho`` (kg/m^3); ``elements`` along it; ``vref``: the section's orientation vector (local
y towards it; default: whichever global axis is most normal to the strut); ``pins``: the
pin flags of its two ends (Nastran CBAR's PA, PB: digits 4-6, the local rotations released,
liftoff.core.beam.release), e.g. ``["456", "56"]`` for a pin-ended (clevis) strut, a
two-force member whose ends pass no moment; default none (both ends take moments). SI units.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from liftoff.core.beam import Section, assemble_frame, beam_element, check_pins, standard_section
from liftoff.core.elastic import check_elastic
from liftoff.core.errors import InputError

from .component import Component
from .models import line_component


@dataclass
class Strut:
    """One straight member (module docstring); lengths in m, modulus in Pa, density kg/m^3."""

    name: str = "strut"
    ends: dict = field(default_factory=dict)
    section: object = field(default_factory=dict)
    E: float = 200e9
    nu: float = 0.3
    rho: float = 7850.0
    elements: int = 4
    vref: tuple = ()
    pins: tuple = ("", "")

    def check(self) -> None:
        o = f"Strut({self.name})"
        if len(self.ends) != 2:
            raise InputError(f"{o}.ends: give exactly two named end points (got {len(self.ends)})")
        a, b = (np.asarray(v, float).reshape(-1) for v in self.ends.values())
        if a.shape != (3,) or b.shape != (3,) or not (np.all(np.isfinite(a)) and np.all(np.isfinite(b))):
            raise InputError(f"{o}.ends: each end is [x, y, z] in m")
        if not np.linalg.norm(b - a) > 0:
            raise InputError(f"{o}.ends: its two ends coincide at {a.tolist()} m")
        self.E, self.nu, self.rho = check_elastic(o, self.E, self.nu, self.rho)
        if isinstance(self.elements, bool) or int(self.elements) != self.elements or not self.elements >= 1:
            raise InputError(f"{o}.elements must be a whole number >= 1 (got {self.elements!r})")
        self.section_of()
        check_pins(tuple(self.pins), f"{o}.pins")
        if len(self.vref) and (np.shape(self.vref) != (3,) or
                               np.linalg.norm(np.cross(b - a, np.asarray(self.vref, float))) == 0):
            raise InputError(f"{o}.vref must be 3 numbers not along the strut (got {list(self.vref)})")

    def section_of(self) -> Section:
        """The section: a Section as given, or a standard shape's (its table)."""
        if isinstance(self.section, Section):
            return self.section
        return standard_section(self.section, f"Strut({self.name}).section")[0]


def strut_component(p: Strut, name: str | None = None) -> tuple[Component, dict]:
    """The strut's Component: ``elements`` beams between its ends (named by ``ends``; the
    nodes between ``<name>_n<k>``), every node six labelled DOFs; no thermal loads."""
    p.check()
    name = name or p.name
    (na, a), (nb, b) = ((n, np.asarray(v, float)) for n, v in p.ends.items())
    n = int(p.elements)
    X = a + np.linspace(0.0, 1.0, n + 1)[:, None] * (b - a)
    names = [na] + [f"{name}_n{k}" for k in range(1, n)] + [nb]
    d = (b - a) / np.linalg.norm(b - a)
    vref = np.asarray(p.vref, float) if len(p.vref) else np.eye(3)[int(np.argmin(np.abs(d)))]
    sec, G = p.section_of(), p.E / (2 * (1 + p.nu))
    pa, pb = check_pins(tuple(p.pins), f"Strut({name}).pins")
    K, M = assemble_frame(n + 1, ((k, k + 1, *beam_element(X[k], X[k + 1], p.E, G, sec, p.rho, vref,
                                                             pins=(pa if k == 0 else "", pb if k == n - 1 else "")))
                                  for k in range(n)))
    return line_component(name, X, names, K, M, np.column_stack([np.arange(n), np.arange(1, n + 1)])), {}


__all__ = ["Strut", "strut_component"]
