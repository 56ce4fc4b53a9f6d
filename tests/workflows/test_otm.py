"""A payload provider's OTM applied at an interface point ([[recovery.otm]], issue 24;
reduction.nastran.interface_otm): matrices written to an OUTPUT4 file in inch-pound-second
units, read back (pyyeti), converted to SI and composed with the vehicle's modes at the
point. Checked on the stick stack against the run's own output-point accelerations and
closed-form rigid-body kinematics computed here in SI: a rigid lever's acceleration
a + alpha x r and a rigid mass's inertia force m (a + alpha x r)."""
import importlib.util
import tomllib

import numpy as np
import pytest
from liftoff.transient import load_result

from liftoff.config import default_text
from liftoff.core.errors import InputError
from liftoff.workflows.cli import main

from .test_run import STICK, _toml

pytestmark = pytest.mark.skipif(importlib.util.find_spec("pyyeti") is None, reason="needs pyyeti (nastran extra)")
INCH = 0.0254
SLINCH = 0.45359237 * 9.80665 / INCH        # kg in one lbf s^2/in
R_IN = np.array([20.0, -10.0, 150.0])       # in: the lever from the interface point to the payload's c.g.
M_SRC = 30.0                                # lbf s^2/in: the payload's mass


def _skew(r):
    return np.array([[0, -r[2], r[1]], [r[2], 0, -r[0]], [-r[1], r[0], 0]])


def _otm_file(path):
    from liftoff.reduction import write_op4

    lever = np.hstack([np.eye(3), -_skew(R_IN)])                      # a_cg = a + alpha x r = a - r x alpha
    return write_op4(path, {"ATM0": np.hstack([np.eye(3), np.zeros((3, 3))]),
                            "ATMR": np.hstack([np.zeros((3, 3)), np.eye(3)]),
                            "ATML": lever, "LTM": M_SRC * lever})


def _scenario(tmp_path, otm: list) -> object:
    d = tomllib.loads(default_text())
    d["model"] = STICK
    d["time"]["t_end"] = 7.0
    d["case"] = [{"name": "nominal"}]
    d["recovery"]["otm"] = otm
    p = tmp_path / "s.toml"
    p.write_text(_toml(d))
    return p


def test_otm_at_the_payload_station_against_rigid_body_kinematics(tmp_path, capsys):
    _otm_file(tmp_path / "payload_otm.op4")
    pt = "payload_station"
    common = {"file": "payload_otm.op4", "point": pt, "units": "in-lbf-s"}
    otm = [dict(common, name="translation", acc="ATM0", quantity="acceleration", rows=["p:Tx", "p:Ty", "p:Tz"]),
           dict(common, name="rotation", acc="ATMR", quantity="angular_acceleration"),
           dict(common, name="lever", acc="ATML", quantity="acceleration", rows=["cg:Tx", "cg:Ty", "cg:Tz"]),
           dict(common, name="inertia", acc="LTM", quantity="load", rows=["cg:Tx", "cg:Ty", "cg:Tz"])]
    p = _scenario(tmp_path, otm)
    assert main(["run", str(p), "--out", str(tmp_path / "o"), "--cache", str(tmp_path / "c"), "--no-progress",
                 "--no-snapshots", "--no-error-estimate"]) == 0
    capsys.readouterr()
    res = load_result(tmp_path / "o" / "results_nominal.h5")
    a_own = res.acceleration["a"][:, [res.output_labels["a"].index(f"{pt}:{c}") for c in ("Tx", "Ty", "Tz")]]
    rec = res.recovered
    a, alpha = rec["otm_translation"], rec["otm_rotation"]
    scale = np.abs(a_own).max()
    assert scale > 0.1                                   # the payload accelerates (m/s^2)
    # the OTM [I 0] in in/s^2 per in/s^2 is the run's own acceleration of the point, in SI
    np.testing.assert_allclose(a, a_own, rtol=0, atol=1e-9 * scale)
    assert res.recovery_items["otm_translation"].units == ("m/s^2",) * 3
    assert res.recovery_items["otm_rotation"].units == ("rad/s^2",) * 3
    # the lever (translation and rotation columns, inches) and the inertia force (lbf s^2/in),
    # against the kinematics here in SI: a + alpha x r, m (a + alpha x r)
    r_si = R_IN * INCH
    expect = a_own + np.cross(alpha, r_si)
    big = np.abs(expect).max()
    np.testing.assert_allclose(rec["otm_lever"], expect, rtol=0, atol=1e-9 * big)
    np.testing.assert_allclose(rec["otm_inertia"], M_SRC * SLINCH * expect, rtol=0, atol=1e-9 * M_SRC * SLINCH * big)
    assert res.recovery_items["otm_inertia"].units == ("N",) * 3
    # the rows reach the max/min table under the OTM's name and labels
    table = (tmp_path / "o" / "maxmin_nominal.csv").read_text()
    assert "otm_inertia cg:Tx,N," in table and "otm_lever cg:Tz,m/s^2," in table


def test_bad_otms_are_one_line_before_any_stage(tmp_path, capsys):
    _otm_file(tmp_path / "payload_otm.op4")
    base = {"name": "p", "file": "payload_otm.op4", "point": "payload_station", "acc": "ATM0"}
    for over, expect in (({"file": "nope.op4"}, "recovery.otm[0].file: file not found"),
                         ({"acc": None}, "recovery.otm[0]: give at least one of disp, vel, acc"),
                         ({"units": "furlong"}, "recovery.otm[0].units"),
                         ({"bogus": 1}, "recovery.otm[0]: unknown key 'bogus'")):
        o = {k: v for k, v in {**base, **over}.items() if v is not None}
        p = _scenario(tmp_path, [o])
        assert main(["run", str(p), "--out", str(tmp_path / "o"), "--no-progress"]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and expect in err, err
        assert not (tmp_path / "o").exists()
    # found when the case is built (the matrices need pyyeti): a matrix absent from the file or
    # of the wrong shape, and a point not on the vehicle
    from liftoff.reduction.nastran import interface_otm

    with pytest.raises(InputError, match="matrix 'nothere' not found"):
        interface_otm(tmp_path / "payload_otm.op4", name="p", units="SI", acc="NOTHERE")
    from liftoff.reduction import write_op4

    write_op4(tmp_path / "bad.op4", {"ATM": np.eye(3)})
    with pytest.raises(InputError, match=r"matrix 'atm' is 3 x 3, expected 3 x 6"):
        interface_otm(tmp_path / "bad.op4", name="p", units="SI", acc="ATM")
    p = _scenario(tmp_path, [dict(base, point="nowhere")])
    assert main(["run", str(p), "--out", str(tmp_path / "o"), "--cache", str(tmp_path / "c"), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "recovery.otm[0].point: point 'nowhere' is not on the" in err, err
