"""Load campaigns on the stick model: the runner's envelope equals that of the same cases run
one by one; a restarted campaign skips the cases already done; statistics equal the batch
formulas; envelope histories, ParaView output, the comparison table and the command line."""
import csv
import pickle

import numpy as np
import pytest

from liftoff.transient import solve
from liftoff.workflows import report
from liftoff.workflows.executors import InlineExecutor
from liftoff.workflows.loads import build_problem
from liftoff.workflows.run import Options, run

from .test_run import STICK, _scenario

QUIET = dict(progress=False, plots=False, snapshots=False, echo=lambda *a, **k: None)


@pytest.fixture(scope="module")
def campaign4(tmp_path_factory):
    """Two named cases + 4 generated ones on 2 worker processes (t_end 7.2 s)."""
    tmp = tmp_path_factory.mktemp("campaign")
    p = _scenario(tmp, STICK, t_end=7.2)
    out = run(p, tmp / "out", cache_dir=tmp / "cache", n_cases=4, options=Options(workers=2), **QUIET)
    return tmp, p, out


def _same(env_a, env_b) -> bool:
    """Envelope rows equal to the bit (NaN, an estimate not made, equal to NaN)."""
    norm = lambda rows: [{k: ("nan" if isinstance(v, float) and v != v else v) for k, v in r.items()} for r in rows]  # noqa: E731
    return norm(env_a) == norm(env_b)


def _one_by_one(out):
    """Max/min of every case solved here, in this process, without the runner."""
    sc, stack = out.scenario, next(iter(out.stacks.values()))
    per_case = {}
    for case in list(sc.cases) + [sc.generated_case(i) for i in range(sc.n_generated)]:
        cp = build_problem(case, stack, progress=False)
        res = solve(cp.problem)
        per_case[case.name] = report.maxmin(res.time, report.items(res, cp.attach, band_hz=sc.post.acceleration_band_hz),
                                            case.name)
    return per_case


def test_campaign_envelope_equals_cases_run_one_by_one(campaign4):
    _, _, out = campaign4
    per_case = _one_by_one(out)
    ref = report.envelope(per_case)
    assert [r["item"] for r in out.envelope] == [r["item"] for r in ref]
    keys = ("item", "unit", "max", "t_max", "case_max", "min", "t_min", "case_min", "category")
    for a, b in zip(out.envelope, ref):                         # (the error estimates are not part of it)
        assert {k: a[k] for k in keys} == {k: b[k] for k in keys}, (a, b)   # values, times and cases, exactly
    assert {r["case_max"] for r in ref} & {"d0000", "d0001", "d0002", "d0003"}    # dispersions matter
    # statistics over the 4 generated cases = the batch formulas on the per-case maxima
    from liftoff.analysis.stats import k_factor

    st = out.aggregate.statistics()
    mx = np.array([[r["max"] for r in per_case[f"d000{i}"]] for i in range(4)])
    mn = np.array([[r["min"] for r in per_case[f"d000{i}"]] for i in range(4)])
    k = k_factor(0.99, 0.90, 4)
    scale = np.abs(mx).max(axis=0) + 1e-30
    np.testing.assert_allclose(st["mean_max"], mx.mean(axis=0), rtol=1e-12, atol=1e-12 * scale.max())
    np.testing.assert_allclose(st["normal_max"], mx.mean(axis=0) + k * mx.std(axis=0, ddof=1),
                               rtol=1e-10, atol=1e-10 * scale.max())
    np.testing.assert_allclose(st["normal_min"], mn.mean(axis=0) - k * mn.std(axis=0, ddof=1),
                               rtol=1e-10, atol=1e-10 * np.abs(mn).max())


def test_campaign_outputs(campaign4):
    import h5py

    tmp, _, out = campaign4
    d = tmp / "out"
    for name in ("cases.csv", "statistics.csv", "statistics.h5", "envelope_histories.h5", "srs.csv",
                 "design_loads.csv", "maxmin_envelope.csv"):
        assert (d / name).is_file(), name
    gov = [f.name for f in d.glob("results_d*.h5")]
    assert len(gov) == 1                                    # only the governing generated case in full
    # its step line says why it has no estimate (it blamed --no-error-estimate, not given)
    block = out.summary.split(f"case {gov[0][8:-3]!r}:")[1]
    assert block.split("\n")[1:4] and "a generated case is solved without a second run at h/2" in block
    assert "--no-error-estimate" not in out.summary
    head = (d / "statistics.csv").read_text().splitlines()[0]          # 4 cases: no order statistic, said so
    assert "order statistic = none (too few cases" in head and "0-th" not in head
    rows = (d / "cases.csv").read_text().splitlines()
    assert rows[1].startswith("index,name,srb_ignition_delay[engine[srb_left].start]") and len(rows) == 6
    # each envelope value set by a generated case: that case's history, at its time, is the value
    env = {r["item"]: r for r in out.envelope}
    with h5py.File(d / "envelope_histories.h5", "r") as f:
        n = 0
        for case, g in f["cases"].items():
            t = g["time"][()]
            for k, row in enumerate(g["row"][()]):
                side = g["side"][k].decode() if isinstance(g["side"][k], bytes) else str(g["side"][k])
                r = env[f["items"][row].decode() if isinstance(f["items"][row], bytes) else str(f["items"][row])]
                j = int(np.argmin(np.abs(t - r[f"t_{side}"])))
                assert g["value"][j, k] == r[side] and case == r[f"case_{side}"]
                assert g["t_extreme"][k] == r[f"t_{side}"]
                n += 1
        assert n > 0
    # statistics.h5's srs group: its own dimensions, each a scale with units (issue 24: it reused
    # the root's 'items' and had no frequency or Q, so xarray could not open it)
    with h5py.File(d / "statistics.h5", "r") as f:
        g = f["srs"]
        env = g["envelope"]
        assert env.shape == (g["q"].shape[0], g["freq_Hz"].shape[0], g["srs_items"].shape[0])
        assert [env.dims[k][0].name for k in range(3)] == ["/srs/q", "/srs/freq_Hz", "/srs/srs_items"]
        assert g["freq_Hz"].attrs["units"] == "Hz" and g["freq_Hz"][0] > 0 and list(g["q"][()]) == [10.0, 25.0]
        assert env.attrs["units"] and g["srs_items"].shape[0] < f["items"].shape[0]


def test_time_consistent_interface_loads_cover_every_case(campaign4):
    """interface_loads_envelope.csv of a campaign is the envelope over every case, named and
    generated, each from its summary's time-consistent rows: the same rows (values, times and
    cases, exactly) as the envelope of every case solved one by one here. Before, it covered the
    named cases and the governing generated one only (a review: a 3.6 % larger attach peak of
    another generated case was in maxmin_envelope.csv but not in this table)."""
    from liftoff.analysis import interface_loads as il

    tmp, _, out = campaign4
    sc, stack = out.scenario, next(iter(out.stacks.values()))
    per_case = []
    for case in list(sc.cases) + [sc.generated_case(i) for i in range(sc.n_generated)]:
        cp = build_problem(case, stack, progress=False)
        res = solve(cp.problem)
        per_case.append(il.time_consistent(res.time, report.interface_histories(res, cp.attach), case.name))
    ref = il.envelope(per_case)
    assert ref, "the stick model has attach points"
    path = tmp / "out" / "interface_loads_envelope.csv"
    got = il.read_csv(path)
    assert len(got) == len(ref)
    for a, b in zip(got, ref):
        assert (a["interface"], a["peak"], a["case"]) == (b["interface"], b["peak"], b["case"])
        assert a["time"] == pytest.approx(b["time"], rel=1e-6)                # (the file's 7 digits)
        np.testing.assert_allclose(a["values"], b["values"], rtol=1e-6, atol=1e-6 * np.abs(b["values"]).max())
    assert {r["case"] for r in ref} - {c.name for c in sc.cases}, "a generated case sets a peak: the test can fail"
    assert "the 4 generated cases" in path.read_text().splitlines()[1]


def test_summary_time_consistent_rows_round_trip_a_record(tmp_path, campaign4):
    """A case record keeps its time-consistent rows (campaign.save_summary / load_summary)."""
    from liftoff.analysis import interface_loads as il
    from liftoff.workflows import campaign

    tmp, _, out = campaign4
    rec = next((tmp / "out.campaign" / "cases").glob("*.npz"), None) or next(tmp.rglob("cases/*.npz"))
    s = campaign.load_summary(rec)
    assert s.consistent is not None
    rows = il.from_arrays(s.consistent, s.name)
    again = il.from_arrays(campaign.load_summary(campaign.save_summary(s, tmp_path / "cases" / rec.name,
                                                                       "k")).consistent, s.name)
    assert rows and [(r["interface"], r["peak"], r["time"]) for r in rows] == \
        [(r["interface"], r["peak"], r["time"]) for r in again]
    assert all(np.array_equal(a["values"], b["values"]) and a["labels"] == b["labels"] and a["units"] == b["units"]
               for a, b in zip(rows, again))


def _summary(name, mx, mn):
    from types import SimpleNamespace

    n = len(mx)
    return SimpleNamespace(name=name, items=tuple(f"i{j}" for j in range(n)), units=("N",) * n,
                           categories=("contact_force",) * n, mx=np.array(mx, float), mn=np.array(mn, float),
                           t_mx=np.zeros(n), t_mn=np.zeros(n), err_mx=None, err_mn=None, srs_items=(), srs=None,
                           support_items=(), support=None)


def test_design_basis_is_the_p99_90_bound_or_a_named_case_beyond_it():
    """design_loads.csv's basis (analysis.aggregate.design_basis): over the dispersed cases
    the P99/90 normal bound mean +- k std (batch formulas), except where a named case's load
    lies beyond it: a design load below a load the run computed would be wrong without a word.
    Item 0: the named case 'off' beyond the bound on both sides; item 1: inside it."""
    from liftoff.analysis.aggregate import Aggregate, design_basis
    from liftoff.analysis.stats import k_factor

    gen_mx = np.array([[1.0, 2.0], [1.2, 2.2], [0.9, 1.9], [1.1, 2.1]])
    gen_mn = -gen_mx
    agg = Aggregate(4)
    agg.add(_summary("nominal", [1.0, 2.0], [-1.0, -2.0]), generated=False)
    agg.add(_summary("off", [50.0, 2.0], [-50.0, -2.0]), generated=False)
    for i in range(4):
        agg.add(_summary(f"d{i}", gen_mx[i], gen_mn[i]), generated=True)
    k = k_factor(0.99, 0.90, 4)
    bound_mx = gen_mx.mean(axis=0) + k * gen_mx.std(axis=0, ddof=1)
    bound_mn = gen_mn.mean(axis=0) - k * gen_mn.std(axis=0, ddof=1)
    assert bound_mx[0] < 50.0 and bound_mx[1] > 2.0          # the case the test is about
    mx, mn, b_mx, b_mn = design_basis(agg)
    assert mx[0] == 50.0 and mn[0] == -50.0 and b_mx[0] == b_mn[0] == "case off"
    np.testing.assert_allclose([mx[1], mn[1]], [bound_mx[1], bound_mn[1]], rtol=1e-12)
    assert b_mx[1] == b_mn[1] == "P99/90 normal"
    one = Aggregate(1)                                        # fewer than 2 dispersed cases: the envelope
    one.add(_summary("off", [50.0, 2.0], [-50.0, -2.0]), generated=False)
    one.add(_summary("d0", [60.0, 1.0], [-1.0, -1.0]), generated=True)
    mx, mn, b_mx, b_mn = design_basis(one)
    assert list(mx) == [60.0, 2.0] and list(mn) == [-50.0, -2.0] and set(b_mx + b_mn) == {"envelope"}


def test_uncertainty_factor_widens_the_range_outward():
    """The design range holds its basis: f x each bound where it lies on its own side of zero
    (max > 0, min < 0); a compression-only item (max < 0) or a shear that never reverses
    (min > 0) has that bound moved toward zero by (f - 1) of its size, not f x it (which put
    the max of a compression-only attach Tz at -2.25 MN, inside its computed -1.80 MN)."""
    from liftoff.analysis.aggregate import factored_outward

    assert factored_outward(2.0, -4.0, 1.25) == (2.5, -5.0)
    assert factored_outward(-1.8e6, -4.0e6, 1.25) == (-1.35e6, -5.0e6)
    assert factored_outward(8.0, 2.0, 1.5) == (12.0, 1.0)
    assert factored_outward(0.0, 0.0, 1.25) == (0.0, 0.0)


def test_design_loads_file_is_its_basis_times_the_factor(campaign4):
    """design_loads.csv of the campaign: each row the basis of design_basis times its
    category's uncertainty factor, the basis named per side."""
    from liftoff.analysis.aggregate import design_basis

    tmp, _, out = campaign4
    agg, factors = out.aggregate, out.scenario.post.uncertainty
    mx, mn, b_mx, b_mn = design_basis(agg)
    rows = list(csv.DictReader(ln for ln in (tmp / "out" / "design_loads.csv").read_text().splitlines()
                               if not ln.startswith("#")))
    want = [j for j, c in enumerate(agg.categories) if c in factors]
    assert [r["item"] for r in rows] == [agg.items[j] for j in want] and rows
    for r, j in zip(rows, want):
        f = factors[agg.categories[j]]
        assert (r["basis_max"], r["basis_min"]) == (b_mx[j], b_mn[j])
        np.testing.assert_allclose([float(r["design_max"]), float(r["design_min"])],
                                   [mx[j] + (f - 1) * abs(mx[j]), mn[j] - (f - 1) * abs(mn[j])],
                                   rtol=1e-6)            # the CSV's 7 significant digits
        assert float(r["design_max"]) >= float(r["max"]) and float(r["design_min"]) <= float(r["min"])
    raised = sum((b_mx[j] != "P99/90 normal") + (b_mn[j] != "P99/90 normal") for j in want)
    assert (f"design loads: the P99/90 normal bound, except {raised} of {2 * len(want)} max/min values"
            in (tmp / "out" / "summary.txt").read_text())


def test_correlated_contours_over_the_campaign(campaign4):
    """correlated_statistics.csv (analysis.correlated, aggregate.write_contours): each pair's
    support functions, computed here from every case solved one by one, give the envelope
    (max over the 6 cases) and the P99/90 normal bound (batch mean + k std over the 4
    dispersed cases) that the streaming aggregate holds; the envelope polygon holds every
    sample of every case (the polygon is the hull cut by 72 lines: it contains the hull)."""
    from liftoff.analysis import correlated as cl
    from liftoff.analysis.stats import k_factor

    tmp, _, out = campaign4
    sc, stack = out.scenario, next(iter(out.stacks.values()))
    supports, samples = {}, {}
    for case in list(sc.cases) + [sc.generated_case(i) for i in range(sc.n_generated)]:
        cp = build_problem(case, stack, progress=False)
        res = solve(cp.problem)
        itfs = report.interface_histories(res, cp.attach)
        names, supports[case.name] = cl.case_support(itfs)
        samples[case.name] = {f"{i.name}|{pair}": (cl.pair_values(i.labels, i.values, xn),
                                                   cl.pair_values(i.labels, i.values, yn))
                              for i in itfs for pair, xn, yn in cl.PAIRS}
    agg = out.aggregate
    assert agg.support_items == names and len(names) == 14           # 7 attach points x 2 pairs
    st = agg.support_statistics()
    every = np.array(list(supports.values()))
    gen = np.array([supports[f"d000{i}"] for i in range(4)])
    scale = np.abs(every).max()
    np.testing.assert_allclose(st["envelope"], every.max(axis=0), rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(st["normal"], gen.mean(axis=0) + k_factor(0.99, 0.90, 4) * gen.std(axis=0, ddof=1),
                               rtol=1e-10, atol=1e-10 * scale)
    assert np.all(np.isnan(st["order"]))            # 4 cases: too few for a P99/90 order statistic
    assert "order (none: too few cases" in (tmp / "out" / "correlated_statistics.csv").read_text().splitlines()[0]
    rows = list(csv.DictReader(ln for ln in (tmp / "out" / "correlated_statistics.csv").read_text().splitlines()
                               if not ln.startswith("#")))
    assert {r["contour"] for r in rows} == {"envelope", "normal"}
    for j, name in enumerate(names):
        itf, _, pair = name.rpartition("|")
        poly = [r for r in rows if r["interface"] == itf and r["pair"] == pair and r["contour"] == "envelope"]
        px, py = np.array([float(r["x"]) for r in poly]), np.array([float(r["y"]) for r in poly])
        ex, ey = np.roll(px, -1) - px, np.roll(py, -1) - py
        for x, y in (samples[c][name] for c in samples):
            cross = ex[:, None] * (y[None, :] - py[:, None]) - ey[:, None] * (x[None, :] - px[:, None])
            # 7 printed digits of the vertices: 1e-6 of the pair's scale, squared (a cross product)
            assert cross.min() >= -1e-6 * (np.abs(px).max() + np.abs(py).max()) ** 2, name


def test_tasks_carry_no_model(campaign4):
    """A task names the scenario, the case index and the cache folder; the model stays in
    the cache (a task pickles to a few kB, the stack to megabytes)."""
    from liftoff.workflows.campaign import CaseTask, ScenarioRef

    _, _, out = campaign4
    t = CaseTask(ScenarioRef.of(out.scenario), 3, "/cache", "key")
    stack = next(iter(out.stacks.values()))
    assert len(pickle.dumps(t)) < 30_000 < len(pickle.dumps(stack.vehicle))


def test_a_worker_builds_its_stack_again_when_what_made_it_changed(tmp_path, monkeypatch):
    """A worker keeps the last (scenario, stack) it built (a long-lived Dask worker keeps it
    across campaigns). It builds them again for a scenario in another folder (whose CSV files
    it reads), for a file the scenario names whose contents changed, and for a task whose
    stack key (the model's input files' contents) is not its stack's; a stack still of another
    key once built again means the inputs changed while the campaign ran: refused, named."""
    from types import SimpleNamespace

    from liftoff.core.errors import InputError
    from liftoff.workflows import campaign, pipeline

    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    (tmp_path / "a" / "thrust.csv").write_text("time,value\n0,1\n")
    (tmp_path / "b" / "thrust.csv").write_text("time,value\n0,1\n")
    built = []
    keys = {"now": "K1"}

    def build_stack(model, cache, **kw):
        built.append(model)
        return SimpleNamespace(key=keys["now"])

    monkeypatch.setattr(pipeline, "build_stack", build_stack)
    monkeypatch.setattr(campaign.ScenarioRef, "load", lambda self: SimpleNamespace(
        path=self.source, generated_case=lambda i: SimpleNamespace(model=self.base, source=self.source,
                                                                   name=f"d{i:04d}")))
    campaign._MEMO.clear()
    data = {"profiles": {"thrust": {"file": "thrust.csv"}}}
    ref = lambda base: campaign.ScenarioRef(data, "s.toml", str(tmp_path / base), 4, "digest")  # noqa: E731
    task = lambda base, key="": campaign.CaseTask(ref(base), 1, "/cache", "mkey", stack_key=key)  # noqa: E731
    campaign._worker_state(task("a"))
    campaign._worker_state(task("a", "K1"))
    assert len(built) == 1                                   # kept
    campaign._worker_state(task("b"))
    assert built[-1] == str(tmp_path / "b") and len(built) == 2         # another folder
    (tmp_path / "b" / "thrust.csv").write_text("time,value\n0,2.0\n")
    campaign._worker_state(task("b"))
    assert len(built) == 3                                   # a named file's contents changed
    keys["now"] = "K2"
    campaign._worker_state(task("b", "K2"))
    assert len(built) == 4                                   # the model's input files changed
    with pytest.raises(InputError, match=r"s.toml: case d0001: the model's input files changed while the campaign"):
        campaign._worker_state(task("b", "K3"))
    campaign._MEMO.clear()


def test_restart_skips_done_cases(campaign4):
    """A second run reuses every record; more cases run only the new ones; a changed
    scenario (seed) runs them all again; the envelope equals the first run's."""
    tmp, p, first = campaign4
    opts = Options(executor=InlineExecutor(), campaign=tmp / "out.campaign")
    again = run(p, tmp / "again", cache_dir=tmp / "cache", n_cases=4, options=opts, **QUIET)
    assert (again.campaign.ran, again.campaign.reused) == (0, 4)
    assert _same(again.envelope, first.envelope)
    more = run(p, tmp / "more", cache_dir=tmp / "cache", n_cases=6, options=opts, **QUIET)
    assert (more.campaign.ran, more.campaign.reused) == (2, 4)
    text = p.read_text()
    assert '"seed" = 20261122' in text
    p2 = p.with_name("seed5.toml")
    p2.write_text(text.replace('"seed" = 20261122', '"seed" = 5'))
    other = run(p2, tmp / "other", cache_dir=tmp / "cache", n_cases=4, options=opts, **QUIET)
    assert (other.campaign.ran, other.campaign.reused) == (4, 0)


def test_records_follow_the_built_model_and_the_files_a_case_names(tmp_path, campaign4, monkeypatch):
    """A record's key holds the built model's StackModel.key (its stages' code, libraries and
    input files: a record made on another build of the same [model] parameters is not
    reused) and the contents of every file the case's mapping names (a force table's CSV
    edited between runs: its records run again); referenced_files finds relative and
    absolute names and ignores strings that name no file."""
    from liftoff.workflows import campaign

    tmp, p, first = campaign4
    sc = first.scenario
    stack = next(iter(first.stacks.values()))
    mkey = next(iter(first.stacks))
    assert stack.key
    assert campaign.case_key(sc, 0, mkey, stack.key) != campaign.case_key(sc, 0, mkey, stack.key + "x")
    opts = Options(executor=InlineExecutor(), campaign=tmp / "out.campaign")
    again = run(p, tmp_path / "again", cache_dir=tmp / "cache", n_cases=4, options=opts, **QUIET)
    assert (again.campaign.ran, again.campaign.reused) == (0, 4)
    real = campaign.case_key
    monkeypatch.setattr(campaign, "case_key", lambda sc, i, m, s="": real(sc, i, m, s + "another build"))
    rebuilt = run(p, tmp_path / "rebuilt", cache_dir=tmp / "cache", n_cases=4, options=opts, **QUIET)
    assert (rebuilt.campaign.ran, rebuilt.campaign.reused) == (4, 0)
    table = tmp_path / "thrust.csv"
    table.write_text("0.0, 1.0\n1.0, 2.0\n")
    raw = {"force": {"csv": "thrust.csv", "label": "top:Tz"}, "also": [str(table), "top:Tz", "nominal", ""]}
    files = campaign.referenced_files(raw, tmp_path)
    assert set(files) == {"thrust.csv", str(table)} and files["thrust.csv"] == files[str(table)]
    table.write_text("0.0, 1.0\n1.0, 30.0\n")                   # (another size: not the same stat)
    assert campaign.referenced_files(raw, tmp_path)["thrust.csv"] != files["thrust.csv"]


def test_damaged_or_foreign_records_run_again(tmp_path, campaign4):
    """A record copied over another case's, one with NaN peaks and one without its scalars
    are not reused: their cases run again and the envelope is the first run's (issue 27:
    the copy was used under the wrong case, NaN reached design_loads.csv, and a record
    without scalars exited 1)."""
    import shutil

    from liftoff.workflows.campaign import load_summary, save_summary

    tmp, p, first = campaign4
    camp = tmp_path / "c.campaign"
    shutil.copytree(tmp / "out.campaign", camp)
    recs = [camp / "cases" / first.campaign.records[i].name for i in range(4)]    # this scenario's records
    assert all(r.is_file() for r in recs)
    shutil.copyfile(recs[0], recs[1])                                   # d0000's record under d0001's name
    s = load_summary(recs[2])
    s.mx[0] = np.nan
    save_summary(s, recs[2], recs[2].stem.rsplit("-", 1)[1])            # a NaN peak
    with np.load(recs[3]) as z:
        data = {k: z[k] for k in z.files if k != "scalars"}
    np.savez(recs[3], **data)                                           # no scalars
    notes = []
    again = run(p, tmp_path / "again", cache_dir=tmp / "cache", n_cases=4,
                options=Options(executor=InlineExecutor(), campaign=camp),
                **{**QUIET, "echo": lambda *a, **k: notes.append(" ".join(map(str, a)))})
    assert (again.campaign.ran, again.campaign.reused) == (3, 1)
    assert _same(again.envelope, first.envelope)
    said = "\n".join(notes)
    assert "it is the record of case 'd0000'" in said and "NaN" in said and "missing 'scalars'" in said


def test_modal_results_dropped_once_written(tmp_path, campaign4):
    """Options.modal_results = False (the command line): the results in memory lose their modal
    displacements once written; the results files and snapshots have them, the same values as
    a run that keeps them."""
    from liftoff.transient.result import load_result

    tmp, p, _ = campaign4
    kept = run(p, tmp_path / "kept", cache_dir=tmp / "cache", n_cases=0, **{**QUIET, "snapshots": True})
    out = run(p, tmp_path / "dropped", cache_dir=tmp / "cache", n_cases=0,
              options=Options(modal_results=False), **{**QUIET, "snapshots": True})
    assert out.results.keys() == kept.results.keys() and len(out.results) == 2
    for name, (res, _) in out.results.items():
        assert res.modal == {}
        q = kept.results[name][0].modal["q_a"]
        assert q.shape[0] == res.time.size and q.shape[1] > 6
        back = load_result(tmp_path / "dropped" / f"results_{name}.h5")
        np.testing.assert_array_equal(back.modal["q_a"], q)
        np.testing.assert_array_equal(back.recovered["cg_motion"], res.recovered["cg_motion"])
        shots = sorted(f.name for f in (tmp_path / "kept").glob(f"snapshot*{name}*"))
        assert shots and shots == sorted(f.name for f in (tmp_path / "dropped").glob(f"snapshot*{name}*"))


def test_fields_and_compare(tmp_path, campaign4):
    """ParaView series (.pvd + .vtu frames with total and elastic displacement) and the
    GIF of the governing case (its modal displacements kept for them although the command
    line's modal_results=False drops the others'); a comparison against the campaign's envelope."""
    import meshio

    tmp, p, first = campaign4
    out = run(p, tmp_path / "f", cache_dir=tmp / "cache", n_cases=0,
              options=Options(fields=True, compare=tmp / "out", modal_results=False), **QUIET)
    assert all(res.modal["q_a"].shape[0] == res.time.size for res, _ in out.results.values())
    gov = out.results[next(iter(out.results))][1].case.name
    pvd = (tmp_path / "f" / f"fields_{gov}.pvd").read_text()
    frames = sorted((tmp_path / "f").glob(f"fields_{gov}_*.vtu"))
    assert len(frames) == 48 and pvd.count("<DataSet") == 48 and frames[-1].name in pvd
    m = meshio.read(frames[-1])
    assert {"displacement", "elastic"} <= set(m.point_data) and m.point_data["displacement"].shape[1] == 3
    # the stack has lifted off at the last frame: total motion up, elastic part small
    assert np.median(m.point_data["displacement"][:, 2]) > 10 * np.abs(m.point_data["elastic"][:, 2]).max() or \
        np.abs(m.point_data["displacement"]).max() > np.abs(m.point_data["elastic"]).max()
    assert (tmp_path / "f" / f"animation_{gov}.gif").stat().st_size > 10_000
    rows = [ln for ln in (tmp_path / "f" / "compare.csv").read_text().splitlines() if not ln.startswith("#")]
    assert rows[0].startswith("item,unit,max,max_old,max_change_pct")
    # the same model both times: every elastic vehicle mode pairs with itself, MAC 1, no change
    modes = (tmp_path / "f" / "compare_modes.csv").read_text().splitlines()
    assert modes[1] == "mode,f_hz,old_mode,f_old_hz,mac,change_pct"
    for line in modes[2:]:
        mode, f, old, f_old, mac, change = line.split(",")
        assert old == mode and float(mac) > 1 - 1e-9 and abs(float(change)) < 1e-9
    # the named cases against the envelope of named + generated cases: never above it
    env = {r["item"]: r for r in first.envelope}
    for r in out.envelope:
        assert r["max"] <= env[r["item"]]["max"] and r["min"] >= env[r["item"]]["min"]


def test_cli_campaign(tmp_path, campaign4, capsys):
    from liftoff.workflows.cli import main

    tmp, p, _ = campaign4
    assert main(["run", str(p), "--out", str(tmp_path / "c"), "--cache", str(tmp / "cache"), "--no-progress",
                 "--no-snapshots", "--cases", "2", "--workers", "0", "--campaign", str(tmp / "out.campaign")]) == 0
    text = capsys.readouterr().out
    assert "campaign: 2 generated cases (0 run, 2 reused" in text
    # the manifest records the command as given, its options too (it said `liftoff run <scenario>`)
    import json
    import shlex

    cmd = shlex.split(json.loads((tmp_path / "c" / "MANIFEST.json").read_text())["command"])
    assert cmd[:3] == ["liftoff", "run", str(p)] and cmd[cmd.index("--cases") + 1] == "2" and "--no-snapshots" in cmd
    # from Python: the scenario and the options that change the outputs
    _, _, out4 = campaign4
    man = json.loads((tmp / "out" / "MANIFEST.json").read_text())["command"]
    assert "--cases 4" in man and man.endswith("(called from Python)") and out4.campaign is not None
    assert main(["run", str(p), "--out", str(tmp_path / "d"), "--no-cache", "--cases", "-1"]) == 2
    assert "--cases -1: must be 0 or more" in capsys.readouterr().err


def test_dask_local_cluster_gives_the_same_envelope(tmp_path, campaign4):
    """The same 4 generated cases on a local Dask cluster (one worker process): the same
    envelope as the process pool's, exactly (the same cases, fed in the same order)."""
    pytest.importorskip("distributed")
    tmp, p, first = campaign4
    out = run(p, tmp_path / "dask", cache_dir=tmp / "cache", n_cases=4,
              options=Options(workers=1, dask="local", campaign=tmp_path / "camp"), **QUIET)
    assert (out.campaign.ran, out.campaign.reused) == (4, 0)
    assert _same(out.envelope, first.envelope)


def test_mpi_futures_gives_the_same_envelope(tmp_path, campaign4):
    """The command line under mpiexec (mpi4py.futures, 2 ranks: the command and one
    worker): the same envelope as the process pool's."""
    import csv
    import os
    import shutil
    import subprocess
    import sys

    if shutil.which("mpiexec") is None:
        pytest.skip("no mpiexec")
    tmp, p, first = campaign4
    root = ["--allow-run-as-root"] if os.geteuid() == 0 else []
    cmd = ["mpiexec", *root, "--oversubscribe", "-n", "2", sys.executable, "-m", "mpi4py.futures", "-m",
           "liftoff.workflows.cli", "run", str(p), "--out", str(tmp_path / "mpi"), "--cache", str(tmp / "cache"),
           "--cases", "4", "--mpi", "--workers", "1", "--campaign", str(tmp_path / "camp"), "--no-progress",
           "--no-snapshots"]
    # a clean environment: the FE tests of this session initialise MPI in-process, and the
    # variables that leaves behind would make mpiexec's children attach to it
    env = {k: v for k, v in os.environ.items() if not k.startswith(("OMPI_", "PMIX_", "OPAL_", "PMI_"))}
    env.update(OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=300, env=env)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    assert "generated cases (4 run, 0 reused)" in proc.stdout
    lines = [ln for ln in (tmp_path / "mpi" / "maxmin_envelope.csv").read_text().splitlines() if ln[:1] != "#"]
    rows = list(csv.DictReader(lines))
    assert [(r["item"], r["case_max"], r["case_min"]) for r in rows] == \
        [(r["item"], r["case_max"], r["case_min"]) for r in first.envelope]
    for r, f in zip(rows, first.envelope):
        assert float(r["max"]) == pytest.approx(f["max"], rel=1e-6, abs=1e-6 * abs(f["max"]) + 1e-12)




def test_every_hdf5_file_of_a_campaign_opens_in_xarray(campaign4):
    """Every HDF5 file a campaign run writes (results, spectra, statistics, envelope histories)
    opens in xarray through h5netcdf, every group, with real dimensions (dimension scales, no
    phony dims) and a units attribute on every numeric variable (issue 24)."""
    xr = pytest.importorskip("xarray")
    pytest.importorskip("h5netcdf")
    import h5py

    tmp, _, _ = campaign4
    files = sorted((tmp / "out").glob("*.h5"))
    assert {f.name for f in files} >= {"statistics.h5", "envelope_histories.h5", "results_nominal.h5",
                                       "spectra_nominal.h5"}
    bad = []
    for f in files:
        groups = [None]
        with h5py.File(f, "r") as h:
            h.visit(lambda n: groups.append(n) if isinstance(h[n], h5py.Group) else None)
        for g in groups:
            try:
                with xr.open_dataset(f, engine="h5netcdf", group=g) as ds:
                    bad += [f"{f.name}:{g} dim {d}" for d in ds.dims if str(d).startswith("phony")]
                    # every numeric variable states its units (label arrays of text need none)
                    bad += [f"{f.name}:{g}/{v} has no units" for v in ds.variables
                            if ds[v].dtype.kind in "fiuc" and "units" not in ds[v].attrs]
            except Exception as e:                      # noqa: BLE001 - report every file and group
                bad.append(f"{f.name}:{g} {type(e).__name__}: {e}")
        if hasattr(xr, "open_datatree"):               # the whole file as one tree (xarray >= 2024.10)
            try:
                with xr.open_datatree(f, engine="h5netcdf") as tree:
                    assert len(list(tree.subtree)) == len(groups)
            except Exception as e:                      # noqa: BLE001
                bad.append(f"{f.name} as a tree: {type(e).__name__}: {e}")
    assert not bad, "\n".join(bad)
    # each spectrum group carries its items' units itself ("units of each item": the SRS and FFT
    # groups had none, the PSD's alone did)
    with h5py.File(tmp / "out" / "spectra_nominal.h5", "r") as h:
        for g in ("psd", "fft", "srs"):
            if g in h:
                assert h[g]["item_units"].shape == h[g]["items"].shape, g


class _Recording(InlineExecutor):
    """Runs each task at once and keeps the tasks it was given."""

    def __init__(self):
        self.tasks = []

    def submit(self, fn, /, *args, **kwargs):
        self.tasks.append(args[0])
        return super().submit(fn, *args, **kwargs)


class _Refusing(InlineExecutor):
    def submit(self, fn, /, *args, **kwargs):
        raise AssertionError(f"a case ran again: {args[0].index}")


def _h5_tree(path) -> dict:
    import h5py

    out = {}
    with h5py.File(path, "r") as f:
        f.visititems(lambda name, obj: out.__setitem__(name, obj[()]) if isinstance(obj, h5py.Dataset) else None)
    return out


def test_envelope_histories_captured_while_running_equal_a_rerun(tmp_path, campaign4):
    """The histories the cases send back as they reach the running envelope (campaign.Captured)
    stand for the re-run of the envelope-setting cases: envelope_histories.h5 equal to the
    bit without any case run again; only the setters' files are kept; a missing or foreign
    captured file falls back to the re-run."""
    import shutil
    from dataclasses import asdict

    from liftoff.analysis.aggregate import Aggregate
    from liftoff.workflows import campaign
    from liftoff.workflows.cache import stage_key

    tmp, _, out = campaign4
    sc = out.scenario
    mkey = stage_key("model", asdict(sc.generated_case(0).model))
    ref = campaign.ScenarioRef.of(sc)
    ex = _Recording()                   # one case at a time: each is sent the envelope of those before it
    camp = campaign.run_campaign(sc, ref, tmp / "cache", mkey, ex, tmp_path / "c", progress=False, window=1,
                                 echo=lambda *a: None)
    assert ex.tasks[0].envelope is None and all(t.capture for t in ex.tasks)
    assert all(np.all(np.isfinite(t.envelope.mx)) and np.all(t.envelope.mx_case < t.index) for t in ex.tasks[1:])
    agg = Aggregate(sc.n_generated)
    for i in range(sc.n_generated):
        agg.add(campaign.load_summary(camp.records[i]), generated=True)
    env = agg.envelope_rows()
    setters = campaign.envelope_setters(sc, env)
    assert len(setters) >= 3
    kept = {f.name for f in (tmp_path / "c" / "histories").glob("*.npz")}
    assert {camp.records[i].name for i in setters} <= kept        # every setter's histories came back
    rerun = campaign.write_envelope_histories(env, setters, ref, str(tmp / "cache"), mkey, InlineExecutor(),
                                              tmp_path / "rerun.h5")
    saved = tmp_path / "saved"
    shutil.copytree(tmp_path / "c" / "histories", saved)
    got = campaign.write_envelope_histories(env, setters, ref, str(tmp / "cache"), mkey, _Refusing(),
                                            tmp_path / "captured.h5", camp.captured)
    a, b = _h5_tree(rerun), _h5_tree(got)
    assert a.keys() == b.keys() and any(k.endswith("/value") for k in a)
    for k in a:
        assert np.array_equal(a[k], b[k]), k
    assert {f.name for f in (tmp_path / "c" / "histories").glob("*.npz")} == {camp.records[i].name for i in setters}
    # a setter's file missing, another's replaced by a third case's: those two run again
    first, second = sorted(setters)[:2]
    camp.captured.path(first).unlink()
    shutil.copyfile(saved / camp.records[sorted(setters)[-1]].name, camp.captured.path(second))
    ex = _Recording()
    again = campaign.write_envelope_histories(env, setters, ref, str(tmp / "cache"), mkey, ex,
                                              tmp_path / "again.h5", camp.captured)
    assert sorted(t.index for t in ex.tasks) == [first, second]
    c = _h5_tree(again)
    assert c.keys() == a.keys() and all(np.array_equal(a[k], c[k]) for k in a)


def test_cases_marched_together_capture_against_each_other(tmp_path, campaign4):
    """With --march-together a task's later case is sent the running envelope joined with
    the task's earlier cases (RunningEnvelope.joined: each value a case takes, as Captured
    keeps them): the first case of a first task captures every item, each later one only
    the items where it reaches the cases before it, so a worker holds fewer captured
    histories; the campaign's envelope histories from the captured files equal the re-run
    of the envelope-setting cases (one by one) to round-off, none run again: within 1e-9 of
    each history's peak, the tolerance of the batch's peaks against one-by-one solves (the
    batch sums in another order: test_cases_marched_together_give_the_one_by_one_peaks)."""
    from dataclasses import asdict

    from liftoff.analysis.aggregate import Aggregate
    from liftoff.workflows import campaign
    from liftoff.workflows.cache import stage_key

    tmp, _, out = campaign4
    sc = out.scenario
    mkey = stage_key("model", asdict(sc.generated_case(0).model))
    ref = campaign.ScenarioRef.of(sc)
    task = campaign.CaseTask(ref, 0, str(tmp / "cache"), mkey, (), True, None, (1, 2, 3))
    got = campaign.run_case(task)
    assert [s.index for s in got] == [0, 1, 2, 3] and set(got[0].histories) == set(got[0].items)
    env = None
    for s in got:
        want = np.ones(len(s.items), bool) if env is None else env.reached(s)
        assert sorted(s.histories or {}) == sorted(np.array(s.items)[want]), s.name
        env = campaign.RunningEnvelope.joined(env, s)
    assert sum(len(s.histories or {}) for s in got) < 4 * len(got[0].items)      # fewer than every item each
    ex = _Recording()
    camp = campaign.run_campaign(sc, ref, tmp / "cache", mkey, ex, tmp_path / "c", progress=False,
                                 echo=lambda *a: None, together=4)
    assert [(t.index, t.together) for t in ex.tasks] == [(0, (1, 2, 3))]
    agg = Aggregate(sc.n_generated)
    for i in range(sc.n_generated):
        agg.add(campaign.load_summary(camp.records[i]), generated=True)
    env_rows = agg.envelope_rows()
    setters = campaign.envelope_setters(sc, env_rows)
    rerun = campaign.write_envelope_histories(env_rows, setters, ref, str(tmp / "cache"), mkey, InlineExecutor(),
                                              tmp_path / "rerun.h5")
    captured = campaign.write_envelope_histories(env_rows, setters, ref, str(tmp / "cache"), mkey, _Refusing(),
                                                 tmp_path / "captured.h5", camp.captured)
    a, b = _h5_tree(rerun), _h5_tree(captured)
    assert a.keys() == b.keys()
    for k in a:
        if np.asarray(a[k]).dtype.kind in "fc":
            scale = float(np.max(np.abs(a[k]), initial=0.0)) + 1e-300
            assert np.all(np.abs(np.asarray(a[k]) - np.asarray(b[k])) <= 1e-9 * scale), k
        else:
            assert np.array_equal(a[k], b[k]), k


def test_captured_keeps_only_the_cases_holding_the_running_envelope(tmp_path):
    """campaign.Captured's bookkeeping: a case's file holds the items where it holds the
    running envelope on arrival (beyond it, or equal and earlier in case order, as the
    Aggregate's envelope); it is deleted once another case takes all of them; a case that
    holds none writes nothing; a task's RunningEnvelope asks for the same items; load gives
    the histories exactly and refuses another case's file."""
    from liftoff.workflows.campaign import CaseSummary, Captured, RunningEnvelope

    recs = {i: tmp_path / "cases" / f"d{i:04d}-k{i}.npz" for i in range(5)}
    cap = Captured(tmp_path, recs)
    t = np.linspace(0.0, 1.0, 5)

    def case(i, mx, mn):
        h = {"a": t * (i + 1), "b": t - i}
        return CaseSummary(f"d{i:04d}", i, ("a", "b"), ("N", "m"), ("x", "y"), np.array(mx, float), t[:2],
                           np.array(mn, float), t[:2], time=t, histories=h)

    files = lambda: sorted(f.name for f in cap.folder.glob("*.npz"))  # noqa: E731
    assert cap.running() is None
    cap.arrive(case(0, [1, 1], [0, 0]))
    assert files() == ["d0000-k0.npz"]
    cap.arrive(case(2, [2, 1], [0, -1]))   # a max and b min beyond; b max and a min equal, case 0 keeps them
    e = cap.running()
    assert list(e.mx) == [2, 1] and list(e.mx_case) == [2, 0] and list(e.mn) == [0, -1] and list(e.mn_case) == [0, 2]
    assert files() == ["d0000-k0.npz", "d0002-k2.npz"]
    assert list(e.reached(case(1, [2, 0], [5, 5]))) == [True, False]     # equal and earlier: reached
    assert list(e.reached(case(3, [2, 1], [0, -1]))) == [False, False]   # equal and later: not
    cap.arrive(case(1, [2, 0], [5, 5]))    # takes a max from case 2, which keeps b min
    assert files() == ["d0000-k0.npz", "d0001-k1.npz", "d0002-k2.npz"]
    tm, h = cap.load(1, ["a"])
    assert np.array_equal(tm, t) and np.array_equal(h["a"], 2 * t) and cap.load(1, ["b"]) is None
    cap.arrive(case(3, [3, 5], [-1, -2]))  # beyond everything: the others' files go
    assert files() == ["d0003-k3.npz"]
    joined = None                          # a task's own joining (RunningEnvelope.joined): the same envelope
    for c in (case(0, [1, 1], [0, 0]), case(2, [2, 1], [0, -1]), case(1, [2, 0], [5, 5]), case(3, [3, 5], [-1, -2])):
        joined = RunningEnvelope.joined(joined, c)
    e = cap.running()
    for a, b in ((joined.mx, e.mx), (joined.mx_case, e.mx_case), (joined.mn, e.mn), (joined.mn_case, e.mn_case)):
        assert np.array_equal(a, b)
    cap.arrive(case(4, [0, 0], [0, 0]))    # holds nothing: nothing written
    assert files() == ["d0003-k3.npz"]
    tm, h = cap.load(3, ["a", "b"])
    assert np.array_equal(h["a"], 4 * t) and np.array_equal(h["b"], t - 3) and cap.load(4, ["a"]) is None
    (cap.folder / "d0003-k3.npz").rename(cap.folder / "d0001-k1.npz")   # another case's file under case 1's name
    assert cap.load(1, ["a"]) is None


def test_on_demand_executor_opens_its_pool_only_when_a_task_comes():
    """executors.OnDemand: no task, no pool; the first task opens it, later ones reuse it;
    shutdown closes it (and a task after that opens a new one)."""
    from contextlib import contextmanager

    from liftoff.workflows.executors import OnDemand

    events = []

    @contextmanager
    def opener():
        events.append("open")
        yield InlineExecutor(), "inline"
        events.append("close")

    with OnDemand(opener, 2) as idle:
        assert not idle.opened and idle._max_workers == 2
    assert events == []
    ex = OnDemand(opener, 0)
    assert [ex.submit(pow, 2, k).result() for k in (3, 4)] == [8, 16] and ex.opened
    assert events == ["open"]
    ex.shutdown()
    assert events == ["open", "close"] and not ex.opened
    assert ex.submit(pow, 3, 2).result() == 9 and events == ["open", "close", "open"]
    ex.shutdown()
    assert events == ["open", "close", "open", "close"]


def test_the_runs_own_pool_is_closed_before_its_outputs(tmp_path, monkeypatch):
    """A run's own worker processes (each holding the model: 0.65 GB of PSS in the default) are shut
    down once the generated cases are done, not kept idle through the named cases and the
    reports; a caller's executor is left open."""
    import multiprocessing

    from liftoff.workflows import run as run_mod

    seen = []
    real = run_mod.write_results

    def spy(*args, **kwargs):
        seen.append(len(multiprocessing.active_children()))
        return real(*args, **kwargs)

    monkeypatch.setattr(run_mod, "write_results", spy)
    p = _scenario(tmp_path, STICK, t_end=7.2)
    out = run(p, tmp_path / "out", cache_dir=tmp_path / "cache", n_cases=2, options=Options(workers=1), **QUIET)
    assert out.campaign.ran == 2 and seen == [0]
    mine = _Recording()
    again = run(p, tmp_path / "again", cache_dir=tmp_path / "cache", n_cases=3,
                options=Options(executor=mine, campaign=tmp_path / "out.campaign"), **QUIET)
    assert (again.campaign.ran, again.campaign.reused) == (1, 2) and [t.index for t in mine.tasks] == [2]
    assert mine.submit(pow, 2, 5).result() == 32          # still open


def test_cases_marched_together_give_the_one_by_one_peaks(tmp_path, campaign4, monkeypatch):
    """Options(march_together=3) (--march-together 3): the 4 generated cases as a task of
    three marched together (liftoff.transient.solve_batch_iter) and one alone. Each case's record
    (every item's max and min) equals the one-by-one campaign's to round-off: within 1e-9 of
    the item's largest magnitude over the cases (the batch sums in another order; on this
    model its contact forces land 1e-12 of their peak from a one-by-one solve, docs/transient.md);
    where the time of an extreme differs (a plateau, its first step decided by round-off) the
    one-by-one history holds that extreme at the batch's time too; the envelope the same
    values to that tolerance."""
    import liftoff.transient as lt
    from liftoff.workflows import campaign

    marched = []
    batch = lt.solve_batch_iter
    monkeypatch.setattr(lt, "solve_batch_iter", lambda problems: marched.append(len(problems)) or batch(problems))
    tmp0, p, first = campaign4
    out = run(p, tmp_path / "out", cache_dir=tmp0 / "cache", n_cases=4,
              options=Options(executor=InlineExecutor(), campaign=tmp_path / "camp", march_together=3), **QUIET)
    assert (out.campaign.ran, out.campaign.reused) == (4, 0)
    assert marched == [3]          # marched together, not a step back to one by one; the fourth case alone: solve
    batched = [campaign.load_summary(out.campaign.records[i]) for i in range(4)]
    alone = [campaign.load_summary(first.campaign.records[i]) for i in range(4)]
    scale = np.max([np.maximum(np.abs(s.mx), np.abs(s.mn)) for s in alone], axis=0) + 1e-300
    sc, stack = first.scenario, next(iter(first.stacks.values()))
    for i, (b, a) in enumerate(zip(batched, alone)):
        assert (b.name, b.index, b.items) == (a.name, a.index, a.items)
        for got, ref in ((b.mx, a.mx), (b.mn, a.mn)):
            assert np.all(np.abs(got - ref) <= 1e-9 * scale)
        cp = build_problem(sc.generated_case(i), stack, progress=False)
        res = solve(cp.problem)
        its = report.items(res, cp.attach, band_hz=sc.post.acceleration_band_hz)
        for got, ref, value in ((b.t_mx, a.t_mx, a.mx), (b.t_mn, a.t_mn, a.mn)):
            for j in np.flatnonzero(got != ref):
                at = int(np.argmin(np.abs(res.time - got[j])))
                assert abs(res.time[at] - got[j]) <= 1e-9 and abs(its[j].values[at] - value[j]) <= 1e-9 * scale[j]
        assert np.array_equal(b.recontacts, a.recontacts)
        np.testing.assert_allclose(b.separation, a.separation, rtol=0, atol=0.5 * a.h)
    assert [r["item"] for r in out.envelope] == [r["item"] for r in first.envelope]
    for r, q in zip(out.envelope, first.envelope):
        for side in ("max", "min"):
            assert abs(r[side] - q[side]) <= 1e-9 * max(abs(q["max"]), abs(q["min"]), 1e-300), (r, q)


def test_march_together_refuses_fewer_than_one(tmp_path, campaign4, capsys):
    from liftoff.workflows.cli import main

    tmp0, p, _ = campaign4
    assert main(["run", str(p), "--out", str(tmp_path / "o"), "--cache", str(tmp0 / "cache"), "--cases", "2",
                 "--march-together", "0"]) == 2
    err = capsys.readouterr().err
    assert "--march-together 0" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "o").exists()


def test_cases_the_batch_refuses_are_solved_one_by_one_and_said(tmp_path, campaign4, monkeypatch):
    """A group the batch cannot march (its InputError: here forced) is solved one by one, the
    records those of the one-by-one campaign bit for bit, and the worker says so once."""
    import liftoff.transient as lt
    from liftoff.core.errors import InputError
    from liftoff.workflows import campaign

    def refuse(problems):
        raise InputError("batch: friction, dashpots, latches and soft release are not marched batched")

    monkeypatch.setattr(lt, "solve_batch_iter", refuse)
    tmp0, p, first = campaign4
    with pytest.warns(UserWarning, match="--march-together: cases d0000, d0001 solved one by one") as got:
        out = run(p, tmp_path / "out", cache_dir=tmp0 / "cache", n_cases=4,
                  options=Options(executor=InlineExecutor(), campaign=tmp_path / "camp", march_together=2), **QUIET)
    assert sum("--march-together" in str(w.message) for w in got) == 1
    for i in range(4):
        a, b = (campaign.load_summary(o.campaign.records[i]) for o in (first, out))
        assert np.array_equal(a.mx, b.mx) and np.array_equal(a.t_mn, b.t_mn)
    assert _same(out.envelope, first.envelope)


def test_a_record_whose_header_declares_too_much_is_damaged(tmp_path, campaign4, monkeypatch):
    """A record (or captured histories file) whose damaged header declares more than the
    memory holds (read_record's ResourceError) is a damaged record to run again, not the
    run's end."""
    from liftoff.core.errors import ResourceError
    from liftoff.workflows import campaign

    _, _, first = campaign4
    path = first.campaign.records[0]

    def huge(*a, **k):
        raise ResourceError("campaign record: its arrays would take 9e12 bytes")

    monkeypatch.setattr(campaign, "read_record", huge)
    why = campaign.record_problem(path, "d0000", 0, campaign.record_key(path))
    assert why is not None and "9e12 bytes" in why


def test_a_batch_refused_for_memory_is_solved_one_by_one(tmp_path, campaign4, monkeypatch):
    """A group whose histories the batch's memory check refuses (its ResourceError: here
    forced) is solved one by one like any group the batch cannot march, the records those of
    the one-by-one campaign, and the warning points at a smaller --march-together."""
    import liftoff.transient as lt
    from liftoff.core.errors import ResourceError
    from liftoff.workflows import campaign

    def too_big(problems):
        raise ResourceError("transient: 2 cases marched together need 9e9 bytes")

    monkeypatch.setattr(lt, "solve_batch_iter", too_big)
    monkeypatch.setattr(campaign, "_MEMO", {})          # (the fixture's worker memo may hold "warned")
    tmp0, p, first = campaign4
    said = []
    with pytest.warns(UserWarning, match="solved one by one .*a smaller --march-together needs less memory"):
        out = run(p, tmp_path / "out", cache_dir=tmp0 / "cache", n_cases=4,
                  options=Options(executor=InlineExecutor(), campaign=tmp_path / "camp", march_together=2),
                  **{**QUIET, "echo": lambda *a, **k: said.append(" ".join(map(str, a)))})
    # said by the run itself too, once (a remote worker's warning is not seen)
    assert sum("solved one by one" in line and "smaller --march-together" in line for line in said) == 1
    for i in range(4):
        a, b = (campaign.load_summary(o.campaign.records[i]) for o in (first, out))
        assert np.array_equal(a.mx, b.mx) and np.array_equal(a.t_mn, b.t_mn)


def test_march_together_checked_before_the_model_stages(tmp_path, campaign4):
    from liftoff.core.errors import InputError

    _, p, _ = campaign4
    with pytest.raises(InputError, match="--march-together 0"):
        run(p, tmp_path / "out", cache_dir=tmp_path / "empty-cache", n_cases=2, options=Options(march_together=0),
            **QUIET)
    assert not (tmp_path / "empty-cache").exists() or not any((tmp_path / "empty-cache").rglob("*.npz"))


def test_model_products_are_built_once_per_stack(campaign4, monkeypatch):
    """The recovery matrices that depend on the model alone (attach forces, c.g. motion and
    accelerations) are built by a stack's first case and taken from it by the next
    (StackModel.product: a campaign worker's cases share its stack): the same matrices, bit
    for bit, as a first case's, with no call to the functions that build them."""
    import liftoff.reduction as red

    _, _, out = campaign4
    sc, stack = out.scenario, next(iter(out.stacks.values()))
    stack._products.clear()
    first = build_problem(sc.cases[0], stack, progress=False)
    assert {k[0] for k in stack._products} == {"interface_force", "cg_motion", "cg_acceleration", "truncation"}

    def built_again(*a, **k):
        raise AssertionError("a model product built again")

    monkeypatch.setattr(red, "interface_force_recovery", built_again)
    monkeypatch.setattr(red, "cg_acceleration_recovery", built_again)
    again = build_problem(sc.cases[0], stack, progress=False)
    for r1, r2 in zip(first.problem.recoveries, again.problem.recoveries, strict=True):
        assert r1.name == r2.name
        for part in ("disp", "vel", "acc", "const"):
            a, b = getattr(r1, part), getattr(r2, part)
            assert (a is None and b is None) or np.array_equal(a, b), (r1.name, part)
            assert a is None or a is not b                # each problem holds its own copy


def test_a_failed_task_names_its_cases_and_the_finished_ones_are_kept(monkeypatch):
    """run_tasks: a task that fails with anything but the worker's own one-line errors (a
    lost worker, a library's error) is raised naming its generated cases (it named none),
    after the tasks that finished beside it were handed on; a worker's InputError or
    ResourceError goes as it is, a MemoryError as a ResourceError naming its cases."""
    from types import SimpleNamespace

    from liftoff.core.errors import InputError
    from liftoff.workflows import campaign

    def fake(task):
        if task.index == 2:
            raise ZeroDivisionError("float division by zero")
        if task.index == 5:
            raise InputError("case d0005: a key is wrong")
        return task.index

    monkeypatch.setattr(campaign, "run_case", fake)
    tasks = [SimpleNamespace(index=i, together=(i + 1,) if i == 2 else ()) for i in (0, 1, 2, 4)]
    got = []
    with pytest.raises(RuntimeError, match=r"campaign: generated case d0002, d0003: ZeroDivisionError: float division"):
        campaign.run_tasks(InlineExecutor(), tasks, got.append, window=4)
    assert got == [0, 1, 4]
    with pytest.raises(InputError, match="case d0005: a key is wrong"):
        campaign.run_tasks(InlineExecutor(), [SimpleNamespace(index=5, together=())], got.append, window=1)
    # a worker's ResourceError goes as it is (exit status 4, not 1 as an internal error), and
    # a worker out of memory becomes one, naming its cases
    from liftoff.core.errors import ResourceError

    def short(task):
        if task.index == 6:
            raise ResourceError("case d0006: the transient needs 30 GB of histories")
        raise MemoryError()

    monkeypatch.setattr(campaign, "run_case", short)
    with pytest.raises(ResourceError, match="case d0006: the transient needs 30 GB"):
        campaign.run_tasks(InlineExecutor(), [SimpleNamespace(index=6, together=())], got.append, window=1)
    with pytest.raises(ResourceError, match=r"campaign: generated case d0007, d0008: out of memory in its worker"):
        campaign.run_tasks(InlineExecutor(), [SimpleNamespace(index=7, together=(8,))], got.append, window=1)


def test_results_groups_take_the_root_time_as_a_datatree(campaign4):
    """README: a results file opened as an xarray DataTree gives each group the root's time
    as its coordinate, so a group's histories select by time in seconds."""
    xr = pytest.importorskip("xarray")
    pytest.importorskip("h5netcdf")
    if not hasattr(xr, "open_datatree"):
        pytest.skip("xarray without open_datatree")
    tmp, _, _ = campaign4
    with xr.open_datatree(tmp / "out" / "results_nominal.h5", engine="h5netcdf") as tree:
        rec = tree["recovered"].to_dataset()
        t = rec["time"].values
        assert t.size > 10 and np.all(np.diff(t) > 0)
        k = t.size // 2
        at = rec.sel(time=t[k])
        assert float(at["cg_motion"][0]) == float(rec["cg_motion"][k, 0])
