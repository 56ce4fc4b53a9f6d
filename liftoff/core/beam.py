"""The straight 3-D beam element (issue 26): Timoshenko (shear-deformable, with rotary
inertia) or Euler-Bernoulli, 2 nodes, 6 DOFs a node (ux uy uz rx ry rz), in one place for
every layer that builds beams (reduction.models' reference frames, workflows.stick, fem).
Numpy only; SI units (m, Pa, kg/m^3, N, rad).

Local axes: x along the beam (node 1 to node 2), y and z its principal axes, z = x cross
``vref`` normalised, y = z cross x (``vref`` the orientation vector, as Nastran CBEAM's v).
Section: area A, second moments Iy (about y: bending in the x-z plane) and Iz (about z:
bending in the x-y plane), torsion constant J, shear areas Ay, Az (the effective areas for
shear along y and z; None: no shear deformation, Euler-Bernoulli).

Stiffness (Przemieniecki, Theory of Matrix Structural Analysis, 1968, eq. 5.116): axial
EA/L, torsion GJ/L, and in the x-y plane with phi_y = 12 E Iz / (G Ay L^2)

    E Iz / ((1 + phi) L^3) [[12, 6L, -12, 6L], [6L, (4 + phi) L^2, -6L, (2 - phi) L^2], ...]

(the x-z plane the same with Iy, Az and the sign of theta_y = -dw/dx). It is the exact
stiffness of the Timoshenko beam under end loads: nodal displacements of point-loaded
frames are exact with one element per span.

Mass (consistent, Przemieniecki eq. 11.41-11.42 / Archer 1965): translational
rho A L / (1 + phi)^2 [[13/35 + 7 phi/10 + phi^2/3, ...]] plus, with ``rotary``, the
rotary inertia of the section rho I / ((1 + phi)^2 L) [[6/5, (1/10 - phi/2) L, ...]]; axial
rho A L/6 [[2, 1], [1, 2]], torsion rho (Iy + Iz) L/6 [[2, 1], [1, 2]]. With phi = 0 and no
rotary inertia it is the Euler-Bernoulli element of Przemieniecki's eq. 11.32 (rho A L/420
[[156, 22L, 54, -13L], ...]).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import InputError


@dataclass(frozen=True)
class Section:
    """Beam section properties (m^2, m^4): A, Iy, Iz, J, shear areas Ay, Az (None: rigid in
    shear, Euler-Bernoulli)."""

    A: float
    Iy: float
    Iz: float
    J: float
    Ay: float | None = None
    Az: float | None = None

    def __post_init__(self):
        for k in ("A", "Iy", "Iz", "J"):
            v = getattr(self, k)
            if isinstance(v, bool) or not np.isfinite(v) or not v > 0:
                raise InputError(f"beam section: {k} must be > 0 (got {v!r})")
        for k in ("Ay", "Az"):
            v = getattr(self, k)
            if v is not None and (isinstance(v, bool) or not np.isfinite(v) or not v > 0):
                raise InputError(f"beam section: shear area {k} must be > 0 or None (got {v!r})")


def _axes(x1: np.ndarray, x2: np.ndarray, vref) -> tuple[float, np.ndarray]:
    d = x2 - x1
    L = float(np.linalg.norm(d))
    if not L > 0:
        raise InputError(f"beam element from {x1.tolist()} to {x2.tolist()} m has zero length")
    ex = d / L
    v = np.asarray(vref, float)
    if np.linalg.norm(np.cross(ex, v)) < 1e-8 * max(np.linalg.norm(v), 1e-300):
        # the default vref along the beam: take y, or for a beam along y the global axis least
        # along it (y there gave z = x cross y = 0 and NaN matrices)
        v = np.array([0.0, 1.0, 0.0]) if abs(ex[1]) < 0.9 else np.eye(3)[int(np.argmin(np.abs(ex)))]
    ez = np.cross(ex, v)
    ez /= np.linalg.norm(ez)
    ey = np.cross(ez, ex)
    return L, np.vstack([ex, ey, ez])


def element_axes(x1, x2, vref) -> np.ndarray:
    """The local axes of a beam from ``x1`` to ``x2`` with orientation vector ``vref``: rows
    x (along it), y, z (module docstring)."""
    return _axes(np.asarray(x1, float), np.asarray(x2, float), vref)[1]


def bending_stiffness(EI: float, L: float, phi: float = 0.0) -> np.ndarray:
    """4 x 4 stiffness of one bending plane (w, theta at both ends), phi = 12 E I / (G A_s L^2)
    (0: Euler-Bernoulli)."""
    return EI / ((1 + phi) * L ** 3) * np.array([
        [12, 6 * L, -12, 6 * L], [6 * L, (4 + phi) * L ** 2, -6 * L, (2 - phi) * L ** 2],
        [-12, -6 * L, 12, -6 * L], [6 * L, (2 - phi) * L ** 2, -6 * L, (4 + phi) * L ** 2]])


def _translational_mass(rhoA: float, L: float, phi: float) -> np.ndarray:
    a = 13 / 35 + 7 * phi / 10 + phi ** 2 / 3
    b = (11 / 210 + 11 * phi / 120 + phi ** 2 / 24) * L
    c = 9 / 70 + 3 * phi / 10 + phi ** 2 / 6
    d = (13 / 420 + 3 * phi / 40 + phi ** 2 / 24) * L
    e = (1 / 105 + phi / 60 + phi ** 2 / 120) * L ** 2
    f = (1 / 140 + phi / 60 + phi ** 2 / 120) * L ** 2
    return rhoA * L / (1 + phi) ** 2 * np.array([[a, b, c, -d], [b, e, d, -f], [c, d, a, -b], [-d, -f, -b, e]])


def _rotary_mass(rhoI: float, L: float, phi: float) -> np.ndarray:
    a = 6 / 5
    b = (1 / 10 - phi / 2) * L
    e = (2 / 15 + phi / 6 + phi ** 2 / 3) * L ** 2
    f = (-1 / 30 - phi / 6 + phi ** 2 / 6) * L ** 2
    return rhoI / ((1 + phi) ** 2 * L) * np.array([[a, b, -a, b], [b, e, -b, f], [-a, -b, a, -b], [b, f, -b, e]])


def beam_element(x1, x2, E: float, G: float, section: Section, rho: float, vref=(0.0, 0.0, 1.0),
                 rotary: bool = True, nsm: float = 0.0,
                 pins: tuple[str, str] = ("", "")) -> tuple[np.ndarray, np.ndarray]:
    """Global 12 x 12 stiffness and consistent mass of a straight beam from ``x1`` to ``x2``
    (module docstring): Timoshenko where the section has shear areas, Euler-Bernoulli
    where it has none; ``rotary``: the bending rotary inertia rho I in the mass; ``nsm``:
    non-structural mass per length (kg/m, Nastran PBEAM's NSM), translational only (no
    rotary or torsional inertia); ``pins``: pin flags at node 1 and node 2 (:func:`release`)."""
    x1, x2 = np.asarray(x1, float), np.asarray(x2, float)
    L, lam = _axes(x1, x2, vref)
    s = section
    phi_y = 0.0 if s.Ay is None else 12 * E * s.Iz / (G * s.Ay * L ** 2)     # x-y plane (v, theta_z)
    phi_z = 0.0 if s.Az is None else 12 * E * s.Iy / (G * s.Az * L ** 2)     # x-z plane (w, theta_y)
    k = np.zeros((12, 12))
    m = np.zeros((12, 12))
    for a, b, val in ((0, 6, E * s.A / L), (3, 9, G * s.J / L)):
        k[np.ix_([a, b], [a, b])] = val * np.array([[1, -1], [-1, 1]])
    mA = rho * s.A + nsm                             # translational mass per length (kg/m)
    m[np.ix_([0, 6], [0, 6])] = mA * L / 6 * np.array([[2, 1], [1, 2]])
    m[np.ix_([3, 9], [3, 9])] = rho * (s.Iy + s.Iz) * L / 6 * np.array([[2, 1], [1, 2]])
    flip = np.diag([1, -1, 1, -1])                   # x-z plane: theta_y = -dw/dx
    xy, xz = [1, 5, 7, 11], [2, 4, 8, 10]
    k[np.ix_(xy, xy)] = bending_stiffness(E * s.Iz, L, phi_y)
    k[np.ix_(xz, xz)] = flip @ bending_stiffness(E * s.Iy, L, phi_z) @ flip
    m[np.ix_(xy, xy)] = _translational_mass(mA, L, phi_y) + (_rotary_mass(rho * s.Iz, L, phi_y) if rotary else 0)
    m[np.ix_(xz, xz)] = flip @ (_translational_mass(mA, L, phi_z)
                                + (_rotary_mass(rho * s.Iy, L, phi_z) if rotary else 0)) @ flip
    if any(pins):
        k, m = release(k, m, pins)
    T = np.kron(np.eye(4), lam)
    return T.T @ k @ T, T.T @ m @ T


#: pin-flag digits: the element's local rotations at a node (Nastran CBAR/CBEAM PA, PB; the
#: translations 1-3 are not released here: a released translation is a gap, not a pin)
PIN_DIGITS = "456"


def release(k: np.ndarray, m: np.ndarray, pins: tuple[str, str]) -> tuple[np.ndarray, np.ndarray]:
    """Local 12 x 12 stiffness and mass with the rotations ``pins`` (digits 4-6 at node 1,
    node 2: Nastran's pin flags PA, PB) released: those DOFs statically condensed out, T =
    [I; -K_rr^-1 K_rc] over the connected DOFs c, K_c = T^T K T and M_c = T^T M T (the
    released rotations follow the element's static shape under its end displacements, as
    Guyan's reduction within the element), and the released rows and columns zero, so the
    node's rotation there takes nothing from this element (a pinned end passes no moment
    about that axis). Torsion (4) may be released at one node only (at both the element
    would be free to spin about its axis). InputError for other flags."""
    if not (isinstance(pins, (tuple, list)) and len(pins) == 2 and all(isinstance(f, str) for f in pins)):
        raise InputError(f"pin flags are two strings of digits 4-6, node 1's and node 2's (got {pins!r})")
    for f in pins:
        if any(c not in PIN_DIGITS for c in f) or len(set(f)) != len(f):
            raise InputError(f"pin flag {f!r}: digits 4, 5, 6 (the local rotations x, y, z) each at most once")
    if "4" in pins[0] and "4" in pins[1]:
        raise InputError("pin flags: torsion (4) released at both ends leaves the element free to spin about its axis")
    r = [6 * n + int(c) - 1 for n, f in enumerate(pins) for c in f]
    if not r:
        return k, m
    c = [i for i in range(12) if i not in r]
    T = np.zeros((12, len(c)))
    T[c, np.arange(len(c))] = 1.0
    T[r] = -np.linalg.solve(k[np.ix_(r, r)], k[np.ix_(r, c)])
    kc, mc = np.zeros((12, 12)), np.zeros((12, 12))
    kc[np.ix_(c, c)] = T.T @ k @ T
    mc[np.ix_(c, c)] = T.T @ m @ T
    return kc, mc


def assemble_frame(n_nodes: int, elements) -> tuple:
    """Sparse K, M (6 DOFs per node, node-major; scipy CSR) from ``elements``: (node a, node
    b, 12 x 12 stiffness, 12 x 12 mass) each, in global axes (:func:`beam_element`)."""
    import scipy.sparse as sp

    n = 6 * int(n_nodes)
    rows, cols, kv, mv = [], [], [], []
    for a, b, ke, me in elements:
        dofs = np.r_[6 * a:6 * a + 6, 6 * b:6 * b + 6]
        rows.append(np.repeat(dofs, 12))
        cols.append(np.tile(dofs, 12))
        kv.append(np.asarray(ke).ravel())
        mv.append(np.asarray(me).ravel())
    r, c = np.concatenate(rows), np.concatenate(cols)
    K = sp.csr_matrix((np.concatenate(kv), (r, c)), shape=(n, n))
    M = sp.csr_matrix((np.concatenate(mv), (r, c)), shape=(n, n))
    return K, M


# ---- sections of standard shapes ------------------------------------------------------------------
def tube(r_out: float, t: float, nu: float = 0.3) -> Section:
    """Circular tube, outer radius ``r_out``, wall ``t`` (m): exact A, I, J (= 2 I); shear
    area k A with Cowper's coefficient (J. Appl. Mech. 33, 1966, Table 1) for a hollow
    circle, m = r_in / r_out: k = 6 (1 + nu)(1 + m^2)^2 / ((7 + 6 nu)(1 + m^2)^2 + (20 + 12 nu) m^2)
    (0.53 for a thin tube, 6 (1 + nu)/(7 + 6 nu) = 0.886 for a solid bar at nu = 0.3)."""
    if not (r_out > 0 and 0 < t <= r_out):
        raise InputError(f"tube section: need r_out > 0 and 0 < t <= r_out (got {r_out!r}, {t!r})")
    ri = r_out - t
    A = np.pi * (r_out ** 2 - ri ** 2)
    I = np.pi / 4 * (r_out ** 4 - ri ** 4)
    m2 = (ri / r_out) ** 2
    k = 6 * (1 + nu) * (1 + m2) ** 2 / ((7 + 6 * nu) * (1 + m2) ** 2 + (20 + 12 * nu) * m2)
    return Section(A, I, I, 2 * I, k * A, k * A)


def rectangle(b: float, h: float, nu: float = 0.3) -> Section:
    """Solid rectangle, width ``b`` (along y), height ``h`` (along z): A = b h,
    Iy = b h^3/12, Iz = h b^3/12, J from Saint-Venant's series (Timoshenko & Goodier,
    Theory of Elasticity, eq. 167: J = a^3 c (1/3 - 64 a/(pi^5 c) sum tanh(n pi c/(2a))/n^5),
    a <= c the sides, n odd), shear areas with Cowper's 10 (1 + nu)/(12 + 11 nu)."""
    if not (b > 0 and h > 0):
        raise InputError(f"rectangle section: need b, h > 0 (got {b!r}, {h!r})")
    a, c = min(b, h), max(b, h)
    n = np.arange(1, 200, 2)
    J = a ** 3 * c * (1 / 3 - 64 * a / (np.pi ** 5 * c) * np.sum(np.tanh(n * np.pi * c / (2 * a)) / n ** 5))
    k = 10 * (1 + nu) / (12 + 11 * nu)
    return Section(b * h, b * h ** 3 / 12, h * b ** 3 / 12, float(J), k * b * h, k * b * h)


def i_section(h: float, b: float, tw: float, tf: float) -> Section:
    """Doubly symmetric thin-walled I: depth ``h`` (along z, flange centre to centre),
    flange width ``b``, web ``tw``, flanges ``tf`` (m), thin-wall formulas: A = 2 b tf + h tw,
    Iy = tw h^3/12 + 2 b tf (h/2)^2 (strong axis, bending in x-z), Iz = 2 tf b^3/12,
    J = (2 b tf^3 + h tw^3)/3 (open section); shear areas: the web (h tw) along z, the
    flanges (5/6 2 b tf) along y."""
    for nm, v in (("h", h), ("b", b), ("tw", tw), ("tf", tf)):
        if not v > 0:
            raise InputError(f"I section: {nm} must be > 0 (got {v!r})")
    if not (tw < b and tf < h):     # h is flange centre to centre: flanges thicker than it overlap
        raise InputError(f"I section: the web tw = {tw!r} m must be thinner than the flanges are wide (b = {b!r} m) "
                         f"and the flanges tf = {tf!r} m thinner than the depth h = {h!r} m")
    A = 2 * b * tf + h * tw
    return Section(A, tw * h ** 3 / 12 + 2 * b * tf * (h / 2) ** 2, 2 * tf * b ** 3 / 12,
                   (2 * b * tf ** 3 + h * tw ** 3) / 3, 5 / 6 * 2 * b * tf, h * tw)


def t_section(h: float, b: float, tw: float, tf: float) -> tuple[Section, float]:
    """A T: web ``tw`` wide and ``h`` deep (along z) under a flange ``b`` wide, ``tf`` thick
    (m), composed exactly of its two rectangles; returns (Section about the centroid, the
    centroid's height above the web's bottom, m). Iy (bending in x-z) by the parallel-axis
    theorem, Iz = (tf b^3 + h tw^3)/12; J = (b tf^3 + h tw^3)/3 (open thin-walled); shear
    areas: the web (h tw) along z, 5/6 of the flange (b tf) along y. The element's axis is
    the centroid's (no offset: place the nodes there)."""
    for nm, v in (("h", h), ("b", b), ("tw", tw), ("tf", tf)):
        if not v > 0:
            raise InputError(f"T section: {nm} must be > 0 (got {v!r})")
    if not tw <= b:
        raise InputError(f"T section: the web tw = {tw!r} m must be no wider than the flange b = {b!r} m")
    a_web, a_fl = h * tw, b * tf
    A = a_web + a_fl
    zc = (a_web * h / 2 + a_fl * (h + tf / 2)) / A
    Iy = tw * h ** 3 / 12 + a_web * (h / 2 - zc) ** 2 + b * tf ** 3 / 12 + a_fl * (h + tf / 2 - zc) ** 2
    Iz = (tf * b ** 3 + h * tw ** 3) / 12
    return Section(A, Iy, Iz, (b * tf ** 3 + h * tw ** 3) / 3, 5 / 6 * a_fl, a_web), zc


def hat_section(h: float, b: float, c: float, t: float) -> tuple[Section, float]:
    """A hat stringer of uniform wall ``t`` (m), thin-walled (its mid-line): a crown ``b``
    wide at height ``h`` on two vertical webs ``h`` high, each with a foot flange ``c`` wide
    at z = 0 (on the skin), symmetric about z; returns (Section about the centroid, the
    centroid's height above the feet's mid-line, m). A = t (b + 2 h + 2 c); Iy, Iz by
    composition (the walls' own t^3 terms across their thickness dropped: thin walls);
    J = t^3 (b + 2 h + 2 c)/3 (open section); shear areas: the webs (2 h t) along z, 5/6 of
    the crown and feet along y."""
    for nm, v in (("h", h), ("b", b), ("c", c), ("t", t)):
        if not v > 0:
            raise InputError(f"hat section: {nm} must be > 0 (got {v!r})")
    if not t < min(h, b):           # a wall thicker than what it spans is no thin-walled hat
        raise InputError(f"hat section: the wall t = {t!r} m must be thinner than the hat's height h = {h!r} m "
                         f"and crown b = {b!r} m")
    A = t * (b + 2 * h + 2 * c)
    zc = (b * t * h + 2 * h * t * h / 2) / A
    Iy = b * t * (h - zc) ** 2 + 2 * (t * h ** 3 / 12 + h * t * (h / 2 - zc) ** 2) + 2 * c * t * zc ** 2
    Iz = t * b ** 3 / 12 + 2 * h * t * (b / 2) ** 2 + 2 * (t * c ** 3 / 12 + c * t * (b / 2 + c / 2) ** 2)
    return Section(A, Iy, Iz, t ** 3 * (b + 2 * h + 2 * c) / 3, 5 / 6 * t * (b + 2 * c), 2 * h * t), zc


def box_section(b: float, h: float, t: float) -> Section:
    """A thin-walled rectangular hollow section (a box girder, a square column): outer width
    ``b`` (along y), depth ``h`` (along z), wall ``t`` (m), by its mid-line (bm = b - t,
    hm = h - t; the walls' own t^3 terms dropped): A = 2 t (bm + hm), Iy = t hm^3/6 +
    bm t hm^2/2, Iz likewise, J = 4 (bm hm)^2 t / (2 (bm + hm)) (Bredt-Batho, closed cell),
    shear areas the walls parallel to each axis (2 hm t along z, 2 bm t along y)."""
    for nm, v in (("b", b), ("h", h), ("t", t)):
        if not v > 0:
            raise InputError(f"box section: {nm} must be > 0 (got {v!r})")
    if not 2 * t < min(b, h):
        raise InputError(f"box section: the wall t = {t!r} m must be < half the smaller side ({min(b, h)!r} m)")
    bm, hm = b - t, h - t
    return Section(2 * t * (bm + hm), t * hm ** 3 / 6 + bm * t * hm ** 2 / 2, t * bm ** 3 / 6 + hm * t * bm ** 2 / 2,
                   2 * t * bm ** 2 * hm ** 2 / (bm + hm), 2 * bm * t, 2 * hm * t)


#: standard shapes by name: (section function, the distance (m) from the face the member
#: sits on (a frame's or stringer's base on the skin) to its centroid, from the dimensions
#: and the function's result)
SHAPES = {
    "tube": (tube, lambda d, out: d["r_out"]),
    "rectangle": (rectangle, lambda d, out: 0.5 * d["h"]),
    "box": (box_section, lambda d, out: 0.5 * d["h"]),
    "i": (i_section, lambda d, out: 0.5 * (d["h"] + d["tf"])),
    "t": (t_section, lambda d, out: out[1]),
    "hat": (hat_section, lambda d, out: 0.5 * d["t"] + out[1]),
}


def standard_section(spec: dict, where: str = "section", nu: float | None = None) -> tuple[Section, float]:
    """(Section, distance from the base to the centroid, m) of ``spec`` = {"shape": one of
    :data:`SHAPES`, the shape function's dimensions (m)}: e.g. {"shape": "t", "h": 0.15,
    "b": 0.06, "tw": 0.004, "tf": 0.006}. Base: the flat face the member sits on (the web's
    foot of a T or I frame, the feet of a hat stringer, a side of a rectangle or tube).
    InputError naming ``where`` and the culprit on an unknown shape or a wrong dimension.
    ``nu``: the member's material's Poisson ratio, for the shapes whose shear coefficient
    takes one (Cowper's: tube, rectangle) unless the table gives its own (-1 < nu < 0.5)."""
    import inspect

    if not isinstance(spec, dict) or "shape" not in spec:
        raise InputError(f"{where}: expected a table with shape = one of {', '.join(SHAPES)} and its dimensions (m)")
    shape = spec["shape"]
    if shape not in SHAPES:
        raise InputError(f"{where}: unknown shape {shape!r} (one of {', '.join(SHAPES)})")
    make, base = SHAPES[shape]
    dims = {k: v for k, v in spec.items() if k != "shape"}
    params = inspect.signature(make).parameters
    bad = sorted(set(dims) - set(params))
    missing = [n for n, par in params.items() if par.default is inspect.Parameter.empty and n not in dims]
    if bad or missing:
        raise InputError(f"{where}: shape {shape!r} takes {', '.join(params)} (m)"
                         + (f"; unknown {', '.join(bad)}" if bad else "") + (f"; missing {', '.join(missing)}" if missing else ""))
    for k, v in dims.items():
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not np.isfinite(v):
            raise InputError(f"{where}.{k}: expected a number (got {v!r})")
    if "nu" in dims and not -1.0 < dims["nu"] < 0.5:
        raise InputError(f"{where}.nu: Poisson's ratio must lie in (-1, 0.5) (got {dims['nu']!r})")
    if "nu" in params and "nu" not in dims and nu is not None:
        dims["nu"] = float(nu)
    out = make(**dims)
    return (out[0] if isinstance(out, tuple) else out), float(base(dims, out))


__all__ = ["Section", "SHAPES", "standard_section", "box_section", "assemble_frame", "beam_element", "bending_stiffness", "tube", "rectangle", "i_section", "t_section",
           "hat_section"]
