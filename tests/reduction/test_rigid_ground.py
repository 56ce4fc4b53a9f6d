"""reduction.models.RigidGround / rigid_ground_cb (issue 23: "rigid ground" as the pad): no
DOFs, its named points labelled with zero displacement; the pad's system modes are none,
and the transient holds each post to a fixed point (body b is ground: transient.model)."""
import numpy as np
import pytest

from liftoff.core.errors import InputError
from liftoff.reduction.models import RigidGround, rigid_ground_cb


def test_ground_has_points_and_no_dofs():
    g = RigidGround({"post_1": (1.0, 2.0, 3.0), "post_2": [-1, 2, 3]})
    g.check()
    cb = rigid_ground_cb(g, "pad")
    assert cb.n_modes == 0 and cb.boundary_labels == () and cb.M.shape == (0, 0)
    assert cb.points == ("post_1", "post_2") and cb.point_coords[1] == pytest.approx([-1.0, 2.0, 3.0])
    assert cb.label_transform.shape == (12, 0)
    from liftoff.reduction.assembly import assemble
    from liftoff.reduction.system import system_modes

    modes = system_modes(assemble([cb], "pad"), n_rigid=0)
    assert modes.omega.size == 0


@pytest.mark.parametrize("points, message", [(None, "give its points"), ({}, "give its points"),
                                             ({"p": (1.0, 2.0)}, "must be \\[x, y, z\\]")])
def test_bad_ground_refused(points, message):
    with pytest.raises(InputError, match=message):
        RigidGround(points).check()
