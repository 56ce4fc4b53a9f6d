"""Mesh convergence of FE frequencies against closed forms / an independent beam theory.

Each test refines three or more meshes, prints the observed order and checks it against
the expected rate, and checks the finest mesh against the reference with a tolerance
justified below. nu = 0 where it makes the 3-D solid match the 1-D theory exactly.
"""
import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as sla

from liftoff.fem import build_model, eigenmodes
from liftoff.meshes.spec import Geometry, Material

pytestmark = pytest.mark.fem
E, RHO = 2.0e11, 7800.0
MAT0 = Material("steel_nu0", E, 0.0, RHO)


def _dominant_share(model, modes, j, axis):
    u = model.nodal_displacement(modes.shapes[:, j])
    return np.linalg.norm(u[:, axis]) / np.linalg.norm(u)


def _orders(err, ratio=2.0):
    err = np.abs(np.asarray(err))
    return np.log(err[:-1] / err[1:]) / np.log(ratio)


def test_axial_rod_modes_converge_at_second_order_p1(msh):
    """Free-free bar, nu = 0: u = cos(pi x / L) e_x is an exact 3-D mode, f1 = c / (2 L)."""
    L, a = 1.0, 0.05
    f_exact = np.sqrt(E / RHO) / (2 * L)
    err = []
    for n in (4, 8, 16, 32):
        model = build_model(Geometry("rod", msh("box", L=L, W=a, H=a, n=(n, 1, 1)), {"solid": MAT0}), degree=1)
        modes = eigenmodes(model, n_modes=16)
        assert modes.n_rigid == 6
        axial = [j for j in range(6, 16) if _dominant_share(model, modes, j, 0) > 0.99]
        err.append(modes.freq_hz[axial[0]] / f_exact - 1)
    p = _orders(err)
    print(f"axial rod P1: relative errors {np.array(err)}, observed orders {p}")
    # P1 elements: eigenvalue (and frequency) error O(h^2)
    assert np.all(p > 1.8) and np.all(p < 2.4)
    # finest (32 elements along L): (pi h / L)^2 / 12-type error ~ 1e-3 * (1/4)^... measured 3.4e-4
    assert abs(err[-1]) < 5e-4


def timoshenko_free_free(L, a, nu, n_el=2000, n_modes=2):
    """Bending frequencies (Hz) of a free-free square Timoshenko beam (kappa = 10(1+nu)/(12+11nu),
    Cowper), by an independent 1-D FE: linear w and theta, one-point shear integration
    (no locking), consistent mass with rotary inertia; n_el = 2000 converges it to ~1e-6."""
    G = E / (2 * (1 + nu))
    kappa = 10 * (1 + nu) / (12 + 11 * nu)
    A, I, le = a * a, a ** 4 / 12, L / n_el
    Kb = E * I / le * np.array([[0, 0, 0, 0], [0, 1, 0, -1], [0, 0, 0, 0], [0, -1, 0, 1.0]])
    b = np.array([-1 / le, -0.5, 1 / le, -0.5])
    Ke = Kb + kappa * G * A * le * np.outer(b, b)
    Me = np.zeros((4, 4))
    Me[np.ix_([0, 2], [0, 2])] = RHO * A * le / 6 * np.array([[2, 1], [1, 2]])
    Me[np.ix_([1, 3], [1, 3])] = RHO * I * le / 6 * np.array([[2, 1], [1, 2]])
    d = 2 * np.arange(n_el)[:, None] + np.arange(4)[None, :]
    r, c = np.repeat(d, 4, axis=1).ravel(), np.tile(d, (1, 4)).ravel()
    n = 2 * (n_el + 1)
    K = sp.csc_matrix((np.tile(Ke.ravel(), n_el), (r, c)), shape=(n, n))
    M = sp.csc_matrix((np.tile(Me.ravel(), n_el), (r, c)), shape=(n, n))
    w2 = np.sort(sla.eigsh(K, k=2 + n_modes, M=M, sigma=-1.0, which="LM", return_eigenvectors=False))
    return np.sqrt(w2[2:]) / (2 * np.pi)


def test_free_free_beam_bending_converges_at_p2_rate(msh):
    """Free-free square beam L/a = 20, nu = 0, P2 on structured tetrahedra (h halved twice),
    against Timoshenko theory (EB would be 0.8 % high here: shear + rotary inertia)."""
    L, a = 1.0, 0.05
    f_ref = timoshenko_free_free(L, a, 0.0)[0]
    f_ref_half = timoshenko_free_free(L, a, 0.0, n_el=1000)[0]
    assert abs(f_ref_half / f_ref - 1) < 1e-5          # the reference itself is converged
    err = []
    for n in ((10, 1, 1), (20, 2, 2), (40, 4, 4)):
        model = build_model(Geometry("beam", msh("box", L=L, W=a, H=a, n=n), {"solid": MAT0}), degree=2)
        modes = eigenmodes(model, n_modes=8)
        assert modes.n_rigid == 6
        err.append(modes.freq_hz[6] / f_ref - 1)
    p = _orders(err)
    print(f"free-free beam P2: f_ref {f_ref:.4f} Hz, relative errors {np.array(err)}, observed orders {p}")
    # P2: frequency error O(h^4) asymptotically; these coarse meshes give 3.4 and 3.7
    assert np.all(p > 3.0)
    # finest: measured 2e-5; 3-D vs Timoshenko differs at O((k r)^4) ~ 2e-5 for k r ~ 0.07
    assert 0 < err[-1] < 1e-4


def test_thin_ring_inplane_n2_mode_converges(msh):
    """Free-free thin ring (R = 1, t = 0.04, width 0.08), first flexible mode = in-plane
    n = 2 flexure: omega^2 = E I / (rho A R^4) n^2 (n^2 - 1)^2 / (n^2 + 1) (Love / Hoppe)."""
    R, t, b, n = 1.0, 0.04, 0.08, 2
    f_exact = np.sqrt(E * t ** 2 / 12 / (RHO * R ** 4) * n ** 2 * (n ** 2 - 1) ** 2 / (n ** 2 + 1)) / (2 * np.pi)
    f = []
    for h in (0.16, 0.08, 0.04):
        model = build_model(Geometry("ring", msh("ring", R=R, t=t, b=b, h=h), {"ring": MAT0}), degree=2)
        modes = eigenmodes(model, n_modes=8)
        assert modes.n_rigid == 6
        assert _dominant_share(model, modes, 6, 2) < 0.01          # in-plane: no axial motion
        f.append(modes.freq_hz[6])
    f = np.array(f)
    err = f / f_exact - 1
    # the thin-ring formula has a model error ~ n^2 (t/R)^2 (1 + E/(kappa G)) / 12 ~ 0.2 %,
    # so the order is taken from successive differences (reference-free), not from err
    p = np.log(abs(f[0] - f[1]) / abs(f[1] - f[2])) / np.log(2)
    print(f"thin ring n=2 P2 (unstructured): f {f} Hz vs thin-ring {f_exact:.4f} Hz, "
          f"errors {err}, observed order {p:.2f}")
    assert p > 1.5                 # unstructured tets, pre-asymptotic (measured 2.3; P2 -> 4)
    assert abs(err[0]) > abs(err[1])
    assert abs(err[-1]) < 5e-3     # within 2.5x the thin-ring model error
