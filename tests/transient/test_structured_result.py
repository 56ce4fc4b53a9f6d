"""Structured results: contact directions and recovery items carried as data (in memory and in
the HDF5 file, format version 3), HDF5 dimension scales on the time-major datasets, and the
readers (contact_summary, the lift-off report's items) using that data instead of names.

References are the problem definitions themselves (the ContactPoint and Recovery objects the
run was given) and, for the peak forces, the static closed form m g of a block on a spring."""
import math

import h5py
import numpy as np
import pytest

from liftoff.core.errors import InputError
from liftoff.transient import (ContactPoint, Forcing, ModalBody, Recovery, TabulatedForce, TransientProblem,
                               ground, load_result, solve)
from liftoff.transient.examples import holddown_contacts, toy_pad, toy_vehicle
from liftoff.transient.result import ContactDirection, RecoveryItem


@pytest.fixture(scope="module")
def run():
    """Toy vehicle on a toy pad; the hold-downs list the axial direction (Tz) first."""
    v, p = toy_vehicle(3), toy_pad(3)
    contacts = holddown_contacts(3, 1e10, release_time=0.02)
    fo = Forcing(tables=[TabulatedForce("a", "top:Tz", [0.0, 0.05], [0.0, 1e6])], gravity=(0, 0, -9.81))
    labels = ["post_1:Tz", "post_1:Rx"] if "post_1:Rx" in v.dof_labels else ["post_1:Tz", "post_1:Tx"]
    recs = [Recovery("post_1_load", "a", ["Fz", "Mx"], disp=v.rows(labels), units=("N", "N m"),
                     category="interface_force", description="test item"),
            Recovery("plain", "a", ["top:Tz"], disp=v.rows(["top:Tz"]))]
    prob = TransientProblem(v, p, contacts, fo, t_end=0.04, outputs={"a": ["top:Tz", "post_1:Tx"]},
                            recoveries=recs, keep_modal=True, progress=False)
    return prob, solve(prob)


def test_contact_directions_are_the_contact_points(run):
    prob, r = run
    expect = [ContactDirection(c.name, i, la, lb, la.split(":")[1], d == c.axial, c.normal_sign)
              for i, c in enumerate(prob.contacts) for d, (la, lb) in enumerate(zip(c.labels_a, c.labels_b))]
    assert list(r.contact_directions) == expect
    assert {d.unit for d in expect} == {"N"}
    assert ContactDirection("c", 0, "p:Rx", None, "Rx", False, 1.0).unit == "N m"
    assert r.contact_labels == tuple(f"{d.contact}/{d.label_a}" for d in expect)
    # the axial direction is listed first by holddown_contacts: the summary must use column 0 of each
    s = r.contact_summary()
    for c, row in enumerate(s):
        assert row["axial_column"] == 3 * c and row["columns"] == [3 * c, 3 * c + 1, 3 * c + 2]
        # the maximum of the same numbers (normal_sign * force with sign +1 is exact)
        assert row["peak_compression"] == pytest.approx(max(r.contact_force[:, 3 * c].max(), 0.0), rel=1e-15)


def test_recovery_items_carry_category_labels_units(run):
    _, r = run
    assert r.recovery_items["post_1_load"] == RecoveryItem("post_1_load", "a", "interface_force", ("Fz", "Mx"),
                                                           ("N", "N m"), "test item")
    # defaults: category 'user', one units string for every column
    assert r.recovery_items["plain"] == RecoveryItem("plain", "a", "user", ("top:Tz",), ("SI",), "")
    assert r.recovered_units == {"post_1_load": "per column: N, N m", "plain": "SI"}
    assert [it.name for it in r.items("interface_force")] == ["post_1_load"]


def test_round_trip_keeps_the_metadata(run, tmp_path):
    _, r = run
    back = load_result(r.save(tmp_path / "res.h5"))
    assert back.contact_directions == r.contact_directions
    assert back.recovery_items == r.recovery_items
    assert list(back.recovered) == list(r.recovered)  # order kept
    for k in r.recovered:
        assert np.array_equal(back.recovered[k], r.recovered[k])
    assert back.output_labels == r.output_labels and back.contact_names == r.contact_names


def test_dimension_scales(run, tmp_path):
    """h5py sees the time axis and the label axes as HDF5 dimension scales."""
    _, r = run
    path = r.save(tmp_path / "res.h5")
    with h5py.File(path, "r") as f:
        def scale(ds, axis):
            (name, sc), = f[ds].dims[axis].items()
            assert h5py.h5ds.is_scale(sc.id) and name == sc.name.rsplit("/", 1)[-1]
            return sc.name
        for ds in ("iterations", "contact/force", "contact/state", "body_a/displacement", "body_a/velocity",
                   "body_a/acceleration", "body_a/rigid_body_motion", "body_b/modal_q", "recovered/plain",
                   "recovered/post_1_load"):
            assert scale(ds, 0) == "/time" and f[ds].shape[0] == f["time"].shape[0]
        assert scale("contact/force", 1) == "/contact/labels"
        assert scale("contact/state", 1) == "/contact/names"
        assert scale("contact/separation_time", 0) == "/contact/names"
        assert scale("contact/direction/axial", 0) == "/contact/labels"
        assert scale("body_a/displacement", 1) == "/body_a/output_labels"
        assert scale("body_a/rigid_body_motion", 1) == "/body_a/rigid_body_components"
        assert scale("body_b/modal_q", 1) == "/body_b/mode"
        assert f["body_b/mode"][0] == 1 and f["body_b/mode"][-1] == f["body_b/modal_q"].shape[1]   # as modes_vehicle.h5
        assert scale("recovered/post_1_load", 1) == "/recovered/post_1_load_columns"
        assert [s.decode() for s in f["recovered/post_1_load_columns"][()]] == ["Fz", "Mx"]
        assert [s.decode() for s in f["contact/direction/component"][()]] == ["Tz", "Tx", "Ty"] * 3
        assert list(f["recovered/post_1_load"].attrs["column_units"]) == ["N", "N m"]
        assert f["recovered/post_1_load"].attrs["category"] == "interface_force"
        assert f.attrs["version"] == 3


def test_ground_direction_and_normal_sign(tmp_path):
    """A block below a ground spring (normal_sign -1) pushed up by a constant force m g: the
    compression is -F, static value m g; label_b None survives the file."""
    m, k = 10.0, 1e6
    block = ModalBody("block", omega=[0.0], zeta=[0.0], dof_labels=["b:Tz", "b:Tx"], phi=[[1 / math.sqrt(m)], [0.0]],
                      participation=[[0, 0, math.sqrt(m), 0, 0, 0]], rigid_body_mass=np.diag([m, m, m, 0, 0, 0]))
    c = ContactPoint("stop", ["b:Tx", "b:Tz"], [None, None], k, axial=1, normal_sign=-1.0, release_time=-math.inf)
    prob = TransientProblem(block, ground(), [c], Forcing(gravity=(0, 0, 9.81)), t_end=0.01, progress=False)
    r = solve(prob)
    d = r.contact_directions
    assert [(x.component, x.axial, x.normal_sign, x.label_b) for x in d] == [("Tx", False, -1.0, None),
                                                                            ("Tz", True, -1.0, None)]
    s = r.contact_summary()[0]
    assert s["axial_column"] == 1
    assert s["peak_compression"] == pytest.approx(m * 9.81, rel=1e-9)   # static: closed, at rest
    assert s["peak_tension"] == 0.0
    back = load_result(r.save(tmp_path / "stop.h5"))
    assert back.contact_directions == d and back.contact_summary()[0]["axial_column"] == 1
    with h5py.File(tmp_path / "stop.h5", "r+") as f:     # a version-2 file (modes from 0) still reads
        f.attrs["version"] = 2
    assert load_result(tmp_path / "stop.h5").contact_directions == d


def test_version_1_and_bad_names_are_one_line_errors(tmp_path):
    old = tmp_path / "old.h5"
    with h5py.File(old, "w") as f:
        f.attrs["format"] = "liftoff-transient-result"
        f.attrs["version"] = 1
    with pytest.raises(InputError, match=r"version 1 is not supported \(this liftoff reads version 2, 3\)"):
        load_result(old)
    rows = np.ones((1, 3))
    with pytest.raises(InputError, match="not end in '_columns'"):
        Recovery("x_columns", "a", ["c"], disp=rows)
    with pytest.raises(InputError, match="without '/'"):
        Recovery("a/b", "a", ["c"], disp=rows)
    with pytest.raises(InputError, match="2 units for 1 labels"):
        Recovery("x", "a", ["c"], disp=rows, units=("m", "m"))
    with pytest.raises(InputError, match="category"):
        Recovery("x", "a", ["c"], disp=rows, category="")
