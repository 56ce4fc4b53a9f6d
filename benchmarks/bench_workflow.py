"""Cold and warm wall time of `liftoff run` (the embedded default scenario), per stage.

    python benchmarks/bench_workflow.py [--scenario FILE | --example barge] [--keep DIR] [--json FILE]
                                        [--warm-repeat N]

Cold: a fresh, empty stage cache (meshing, FE assembly, Craig-Bampton, system modes all
computed). Warm: the same command again on that cache (a second run that changes only
loads or cases costs this much; with ``--warm-repeat N`` N such runs, the fastest reported
with its stage times and every wall time listed: the machine is shared and drifts). Each
run is a separate `liftoff run` process, so the
totals include interpreter start-up, imports and numba compilation. Per-stage times come
from the run's own summary.txt. With ``--json`` (docs/figures/bench_workflow.json for the
default) the figures are written for benchmarks/default_figures.py, which renders them into
README.md and docs/workflow.md (machine-dependent: the test checks the documents show the
file, not that another machine gives the same times).
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
LIFTOFF = Path(sys.executable).with_name("liftoff")


def stage_times(summary: Path) -> dict[str, float]:
    out, on = {}, False
    for line in summary.read_text().splitlines():
        if "wall time per stage" in line:
            on = True
            continue
        m = re.match(r"\s{4}(.+?)\s+([0-9.]+) s$", line) if on else None
        if m:
            out[m.group(1).strip()] = float(m.group(2))
    return out


def model_line(summary: str) -> dict:
    """Modes and steps of the run (its summary.txt): what the times were measured on."""
    out = {}
    m = re.search(r"vehicle\s+(\d+) modes.*?pad (\d+) modes", summary)
    if m:
        out.update(vehicle_modes=int(m.group(1)), pad_modes=int(m.group(2)))
    m = re.search(r"case '[^']+': (\d+) steps of h = ([0-9.e-]+) s", summary)
    if m:
        out.update(steps=int(m.group(1)), h_s=float(m.group(2)))
    return out


def run_once(scenario, out: Path, cache: Path, example: str | None = None) -> tuple[float, dict]:
    cmd = [str(LIFTOFF), "run", *([str(scenario)] if scenario else []), *(["--example", example] if example else []),
           "--out", str(out), "--cache", str(cache), "--no-progress"]
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True, env={**os.environ, "PYVISTA_OFF_SCREEN": "true"})
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        sys.exit(f"bench_workflow: `{' '.join(cmd)}` failed:\n{proc.stderr[-2000:]}")
    return wall, stage_times(out / "summary.txt")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scenario", type=Path, default=None, help="scenario file (default: embedded)")
    ap.add_argument("--example", choices=("barge",), default=None, help="an embedded example (liftoff run --example)")
    ap.add_argument("--keep", type=Path, default=None, help="keep outputs and cache in this directory")
    ap.add_argument("--warm-repeat", type=int, default=3, help="warm runs (the fastest is reported) [3]")
    ap.add_argument("--json", type=Path, default=None,
                    help="also write the figures here (docs/figures/bench_workflow.json: the default's, rendered into "
                         "README.md and docs/workflow.md by benchmarks/default_figures.py)")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="liftoff-bench-") as tmp:
        base = args.keep or Path(tmp)
        cache = base / "cache"
        cold_wall, cold = run_once(args.scenario, base / "cold", cache, args.example)
        warms = []
        for k in range(max(1, args.warm_repeat)):
            warms.append(run_once(args.scenario, base / f"warm{k}", cache, args.example) + (k,))
            print(f"warm run {k + 1}: {warms[-1][0]:.1f} s", flush=True)
        warm_wall, warm, k = min(warms, key=lambda w: w[0])
        summary = (base / f"warm{k}" / "summary.txt").read_text()
    what = args.scenario or (f"--example {args.example}" if args.example else "(embedded default)")
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(f"liftoff run {what}: {platform.processor() or platform.machine()}, "
          f"{os.cpu_count()} CPUs, Python {platform.python_version()}, load average {load:.1f} at the end")
    print(f"{'stage':<40}{'cold (s)':>10}{'warm (s)':>10}")
    for name in cold:
        w = warm.get(name, warm.get(name.replace("(built)", "(hit)"), float("nan")))
        print(f"{name:<40}{cold[name]:>10.2f}{w:>10.2f}")
    print(f"{'process wall time (incl. start-up)':<40}{cold_wall:>10.2f}{warm_wall:>10.2f}")
    print(f"warm / cold = {warm_wall / cold_wall:.2f}")
    if args.json:
        rec = {"what": str(what), "date": time.strftime("%Y-%m-%d"), "cpus": os.cpu_count(),
               "machine": platform.processor() or platform.machine(), "python": platform.python_version(),
               "load_average_end": load, "cold_s": cold, "warm_s": warm, "cold_wall_s": cold_wall,
               "warm_wall_s": warm_wall, "warm_walls_s": [w[0] for w in warms], "model": model_line(summary)}
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(rec, indent=1) + "\n")
        print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
