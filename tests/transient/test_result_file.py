"""Result file: HDF5 round trip, units on every dataset, atomic write; outputs recovered on the fly
agree with the same quantities recomputed from the kept modal histories."""

import h5py
import numpy as np
import pytest

from liftoff.transient import Forcing, InputError, Recovery, TabulatedForce, TransientProblem, load_result, solve
from liftoff.transient.examples import holddown_contacts, toy_pad, toy_vehicle

from ..roundoff import product_atol


@pytest.fixture(scope="module")
def run():
    v, p = toy_vehicle(3), toy_pad(3)
    contacts = holddown_contacts(3, 1e10, release_time=0.02)
    fo = Forcing(tables=[TabulatedForce("a", "top:Tz", [0.0, 0.05], [0.0, 1e6])], gravity=(0, 0, -9.81))
    loads = Recovery("post_1_forces", "a", ["post_1:Tz", "post_1:Tx"],
                     disp=2.0 * v.rows(["post_1:Tz", "post_1:Tx"]), acc=v.rows(["post_1:Tz", "post_1:Tx"]),
                     units="mixed test units")
    prob = TransientProblem(v, p, contacts, fo, t_end=0.06, outputs={"a": ["top:Tz", "post_1:Tx"], "b": ["pad_2:Tz"]},
                            recoveries=[loads], keep_modal=True, progress=False)
    return v, p, solve(prob)


def test_outputs_match_modal_histories(run):
    v, p, r = run
    rows = v.rows(["top:Tz", "post_1:Tx"])
    # the kernel's output rows and these products sum the same n_modes products in another
    # order: n eps (|q| |rows|) (tests/roundoff.py)
    for hist, modal in ((r.displacement, "q_a"), (r.velocity, "v_a"), (r.acceleration, "acc_a")):
        assert np.allclose(hist["a"], r.modal[modal] @ rows.T, rtol=0, atol=product_atol(r.modal[modal], rows.T))
    rows_f = v.rows(["post_1:Tz", "post_1:Tx"])
    rec = r.modal["q_a"] @ (2.0 * rows_f).T + r.modal["acc_a"] @ rows_f.T
    tol = product_atol(r.modal["q_a"], 2.0 * np.abs(rows_f.T)) + product_atol(r.modal["acc_a"], rows_f.T)
    assert np.allclose(r.recovered["post_1_forces"], rec, rtol=0, atol=2 * tol)
    R = np.linalg.solve(v.rigid_body_mass, v.participation.T).T
    rb = r.modal["q_a"] @ R
    # plus the 6 x 6 solve for the rows: eps cond(rigid-body mass)
    tol = product_atol(r.modal["q_a"], R) * np.linalg.cond(v.rigid_body_mass)
    assert np.allclose(r.rigid_body_motion_a, rb, rtol=0, atol=tol)
    # the vehicle lifts off: all three hold-downs open after the release
    assert np.all(np.isfinite(r.separation_time)) and np.all(r.separation_time >= 0.02)


def test_round_trip_units_and_atomic_write(run, tmp_path):
    _, _, r = run
    path = r.save(tmp_path / "res.h5")
    assert sorted(x.name for x in tmp_path.iterdir()) == ["res.h5"]  # no temporary left behind
    with h5py.File(path, "r") as f:
        missing = []
        f.visititems(lambda name, obj: missing.append(name)
                     if isinstance(obj, h5py.Dataset) and "units" not in obj.attrs else None)
        assert missing == []
        assert f["contact/force"].attrs["units"].startswith("N")
        assert f["time"].attrs["units"] == "s"
    back = load_result(path)
    assert np.array_equal(back.time, r.time)
    assert np.array_equal(back.contact_force, r.contact_force)
    assert np.array_equal(back.contact_state, r.contact_state)
    assert back.contact_labels == r.contact_labels
    assert np.array_equal(back.separation_time, r.separation_time, equal_nan=True)
    assert np.array_equal(back.displacement["a"], r.displacement["a"])
    assert np.array_equal(back.recovered["post_1_forces"], r.recovered["post_1_forces"])
    assert back.recovered_units["post_1_forces"] == "mixed test units"
    assert np.array_equal(back.modal["q_b"], r.modal["q_b"])
    assert back.h == r.h and back.method == "direct"
    s = back.contact_summary()
    assert [c["name"] for c in s] == ["holddown_1", "holddown_2", "holddown_3"]
    assert all(c["separation_time"] is not None and c["peak_compression"] > 0 for c in s)


def test_load_result_rejects_other_files(tmp_path):
    with pytest.raises(InputError, match="result file not found"):
        load_result(tmp_path / "nope.h5")
    bad = tmp_path / "other.h5"
    with h5py.File(bad, "w") as f:
        f.attrs["format"] = "something-else"
    with pytest.raises(InputError, match="format is"):
        load_result(bad)


@pytest.mark.parametrize("rigid", [False, True])
def test_chunked_march_is_seamless(monkeypatch, rigid):
    """The time loop runs in compiled chunks; any chunk size must give bit-identical results."""
    import liftoff.transient.solver as solver

    v, p = toy_vehicle(3), toy_pad(3)
    contacts = holddown_contacts(3, 1e10, release_time=0.02, rigid=rigid)
    fo = Forcing(tables=[TabulatedForce("a", "top:Tz", [0.0, 0.05], [0.0, 1e6])], gravity=(0, 0, -9.81))
    prob = TransientProblem(v, p, contacts, fo, t_end=0.06, outputs={"a": ["top:Tz"]}, progress=False)
    ref = solve(prob)
    monkeypatch.setattr(solver, "CHUNK", 7)
    r = solve(prob)
    assert np.array_equal(r.contact_force, ref.contact_force)
    assert np.array_equal(r.contact_state, ref.contact_state)
    assert np.array_equal(r.displacement["a"], ref.displacement["a"])
    assert np.all(np.isfinite(r.separation_time))


def test_metadata_is_standard_json_and_accuracy_needs_contacts(tmp_path):
    """A results file's metadata is standard JSON: non-finite numbers (a stability margin of
    inf for rigid contacts) are null, not Infinity, which strict readers refuse; an accuracy
    target on a problem without contacts is refused (nothing would be estimated: it passed
    with an estimated error of 0)."""
    import json
    import math

    import h5py

    from liftoff.core.errors import InputError
    from liftoff.transient import Forcing, TransientProblem, solve
    from liftoff.transient.examples import holddown_contacts, toy_pad, toy_vehicle

    p = TransientProblem(toy_vehicle(), toy_pad(), holddown_contacts(4, stiffness=2e9), Forcing(gravity=(0, 0, -9.81)),
                         t_end=0.02, h=1e-3, progress=False)
    res = solve(p)
    res.metadata["stability_margin"] = math.inf
    res.metadata["nested"] = {"x": [1.0, -math.inf, math.nan]}
    path = res.save(tmp_path / "r.h5")
    with h5py.File(path) as f:
        text = f.attrs["metadata"]
    meta = json.loads(text, parse_constant=lambda c: (_ for _ in ()).throw(ValueError(c)))
    assert meta["stability_margin"] is None and meta["nested"] == {"x": [1.0, None, None]}
    with pytest.raises(InputError, match="accuracy = 0.01: .* no contacts"):
        TransientProblem(toy_vehicle(), toy_pad(), [], Forcing(), t_end=0.02, accuracy=0.01)
