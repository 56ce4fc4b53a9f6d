"""A component that is one straight member between two named points (``type = "strut"``):
an attach strut, a thrust beam, a truss member joining two other components, as the
3-D Timoshenko beams of liftoff.core.beam (numpy only; reduced by the CB stage like any
component, its two end points its boundary).

``ends = {name = [x, y, z], other = [x, y, z]}`` (m): the two end points, named as the
joints the strut shares with the components it links (each end's six DOFs are the joint's);
``section``: a liftoff.core.beam.Section or a standard shape's table (``{shape = "tube",
r_out = ..., t = ...}``, liftoff.core.beam.standard_section); material ``E`` (Pa), ``nu``,
``rho`` (kg/m^3); ``elements`` along it; ``vref``: the section's orientation vector (local
y towards it; default: whichever global axis is most normal to the strut); ``pinned``: a
pin-ended (clevis) strut, a two-force member whose ends pass no moment (below); default
False (both ends take moments). SI units.

A pinned strut: its end elements' bending rotations released (Nastran's pin flags 56 at
both ends, liftoff.core.beam.release: condensed within the element), its torsion left out
(a straight beam's torsion is uncoupled from its axial and bending DOFs, and a strut
pinned at both ends carries none: the torsion chain would be free to spin), so its end
points are three translations each (``point:Tx``, ``Ty``, ``Tz``), and a joint overlays only
those: the rotations there are the other components' alone. Its nodes between keep their
translations and the two bending rotations about the strut's local y and z (unlabelled).
With one element it is a rod, EA/L along its axis, with the rigid bar's inertia across it.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from liftoff.core.beam import Section, assemble_frame, beam_element, element_axes, standard_section
from liftoff.core.elastic import check_elastic
from liftoff.core.errors import InputError
from liftoff.core.labels import TRANSLATIONS

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
    pinned: bool = False

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
        if not isinstance(self.pinned, bool):
            raise InputError(f"{o}.pinned must be true or false (got {self.pinned!r})")
        if len(self.vref) and (np.shape(self.vref) != (3,) or
                               np.linalg.norm(np.cross(b - a, np.asarray(self.vref, float))) == 0):
            raise InputError(f"{o}.vref must be 3 numbers not along the strut (got {list(self.vref)})")

    def section_of(self) -> Section:
        """The section: a Section as given, or a standard shape's (its table)."""
        if isinstance(self.section, Section):
            return self.section
        return standard_section(self.section, f"Strut({self.name}).section", self.nu)[0]


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
    end = "56" if p.pinned else ""              # a pinned strut: its end elements' bending released

    def element(k: int):
        pins = (end if k == 0 else "", end if k == n - 1 else "")
        return (k, k + 1, *beam_element(X[k], X[k + 1], p.E, G, sec, p.rho, vref, pins=pins))

    K, M = assemble_frame(n + 1, (element(k) for k in range(n)))
    cells = np.column_stack([np.arange(n), np.arange(1, n + 1)])
    if not p.pinned:
        return line_component(name, X, names, K, M, cells), {}
    return _pinned_component(name, X, (na, nb), K, M, cells, element_axes(a, b, vref)), {}


def _pinned_component(name: str, X: np.ndarray, ends: tuple[str, str], K, M, cells, axes: np.ndarray) -> Component:
    """The pinned strut (module docstring) from its assembled K, M (6 DOFs a node, end
    elements' bending rotations released): T maps its kept coordinates (each node's global
    translations, the inner nodes' rotations about the local y and z ``axes[1:]``) to the
    6 (n + 1) DOFs, K_r = T^T K T, M_r = T^T M T; the end translations labelled."""
    import scipy.sparse as sp

    nn = X.shape[0]
    cols: list[np.ndarray] = []
    trans: list[int] = []                                               # the translations' columns, node-major
    for i in range(nn):
        for d in range(3):
            e = np.zeros(6 * nn)
            e[6 * i + d] = 1.0
            trans.append(len(cols))
            cols.append(e)
        if 0 < i < nn - 1:
            for ax in axes[1:]:
                e = np.zeros(6 * nn)
                e[6 * i + 3:6 * i + 6] = ax
                cols.append(e)
    T = sp.csr_matrix(np.column_stack(cols))
    Kr, Mr = (T.T @ A @ T for A in (K, M))
    fmap = sp.csr_matrix((np.ones(3 * nn), (np.arange(3 * nn), trans)), shape=(3 * nn, T.shape[1]))
    labels = [f"{pt}:{c}" for pt in ends for c in TRANSLATIONS]
    return Component(name=name, K=Kr, M=Mr, dof_labels=labels, label_dofs=np.r_[trans[:3], trans[-3:]],
                     points=ends, point_coords=X[[0, -1]], nodes=X, cells=cells, cell_type="line", field_map=fmap)


__all__ = ["Strut", "strut_component"]
