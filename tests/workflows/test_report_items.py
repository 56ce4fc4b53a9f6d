"""The lift-off report reads names, units and kinds of its histories from the result's metadata
(contact directions, recovery items), not from the spelling of labels: checked on a run whose
hold-downs list the axial direction first, with recoveries of several
categories. Reference: the problem definition the run was given."""
import numpy as np

from liftoff.transient import ContactPoint, Forcing, PointForce, Recovery, TransientProblem, solve
from liftoff.transient.examples import holddown_contacts, toy_pad, toy_vehicle
from liftoff.workflows import report


def test_items_follow_the_result_metadata():
    v, p = toy_vehicle(3), toy_pad(3)
    cps = [ContactPoint(f"hd{i}", [f"post_{i}:{c}" for c in ("Tz", "Ty", "Tx")],
                        [f"pad_{i}:{c}" for c in ("Tz", "Ty", "Tx")], 1e10, axial=0) for i in (1, 2, 3)]
    recs = [Recovery("attach_x", "a", ["Tx", "Rz"], disp=v.rows(["top:Tx", "top:Tz"]), units=("N", "N m"),
                     category="interface_force"),
            Recovery("q", "a", [f"q{j}" for j in range(v.n_modes)], disp=np.eye(v.n_modes), category="modal"),
            Recovery("mine", "a", ["u"], disp=v.rows(["top:Tz"]), units="mm")]
    prob = TransientProblem(v, p, cps, Forcing(gravity=(0, 0, -9.81)), t_end=0.005, outputs={"a": ["top:Tz"]},
                            recoveries=recs, progress=False)
    r = solve(prob)
    its = report.items(r, {"attach_x": ("top", "core")})
    names = [(it.name, it.unit, it.category) for it in its]
    posts = [(f"post {c.name} {la.split(':')[1]}", "N", "contact_force")
             for c in cps for la in c.labels_a]
    assert names[:len(posts)] == posts
    assert names[len(posts):] == [("attach top on core Tx", "N", "interface_force"),
                                  ("attach top on core Rz", "N m", "interface_force"),
                                  ("mine u", "mm", "user"),
                                  ("disp top:Tz", "m", "displacement"), ("acc top:Tz", "m/s^2", "acceleration")]
    # the columns are the result's: post forces in direction order, recoveries by name
    assert np.array_equal(its[0].values, r.contact_force[:, 0])
    assert np.array_equal(its[len(posts) + 1].values, r.recovered["attach_x"][:, 1])
    rows = report.maxmin(r.time, its, "c")
    assert [row["category"] for row in rows] == [n[2] for n in names]


def test_acceleration_recoveries_take_the_band(tmp_path):
    """A recovery made from the modal accelerations alone (an ATM: liquid pressures, liquid
    inertia forces) is set, like an output acceleration, by the highest modes; with a band it
    is reported low-pass filtered (analysis/spectra.lowpass, its own unit test), the raw
    history kept; a recovery with a displacement part is not filtered. The flag survives the
    results file. Reference: lowpass applied to the same history, and the unfiltered history."""
    from liftoff.transient.result import load_result
    from liftoff.analysis.spectra import lowpass

    v, p = toy_vehicle(3), toy_pad(3)
    cps = holddown_contacts(3, release_time=0.01)    # the lateral load is let go at release
    rows = v.rows(["top:Tx"])
    recs = [Recovery("atm", "a", ["a"], acc=rows, units="m/s^2"),
            Recovery("ltm", "a", ["f"], disp=rows, acc=rows, units="N", category="interface_force")]
    prob = TransientProblem(v, p, cps, Forcing([PointForce("a", "top:Tx", 3e5)], gravity=(0, 0, -9.81)), t_end=0.05,
                            outputs={"a": ["top:Tz"]}, recoveries=recs, progress=False)
    r = solve(prob)
    assert r.recovery_items["atm"].from_acceleration and not r.recovery_items["ltm"].from_acceleration
    r = load_result(r.save(tmp_path / "r.h5"))
    assert r.recovery_items["atm"].from_acceleration and not r.recovery_items["ltm"].from_acceleration
    band = 50.0
    its = {it.name: it for it in report.items(r, {}, band_hz=band)}
    atm, ltm = its["atm a"], its["ltm f"]
    assert np.array_equal(atm.values, lowpass(r.recovered["atm"], r.h, band)[:, 0])
    assert np.array_equal(atm.history, r.recovered["atm"][:, 0])
    assert not np.allclose(atm.values, atm.history)      # the release excites modes above the band
    assert ltm.raw is None and np.array_equal(ltm.values, r.recovered["ltm"][:, 0])
    assert np.array_equal(its["acc top:Tz"].values, lowpass(r.acceleration["a"], r.h, band)[:, 0])


def test_band_check_warns_when_the_band_reaches_a_component_cut():
    """summary.txt states what the acceleration band passes at the lowest component cut (the
    highest kept fixed-interface mode); above 1 % it warns. Reference: |H|^2 of the order-n
    Butterworth run twice, 1 / (1 + (f/f_c)^(2n)), at the cut."""
    from types import SimpleNamespace

    from liftoff.analysis.spectra import LOWPASS_ORDER

    six = ("a:Tx", "a:Ty", "a:Tz", "b:Tx", "b:Ty", "b:Tz")
    cb = lambda n, f, n_dof, r=0: SimpleNamespace(n_modes=n, n_eigenmodes=n - r, fixed_freq_hz=np.array(f, float),  # noqa: E731
                                                  n_dof=n_dof, boundary_labels=six)
    cbs = {"core": cb(2, [10.0, 59.0], 100), "srb": cb(1, [80.0], 100), "rigid": cb(0, [], 6),
           "whole": cb(3, [1.0, 2.0, 5.0], 9)}                 # all 3 interior modes: no cut
    ok = report.band_lines(40.0, cbs)
    leak = 1 / (1 + (59.0 / 40.0) ** (2 * LOWPASS_ORDER))
    assert len(ok) == 1 and f"passes {100 * leak:.2g} % at 59.0 Hz" in ok[0] and "'core'" in ok[0]
    # the band is the -6 dB point: 1 / (1 + 0.8^16) = 0.973 passed at 32 Hz, one half at 40 Hz
    assert "(zero phase, -6 dB there: 97 % passed at 32 Hz, 50 % at 40 Hz)" in ok[0]
    wide = report.band_lines(55.0, cbs)
    assert len(wide) == 2 and "WARNING" in wide[1] and "'core'" in wide[1]
    assert "unfiltered" in report.band_lines(0.0, cbs)[0]
    by_band = report.band_lines(40.0, cbs, {"core": 60.0})   # selected by band: cut at f_max, not at 59 Hz
    assert "at 60.0 Hz" in by_band[0] and "'core'" in by_band[0]
    assert "passes" not in report.band_lines(40.0, {})[0]      # a model without CB components
    # residual vectors (above the cut, reduction.craig_bampton) do not move it: still 59 Hz, still a warning
    with_rv = report.band_lines(55.0, {**cbs, "core": cb(4, [10.0, 59.0, 900.0, 1500.0], 100, r=2)})
    assert len(with_rv) == 2 and "at 59.0 Hz" in with_rv[1] and "'core'" in with_rv[1]


def test_filtered_peaks_at_an_end_of_the_record_are_named():
    """The zero-phase filter (analysis.spectra.lowpass) carries an end transient: a 35 Hz sine
    on a static level, ending mid-period, filtered to 40 Hz, comes out above its steady
    filtered amplitude (the reference: |H|^2 at 35 Hz) within EDGE_PERIODS / f_c of the end.
    analysis.histories.edge_extremes names a band-limited item whose max or min lies there,
    not one whose extremes lie inside the record, nor an unfiltered one."""
    from liftoff.analysis.histories import EDGE_PERIODS, edge_extremes
    from liftoff.analysis.spectra import lowpass, lowpass_gain
    from liftoff.analysis.tables import Item

    h, f, band = 1e-3, 35.0, 40.0
    t = np.arange(0.0, 3.0 + 0.3 / f, h)
    x = 5.0 + np.sin(2 * np.pi * f * t)
    y = lowpass(x, h, band)
    gain = lowpass_gain(f, band)
    inside = np.abs(t - t[-1]) > EDGE_PERIODS / band
    # steady, inside the record: the gain, within 1 % (the end transient's tail beyond the span)
    assert abs(y[inside][t[inside] > 0.5].max() - 5.0 - gain) < 1e-2 * gain
    assert y.max() - 5.0 > 1.05 * gain and t[np.argmax(y)] > t[-1] - EDGE_PERIODS / band   # raised at the end
    hump = 5.0 + np.exp(-((t - 1.5) / 0.2) ** 2)                                   # its peak mid-record
    its = [Item("acc end", "m/s^2", y, "acceleration", raw=x),
           Item("acc mid", "m/s^2", lowpass(hump, h, band), "acceleration", raw=hump),
           Item("post end", "N", x, "contact_force")]                               # unfiltered: not checked
    got = edge_extremes(t, its, band)
    assert [(n, side) for n, side, _ in got] == [("acc end", "max")] and got[0][2] == t[np.argmax(y)]
    assert edge_extremes(t, its, 0.0) == []


def test_display_points_keep_every_peak_where_it_is():
    """A long history is drawn through fewer points (report.display_points); the reference is
    the history itself: its global and per-bin extremes are drawn with their own times, in
    time order, and a short history is drawn as it is."""
    rng = np.random.default_rng(5)
    n, bins = 106_383, 2000
    t = np.linspace(0.0, 9.6, n)
    y = np.sin(40 * t) + 0.1 * rng.standard_normal(n)
    y[77_777] = 5.0                                          # a one-sample spike
    x2, y2 = report.display_points(t, y, bins)
    assert x2.size <= 2 * bins + 2 and np.all(np.diff(x2) > 0)
    assert y2.max() == y.max() == 5.0 and x2[np.argmax(y2)] == t[77_777]
    assert y2.min() == y.min() and x2[np.argmin(y2)] == t[np.argmin(y)]
    assert x2[0] == t[0] and x2[-1] == t[-1]
    m = -(-n // bins)                                        # every run's extremes are there
    for b in (0, 1000, -(-n // m) - 1):
        seg = y[b * m:(b + 1) * m]
        assert seg.max() in y2 and seg.min() in y2
    xs, ys = report.display_points(t[:3000], y[:3000], bins)
    assert xs is not None and np.array_equal(ys, y[:3000])


def test_slosh_summary_finds_each_liquids_first_slosh_mode_and_peak_force():
    """report.slosh_summary on a CB model whose recovery item slosh_force has two liquids'
    pendulums: each liquid's first slosh mode is the lowest fixed-interface mode where its
    pendulums carry a quarter of their largest force per unit modal coordinate; its peak
    force is the largest |max|, |min| of its envelope rows."""
    from types import SimpleNamespace

    from liftoff.reduction.craig_bampton import CBRecovery

    labels = ("lox:1", "lox:2", "lh2:1", "lh2:2")
    disp = np.zeros((4, 5 + 6))
    disp[2, 0] = disp[3, 0] = 5.0          # mode 1: lh2 sloshes
    disp[0, 1] = 1.0                       # mode 2: lox at a tenth of its largest (below a quarter)
    disp[0, 2] = 10.0                      # mode 3: lox's own mode
    disp[1, 4] = 3.0                       # mode 5: lox again, smaller
    cb = SimpleNamespace(recovery=(CBRecovery("slosh_force", labels, ("N",) * 4, disp=disp),), n_modes=5,
                         fixed_freq_hz=np.array([0.34, 0.38, 0.41, 0.6, 0.7]))
    rows = [{"item": "core_slosh_force lox:1", "max": 2.0e3, "min": -5.0e3},
            {"item": "core_slosh_force lox:2", "max": 1.0e3, "min": -1.0e3},
            {"item": "core_slosh_force lh2:1", "max": 7.0e2, "min": -1.0e2},
            {"item": "core_slosh_wave_height lox:2", "max": 0.02, "min": -0.03}]
    out = {r["liquid"]: r for r in report.slosh_summary({"core": cb}, rows)}
    assert out["lox"]["mode"] == 3 and out["lox"]["hz"] == 0.41 and out["lox"]["peak_n"] == 5.0e3
    assert out["lh2"]["mode"] == 1 and out["lh2"]["hz"] == 0.34 and out["lh2"]["peak_n"] == 7.0e2
    assert out["lox"]["peak_item"] == "core_slosh_force lox:1"
    assert out["lox"]["peak_wave_m"] == 0.03 and out["lh2"]["peak_wave_m"] is None


def test_largest_loads_promise_estimates_only_where_their_lines_carry_them():
    """summary.txt's "largest loads": each line on its larger side; the heading says estimates
    only as far as the lines shown carry one (a review: a campaign's post compression peaks of a
    generated case, no estimate, under a heading promising them, tripped by the tension side's
    estimate of a named case)."""
    def row(item, mx, mn, mx_err, mn_err, case_max="d0001", case_min="nominal"):
        return {"item": item, "unit": "N", "category": "contact_force", "max": mx, "t_max": 1.0, "case_max": case_max,
                "min": mn, "t_min": 2.0, "case_min": case_min, "max_err": mx_err, "min_err": mn_err}

    lines = report.largest_load_lines([row("post a Tz", 7e6, -0.0, float("nan"), 0.0)])
    assert "no step-error estimate" in lines[0] and "est. error" not in lines[1]
    lines = report.largest_load_lines([row("post a Tz", 7e6, -0.0, 5.0, 0.0), row("post b Tz", 6e6, 0.0, None, 1.0)])
    assert "est. error where the case had a run at h/2" in lines[0]
    assert "(est. error 5e-06 MN)" in lines[1] and "est. error" not in lines[2]
    lines = report.largest_load_lines([row("post a Tz", 7e6, -0.0, 5.0, None, case_max="nominal")])
    assert "est. error: Richardson from a run at h/2" in lines[0]
