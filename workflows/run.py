"""``liftoff run [SCENARIO.toml] --out DIR``: geometry to lift-off loads in one command.

Stages: scenario -> components (gmsh + dolfinx, or stick) -> Craig-Bampton -> system
modes -> per case: loads and vehicle effects -> static initial state -> two-body
transient -> results HDF5, max/min tables, plots, snapshots; Table 1 and a summary.
Without a scenario the embedded default (liftoff/config/default_scenario.toml) runs.
Outputs are listed in docs/workflow.md.
"""
from __future__ import annotations

import argparse
import shlex
import tempfile
import time
from contextlib import ExitStack, contextmanager
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

from liftoff.core.errors import InputError
from liftoff.core.records import write_text

from . import outputs, report
from .cache import StageCache, default_cache_dir, stage_key
from .outdir import check_target, staged_output


@dataclass
class RunOutput:
    out: Path
    scenario: object
    stacks: dict
    results: dict                       # case -> (TransientResult, CaseProblem): named and governing cases
    table1: object
    envelope: list
    stage_times: list
    files: list = field(default_factory=list)
    summary: str = ""
    campaign: object = None             # CampaignRun of the generated cases, or None
    aggregate: object = None            # the Aggregate (envelope, statistics, SRS)


@dataclass
class Prepared:
    """Everything a run needs before it writes a file: the reduced stacks and every named
    case's validated transient problem (points, labels, loads and statics checked up front);
    every generated case parsed and the first one built on its model (``gen_model``: its
    model key, None without generated cases)."""

    stacks: dict                        # model key -> StackModel
    problems: dict                      # case name -> (CaseProblem, model key)
    stage_times: list
    gen_model: str | None = None


@dataclass
class Options:
    """How ``liftoff run`` runs the generated cases and what it writes besides the tables."""

    workers: int = 2
    dask: str | None = None
    mpi: bool = False
    executor: object = None             # any concurrent.futures.Executor (Python API), else from the above
    campaign: Path | None = None        # records folder (default DIR.campaign beside DIR)
    keep_histories: bool = False        # results_<case>.h5 of every envelope-setting generated case
    fields: bool | None = None          # ParaView .pvd/.vtu + GIF of the governing case (None: [postprocess.fields])
    compare: Path | None = None         # an earlier run's folder or max/min CSV
    contributions: Path | None = None   # the earlier run's scenario: the compared peaks split (workflows/contributions.py)
    #: RunOutput.results keep each case's modal displacements (``modal["q_a"]``, ``["q_b"]``; 0.9 GB a
    #: default case). False (the command line): dropped once the case's results file and snapshots are
    #: handed off (they are in results_<case>.h5), unless the fields (--fields) need them
    modal_results: bool = True
    #: generated cases a worker marches together (liftoff.transient.solve_batch; 1: one by one). Faster
    #: per case, but a worker holds that many cases' histories and results at once (docs/workflow.md)
    march_together: int = 1


def run(scenario=None, out: Path | str = "out/run", cache_dir: Path | str | None | bool = None,
        progress: bool = True, plots: bool = True, snapshots: bool = True, echo=print,
        n_cases: int | None = None, options: Options | None = None, error_estimate: bool = True,
        max_memory: float | None = None, command: str | None = None) -> RunOutput:
    """Run a scenario (path, parsed Scenario, or None for the default) into ``out``.

    ``cache_dir``: None -> default (``$LIFTOFF_CACHE`` or DIR/../.liftoff-cache),
    False -> no cache, else that directory. ``n_cases``: generated cases (``[dispersion]``),
    run on the executor of ``options`` with per-case records in a campaign folder. Every
    named case is built and checked before the first file is written; the files are
    written into a staging folder that replaces ``out`` as a whole at the end
    (workflows/outdir.py), so a failed run leaves ``out`` as it was. ``error_estimate``:
    every named case runs again at h/2 (transient/accuracy.py) so that each max/min carries
    an estimated error; ``max_memory`` (bytes) overrides the memory limit of the histories (and
    of what the run keeps per generated case, checked before any case is generated);
    ``command``: the command line MANIFEST.json records (the command line's own; from Python
    ``liftoff run <scenario>`` and the options given, :func:`_api_command`).

    Under ``mpirun -n N`` every rank calls this: the model stages are built by all ranks
    together (workflows/parallel.py), the cases and every file by rank 0, which returns the
    RunOutput (the other ranks return None)."""
    from liftoff.config import Scenario, load_scenario

    from .parallel import SERIAL, on_root, world

    t_start = time.perf_counter()
    out, opt = Path(out), options or Options()
    comm = SERIAL if opt.mpi else world()      # --mpi: the other ranks serve the case pool
    if comm.rank != 0:
        echo, progress = (lambda *a, **k: None), False
    if isinstance(scenario, Scenario):
        sc = scenario.with_generated(n_cases) if n_cases is not None else scenario
    else:
        sc = load_scenario(scenario, n_cases=n_cases)
    on_root(comm, lambda: check_target(out), share=False)
    from .campaign import check_case_memory
    from .executors import check_dask_address, check_mpi, probe_dask_scheduler

    check_case_memory(sc.path, sc.n_generated, max_memory)      # before any case is generated
    check_dask_address(opt.dask)
    if not (isinstance(opt.march_together, int) and opt.march_together >= 1):
        raise InputError(f"--march-together {opt.march_together!r}: must be 1 (one by one) or more")
    if sc.n_generated:              # the case pool (_executor) is made only then: checked before the model stages
        if opt.dask not in (None, "local"):
            on_root(comm, lambda: probe_dask_scheduler(opt.dask), share=False)
        check_mpi(opt.mpi)
    if opt.compare is not None:           # read before the first expensive stage (and again at the end)
        from liftoff.analysis.aggregate import read_maxmin

        on_root(comm, lambda: read_maxmin(Path(opt.compare)), share=False)
        old_modes = report.earlier_modes(opt.compare)
        if old_modes.is_file():           # the earlier run's modes, paired with this run's at the end
            on_root(comm, lambda: report.read_mode_shapes(old_modes), share=False)
    if opt.contributions is not None:     # the earlier scenario read and matched before any stage
        from . import contributions

        on_root(comm, lambda: contributions.check(sc, opt, sc.n_generated), share=False)
    want_pics = snapshots and any(c.output.snapshots for c in sc.cases)
    if want_pics or _fields_wanted(sc, opt):  # pyvista (fem.snapshot) before dolfinx (FENICSX-NOTES.md)
        import liftoff.fem.snapshot  # noqa: F401
    from .parallel import root_only

    with _run_cache(cache_dir, out, sc.n_generated, comm) as cache:
        models = prepare_models(sc, cache, progress, echo)      # model stages: every rank (SPMD FE stages)
        return root_only(comm, lambda: _cases_and_files(        # the cases' problems and checks: rank 0
            sc, prepare(sc, cache, progress, echo, error_estimate, max_memory, models), cache, opt, out, plots,
            want_pics, progress, echo, t_start, error_estimate,
            command or _api_command(sc, n_cases, opt, error_estimate, plots, max_memory, snapshots)))


def _cases_and_files(sc, prep: Prepared, cache: StageCache, opt: Options, out: Path, plots: bool,
                     want_pics: bool, progress: bool, echo, t_start: float, error_estimate: bool,
                     command: str) -> RunOutput:
    """Rank 0: the generated cases on their executor, then every output, staged into ``out``."""
    from .executors import OnDemand

    with ExitStack() as pool:
        executor, how = pool.enter_context(_executor(opt, sc.n_generated))
        camp = _run_generated(sc, prep, cache, executor, how, out, opt, progress, echo)
        if _own_local_pool(opt, sc.n_generated):
            # its workers each hold the model (0.65 GB of PSS each in the default) and would idle through the
            # named cases and the reports: closed now, opened again only if the end re-runs a case
            pool.close()
            executor = pool.enter_context(OnDemand(lambda: _executor(opt, sc.n_generated), opt.workers))
        with staged_output(out, command=command) as stage:
            output = write_results(sc, prep, stage, plots, want_pics, echo, t_start,
                                   _Campaign(camp, executor, cache, opt), error_estimate)
    output.out = out
    output.files = [out / Path(f).relative_to(stage) for f in output.files]
    echo(f"  outputs in {out}/ ({len(output.files)} files); cache {cache.root}")
    return output


def _api_command(sc, n_cases, opt: Options, error_estimate: bool, plots: bool, max_memory,
                 snapshots: bool = True) -> str:
    """The command line equivalent of a run called from Python, as far as its options go (for
    MANIFEST.json): the scenario, the generated cases and the options that change the outputs."""
    embedded = str(sc.path).startswith("<")           # the embedded default: `liftoff run` alone
    parts = ["liftoff", "run"] + ([] if embedded else [str(sc.path)])
    if n_cases:
        parts += ["--cases", str(n_cases)]
    for flag, value in (("--campaign", opt.campaign), ("--compare", opt.compare), ("--contributions", opt.contributions),
                        ("--fields", opt.fields), ("--keep-histories", opt.keep_histories),
                        ("--march-together", opt.march_together if (opt.march_together or 0) > 1 else None)):
        if value:
            parts += [flag] if value is True else [flag, str(value)]
    if not error_estimate:
        parts.append("--no-error-estimate")
    if not plots:
        parts.append("--no-plots")
    if not snapshots:
        parts.append("--no-snapshots")
    if max_memory is not None:
        parts += ["--max-memory", f"{max_memory / 1e9:g}"]
    return shlex.join(parts) + " (called from Python)"


def _fields_wanted(sc, opt: Options) -> bool:
    return sc.post.fields.enabled if opt.fields is None else bool(opt.fields)


@contextmanager
def _run_cache(cache_dir, out: Path, n_generated: int, comm):
    """The stage cache of a run; with generated cases and no cache, a temporary one (the
    workers load the model from it by path; under mpirun rank 0's, shared with the others)."""
    root = None if cache_dir is False else Path(cache_dir) if cache_dir else default_cache_dir(out)
    if root is None and n_generated:
        with tempfile.TemporaryDirectory(prefix="liftoff-cache-") as tmp:
            yield StageCache(Path(comm.bcast(tmp if comm.rank == 0 else None)), comm=comm, temporary=True)
        return
    yield StageCache(root, comm=comm)


def _own_local_pool(opt: Options, n_generated: int) -> bool:
    """Whether the case pool is the run's own worker processes on this machine (a process
    pool or a Dask LocalCluster): not a caller's executor, not MPI's ranks, not a remote
    scheduler's workers."""
    return bool(n_generated) and opt.executor is None and not opt.mpi and (
        opt.dask == "local" or (not opt.dask and opt.workers > 0))


@contextmanager
def _executor(opt: Options, n_generated: int):
    if not n_generated:
        yield None, ""
    elif opt.executor is not None:
        yield opt.executor, type(opt.executor).__name__
    else:
        from .executors import make_executor

        with make_executor(opt.workers, opt.dask, opt.mpi) as pair:
            yield pair


@dataclass
class _Campaign:
    run: object                          # CampaignRun or None
    executor: object
    cache: StageCache
    options: Options


def prepare_models(sc, cache: StageCache, progress: bool, echo) -> tuple[dict, list]:
    """Model stages (cached) of every distinct model of the named cases and of the first
    generated case: ({model key: StackModel}, stage times). Under mpirun every rank runs them
    (the FE stages are distributed); the rest of :func:`prepare` is rank 0's."""
    stacks, stage_times = {}, []
    for case in sc.cases:
        _stack_for(case, stacks, cache, progress, echo, stage_times)
    if sc.n_generated:
        _stack_for(sc.generated_case(0), stacks, cache, progress, echo, stage_times)
    return stacks, stage_times


def prepare(sc, cache: StageCache, progress: bool, echo, error_estimate: bool = True,
            max_memory: float | None = None, models: tuple[dict, list] | None = None) -> Prepared:
    """Model stages (:func:`prepare_models`, or its result ``models``), then every named
    case's problem, its step (stability, time axis) and static initial state (section 2.6),
    then every generated case parsed (its draws checked) and the first one built, so that
    bad input stops the run before any output; the memory of the named cases' histories is
    estimated (transient/stepping.py) and refused beyond ``max_memory`` bytes."""
    from liftoff.transient import static_equilibrium

    from .loads import build_problem

    stacks, stage_times = models if models is not None else prepare_models(sc, cache, progress, echo)
    problems, memory = {}, {}
    for case in sc.cases:
        mkey = _stack_for(case, stacks, cache, progress, echo, stage_times)
        t0 = time.perf_counter()
        cp = build_problem(case, stacks[mkey], progress=progress)
        pr = cp.problem
        pr.memory_limit = max_memory
        try:
            steps = _case_steps(pr)
            static_equilibrium(pr.body_a, pr.body_b, pr.contacts, pr.forcing, pr.t0)
        except InputError as exc:
            raise case.at().wrap(exc) from None
        _check_selections(sc, case.name, pr)
        memory[case.name] = (pr, steps)
        problems[case.name] = (cp, mkey)
        stage_times.append((f"loads [{case.name}]", time.perf_counter() - t0))
    _check_run_memory(memory, error_estimate, max_memory)
    gen_model = None
    if sc.n_generated:
        t0 = time.perf_counter()
        first = sc.generated_case(0)
        gen_model = _stack_for(first, stacks, cache, progress, echo, stage_times)
        if sc.dispersion.database is not None:      # every file's columns are DOFs of the vehicle
            from liftoff.config.values import Where

            sc.dispersion.database.check(Where(sc.path, "dispersion.database"), stacks[gen_model].vehicle.dof_index)
        from tqdm import tqdm

        # every case parsed (its draws checked) before the first runs: a few ms a case, shown
        for i in tqdm(range(1, sc.n_generated), desc="checking generated cases", unit="case", leave=False,
                      disable=not progress or sc.n_generated < 1000):
            if stage_key("model", asdict(sc.generated_case(i).model)) != gen_model:
                raise InputError(f"{sc.path}: case d{i:04d}: its [model] differs from the first generated case's")
        cp = build_problem(first, stacks[gen_model], progress=False)
        pr = cp.problem
        _check_selections(sc, first.name, pr)
        try:
            _case_steps(pr)
            static_equilibrium(pr.body_a, pr.body_b, pr.contacts, pr.forcing, pr.t0)
        except InputError as exc:
            raise first.at().wrap(exc) from None
        stage_times.append((f"generated cases checked ({sc.n_generated})", time.perf_counter() - t0))
    return Prepared(stacks, problems, stage_times, gen_model)


def _check_selections(sc, name: str, problem) -> None:
    """[postprocess.srs] / [postprocess.psd] must select at least one history of each case
    (analysis.histories.item_categories), checked before any case runs."""
    from liftoff.analysis.histories import item_categories
    from liftoff.config.postprocess import CATEGORIES

    cats = None
    for key, spec in (("srs", sc.post.srs), ("psd", sc.post.psd)):
        if spec is None:
            continue
        cats = item_categories(problem) if cats is None else cats
        if not set(spec.categories) & cats:
            has = sorted(cats & set(CATEGORIES))         # those a selection may name
            raise InputError(f"{sc.path}: [postprocess.{key}] categories = {list(spec.categories)} select no history "
                             f"of case {name!r} (it has: {', '.join(has) or 'none'})")


def _case_steps(problem) -> int:
    """The number of steps of a case's transient (its step checked: stability, time axis)."""
    import warnings

    from liftoff.transient.stepping import choose_step

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # given again when the case runs
        return choose_step(problem).n_steps


def _check_run_memory(cases: dict, error_estimate: bool, max_memory: float | None) -> None:
    """ResourceError when the histories of all named cases (kept until the envelope is
    written), plus the h/2 run of the error estimate of one, exceed the memory limit."""
    from liftoff.transient.stepping import MEMORY_FRACTION, available_memory, memory_estimate

    from liftoff.core.errors import ResourceError

    need, extra = 0.0, 0.0
    for pr, steps in cases.values():
        need += sum(memory_estimate(pr, steps, 1).values())
        if error_estimate or pr.accuracy is not None:     # the h/2 run: its histories and, with an accuracy
            extra = max(extra, sum(memory_estimate(pr, steps, 2, 2 if pr.accuracy is not None else 0).values()))
            #                                                    target, its modal histories (twice the steps)
    limit = max_memory if max_memory is not None else MEMORY_FRACTION * available_memory()
    if need + extra > limit:
        raise ResourceError(f"the transients of the {len(cases)} cases need about {(need + extra) / 1e9:.3g} GB of "
                            f"histories but the limit is {limit / 1e9:.3g} GB; use fewer steps (a larger h or a shorter "
                            "run), fewer cases, outputs or modes, or raise the limit (--max-memory GB)")


def _stack_for(case, stacks: dict, cache: StageCache, progress: bool, echo, stage_times: list) -> str:
    """The model key of a case, its stack built (cached) if not yet in ``stacks``."""
    from .loads import stack_mass_summary
    from .pipeline import build_stack

    mkey = stage_key("model", asdict(case.model))      # cases with equal models share one stack
    if mkey not in stacks:
        n0 = len(cache.log)
        t0 = time.perf_counter()
        stacks[mkey] = build_stack(case.model, cache, progress=progress, where=case.at("model"))
        for stage, label, how, secs in cache.log[n0:]:
            stage_times.append((f"{stage} {label} ({how})", secs))
        stage_times.append(("model stages total", time.perf_counter() - t0))
        echo(stack_mass_summary(stacks[mkey]))
    return mkey


def _run_generated(sc, prep: Prepared, cache: StageCache, executor, how: str, out: Path, opt: Options,
                   progress: bool, echo):
    """The generated cases on the executor (records in the campaign folder), or None."""
    if not sc.n_generated:
        return None
    from . import campaign

    folder = Path(opt.campaign) if opt.campaign else out.absolute().parent / f"{out.name}.campaign"
    campaign.prime(sc, str(cache.root), prep.gen_model, prep.stacks[prep.gen_model])
    from .beside import trim_heap

    trim_heap()      # the checks' freed arrays (the statics' dense solves) back to the system: 0.1 GB of the
    #                  command's while its workers run the cases (the campaign's peak), 2026-12-07
    echo(f"  running generated cases on {how}")
    camp = campaign.run_campaign(sc, campaign.ScenarioRef.of(sc), cache.root, prep.gen_model, executor, folder,
                                 progress=progress, echo=echo, together=opt.march_together,
                                 stack_key=prep.stacks[prep.gen_model].key)
    prep.stage_times.append((f"generated cases ({camp.ran} run, {camp.reused} reused)", camp.wall))
    return camp


def write_results(sc, prep: Prepared, out: Path, plots: bool, want_pics: bool, echo, t_start: float,
                  camp: _Campaign | None = None, error_estimate: bool = True) -> RunOutput:
    """Table 1, then per named case the transient, its results file, max/min table, plots,
    snapshots and spectra; the generated cases' records; the envelope over all cases,
    statistics, SRS, design loads; the governing generated case's histories and pictures;
    ParaView output; the comparison and the summary. Everything goes to ``out``. The named
    cases' results files, plots and snapshots are written beside the run (workflows/beside.py)."""
    from .beside import Beside, available

    beside = Beside(available())
    if plots:              # pyplot for the picture children (pyvista is imported at the run's start already)
        from liftoff.analysis.plots import _pyplot

        beside.preload(_pyplot)
    try:
        return _write_results(sc, prep, out, plots, want_pics, echo, t_start, camp, error_estimate, beside)
    except BaseException:
        beside.kill()
        raise


def _write_results(sc, prep: Prepared, out: Path, plots: bool, want_pics: bool, echo, t_start: float,
                   camp, error_estimate: bool, beside) -> RunOutput:
    from liftoff.analysis.aggregate import Aggregate

    from liftoff.transient.accuracy import EstimatesInOrder

    stage_times = list(prep.stage_times)
    results, files, tab1 = {}, [], None
    agg = Aggregate(sc.n_generated)
    opt = camp.options if camp else Options()
    keep_q = opt.modal_results or _fields_wanted(sc, opt)      # the fields' case is known only at the end
    # the named cases' runs at h/2 march one case ahead on a second thread (transient/accuracy.py)
    scratch = None if keep_q else out       # modal displacements dropped once written: kept on disk meanwhile
    pairs = [_full_problem(prep.problems[c.name][0], scratch)
             if _estimated_ahead(prep.problems[c.name][0], error_estimate) else None for c in sc.cases]
    model_note = _model_files_note(sc, prep)
    if model_note:
        echo("  note: " + model_note)
    with EstimatesInOrder(pairs) as ahead, _forks_wait_for(beside, ahead):
        for k, case in enumerate(sc.cases):
            cp, mkey = prep.problems[case.name]
            stack = prep.stacks[mkey]
            if tab1 is None:
                tab1, f1 = _table1(stack, cp, case, out, echo, stage_times, beside, camp.cache if camp else None)
                files += f1
            res, f2 = _full_case(sc, stack, cp, case.name, out, plots and case.output.plots,
                                 want_pics and case.output.snapshots, stage_times, agg, generated=False,
                                 error_estimate=error_estimate, beside=beside,
                                 estimate=(lambda k=k: ahead.get(k)) if pairs[k] is not None else None,
                                 keep_modal=keep_q)
            files += f2
            results[case.name] = (res, cp)
    camp_run = camp.run if camp else None
    if camp_run is not None:
        from .campaign import feed_records

        t0 = time.perf_counter()
        files.append(feed_records(sc, camp_run, agg, out / "cases.csv"))
        files += _generated_outputs(sc, prep, camp, agg, out, stage_times, results, plots, want_pics, keep_q)
        stage_times.append(("campaign tables and histories", time.perf_counter() - t0))
    files += _loads_tables(sc, agg, out, echo, camp, plots)
    if camp is not None and camp.options.contributions is not None:
        from liftoff.analysis.aggregate import read_maxmin

        from . import contributions

        t0 = time.perf_counter()
        old_sc = contributions.check(sc, camp.options, sc.n_generated)
        files += contributions.write(sc, old_sc, prep, camp.cache, results, read_maxmin(Path(camp.options.compare)),
                                     out, echo)
        stage_times.append(("contributions (3 transients per named case)", time.perf_counter() - t0))
    partial = ("the generated cases other than the governing one are not in this table (their histories are not "
               "kept; see envelope_histories.h5)") if camp_run is not None else ""
    consistent = None
    if camp_run is not None and not agg.consistent_missing:      # every case's summary carries its rows
        from .campaign import generated_index

        named = [n for n in results if generated_index(sc, n) is None]
        consistent = (agg.consistent, ", ".join(named) + f" and the {sc.n_generated} generated cases (each case's "
                      "time-consistent rows kept in its summary)")
    t0 = time.perf_counter()
    files += outputs.write("run", outputs.RunContext(results, out, plots, sc.title, partial, sc.post.units, beside,
                                                     consistent), beside=beside)
    stage_times.append(("interface, correlated loads, workbook", time.perf_counter() - t0))
    files += _fields(sc, prep, results, agg, out, opt, stage_times, beside)
    t0 = time.perf_counter()
    files += beside.wait()
    for name, secs in beside.seconds.items():
        # (inline, a job's time is already in the stage that ran it: shown, marked, not to be added again)
        stage_times.append((name + (" (beside the run)" if beside.forked else " (inline: within a stage above)"), secs))
    if beside.forked:
        stage_times.append(("waiting for the pictures", time.perf_counter() - t0))
    env = agg.envelope_rows()
    first = next(iter(prep.stacks.values()))
    text = report.summary(sc, first, results, stage_times, env, time.perf_counter() - t_start)
    if model_note:
        text += "\n  note: " + model_note
    if camp_run is not None:
        text += "\n" + _campaign_text(sc, camp_run, agg)
    files.append(write_text(out / "summary.txt", text + "\n"))
    echo(text)
    return RunOutput(out, sc, prep.stacks, results, tab1, env, stage_times, files, text, camp_run, agg)


@contextmanager
def _forks_wait_for(beside, ahead):
    """``beside`` forks only while ``ahead``'s second thread is between chunks."""
    before, beside.quiet = beside.quiet, ahead.paused
    try:
        yield
    finally:
        beside.quiet = before


#: the run's files of the "model" stage (workflows/outputs.py) and Table 1, written once
MODEL_FILES = "modes_vehicle.*, modal_mass_*.csv, recovery_vehicle.op4 and its index, cb_checks.*, table1.*"


def _model_files_note(sc, prep: Prepared) -> str:
    """"" when every named case shares the first one's model files (outputs.model_identity:
    its stack, recoveries and contacts), else a sentence naming the cases that do not: their
    own are not written (a case with other gravity has other constant columns in its recovery
    matrices; another [model], other modes)."""
    ids = {c.name: outputs.model_identity(prep.stacks[prep.problems[c.name][1]], prep.problems[c.name][0])
           for c in sc.cases}
    if not ids:
        return ""
    first = sc.cases[0].name
    other = [n for n, i in ids.items() if i != ids[first]]
    if not other:
        return ""
    return (f"the run's model files ({MODEL_FILES}) are of case {first}'s model, recoveries and contacts; "
            f"case{'s' if len(other) > 1 else ''} {', '.join(other)} differ{'' if len(other) > 1 else 's'} in them "
            "(another [model], gravity, cryo or [recovery]): their own are not written (run such a case from a "
            "scenario of its own)")


def _table1(stack, cp, case, out: Path, echo, stage_times: list, beside=None, cache=None):
    from .loads import table1

    t0 = time.perf_counter()
    tab1 = table1(stack, cp, case)
    files = [write_text(out / "table1.txt", tab1.table() + "\n"),
             write_text(out / "table1.csv", "# c.g. motion under static loads; m and rad\n" + tab1.csv())]
    files += outputs.write("model", stack, cp, out, beside=beside, cache=cache)
    echo(tab1.table())
    stage_times.append(("Table 1, modal tables", time.perf_counter() - t0))
    return tab1, files


def _full_problem(cp, scratch: Path | None = None):
    """A case's transient with full outputs: its modal displacements kept (fields, snapshots),
    in a scratch file in folder ``scratch`` instead of memory if given (TransientProblem.modal_scratch)."""
    return replace(cp.problem, keep_modal="q", modal_scratch=None if scratch is None else str(scratch))


def _estimated_ahead(cp, error_estimate: bool) -> bool:
    """Whether a named case's h/2 run marches ahead of it (EstimatesInOrder): an estimate
    asked for, with no accuracy setting (whose halvings depend on each estimate)."""
    return error_estimate and cp.problem.accuracy is None


def _full_case(sc, stack, cp, name: str, out: Path, plots: bool, pics: bool, stage_times: list, agg,
               generated: bool, solved=None, error_estimate: bool = False, beside=None, estimate=None,
               keep_modal: bool = True):
    """A case with full outputs: the transient (modal displacements kept; with
    ``error_estimate`` or an ``accuracy`` setting also at h/2, so that each max/min carries
    an estimated error), its results file, max/min table, plots, snapshots and spectra;
    its summary fed to ``agg`` (named cases; a generated case's summary comes from its record).
    ``beside`` (workflows/beside.py): writes the results file and draws the plots and
    snapshots beside the run, its files returned by its ``wait``; None: inline. ``estimate``:
    returns the case's estimate pair (:class:`transient.accuracy.EstimatesInOrder`), instead
    of solving it here. ``keep_modal`` False: the returned result's modal displacements are
    dropped once the results file and snapshots have them (Options.modal_results), and kept
    meanwhile in a scratch file in ``out`` (TransientProblem.modal_scratch), not in memory."""

    from liftoff.transient import solve, solve_estimated

    from .campaign import summarize

    t0 = time.perf_counter()
    half, problem = None, _full_problem(cp, None if keep_modal else out)
    if solved is not None:
        res, secs = solved
    elif estimate is not None:
        est, secs = estimate(), None
        res, half = est.result, est.check
    elif error_estimate or problem.accuracy is not None:
        est, secs = solve_estimated(problem), None
        res, half = est.result, est.check
    else:
        res, secs = solve(problem), None
    stage_times.append((f"transient [{name}]" + (" + h/2" if half is not None else ""),
                        time.perf_counter() - t0 if secs is None else secs))
    t0 = time.perf_counter()
    res.metadata["truncation"] = [c.as_dict() for c in cp.truncation]
    files = []
    band = sc.post.acceleration_band_hz
    its = report.items(res, cp.attach, report.liquid_heads(cp), band)    # made once: summary, max/min, ends
    # the band-limited peaks at an end of the record, where the filter's end transient is (summary.txt warns)
    res.metadata["band_edge_extremes"] = [list(e) for e in report.edge_extremes(res.time, its, band)]
    srs = None
    if not generated:                   # a generated case's summary comes from its record
        summary = summarize(res, cp, name, -1, sc.post, check=half, its=its)
        agg.add(summary, generated=False)
        srs = (summary.srs_items, summary.srs)      # its SRS, not computed again for the spectra file
    rows = report.maxmin(res.time, its, name)       # (report.case_maxmin's, on the items above)
    if half is not None:
        report.with_errors(rows, report.case_maxmin(half, cp, name, band))
    files.append(report.write_csv(rows, out / f"maxmin_{name}.csv"))
    files += outputs.write("case", res, cp, out, name)

    # nothing the run reads again: written beside it, in three children, so that both cores draw
    # while the run waits for the last case's (one child for the three: 11.9 s a warm default run
    # against 10.8 s, medians of 5 pairs, 2026-12-07)
    jobs = [(f"results file [{name}]", lambda: [Path(res.save(out / f"results_{name}.h5"))])]
    if plots:
        jobs.append((f"plots [{name}]", lambda: report.plots(res, cp, out, name)))
    if pics:
        jobs.append((f"snapshots [{name}]", lambda: report.snapshots(stack, res, cp, out, name)))
    for job, work in jobs:
        if beside is not None:
            beside.submit(job, work)
        else:
            files += work()
    if not keep_modal:      # (a forked child keeps its own copy until it has written them)
        res.modal = {}
    files += report.spectra(res, cp, sc.post, out, name, srs)
    stage_times.append((f"reports [{name}]", time.perf_counter() - t0))
    return res, files


def _generated_outputs(sc, prep: Prepared, camp: _Campaign, agg, out: Path, stage_times: list, results: dict,
                       plots: bool, pics: bool, keep_modal: bool = True) -> list:
    """cases.csv, envelope_histories.h5 (the history of each envelope value set by a
    generated case, captured while the campaign ran or re-run on the executor), and the
    governing generated case in full:
    results, max/min, plots, snapshots, spectra (with --keep-histories every
    envelope-setting generated case's results file)."""
    from . import campaign

    files = []
    env = agg.envelope_rows()
    setters = campaign.envelope_setters(sc, env)
    ref = campaign.ScenarioRef.of(sc)
    files.append(campaign.write_envelope_histories(env, setters, ref, str(camp.cache.root), prep.gen_model,
                                                   camp.executor, out / "envelope_histories.h5", camp.run.captured))
    gov = campaign.governing_case(sc, env)
    if gov is None:
        return files
    keep = sorted(setters) if camp.options.keep_histories else [gov]
    stack = prep.stacks[prep.gen_model]
    for idx in keep:
        task = campaign.CaseTask(ref, idx, str(camp.cache.root), prep.gen_model)
        res, cp, case, secs = campaign.solve_generated(task, keep_modal="q", modal_scratch=None if keep_modal else out)
        if idx == gov:
            _, f = _full_case(sc, stack, cp, case.name, out, plots, pics, stage_times, agg, True, solved=(res, secs),
                              keep_modal=keep_modal)
            files += f
            results[case.name] = (res, cp)
        else:
            files.append(Path(res.save(out / f"results_{case.name}.h5")))
    return files


def _loads_tables(sc, agg, out: Path, echo, camp, plots: bool = False) -> list:
    """maxmin_envelope.csv, statistics, correlated-load contours, SRS, design loads and the
    comparison table."""
    from liftoff.analysis import aggregate

    env = agg.envelope_rows()
    files = [report.write_csv(env, out / "maxmin_envelope.csv")]
    echo("Max/min envelope over cases (posts: force on vehicle, Tz > 0 compression; full table in "
         "maxmin_envelope.csv):")
    echo(report.format_table(env, select=report.is_force, limit=40))
    s = sc.post.srs
    freq = report.srs_freq(s) if s is not None else None
    if agg.n >= 2:
        files += aggregate.write_statistics(agg, out, freq, s.q if s is not None else None)
        f = aggregate.write_contours(agg, out)
        if f is not None:
            files.append(f)
            if plots:
                files.append(report.plot_contours(f, out))
    if s is not None:
        f = aggregate.write_srs(agg, freq, s.q, out)
        files += [f] if f else []
    f = aggregate.write_design(agg, sc.post.uncertainty, out)
    files += [f] if f else []
    compare = camp.options.compare if camp else None
    if compare is not None:
        path, rows = aggregate.write_compare(env, aggregate.read_maxmin(Path(compare)), out)
        files.append(path)
        echo(report.format_changes(rows, limit=12))
        old_modes = report.earlier_modes(compare)
        if old_modes.is_file() and (out / "modes_vehicle.h5").is_file():
            path, pairs = report.compare_modes(out / "modes_vehicle.h5", old_modes, out)
            files.append(path)
            echo(report.format_mode_changes(pairs))
    return files


def _fields(sc, prep: Prepared, results: dict, agg, out: Path, opt: Options, stage_times: list,
            beside=None) -> list:
    """ParaView series and GIF of the governing case (the case setting the most force
    envelope values), when asked; the GIF drawn beside the series (``beside``,
    workflows/beside.py; None: after it)."""
    if not _fields_wanted(sc, opt) or not results:
        return []
    from . import fields
    from .campaign import governing_case

    t0 = time.perf_counter()
    name = governing_case(sc, agg.envelope_rows(), named=True)
    res, cp = results.get(name) or next(iter(results.values()))
    name = cp.case.name
    stack = prep.stacks[prep.gen_model] if name not in prep.problems else prep.stacks[prep.problems[name][1]]
    n = sc.post.fields.frames
    files = []
    if sc.post.fields.gif:
        def gif() -> list:
            g = fields.write_gif(stack, res, out, name, n)
            return [g] if g else []

        if beside is not None:
            beside.submit(f"animation [{name}]", gif)
        else:
            files += gif()
    files += fields.write_pvd(stack, res, out, name, n)
    drawn = " (the animation beside)" if beside is not None and beside.forked else " and animation"
    stage_times.append((f"ParaView fields{drawn} [{name}]", time.perf_counter() - t0))
    return files


def _campaign_text(sc, camp_run, agg) -> str:
    lines = [f"  campaign: {sc.n_generated} generated cases ({camp_run.ran} run, {camp_run.reused} reused from "
             f"{camp_run.folder}), seed {sc.dispersion.seed}"]
    if agg.n >= 2:
        lines.append(f"    statistics over {agg.n} cases: P99/90 k = {agg.k:.4f}; order statistic: "
                     + (f"{agg.r}-th largest" if agg.r else "none (fewer than 230 cases)")
                     + " (statistics.csv)")
        rows = [j for j, cat in enumerate(agg.categories) if cat in sc.post.uncertainty]
        if rows:
            from liftoff.analysis.aggregate import design_basis

            _, _, b_mx, b_mn = design_basis(agg)
            raised = sum((b_mx[j] != "P99/90 normal") + (b_mn[j] != "P99/90 normal") for j in rows)
            lines.append(f"    design loads: the P99/90 normal bound, except {raised} of {2 * len(rows)} max/min "
                         "values where a named case's load lies beyond it and is the basis (design_loads.csv "
                         "basis_max, basis_min)")
    return "\n".join(lines)


# ------------------------------------------------------------------ command line
def add_parser(sub: argparse._SubParsersAction) -> None:
    """Register ``liftoff run`` on the CLI's subparsers (workflows/cli.py)."""
    p = sub.add_parser(
        "run", help="geometry-to-loads lift-off run (default: the embedded Shuttle-like scenario)",
        description="Run a lift-off scenario from geometry to loads: FE (or stick) models, "
                    "Craig-Bampton, system modes, vehicle effects, two-body transient, tables, "
                    "plots and snapshots. Without SCENARIO the embedded default runs "
                    "(docs/workflow.md).")
    p.add_argument("scenario", type=Path, nargs="?", default=None, help="scenario file (TOML)")
    p.add_argument("--out", type=Path, required=True, metavar="DIR", help="output directory (created)")
    p.add_argument("--cache", type=Path, default=None, metavar="DIR",
                   help="stage cache directory (default $LIFTOFF_CACHE or DIR/../.liftoff-cache)")
    p.add_argument("--no-cache", action="store_true", help="do not read or write the stage cache")
    p.add_argument("--no-snapshots", action="store_true", help="skip the pyvista pictures")
    p.add_argument("--no-plots", action="store_true", help="skip the matplotlib plots (as [output] plots = false)")
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
    p.add_argument("--example", choices=("barge",), default=None,
                   help="run an embedded example instead of the default lift-off scenario: 'barge' (a barge hitting "
                        "a dock, with a dock-stiffness sweep; docs/barge.md)")
    from .cli import add_common

    add_common(p)
    g = p.add_argument_group("load campaigns (docs/workflow.md, Campaigns)")
    g.add_argument("--cases", type=int, default=None, metavar="N",
                   help="generated (dispersed) cases to run besides the named ones (overrides [dispersion] n_cases)")
    g.add_argument("--workers", type=int, default=2, metavar="N",
                   help="local worker processes for the generated cases (0: in this process) [2]")
    g.add_argument("--dask", default=None, metavar="ADDRESS",
                   help="run the generated cases on a Dask scheduler (tcp://host:8786), or 'local' for a "
                        "LocalCluster of --workers processes")
    g.add_argument("--mpi", action="store_true",
                   help="run them on mpi4py.futures (start as mpiexec -n K python -m mpi4py.futures "
                        "-m liftoff.workflows.cli run ... --mpi)")
    g.add_argument("--march-together", type=int, default=1, metavar="K",
                   help="generated cases each worker marches together (liftoff.transient.solve_batch: faster a "
                        "case, K cases' histories held at once; 1: one by one) [1]")
    g.add_argument("--campaign", type=Path, default=None, metavar="DIR",
                   help="per-case records, so that a restarted run skips finished cases (default DIR.campaign)")
    g.add_argument("--keep-histories", action="store_true",
                   help="write results_<case>.h5 of every envelope-setting generated case")
    g.add_argument("--fields", action="store_true", default=None,
                   help="ParaView .pvd/.vtu series and GIF of the governing case ([postprocess.fields])")
    g.add_argument("--compare", type=Path, default=None, metavar="PATH",
                   help="an earlier run's folder or max/min CSV: writes compare.csv (percent change)")
    g.add_argument("--contributions", type=Path, default=None, metavar="SCENARIO",
                   help="with --compare: the earlier run's scenario; splits each compared peak into forcing, "
                        "modes and damping (contributions.csv; three more transients per named case)")
    p.add_argument("--ranks", type=int, default=None, metavar="N",
                   help="run on N MPI processes: launches `mpirun -n N liftoff run ...` (the same as "
                        "starting it under mpirun yourself); the FE stages are distributed over them")
    p.set_defaults(func=_cli)
    _PARSER[:] = [p]


def _cli(args: argparse.Namespace) -> int:
    from liftoff.config.barge import scenario_kind

    from .parallel import launched_size

    kw = dict(cache_dir=False if args.no_cache else args.cache, progress=not args.no_progress,
              snapshots=not args.no_snapshots)
    if args.example is not None and args.scenario is not None:
        raise InputError("liftoff run: give a scenario file or --example, not both")
    if args.example == "barge" or scenario_kind(args.scenario) == "barge":   # kind = "barge": workflows/barge.py
        from .barge import run as run_barge

        _barge_options(args)
        run_barge(args.scenario, args.out, plots=not args.no_plots, command=getattr(args, "command_line", None), **kw)
        return 0
    if args.ranks is not None:
        if args.ranks < 1:
            raise InputError(f"--ranks: {args.ranks} must be >= 1")
        if launched_size() > 1 and args.ranks != launched_size():
            raise InputError(f"--ranks {args.ranks} inside `mpirun -n {launched_size()}`: give one of the two")
        if args.ranks > 1 and launched_size() == 1:
            return launch(args.ranks, _child_args(args), getattr(args, "command_line", ""))
    opt = Options(workers=args.workers, dask=args.dask, mpi=args.mpi, campaign=args.campaign,
                  keep_histories=args.keep_histories, fields=args.fields, compare=args.compare,
                  contributions=args.contributions, modal_results=False, march_together=args.march_together)
    if args.cases is not None and args.cases < 0:
        raise InputError(f"--cases {args.cases}: must be 0 or more")
    run(args.scenario, args.out, n_cases=args.cases, options=opt, error_estimate=not args.no_error_estimate,
        max_memory=None if args.max_memory is None else args.max_memory * 1e9, plots=not args.no_plots,
        command=getattr(args, "command_line", None), **kw)
    return 0


#: the `liftoff run` options a barge scenario takes (workflows/barge.py); the others are the lift-off run's
BARGE_OPTIONS = ("out", "cache", "no_cache", "no_snapshots", "no_plots", "no_progress", "example")


def _given_options(args: argparse.Namespace, skip: tuple = ()):
    """(action, value) of each option of ``args`` that is not its default, from the parser's
    own table (a new option is seen without a line here), less help and ``skip`` (dests)."""
    for action in _PARSER[0]._actions:
        if not action.option_strings or action.dest == "help" or action.dest in skip:
            continue
        value = getattr(args, action.dest, action.default)
        if value is not None and value != action.default:
            yield action, value


def _barge_options(args: argparse.Namespace) -> None:
    """InputError naming the first lift-off-only option given with a barge scenario (they were
    dropped without a word: --compare wrote nothing, --max-memory set no limit, --ranks ran
    serial, and the run exited 0)."""
    for action, _ in _given_options(args, BARGE_OPTIONS):
        raise InputError(f"liftoff run: {action.option_strings[0]} is an option of the lift-off run; a barge "
                         f"scenario takes {', '.join('--' + o.replace('_', '-') for o in BARGE_OPTIONS)}")


def _child_args(args: argparse.Namespace) -> list[str]:
    """The command line of the ranks `--ranks N` launches: every option of ``args`` that is
    not its default (:func:`_given_options`), less --ranks itself."""
    argv = ["run"] + ([str(args.scenario)] if args.scenario is not None else [])
    for action, value in _given_options(args, ("ranks",)):
        flag = action.option_strings[0]
        argv += [flag] if isinstance(action, argparse._StoreTrueAction) else [flag, str(value)]
    return argv


#: the `liftoff run` parser (add_parser), whose options :func:`_child_args` passes on
_PARSER: list = []


#: the most --ranks per CPU (oversubscribed FE stages only wait on one another beyond a few)
MAX_RANKS_PER_CPU = 4


def launch(ranks: int, argv: list[str], command: str = "") -> int:
    """``mpirun --quiet -n ranks python -m liftoff.workflows.cli ARGV``; returns its exit
    status. Every rank reports an error (it may be its own); the copies of an error line
    are printed once. ``command``: the command line as the user gave it, which the ranks'
    MANIFEST.json records (environment LIFTOFF_COMMAND)."""
    import os
    import shutil
    import subprocess
    import sys

    from liftoff.core.errors import InputError

    mpirun = shutil.which("mpirun")
    if mpirun is None:
        raise InputError("--ranks: mpirun not found (Debian package openmpi-bin, installed with python3-dolfinx-real)")
    cpus = os.cpu_count() or 1
    if ranks > MAX_RANKS_PER_CPU * cpus:
        raise InputError(f"--ranks {ranks}: more than {MAX_RANKS_PER_CPU} ranks per CPU ({cpus} CPUs here); the FE "
                         "stages would only wait on one another")
    cmd = [mpirun, "--quiet", "-n", str(ranks)] + (["--oversubscribe"] if ranks > cpus else [])
    # not under mpirun (launch is only called then): the calling process may be a Python
    # that initialised MPI and started us
    from .executors import die_with_parent
    from .parallel import mpirun_env

    env = mpirun_env(os.environ)
    if command:
        env["LIFTOFF_COMMAND"] = command

    # mpirun (and through it every rank) is stopped when this process ends, however it ends:
    # SIGTERM here, or a kill of this process (issue 27: ranks survived and replaced the output)
    proc = subprocess.Popen(cmd + [sys.executable, "-m", "liftoff.workflows.cli", *argv], stderr=subprocess.PIPE,
                            env=env, preexec_fn=die_with_parent)
    try:
        _forward_stderr(proc.stderr.fileno(), sys.stderr)
        return proc.wait()
    finally:
        if proc.poll() is None:
            proc.terminate()
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                proc.kill()


def _forward_stderr(fd: int, dest) -> None:
    """Copy the ranks' stderr to ``dest`` as it comes (progress bars included), dropping
    repeated ``liftoff: error:`` lines."""
    import os

    seen, pending = set(), b""
    while True:
        chunk = os.read(fd, 65536)
        if not chunk:
            break
        lines = (pending + chunk).split(b"\n")
        pending = lines.pop()
        for line in lines:
            if line.startswith(b"liftoff: error:"):
                if line in seen:
                    continue
                seen.add(line)
            dest.write(line.decode(errors="replace") + "\n")
        if b"\r" in pending and not pending.startswith(b"liftoff:"):    # a progress bar redrawn in place
            cut = pending.rindex(b"\r") + 1
            dest.write(pending[:cut].decode(errors="replace"))
            pending = pending[cut:]
        dest.flush()
    if pending:
        dest.write(pending.decode(errors="replace"))
        dest.flush()
