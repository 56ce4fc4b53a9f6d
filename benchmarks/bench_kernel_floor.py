"""The transient kernel against its floor (issue 28): liftoff's per-step time beside a
hand-written numba loop doing only the per-step arithmetic of the same problem.

    .venv/bin/python benchmarks/bench_kernel_floor.py [--modes 300 3300] [--repeat 3]

Problem: benchmarks/bench_transient.py's (8 hold-down points x 3 directions = 24 contact
rows, h = 1e-4 s, or eq. 12's step where shorter) with n vehicle + 100 pad modes, bolted throughout (one active set, as
most of a lift-off's steps).

The floor, per step, for n modes, nc contact rows and k recovered output rows (k counted
from liftoff's own result, each over its body's modes):

* exact modal update of the free motion: qf = F q + G v + Ac P0 + Bc P1, and the same for
  vf (8 coefficient arrays, eq. 9-10);
* contact displacement u = Phi qf (nc x n) and the force f = -A^-1 (c + u) with the
  active set's inverse (nc x nc, known);
* the contact load Phi^T f, the end-of-step q, v and acceleration;
* the outputs y = L [q v acc] (k rows) and the contact forces stored;

its products by BLAS (dgemv through numba's np.dot) on one thread, as liftoff's solve.

liftoff's per-step time is the slope of ``solve`` over two run lengths (4,000 and 12,000
steps), so set-up, static solve and compilation drop out; both are the best of
``--repeat`` measurements in this process, taken in turns (liftoff, floor, liftoff, ...).
The issue's target: liftoff within 1.2x of the floor.
"""
from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import sys
import time
from pathlib import Path

import liftoff  # noqa: F401 - before numpy: it picks the OpenBLAS kernels (liftoff/core/openblas.py)
import numpy as np
from numba import njit

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_transient import N_PAD, host_cpu, problem  # noqa: E402

from liftoff.transient import solve  # noqa: E402


@njit(cache=True)
def floor_march(n_steps, coef, w2, zw2, P0, P1, Phi, PhiT, Ainv, offset, La, Lb, na, q, v, acc, F, Ya, Yb):
    """The per-step arithmetic alone (module docstring), its products by BLAS (dgemv through
    numba's np.dot, as fast as these shapes go on this machine); F (n_steps, nc), Ya, Yb
    (n_steps, rows) the outputs of body a (over its na modes) and b."""
    n = q.size
    qf, vf = np.empty(n), np.empty(n)
    for s in range(n_steps):
        for m in range(n):
            qf[m] = coef[0, m] * q[m] + coef[1, m] * v[m] + coef[2, m] * P0[m] + coef[3, m] * P1[m]
            vf[m] = coef[4, m] * q[m] + coef[5, m] * v[m] + coef[6, m] * P0[m] + coef[7, m] * P1[m]
        u = np.dot(Phi, qf) + offset
        f = -np.dot(Ainv, u)
        F[s] = f
        Pc = np.dot(PhiT, f)
        for m in range(n):
            q[m] = qf[m] + coef[3, m] * Pc[m]
            v[m] = vf[m] + coef[7, m] * Pc[m]
            acc[m] = P1[m] + Pc[m] - zw2[m] * v[m] - w2[m] * q[m]
        ka, kb = La.shape[0] // 3, Lb.shape[0] // 3
        Ya[s, :ka] = np.dot(La[:ka], q[:na])
        Ya[s, ka:2 * ka] = np.dot(La[ka:2 * ka], v[:na])
        Ya[s, 2 * ka:] = np.dot(La[2 * ka:], acc[:na])
        Yb[s, :kb] = np.dot(Lb[:kb], q[na:])
        Yb[s, kb:2 * kb] = np.dot(Lb[kb:2 * kb], v[na:])
        Yb[s, 2 * kb:] = np.dot(Lb[2 * kb:], acc[na:])
    return F


def output_rows(res) -> tuple[int, int]:
    """(rows over body a's modes, rows over body b's modes) that liftoff recovers per step."""
    a = sum(np.shape(getattr(res, kind)["a"])[1] for kind in ("displacement", "velocity", "acceleration"))
    b = sum(np.shape(getattr(res, kind)["b"])[1] for kind in ("displacement", "velocity", "acceleration"))
    a += 0 if res.rigid_body_motion_a is None else res.rigid_body_motion_a.shape[1]
    b += 0 if res.rigid_body_motion_b is None else res.rigid_body_motion_b.shape[1]
    for name, arr in res.recovered.items():
        if res.recovery_items[name].body == "a":
            a += arr.shape[1]
        else:
            b += arr.shape[1]
    return a, b


def _liftoff_problems(n_veh: int) -> dict:
    return {steps: problem(steps, n_veh=n_veh, release=None) for steps in (4_000, 12_000)}


def liftoff_times(probs: dict) -> tuple[dict, object]:
    """One measurement: the wall time of ``solve`` at each run length."""
    times, res = {}, None
    for steps, prob in probs.items():
        t0 = time.perf_counter()
        res = solve(prob)
        times[steps] = time.perf_counter() - t0
    return times, res


def floor_inputs(n_veh: int, res, steps: int = 8_000) -> tuple:
    rng = np.random.default_rng(3)
    n, nc = n_veh + N_PAD, 24
    ka, kb = (3 * ((k + 2) // 3) for k in output_rows(res))    # whole q, v, acc triples
    coef = rng.uniform(-1.0, 1.0, (8, n)) * 1e-3
    w2, zw2 = rng.uniform(0, 1e6, n), rng.uniform(0, 10, n)
    P0, P1 = rng.standard_normal(n), rng.standard_normal(n)
    Phi, Ainv = rng.standard_normal((nc, n)), rng.standard_normal((nc, nc)) * 1e-3
    PhiT = np.ascontiguousarray(Phi.T)
    La, Lb = rng.standard_normal((ka, n_veh)), rng.standard_normal((kb, N_PAD))

    def args(N):
        return (N, coef, w2, zw2, P0, P1, Phi, PhiT, Ainv, np.zeros(nc), La, Lb, n_veh, np.zeros(n), np.zeros(n),
                np.zeros(n), np.zeros((N, nc)), np.zeros((N, ka)), np.zeros((N, kb)))
    floor_march(*args(10))
    return args, steps


def floor_per_step(args, steps: int) -> float:
    """One measurement of the floor, one BLAS thread as liftoff's solve."""
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1, user_api="blas"):
        a = args(steps)
        t0 = time.perf_counter()
        floor_march(*a)
        return (time.perf_counter() - t0) / steps


def measure(n_veh: int, repeat: int) -> tuple[float, float, object]:
    """(liftoff, floor) per step from the best of ``repeat`` measurements each, taken in turns
    (liftoff's two lengths, the floor, liftoff's two lengths, ...), so that the minima come from
    the same stretch of time on a machine whose speed drifts; liftoff's is the slope between
    the best times of its two lengths; and liftoff's result."""
    probs = _liftoff_problems(n_veh)
    _, res = liftoff_times(probs)                     # compiled and warm
    args, steps = floor_inputs(n_veh, res)
    best = {k: np.inf for k in probs}
    floor = []
    for _ in range(repeat):
        times, res = liftoff_times(probs)
        best = {k: min(best[k], t) for k, t in times.items()}
        floor.append(floor_per_step(args, steps))
    return (best[12_000] - best[4_000]) / 8_000, min(floor), res


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--modes", type=int, nargs="+", default=[200, 3000], help="vehicle modes (pad: 100)")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--json", type=Path, help="write the figures (docs/figures/bench_kernel_floor.json), which "
                    "benchmarks/default_figures.py renders into the README")
    ap.add_argument("--append", action="store_true",
                    help="keep the --json file's measurement and add this one as another machine's (under 'others', "
                         "replacing one of the same CPU): the ratio depends on the CPU")
    args = ap.parse_args()
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(f"bench_kernel_floor: {platform.machine()}, {os.cpu_count()} cores, load average {load:.1f}, "
          f"best of {args.repeat}")
    print(f"  {'modes (vehicle + pad)':<24}{'liftoff (us/step)':>18}{'floor (us/step)':>18}{'ratio':>8}"
          f"{'outputs':>9}")
    rows = []
    for n_veh in args.modes:
        per_step, floor, res = measure(n_veh, args.repeat)
        ka, kb = output_rows(res)
        print(f"  {f'{n_veh} + {N_PAD}':<24}{1e6 * per_step:>18.1f}{1e6 * floor:>18.1f}{per_step / floor:>8.2f}"
              f"{ka + kb:>9}")
        rows.append({"vehicle_modes": n_veh, "pad_modes": N_PAD, "contact_rows": 24, "liftoff_us": 1e6 * per_step,
                     "floor_us": 1e6 * floor, "outputs": ka + kb})
    print("  target (issue 28): ratio <= 1.2")
    if args.json:
        from liftoff.core import write_text
        from liftoff.core.openblas import describe

        blas = describe()
        this = {"date": datetime.date.today().isoformat(), "cpus": os.cpu_count(), **host_cpu(),
                "load_average_end": os.getloadavg()[0] if hasattr(os, "getloadavg") else None, "repeat": args.repeat,
                "blas_kernels": blas["kernels"], "rows": rows}
        if args.append and args.json.is_file():        # (no file yet: this one is the first machine's)
            kept = json.loads(args.json.read_text())
            kept["others"] = [o for o in kept.get("others", []) if o.get("cpu") != this["cpu"]] + [this]
            this = kept
        write_text(args.json, json.dumps(this, indent=1) + "\n")
        print(f"  wrote {args.json}")


if __name__ == "__main__":
    main()
