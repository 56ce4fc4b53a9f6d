"""Time-consistent interface loads (analysis/interface_loads.py): each row is the history
sampled at its peak's time, the peak is the component's extreme, and the envelope over cases
keeps each peak's own case with its consistent components."""
import numpy as np
import pytest

from liftoff.analysis import interface_loads as il
from liftoff.core.errors import InputError

LABELS = ("Tx", "Ty", "Tz", "Rx", "Ry", "Rz")
UNITS = ("N", "N", "N", "N m", "N m", "N m")


def _interface(t, phase=0.0, scale=1.0, name="attach a on core"):
    # six components with known extremes: component j = (j+1) sin(2 pi (j+1) t / T + phase)
    T = t[-1] - t[0]
    scale = np.broadcast_to(scale, (6,))
    vals = np.column_stack([scale[j] * (j + 1) * np.sin(2 * np.pi * (j + 1) * t / T + phase) for j in range(6)])
    return il.InterfaceHistory(name, LABELS, UNITS, vals)


def test_rows_are_the_histories_at_the_peak_times():
    t = np.linspace(0.0, 2.0, 2001)
    itf = _interface(t, phase=0.3)
    rows = il.time_consistent(t, [itf], "nominal")
    assert len(rows) == 12                      # 6 components x (max, min)
    for r in rows:
        i = int(np.flatnonzero(t == r["time"])[0])
        # the consistent vector is the history's sample at that time, bit for bit
        assert np.array_equal(r["values"], itf.values[i])
        col = itf.values[:, r["component"]]
        peak = col.max() if r["extreme"] == "max" else col.min()
        assert r["values"][r["component"]] == peak
        # and a closed form: component j peaks at +/-(j+1) (the grid samples the sine to
        # within (j+1) (1 - cos(pi (j+1) dt / T)) ~ 1e-5 (j+1)^3 of its crest)
        j = r["component"]
        assert abs(abs(peak) - (j + 1)) < 2e-5 * (j + 1) ** 3


def test_envelope_keeps_each_peaks_case_and_its_consistent_components():
    t = np.linspace(0.0, 1.0, 501)
    a = il.time_consistent(t, [_interface(t, 0.0, 1.0)], "a")
    b = il.time_consistent(t, [_interface(t, 1.0, np.array([1.5, 1.5, 1.5, 0.5, 0.5, 0.5]))], "b")
    env = il.envelope([a, b])
    assert len(env) == 12
    assert {r["case"] for r in env} == {"a", "b"}   # b sets the forces' peaks, a the moments'
    for r in env:
        ra = next(x for x in a if x["peak"] == r["peak"])
        rb = next(x for x in b if x["peak"] == r["peak"])
        va, vb = ra["values"][r["component"]], rb["values"][r["component"]]
        winner = ra if (va >= vb if r["extreme"] == "max" else va <= vb) else rb
        assert r["case"] == winner["case"] and np.array_equal(r["values"], winner["values"])


def test_csv_round_trip(tmp_path):
    t = np.linspace(0.0, 1.0, 101)
    rows = il.time_consistent(t, [_interface(t), _interface(t, 0.5, 2.0, "attach b on orbiter")], "nominal")
    path = il.write_csv(rows, tmp_path / "interface_loads_nominal.csv", "cases: nominal")
    text = path.read_text()
    assert text.startswith("# liftoff time-consistent interface loads") and "# cases: nominal" in text
    back = il.read_csv(path)
    assert len(back) == len(rows)
    for r, o in zip(back, rows):
        assert (r["interface"], r["peak"], r["case"], r["labels"], r["units"]) == \
            (o["interface"], o["peak"], o["case"], o["labels"], o["units"])
        # written with 7 significant digits (%.6e): relative 5e-7 of each value
        np.testing.assert_allclose(r["values"], o["values"], rtol=5e-7, atol=1e-12)
        assert abs(r["time"] - o["time"]) <= 5e-7 * abs(o["time"]) + 1e-15


def test_bad_shapes_are_refused():
    with pytest.raises(InputError, match="attach x"):
        il.InterfaceHistory("attach x", LABELS, UNITS, np.zeros((10, 5)))
    t = np.linspace(0.0, 1.0, 11)
    with pytest.raises(InputError, match="12 samples for 11 times"):
        il.time_consistent(t, [il.InterfaceHistory("attach y", LABELS, UNITS, np.zeros((12, 6)))], "c")
    with pytest.raises(InputError, match="no interface loads"):
        il.write_csv([], __import__("pathlib").Path("/tmp/none.csv"))
