"""Free vibration of a simply supported thin circular cylinder against Flügge's shell theory.

Cylinder R = 1 m, L = 8 m, t = 0.01 m (R/t = 100), steel E = 210 GPa, nu = 0.3,
rho = 7850 kg/m^3; both ends shear diaphragms (v = w = 0, the rotation about the axis held,
u and the bending rotation free: "SS3", Leissa, Vibration of Shells, NASA SP-288 (1973),
ch. 2). Then u = A cos(lam x/R) cos(n th), v = B sin(lam x/R) sin(n th),
w = C sin(lam x/R) cos(n th), lam = m pi R / L, are exact modes of Flügge's equations
(Flügge, Stresses in Shells, 1973, ch. 5; Leissa ch. 2), which reduce to the symmetric
3 x 3 eigenproblem (K - Delta I)(A, B, C) = 0, Delta = rho (1 - nu^2) R^2 omega^2 / E, with
k = t^2 / (12 R^2):

    K11 = lam^2 + (1-nu)/2 n^2 (1 + k)          K12 = -(1+nu)/2 lam n
    K22 = n^2 + (1-nu)/2 lam^2 (1 + 3k)         K13 = -nu lam - k lam^3 + k (1-nu)/2 lam n^2
    K33 = 1 + k ((lam^2 + n^2)^2 - 2 n^2 + 1)    K23 = n + k (3-nu)/2 lam^2 n

The smallest root is the flexural mode. The reference is checked on its own below: for
lam -> 0 it gives the inextensional ring frequency of Rayleigh (Theory of Sound, 1877),
and for n = 1, lam = 0 a rigid translation (a zero root that Donnell's theory misses).
Donnell's simpler theory is 5-9 % off for n = 2-4 here, so Flügge is the reference.

The shell model (Reissner-Mindlin with rotary inertia) differs from Flügge's by
O((n t / R)^2 / 12) ~ 1e-4 for the modes compared; the rest is discretisation error. A half
cylinder (symmetry plane through the axis: every (m, n) once) is meshed three times.
"""
import numpy as np
import pytest
from mpi4py import MPI

from liftoff.fem import petsc_backend as pb

from .shell_cases import ShellCase, param_grid

pytestmark = pytest.mark.fem
R, L, T, E, NU, RHO = 1.0, 8.0, 0.01, 210e9, 0.3, 7850.0


def flugge_matrix(m: int, n: int) -> np.ndarray:
    lam, k = m * np.pi * R / L, T ** 2 / (12 * R ** 2)
    K = np.zeros((3, 3))
    K[0, 0] = lam ** 2 + (1 - NU) / 2 * n ** 2 * (1 + k)
    K[1, 1] = n ** 2 + (1 - NU) / 2 * lam ** 2 * (1 + 3 * k)
    K[2, 2] = 1 + k * ((lam ** 2 + n ** 2) ** 2 - 2 * n ** 2 + 1)
    K[0, 1] = K[1, 0] = -(1 + NU) / 2 * lam * n
    K[0, 2] = K[2, 0] = -NU * lam - k * lam ** 3 + k * (1 - NU) / 2 * lam * n ** 2
    K[1, 2] = K[2, 1] = n + k * (3 - NU) / 2 * lam ** 2 * n
    return K


def flugge_hz(m: int, n: int) -> float:
    delta = np.linalg.eigvalsh(flugge_matrix(m, n))[0]
    return np.sqrt(delta * E / (RHO * (1 - NU ** 2) * R ** 2)) / (2 * np.pi)


def test_flugge_reference_limits():
    k = T ** 2 / (12 * R ** 2)
    for n in (2, 3, 4):
        K = flugge_matrix(1, n)
        K[0, 1] = K[1, 0] = K[0, 2] = K[2, 0] = 0.0     # lam -> 0 in the ring block
        K[1, 1], K[1, 2], K[2, 1], K[2, 2] = n ** 2, n, n, 1 + k * (n ** 2 - 1) ** 2
        ring = k * n ** 2 * (n ** 2 - 1) ** 2 / (n ** 2 + 1)
        assert np.linalg.eigvalsh(K[1:, 1:])[0] == pytest.approx(ring, rel=k * n ** 4)
    K = flugge_matrix(1, 1)
    K[:, 0] = K[0, :] = 0.0
    K[1, 1], K[1, 2], K[2, 1], K[2, 2] = 1.0, 1.0, 1.0, 1 + k * (1 - 2 + 1)
    assert abs(np.linalg.det(K[1:, 1:])) < 1e-15


def _fe_modes(n_th: int, n_x: int, n_modes: int = 12, extra_stiffness=None):
    """Frequencies (Hz), modes, DOF coordinates and components of the half cylinder;
    ``extra_stiffness(case)``: a scipy matrix added to K (the prestress test's K_G)."""
    g, cells = param_grid(n_x, n_th)
    x, th = L * g[:, 0], np.pi * g[:, 1]                # th = 0 .. pi: the half z >= 0
    case = ShellCase(np.column_stack([x, R * np.cos(th), R * np.sin(th)]), cells, E, NU, T, rho=RHO)
    if extra_stiffness is not None:
        case.K = case.K + extra_stiffness(case)
    c = case.coords
    tol = 1e-9 * L
    ends = (np.abs(c[:, 0]) < tol) | (np.abs(c[:, 0] - L) < tol)
    fixed = np.unique(np.concatenate([case.where(ends, [1, 2, 3]),
                                      case.where(np.abs(c[:, 2]) < tol, [2, 3, 4])]))
    free = np.setdiff1d(np.arange(case.n_dof), fixed)
    Kf, Mf = (pb.csr_matrix(MPI.COMM_SELF, free.size, free.size, free.size, A[free][:, free])
              for A in (case.K, case.M))
    lam, Phi = pb.eigensolve(Kf, Mf, n_modes, sigma=-(2 * np.pi) ** 2, what="cylinder")
    keep = lam > (2 * np.pi) ** 2                        # drop the axial rigid translation
    full = np.zeros((case.n_dof, int(keep.sum())))
    full[free] = Phi[:, keep]
    return np.sqrt(lam[keep]) / (2 * np.pi), full, c, case.comp


def _wave_numbers(phi, coords, comp) -> tuple[int, int]:
    """(m, n) of a mode: largest projection of the radial displacement on sin(m pi x/L) cos(n th)."""
    y, z = (np.flatnonzero(comp == k) for k in (1, 2))
    y, z = (i[np.lexsort(coords[i].T)] for i in (y, z))   # the same nodes in the same order
    assert np.allclose(coords[y], coords[z])
    x, th = coords[y, 0], np.arctan2(coords[y, 2], coords[y, 1])
    w = phi[y] * np.cos(th) + phi[z] * np.sin(th)
    score = {(m, n): abs(w @ (np.sin(m * np.pi * x / L) * np.cos(n * th)))
             / np.linalg.norm(np.sin(m * np.pi * x / L) * np.cos(n * th)) for m in (1, 2, 3) for n in range(8)}
    return max(score, key=score.get)


def test_simply_supported_cylinder_frequencies():
    ref = sorted((flugge_hz(m, n), (m, n)) for m in (1, 2, 3) for n in range(1, 10))[:5]
    print("Flügge:", [(mn, round(f, 3)) for f, mn in ref])
    errs = []
    for n_th, n_x in ((20, 10), (30, 15), (40, 20)):
        f, Phi, coords, comp = _fe_modes(n_th, n_x)
        mn = [_wave_numbers(Phi[:, j], coords, comp) for j in range(5)]
        errs.append(f[:5] / np.array([fr for fr, _ in ref]) - 1)
        print(f"half cylinder {n_th} x {n_x}: {[(w, round(v, 3)) for w, v in zip(mn, f[:5])]}, "
              f"errors vs Flügge {errs[-1]}")
    # the ordering of the wave numbers is Flügge's: (1,3) (1,2) (1,4) (2,4) (2,3)
    assert mn == [w for _, w in ref]
    e = np.abs(np.array(errs))
    # discretisation error ~ (n h)^2: it falls by about (30/40)^2 = 0.56 on the last refinement
    assert np.all(e[2, [0, 2, 3]] < 0.75 * e[1, [0, 2, 3]])
    # the 1 % for the five lowest (m, n) on the finest mesh (measured 0.05-0.8 %)
    assert np.all(e[2] < 0.01)
