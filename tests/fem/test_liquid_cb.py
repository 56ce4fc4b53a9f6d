"""Craig-Bampton reduction of a hydroelastic component (issue 10): the fixed-interface modes
and the CB mass include the liquid's added mass (Psi^T (M + M_a) Psi), the constraint modes
stay static, and the liquid's recovery rows ride along.

References, independent of the CB code: the full model's wet eigensolve (fem.liquid, SLEPc
with M + M_a as a shell operator) and closed forms (the liquid's axial mass rho V and its
head rho g h, exact on the mesh; fem/liquid.py)."""
from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI

pytestmark = pytest.mark.fem
pytest.importorskip("gmsh")

RHO = 1141.0


@pytest.fixture(scope="module")
def tank(tmp_path_factory):
    from liftoff.fem import build_model
    from liftoff.meshes.tank import Compartment, TankParams, build_tank
    from liftoff.reduction import Component
    from liftoff.reduction.liquid import LiquidMass

    p = TankParams(radius=1.0, wall_thickness=0.1, compartments=(Compartment("lox", 1.5, 0.72, 1.6, 0.5, RHO),),
                   patches={"bot": (0, 0, 0), "top": (0, 0, 0.72 + 1.5 + 1.6)}, patch_half_width=0.3,
                   mesh_size=0.35, liquid="hydroelastic")
    g = build_tank(p, tmp_path_factory.mktemp("tankcb"))
    m = build_model(g)
    comp = Component(name="tank", **m.component_fields(), liquid=LiquidMass(**m.liquid_fields()))
    return p, g, m, comp


def _wet_modes(m, keep_free, n):
    """Full-model wet eigenpairs with every labelled DOF fixed except ``keep_free``."""
    from liftoff.fem import petsc_backend as pb
    from liftoff.fem.liquid import wet_eigensolve

    K, M = m.matrices()
    fixed = np.setdiff1d(m.label_dofs, keep_free)
    inner = np.setdiff1d(np.arange(m.n_dof), fixed)
    Ki, Mi = (pb.csr_matrix(MPI.COMM_SELF, inner.size, inner.size, inner.size, A[inner][:, inner]) for A in (K, M))
    return wet_eigensolve(Ki, Mi, [m.liquid], n, dofs=inner)[0]


@pytest.mark.parametrize("which", ["petsc", "petsc-slepc", "scipy"])
def test_fixed_interface_modes_include_the_liquid(tank, which):
    from liftoff.fem import petsc_solver
    from liftoff.reduction import craig_bampton

    _, _, m, comp = tank
    solver = {"petsc": petsc_solver(), "petsc-slepc": petsc_solver(eigensolver="slepc"), "scipy": None}[which]
    cb = craig_bampton(comp, comp.dof_labels, n_modes=10, solver=solver)
    ref = _wet_modes(m, np.zeros(0, np.int64), 10)
    assert cb.fixed_omega ** 2 == pytest.approx(ref, rel=1e-7)
    # the liquid's recovery items
    assert {it.name for it in cb.recovery} == {"ullage_volume", "liquid_pressure", "liquid_axial_inertia"}


@pytest.mark.parametrize("which", ["petsc", "scipy"])
def test_band_counts_wet_modes(tank, which):
    """f_max band: the wet modes below it (the PETSc solver counts them by the inertia of the
    augmented matrix, fem.liquid.count_below_wet; scipy grows its Krylov basis)."""
    from liftoff.fem import petsc_solver
    from liftoff.reduction import craig_bampton

    _, _, m, comp = tank
    ref = np.sqrt(_wet_modes(m, np.zeros(0, np.int64), 10)) / (2 * np.pi)
    f_max = 0.5 * (ref[6] + ref[7])
    cb = craig_bampton(comp, comp.dof_labels, f_max=f_max, solver=petsc_solver() if which == "petsc" else None)
    assert cb.n_modes == 7


def test_cb_mass_carries_the_liquid(tank):
    """Rigid-body mass of the CB model = structure + liquid along the axis (exact: the
    constraint modes hold the rigid-body motions and the axial added mass is rho V); the
    liquid's axial inertia and bottom head recovered through the CB rows under rigid motion."""
    from liftoff.meshes.tank import inner_cavities
    from liftoff.reduction import craig_bampton

    p, g, m, comp = tank
    cb = craig_bampton(comp, comp.dof_labels, n_modes=10)
    RB = m.rigid_body_shape()
    K, M = m.matrices()
    m_struct = (RB[:, 2] @ (M @ RB[:, 2]))
    m_liquid = RHO * g.group_volumes["tank_lox_liquid"]
    x_b = np.array([1.0 if lab.endswith(":Tz") else 0.0 for lab in cb.boundary_labels])
    x = np.concatenate([np.zeros(cb.n_modes), x_b])             # rigid axial translation in CB DOFs
    assert x @ cb.M @ x == pytest.approx(m_struct + m_liquid, rel=1e-10)
    assert np.abs(cb.K @ x).max() < 1e-6 * np.abs(cb.K).max()
    rec = {it.name: it for it in cb.recovery}
    assert rec["liquid_axial_inertia"].acc @ x == pytest.approx([m_liquid], rel=1e-10)
    cav = inner_cavities(p)[0]
    rho = m.liquid.density["tank_lox_liquid"]
    assert rec["liquid_pressure"].acc @ (9.80665 * x) == pytest.approx([rho * 9.80665 * (cav.z_fill - cav.z_bottom)],
                                                                       rel=1e-10)
    assert np.abs(rec["ullage_volume"].disp @ x).max() < 1e-12


def test_cb_reproduces_the_wet_model_with_a_free_interface(tank):
    """The top patch left free: eigenvalues of the CB model (bot fixed) against the full wet
    model (bot fixed), 30 fixed-interface modes: this checks the coupling C_M = Phi^T (M + M_a)
    Psi and M_B = Psi^T (M + M_a) Psi. Measured +2.8e-5 .. +3.1e-5 for the first three (a CB
    model converges from above)."""
    from liftoff.reduction import craig_bampton

    _, _, m, comp = tank
    cb = craig_bampton(comp, comp.dof_labels, n_modes=30)
    keep = np.concatenate([np.arange(cb.n_modes),
                           cb.n_modes + np.flatnonzero([lab.startswith("top:") for lab in cb.boundary_labels])])
    import scipy.linalg as sla

    lam = sla.eigh(cb.K[np.ix_(keep, keep)], cb.M[np.ix_(keep, keep)], eigvals_only=True)[:3]
    top = np.array([m.dof_index(f"top:{c}") for c in ("Tx", "Ty", "Tz", "Rx", "Ry", "Rz")])
    ref = _wet_modes(m, top, 3)
    assert np.all(lam >= ref * (1 - 1e-9))
    assert lam == pytest.approx(ref, rel=3e-4)


@pytest.mark.slow
def test_two_ranks_match_serial(tank):
    """mpirun -n 2: the structure distributed, the liquid held whole on every rank (fem.model):
    the same wet fixed-interface frequencies (SLEPc tolerance 1e-10), liquid mass, head and
    cavity volume row as one rank."""
    from .test_mpi import _run

    _, g, _, _ = tank
    path = str(g.save(Path(g.msh_path).with_suffix(".json")))
    serial, parallel = _run(1, path, 1, "mpi_liquid_script.py"), _run(2, path, 1, "mpi_liquid_script.py")
    assert parallel["size"] == 2 and parallel["n_p"] == serial["n_p"]
    assert np.allclose(parallel["freq"], serial["freq"], rtol=1e-8)
    for k in ("axial", "head", "dv"):
        assert np.allclose(parallel[k], serial[k], rtol=1e-9), k


def test_convective_wall_gives_a_rigid_liquid_mass_and_cg(tank):
    """convective = "wall": the liquid's sloshing part lumped laterally on the wetted wall
    (fem.liquid.convective_mass). Through the CB model, the liquid's 6x6 rigid-body mass
    (CB rigid-body mass minus the structure's) has the liquid's mass rho V in all three
    directions and its c.g. height (the mesh centroid) to round-off; the lateral c.g. is the
    axis within 1e-4 m (mesh asymmetry of the lateral weights)."""
    from liftoff.fem import build_model
    from liftoff.reduction import Component, craig_bampton
    from liftoff.reduction.liquid import LiquidMass

    from liftoff.core.labels import split_label
    from liftoff.core.rigid import cg_mass, dof_rb

    _, g, m_free, _ = tank
    m = build_model(g, convective="wall")
    comp = Component(name="tank", **m.component_fields(), liquid=LiquidMass(**m.liquid_fields()))
    cb = craig_bampton(comp, comp.dof_labels, n_modes=6)
    pts = [split_label(lab) for lab in cb.boundary_labels]
    rb_b = dof_rb(np.array([cb.point_coord(p) for p, _ in pts]), np.array([k for _, k in pts]))
    x = np.vstack([np.zeros((cb.n_modes, 6)), rb_b])
    RB = m_free.rigid_body_shape()
    _, M_struct = m_free.matrices()
    mp = cg_mass(x.T @ cb.M @ x - RB.T @ (M_struct @ RB))
    mass = RHO * g.group_volumes["tank_lox_liquid"]
    assert mp.mass_xyz == pytest.approx([mass] * 3, rel=1e-9)
    assert mp.cg[2] == pytest.approx(m.liquid.centroid[2], rel=1e-9)
    assert np.abs(mp.cg[:2]).max() < 1e-4
    # a lateral mass can only lower the modes (Rayleigh)
    free = craig_bampton(Component(name="t", **m_free.component_fields(), liquid=LiquidMass(**m_free.liquid_fields())),
                         comp.dof_labels, n_modes=6)
    assert cb.fixed_freq_hz[0] <= free.fixed_freq_hz[0] * (1 + 1e-9)


def test_convective_bad_value():
    from liftoff.fem import build_model

    from liftoff.core.errors import InputError

    with pytest.raises(InputError, match="convective"):
        build_model("nowhere.json", convective="glued")
