"""Benchmark: eigensolve of the default vehicle components and the launch pad.

For each component (meshes.vehicle.default_stack + meshes.pad.default_pad, default mesh
sizes, P1): DOFs, number of modes, wall time of fem.eigenmodes (SLEPc Krylov-Schur,
shift-invert, MUMPS Cholesky) against scipy.sparse.linalg.eigsh (ARPACK shift-invert,
SuperLU) on the same matrices in the same process, the largest relative frequency
difference between the two, and the SLEPc time on 1 and 2 MPI ranks (mpirun children).

Usage: .venv/bin/python benchmarks/bench_fem.py [--modes 30] [--out out/bench_fem]
Writes <out>/bench_fem.json (atomically) and prints a Markdown table. Times in seconds.
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import liftoff  # noqa: F401 - before numpy: it picks the OpenBLAS kernels (liftoff/core/openblas.py)
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def _child(json_path: str, n_modes: int) -> None:
    """mpirun child: build the model of one geometry and time its eigensolve."""
    from mpi4py import MPI

    from liftoff.fem import build_model, eigenmodes
    from liftoff.meshes.spec import Geometry

    comm = MPI.COMM_WORLD
    t0 = time.perf_counter()
    model = build_model(Geometry.load(json_path))
    comm.Barrier()
    t1 = time.perf_counter()
    modes = eigenmodes(model, n_modes=n_modes)
    comm.Barrier()
    t2 = time.perf_counter()
    if comm.rank == 0:
        print("RESULT " + json.dumps({"ranks": comm.size, "build_s": t1 - t0, "eig_s": t2 - t1,
                                      "freq": modes.freq_hz.tolist()}), flush=True)


def _mpirun(n: int, json_path: Path, n_modes: int) -> dict | None:
    mpirun = shutil.which("mpirun")
    if mpirun is None:
        return None
    env = dict(os.environ, PYTHONPATH=str(ROOT), OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1")
    res = subprocess.run([mpirun, "-n", str(n), sys.executable, __file__, "--child", str(json_path),
                          "--modes", str(n_modes)], capture_output=True, text=True, env=env, cwd=ROOT)
    lines = [ln for ln in res.stdout.splitlines() if ln.startswith("RESULT ")]
    if res.returncode or not lines:
        raise RuntimeError(f"mpirun -n {n} failed: {res.stderr[-1500:]}")
    return json.loads(lines[0][7:])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--modes", type=int, default=30, help="modes per component (rigid included)")
    ap.add_argument("--out", default="out/bench_fem", help="output folder (meshes + JSON)")
    ap.add_argument("--meshes", default=None,
                    help="folder of already built geometries (core, srb_left, srb_right, orbiter, pad .json)")
    ap.add_argument("--only", nargs="*", default=None, help="component names to run (default: all)")
    ap.add_argument("--repeat", type=int, default=1,
                    help="MPI runs per rank count; the minimum time is kept (a shared machine is noisy)")
    ap.add_argument("--child", default=None, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        return _child(args.child, args.modes)

    import scipy.sparse.linalg as sla
    from tqdm import tqdm

    from liftoff.fem import build_model, eigenmodes
    from liftoff.meshes.pad import default_pad
    from liftoff.meshes.vehicle import default_stack

    from liftoff.meshes.spec import Geometry

    out = Path(args.out)
    load0 = os.getloadavg()
    print(f"load average at start {load0} on {os.cpu_count()} cores (timings are noisy under load)")
    t = time.perf_counter()
    if args.meshes:
        mdir = Path(args.meshes)
        geos = {n: Geometry.load(mdir / f"{n}.json") for n in ("core", "srb_left", "srb_right", "orbiter", "pad")}
    else:
        mdir = out / "meshes"
        geos = dict(default_stack(out_dir=mdir))
        geos["pad"] = default_pad(out_dir=mdir)
        print(f"meshes built in {time.perf_counter() - t:.1f} s", flush=True)
    if args.only:
        geos = {n: geos[n] for n in args.only}
    rows = []
    for name, g in tqdm(geos.items(), desc="components", file=sys.stdout):
        t0 = time.perf_counter()
        model = build_model(g)
        t1 = time.perf_counter()
        modes = eigenmodes(model, n_modes=args.modes)
        t2 = time.perf_counter()
        K, M = model.matrices()
        sigma = -(2 * np.pi * 1.0) ** 2              # the same shift fem uses
        w2 = np.sort(sla.eigsh(K.tocsc(), k=args.modes, M=M.tocsc(), sigma=sigma, which="LM",
                               return_eigenvectors=False))
        t3 = time.perf_counter()
        f_scipy = np.sqrt(np.clip(w2, 0, None)) / (2 * np.pi)
        flex = modes.freq_hz > 0
        diff = float(np.max(np.abs(modes.freq_hz[flex] / f_scipy[flex] - 1)))
        mpi = {}
        for _ in range(max(1, args.repeat)):
            for n in (1, 2):
                r = _mpirun(n, mdir / f"{g.name}.json", args.modes)
                if r and (n not in mpi or r["eig_s"] < mpi[n]["eig_s"]):
                    mpi[n] = r
        row = {"component": name, "dofs": model.n_dof, "modes": args.modes, "n_rigid": modes.n_rigid,
               "f_first_flexible_hz": float(modes.freq_hz[modes.n_rigid]), "f_last_hz": float(modes.freq_hz[-1]),
               "build_s": t1 - t0, "slepc_s": t2 - t1, "scipy_eigsh_s": t3 - t2,
               "eigsh_over_slepc": (t3 - t2) / (t2 - t1), "max_rel_freq_diff": diff}
        if mpi.get(1) and mpi.get(2):
            row.update({"mpi1_eig_s": mpi[1]["eig_s"], "mpi2_eig_s": mpi[2]["eig_s"],
                        "mpi1_build_s": mpi[1]["build_s"], "mpi2_build_s": mpi[2]["build_s"],
                        "speedup_2_ranks": mpi[1]["eig_s"] / mpi[2]["eig_s"],
                        "mpi_max_rel_freq_diff": float(np.max(np.abs(
                            np.array(mpi[2]["freq"])[flex] / np.array(mpi[1]["freq"])[flex] - 1)))})
        rows.append(row)
    out.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=out, suffix=".tmp")
    with os.fdopen(fd, "w") as fh:
        json.dump({"units": "s, Hz", "cpu_count": os.cpu_count(), "loadavg_start": load0,
                   "loadavg_end": os.getloadavg(), "rows": rows}, fh, indent=1)
    os.replace(tmp, out / "bench_fem.json")
    print(f"load average at end {os.getloadavg()}")
    print("\n| component | DOFs | modes | 1st flex (Hz) | build (s) | SLEPc (s) | scipy eigsh (s) | "
          "eigsh/SLEPc | max rel diff | 1 rank (s) | 2 ranks (s) | speed-up |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['component']} | {r['dofs']} | {r['modes']} | {r['f_first_flexible_hz']:.3f} | "
              f"{r['build_s']:.1f} | {r['slepc_s']:.2f} | {r['scipy_eigsh_s']:.2f} | {r['eigsh_over_slepc']:.2f} | "
              f"{r['max_rel_freq_diff']:.1e} | {r.get('mpi1_eig_s', float('nan')):.2f} | "
              f"{r.get('mpi2_eig_s', float('nan')):.2f} | {r.get('speedup_2_ranks', float('nan')):.2f} |")


if __name__ == "__main__":
    main()
