"""Properties of the shell element (liftoff.fem.shell) that hold exactly, whatever the mesh:
rigid-body motions cost no energy and nothing else does (drilling stabilised), the mass
matrix integrates rho t and rho t^3/12 exactly, and the energy does not depend on the
orientation of the cells' normals (closed and branching surfaces need no oriented mesh).
"""
import numpy as np
import pytest
import scipy.linalg as sla
import ufl

from liftoff.core.rigid import dof_rb

from .shell_cases import ShellCase, param_grid

pytestmark = pytest.mark.fem
E, NU, T, RHO = 70e9, 0.3, 0.02, 2700.0


def _curved_patch(flip: bool = False, n: int = 4):
    """A doubly curved, irregular patch (no symmetry that could hide a wrong term)."""
    g, cells = param_grid(n, n)
    rng = np.random.default_rng(1)
    g[:, :] += np.where((g > 0) & (g < 1), 0.15 / n * rng.uniform(-1, 1, g.shape), 0.0)
    X = np.column_stack([g[:, 0], 0.7 * g[:, 1], 0.3 * g[:, 0] ** 2 - 0.2 * g[:, 1] ** 2 + 0.1 * g[:, 0] * g[:, 1]])
    if flip:
        cells = cells.copy()
        cells[::2] = cells[::2, ::-1]                     # every other normal reversed
    return ShellCase(X, cells, E, NU, T, rho=RHO)


def test_rigid_body_modes_exact_and_no_spurious_zero_energy_modes():
    case = _curved_patch()
    RB = dof_rb(case.coords - case.coords.mean(axis=0), case.comp)
    K = case.K.toarray()
    assert np.abs(K @ RB).max() < 1e-9 * np.abs(K).max()
    lam_m = sla.eigh(K, case.M.toarray(), eigvals_only=True)
    print(f"lowest eigenvalues of (K, M): {lam_m[:8]}, median {np.median(lam_m):.3g}")
    # exactly six zero-energy modes (round-off ~ eps * lambda_max ~ 1e-5): the seventh is the
    # first bending mode of the free patch (measured 2.8e5 rad^2/s^2, 84 Hz; a thin-plate
    # estimate for a 1 m x 0.7 m x 20 mm aluminium plate gives ~100 Hz), not a drilling or
    # hourglass mode at round-off level
    assert np.all(np.abs(lam_m[:6]) < 1e-8 * lam_m[6])
    assert lam_m[6] > 1e5


def test_mass_integrates_translation_and_rotary_inertia():
    from dolfinx import fem

    case = _curved_patch()
    M = case.M.toarray()
    area = fem.assemble_scalar(fem.form(fem.Constant(case.mesh, 1.0) * ufl.dx(domain=case.mesh)))
    for c in range(3):
        e = (case.comp == c).astype(float)
        assert e @ M @ e == pytest.approx(RHO * T * area, rel=1e-12)
        r = (case.comp == 3 + c).astype(float)
        assert r @ M @ r == pytest.approx(RHO * T ** 3 / 12 * area, rel=1e-12)
        assert abs(e @ M @ r) < 1e-14 * RHO * T * area


def test_energy_independent_of_normal_orientation():
    a, b = _curved_patch(), _curved_patch(flip=True)
    pa, pb = (np.lexsort(np.column_stack([np.round(c.coords, 12), c.comp]).T) for c in (a, b))
    assert np.allclose(a.coords[pa], b.coords[pb]) and np.array_equal(a.comp[pa], b.comp[pb])
    Ka, Kb = a.K[pa][:, pa], b.K[pb][:, pb]               # the same DOF order in both
    assert abs(Ka - Kb).max() < 1e-10 * abs(Ka).max()
