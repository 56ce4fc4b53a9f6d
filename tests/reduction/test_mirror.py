"""Mirror-image components (reduction/mirror.py) against the same structure built at the
mirrored place: a beam stick (Timoshenko beams, off-axis links and lumped masses with
inertia, every node 6 DOFs, rotations included) at x = -3 m, and the stick built
independently from the mirrored stations, points and masses at x = +3 m. The element
matrices of the second are formed in the mirrored geometry, so they check the sign rules
(a translation along the normal, rotations about the two other axes) and the renaming."""
import numpy as np
import pytest

from liftoff.core.errors import InputError
from liftoff.reduction import craig_bampton
from liftoff.reduction.beam_stick import BeamStick, beam_stick_component
from liftoff.reduction.mirror import label_signs, mirror_cb, mirror_component, mirror_load

POINTS = {"b_left_top": 12.0, "b_left_hd_1": [-3.0 + 0.8, 0.6, 0.0], "b_left_att": [-3.0 + 1.1, -0.4, 9.0]}
MASSES = {"b_left_top": (800.0, 90.0, 60.0, 40.0), "b_left_att": (300.0, 20.0, 10.0, 5.0)}


def _stick(side: str) -> BeamStick:
    s = -1.0 if side == "left" else 1.0
    rn = lambda k: k.replace("b_left", f"b_{side}")                       # noqa: E731
    pts = {rn(k): (v if not isinstance(v, list) else [-v[0] if s > 0 else v[0], v[1], v[2]])
           for k, v in POINTS.items()}
    return BeamStick(name=f"b_{side}", axis_xy=(3.0 * s, 0.0), stations=(0.0, 4.0, 12.0), radius=(0.9, 0.7),
                     thickness=(0.01,), mass_per_length=(900.0, 400.0), points=pts,
                     masses={rn(k): v for k, v in MASSES.items()}, element_length=1.0)


@pytest.fixture(scope="module")
def pair():
    left, _ = beam_stick_component(_stick("left"))
    right, _ = beam_stick_component(_stick("right"))
    return left, right


def test_label_signs():
    labels = [f"p:{c}" for c in ("Tx", "Ty", "Tz", "Rx", "Ry", "Rz")]
    assert label_signs(labels, 0).tolist() == [-1, 1, 1, 1, -1, -1]
    assert label_signs(labels, 1).tolist() == [1, -1, 1, -1, 1, -1]
    assert label_signs(labels, 2).tolist() == [1, 1, -1, -1, -1, 1]


def test_mirrored_component_is_the_stick_built_mirrored(pair):
    """Every DOF of a stick is labelled, so the mirror's K and M are the mirrored build's
    entry by entry (to the round-off of the element matrices formed in the other geometry:
    1e-12 of the largest entry), its points and nodes the mirrored ones."""
    left, right = pair
    m = mirror_component(left, "b_right", "x")
    assert m.points == right.points and m.dof_labels == right.dof_labels
    np.testing.assert_allclose(m.point_coords, right.point_coords, atol=1e-12)
    np.testing.assert_allclose(m.nodes, right.nodes, atol=1e-12)
    for a, b in ((m.K, right.K), (m.M, right.M)):
        assert abs(a - b).max() <= 1e-12 * abs(b).max()
    f = np.zeros(left.n_dof)
    f[left.dofs_of(["b_left_att:Tx", "b_left_att:Ry"])] = [10.0, 3.0]
    g = mirror_load(left, f, "x")
    assert g[right.dofs_of(["b_right_att:Tx"])] == -10.0 and g[right.dofs_of(["b_right_att:Ry"])] == -3.0


def test_mirrored_craig_bampton_model_needs_no_eigensolve(pair):
    """mirror_cb of the left stick's CB model against the CB model of the stick built at the
    mirrored place: the same fixed-interface frequencies (1e-10), boundary stiffness and
    mass (1e-10 of their largest entry), each mode's coupling to the boundary the same up
    to the mode's sign, the label transform and the mode shapes likewise."""
    left, right = pair
    bl = [f"{p}:{c}" for p in POINTS for c in ("Tx", "Ty", "Tz", "Rx", "Ry", "Rz")]
    br = [lab.replace("b_left", "b_right") for lab in bl]
    cl = craig_bampton(left, bl, f_max=200.0)
    cr = craig_bampton(right, br, f_max=200.0)
    mc = mirror_cb(cl, "b_right", "x", source_component=left)
    assert mc.boundary_labels == cr.boundary_labels and mc.points == cr.points and mc.n_modes == cr.n_modes > 5
    np.testing.assert_allclose(mc.fixed_omega, cr.fixed_omega, rtol=1e-10)
    nq = mc.n_modes
    for a, b in ((mc.K_B, cr.K_B), (mc.M_B, cr.M_B)):
        assert np.abs(a - b).max() <= 1e-10 * np.abs(b).max()
    s = np.sign(np.sum(mc.C_M * cr.C_M, axis=1))                 # each mode's sign
    assert np.all(s != 0)
    assert np.abs(s[:, None] * mc.C_M - cr.C_M).max() <= 1e-8 * np.abs(cr.C_M).max()
    cols = np.r_[s, np.ones(mc.n_boundary)]
    assert np.abs(mc.label_transform * cols - cr.label_transform).max() <= 1e-8 * np.abs(cr.label_transform).max()
    assert np.abs(mc.fixed_interface_modes * s - cr.fixed_interface_modes).max() \
        <= 1e-8 * np.abs(cr.fixed_interface_modes).max()
    assert np.abs(mc.constraint_modes - cr.constraint_modes).max() <= 1e-10 * np.abs(cr.constraint_modes).max()
    # the mirror's own CB (reduced again) is the same model: the transform commutes with the reduction
    again = craig_bampton(mirror_component(left, "b_right", "x"), br, f_max=200.0)
    np.testing.assert_allclose(again.fixed_omega, mc.fixed_omega, rtol=1e-10)
    assert nq == again.n_modes


def test_mirror_refuses_what_it_cannot_reflect(pair):
    left, _ = pair
    with pytest.raises(InputError, match="mirror normal 'w'"):
        mirror_component(left, "b_right", "w")
    cl = craig_bampton(left, [f"b_left_top:{c}" for c in ("Tx", "Ty", "Tz", "Rx", "Ry", "Rz")], n_modes=3)
    with pytest.raises(InputError, match="mode shapes need the source component"):
        mirror_cb(cl, "b_right", "x")
