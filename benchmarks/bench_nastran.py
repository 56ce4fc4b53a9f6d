"""Import time and memory of a large Nastran Craig-Bampton component (reduction/nastran.py).

A synthetic EXTSEOUT set with ``--grids`` boundary grids (6 DOFs each, every third grid in
a rotated rectangular output frame) and ``--modes`` modal DOFs (default 500 + 7,000 =
10,000 a-set DOFs) is written with pyyeti's own writers (``op4.write``, binary and ASCII;
``bulk.wtextseout`` for the .asm/.pch): dense mass coupling C_M, dense K_bb and M_bb,
diagonal K_qq, M_qq = I. Each import then runs in a fresh Python process, which reports the
wall time of ``from_extseout`` and its peak resident memory (VmHWM) beside the
resident memory before the call (interpreter, numpy, pyyeti, pandas loaded). The dense K
and M of that size take 2 x n^2 x 8 bytes (1.6 GB at n = 10,000).

    .venv/bin/python benchmarks/bench_nastran.py [--grids 500] [--modes 7000] [--dir out/bench_nastran]
"""
from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import time
from pathlib import Path

import liftoff  # noqa: F401 - before numpy: it picks the OpenBLAS kernels (liftoff/core/openblas.py)
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))


def write_model(folder: Path, n_grids: int, n_modes: int) -> dict:
    """Binary and ASCII EXTSEOUT sets of a synthetic CB component (mm-t-s numbers)."""
    from pyyeti.nastran import bulk, n2p, op4

    rng = np.random.default_rng(1)
    nb = 6 * n_grids
    n = nb + n_modes
    A = rng.normal(size=(nb, nb)) / np.sqrt(nb)
    K = np.zeros((n, n))
    K[:nb, :nb] = 1e6 * (A @ A.T)                                   # dense SPD boundary stiffness
    K[nb:, nb:] = np.diag((2 * np.pi * np.linspace(1.0, 500.0, n_modes)) ** 2)
    M = np.zeros((n, n))
    M[:nb, :nb] = 1e-3 * (np.eye(nb) + 0.01 * (A + A.T))
    C = 1e-3 * rng.normal(size=(n_modes, nb))
    M[nb:, :nb], M[:nb, nb:] = C, C.T
    M[nb:, nb:] = np.eye(n_modes)
    xyz = np.c_[1000.0 * np.cos(np.arange(n_grids)), 1000.0 * np.sin(np.arange(n_grids)), np.arange(n_grids) * 10.0]
    rect = np.array([[10, 1, 0], [0.0, 0, 0], [1.0, 0, 0], [0, 1.0, 0]])
    cd = [rect if g % 3 == 0 else 0 for g in range(n_grids)]
    uset = n2p.addgrid(None, np.arange(1, n_grids + 1), "b", 0, xyz, cd)
    paths = {}
    t0 = time.perf_counter()
    name = str(folder / "big")
    bulk.wtextseout(name, se=100, bset=np.arange(nb), uset=uset, spoint1=1_000_001, namelist=["kaa", "maa"],
                    kaa=K, maa=M)
    paths["binary"] = Path(name + ".op4")
    timing = {"write_binary_s": time.perf_counter() - t0}
    for ext in (".asm", ".pch"):
        (folder / f"big_ascii{ext}").write_text(Path(name + ext).read_text())
    t0 = time.perf_counter()
    op4.write(str(folder / "big_ascii.op4"), {"kaa": K, "maa": M}, binary=False)
    timing["write_ascii_s"] = time.perf_counter() - t0
    paths["ascii"] = folder / "big_ascii.op4"
    return {"paths": {k: str(v) for k, v in paths.items()}, "n": n, "n_b": nb, "n_q": n_modes, **timing,
            "size_mb": {k: Path(v).stat().st_size / 1e6 for k, v in paths.items()}}


def high_water_mb() -> float:
    """Peak resident memory of this process image (VmHWM; ru_maxrss would carry the
    parent's peak across fork + exec)."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) / 1024
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def child(path: str) -> None:
    """Run in a fresh process: import once, print JSON (time, memory)."""
    import liftoff.reduction.nastran as nastran

    nastran._nastran()                                   # load pyyeti, pandas before measuring
    rss0 = high_water_mb()
    t0 = time.perf_counter()
    cpu0 = time.process_time()
    cb = nastran.from_extseout(path, name="big", units="mm-t-s")
    wall, cpu = time.perf_counter() - t0, time.process_time() - cpu0
    rss1 = high_water_mb()
    print(json.dumps({"wall_s": wall, "cpu_s": cpu, "rss_before_mb": rss0, "peak_rss_mb": rss1,
                      "n_modes": cb.n_modes, "n_boundary": cb.n_boundary}))


def gc_collect() -> None:
    import gc

    gc.collect()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--grids", type=int, default=500)
    ap.add_argument("--modes", type=int, default=7000)
    ap.add_argument("--dir", type=Path, default=Path("out/bench_nastran"))
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--reuse", action="store_true", help="reuse the files of an earlier run in --dir")
    ap.add_argument("--child", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        child(args.child)
        return
    args.dir.mkdir(parents=True, exist_ok=True)
    meta = args.dir / "model.json"
    if args.reuse and meta.is_file():
        info = json.loads(meta.read_text())
    else:
        info = write_model(args.dir, args.grids, args.modes)
        meta.write_text(json.dumps(info))
    gc_collect()
    print(f"model: {info['n']} a-set DOFs ({info['n_b']} boundary + {info['n_q']} modal); "
          f"OP4 binary {info['size_mb']['binary']:.0f} MB (written in {info['write_binary_s']:.1f} s), "
          f"ASCII {info['size_mb']['ascii']:.0f} MB ({info['write_ascii_s']:.1f} s)")
    print(f"dense K and M alone: {2 * info['n'] ** 2 * 8 / 1e6:.0f} MB")
    for kind, path in info["paths"].items():
        runs = []
        for _ in range(args.repeat):
            out = subprocess.run([sys.executable, __file__, "--child", path], capture_output=True, text=True, check=True)
            runs.append(json.loads(out.stdout.strip().splitlines()[-1]))
        best = min(runs, key=lambda r: r["wall_s"])
        print(f"{kind:6s}: import {best['wall_s']:.2f} s wall ({best['cpu_s']:.2f} s CPU, best of {args.repeat}), "
              f"peak RSS {best['peak_rss_mb']:.0f} MB (before the call {best['rss_before_mb']:.0f} MB); "
              f"{best['n_modes']} modes, {best['n_boundary']} boundary DOFs")
    print(f"load average: {' '.join(f'{x:.2f}' for x in __import__('os').getloadavg())}")


if __name__ == "__main__":
    main()
