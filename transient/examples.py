"""Small exact modal bodies for examples and validation (closed form or tiny K, M + eigh).

* :func:`free_free_rod`  axial modes of a uniform free-free rod (closed form).
* :func:`spring_block`   a grounded mass on a spring (one mode).
* :func:`truss_body`     modal body of a small 3-D pin-jointed truss with lumped masses.
* :func:`toy_vehicle`, :func:`toy_pad`, :func:`holddown_contacts`: a flexible free-free
  "vehicle" (6 rigid + elastic modes) standing on a grounded flexible "pad" at 2-4
  hold-down points.
* :func:`module_truss`, :func:`docking_contacts`: two free-free flexible "modules" (6 rigid
  + elastic modes each) meeting at a docking ring of latch points with inclined (guide
  petal) contact normals.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg

from liftoff.core.errors import InputError
from liftoff.core.labels import COMPONENTS
from liftoff.core.rigid import nodal_rb

from .body import ModalBody
from .model import ContactPoint

_AXES = {"Tx": 0, "Ty": 1, "Tz": 2}


def free_free_rod(L: float, E: float, rho: float, A: float, n_modes: int, zeta: float = 0.0,
                  name: str = "rod", end_labels: tuple[str, str] = ("end0", "end1"), component: str = "Tz",
                  origin: float = 0.0, stations: int = 0) -> ModalBody:
    """Axial modes of a uniform free-free rod along ``component`` (closed form).

    Mode 0 is the rigid translation (omega = 0, phi = 1/sqrt(m)); mode k >= 1 has
    omega_k = k pi c / L, c = sqrt(E/rho), phi_k(x) = sqrt(2/m) cos(k pi x / L), m = rho A L.
    DOFs: the two ends (x = 0 at ``end_labels[0]``, x = L at ``end_labels[1]``), plus
    ``stations`` equally spaced interior points ``{name}_s{i}``. Elastic modes get ``zeta``.
    """
    if component not in _AXES:
        raise InputError(f"free_free_rod: component must be Tx, Ty or Tz, got {component!r}")
    if not (L > 0 and E > 0 and rho > 0 and A > 0 and n_modes >= 1):
        raise InputError("free_free_rod: L, E, rho, A must be positive and n_modes >= 1")
    m = rho * A * L
    c = math.sqrt(E / rho)
    k = np.arange(n_modes)
    omega = k * math.pi * c / L
    xs = [0.0, L] + [L * (i + 1) / (stations + 1) for i in range(stations)]
    names = list(end_labels) + [f"{name}_s{i + 1}" for i in range(stations)]
    phi = np.array([[math.sqrt((1.0 if kk == 0 else 2.0) / m) * math.cos(kk * math.pi * x / L) for kk in k]
                    for x in xs])
    ax = _AXES[component]
    part = np.zeros((n_modes, 6))
    part[0, ax] = math.sqrt(m)  # int rho A phi_k dx: sqrt(m) for the rigid mode, 0 for cos modes
    rbm = np.zeros((6, 6))
    rbm[ax, ax] = m
    coords = np.zeros((len(xs), 3))
    coords[:, ax] = origin + np.array(xs)
    return ModalBody(name=name, omega=omega, zeta=np.where(omega > 0, zeta, 0.0),
                     dof_labels=tuple(f"{p}:{component}" for p in names), phi=phi, participation=part,
                     ref_point=np.zeros(3), points=tuple(names), point_coords=coords, rigid_body_mass=rbm)


def spring_block(mass: float, stiffness: float, zeta: float = 0.0, name: str = "block", point: str = "block",
                 component: str = "Tz", position=(0.0, 0.0, 0.0)) -> ModalBody:
    """A mass on a grounded spring along ``component``: one mode, omega = sqrt(k/m), phi = 1/sqrt(m)."""
    if component not in _AXES or not (mass > 0 and stiffness > 0):
        raise InputError("spring_block: mass and stiffness must be positive, component Tx|Ty|Tz")
    ax = _AXES[component]
    part = np.zeros((1, 6))
    part[0, ax] = math.sqrt(mass)
    rbm = np.zeros((6, 6))
    rbm[ax, ax] = mass
    return ModalBody(name=name, omega=[math.sqrt(stiffness / mass)], zeta=[zeta], dof_labels=(f"{point}:{component}",),
                     phi=[[1.0 / math.sqrt(mass)]], participation=part, ref_point=np.zeros(3), points=(point,),
                     point_coords=np.array([position], dtype=float), rigid_body_mass=rbm)


# ------------------------------------------------------------------ trusses
@dataclass
class Truss:
    """A pin-jointed truss: free nodes (3 translations each), fixed anchor points, bars, masses."""

    names: list
    coords: np.ndarray          # (n_nodes, 3)
    masses: np.ndarray          # (n_nodes,)
    bars: list                  # (i, j, EA); j may be ('anchor', xyz)

    def matrices(self):
        """Global K (bars k n n^T, k = EA/L) and lumped M, DOF order node-major (Tx, Ty, Tz)."""
        n = 3 * len(self.names)
        K = np.zeros((n, n))
        for i, j, EA in self.bars:
            xi = self.coords[i]
            xj = np.asarray(j[1], dtype=float) if isinstance(j, tuple) else self.coords[j]
            d = xj - xi
            Lb = np.linalg.norm(d)
            e = d / Lb
            kb = EA / Lb * np.outer(e, e)
            si = slice(3 * i, 3 * i + 3)
            K[si, si] += kb
            if not isinstance(j, tuple):
                sj = slice(3 * j, 3 * j + 3)
                K[sj, sj] += kb
                K[si, sj] -= kb
                K[sj, si] -= kb
        M = np.diag(np.repeat(self.masses, 3))
        return K, M


def truss_body(truss: Truss, name: str, zeta: float = 0.02, ref_point=None, n_modes: int | None = None) -> ModalBody:
    """Exact modal body of a truss (scipy.linalg.eigh of K, M); rigid modes (omega = 0) get zeta = 0."""
    K, M = truss.matrices()
    lam, Phi = scipy.linalg.eigh(K, M)
    scale = max(abs(lam).max(), 1.0)
    lam = np.where(lam < 1e-9 * scale, 0.0, lam)
    if n_modes is not None:
        lam, Phi = lam[:n_modes], Phi[:, :n_modes]
    omega = np.sqrt(lam)
    ref = np.asarray(truss.masses @ truss.coords / truss.masses.sum() if ref_point is None else ref_point, dtype=float)
    RB = nodal_rb(truss.coords, ref)
    labels = tuple(f"{p}:{c}" for p in truss.names for c in COMPONENTS[:3])
    return ModalBody(name=name, omega=omega, zeta=np.where(omega > 0, zeta, 0.0), dof_labels=labels, phi=Phi,
                     participation=Phi.T @ M @ RB, ref_point=ref, points=tuple(truss.names),
                     point_coords=truss.coords.copy(), rigid_body_mass=RB.T @ M @ RB)


def _ring(n: int, radius: float, z: float, phase: float = 0.0) -> np.ndarray:
    a = phase + 2 * np.pi * np.arange(n) / n
    return np.column_stack([radius * np.cos(a), radius * np.sin(a), np.full(n, z)])


def vehicle_truss(n_posts: int = 4, radius: float = 2.0, height: float = 20.0, mass: float = 50e3,
                  EA: float = 5e9) -> Truss:
    """Free-free vehicle: n_posts base posts (z = 0), a mid ring (z = height/3), a top node.

    All base/mid nodes are connected pairwise (rigid as a solid) and the top node to all
    of them; masses: 10 % on the posts, 40 % on the mid ring, 50 % at the top."""
    if not 2 <= n_posts <= 4:
        raise InputError(f"vehicle_truss: n_posts must be 2, 3 or 4, got {n_posts}")
    base = _ring(n_posts, radius, 0.0)
    mid = _ring(n_posts, 0.8 * radius, height / 3, phase=np.pi / n_posts)
    top = np.array([[0.0, 0.0, height]])
    coords = np.vstack([base, mid, top])
    names = [f"post_{i + 1}" for i in range(n_posts)] + [f"ring_{i + 1}" for i in range(n_posts)] + ["top"]
    masses = np.concatenate([np.full(n_posts, 0.1 * mass / n_posts), np.full(n_posts, 0.4 * mass / n_posts),
                             [0.5 * mass]])
    nn = 2 * n_posts
    bars = [(i, j, EA) for i in range(nn) for j in range(i + 1, nn)] + [(i, nn, EA) for i in range(nn)]
    return Truss(names, coords, masses, bars)


def pad_truss(n_posts: int = 4, radius: float = 2.0, depth: float = 3.0, mass: float = 20e3,
              EA: float = 2e9) -> Truss:
    """Grounded pad: one node under each post (z = 0), each held by three bars to anchors at z = -depth,
    the top nodes connected pairwise; equal lumped masses."""
    top = _ring(n_posts, radius, 0.0)
    names = [f"pad_{i + 1}" for i in range(n_posts)]
    bars = []
    for i, x in enumerate(top):
        for off in ((0.0, 0.0), (1.5, 0.0), (0.0, 1.5)):
            bars.append((i, ("anchor", (x[0] + off[0], x[1] + off[1], -depth)), EA))
    bars += [(i, j, EA) for i in range(n_posts) for j in range(i + 1, n_posts)]
    return Truss(names, top, np.full(n_posts, mass / n_posts), bars)


def toy_vehicle(n_posts: int = 4, zeta: float = 0.02, n_modes: int | None = None, **kw) -> ModalBody:
    """Free-free flexible vehicle (6 rigid + 3(2 n_posts + 1) - 6 elastic modes), DOFs ``post_i:T*``."""
    return truss_body(vehicle_truss(n_posts, **kw), "vehicle", zeta=zeta, n_modes=n_modes)


def toy_pad(n_posts: int = 4, zeta: float = 0.05, **kw) -> ModalBody:
    """Grounded flexible pad (3 n_posts elastic modes), DOFs ``pad_i:T*`` under the vehicle posts."""
    return truss_body(pad_truss(n_posts, **kw), "pad", zeta=zeta, ref_point=np.zeros(3))


def holddown_contacts(n_posts: int = 4, stiffness: float = 1e10, release_time: float = math.inf,
                      rigid: bool = False) -> list[ContactPoint]:
    """One contact per post: axial Tz (vehicle on the + side of the pad), laterals Tx, Ty."""
    return [ContactPoint(f"holddown_{i + 1}", [f"post_{i + 1}:Tz", f"post_{i + 1}:Tx", f"post_{i + 1}:Ty"],
                         [f"pad_{i + 1}:Tz", f"pad_{i + 1}:Tx", f"pad_{i + 1}:Ty"], stiffness, axial=0,
                         normal_sign=1.0, release_time=release_time, rigid=rigid)
            for i in range(n_posts)]


# ------------------------------------------------------------------ docking
def module_truss(side: str, n_ring: int = 4, radius: float = 1.0, length: float = 4.0, mass: float = 6000.0,
                 EA: float = 2e8) -> Truss:
    """A free-free "module" along x: a docking ring of ``n_ring`` points at x = 0 (``<side>_dock_<i>``,
    in the y-z plane), a back ring at x = -length (side 'a', the chaser) or +length (side 'b',
    the target), a centre node; all ring nodes joined pairwise and to the centre. Masses: 10 %
    on the docking ring, 30 % on the back ring, 60 % at the centre (kg)."""
    if side not in ("a", "b"):
        raise InputError(f"module_truss: side must be 'a' or 'b', got {side!r}")
    sgn = -1.0 if side == "a" else 1.0
    ang = 2 * np.pi * np.arange(n_ring) / n_ring
    ring = np.column_stack([np.zeros(n_ring), radius * np.cos(ang), radius * np.sin(ang)])
    back = ring + np.array([sgn * length, 0.0, 0.0])
    coords = np.vstack([ring, back, [[sgn * length / 2, 0.0, 0.0]]])
    names = [f"{side}_dock_{i + 1}" for i in range(n_ring)] + [f"{side}_back_{i + 1}" for i in range(n_ring)] \
        + [f"{side}_centre"]
    masses = np.concatenate([np.full(n_ring, 0.1 * mass / n_ring), np.full(n_ring, 0.3 * mass / n_ring), [0.6 * mass]])
    nn = 2 * n_ring
    bars = [(i, j, EA) for i in range(nn) for j in range(i + 1, nn)] + [(i, nn, EA) for i in range(nn)]
    return Truss(names, coords, masses, bars)


def docking_contacts(n_ring: int = 4, stiffness: float = 2e6, petal_angle: float = 30.0, gap: float = 0.02,
                     friction: float = 0.0, damping: float = 0.0, latch_force: float | None = None) -> list[ContactPoint]:
    """One contact per docking-ring point of :func:`module_truss` a (chaser, coming from -x) and b:
    normal from b towards a, inclined by ``petal_angle`` (degrees) from -x towards the ring's
    centre (a guide petal: a point of a that is off-centre outwards touches first and is
    pushed back and inwards, a centring force);
    never bolted unless latched (``latch_force``, N)."""
    beta = math.radians(petal_angle)
    out = []
    for i in range(n_ring):
        phi = 2 * np.pi * i / n_ring
        n = [-math.cos(beta), -math.sin(beta) * math.cos(phi), -math.sin(beta) * math.sin(phi)]
        la = [f"a_dock_{i + 1}:{c}" for c in COMPONENTS[:3]]
        lb = [f"b_dock_{i + 1}:{c}" for c in COMPONENTS[:3]]
        out.append(ContactPoint(f"latch_{i + 1}", la, lb, stiffness, gap=gap, release_time=-math.inf, normal=n,
                                friction=friction, damping=damping, latch_force=latch_force))
    return out
