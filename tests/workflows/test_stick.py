"""The stick model is the FE stack's twin: the same point names at the positions of the one
stack layout (meshes.layout.StackLayout, meshes.pad.PadParams), and its masses."""
import numpy as np

from liftoff.meshes import PadParams, StackLayout, StickParams
from liftoff.workflows.pipeline import boundary_points
from liftoff.workflows.stick import stack_components

from ..roundoff import sum_rtol


def _layout_points(lay: StackLayout, pad: PadParams) -> dict:
    fe = {}
    for side in ("left", "right"):
        fe.update(lay.holddown_points(side))
        fe.update(lay.srb_attach_points(side))
    fe.update(lay.orbiter_attach_points())
    fe.update(pad.post_points())
    return fe


def test_stick_points_are_the_layout_points():
    """Every interface point of the layout is a named stick node at the layout's position, for
    the default layout and a changed one (the stick follows the layout, it has no copy of it)."""
    for lay in (StackLayout(), StackLayout(srb_axis_x=6.8, srb_skirt_radius=2.9, orbiter_axis_y=8.2,
                                           srb_fwd_attach_z=38.0, holddown_azimuths_deg=(30.0, 150.0, 210.0, 330.0))):
        pad = PadParams(layout=lay)
        comps = stack_components(StickParams(pad=pad))
        stick = {p: c.point_coord(p) for c in comps.values() for p in boundary_points(c)}
        for name, xyz in _layout_points(lay, pad).items():
            # the same few operations of the layout (offsets, trigonometry of the azimuths): a few eps
            # of the coordinates' size
            np.testing.assert_allclose(stick[name], xyz, rtol=0, atol=sum_rtol(8) * np.abs(xyz).max(), err_msg=name)
    # the pad's pedestals stand where PadParams puts them, under the deck (clamped nodes are not
    # DOFs of the component; their coordinates are in its node table)
    nodes = comps["pad"].nodes
    lo, _ = pad.deck_bounds()
    for x, y in pad.pedestal_xy:
        assert np.any(np.all(np.isclose(nodes, [x, y, lo[2] - pad.pedestal_height], rtol=0,
                                        atol=sum_rtol(8) * np.abs(nodes).max()), axis=1))


def test_stick_masses():
    """Total masses equal the parameters (beams' smeared mass + lumped masses) plus the stiff
    steel links to the interface points (500 kg/m, a few metres each: < 6 %)."""
    p = StickParams()
    comps = stack_components()
    expect = {"core": p.core_mass_lox + p.core_mass_aft, "srb_left": p.srb_mass, "srb_right": p.srb_mass,
              "orbiter": p.orbiter_mass + p.ssme_mass + p.payload_mass, "pad": p.pad.mlp_mass}
    for name, c in comps.items():
        ones = np.zeros(c.n_dof)
        ones[0::6] = 1.0                       # unit x translation of every node (6 DOFs per node)
        m = ones @ (c.M @ ones)
        assert expect[name] - 1.0 <= m <= 1.06 * expect[name], (name, m, expect[name])
