"""``liftoff run [SCENARIO.toml] --out DIR``: geometry to lift-off loads in one command.

Stages: scenario -> components (gmsh + dolfinx, or stick) -> Craig-Bampton -> system
modes -> per case: loads and vehicle effects -> static initial state -> two-body
transient -> results HDF5, max/min tables, plots, snapshots; Table 1 and a summary.
Without a scenario the embedded default (liftoff/config/default_scenario.toml) runs.
Outputs are listed in docs/workflow.md.
"""
from __future__ import annotations

import argparse
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

from liftoff.core.errors import InputError
from liftoff.core.records import write_text

from .cache import StageCache, default_cache_dir, stage_key
from .outdir import check_target, staged_output


@dataclass
class RunOutput:
    out: Path
    scenario: object
    stacks: dict
    results: dict                       # case -> (TransientResult, CaseProblem)
    table1: object
    envelope: list
    stage_times: list
    files: list = field(default_factory=list)
    summary: str = ""


@dataclass
class Prepared:
    """Everything a run needs before it writes a file: the reduced stacks and every case's
    validated transient problem (points, labels, loads and statics checked up front)."""

    stacks: dict                        # model key -> StackModel
    problems: dict                      # case name -> (CaseProblem, model key)
    stage_times: list


def run(scenario=None, out: Path | str = "out/run", cache_dir: Path | str | None | bool = None,
        progress: bool = True, plots: bool = True, snapshots: bool = True, echo=print,
        error_estimate: bool = True, max_memory: float | None = None) -> RunOutput:
    """Run a scenario (path, parsed Scenario, or None for the default) into ``out``.

    ``error_estimate``: every max/min value gets an estimated error from a second transient
    at h/2 (transient/accuracy.py; always on for a case with ``[time] accuracy``);
    ``max_memory``: bytes the transients may use (None: 80 % of the memory available).
    ``cache_dir``: None -> default (``$LIFTOFF_CACHE`` or DIR/../.liftoff-cache),
    False -> no cache, else that directory. Every case is built and checked before the
    first file is written; the files are written into a staging folder that replaces
    ``out`` as a whole at the end (workflows/outdir.py), so a failed run leaves ``out``
    as it was."""
    from liftoff.config import Scenario, load_scenario

    t_start = time.perf_counter()
    out = Path(out)
    sc = scenario if isinstance(scenario, Scenario) else load_scenario(scenario)
    check_target(out)
    want_pics = snapshots and any(c.output.snapshots for c in sc.cases)
    if want_pics:  # pyvista (imported by fem.snapshot) before dolfinx (FENICSX-NOTES.md)
        import liftoff.fem.snapshot  # noqa: F401
    cache = StageCache(None if cache_dir is False else Path(cache_dir) if cache_dir else default_cache_dir(out))
    prep = prepare(sc, cache, progress, echo, error_estimate, max_memory)
    with staged_output(out, command=f"liftoff run {sc.path}") as stage:
        output = write_results(sc, prep, stage, plots, want_pics, echo, t_start, error_estimate)
    output.out = out
    output.files = [out / Path(f).relative_to(stage) for f in output.files]
    echo(f"  outputs in {out}/ ({len(output.files)} files); cache {cache.root}")
    return output


def prepare(sc, cache: StageCache, progress: bool, echo, error_estimate: bool = True,
            max_memory: float | None = None) -> Prepared:
    """Model stages (cached) for every distinct model, then every case's problem, its step
    (stability, time axis) and static initial state (section 2.6), so that bad input in any
    case stops the run before any output; the memory of all cases' histories is estimated
    (transient/stepping.py) and refused beyond ``max_memory`` bytes."""
    from liftoff.transient import static_equilibrium

    from .loads import build_problem, stack_mass_summary
    from .pipeline import build_stack

    stacks, problems, stage_times, memory = {}, {}, [], {}
    for case in sc.cases:
        mkey = stage_key("model", asdict(case.model))      # cases with equal models share one stack
        if mkey not in stacks:
            n0 = len(cache.log)
            t0 = time.perf_counter()
            stacks[mkey] = build_stack(case.model, cache, progress=progress, where=case.at("model"))
            for stage, label, how, secs in cache.log[n0:]:
                stage_times.append((f"{stage} {label} ({how})", secs))
            stage_times.append(("model stages total", time.perf_counter() - t0))
            echo(stack_mass_summary(stacks[mkey]))
        t0 = time.perf_counter()
        cp = build_problem(case, stacks[mkey], progress=progress)
        pr = cp.problem
        pr.memory_limit = max_memory
        try:
            steps = _case_steps(pr)
            static_equilibrium(pr.body_a, pr.body_b, pr.contacts, pr.forcing, pr.t0)
        except InputError as exc:
            raise case.at().wrap(exc) from None
        memory[case.name] = (pr, steps)
        problems[case.name] = (cp, mkey)
        stage_times.append((f"loads [{case.name}]", time.perf_counter() - t0))
    _check_run_memory(memory, error_estimate, max_memory)
    return Prepared(stacks, problems, stage_times)


def _case_steps(problem) -> int:
    """The number of steps of a case's transient (its step checked: stability, time axis)."""
    import warnings

    from liftoff.transient.stepping import choose_step

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # given again when the case runs
        return choose_step(problem).n_steps


def _check_run_memory(cases: dict, error_estimate: bool, max_memory: float | None) -> None:
    """ResourceError when the histories of all cases (kept until the envelope is written),
    plus the h/2 run of the error estimate of one, exceed the memory limit."""
    from liftoff.transient.stepping import MEMORY_FRACTION, available_memory, memory_estimate

    from liftoff.core.errors import ResourceError

    need, extra = 0.0, 0.0
    for pr, steps in cases.values():
        need += sum(memory_estimate(pr, steps, 1).values())
        if error_estimate or pr.accuracy is not None:
            extra = max(extra, sum(memory_estimate(pr, steps, 2).values()))
    limit = max_memory if max_memory is not None else MEMORY_FRACTION * available_memory()
    if need + extra > limit:
        raise ResourceError(f"the transients of the {len(cases)} cases need about {(need + extra) / 1e9:.3g} GB of "
                            f"histories but the limit is {limit / 1e9:.3g} GB; use fewer steps (a larger h or a shorter "
                            "run), fewer cases, outputs or modes, or raise the limit (--max-memory GB)")


def write_results(sc, prep: Prepared, out: Path, plots: bool, want_pics: bool, echo, t_start: float,
                  error_estimate: bool = True) -> RunOutput:
    """Table 1, then per case the transient (with its h/2 companion for the error estimates),
    its results file, max/min table, plots and snapshots; the envelope over cases and the
    summary. Everything goes to ``out``."""
    from liftoff.transient import solve, solve_estimated

    from . import report
    from .loads import table1

    stage_times = list(prep.stage_times)
    results, files, per_case_rows, tab1 = {}, [], {}, None
    for case in sc.cases:
        cp, mkey = prep.problems[case.name]
        stack = prep.stacks[mkey]
        if tab1 is None:
            t0 = time.perf_counter()
            tab1 = table1(stack, cp, case)
            files += [write_text(out / "table1.txt", tab1.table() + "\n"),
                      write_text(out / "table1.csv", "# c.g. motion under static loads; m and rad\n" + tab1.csv())]
            echo(tab1.table())
            stage_times.append(("Table 1", time.perf_counter() - t0))
        t0 = time.perf_counter()
        half = None
        if error_estimate or cp.problem.accuracy is not None:
            est = solve_estimated(cp.problem)
            res, half = est.result, est.check
        else:
            res = solve(cp.problem)
        stage_times.append((f"transient [{case.name}]" + (" + h/2" if half is not None else ""),
                            time.perf_counter() - t0))
        t0 = time.perf_counter()
        files.append(Path(res.save(out / f"results_{case.name}.h5")))
        results[case.name] = (res, cp)
        rows = report.maxmin(res.time, report.items(res, cp.attach), case.name)
        if half is not None:
            report.with_errors(rows, report.maxmin(half.time, report.items(half, cp.attach), case.name))
            half = None  # only its peaks are kept
        per_case_rows[case.name] = rows
        files.append(report.write_csv(rows, out / f"maxmin_{case.name}.csv"))
        if plots and case.output.plots:
            files += report.plots(res, cp, out, case.name)
        if want_pics and case.output.snapshots:
            files += report.snapshots(stack, res, cp, out, case.name)
        stage_times.append((f"reports [{case.name}]", time.perf_counter() - t0))
    env = report.envelope(per_case_rows)
    files.append(report.write_csv(env, out / "maxmin_envelope.csv"))
    echo("Max/min envelope over cases (posts: force on vehicle, Tz > 0 compression; full table in "
         "maxmin_envelope.csv):")
    echo(report.format_table(env, select=report.is_force, limit=40))
    first = next(iter(prep.stacks.values()))
    text = report.summary(sc, first, results, stage_times, env, time.perf_counter() - t_start)
    files.append(write_text(out / "summary.txt", text + "\n"))
    echo(text)
    return RunOutput(out, sc, prep.stacks, results, tab1, env, stage_times, files, text)


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
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
    p.add_argument("--example", choices=("barge",), default=None,
                   help="run an embedded example instead of the default lift-off scenario: 'barge' (a barge hitting "
                        "a dock, with a dock-stiffness sweep; docs/barge.md)")
    from .cli import add_common

    add_common(p)
    p.set_defaults(func=_cli)


def _cli(args: argparse.Namespace) -> int:
    from liftoff.config.barge import scenario_kind

    kw = dict(cache_dir=False if args.no_cache else args.cache, progress=not args.no_progress,
              snapshots=not args.no_snapshots)
    if args.example is not None and args.scenario is not None:
        raise InputError("liftoff run: give a scenario file or --example, not both")
    if args.example == "barge" or scenario_kind(args.scenario) == "barge":   # kind = "barge": workflows/barge.py
        from .barge import run as run_barge

        run_barge(args.scenario, args.out, **kw)
        return 0
    run(args.scenario, args.out, error_estimate=not args.no_error_estimate,
        max_memory=None if args.max_memory is None else args.max_memory * 1e9, **kw)
    return 0
