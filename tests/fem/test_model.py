"""FE model: rigid-body modes, eigen-solution vs scipy, mass properties, Component export, VTU."""
import numpy as np
import pytest
import scipy.sparse.linalg as sla

from liftoff.fem import build_model, eigenmodes, mass_properties, write_modes_vtu
from liftoff.meshes.spec import Geometry, Material, Patch, PointMass, SmearedMass
from liftoff.reduction.component import Component, load_component

from ..roundoff import sum_rtol

pytestmark = pytest.mark.fem
STEEL = Material("steel", 2.0e11, 0.3, 7800.0)
L, W, H = 1.0, 0.1, 0.1


@pytest.fixture(scope="module")
def box_model(msh):
    g = Geometry("box", msh("box", L=L, W=W, H=H, n=(20, 2, 2)), {"solid": STEEL},
)
    return build_model(g, degree=1)


def _box_with_masses(msh, degree, lumped=False):
    g = Geometry("box", msh("box", L=L, W=W, H=H, n=(10, 2, 2)), {"solid": STEEL},
                 patches=[Patch("x1", (1.2, 0.05, 0.05))],
                 point_masses=[PointMass("engine", "x1", 10.0, np.diag([1.0, 2.0, 3.0]))],
                 smeared_masses=[SmearedMass("y0", 5.0)])
    return build_model(g, degree=degree, lumped_smeared_mass=lumped)


def test_free_free_rigid_modes_zero_to_roundoff(box_model):
    modes = eigenmodes(box_model, n_modes=10)
    K, M = box_model.matrices()
    lam_flex = modes.eigenvalues[6]
    print(f"rigid-body eigenvalues {modes.eigenvalues[:6]} rad^2/s^2, first flexible {lam_flex:.4g}")
    assert modes.n_rigid == 6 and np.all(modes.freq_hz[:6] == 0.0)
    # round-off of a shift-invert solve is ~ eps * lambda_max ~ 1e-16 * 1e13 (h = 0.05 m steel)
    assert np.all(np.abs(modes.eigenvalues[:6]) < 1e-9 * lam_flex)
    Phi = modes.shapes
    assert np.allclose(Phi.T @ (M @ Phi), np.eye(10), atol=1e-8)          # mass-normalised
    r = K @ Phi - (M @ Phi) * modes.eigenvalues
    assert np.linalg.norm(r[:, 6:]) < 1e-6 * np.linalg.norm(K @ Phi[:, 6:])
    # rigid modes span the geometric rigid-body shape: K RB = 0 and RB in span(Phi_rigid)
    RB = box_model.rigid_body_shape()
    assert np.abs(K @ RB).max() < 1e-6 * np.abs(K).max()
    P = Phi[:, :6] @ (Phi[:, :6].T @ (M @ RB))
    assert np.linalg.norm(P - RB) < 1e-6 * np.linalg.norm(RB)


def test_slepc_matches_scipy_eigsh_on_same_matrices(box_model):
    """Second method: scipy's ARPACK shift-invert (SuperLU) on the exported matrices."""
    modes = eigenmodes(box_model, n_modes=12)
    K, M = box_model.matrices()
    w2 = np.sort(sla.eigsh(K.tocsc(), k=12, M=M.tocsc(), sigma=-(2 * np.pi) ** 2, which="LM",
                           return_eigenvectors=False))
    assert np.allclose(modes.eigenvalues[6:], w2[6:], rtol=1e-8)


def test_band_equals_count(box_model):
    count = eigenmodes(box_model, n_modes=20)
    f_hi = 0.5 * (count.freq_hz[14] + count.freq_hz[15])
    band = eigenmodes(box_model, band_hz=(1.0, f_hi))
    assert len(band) == 15 - 6 and band.n_rigid == 0
    assert np.allclose(band.freq_hz, count.freq_hz[6:15], rtol=1e-9)
    with_rigid = eigenmodes(box_model, band_hz=(0.0, f_hi))
    assert with_rigid.n_rigid == 6 and len(with_rigid) == 15


def test_clamped_model_has_no_rigid_modes_and_is_grounded(msh):
    g = Geometry("cantilever", msh("box", L=L, W=W, H=H, n=(20, 2, 2)), {"solid": STEEL}, clamped=["x0"])
    model = build_model(g, degree=1)
    free = build_model(Geometry("box", g.msh_path, {"solid": STEEL}), degree=1)
    n_face = np.sum(np.isclose(free.nodes[:, 0], 0.0))
    assert model.n_dof == free.n_dof - 3 * n_face          # clamped DOFs removed, not penalised
    modes = eigenmodes(model, n_modes=4)
    assert modes.n_rigid == 0 and modes.freq_hz[0] > 10.0
    K, M = model.matrices()
    assert np.allclose(np.sort(sla.eigsh(K.tocsc(), 4, M.tocsc(), sigma=0, return_eigenvectors=False)),
                       modes.eigenvalues, rtol=1e-8)


@pytest.mark.parametrize("degree", [1, 2])
def test_mass_properties_closed_form(msh, degree):
    """Box 78 kg + 10 kg point mass (inertia diag(1,2,3) about its point) + 5 kg smeared on
    the y = 0 face: mass, c.g. and inertia exact (consistent mass integrates the quadratic
    rigid-body products exactly), so tolerance is round-off."""
    model = _box_with_masses(msh, degree)
    mp = mass_properties(model)
    tol = sum_rtol(model.matrices()[1].nnz)      # RB^T M RB: sums over every entry of M
    m_box, m_pt, m_s = 7800.0 * L * W * H, 10.0, 5.0
    c_box, c_pt, c_s = np.array([0.5, 0.05, 0.05]), np.array([1.2, 0.05, 0.05]), np.array([0.5, 0.0, 0.05])
    m = m_box + m_pt + m_s
    cg = (m_box * c_box + m_pt * c_pt + m_s * c_s) / m

    def shift(mass, d):
        return mass * (d @ d * np.eye(3) - np.outer(d, d))
    I = (m_box / 12 * np.diag([W ** 2 + H ** 2, L ** 2 + H ** 2, L ** 2 + W ** 2]) + shift(m_box, c_box - cg)
         + np.diag([1.0, 2.0, 3.0]) + shift(m_pt, c_pt - cg)
         + m_s / 12 * np.diag([H ** 2, L ** 2 + H ** 2, L ** 2]) + shift(m_s, c_s - cg))
    assert mp.mass == pytest.approx(m, rel=tol)
    assert np.allclose(mp.cg, cg, rtol=0, atol=tol * L)
    # inertia about the c.g.: the second moments less m d d^T (cancellation ~ (L / size of I)^2)
    assert np.allclose(mp.inertia, I, rtol=0, atol=tol * m * L ** 2)


def test_lumped_smeared_mass_keeps_mass_and_cg(msh):
    """Vertex quadrature integrates linear functions exactly: mass and c.g. exact."""
    ma, mb = _box_with_masses(msh, 1, lumped=True), _box_with_masses(msh, 1, lumped=False)
    a, b = mass_properties(ma), mass_properties(mb)
    tol = sum_rtol(max(ma.matrices()[1].nnz, mb.matrices()[1].nnz))   # sums over the entries of M
    assert a.mass == pytest.approx(b.mass, rel=tol)
    assert np.allclose(a.cg, b.cg, rtol=0, atol=tol * L)


def test_component_fields_make_a_component(msh, tmp_path):
    model = _box_with_masses(msh, 1)
    comp = Component(name="box", **model.component_fields())
    assert comp.dof_labels == tuple(f"x1:{c}" for c in ("Tx", "Ty", "Tz", "Rx", "Ry", "Rz"))
    assert comp.n_dof == model.n_dof and comp.field_map.shape == (3 * comp.nodes.shape[0], model.n_dof)
    assert np.allclose(comp.point_coords, [[1.2, 0.05, 0.05]])
    back = load_component(comp.save(tmp_path / "box.npz"))
    assert (back.K != comp.K).nnz == 0 and back.cell_type == "tetra"
    # the 6x6 rigid mass of the component from its labelled point matches fem's
    mp = mass_properties(model, about=(1.2, 0.05, 0.05))
    assert np.allclose(mp.rigid_mass[:3, :3], mp.mass * np.eye(3))


def test_vtu_output_roundtrip(box_model, tmp_path):
    import meshio

    modes = eigenmodes(box_model, n_modes=8)
    path = write_modes_vtu(box_model, modes, tmp_path / "modes.vtu")
    mesh = meshio.read(path)
    assert mesh.points.shape == box_model.nodes.shape and len(mesh.point_data) == 8
    key = sorted(mesh.point_data)[7]
    assert np.allclose(mesh.point_data[key], box_model.nodal_displacement(modes.shapes[:, 7]))


def test_rigid_quotients_within_roundoff_and_a_ground_spring_refused(box_model):
    """The geometric rigid modes' Rayleigh quotients are round-off of K's entries (within the
    floor eps |phi|^T |K| |phi|, fem.modes._rigid_modes), so their count does not depend on
    the machine; a spring to ground restraining a rigid motion (1 Hz on the 78 kg box) is far
    above that floor and refused as "not clean"."""
    import types

    import scipy.sparse as sp

    from liftoff.core.errors import InputError
    from liftoff.fem.modes import _check_singular, _rigid_modes

    lam, _, floor = _rigid_modes(box_model)
    assert np.all(np.abs(lam) <= floor) and floor < (2 * np.pi * 0.01) ** 2
    K, M = box_model.matrices()
    k = (2 * np.pi * 1.0) ** 2 * M.sum() / 3          # M.sum(): three times the mass (x, y, z rows)
    K2 = K + sp.csr_matrix(([k], ([0], [0])), shape=K.shape)
    sprung = types.SimpleNamespace(name="sprung", grounded=False, matrices=lambda: (K2, M),
                                   rigid_body_shape=box_model.rigid_body_shape, dof_coords=box_model.dof_coords)
    lam2, _, floor2 = _rigid_modes(sprung)
    assert np.abs(lam2).max() > 1e3 * floor2
    flexible = eigenmodes(box_model, n_modes=8).eigenvalues[6:]
    with pytest.raises(InputError, match="not clean"):
        _check_singular(sprung, np.sort(np.r_[lam2, flexible]), 0.01, floor2)
