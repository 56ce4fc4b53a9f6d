"""Gravity slosh of the liquids of a tank from the tank's own liquid mesh (issue 25): the
free-surface gravity condition added to fem.liquid's incompressible liquid, its sloshing
modes in a rigid tank, and their equivalent mechanical model (spring-mass or pendulum per
mode, as NASA SP-106 tabulates it).

Small motion about rest under an apparent acceleration g_eff (1 g on the pad, the thrust
acceleration in flight) along -z, p the perturbation pressure, eta the free surface's rise,
n the liquid's outward normal (Abramson, NASA SP-106, 1966, ch. 2; Morand & Ohayon,
Fluid-Structure Interaction, 1995, ch. 6):

    lap p = 0 in the liquid,   dp/dn = -rho u''.n on the wall,
    p = rho g_eff eta  and  eta'' = -(1/rho) dp/dn  on the free surface,                   (1)

so dp/dn = -p'' / g_eff on the free surface. Galerkin with the pressure space of fem.liquid
(eq. 2 there), its free-surface DOFs now kept:

    H p + (1 / g_eff) S p'' = -rho G u'',   S_ij = int_fs N_i N_j dS                       (2)

(H the Laplacian over all pressure DOFs: Neumann wherever p is not prescribed). With the
wall held (u = 0), (2) is the sloshing eigenproblem

    H phi = lambda S phi,   omega^2 = g_eff lambda,                                          (3)

S only on the surface rows (the interior rows carry no mass: infinite eigenvalues). Its
lambda = 0 mode (p constant; there when no p = 0 DOF holds the liquid) is not a wave and is
dropped. Condensing the non-surface DOFs k out of (2) with the wall moving rigidly with
acceleration a along a rigid field r (coupling vector g = G r, blocks g_k, g_f):

    Hc p_f + S p_f'' / g_eff = -rho b a,   b = g_f - H_fk H_kk^-1 g_k,
    force on the wall along r:  F = -m_0 a + b^T p_f,   m_0 = rho g_k^T H_kk^-1 g_k         (4)

m_0 is the impulsive mass (the p = 0 added mass of fem.liquid). With phi_n normalised
phi_n^T S phi_n = 1 and beta_n = phi_n^T b (= x_n^T g for the full eigenvector x_n of (3)),
each mode is an oscillator c'' + omega_n^2 c = -rho g_eff beta_n a, and its force on the tank
at frequency omega is -a rho g_eff beta_n^2 / (omega_n^2 - omega^2): a mass

    m_n = rho beta_n^2 / lambda_n                                                            (5)

on a spring k_n = m_n omega_n^2 (SP-106's spring-mass model). At omega -> 0 the forces add to
the whole liquid, m_0 + sum_n m_n = rho V (exactly, over all the modes: block elimination of
the Neumann problem, whose lateral solution p = -rho a x is linear and lies in the FE space).
The mode's moment about a horizontal axis, from the rotation field through the same rows,
gives the height z_n at which F_n acts (wall and bottom pressure, the hydrostatic part of
the moving surface included: SP-106's "including bottom pressure" height); over all modes
m_0 z_0 + sum m_n z_n = m (z_c + I_fs / V) (z_c the liquid's centroid, I_fs the free
surface's second moment: the quasi-static tilt of the surface adds I_fs/V). A pendulum of
mass m_n, length L_n = g_eff / omega_n^2 = 1 / lambda_n, hinged at z_n gives the same force
and moment. The modes here are those of a rigid tank; in a flexible one they couple with the
wall (the Craig-Bampton model, not yet: docs/hydro.md).

Which liquid a DOF belongs to: fem.liquid's p_group (several liquids in one operator are
separate regions: H is block diagonal and each liquid is solved alone). Units SI.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from liftoff.core.errors import InputError
from liftoff.core.units import G0

LATERAL_MASS = 1e-3       # a mode with a slosh mass below this fraction of its liquid's is not reported


@dataclass
class SloshMode:
    """One lateral sloshing mode of a liquid in its rigid tank (module docstring, eq. 3-5)."""

    liquid: str
    frequency: float            # Hz, at the model's g_eff
    mass: float                 # kg, slosh mass m_n (eq. 5), along ``direction``
    direction: tuple            # (x, y) unit vector of the mode's lateral force
    height: float               # m, z at which the mode's force acts (its moment / force)
    axial_force_ratio: float    # |F_z| / |F_xy| of the mode (0 for a lateral mode)
    wave_per_force: float = np.nan   # m/N: the mode's largest free-surface rise per newton of its force

    @property
    def stiffness(self) -> float:       # N/m, k_n = m_n omega_n^2
        return self.mass * (2 * np.pi * self.frequency) ** 2


@dataclass
class LiquidSlosh:
    """The slosh model of one liquid: its modes, impulsive (fixed) mass and totals."""

    liquid: str
    gravity: float              # m/s^2, g_eff
    mass: float                 # kg, of the meshed liquid (rho V)
    centroid: np.ndarray        # (3,) m
    impulsive_mass: tuple       # kg, (x, y): the p = 0 added mass m_0
    impulsive_height: tuple     # m, (x, y): z of m_0's force
    surface_second_moment: tuple   # m^4, (about y: int (x - x0)^2 dA, about x: int (y - y0)^2 dA)
    modes: list = field(default_factory=list)

    @property
    def mass_kept(self) -> float:
        """(m_0 + sum m_n) / m along x: 1 when every mode is kept (module docstring)."""
        return (self.impulsive_mass[0] + sum(m.mass * m.direction[0] ** 2 for m in self.modes)) / self.mass

    def pendulum_length(self, mode: SloshMode) -> float:
        """m, L_n = g_eff / omega_n^2."""
        return self.gravity / (2 * np.pi * mode.frequency) ** 2


def _rigid(op, x0: np.ndarray) -> np.ndarray:
    """Coupling vectors (n_c, 5) of the rigid fields tx, ty, tz, rx, ry (rotations about x0)."""
    c, k = op.c_coords - x0, op.c_comp
    R = np.zeros((k.size, 5))
    for j in range(3):
        R[:, j] = (k == j)
    R[:, 3] = np.where(k == 1, -c[:, 2], np.where(k == 2, c[:, 1], 0.0))     # e_x x r' = (0, -z', y')
    R[:, 4] = np.where(k == 0, c[:, 2], np.where(k == 2, -c[:, 0], 0.0))     # e_y x r' = (z', 0, -x')
    return R


def _surface_moments(Sff: sp.csr_matrix, xy: np.ndarray, rho: float) -> tuple[float, float, np.ndarray]:
    """Area, centroid (x, y) and second moments of the free surface from its mass matrix
    (S 1 integrates N_i over the surface: exact for any function in the space)."""
    w = np.asarray(Sff @ np.ones(Sff.shape[0])).ravel() * rho        # int N_i dA
    area = float(w.sum())
    c = w @ xy / area
    d = xy - c
    Sd = lambda u, v: float(u @ (Sff @ v)) * rho       # noqa: E731  int u v dA, both in the space
    return area, c, np.array([Sd(d[:, 0], d[:, 0]), Sd(d[:, 1], d[:, 1])])


def _eigen(A: sp.csr_matrix, B: sp.csr_matrix, want: int, sigma: float, what: str):
    """The ``want`` lowest pairs of A x = lambda B x, B semi-definite (eq. 3): SLEPc,
    shift-invert at ``sigma`` < 0 with a MUMPS Cholesky factor of A - sigma B (SPD)."""
    from petsc4py import PETSc

    from . import petsc_backend as pb

    n = A.shape[0]
    Ap = pb.csr_matrix(PETSc.COMM_SELF, n, n, n, sp.csr_matrix(A))
    Bp = pb.csr_matrix(PETSc.COMM_SELF, n, n, n, sp.csr_matrix(B))
    try:
        for M in (Ap, Bp):
            M.setOption(PETSc.Mat.Option.SYMMETRIC, True)
        return pb.eigensolve(Ap, Bp, want, sigma, what=f"{what}: sloshing modes")
    finally:
        Ap.destroy()
        Bp.destroy()


#: sloshing modes whose frequencies agree within this fraction are one group (a round tank's
#: equal pairs, split by the mesh by about 1e-4; its distinct lateral modes differ by 70 % and more)
PAIR_TOL = 1e-2


def _whole_groups(idx: np.ndarray, lam: np.ndarray, n: int) -> np.ndarray:
    """The first ``n`` of the modes ``idx`` (ascending lambda), and those after them with the
    frequency of the last: a round tank's lateral modes come in equal pairs that the eigensolver
    returns turned by any angle, so one member alone sloshes in an arbitrary direction."""
    k = min(n, idx.size)
    while 0 < k < idx.size and abs(np.sqrt(lam[idx[k]] / lam[idx[k - 1]]) - 1.0) <= PAIR_TOL:
        k += 1
    return idx[:k]


def slosh_modes(op, gravity: float = G0, n_modes: int = 6, lateral_only: bool = True, groups=None) -> dict:
    """The ``n_modes`` lowest sloshing modes of each liquid of ``op`` (a fem.liquid.LiquidOperator
    built with a free surface; rounded up to whole groups of equal frequency, :func:`_whole_groups`) in a rigid tank under ``gravity`` (m/s^2, g_eff): {liquid group:
    LiquidSlosh}. Modes without lateral force (axisymmetric, n >= 2 waves of an axisymmetric
    tank: slosh mass below LATERAL_MASS of the liquid's) are left out when ``lateral_only``;
    ``LiquidSlosh.mass_kept`` says how much of the liquid the kept modes and m_0 carry;
    ``groups``: only these liquids (default all)."""
    if isinstance(gravity, bool) or not np.isfinite(gravity) or not gravity > 0:
        raise InputError(f"liquid {op.name!r}: slosh needs an apparent acceleration g_eff > 0 m/s^2 (got {gravity!r})")
    if isinstance(n_modes, bool) or int(n_modes) != n_modes or n_modes < 1:
        raise InputError(f"liquid {op.name!r}: slosh n_modes must be an integer >= 1 (got {n_modes!r})")
    fs = op.free
    if fs is None:
        raise InputError(f"liquid {op.name!r} has no free surface: it cannot slosh")
    out = {}
    for c, g in enumerate(op.groups):
        if groups is not None and g not in groups:
            continue
        rho = op.density[g]
        k = np.flatnonzero(op.p_group == c)
        f = np.flatnonzero(fs.group == c)
        if f.size < 3:
            continue                                            # a full compartment: no free surface
        Hkk = op.Hs[k][:, k]
        Hkf = fs.Hkf[k][:, f]
        A = sp.bmat([[Hkk, Hkf], [Hkf.T, fs.Hff[f][:, f]]], format="csc")
        B = sp.bmat([[sp.csr_matrix((k.size, k.size)), None], [None, fs.Sff[f][:, f]]], format="csc")
        area, xy0, I_fs = _surface_moments(fs.Sff[f][:, f], fs.coords[f, :2], rho)
        n_null = 0 if fs.pinned[c] else 1
        x0 = np.array([xy0[0], xy0[1], 0.0])
        R = _rigid(op, x0)
        GR = op.G @ R                                          # (n_p, 5): G r over the kept DOFs (eq. 4)
        g_rows = np.vstack([GR[k], fs.Gf[f] @ R])              # (k + f, 5): over both blocks
        sigma = -1e-3 / np.sqrt(area)                         # below lambda_1 ~ xi / R, off the null mode
        want = int(n_modes) + n_null + 2 + (int(n_modes) + 4 if lateral_only else 0)   # 2: room for a partner
        while True:                 # axisymmetric and higher-wave modes lie between the lateral ones
            want = min(want, f.size - 2)
            lam, X = _eigen(A, B, want, sigma, f"liquid {g!r}")
            if n_null:
                if not abs(lam[0]) < 1e-6 * lam[1]:
                    raise InputError(f"liquid {g!r}: the sloshing problem's constant pressure mode was not found "
                                     f"(lowest lambda {lam[0]:.3e} 1/m)")
                lam, X = lam[1:], X[:, 1:]
            X = X / np.sqrt(np.einsum("ij,ij->j", X, B @ X))  # phi^T (S / rho) phi = 1: m_n = beta^2 / lambda (eq. 5)
            beta = X.T @ g_rows                               # (n, 5): x_n^T G r
            Fxy = np.hypot(beta[:, 0], beta[:, 1])
            mass_n = Fxy ** 2 / lam
            keep = mass_n > LATERAL_MASS * rho * op.volumes[g] if lateral_only else np.ones(lam.size, bool)
            idx = np.flatnonzero(keep)
            # the last mode asked for below the highest computed: an equal partner of it is computed too
            if (idx.size >= n_modes and idx[int(n_modes) - 1] < lam.size - 1) or want >= f.size - 2:
                break
            want = 2 * want if idx.size < n_modes else want + 2
        modes = []
        for j in _whole_groups(np.flatnonzero(keep), lam, int(n_modes)):
            d = beta[j, :2] / Fxy[j] if Fxy[j] > 0 else np.array([1.0, 0.0])
            height = (d[0] * beta[j, 4] - d[1] * beta[j, 3]) / Fxy[j] if Fxy[j] > 0 else np.nan
            eta = np.abs(X[k.size:, j]).max() / (rho * gravity)     # eta = p / (rho g_eff) on the surface (eq. 1)
            modes.append(SloshMode(g, float(np.sqrt(gravity * lam[j]) / (2 * np.pi)), float(mass_n[j]),
                                   (float(d[0]), float(d[1])), float(height),
                                   float(abs(beta[j, 2]) / Fxy[j]) if Fxy[j] > 0 else np.inf,
                                   float(eta / Fxy[j]) if Fxy[j] > 0 else np.nan))
        # impulsive mass (p = 0 on the surface: fem.liquid's added mass), this liquid's rows
        on = (op.p_group == c).astype(float)[:, None]
        Mi = (on * GR).T @ op.solve(on * GR)                   # kg: op's H is divided by rho
        m0 = (float(Mi[0, 0]), float(Mi[1, 1]))
        z0 = (Mi[0, 4] / Mi[0, 0] if Mi[0, 0] > 0 else np.nan, -Mi[1, 3] / Mi[1, 1] if Mi[1, 1] > 0 else np.nan)
        out[g] = LiquidSlosh(g, float(gravity), float(rho * op.volumes[g]), np.asarray(op.centroids[g], float).copy(),
                             m0, (float(z0[0]), float(z0[1])), (float(I_fs[0]), float(I_fs[1])), modes)
    if not out and groups is None:
        raise InputError(f"liquid {op.name!r}: no liquid has a free surface to slosh")
    return out


def geometry_slosh(geometry, gravity: float = G0, n_modes: int = 6, degrees=(2,)) -> dict:
    """:func:`slosh_modes` of the hydroelastic liquids of a meshed ``meshes.spec.Geometry``
    (its ``liquids``; each density scaled to the CAD volume's mass as in the structural
    model), with pressure P_k for each k of ``degrees`` on the same mesh (read once), serial:
    {k: {liquid group: LiquidSlosh}}."""
    from mpi4py import MPI

    from .liquid import geometry_liquid_operator
    from .mesh import read_mesh_parts

    if not geometry.liquids:
        raise InputError(f"{geometry.name}: no hydroelastic liquid to slosh (a smeared liquid has no free surface)")
    tm = read_mesh_parts(geometry.msh_path, MPI.COMM_SELF, tuple(geometry.shells), liquids=tuple(geometry.liquids))[2]
    out = {}
    for degree in degrees:
        op = geometry_liquid_operator(tm, geometry, degree)
        try:
            out[degree] = slosh_modes(op, gravity, n_modes)
        finally:
            op.destroy()
    return out


# ---- the slosh modes in a structural model: tank-referenced pendulums ----------------------------
DEFAULT_MODES = 4          # lateral modes per liquid when Liquid.slosh_modes is 0: two pairs in a round tank


@dataclass
class SloshPendulums:
    """Slosh modes of a model's liquids as extra DOFs of its component (``convective =
    "slosh"``; docs/hydro.md, "Slosh in the model"). Pendulum n (mass m_n, length L_n, hinged
    at z_n: fem.slosh's mode n) has its bob at z_n - L_n; its DOF s_n is the bob's lateral
    displacement along d_n, and its spring k_n = m_n omega_n^2 acts on the stretch
    s_n - r_n . x, r_n the tank wall's displacement along d_n at the bob's height (two rings of
    wetted nodes, averaged and interpolated: rigid-body motions of the tank stretch nothing).
    The bobs' masses at z_n - L_n give the liquid's c.g. exactly over all modes
    (sum m_n L_n = rho I_fs, module docstring); the gravity moment F_n L_n of a swinging
    pendulum (the pendulum effect, like the vehicle's own gravity softening) is not in this
    linear, stress-free model."""

    names: tuple               # "liquid:n"
    liquid: tuple              # liquid group of each
    mass: np.ndarray           # (n,) kg
    stiffness: np.ndarray      # (n,) N/m
    direction: np.ndarray      # (n, 2)
    position: np.ndarray       # (n, 3) m: the bob's (x, y on the rings' mean, z_n - L_n)
    R: sp.csr_matrix           # (n, n_dof): r_n
    frequency: np.ndarray      # (n,) Hz (rigid tank, g_eff)
    gravity: dict = field(default_factory=dict)   # liquid group -> g_eff m/s^2
    wave_per_force: np.ndarray | None = None      # (n,) m/N: largest free-surface rise per newton of force

    @property
    def n(self) -> int:
        return int(self.mass.size)

    def carried(self) -> dict:
        """{liquid: ((m_x, m_x z_x), (m_y, m_y z_y))}: what the bobs carry laterally
        (fem.liquid.convective_mass leaves it out of the wall's lumped mass)."""
        out = {}
        for g in dict.fromkeys(self.liquid):
            on = np.array([lq == g for lq in self.liquid])
            wx, wy = self.mass[on] * self.direction[on, 0] ** 2, self.mass[on] * self.direction[on, 1] ** 2
            z = self.position[on, 2]
            out[g] = ((float(wx.sum()), float(wx @ z)), (float(wy.sum()), float(wy @ z)))
        return out

    def augment(self, K: sp.spmatrix, M: sp.spmatrix) -> tuple[sp.csr_matrix, sp.csr_matrix]:
        """K and M over the model's DOFs and then the n bob DOFs:
        K + R^T k R, -R^T k / -k R, k; M, m."""
        k = sp.diags(self.stiffness)
        R = sp.csr_matrix(self.R)
        Ka = sp.bmat([[sp.csr_matrix(K) + R.T @ k @ R, -(R.T @ k)], [-(k @ R), k]], format="csr")
        Ma = sp.bmat([[sp.csr_matrix(M), None], [None, sp.diags(self.mass)]], format="csr")
        return Ka, Ma


def _ring_row(area: np.ndarray, xyz: np.ndarray, z_target: float, d: np.ndarray, Txy: tuple,
              what: str) -> tuple[sp.csr_matrix, np.ndarray]:
    """Row r (1, n_dof) of the wall's displacement along (d, 0) at height ``z_target``: the
    area-weighted means of two rings of wetted nodes (bands at z_target +- a sixth of the
    wetted height, kept inside it), interpolated (or extrapolated) linearly to z_target; and
    the point (x, y, z_target) whose rigid-body displacement r returns exactly. ``Txy``: the
    field map's x and y rows of the wetted nodes (at ``xyz``, nodal areas ``area``)."""
    z = xyz[:, 2]
    lo, hi = float(z.min()), float(z.max())
    span = hi - lo
    if not span > 0:
        raise InputError(f"{what}: the wetted wall has no height to hang a slosh pendulum on")
    delta = span / 6
    centres = np.clip([z_target - delta, z_target + delta], lo + delta / 2, hi - delta / 2)
    if centres[1] - centres[0] < delta:
        centres = (centres[0], centres[0] + delta) if centres[0] + delta <= hi - delta / 2 else (centres[1] - delta, centres[1])
    rings = []
    for c in centres:
        on = np.abs(z - c) <= delta / 2
        if not np.any(on):
            raise InputError(f"{what}: no wetted node within {delta / 2:.3g} m of z = {c:.4g} m (a finer mesh)")
        w = np.zeros(z.size)
        w[on] = area[on] / area[on].sum()
        rings.append(w)
    za, zb = (float(w @ z) for w in rings)
    t = (z_target - za) / (zb - za)
    w = (1 - t) * rings[0] + t * rings[1]                   # sum w = 1, sum w z = z_target
    r = sp.csr_matrix(w[None, :]) @ (d[0] * Txy[0] + d[1] * Txy[1])
    r.eliminate_zeros()
    return sp.csr_matrix(r), np.array([w @ xyz[:, 0], w @ xyz[:, 1], z_target])


def slosh_pendulums(tm, geometry, nodes: np.ndarray, T: sp.csr_matrix, degree: int = 2) -> SloshPendulums:
    """The slosh modes of the liquids of ``geometry`` (its liquid mesh ``tm``, pressure
    P_``degree``; each liquid's ``slosh_modes`` lateral modes, DEFAULT_MODES when 0, at its
    ``gravity``) as tank-referenced pendulums on the structure (``nodes``, field map ``T``)."""
    from scipy.spatial import cKDTree

    from .liquid import geometry_liquid_operator, wetted_nodes

    op = geometry_liquid_operator(tm, geometry, degree)
    tree = cKDTree(nodes)
    Tc = sp.csr_matrix(T)
    rows, names, liquid, mass, k, dirs, pos, freq, grav, wave = [], [], [], [], [], [], [], [], {}, []
    try:
        for g, liq in geometry.liquids.items():
            n = liq.slosh_modes or DEFAULT_MODES
            s = slosh_modes(op, liq.gravity, n, groups=(g,)).get(g) if op.free is not None else None
            if s is None:
                continue
            grav[g] = s.gravity
            node, area = wetted_nodes(tm, liq, g, nodes, tree)
            Txy = (Tc[3 * node], Tc[3 * node + 1])            # the wetted nodes' x, y rows, once per liquid
            for j, md in enumerate(s.modes, 1):
                d = np.array(md.direction, float)
                z_bob = md.height - s.pendulum_length(md)
                r, p = _ring_row(area, nodes[node], z_bob, d, Txy, f"liquid {g!r} slosh mode {j}")
                rows.append(r)
                names.append(f"{g}:{j}")
                liquid.append(g)
                mass.append(md.mass)
                k.append(md.stiffness)
                dirs.append(d)
                pos.append(p)
                freq.append(md.frequency)
                wave.append(md.wave_per_force)
    finally:
        op.destroy()
    if not rows:
        raise InputError(f"model {geometry.name!r}: convective = 'slosh' but no liquid has a free surface")
    return SloshPendulums(tuple(names), tuple(liquid), np.array(mass), np.array(k), np.array(dirs), np.array(pos),
                          sp.vstack(rows, format="csr"), np.array(freq), grav, np.array(wave))


__all__ = ["SloshMode", "LiquidSlosh", "slosh_modes", "geometry_slosh", "G0", "LATERAL_MASS", "SloshPendulums",
           "slosh_pendulums", "DEFAULT_MODES"]
