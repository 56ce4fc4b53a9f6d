"""Cases marched together (liftoff.transient.solve_batch) against the same cases solved one
by one (liftoff.transient.solve): issue 28's batched-marching target.

    .venv/bin/python benchmarks/bench_batch.py [--modes 3000 300] [--cases 64] [--repeat 3]
                                               [--default-cases 8] [--json docs/figures/bench_batch.json]
                                               [--append]

The problem is benchmarks/bench_transient.py's (8 hold-down points x 3 directions = 24
penalty contact rows, gravity, a thrust ramp; bolted throughout, as the issue's
measurement asked), at ``--modes`` vehicle + pad modes; case k's thrust is scaled by
1 + 0.01 k. Per case-step time: the slope of the wall time over two run lengths (500 and
2,500 steps), so the set-up (static solves, step choice, the batch's bases) drops out;
the minimum of ``--repeat`` runs, batched and one-by-one taken in turns; the one-by-one
time is measured on ``--check`` of the cases and scaled to ``--cases``.

With ``--default-cases N`` (8 unless 0) also the default scenario's first N generated cases,
the problems `liftoff run --cases` marches (1,384 + 78 modes, 24 contact rows and every output
row the run recovers), whole solves batched and one by one: where the one-by-one step already
runs from the core's cache, batching saves little, and that is what `liftoff run --cases`
chooses by (it solves its cases one by one).

Equality: the largest difference of the contact forces and the vehicle outputs, batched
against one by one, relative to each history's peak; beside it the one-by-one solve's own
spread when the same case is summed in another order (its vehicle's elastic modes in
reverse order: tests/transient/test_batch.py's reference). A bolted stack's contact
forces are K_C times small differences of large modal displacements, so neither is zero.

The speed-up depends on the CPU (README "Cases marched together" renders each machine's
measurement from docs/figures/bench_batch.json: on an AMD EPYC with AVX2, znver3, less
than on the first machine). The group's pass over the modes is vectorised across its
8 cases (one 512-bit register, or two 256-bit ones); the JSON records the CPU numba compiled
for (LLVM's name) and its vector width; ``--append`` adds a further machine's measurement beside the first.
"""
from __future__ import annotations

import argparse
import dataclasses
import datetime
import json
import os
import platform
import sys
import time as _time
import warnings
from pathlib import Path

import liftoff  # noqa: F401 - before numpy: it picks the OpenBLAS kernels (liftoff/core/openblas.py)
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_transient import host_cpu, problem  # noqa: E402

from liftoff.transient import TabulatedForce, solve, solve_batch  # noqa: E402
from liftoff.transient.batch import GROUP  # noqa: E402

#: issue 28's target: batched case-steps per second over one-by-one solves
TARGET = 3.0


def cases(n_steps: int, n_veh: int, n_pad: int, K: int, reverse: bool = False):
    """bench_transient's problem, bolted throughout, its thrust scaled by 1 + 0.01 k in case
    k; ``reverse``: the vehicle's elastic modes in reverse order (the same problem)."""
    base = problem(n_steps, n_veh=n_veh, n_pad=n_pad, release=None)
    if reverse:
        v = base.body_a
        nr = int(np.sum(v.omega == 0))
        perm = np.r_[np.arange(nr), np.arange(v.n_modes - 1, nr - 1, -1)]
        base = dataclasses.replace(base, body_a=dataclasses.replace(
            v, omega=v.omega[perm], zeta=v.zeta[perm], phi=v.phi[:, perm], participation=v.participation[perm]))
    fo = base.forcing
    return [dataclasses.replace(base, progress=False, forcing=dataclasses.replace(
        fo, tables=[TabulatedForce(t.body, t.label, t.time, t.value * (1 + 0.01 * k)) for t in fo.tables]))
        for k in range(K)]


def default_cases(n: int, cache: Path) -> list:
    """The problems of the default scenario's first ``n`` generated cases (the model from the
    stage ``cache``, built there if missing): what `liftoff run --cases` marches."""
    from liftoff.config import Where, load_scenario
    from liftoff.workflows.cache import StageCache
    from liftoff.workflows.loads import build_problem
    from liftoff.workflows.pipeline import build_stack

    sc = load_scenario(None, n_cases=n)
    case0 = sc.generated_case(0)
    stack = build_stack(case0.model, StageCache(cache), progress=False, where=Where(case0.source, "model"))
    return [dataclasses.replace(build_problem(sc.generated_case(i), stack, progress=False).problem, progress=False)
            for i in range(n)]


def measure_default(n: int, repeat: int, cache: Path) -> dict:
    """Whole solves (set-up included) of the default's first ``n`` generated cases, batched and
    one by one, taken in turns, the least of ``repeat`` each; and how far apart their contact
    forces land (of each history's peak)."""
    P = default_cases(n, cache)
    solve_batch(P[:2]), solve(P[0])                      # compile (numba's cache)
    tb, to, rb, r1 = [], [], None, None
    for _ in range(repeat):
        t = _time.perf_counter(); rb = solve_batch(P); tb.append(_time.perf_counter() - t)
        t = _time.perf_counter(); r1 = [solve(p) for p in P]; to.append(_time.perf_counter() - t)
    p0 = P[0]
    return {"cases": n, "group": GROUP, "vehicle_modes": int(p0.body_a.n_modes), "pad_modes": int(p0.body_b.n_modes),
            "contact_rows": int(sum(len(c.labels_a) for c in p0.contacts)), "steps": int(rb[0].time.size - 1),
            "batched_s": min(tb) / n, "one_by_one_s": min(to) / n, "batched_all_s": tb, "one_by_one_all_s": to,
            "contact_force_diff": max(_rel(a.contact_force, b.contact_force) for a, b in zip(rb, r1))}


def _rel(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.abs(a - b).max() / max(np.abs(b).max(), 1e-300))


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--modes", type=int, nargs=2, default=[3000, 300], metavar=("VEHICLE", "PAD"))
    ap.add_argument("--cases", type=int, default=64)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--check", type=int, default=4, help="cases solved one by one (their time scaled to --cases)")
    ap.add_argument("--json", type=Path, default=None, help="also write the figures here")
    ap.add_argument("--append", action="store_true",
                    help="keep the --json file's measurement and add this one as another machine's (under 'others', "
                         "replacing one of the same CPU): the speed-up depends on the CPU's vector width")
    ap.add_argument("--default-cases", type=int, default=8, metavar="N",
                    help="also the default scenario's first N generated cases, whole solves (0: not)")
    ap.add_argument("--cache", type=Path, default=Path(__file__).resolve().parent.parent / "out" / ".liftoff-cache",
                    help="the stage cache of the default's model (built there if missing)")
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore")                      # the synthetic stack's step warning
    nv, npd, K = args.modes[0], args.modes[1], args.cases
    short, long_ = cases(500, nv, npd, K), cases(2500, nv, npd, K)
    solve_batch(short[:2]), solve(short[0])              # compile (numba's cache)

    def batch(P):
        t = _time.perf_counter(); out = solve_batch(P); return _time.perf_counter() - t, out

    def alone(P):
        t = _time.perf_counter(); out = [solve(p) for p in P[:args.check]]
        return (_time.perf_counter() - t) * len(P) / args.check, out

    tb, to = [], []
    for _ in range(args.repeat):
        tb.append(batch(long_)[0] - batch(short)[0])
        to.append(alone(long_)[0] - alone(short)[0])
    rb, r1 = batch(long_)[1], alone(long_)[1]
    rp = [solve(p) for p in cases(2500, nv, npd, K, reverse=True)[:args.check]]
    dF = max(_rel(a.contact_force, b.contact_force) for a, b in zip(rb, r1))
    dY = max(_rel(a.displacement["a"], b.displacement["a"]) for a, b in zip(rb, r1))
    sF = max(_rel(a.contact_force, b.contact_force) for a, b in zip(rp, r1))
    sY = max(_rel(a.displacement["a"], b.displacement["a"]) for a, b in zip(rp, r1))
    per_b, per_1 = min(tb) / 2000 / K * 1e6, min(to) / 2000 / K * 1e6
    print(f"bench_batch: {platform.machine()}, {os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f}, "
          f"min of {args.repeat}")
    print(f"  {nv} + {npd} modes, 24 contact rows, {K} cases in groups of {GROUP}, 2,000 steps (slope of 500 -> 2,500)")
    print(f"  per case-step: batched {per_b:.1f} us, one by one {per_1:.1f} us; speed-up {per_1 / per_b:.2f}"
          f" (issue 28 asked >= {TARGET:g})")
    print(f"  batched vs one by one, of the peak: contact forces {dF:.1e}, vehicle outputs {dY:.1e}; one by one with "
          f"the modes reordered: {sF:.1e}, {sY:.1e}")
    dflt = None
    if args.default_cases:
        dflt = measure_default(args.default_cases, args.repeat, args.cache)
        print(f"  the default's first {dflt['cases']} generated cases ({dflt['vehicle_modes']} + {dflt['pad_modes']} "
              f"modes, {dflt['contact_rows']} contact rows, {dflt['steps']} steps), whole solves: batched "
              f"{dflt['batched_s']:.3f} s a case, one by one {dflt['one_by_one_s']:.3f} s; speed-up "
              f"{dflt['one_by_one_s'] / dflt['batched_s']:.2f}; contact forces {dflt['contact_force_diff']:.1e} apart")
    if args.json is not None:
        from liftoff.core.records import write_text

        this = {
            "date": datetime.date.today().isoformat(), "cpus": os.cpu_count(), "machine": platform.machine(),
            **host_cpu(),
            "load_average_end": os.getloadavg()[0], "repeat": args.repeat, "vehicle_modes": nv, "pad_modes": npd,
            "contact_rows": 24, "cases": K, "group": GROUP, "batched_us": per_b, "one_by_one_us": per_1,
            "batched_all_us": tb, "one_by_one_all_us": to, "contact_force_diff": dF, "output_diff": dY,
            "reordered_contact_force_diff": sF, "reordered_output_diff": sY,
            **({"default": dflt} if dflt else {})}
        if args.append and args.json.is_file():        # (no file yet: this one is the first machine's)
            kept = json.loads(args.json.read_text())
            kept["others"] = [o for o in kept.get("others", []) if o.get("cpu") != this["cpu"]] + [this]
            this = kept
        write_text(args.json, json.dumps(this, indent=1) + "\n")


if __name__ == "__main__":
    main()
