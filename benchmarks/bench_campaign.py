"""Load campaign of the default lift-off: N dispersed cases, warm stage cache, wall time and
peak memory of the whole process tree (the command, its workers, a Dask scheduler).

    .venv/bin/python benchmarks/bench_campaign.py [--cases 1000] [--workers 2] [--dask] [--scaling 200]
                                                  [--flat 250] [--cache DIR] [--json FILE [--append]]

Each measurement is one `liftoff run --cases N` process (the default scenario: its two named
cases with plots and snapshots, then the N generated cases, envelopes, statistics, SRS,
envelope histories and the governing case's reports) with a fresh campaign folder, so no
case is reused. The stage cache is warmed first by one run without generated cases.
Memory: the sum of the proportional set sizes (PSS: shared pages divided among the processes
that map them) of the command and all its descendants, sampled every 0.2 s (psutil); the
peak of that sum is reported, with the peak resident set of the command itself;
CPU: user + system seconds of the same processes (its ratio to the wall time shows how
many cores the run actually got on a shared machine).
--dask repeats the N cases on a local Dask cluster of --workers processes; --scaling M runs
M cases on 1 and on --workers workers; --flat M runs M cases to compare the peak memory
with N's. The machine's load average is printed before and after each run: the machine is
shared, so repeat on a quiet machine for figures to quote.
--json writes every measurement (docs/figures/bench_campaign.json), which
benchmarks/default_figures.py renders into README.md: its figures are never typed; with
--append the runs are added to those the file already holds (its commands listed), so a
long measurement (1,000 cases) can be made on its own.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import psutil

ROOT = Path(__file__).resolve().parent.parent
LIFTOFF = Path(sys.executable).with_name("liftoff")


def tree_pss(proc: psutil.Process) -> tuple[int, int]:
    """(sum of the proportional set sizes (PSS) of the process and its descendants, RSS of
    the process) in bytes. PSS divides each shared page among the processes that map it, so
    the sum is the memory the tree uses: the forked picture processes share the command's
    pages (copy-on-write) and the workers share the libraries, which a sum of resident
    sets would count once per process."""
    try:
        procs = [proc] + proc.children(recursive=True)
    except psutil.NoSuchProcess:
        return 0, 0
    total = 0
    for p in procs:
        try:
            total += p.memory_full_info().pss
        except (psutil.NoSuchProcess, psutil.AccessDenied):
            pass
    try:
        own = proc.memory_info().rss
    except psutil.NoSuchProcess:
        own = 0
    return total, own


def measure(args: list[str], tag: str) -> dict:
    load0 = os.getloadavg()
    t0 = time.perf_counter()
    proc = subprocess.Popen([str(LIFTOFF), "run", *args], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            text=True, env={**os.environ, "PYVISTA_OFF_SCREEN": "true"})
    ps = psutil.Process(proc.pid)
    peak = {"total": 0, "main": 0, "samples": [], "cpu": {}}

    def sample():
        while proc.poll() is None:
            tot, own = tree_pss(ps)
            peak["total"], peak["main"] = max(peak["total"], tot), max(peak["main"], own)
            peak["samples"].append((time.perf_counter() - t0, tot))
            try:
                kids = ps.children(recursive=True)
            except psutil.NoSuchProcess:
                kids = []
            for p in [ps] + kids:          # CPU seconds, last seen per process (workers exit before the end)
                try:
                    c = p.cpu_times()
                    peak["cpu"][p.pid] = c.user + c.system
                except psutil.NoSuchProcess:
                    pass
            time.sleep(0.2)

    th = threading.Thread(target=sample, daemon=True)
    th.start()
    out, _ = proc.communicate()
    wall = time.perf_counter() - t0
    th.join()
    if proc.returncode != 0:
        sys.exit(f"bench_campaign: {tag} failed ({proc.returncode}):\n{out[-3000:]}")
    stage = next((ln.strip() for ln in out.splitlines() if "generated cases (" in ln and " run, " in ln), "")
    steps = next((ln.split("steps of")[0].split(":")[-1].strip() for ln in out.splitlines()
                  if "case 'nominal':" in ln and "steps of" in ln), "")
    return {"tag": tag, "wall": wall, "generated_s": _generated_seconds(stage), "steps": int(steps) if steps else None,
            "peak_total": peak["total"] / 2 ** 30, "peak_main": peak["main"] / 2 ** 30,
            "load": (load0, os.getloadavg()), "stage": stage, "samples": peak["samples"],
            "cpu": sum(peak["cpu"].values())}


def _generated_seconds(stage: str) -> float | None:
    """The run's own wall time of its generated cases, from its stage line
    ("generated cases (N run, 0 reused)   51.19 s"); None if it printed none."""
    try:
        return float(stage.split()[-2])
    except (IndexError, ValueError):
        return None


def report(r: dict) -> None:
    (a0, _, _), (a1, _, _) = r["load"]
    print(f"  {r['tag']:<44} wall {r['wall']:7.1f} s   peak memory (PSS) {r['peak_total']:.2f} GB (main process RSS "
          f"{r['peak_main']:.2f} GB)   CPU {r['cpu']:.0f} s (x{r['cpu'] / r['wall']:.2f} of wall)   "
          f"load average {a0:.1f} -> {a1:.1f}   [{r['stage']}]", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cases", type=int, default=1000)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--dask", action="store_true", help="also on a local Dask cluster")
    ap.add_argument("--scaling", type=int, default=0, metavar="M", help="M cases on 1 and on --workers workers")
    ap.add_argument("--flat", type=int, default=0, metavar="M", help="M cases, to compare peak memory")
    ap.add_argument("--cache", type=Path, default=ROOT / "out" / ".liftoff-cache")
    ap.add_argument("--scenario", type=Path, default=None, help="another scenario than the embedded default")
    ap.add_argument("--scaling-workers", default="", metavar="1,2,4",
                    help="worker counts for --scaling (default: 1 and --workers)")
    ap.add_argument("--no-snapshots", action="store_true", help="pass --no-snapshots (no pyvista)")
    ap.add_argument("--march-together", type=int, default=1, metavar="K",
                    help="the --cases run with K cases marched together a task (liftoff run --march-together)")
    ap.add_argument("--json", type=Path, help="write the measurements (docs/figures/bench_campaign.json)")
    ap.add_argument("--append", action="store_true", help="add the runs to those --json already holds")
    args = ap.parse_args()
    if args.json is not None and not args.json.parent.is_dir():
        sys.exit(f"bench_campaign: --json {str(args.json)!r}: no folder {str(args.json.parent)!r}")
    before = {"commands": [], "runs": []}
    if args.append:
        if args.json is None or not args.json.is_file():
            sys.exit("bench_campaign: --append needs an existing --json file")
        old = json.loads(args.json.read_text())
        before = {"commands": old["commands"], "runs": old["runs"]}
    rows: list[dict] = []
    print(f"bench_campaign: {platform.processor() or platform.machine()}, {os.cpu_count()} CPUs, "
          f"{psutil.virtual_memory().total / 2 ** 30:.0f} GB, Python {platform.python_version()}; cache {args.cache}")
    with tempfile.TemporaryDirectory(prefix="liftoff-bench-campaign-") as tmp:
        tmp = Path(tmp)
        common = [*([str(args.scenario)] if args.scenario else []), "--cache", str(args.cache), "--no-progress",
                  *(["--no-snapshots"] if args.no_snapshots else [])]
        report(measure(["--out", str(tmp / "warm"), *common], "warm-up (named cases only)"))

        def one(n, workers, extra=(), tag="", kind="pool", together=1):
            out = tmp / f"o_{tag}"
            extra = (*extra, "--march-together", str(together)) if together > 1 else extra
            r = measure(["--out", str(out), "--campaign", str(tmp / f"c_{tag}"), "--cases", str(n),
                         "--workers", str(workers), *extra, *common], tag)
            rows.append({"cases": n, "workers": workers, "executor": kind, "march_together": together,
                         **{k: v for k, v in r.items() if k != "samples"}})
            return r

        k = args.march_together
        runs = [one(args.cases, args.workers, tag=f"{args.cases} cases, process pool of {args.workers}"
                    + (f", {k} marched together" if k > 1 else ""), together=k)]
        report(runs[-1])
        if args.dask:
            runs.append(one(args.cases, args.workers, ("--dask", "local"),
                            tag=f"{args.cases} cases, Dask local cluster of {args.workers}", kind="dask"))
            report(runs[-1])
            print(f"  Dask / process pool: {runs[-1]['wall'] / runs[0]['wall']:.2f}")
        if args.flat:
            r = one(args.flat, args.workers, tag=f"{args.flat} cases, process pool of {args.workers}")
            report(r)
            print(f"  peak memory {args.flat} -> {args.cases} cases: {r['peak_total']:.2f} -> "
                  f"{runs[0]['peak_total']:.2f} GB")
        if args.scaling:
            counts = [int(w) for w in args.scaling_workers.split(",")] if args.scaling_workers else [1, args.workers]
            rs = []
            for w in counts:
                rs.append(one(args.scaling, w, tag=f"{args.scaling} cases, {w} worker{'s' if w > 1 else ''}"))
                report(rs[-1])
            gen = [float("nan") if r["generated_s"] is None else r["generated_s"] for r in rs]
            for w, r, g in zip(counts[1:], rs[1:], gen[1:]):
                print(f"  scaling 1 -> {w} workers: {rs[0]['wall'] / r['wall']:.2f}x on the whole command, "
                      f"{gen[0] / g:.2f}x on the generated cases")
    if args.json is not None:
        from liftoff.core.records import write_text

        command = "benchmarks/bench_campaign.py " + " ".join(sys.argv[1:])
        write_text(args.json, json.dumps({
            "date": time.strftime("%Y-%m-%d"), "cpus": os.cpu_count(),
            "memory_gb": psutil.virtual_memory().total / 2 ** 30,
            "commands": before["commands"] + [command],
            "snapshots": not args.no_snapshots, "runs": before["runs"] + rows}, indent=1) + "\n")
        print(f"bench_campaign: wrote {args.json}")


if __name__ == "__main__":
    main()
