"""reduction.models.RigidMass / rigid_mass_cb (issue 23: a rigid mass as a vehicle
component): its Craig-Bampton model (no modes, its point's six DOFs) against the rigid-body
mass matrix of closed form (parallel-axis theorem), and bad input refused in one line."""
import numpy as np
import pytest

from liftoff.core.errors import InputError
from liftoff.reduction.models import RigidMass, rigid_mass_cb


def _skew(r):
    return np.array([[0, -r[2], r[1]], [r[2], 0, -r[0]], [-r[1], r[0], 0]])


def test_mass_matrix_is_the_parallel_axis_theorem():
    """About the point P, with r = c.g. - P and v_cg = u + theta x r = u - [r]x theta:
    M = [[m I, -m [r]x], [m [r]x, I_cg - m [r]x [r]x]] (= I_cg + m (|r|^2 I - r r^T))."""
    p = RigidMass("pif", (1.0, -2.0, 3.0), 4850.0, (1.3, -1.8, 5.0), (6466.7, 6100.0, 1717.1, 120.0, -40.0, 15.0))
    p.check()
    cb = rigid_mass_cb(p, "payload")
    r = np.array(p.cg) - np.array(p.at)
    S = _skew(r)
    ref = np.block([[p.mass * np.eye(3), -p.mass * S], [p.mass * S, p.tensor() - p.mass * S @ S]])
    assert cb.M == pytest.approx(ref, rel=1e-12, abs=1e-12 * np.abs(ref).max())
    assert np.allclose(ref[3:, 3:], p.tensor() + p.mass * (r @ r * np.eye(3) - np.outer(r, r)))
    assert cb.n_modes == 0 and cb.boundary_labels == tuple(f"pif:{c}" for c in ("Tx", "Ty", "Tz", "Rx", "Ry", "Rz"))
    assert not np.any(cb.K)
    assert cb.points == ("pif",) and cb.point_coords[0] == pytest.approx(p.at)
    import warnings

    from liftoff.reduction.checks import cb_check

    with warnings.catch_warnings():             # a run's cb_checks.txt: no 0/0 for a body without stiffness
        warnings.simplefilter("error")
        s = cb_check(cb).summary
    assert s["K_B_min_eig_rel"] == 0.0 and s["K_B_n_zero_eig"] == 6 and s["M_positive_definite"]


@pytest.mark.parametrize("kw, message", [
    (dict(mass=0.0), "mass must be > 0"),
    (dict(mass=float("nan")), "mass must be > 0"),
    (dict(inertia=(1.0, 1.0, 3.0)), "not a body's"),          # Izz above Ixx + Iyy
    (dict(inertia=(1.0, -1.0, 1.0)), "not a body's"),
    (dict(inertia=(1.0, 1.0)), "inertia is"),
    (dict(cg=(0.0, 1.0)), "cg must be"),
    (dict(point=""), "point must be"),
])
def test_bad_rigid_mass_refused(kw, message):
    args = dict(point="p", at=(0.0, 0.0, 0.0), mass=10.0, cg=(), inertia=(1.0, 1.0, 1.0))
    args.update(kw)
    with pytest.raises(InputError, match=message):
        RigidMass(**args).check()
