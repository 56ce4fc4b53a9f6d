"""Cold model stages of `liftoff run` (the default scenario, empty stage cache) four ways:
one by one (a serial run with LIFTOFF_MODEL_WORKERS=1: each component's FE and CB stages
after the last one's, as every run reduced them when issue 28 was written), serial (a
serial run as it is now: the components' FE and CB stages on a pool of processes, one per
core), and under `--ranks N` with the components shared out over the ranks (each reduced
by one rank alone) or distributed over all of them, one after another
(LIFTOFF_MPI_COMPONENTS).

    .venv/bin/python benchmarks/bench_mpi_components.py [--ranks 2]
        [--modes one-by-one serial concurrent distributed] [--json docs/figures/bench_mpi_components.json]

Each run is a separate process with a fresh cache (``--repeat N``: N runs of each mode,
taken in turns, the least reported); the figure is the run's own "model
stages total" (meshing, FE, Craig-Bampton, system modes), and its wall time. Issue 28
asked: concurrent components under mpirun >= 1.6x the serial model stages, on a quiet
machine; its "serial" was the one-by-one run (its text: "the five FE + CB stages run one
after another although they are independent"), so both ratios are printed: against one by
one (the issue's) and against today's serial run, which is concurrent itself. With
``--json`` the figures go to a file that benchmarks/default_figures.py renders into
docs/workflow.md.
"""
from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_workflow import LIFTOFF, stage_times  # noqa: E402

MPI_ENV = {"OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1",
           "OMPI_MCA_rmaps_base_oversubscribe": "1", "PYVISTA_OFF_SCREEN": "true"}


MODES = ("one-by-one", "serial", "concurrent", "distributed")


def cold_run(mode: str, ranks: int, work: Path) -> tuple[float, float]:
    """(model stages total, process wall time) in s of one cold run in ``mode``."""
    out, cache = work / f"out_{mode}", work / f"cache_{mode}"
    cmd = [str(LIFTOFF), "run", "--out", str(out), "--cache", str(cache), "--no-progress"]
    env = {**os.environ, **MPI_ENV}
    if mode == "one-by-one":
        env["LIFTOFF_MODEL_WORKERS"] = "1"
    elif mode != "serial":
        cmd += ["--ranks", str(ranks)]
        env["LIFTOFF_MPI_COMPONENTS"] = mode
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True, env=env)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise SystemExit(f"bench_mpi_components: {mode} run failed:\n{proc.stderr[-2000:]}")
    return stage_times(out / "summary.txt")["model stages total"], wall


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ranks", type=int, default=2)
    ap.add_argument("--modes", nargs="+", default=list(MODES), choices=list(MODES))
    ap.add_argument("--repeat", type=int, default=1, help="cold runs of each mode, taken in turns (the least reported)")
    ap.add_argument("--json", type=Path, default=None, help="also write the figures here")
    args = ap.parse_args(argv)
    every: dict[str, list] = {m: [] for m in args.modes}
    for rep in range(args.repeat):
        for mode in args.modes:
            with tempfile.TemporaryDirectory(prefix="bench-mpi-") as tmp:   # a fresh, empty cache each run
                every[mode].append(cold_run(mode, args.ranks, Path(tmp)))
            print(f"  {mode:12s} model stages {every[mode][-1][0]:7.1f} s   process {every[mode][-1][1]:7.1f} s",
                  flush=True)
    got = {m: min(runs) for m, runs in every.items()}
    print(f"bench_mpi_components: {platform.machine()}, {os.cpu_count()} cores, {args.ranks} ranks, "
          f"load average {os.getloadavg()[0]:.1f} at the end")
    for base in ("one-by-one", "serial"):
        for mode in ("serial", "concurrent", "distributed"):
            if base in got and mode in got and mode != base:
                print(f"  {base} / {mode}: model stages {got[base][0] / got[mode][0]:.2f}x"
                      + (" (issue 28 asked >= 1.6 for concurrent)" if mode == "concurrent" else ""))
    if args.json is not None:
        from liftoff.core.records import write_text

        write_text(args.json, json.dumps({
            "date": datetime.date.today().isoformat(), "cpus": os.cpu_count(), "machine": platform.machine(),
            "ranks": args.ranks, "load_average_end": os.getloadavg()[0], "repeat": args.repeat,
            "runs": {m: {"model_stages_s": got[m][0], "wall_s": got[m][1],
                         "every_model_stages_s": [r[0] for r in every[m]]} for m in got}}, indent=1) + "\n")


if __name__ == "__main__":
    main()
