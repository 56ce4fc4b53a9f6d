"""Pressure stiffening in a model (fem.prestress through fem.model.build_model): a shell tank
with a hydroelastic liquid and ullage pressure, free-free with two reference points.

Checks: K annihilates the rigid-body shape (six exactly free rigid modes), the pressure
raises the lowest fixed-interface (lobar) frequencies, the mass is untouched, the
relative-to-reference update leaves an elastic K as it is, and bad input is refused in one
line. The element-level physics (K_G vs Flügge with initial stress, K_L vs the enclosed
volume, membrane forces pR and pR/2) is tests/fem/test_shell_prestress.py."""
import numpy as np
import pytest

pytestmark = pytest.mark.fem
pytest.importorskip("gmsh")

P_ULLAGE = 2.0e5      # Pa: N_th = p R = 2e5 N/m on a 1 m radius, 3 mm wall


def _params(pressure: float, walls: str = "shell"):
    from liftoff.meshes.tank import Compartment, TankParams

    return TankParams(radius=1.0, wall_thickness=0.1, compartments=(
        Compartment("lox", 2.0, 0.72, 1.0, 0.6, 1141.0, ullage_pressure=pressure),),
        patches={"bot": (0, 0, 0), "top": (0, 0, 0.72 + 2.0 + 1.0)}, patch_half_width=0.3, dry_mass=300.0,
        mesh_size=0.3, liquid="hydroelastic", walls=walls)


@pytest.fixture(scope="module")
def tanks(tmp_path_factory):
    from liftoff.fem import build_model
    from liftoff.meshes.tank import build_tank

    out = {}
    for p in (0.0, P_ULLAGE):
        out[p] = build_model(build_tank(_params(p), tmp_path_factory.mktemp(f"ptank{int(p)}")), convective="wall")
    return out


def _cb(m):
    from liftoff.fem import petsc_solver
    from liftoff.reduction import Component, craig_bampton
    from liftoff.reduction.liquid import LiquidMass

    comp = Component(name="tank", **m.component_fields(), liquid=LiquidMass(**m.liquid_fields()))
    return craig_bampton(comp, comp.dof_labels, n_modes=6, solver=petsc_solver())


def test_rigid_modes_stay_free_and_lobar_modes_stiffen(tanks):
    import scipy.linalg as la

    bare, pressed = tanks[0.0], tanks[P_ULLAGE]
    K, M = pressed.matrices()
    rb = pressed.rigid_body_shape(pressed.point_coords[0])
    # K RB = 0 up to round-off of K's entries times the rigid shape (lever arms ~ 4 m)
    assert np.abs(K @ rb).max() < 1e-9 * np.abs(K).max() * 4.0
    assert abs(M - bare.matrices()[1]).max() < 1e-12 * abs(M).max()      # the pressure adds no mass
    cb0, cb1 = _cb(bare), _cb(pressed)
    gain = cb1.fixed_freq_hz[:4] / cb0.fixed_freq_hz[:4]
    print("fixed-interface Hz bare", np.round(cb0.fixed_freq_hz[:6], 3), "pressurised", np.round(cb1.fixed_freq_hz[:6], 3))
    assert np.all(gain > 1.05)
    w2 = la.eigh(cb1.K, cb1.M, eigvals_only=True)
    # six rigid modes: zero to the round-off of the reduced K (its largest entry ~ (2 pi f_max)^2)
    assert np.all(np.abs(w2[:6]) < 1e-8 * np.abs(w2).max()) and w2[6] > (2 * np.pi * 1.0) ** 2


def test_relative_to_reference_leaves_an_elastic_stiffness_alone(tanks):
    from liftoff.fem import petsc_backend as pb
    from liftoff.fem.prestress import relative_to_reference

    m = tanks[0.0]
    K0 = m.matrices()[0]
    rb = m.rigid_body_shape(m.point_coords[0])
    K1 = pb.gather_csr(relative_to_reference(m.K.copy(), rb, m.ref_first_dof + np.arange(6)))
    assert abs(K1 - K0).max() < 1e-9 * abs(K0).max()


def test_bad_pressures(tmp_path):
    from liftoff.core.errors import InputError
    from liftoff.meshes.spec import Liquid

    with pytest.raises(InputError, match=r"lox.ullage_pressure: the pressure prestress needs walls = 'shell'"):
        _params(P_ULLAGE, walls="solid").check()
    with pytest.raises(InputError, match=r"ullage_pressure -1.0 Pa must be >= 0"):
        Liquid(1000.0, "w", "f", "c", ullage_pressure=-1.0)
    with pytest.raises(InputError, match=r"ullage_pressure needs the cavity"):
        Liquid(1000.0, "w", "f", None, ullage_pressure=1.0)
    with pytest.raises(InputError, match=r"ullage_pressure must be a gauge pressure"):
        _params(float("nan")).check()


def test_a_cavity_present_but_empty_in_the_shell_part_is_refused():
    """With solids and shells in one mesh every surface name is listed in each part, with no
    facets in the part it does not touch: a cavity of solid faces was 'present but empty' in
    the shell part, and its ullage pressure gave a zero load and no prestress, without a word
    (a review, 2026-12-07). Refused as a cavity that is not a shell surface."""
    from types import SimpleNamespace

    from mpi4py import MPI

    from liftoff.core.errors import InputError
    from liftoff.fem.prestress import _cavity_measure
    from liftoff.meshes.spec import Liquid

    empty = SimpleNamespace(values=np.zeros(0, np.int32), indices=np.zeros(0, np.int32))
    part = SimpleNamespace(tagged=SimpleNamespace(surface_tags={"c": empty}, mesh=SimpleNamespace(comm=MPI.COMM_SELF)))
    with pytest.raises(InputError, match=r"its cavity 'c' is not a shell surface"):
        _cavity_measure(part, Liquid(1000.0, "w", "f", "c", ullage_pressure=2e5), "lox")
