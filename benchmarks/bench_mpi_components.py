"""Cold model stages of `liftoff run` (the default scenario, empty stage cache) three ways:
serial (the FE stages one after another, the CB stages on a process pool), and under
`--ranks N` with the components shared out over the ranks (each reduced by one rank
alone) or distributed over all of them, one after another (LIFTOFF_MPI_COMPONENTS).

    .venv/bin/python benchmarks/bench_mpi_components.py [--ranks 2] [--modes concurrent serial distributed]

Each run is a separate process with a fresh cache; the figure is the run's own "model
stages total" (meshing, FE, Craig-Bampton, system modes), and its wall time. Issue 28
asked: concurrent components under mpirun >= 1.6x the serial model stages, on a quiet
machine.
"""
from __future__ import annotations

import argparse
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


def cold_run(mode: str, ranks: int, work: Path) -> tuple[float, float]:
    """(model stages total, process wall time) in s of one cold run in ``mode``."""
    out, cache = work / f"out_{mode}", work / f"cache_{mode}"
    cmd = [str(LIFTOFF), "run", "--out", str(out), "--cache", str(cache), "--no-progress"]
    env = {**os.environ, **MPI_ENV}
    if mode != "serial":
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
    ap.add_argument("--modes", nargs="+", default=["concurrent", "serial", "distributed"],
                    choices=["concurrent", "serial", "distributed"])
    args = ap.parse_args(argv)
    got = {}
    with tempfile.TemporaryDirectory(prefix="bench-mpi-") as tmp:
        for mode in args.modes:
            got[mode] = cold_run(mode, args.ranks, Path(tmp))
            print(f"  {mode:12s} model stages {got[mode][0]:7.1f} s   process {got[mode][1]:7.1f} s", flush=True)
    print(f"bench_mpi_components: {platform.machine()}, {os.cpu_count()} cores, {args.ranks} ranks, "
          f"load average {os.getloadavg()[0]:.1f} at the end")
    if "serial" in got:
        for mode in ("concurrent", "distributed"):
            if mode in got:
                print(f"  serial / {mode}: model stages {got['serial'][0] / got[mode][0]:.2f}x "
                      "(issue 28 asked >= 1.6 for concurrent)")


if __name__ == "__main__":
    main()
