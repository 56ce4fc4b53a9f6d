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

from liftoff.core.records import write_text

from .cache import StageCache, default_cache_dir, stage_key


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


def run(scenario=None, out: Path | str = "out/run", cache_dir: Path | str | None | bool = None,
        progress: bool = True, plots: bool = True, snapshots: bool = True, echo=print) -> RunOutput:
    """Run a scenario (path, parsed Scenario, or None for the default) into ``out``.

    ``cache_dir``: None -> default (``$LIFTOFF_CACHE`` or DIR/../.liftoff-cache),
    False -> no cache, else that directory. Under ``mpirun -n N`` every rank calls this:
    the model stages are built by all ranks together (workflows/parallel.py), the cases
    and every file by rank 0, whose RunOutput holds the results (the others' none)."""
    from liftoff.config import Scenario, Where, load_scenario

    from .loads import stack_mass_summary
    from .parallel import on_root, root_only, world
    from .pipeline import build_stack

    t_start = time.perf_counter()
    comm = world()
    if comm.rank != 0:
        echo, progress = (lambda *a, **k: None), False
    out = Path(out)
    on_root(comm, lambda: out.mkdir(parents=True, exist_ok=True), share=False)
    sc = scenario if isinstance(scenario, Scenario) else load_scenario(scenario)
    want_pics = snapshots and any(c.output.snapshots for c in sc.cases)
    if want_pics:  # pyvista (imported by fem.snapshot) before dolfinx (FENICSX-NOTES.md)
        import liftoff.fem.snapshot  # noqa: F401
    cache = StageCache(None if cache_dir is False else Path(cache_dir) if cache_dir else default_cache_dir(out),
                       comm=comm)
    res = RunOutput(out, sc, {}, {}, None, [], [])
    for case in sc.cases:            # model stages (all ranks); cases with equal models share one stack
        mkey = stage_key("model", asdict(case.model))
        if mkey not in res.stacks:
            n0 = len(cache.log)
            t0 = time.perf_counter()
            res.stacks[mkey] = build_stack(case.model, cache, progress=progress, where=Where(case.source, "model"))
            for stage, label, how, secs in cache.log[n0:]:
                res.stage_times.append((f"{stage} {label} ({how})", secs))
            res.stage_times.append(("model stages total", time.perf_counter() - t0))
            echo(stack_mass_summary(res.stacks[mkey]))
    root_only(comm, lambda: _cases(res, cache, want_pics, plots, progress, echo, t_start))
    return res


def _cases(res: RunOutput, cache: StageCache, want_pics: bool, plots: bool, progress: bool, echo,
           t_start: float) -> None:
    """Per case (rank 0): loads, Table 1 (first case), transient, results and reports."""
    from liftoff.transient import solve

    from . import report
    from .loads import build_problem, table1

    out, sc = res.out, res.scenario
    per_case_rows: dict[str, list] = {}
    for case in sc.cases:
        stack = res.stacks[stage_key("model", asdict(case.model))]
        t0 = time.perf_counter()
        cp = build_problem(case, stack, progress=progress)
        if res.table1 is None:
            res.table1 = table1(stack, cp, case)
            write_text(out / "table1.txt", res.table1.table() + "\n")
            write_text(out / "table1.csv", "# c.g. motion under static loads; m and rad\n" + res.table1.csv())
            res.files += [out / "table1.txt", out / "table1.csv"]
            echo(res.table1.table())
        res.stage_times.append((f"loads + Table 1 [{case.name}]", time.perf_counter() - t0))
        t0 = time.perf_counter()
        result = solve(cp.problem)
        res.stage_times.append((f"transient [{case.name}]", time.perf_counter() - t0))
        t0 = time.perf_counter()
        res.files.append(Path(result.save(out / f"results_{case.name}.h5")))
        res.results[case.name] = (result, cp)
        rows = report.maxmin(result.time, report.items(result, cp.attach), case.name)
        per_case_rows[case.name] = rows
        res.files.append(report.write_csv(rows, out / f"maxmin_{case.name}.csv"))
        if plots and case.output.plots:
            res.files += report.plots(result, cp, out, case.name)
        if want_pics and case.output.snapshots:
            res.files += report.snapshots(stack, result, cp, out, case.name)
        res.stage_times.append((f"reports [{case.name}]", time.perf_counter() - t0))
    res.envelope = report.envelope(per_case_rows)
    res.files.append(report.write_csv(res.envelope, out / "maxmin_envelope.csv"))
    echo("Max/min envelope over cases (posts: force on vehicle, Tz > 0 compression; full table in "
         "maxmin_envelope.csv):")
    echo(report.format_table(res.envelope, select=lambda s: s.startswith(("post", "attach")) and s[-2:] in
                             ("Tx", "Ty", "Tz"), limit=40))
    first = next(iter(res.stacks.values()))
    res.summary = report.summary(sc, first, res.results, res.stage_times, res.envelope,
                                 time.perf_counter() - t_start)
    write_text(out / "summary.txt", res.summary + "\n")
    res.files.append(out / "summary.txt")
    echo(res.summary)
    echo(f"  outputs in {out}/ ({len(res.files)} files); cache {cache.root}")


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
    p.add_argument("--ranks", type=int, default=None, metavar="N",
                   help="run on N MPI processes: launches `mpirun -n N liftoff run ...` (the same as "
                        "starting it under mpirun yourself); the FE stages are distributed over them")
    p.set_defaults(func=_cli)


def _cli(args: argparse.Namespace) -> int:
    from liftoff.core.errors import InputError

    from .parallel import launched_size

    if args.ranks is not None:
        if args.ranks < 1:
            raise InputError(f"--ranks: {args.ranks} must be >= 1")
        if launched_size() > 1 and args.ranks != launched_size():
            raise InputError(f"--ranks {args.ranks} inside `mpirun -n {launched_size()}`: give one of the two")
        if args.ranks > 1 and launched_size() == 1:
            return launch(args.ranks, _child_args(args))
    run(args.scenario, args.out, cache_dir=False if args.no_cache else args.cache,
        progress=not args.no_progress, snapshots=not args.no_snapshots)
    return 0


def _child_args(args: argparse.Namespace) -> list[str]:
    argv = ["run"] + ([str(args.scenario)] if args.scenario is not None else []) + ["--out", str(args.out)]
    argv += ["--cache", str(args.cache)] if args.cache is not None else []
    return argv + [flag for flag, on in (("--no-cache", args.no_cache), ("--no-snapshots", args.no_snapshots),
                                         ("--no-progress", args.no_progress)) if on]


def launch(ranks: int, argv: list[str]) -> int:
    """``mpirun --quiet -n ranks python -m liftoff.workflows.cli ARGV``; returns its exit
    status. Every rank reports an error (it may be its own); the copies of an error line
    are printed once."""
    import os
    import shutil
    import subprocess
    import sys

    from liftoff.core.errors import InputError

    mpirun = shutil.which("mpirun")
    if mpirun is None:
        raise InputError("--ranks: mpirun not found (Debian package openmpi-bin, installed with python3-dolfinx-real)")
    cmd = [mpirun, "--quiet", "-n", str(ranks)] + (["--oversubscribe"] if ranks > (os.cpu_count() or 1) else [])
    env = dict(os.environ)
    if hasattr(os, "geteuid") and os.geteuid() == 0:   # containers: Open MPI refuses root otherwise
        env.update(OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    proc = subprocess.Popen(cmd + [sys.executable, "-m", "liftoff.workflows.cli", *argv], stderr=subprocess.PIPE,
                            env=env)
    _forward_stderr(proc.stderr.fileno(), sys.stderr)
    return proc.wait()


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
