"""A shell component through the rest of the pipeline unchanged: reduction.Component (file
round trip, the stage cache's format), Craig-Bampton against fem's own SLEPc modes, the
CB check's mass properties against fem's, full-field recovery and a picture of it."""
import numpy as np
import pytest

from liftoff.fem.snapshot import Part, snapshot_png  # pyvista first (before dolfinx)
from liftoff.fem import build_model, eigenmodes, mass_properties
from liftoff.meshes.spec import Geometry, Material, Patch, SmearedMass
from liftoff.reduction import (Component, assemble, cb_check, craig_bampton, field_displacement, field_recovery,
                               system_modes)
from liftoff.reduction.component import load_component, save_component
from liftoff.reduction.models import six_labels

pytestmark = pytest.mark.fem


@pytest.fixture(scope="module")
def tube(msh):
    path = msh("shell_tube", R=0.1, L=1.0, n_around=8, n_along=5)
    geo = Geometry("tube", path, {"tube": Material("al", 70e9, 0.3, 2700.0)}, shells={"tube": 0.004},
                   patches=[Patch("root", (0, 0, 0)), Patch("tip", (0, 0, 1.0))],
                   smeared_masses=[SmearedMass("band", 0.5)])
    model = build_model(geo)
    return model, Component(name="tube", **model.component_fields())


def test_shell_component_round_trip(tube, tmp_path):
    _, comp = tube
    back = load_component(save_component(comp, tmp_path / "tube.npz"))
    assert back.cell_type == "triangle6" and np.array_equal(back.cells, comp.cells)
    assert abs(back.K - comp.K).max() == 0 and abs(back.field_map - comp.field_map).max() == 0


def test_cb_of_shell_against_slepc_modes_and_mass(tube):
    model, comp = tube
    bl = six_labels("root") + six_labels("tip")
    # SLEPc asked for four modes more than compared: the tube's modes come in pairs, and the
    # last one asked for may be either of a pair, or be missed (a missed partner: 1.5 %)
    ref = eigenmodes(model, n_modes=20)
    cb = craig_bampton(comp, bl, n_modes=comp.n_dof - len(bl))      # all modes: a change of basis
    sysm = system_modes(assemble([cb], "tube"))
    rel = sysm.freq_hz[6:16] / ref.freq_hz[6:16] - 1
    print(f"shell tube ({comp.n_dof} DOFs): CB all modes vs SLEPc, max rel. error {np.abs(rel).max():.1e}")
    # exact change of basis; SLEPc converged to 1e-10 on the residual -> ~1e-9 on frequency
    assert np.abs(rel).max() < 1e-7
    chk = cb_check(craig_bampton(comp, bl, n_modes=10), comp, ref_point=(0, 0, 0))
    s = chk.summary
    mp = mass_properties(model)
    assert s["rb_ok"]
    assert s["mass_properties_cb"]["mass"] == pytest.approx(mp.mass, rel=1e-12)
    assert np.allclose(s["mass_properties_cb"]["cg"], mp.cg, atol=1e-12)
    # full-field recovery of the first bending pair (a double mode of the axisymmetric tube:
    # any rotation within the pair is a mode) lies in the span of fem's pair
    u = field_recovery(assemble([cb], "tube"), sysm, "tube", comp)
    U = model.field_map() @ ref.shapes[:, 6:8]
    for j in (6, 7):
        c, *_ = np.linalg.lstsq(U, u[:, j], rcond=None)
        assert np.linalg.norm(U @ c - u[:, j]) < 1e-6 * np.linalg.norm(u[:, j])
    # the displacement of given modal coordinates (the snapshots' and fields' way: T q first)
    # is the recovery matrix times them: the same sums in another order, round-off apart
    q = np.random.default_rng(0).standard_normal((sysm.phi.shape[1], 2))
    d = field_displacement(assemble([cb], "tube"), sysm, "tube", comp, q)
    assert np.allclose(d, u @ q, rtol=0, atol=1e-12 * np.abs(u @ q).max())
    assert np.allclose(field_displacement(assemble([cb], "tube"), sysm, "tube", comp, q[:, 0]), d[:, 0])


def test_recovered_shell_field_picture(tube, tmp_path):
    model, comp = tube
    modes = eigenmodes(model, n_modes=8)
    u = (comp.field_map @ modes.shapes[:, 7]).reshape(-1, 3)
    path = snapshot_png(tmp_path / "tube.png", Part(comp.nodes, comp.cells, comp.cell_type, u), title="shell tube")
    import matplotlib.image as mpimg

    img = mpimg.imread(str(path))[..., :3]
    assert img.std() > 0.05 and np.mean(np.any(img < 0.95, axis=2)) > 0.01
