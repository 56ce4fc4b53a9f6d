"""Pressure stiffening of shells (fem.shell.geometric_stiffness_form, volume_hessian_form,
pressure_load_form) against independent references.

1. Geometric stiffness: a simply supported cylinder (tests/fem/test_shell_cylinder_vibration.py)
   under a prescribed uniform membrane prestress N_x (axial) and N_th (hoop). With the
   initial-stress energy N_x |d,x|^2 + N_th |d,s|^2 of the three translations d = (u, v, w),
   Leissa's SS3 modes give, per (m, n) and in Flügge's non-dimensional units,

       K_G = (1 - nu^2)/(E t) [N_x lam^2 I + N_th [[n^2, 0, 0], [0, n^2+1, 2n], [0, 2n, n^2+1]]]

   (d,s = (1/R) d/dth of u e_x + v e_th + w e_r; the n^2 + 1 and 2n terms are the turning
   of e_th and e_r). The reference is det(K_Flügge + K_G - Delta I) = 0.
2. Load stiffness -p d^2V: the bilinear form against a central second difference of the
   volume enclosed by the displaced faceted surface (exact polyhedron volumes).
3. Equilibrium: a closed pressurised capsule, free-free: the static membrane resultants
   against the membrane closed forms pR (hoop) and pR/2 (axial) mid-barrel, and
   K + K_G + K_L leaves rigid rotations free (K_G alone does not).
"""
import numpy as np
import pytest

from liftoff.fem import petsc_backend as pb
from liftoff.fem import shell as sh

from .shell_cases import ShellCase
from .test_shell_cylinder_vibration import E, L, NU, RHO, R, T, _fe_modes, _wave_numbers, flugge_matrix

pytestmark = pytest.mark.fem
N_X, N_TH = 1.0e5, 2.0e5          # N/m


def flugge_prestressed_hz(m: int, n: int, n_x: float, n_th: float) -> float:
    lam = m * np.pi * R / L
    G = n_x * lam ** 2 * np.eye(3) + n_th * np.array([[n * n, 0, 0], [0, n * n + 1, 2 * n], [0, 2 * n, n * n + 1]])
    delta = np.linalg.eigvalsh(flugge_matrix(m, n) + (1 - NU ** 2) / (E * T) * G)[0]
    return np.sqrt(delta * E / (RHO * (1 - NU ** 2) * R ** 2)) / (2 * np.pi)


def _prestress(case):
    """K_G (scipy) of the uniform prestress N_X e_x e_x + N_TH e_th e_th on the case's mesh."""
    import ufl

    mesh = case.mesh
    x = ufl.SpatialCoordinate(mesh)
    P = sh._in_plane(sh.local_frame(mesh))
    r = ufl.sqrt(x[1] ** 2 + x[2] ** 2)
    e_th = ufl.as_vector([0.0, -x[2] / r, x[1] / r])
    a, b = ufl.dot(P.T, ufl.as_vector([1.0, 0.0, 0.0])), ufl.dot(P.T, e_th)
    N0 = N_X * ufl.outer(a, a) + N_TH * ufl.outer(b, b)
    return pb.gather_csr(pb.assemble_matrix(sh.geometric_stiffness_form(case.W, N0)))


def _by_wave_numbers(n_th, n_x, extra=None) -> dict:
    f, Phi, coords, comp = _fe_modes(n_th, n_x, n_modes=10, extra_stiffness=extra)
    out = {}
    for j in range(f.size):
        out.setdefault(_wave_numbers(Phi[:, j], coords, comp), f[j])
    return out


def test_geometric_stiffness_against_flugge_with_initial_stress():
    ref = sorted((flugge_prestressed_hz(m, n, N_X, N_TH), (m, n)) for m in (1, 2, 3) for n in range(1, 10))[:4]
    mn = [w for _, w in ref]
    fr = np.array([f for f, _ in ref])
    gain = fr / np.array([flugge_prestressed_hz(*w, 0.0, 0.0) for w in mn])
    # the test is not trivial: the prestress raises these four by 7-33 %
    assert np.all(gain > 1.05) and gain.max() > 1.25
    errs, gain_errs = [], []
    for n_th, n_x in ((30, 15), (40, 20)):
        bare, pre = _by_wave_numbers(n_th, n_x), _by_wave_numbers(n_th, n_x, _prestress)
        f = np.array([pre[w] for w in mn])
        errs.append(f / fr - 1)
        gain_errs.append(f / np.array([bare[w] for w in mn]) / gain - 1)
        print(f"{n_th} x {n_x}: {mn} prestressed {np.round(f, 3)} vs Flügge {np.round(fr, 3)} Hz, errors "
              f"{np.round(errs[-1], 5)}; stiffening f_p/f_0 errors {np.round(gain_errs[-1], 5)}")
    # the bare shell's accuracy (test_shell_cylinder_vibration: 1 % on the finest mesh) holds under prestress
    assert np.all(np.abs(errs[-1]) < 0.01)
    # the stiffening itself: the discretisation error of the bare shell cancels in f_p / f_0 (to second order)
    assert np.all(np.abs(gain_errs[-1]) < 0.003)


# ---- a closed capsule (cylinder + hemispherical ends), axis x ---------------------------------
CAP_R, CAP_L, CAP_T, CAP_E, CAP_NU, CAP_P = 1.0, 4.0, 0.01, 70e9, 0.3, 1.0e5


def _capsule_case(h: float) -> ShellCase:
    import gmsh

    gmsh.initialize(["-nopopup"])
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        occ = gmsh.model.occ
        c = occ.addCylinder(-CAP_L / 2, 0, 0, CAP_L, 0, 0, CAP_R)
        s1, s2 = occ.addSphere(-CAP_L / 2, 0, 0, CAP_R), occ.addSphere(CAP_L / 2, 0, 0, CAP_R)
        occ.fuse([(3, c)], [(3, s1), (3, s2)])
        occ.synchronize()
        gmsh.option.setNumber("Mesh.CharacteristicLengthMax", h)
        gmsh.model.mesh.generate(2)
        tags, xyz, _ = gmsh.model.mesh.getNodes()
        _, elems, conn = gmsh.model.mesh.getElements(2)
    finally:
        gmsh.finalize()
    index = np.zeros(int(tags.max()) + 1, dtype=np.int64)
    index[tags.astype(np.int64)] = np.arange(tags.size)
    cells = index[np.concatenate(conn).astype(np.int64)].reshape(-1, 3)
    return ShellCase(xyz.reshape(-1, 3), cells, CAP_E, CAP_NU, CAP_T)


def _enclosed_volume(X, cells) -> float:
    a, b, c = X[cells[:, 0]], X[cells[:, 1]], X[cells[:, 2]]
    return abs(np.einsum("ij,ij->i", a, np.cross(b, c)).sum()) / 6.0


def _translations(case, field) -> np.ndarray:
    """DOF vector of the translation field ``field(x) -> (n, 3)`` (rotations 0)."""
    x = np.zeros(case.n_dof)
    u = field(case.coords)
    for c in range(3):
        i = np.flatnonzero(case.comp == c)
        x[i] = u[i, c]
    return x


def _forms(case):
    import ufl

    dx = ufl.dx(domain=case.mesh)
    G = pb.gather_csr(pb.assemble_matrix(sh.volume_hessian_form(case.W, (0.0, 0.0, 0.0), dx)))
    b = pb.gather_vec(pb.assemble_vector(sh.pressure_load_form(case.W, CAP_P, (0.0, 0.0, 0.0), dx)))
    return G, b


def test_volume_hessian_against_affine_maps():
    """d^2V[Ax, Bx] = V0 (tr A tr B - tr AB) for affine fields (exact: det(I + eps A) V0)."""
    case = _capsule_case(0.35)
    X = case.mesh.geometry.x
    cells = case.mesh.geometry.dofmap.array.reshape(-1, 3)
    V0 = _enclosed_volume(X, cells)
    G, _ = _forms(case)
    rng = np.random.default_rng(3)
    for _ in range(3):
        A, B = rng.normal(size=(3, 3)), rng.normal(size=(3, 3))
        a, b = _translations(case, lambda x: x @ A.T), _translations(case, lambda x: x @ B.T)
        ref = V0 * (np.trace(A) * np.trace(B) - np.trace(A @ B))
        # exact arithmetic gives ref; round-off ~ 1e-13 of the terms (|A||B| V0)
        assert a @ (G @ b) == pytest.approx(ref, abs=1e-10 * np.linalg.norm(A) * np.linalg.norm(B) * V0)
        eps = 1e-4           # the polyhedron's own volume under the map, second difference
        fd = (_enclosed_volume(X + eps * X @ A.T, cells) - 2 * V0 + _enclosed_volume(X - eps * X @ A.T, cells)) / eps ** 2
        assert a @ (G @ a) == pytest.approx(fd, rel=1e-5)


def _supports(case) -> np.ndarray:
    """3-2-1 supports of the free-free capsule: both poles and a point on the equator."""
    c = case.coords
    pole0 = np.argmin(np.linalg.norm(c - [-CAP_L / 2 - CAP_R, 0, 0], axis=1))
    pole1 = np.argmin(np.linalg.norm(c - [CAP_L / 2 + CAP_R, 0, 0], axis=1))
    side = np.argmin(np.linalg.norm(c - [0, CAP_R, 0], axis=1))
    at = lambda i, comps: [case.dof_at(c[i], k) for k in comps]      # noqa: E731
    return np.array(at(pole0, (0, 1, 2)) + at(pole1, (1, 2)) + at(side, (2,)))


def test_pressurised_capsule_membrane_forces_and_rigid_rotations():
    import ufl
    from dolfinx import fem

    case = _capsule_case(0.15)
    G, b = _forms(case)
    # the load is self-equilibrated (closed surface): its resultant vanishes to round-off
    rigid = [_translations(case, lambda x, k=k: np.eye(3)[k] + 0 * x) for k in range(3)]
    assert max(abs(r @ b) for r in rigid) < 1e-10 * CAP_P * CAP_R ** 2
    x0 = case.solve(_supports(case), b)
    u = fem.Function(case.W)
    u.x.array[:] = x0
    N = sh.membrane_resultants(ufl.split(u)[0], case.fields, case.mesh)
    P = sh._in_plane(sh.local_frame(case.mesh))
    y = ufl.SpatialCoordinate(case.mesh)
    r = ufl.sqrt(y[1] ** 2 + y[2] ** 2)
    a, t = ufl.dot(P.T, ufl.as_vector([1.0, 0.0, 0.0])), ufl.dot(P.T, ufl.as_vector([0.0, -y[2] / r, y[1] / r]))
    mid = ufl.conditional(ufl.lt(abs(y[0]), CAP_L / 4), 1.0, 0.0)
    area = fem.assemble_scalar(fem.form(mid * ufl.dx(domain=case.mesh)))
    n_x, n_th = (fem.assemble_scalar(fem.form(mid * ufl.dot(e, ufl.dot(N, e)) * ufl.dx)) / area for e in (a, t))
    print(f"mid-barrel N_x {n_x:.6g}, N_th {n_th:.6g} N/m vs membrane {CAP_P * CAP_R / 2:.6g}, {CAP_P * CAP_R:.6g}")
    # membrane theory; the faceted polygon's inscribed radius (1 - cos(pi/n_around) ~ 0.2 %) and the
    # junction's bending boundary layer (decays within sqrt(R t) = 0.1 m of x = +-2) set the tolerance
    assert n_x == pytest.approx(CAP_P * CAP_R / 2, rel=0.01)
    assert n_th == pytest.approx(CAP_P * CAP_R, rel=0.01)
    KG = pb.gather_csr(pb.assemble_matrix(sh.geometric_stiffness_form(case.W, N)))
    KL = -CAP_P * G
    rot = _translations(case, lambda x: np.cross([0.0, 1.0, 0.0], x))
    for k in (3, 4, 5):                      # the rotation DOFs of a rigid rotation about y
        rot[case.comp == k] = [0.0, 1.0, 0.0][k - 3]
    e_g, e_l, e_k = rot @ (KG @ rot), rot @ (KL @ rot), rot @ (case.K @ rot)
    print(f"rigid rotation about y: K {e_k:.3g}, K_G {e_g:.4g}, K_L {e_l:.4g}, K_G + K_L {e_g + e_l:.3g} N m")
    assert e_g > 0.5 * CAP_P * _enclosed_volume(case.mesh.geometry.x, case.mesh.geometry.dofmap.array.reshape(-1, 3))
    # measured 4e-6: what is left is the bending prestress at the dome junctions (membrane N0 only)
    assert abs(e_g + e_l) < 1e-4 * e_g
