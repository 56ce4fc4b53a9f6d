"""Rigid spiders (RBE2), static solves and the thermal-strain load."""
import numpy as np
import pytest

from liftoff.fem import build_model, eigenmodes, point_load, static_solve, thermal_load
from liftoff.meshes.spec import Geometry, Material, Patch

from ..roundoff import solve_rtol, sum_rtol

pytestmark = pytest.mark.fem
STEEL = Material("steel", 2.0e11, 0.3, 7800.0)
L, W, H = 1.0, 0.1, 0.1
REF = np.array([1.25, 0.04, 0.07])      # off the face centre on purpose


@pytest.fixture(scope="module")
def spider_box(msh):
    g = Geometry("box", msh("box", L=L, W=W, H=H, n=(10, 2, 2)), {"solid": STEEL}, patches=[Patch("x1", REF)])
    return build_model(g, degree=2)


def _patch_nodes(model):
    return np.flatnonzero(np.isclose(model.nodes[:, 0], L))


def test_patch_moves_rigidly_with_its_reference_point(spider_box):
    model = spider_box
    modes = eigenmodes(model, n_modes=10)
    nodes = _patch_nodes(model)
    assert nodes.size > 9
    i = model.dof_index("x1:Tx")
    for j in (3, 7, 9):                             # a rigid and two flexible modes
        x = modes.shapes[:, j]
        t, th = x[i:i + 3], x[i + 3:i + 6]
        u = model.nodal_displacement(x)[nodes]
        expected = t + np.cross(th, model.nodes[nodes] - REF)
        # each entry is the spider's rigid map of 6 reference DOFs: a 6-term dot product
        assert np.allclose(u, expected, atol=sum_rtol(6) * np.abs(u).max())
        assert np.abs(th).max() > 0                 # the patch really rotates in these modes


def test_load_at_reference_point_equals_patch_resultant(spider_box):
    """T^T f: nodal forces on the patch reduce to their resultant force and moment about
    the reference point, nothing else (virtual work of the rigid spider)."""
    model = spider_box
    nodes = _patch_nodes(model)
    rng = np.random.default_rng(0)
    F = rng.normal(size=(nodes.size, 3))
    f_full = np.zeros(3 * model.nodes.shape[0])
    f_full.reshape(-1, 3)[nodes] = F
    f = model.field_map().T @ f_full
    i = model.dof_index("x1:Tx")
    # T^T f and the resultant are both sums over the patch nodes (random signs: relative to sum |F|)
    tol = sum_rtol(nodes.size) * np.abs(F).sum() * max(1.0, np.abs(model.nodes[nodes] - REF).max())
    assert np.allclose(f[i:i + 3], F.sum(axis=0), rtol=0, atol=tol)
    assert np.allclose(f[i + 3:i + 6], np.cross(model.nodes[nodes] - REF, F).sum(axis=0), rtol=0, atol=tol)
    assert np.abs(np.delete(f, np.arange(i, i + 6))).max() == 0.0


def test_cantilever_tip_load_through_spider_matches_timoshenko(msh):
    """Cantilever (nu = 0, x0 clamped), tip force through a spider on x1 at the section
    centre: delta = P L^3 / (3 E I) + P L / (kappa G A). The rigid tip face and the clamp
    warping restraint make the 3-D solid slightly stiffer: tolerance 1 %."""
    mat = Material("steel0", 2.0e11, 0.0, 7800.0)
    g = Geometry("cant", msh("box", L=L, W=W, H=H, n=(20, 2, 2)), {"solid": mat},
                 patches=[Patch("x1", (L, W / 2, H / 2))], clamped=["x0"])
    model = build_model(g, degree=2)
    P = 1000.0
    x = static_solve(model, point_load(model, "x1", force=(0, 0, P)))
    I, A, G = W * H ** 3 / 12, W * H, mat.E / 2
    delta = P * L ** 3 / (3 * mat.E * I) + P * L / (5 / 6 * G * A)
    got = x[model.dof_index("x1:Tz")]
    print(f"cantilever tip deflection {got:.6e} m vs Timoshenko {delta:.6e} m ({got / delta - 1:+.4%})")
    assert got == pytest.approx(delta, rel=1e-2)
    # rotation of the tip: P L^2 / (2 E I) (shear adds no rotation at the tip in Timoshenko)
    assert -x[model.dof_index("x1:Ry")] == pytest.approx(P * L ** 2 / (2 * mat.E * I), rel=1e-2)


def test_free_block_thermal_shrink_is_alpha_dT_L(msh):
    """Free block, uniform cryogenic strain alpha dT, 3-2-1 supports (no stress): the FE
    displacement is exactly the free thermal field u = alpha dT (x - x_A) (constant strain
    is in the P1 space), so the block shrinks by alpha dT L to round-off."""
    Lb = 0.4
    g = Geometry("block", msh("box", L=Lb, W=W, H=H, n=(8, 2, 2)), {"solid": STEEL})
    model = build_model(g, degree=1)
    alpha, dT = 1.2e-5, -200.0
    f = thermal_load(model, ["solid"], dT, alpha)
    A, B, C = model.node_dofs((0, 0, 0)), model.node_dofs((Lb, 0, 0)), model.node_dofs((0, W, 0))
    supports = [*A, B[1], B[2], C[2]]
    x = static_solve(model, f, supports=supports)
    K, _ = model.matrices()
    free = np.setdiff1d(np.arange(model.n_dof), supports)
    tol = solve_rtol(np.linalg.cond(K[free][:, free].toarray()))   # the direct solve: eps cond(K)
    u = x.reshape(-1)[model.dof_comp < 3]
    pos = model.dof_coords[model.dof_comp < 3]
    comp = model.dof_comp[model.dof_comp < 3]
    expected = alpha * dT * pos[np.arange(pos.shape[0]), comp]
    assert np.allclose(u, expected, atol=tol * abs(alpha * dT * Lb))
    shrink = x[B[0]] - x[A[0]]
    print(f"block thermal length change {shrink:.6e} m vs alpha dT L {alpha * dT * Lb:.6e} m")
    assert shrink == pytest.approx(alpha * dT * Lb, rel=2 * tol)


def test_thermal_load_in_one_volume_only_is_self_equilibrated(msh, spider_box):
    f = thermal_load(spider_box, "solid", -100.0, {"solid": 2e-5})
    RB = spider_box.rigid_body_shape()
    assert np.abs(RB.T @ f).max() < 1e-9 * np.abs(f).max()      # no net force or moment
