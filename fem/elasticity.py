"""Linear isotropic elasticity on a tagged mesh: material fields and UFL forms.

Stiffness a(u, v) = int sigma(u) : eps(v) dx, sigma = lambda tr(eps) I + 2 mu eps;
mass m(u, v) = int rho u . v dx (+ non-structural mass per unit area on surfaces);
thermal load L(v) = int (3 lambda + 2 mu) alpha dT div(v) dx (the equivalent nodal forces of a
free thermal strain alpha dT I). SI units: Pa, kg/m^3, 1/K, K.
"""
from __future__ import annotations

import ufl

from liftoff.core.errors import InputError

from .mesh import TaggedMesh


def material_fields(tm: TaggedMesh, volumes: dict) -> tuple:
    """Cell-wise (DG0) E, nu, rho from {volume group name: Material}; every group of the
    mesh needs a material and every named volume must exist in the mesh."""
    from dolfinx import fem

    for name in volumes:
        if name not in tm.volume_ids:
            raise InputError(f"volume group {name!r} is not a physical volume of mesh {tm.path!r} "
                             f"(it has: {', '.join(sorted(tm.volume_ids)) or 'none'})")
    for name in tm.volume_ids:
        if name not in volumes:
            raise InputError(f"physical volume {name!r} of mesh {tm.path!r} has no material")
    for name, mat in volumes.items():
        mat.check(f"volume {name!r}")        # meshes.spec.Material: the one material check
    Q = fem.FunctionSpace(tm.mesh, ("DG", 0))
    fields = {k: fem.Function(Q, name=k) for k in ("E", "nu", "rho")}
    for name, mat in volumes.items():
        dofs = Q.dofmap.list.array[tm.cell_tags.find(tm.volume_ids[name])]  # one DG0 DOF per cell
        for k in fields:
            fields[k].x.array[dofs] = float(getattr(mat, k))
    for f in fields.values():
        f.x.scatter_forward()
    return fields["E"], fields["nu"], fields["rho"]


def lame(E, nu):
    return E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))


def epsilon(u):
    return ufl.sym(ufl.grad(u))


#: Poisson's ratio from which a solid is nearly incompressible (lambda/mu >= 49: a bonded
#: propellant grain, an elastomer): its volumetric term is integrated at one point
NEARLY_INCOMPRESSIBLE_NU = 0.49


def nearly_incompressible(nu) -> bool:
    """Whether any cell of the DG0 field ``nu`` (on any process) is nearly incompressible."""
    from mpi4py import MPI

    local = bool(nu.x.array.size) and float(nu.x.array.max()) >= NEARLY_INCOMPRESSIBLE_NU
    return bool(nu.function_space.mesh.comm.allreduce(local, op=MPI.LOR))


def stiffness_form(V, E, nu):
    """a(u, v) = int 2 mu eps(u) : eps(v) + lambda div u div v dx. Where nu >=
    NEARLY_INCOMPRESSIBLE_NU the volumetric term is integrated at one point (the centroid):
    for P2 tetrahedra div u is linear, its mean is its centroid value, so this is exactly
    the P2-P0 mixed displacement-pressure element with its cell-wise pressure condensed,
    stable as nu -> 1/2 (Boffi, Brezzi & Fortin, Mixed Finite Element Methods, 2013, 8.6);
    fully integrated, P2 locks (tests/fem/test_incompressible.py). Needs degree 2: on P1
    the one-point rule is the full integral, and P1 locks."""
    lmbda, mu = lame(E, nu)
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    eu = epsilon(u)
    if not nearly_incompressible(nu):
        return ufl.inner(lmbda * ufl.tr(eu) * ufl.Identity(3) + 2 * mu * eu, epsilon(v)) * ufl.dx
    if V.ufl_element().degree() < 2:
        raise InputError(f"a nearly incompressible solid (nu >= {NEARLY_INCOMPRESSIBLE_NU}) needs degree 2: "
                         "P1 tetrahedra lock")
    inc = ufl.conditional(ufl.ge(nu, NEARLY_INCOMPRESSIBLE_NU), 1.0, 0.0)
    ev = epsilon(v)
    one_point = ufl.dx(metadata={"quadrature_degree": 1})
    return (2 * mu * ufl.inner(eu, ev) + (1 - inc) * lmbda * ufl.tr(eu) * ufl.tr(ev)) * ufl.dx \
        + inc * lmbda * ufl.tr(eu) * ufl.tr(ev) * one_point


def mass_form(V, rho):
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    return rho * ufl.inner(u, v) * ufl.dx


def surface_mass_form(V, facet_tags, mass_per_area: float):
    """Consistent non-structural mass on the facets tagged 1 in ``facet_tags``."""
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    ds = ufl.Measure("ds", domain=V.mesh, subdomain_data=facet_tags)
    return mass_per_area * ufl.inner(u, v) * ds(1)


def area_form(mesh, facet_tags):
    from dolfinx import fem

    ds = ufl.Measure("ds", domain=mesh, subdomain_data=facet_tags)
    return fem.Constant(mesh, 1.0) * ds(1)


def thermal_load_form(V, E, nu, cell_tags, strain_by_id: dict[int, float]):
    """L(v) = sum_vol int (3 lambda + 2 mu) * (alpha dT)_vol * div(v) dx(vol)."""
    lmbda, mu = lame(E, nu)
    v = ufl.TestFunction(V)
    dx = ufl.Measure("dx", domain=V.mesh, subdomain_data=cell_tags)
    return sum((3 * lmbda + 2 * mu) * float(s) * ufl.div(v) * dx(int(i)) for i, s in strain_by_id.items())
