"""Interpolation patches (Nastran RBE3): a reference point that follows the least-squares
rigid fit of a group's node translations and adds no stiffness (fem.spiders,
fem.model). References: thin-walled beam theory for a tube loaded through one, numpy's
least squares for the fit itself, and a load distribution that must be statically
equivalent to the point load.
"""
import numpy as np
import pytest

from liftoff.core.errors import InputError
from liftoff.core.rigid import dof_rb
from liftoff.fem import build_model, point_load, static_solve
from liftoff.meshes.spec import Geometry, Material, Patch

pytestmark = pytest.mark.fem
AL = Material("al", 70e9, 0.3, 2700.0)
R, L, T, N = 0.1, 1.0, 0.005, 24


def _tube(msh, patches, clamped=("root",)):
    return Geometry("tube", msh("shell_tube", R=R, L=L, n_around=N, n_along=20), {"tube": AL},
                    patches=patches, clamped=list(clamped), shells={"tube": T})


def _section():
    """Regular N-gon mid-line: side length, enclosed area, I_yy (thin-walled)."""
    a = 2 * np.pi * np.arange(N) / N
    x0 = R * np.cos(a)
    x1 = np.roll(x0, -1)
    side = 2 * R * np.sin(np.pi / N)
    return side, 0.5 * N * R * R * np.sin(2 * np.pi / N), float(np.sum(T * side * (x0 * x0 + x0 * x1 + x1 * x1) / 3))


def _rigid_rows(xyz, ref):
    """(3n x 6) the nodes' translations (x, y, z interleaved) under a unit rigid motion of ref."""
    return dof_rb(np.repeat(np.asarray(xyz) - np.asarray(ref, float), 3, axis=0), np.tile(np.arange(3), len(xyz)))


def _tip_nodes(model):
    on = np.flatnonzero(np.isclose(model.nodes[:, 2], L))
    assert on.size == 2 * N                      # vertices and P2 edge midpoints
    return on


def test_tube_loaded_through_an_interpolation_patch(msh):
    """Cantilever tube, root edge clamped, loads at a point on the axis at the tip that
    interpolates the tip edge's nodes. Torsion: Bredt-Batho, exact for the regular polygon
    (no warping), 0.5 % (thin-wall theory, (t/R)^2 = 0.25 %). Bending: P L^3/(3EI) +
    P L/(k G A_s), k = 1/2, 1.5 % (the clamped root stops shear warping, as with the rigid
    spider of test_shell_model; here the tip section may warp). The point's motion is the
    least-squares rigid fit (numpy.linalg.lstsq) of the computed tip displacements to
    round-off, and the tip section stays free to deform: it ovalises under the lateral load,
    which a rigid spider forbids."""
    model = build_model(_tube(msh, [Patch("lid", (0.0, 0.0, L), nodes="tip")]))
    side, area, I = _section()
    G = AL.E / (2 * (1 + AL.nu))
    x = static_solve(model, point_load(model, "lid", moment=(0.0, 0.0, 10.0)))
    twist = x[model.dof_index("lid:Rz")] / (10.0 * L * N * side / (4 * area ** 2 * G * T))
    P = 100.0
    x = static_solve(model, point_load(model, "lid", force=(P, 0.0, 0.0)))
    bend = x[model.dof_index("lid:Tx")] / (P * L ** 3 / (3 * AL.E * I) + P * L / (0.5 * G * N * side * T))
    print(f"interpolated tip: twist / Bredt {twist:.5f}, deflection / beam {bend:.5f}")
    assert twist == pytest.approx(1.0, abs=0.005)
    assert bend == pytest.approx(1.0, abs=0.015)
    on = _tip_nodes(model)
    u = model.nodal_displacement(x)[on]
    A = _rigid_rows(model.nodes[on], (0.0, 0.0, L))
    fit = np.linalg.lstsq(A, u.ravel(), rcond=None)[0]
    ref = x[model.dof_index("lid:Tx"):][:6]
    assert np.allclose(ref, fit, rtol=0, atol=1e-9 * np.abs(ref).max())
    rigid = A @ fit
    assert np.linalg.norm(u.ravel() - rigid) > 1e-3 * np.linalg.norm(rigid)     # the section deforms


def test_interpolation_distributes_a_point_load_statically(msh):
    """RBE3 puts a load at its point onto the nodes as the minimum-norm nodal forces with
    the load's resultant (force and moment about the point). Those forces, computed by
    numpy.linalg.lstsq and applied to the nodes (T^T f), must be exactly the point load in
    the model's DOFs (round-off): nothing on any other DOF. With unit weights on the
    regular tip polygon a force alone gives each node the same share."""
    model = build_model(_tube(msh, [Patch("lid", (0.0, 0.0, L), nodes="tip")]))
    on = _tip_nodes(model)
    A = _rigid_rows(model.nodes[on], (0.0, 0.0, L))
    Tt = model.field_map().T
    for F in (np.array([3.0, -2.0, 5.0, 0.4, 0.7, -0.2]), np.array([3.0, -2.0, 5.0, 0.0, 0.0, 0.0])):
        f_on = np.linalg.lstsq(A.T, F, rcond=None)[0]            # min-norm, A^T f = F
        f = np.zeros((model.nodes.shape[0], 3))
        f[on] = f_on.reshape(-1, 3)
        got = Tt @ f.ravel()
        want = point_load(model, "lid", force=F[:3], moment=F[3:])
        assert np.allclose(got, want, rtol=0, atol=1e-12 * np.abs(F).max())
    assert np.allclose(f[on], F[:3] / on.size, rtol=0, atol=1e-14 * np.abs(F).max())


def test_points_sharing_an_edge_with_a_reach(msh):
    """Two points on opposite sides of the tip edge, each interpolating the nodes within
    its reach (a half edge each, sharing two nodes): both constraints hold together (the
    joint elimination), and each point follows the rigid fit of its own half."""
    pts = [Patch("east", (R, 0.0, L), nodes="tip", reach=1.42 * R),
           Patch("west", (-R, 0.0, L), nodes="tip", reach=1.42 * R)]
    model = build_model(_tube(msh, pts))
    x = static_solve(model, point_load(model, "east", force=(0.0, 50.0, 20.0)))
    u = model.nodal_displacement(x)
    for p in pts:
        on = np.flatnonzero(np.isclose(model.nodes[:, 2], L)
                            & (np.linalg.norm(model.nodes - p.ref_point, axis=1) <= p.reach))
        assert N < on.size < 2 * N
        A = _rigid_rows(model.nodes[on], p.ref_point)
        fit = np.linalg.lstsq(A, u[on].ravel(), rcond=None)[0]
        ref = x[model.dof_index(f"{p.name}:Tx"):][:6]
        assert np.allclose(ref, fit, rtol=0, atol=1e-9 * np.abs(x).max())


def test_interpolation_bad_input(msh):
    """Same nodes, same fit: two points rigidly tied to each other, refused; an
    interpolated node on a clamp, refused; a reach that catches no node, refused."""
    same = [Patch("a", (0.0, 0.0, L), nodes="tip"), Patch("b", (0.0, 0.0, 1.2 * L), nodes="tip")]
    with pytest.raises(InputError, match="dependent"):
        build_model(_tube(msh, same))
    with pytest.raises(InputError, match="clamped or on a rigid spider"):
        build_model(_tube(msh, [Patch("a", (0.0, 0.0, 0.0), nodes="root")]))
    with pytest.raises(InputError, match="do not fix a rigid motion"):
        build_model(_tube(msh, [Patch("a", (0.0, 0.0, 3.0), nodes="tip", reach=0.1)]))
    with pytest.raises(InputError, match="reach must be > 0"):
        Patch("a", (0.0, 0.0, 0.0), nodes="tip", reach=0.0)


def test_patch_json_round_trip(tmp_path, msh):
    g = _tube(msh, [Patch("lid", (0.0, 0.0, L), nodes="tip", reach=0.5), Patch("cap", (0.0, 0.0, 0.0), nodes="root")],
              clamped=())
    h = Geometry.load(g.save(tmp_path / "tube.json"))
    assert [(p.name, p.nodes, p.reach) for p in h.patches] == [("lid", "tip", 0.5), ("cap", "root", np.inf)]


def test_rings_through_a_shell_glued_on_a_solid(tmp_path):
    """The shell orbiter's aft attach ring crosses the root of its solid wing, where shell
    edge midpoints follow the P1 solid's edges: their rows must use the interpolation's
    dependent DOFs too, or a rigid motion strains the model. K RB = 0 to round-off."""
    from liftoff.meshes import OrbiterParams, build_orbiter

    model = build_model(build_orbiter(OrbiterParams(walls="shell", mesh_size=1.0, attach="ring"), tmp_path))
    assert model.part("solid") is not None
    K, _ = model.matrices()
    RB = model.rigid_body_shape()
    res = np.abs(K @ RB).max(axis=0) / (abs(K).max() * np.abs(RB).max(axis=0))
    print("K RB residual", res)
    assert res.max() < 1e-12


def test_too_few_nodes_for_the_interpolations():
    """Two points on the same three nodes need 12 dependent DOFs from 9: a one-line
    InputError, not an index error in the elimination."""
    from liftoff.fem.spiders import eliminate_interpolations, interpolation_fit

    xyz = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    fits = [interpolation_fit(xyz, ref, "p") for ref in ((0.0, 0.0, 0.0), (0.3, 0.3, 0.0))]
    with pytest.raises(InputError, match="3 nodes in all cannot carry 2 interpolations"):
        eliminate_interpolations(fits, [np.arange(9), np.arange(9)], "patches 'a', 'b'")
