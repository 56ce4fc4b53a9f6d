"""Linear Reissner-Mindlin shell on a faceted manifold mesh (triangles, tdim 2 in 3-D).

Kinematics (Campello, Pimenta & Wriggers 2003, linearised; the same small-strain model as
the FEniCSx "linear shell" tour): a point at distance zeta from the flat mid-surface
facet moves by ``u + zeta theta x e3``, with ``u`` the mid-surface displacement and
``theta`` the small rotation vector, both in the *global* frame (so shells, solids and
rigid spiders share nodal unknowns without transformations). With the facet frame
(e1, e2, e3), P = [e1 e2] and beta = e3 x theta:

    membrane  eps   = sym(P^T grad(u) P)
    bending   kappa = sym(P^T grad(beta) P)
    shear     gamma = P^T grad(u . e3) - P^T beta
    drilling  varpi = (1/2)(P^T grad(u) P)_[12 - 21] + theta . e3

    W = int  t C:eps:eps + b t^3/12 C:kappa:kappa + k G t gamma.gamma + kd E t^3/h^2 varpi^2  dA

with the plane-stress C = E/(1-nu^2)[(1-nu) sym + nu I x I], G = E/(2(1+nu)), the
Reissner-Mindlin shear factor k = 5/6 and h the cell diameter. b = 12 I / t^3 is the
bending stiffness ratio of Nastran's PSHELL (1 for a homogeneous plate; > 1 for a wall
whose frames and stringers are smeared into its bending stiffness while its membrane
stiffness and mass stay those of the skin). Kinetic energy (consistent
mass) ``int rho t u.u + rho t^3/12 theta.theta dA``: the rotary inertia of the fibre; the
drilling component (theta . e3) is included with the same coefficient so that the mass is
positive definite on every rotation DOF (its energy is (t/h)^2 of the facet's own in-plane
rotary inertia: negligible, and it keeps shift-invert and Craig-Bampton fixed-interface
eigenproblems regular).

Discretisation: continuous P2 displacement and Crouzeix-Raviart (P1, edge-midpoint) rotations
(the "T6-3i" triangle of Campello et al. 2003), full integration. It is free of shear
locking because the discrete Kirchhoff subspace {grad w = theta} stays rich: grad w of a P2
w is piecewise P1 with a continuous tangential component, so the constraint only asks for
a continuous normal slope at each edge midpoint (one condition per edge), which leaves
about one Kirchhoff DOF per vertex (P1/P1 or P2/P2 pairs under full integration have
almost none and lock; reduced one-point shear integration of this pair has spurious
zero-energy modes). Measured (tests/fem/test_shell_plate.py): the error of a clamped plate
is the same for t/L = 1e-4 and 1e-5 and converges at second order. Membrane locking is
absent on flat facets (membrane and bending do not couple inside an element; curvature
enters at the kinks through the facet-wise e3); coarse meshes of the pinched hemisphere
are stiff and converge from below. Accuracy: about 20 elements per circumferential
wavelength give frequencies within 1 % (tests/fem/test_shell_cylinder_vibration.py).
Drilling stabilisation kd E t^3 / h^2 (kd = 1 by default): the value recommended in the
literature for faceted shells (a membrane stiffness E t scaled by (t/h)^2, so it vanishes
relative to membrane and bending as the shell thins); the drilling rotation is needed at
kinks, where one facet's drilling rotation is the neighbour's bending rotation.

The normal e3 = t1 x t2 / |.| comes from the cell Jacobian, e1 = t1/|t1|, e2 = e3 x e1: the
isotropic energies above do not depend on the in-plane orientation of the frame or on the
sign of e3 (flipping e3 flips e2, kappa's diagonal, gamma and varpi together), so no
consistently oriented normal field is needed (closed, non-orientable or branching
surfaces work). Units SI: m, Pa, kg/m^3.

Tests: tests/fem/test_shell_*.py (Scordelis-Lo roof, pinched cylinder, pinched hemisphere,
thin clamped plate, free vibration of a simply supported cylinder).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import ufl

from liftoff.core.errors import InputError

SHEAR_FACTOR = 5.0 / 6.0
DRILLING_FACTOR = 1.0


@dataclass
class ShellFields:
    """Cell-wise (DG0) shell properties: E (Pa), nu, rho (kg/m^3), thickness t (m) and the
    bending stiffness ratio b = 12 I / t^3 (1: homogeneous plate)."""

    E: object
    nu: object
    rho: object
    t: object
    bend: object = 1.0


def shell_fields(tm, materials: dict, thickness: dict, bending: dict | None = None) -> ShellFields:
    """Cell-wise E, nu, rho, t and b of a shell TaggedMesh from {shell group: Material},
    {shell group: thickness (m)} (every shell group needs both) and {shell group: 12 I/t^3}
    (default 1)."""
    from dolfinx import fem

    Q = fem.FunctionSpace(tm.mesh, ("DG", 0))
    out = {k: fem.Function(Q, name=k) for k in ("E", "nu", "rho", "t", "bend")}
    bending = bending or {}
    for name, gid in tm.volume_ids.items():
        if name not in materials or name not in thickness:
            raise InputError(f"shell surface {name!r} of mesh {tm.path!r} needs a material and a thickness")
        mat, t, b = materials[name], float(thickness[name]), float(bending.get(name, 1.0))
        mat.check(f"shell surface {name!r}")       # meshes.spec.Material: the one material check
        if not np.isfinite(t) or t <= 0:
            raise InputError(f"shell surface {name!r}: thickness {t!r} m must be > 0")
        if not np.isfinite(b) or b <= 0:
            raise InputError(f"shell surface {name!r}: bending ratio 12I/t^3 = {b!r} must be > 0")
        dofs = Q.dofmap.list.array[tm.cell_tags.find(gid)]
        for k, v in (("E", mat.E), ("nu", mat.nu), ("rho", mat.rho), ("t", t), ("bend", b)):
            out[k].x.array[dofs] = float(v)
    for f in out.values():
        f.x.scatter_forward()
    return ShellFields(out["E"], out["nu"], out["rho"], out["t"], out["bend"])


def shell_element(cell) -> ufl.MixedElement:
    """P2 displacement x Crouzeix-Raviart rotation, both 3-component (global frame)."""
    return ufl.MixedElement([ufl.VectorElement("CG", cell, 2, dim=3), ufl.VectorElement("CR", cell, 1, dim=3)])


def shell_space(mesh):
    """The mixed function space (u, theta) on a triangle mesh embedded in 3-D."""
    from dolfinx import fem

    if mesh.topology.dim != 2 or mesh.geometry.dim != 3:
        raise InputError(f"shell mesh must be triangles in 3-D (got tdim {mesh.topology.dim}, "
                         f"gdim {mesh.geometry.dim})")
    return fem.FunctionSpace(mesh, shell_element(mesh.ufl_cell()))


def _tangents(mesh):
    """(t1, t2) = (x_,1, x_,2): the columns of the facet's Jacobian (its parametrisation)."""
    J = ufl.Jacobian(mesh)
    return ufl.as_vector([J[0, 0], J[1, 0], J[2, 0]]), ufl.as_vector([J[0, 1], J[1, 1], J[2, 1]])


def local_frame(mesh):
    """(e1, e2, e3) of each flat facet as UFL vectors (see the module docstring)."""
    t1, t2 = _tangents(mesh)
    e3 = ufl.cross(t1, t2)
    e3 = e3 / ufl.sqrt(ufl.dot(e3, e3))
    e1 = t1 / ufl.sqrt(ufl.dot(t1, t1))
    return e1, ufl.cross(e3, e1), e3


def _in_plane(frame):
    e1, e2, _ = frame
    return ufl.as_matrix([[e1[i], e2[i]] for i in range(3)])     # 3 x 2


def _surface_gradient(u, P):
    """P^T grad(u) P: the in-plane (2 x 2, facet frame) gradient of the translations u."""
    return ufl.dot(P.T, ufl.dot(ufl.grad(u), P))


def strains(u, theta, frame):
    """(eps, kappa, gamma, varpi): membrane, bending, transverse shear, drilling."""
    e3 = frame[2]
    P = _in_plane(frame)
    gu = _surface_gradient(u, P)
    beta = ufl.cross(e3, theta)
    eps = ufl.sym(gu)
    kappa = ufl.sym(ufl.dot(P.T, ufl.dot(ufl.grad(beta), P)))
    gamma = ufl.dot(ufl.grad(ufl.dot(u, e3)), P) - ufl.dot(P.T, beta)
    varpi = 0.5 * (gu[0, 1] - gu[1, 0]) + ufl.dot(theta, e3)
    return eps, kappa, gamma, varpi


def _plane_stress(E, nu, e):
    return E / (1 - nu ** 2) * ((1 - nu) * e + nu * ufl.tr(e) * ufl.Identity(2))


def stiffness_form(W, f: ShellFields, drilling: float = DRILLING_FACTOR, dx=None):
    """Bilinear form of the shell strain energy (module docstring)."""
    mesh = W.mesh
    frame = local_frame(mesh)
    u, theta = ufl.split(ufl.TrialFunction(W))
    v, eta = ufl.split(ufl.TestFunction(W))
    eu, ku, gu, du = strains(u, theta, frame)
    ev, kv, gv, dv = strains(v, eta, frame)
    G = f.E / (2 * (1 + f.nu))
    h = ufl.CellDiameter(mesh)
    dx = dx or ufl.dx(domain=mesh)
    return (f.t * ufl.inner(_plane_stress(f.E, f.nu, eu), ev)
            + f.bend * f.t ** 3 / 12 * ufl.inner(_plane_stress(f.E, f.nu, ku), kv)
            + SHEAR_FACTOR * G * f.t * ufl.dot(gu, gv)
            + drilling * f.E * f.t ** 3 / h ** 2 * du * dv) * dx


def mass_form(W, f: ShellFields, dx=None):
    """Consistent mass with rotary inertia rho t^3/12 (module docstring)."""
    u, theta = ufl.split(ufl.TrialFunction(W))
    v, eta = ufl.split(ufl.TestFunction(W))
    dx = dx or ufl.dx(domain=W.mesh)
    return (f.rho * f.t * ufl.dot(u, v) + f.rho * f.t ** 3 / 12 * ufl.dot(theta, eta)) * dx


def surface_mass_form(W, mass_per_area, dx):
    """Non-structural (smeared) mass on the cells of measure ``dx``: translations only."""
    u, _ = ufl.split(ufl.TrialFunction(W))
    v, _ = ufl.split(ufl.TestFunction(W))
    return mass_per_area * ufl.dot(u, v) * dx


def load_form(W, traction, dx=None):
    """L(v) = int q . v dA for a distributed force per unit area ``q`` (N/m^2, global frame)."""
    v, _ = ufl.split(ufl.TestFunction(W))
    dx = dx or ufl.dx(domain=W.mesh)
    return ufl.dot(traction, v) * dx


def thermal_load_form(W, f: ShellFields, cell_tags, strain_by_id: dict[int, float]):
    """Equivalent forces of a free in-plane thermal strain (alpha dT, isotropic, uniform
    through the thickness) per shell group id: L(v) = sum int t E/(1-nu) strain tr(eps(v)) dA."""
    v, eta = ufl.split(ufl.TestFunction(W))
    ev, _, _, _ = strains(v, eta, local_frame(W.mesh))
    dx = ufl.Measure("dx", domain=W.mesh, subdomain_data=cell_tags)
    return sum(f.t * f.E / (1 - f.nu) * float(s) * ufl.tr(ev) * dx(int(i)) for i, s in strain_by_id.items())


def membrane_resultants(u, f: ShellFields, mesh):
    """Membrane stress resultants N = t C eps(u) (2 x 2, N/m, facet frame) of the
    translations ``u`` (the prestress of :func:`geometric_stiffness_form`)."""
    return f.t * _plane_stress(f.E, f.nu, ufl.sym(_surface_gradient(u, _in_plane(local_frame(mesh)))))


def geometric_stiffness_form(W, N0, dx=None):
    """Initial-stress (geometric) stiffness of the membrane prestress ``N0`` (2 x 2, N/m, facet
    frame): K_G(u, v) = int N0_ab (du/ds_a) . (dv/ds_b) dA, with d/ds_a = grad . P e_a the
    tangential derivatives of all three translations (the second-order membrane strain of
    a plate or shell under initial stress; Cook, Malkus, Plesha & Witt, Concepts and
    Applications of FE Analysis, 4th ed., sect. 18.2; bending and shear prestress left
    out). N0 > 0 is tension and stiffens."""
    P = _in_plane(local_frame(W.mesh))
    u, _ = ufl.split(ufl.TrialFunction(W))
    v, _ = ufl.split(ufl.TestFunction(W))
    dx = dx or ufl.dx(domain=W.mesh)
    return ufl.inner(ufl.dot(ufl.dot(ufl.grad(u), P), N0), ufl.dot(ufl.grad(v), P)) * dx


def _outward(mesh, center):
    """The facet normal e3 turned outwards from ``center`` (convex surface around it)."""
    e3 = local_frame(mesh)[2]
    x = ufl.SpatialCoordinate(mesh)
    c = ufl.as_vector([float(v) for v in center])
    return ufl.sign(ufl.dot(e3, x - c)) * e3, x - c


def pressure_load_form(W, pressure: float, center, dx):
    """L(v) = int p n . v dA: a uniform gauge pressure ``pressure`` (Pa) inside the closed
    surface of measure ``dx`` around ``center`` (n outward), pushing the wall out."""
    n, _ = _outward(W.mesh, center)
    v, _ = ufl.split(ufl.TestFunction(W))
    return float(pressure) * ufl.dot(n, v) * dx


def volume_hessian_form(W, center, dx):
    """Second variation d^2V[u, v] of the volume enclosed by the closed surface of measure
    ``dx`` (convex around ``center``) in the translations u, v: with x(xi) the facet
    parametrisation (x_,a = J e_a) and V = 1/3 int x . (x_,1 x x_,2) dxi,

        d^2V[u, v] = 1/3 int [u.(v_,1 x X_,2 + X_,1 x v_,2) + v.(u_,1 x X_,2 + X_,1 x u_,2)
                              + X.(u_,1 x v_,2 + v_,1 x u_,2)] dxi,

    X measured from ``center`` (on a closed surface the result does not depend on the
    origin; the centre keeps round-off small). The load stiffness of a uniform follower
    pressure p is -p d^2V (Hibbitt, Int. J. Solids Struct. 1979; Bonet & Wood, Nonlinear
    Continuum Mechanics for FEA, sect. 8.3.3): with it, K + K_G + K_L of a pressurised
    closed vessel leaves rigid rotations free."""
    mesh = W.mesh
    n, X = _outward(mesh, center)
    t1, t2 = _tangents(mesh)
    area = ufl.cross(t1, t2)
    orient = ufl.sign(ufl.dot(area, n))          # +1 where (t1, t2) already runs outwards
    jac = ufl.sqrt(ufl.dot(area, area))          # dA = jac dxi
    u, _ = ufl.split(ufl.TrialFunction(W))
    v, _ = ufl.split(ufl.TestFunction(W))
    u1, u2 = ufl.dot(ufl.grad(u), t1), ufl.dot(ufl.grad(u), t2)
    v1, v2 = ufl.dot(ufl.grad(v), t1), ufl.dot(ufl.grad(v), t2)
    integrand = (ufl.dot(u, ufl.cross(v1, t2) + ufl.cross(t1, v2)) + ufl.dot(v, ufl.cross(u1, t2) + ufl.cross(t1, u2))
                 + ufl.dot(X, ufl.cross(u1, v2) + ufl.cross(v1, u2)))
    return orient / 3.0 * integrand / jac * dx


def dof_table(W) -> tuple[np.ndarray, np.ndarray]:
    """Coordinates (n, 3) and component (n,) 0..5 = Tx..Rz of this rank's DOFs of the mixed
    space (owned and ghost, local numbering; the rotation DOFs sit at edge midpoints)."""
    imap = W.dofmap.index_map
    n = imap.size_local + imap.num_ghosts
    coords = np.full((n, 3), np.nan)
    comp = np.full(n, -1, dtype=np.int64)
    for s in (0, 1):
        S, parent = W.sub(s).collapse()
        parent = np.asarray(parent, dtype=np.int64).reshape(-1, 3)   # (blocks, 3)
        X = S.tabulate_dof_coordinates()[: parent.shape[0]]
        for c in range(3):
            coords[parent[:, c]] = X
            comp[parent[:, c]] = 3 * s + c
    if np.any(comp < 0):
        raise RuntimeError("shell dof table: unmapped DOFs")
    return coords, comp
