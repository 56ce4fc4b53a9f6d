"""The stick model is the FE stack's twin: same point names at the same positions."""
import importlib.util

import numpy as np
import pytest

from liftoff.workflows.pipeline import boundary_points
from liftoff.workflows.stick import StackParams, stack_components


@pytest.mark.skipif(importlib.util.find_spec("gmsh") is None, reason="meshes/ needs gmsh")
def test_stick_points_match_fe_layout():
    from liftoff.meshes import PadParams, StackLayout

    lay = StackLayout()
    fe = {}
    for side in ("left", "right"):
        fe.update(lay.holddown_points(side))
        fe.update(lay.srb_attach_points(side))
    fe.update(lay.orbiter_attach_points())
    fe.update({k: v for k, v in PadParams(layout=lay).post_points().items()})
    comps = stack_components()
    stick = {p: c.point_coord(p) for c in comps.values() for p in boundary_points(c)}
    for name, xyz in fe.items():
        np.testing.assert_allclose(stick[name], xyz, atol=1e-9, err_msg=name)


def test_stick_masses():
    """Total masses equal the parameters (beams' smeared mass + lumped masses) plus the stiff
    steel links to the interface points (500 kg/m, a few metres each: < 6 %)."""
    p = StackParams()
    comps = stack_components()
    expect = {"core": p.core_mass_lox + p.core_mass_aft, "srb_left": p.srb_mass, "srb_right": p.srb_mass,
              "orbiter": p.orbiter_mass + p.ssme_mass + p.payload_mass, "pad": p.pad_mass}
    for name, c in comps.items():
        ones = np.zeros(c.n_dof)
        ones[0::6] = 1.0                       # unit x translation of every node (6 DOFs per node)
        m = ones @ (c.M @ ones)
        assert expect[name] - 1.0 <= m <= 1.06 * expect[name], (name, m, expect[name])
