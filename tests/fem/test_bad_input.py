"""Bad input: a one-line InputError naming the culprit, never a result that looks valid."""
import re

import numpy as np
import pytest

from liftoff.fem import build_model, eigenmodes, static_solve
from liftoff.meshes.spec import Geometry, Material, Patch
from liftoff.core.errors import InputError

pytestmark = pytest.mark.fem
STEEL = Material("steel", 2.0e11, 0.3, 7800.0)


def _raises(match, fn, *a, **k):
    with pytest.raises(InputError, match=match) as info:
        fn(*a, **k)
    assert "\n" not in str(info.value)
    return info


@pytest.fixture(scope="module")
def box(msh):
    return msh("box", L=0.3, W=0.1, H=0.1, n=(3, 1, 1))


def test_missing_volume_group(box):
    _raises("volume group 'tank_wall' is not a physical volume", build_model,
            Geometry("g", box, {"solid": STEEL, "tank_wall": STEEL}))


def test_physical_volume_without_material(box):
    g = Geometry("g", box, {"other": STEEL})
    _raises("'other'", build_model, g)


@pytest.mark.parametrize("field,value,match", [("E", 0.0, "Young's modulus E = 0.0"),
                                               ("E", -1e9, "Young's modulus"),
                                               ("rho", 0.0, "density rho = 0.0"),
                                               ("rho", -5.0, "density"),
                                               ("nu", 0.5, "Poisson's ratio nu = 0.5"),
                                               ("nu", -1.0, "Poisson")])
def test_bad_material_values(box, field, value, match):
    mat = Material("bad_steel", 2.0e11, 0.3, 7800.0)
    setattr(mat, field, value)       # meshes.spec validates too; fem checks duck-typed input itself
    info = _raises(match, build_model, Geometry("g", box, {"solid": mat}))
    assert "bad_steel" in str(info.value) and "'solid'" in str(info.value)


def test_mesh_without_volume(msh):
    _raises("no volume", build_model, Geometry("g", msh("surface"), {"plate": STEEL}))


def test_missing_mesh_file(tmp_path):
    _raises("not found", build_model, Geometry("g", tmp_path / "nope.msh", {"solid": STEEL}))


def test_missing_patch_and_clamp_surfaces(box):
    _raises("patch 'hold_down_1': no physical surface 'hold_down_1'", build_model,
            Geometry("g", box, {"solid": STEEL}, patches=[Patch("hold_down_1", (0, 0, 0))]))
    _raises("clamped surface 'pedestal_base'", build_model, Geometry("g", box, {"solid": STEEL},
                                                                        clamped=["pedestal_base"]))


def test_overlapping_patches_and_patch_on_clamp(box):
    _raises("patches 'x0' and 'y0' share nodes", build_model,
            Geometry("g", box, {"solid": STEEL}, patches=[Patch("x0", (0, 0, 0)), Patch("y0", (0, 0, 0))]))
    _raises("clamped surface 'y0' shares nodes with patch 'x0'", build_model,
            Geometry("g", box, {"solid": STEEL}, patches=[Patch("x0", (0, 0, 0))], clamped=["y0"]))


def test_floating_part_free_free_and_clamped(msh):
    two = msh("two_boxes")
    free = build_model(Geometry("two", two, {"solid": STEEL}))
    _raises(r"free-free model 'two' has 12 near-zero modes", eigenmodes, free, n_modes=14)
    _raises(r"has at least 10 near-zero modes", eigenmodes, free, n_modes=10)
    # a missing tie: spiders on both facing faces, but nothing joins the two reference points
    untied = build_model(Geometry("untied", two, {"solid": STEEL},
                                  patches=[Patch("a_x1", (0.32, 0.05, 0.05)), Patch("b_x0", (0.33, 0.05, 0.05))]))
    _raises("more than its 6 rigid-body modes", eigenmodes, untied, n_modes=8)
    clamped = build_model(Geometry("half", two, {"solid": STEEL}, clamped=["a_x0"]))
    _raises(re.escape("model 'half' (clamped on a_x0) has 6 near-zero modes"), eigenmodes, clamped, n_modes=8)


def test_free_static_solve_needs_supports(box):
    model = build_model(Geometry("g", box, {"solid": STEEL}))
    _raises("free-free .* give >= 6 supports", static_solve, model, np.zeros(model.n_dof))
    _raises("load has 3 entries", static_solve, model, np.zeros(3), supports=range(6))
    _raises("give either n_modes or band_hz", eigenmodes, model)
    _raises("degree 3 not supported", build_model, Geometry("g", box, {"solid": STEEL}), degree=3)


def test_eigensolver_non_convergence_is_an_error(msh):
    """An unreachable tolerance within one iteration: ConvergenceError, not partial modes."""
    from liftoff.fem import petsc_backend as pb
    from liftoff.core.errors import ConvergenceError

    model = build_model(Geometry("g", msh("box", L=1.0, W=0.1, H=0.1, n=(20, 2, 2)), {"solid": STEEL},
                                 clamped=["x0"]))
    with pytest.raises(ConvergenceError, match="converged .* of 20 eigenpairs"):
        pb.eigensolve(model.K, model.M, 20, -1.0, tol=1e-300, max_it=1, what="model 'g'")
