"""Benchmark: the transient with its h/2 error estimate (transient/accuracy.solve_estimated),
the two runs marched together on two threads (``CONCURRENT_PAIR``, the default) against one
after the other, in the same process.

Problem: bench_transient.py's (vehicle 200 modes, pad 100 modes, 8 hold-downs x 3
directions, bolts released half-way), ``--steps`` steps at h = 1e-4 s; the h/2 run has
twice as many. Each variant is timed ``--repeat`` times, interleaved, after a warm-up that
compiles the kernel; min and median wall time, and the ratio of the minima. The results of
the two variants are the same, bit for bit (checked here; tests/transient/test_accuracy.py).
On two free cores the pair takes the h/2 run's time, 2/3 of the sequential time at best.

    .venv/bin/python benchmarks/bench_error_estimate.py [--steps 50000] [--repeat 3]
"""
from __future__ import annotations

import argparse
import importlib.util
import os
import statistics
import time
from pathlib import Path

import liftoff  # noqa: F401 - before numpy: it picks the OpenBLAS kernels (liftoff/core/openblas.py)
import numpy as np

from liftoff.transient import accuracy, solve_estimated

HERE = Path(__file__).resolve().parent


def _bench_transient():
    spec = importlib.util.spec_from_file_location("bench_transient", HERE / "bench_transient.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=50_000)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    bench = _bench_transient()
    prob = bench.problem(args.steps)
    solve_estimated(bench.problem(2_000))                         # compile
    times = {True: [], False: []}
    last = {}
    for _ in range(args.repeat):
        for together in (True, False):
            accuracy.CONCURRENT_PAIR = together
            t0 = time.perf_counter()
            last[together] = solve_estimated(prob)
            times[together].append(time.perf_counter() - t0)
    a, b = last[True], last[False]
    same = np.array_equal(a.result.contact_force, b.result.contact_force) and \
        np.array_equal(a.check.contact_force, b.check.contact_force)
    print(f"transient + h/2 check, {args.steps} + {2 * args.steps} steps, 300 modes, 24 contact directions "
          f"({os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f} at the end):")
    for together, name in ((True, "together (two threads)"), (False, "one after the other")):
        t = times[together]
        print(f"  {name:24s} min {min(t):.2f} s, median {statistics.median(t):.2f} s")
    print(f"  ratio of the minima: {min(times[True]) / min(times[False]):.2f}; results equal bit for bit: {same}")


if __name__ == "__main__":
    main()
