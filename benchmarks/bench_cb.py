"""Craig-Bampton reduction of the core stage on PETSc/MUMPS (fem.petsc_solver: block Lanczos,
fem.block_lanczos) against SLEPc's fixed-interface eigensolve alone (one-vector
Krylov-Schur): wall time and peak memory, 1 or more MPI ranks.

For each core-stage mesh size (meshes.vehicle.build_core_stage, P1; boundary = the 48 DOFs
of its 8 spider reference points) the component is built once (fem.build_model, saved
under ``--work``), then every measurement runs in a fresh process (``mpirun -n R`` for R
ranks), which loads the component and does one of:

* ``eig``: the fixed-interface eigensolve alone, by SLEPc, as any modal reduction could do it: K_ii,
  M_ii as PETSc matrices, MUMPS factor + SLEPc Krylov-Schur shift-invert, ``--modes``
  modes (fem.petsc_cb.eigensolve_alone; the time excludes building K_ii, M_ii);
* ``cb``: reduction.craig_bampton(component, boundary, n_modes, solver=petsc_solver()),
  everything included (interior extraction, PETSc matrices, factor, constraint modes,
  eigensolve, gathers, CB matrices);
* ``scipy``: the same craig_bampton with the scipy solver (SuperLU + ARPACK; ``--scipy``).

Peak memory is the peak resident set size (VmHWM, reset once the component is loaded, so
the component counts but not the transient copies made while reading it) of each rank,
summed over ranks. Wall times (and the CPU times of the ranks, summed, which other jobs on a shared
machine disturb less) are the minimum over ``--repeat`` runs. Writes ``WORK/bench_cb.json``
and prints a Markdown table.

    .venv/bin/python benchmarks/bench_cb.py                    # 26 k, 113 k, 250 k DOFs, 1 and 2 ranks
    .venv/bin/python benchmarks/bench_cb.py --sizes 0.1 --ranks 1 --repeat 1   # the ~1 M-DOF mesh
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve()
SIZES = (0.9, 0.3, 0.2)            # core-stage mesh sizes (m): ~26 k, 113 k, 250 k DOFs


# ------------------------------------------------------------------ in the child process
def _child(mode: str, path: str, n_modes: int) -> None:
    import numpy as np
    from mpi4py import MPI

    from liftoff.reduction import craig_bampton, load_component

    comm = MPI.COMM_WORLD
    comp = load_component(path)
    bl = list(comp.dof_labels)
    out = {"n_dof": comp.n_dof, "n_boundary": len(bl), "loaded_rss_gb": _gather_sum(comm, _rss("VmRSS"))}
    _reset_peak()          # the peak from here on: the component stays resident, its reading is not counted
    comm.barrier()
    t0, c0 = time.perf_counter(), time.process_time()
    if mode == "eig":
        from liftoff.fem.petsc_cb import eigensolve_alone, interior_matrices

        b = comp.dofs_of(bl)
        i = np.setdiff1d(np.arange(comp.n_dof), b)
        Kii, Mii, _ = interior_matrices(comm, comp.K, comp.M, i, b)
        comm.barrier()
        t0, c0 = time.perf_counter(), time.process_time()
        lam, timings = eigensolve_alone(Kii, Mii, n_modes)
        out.update(timings, freq_hz=(np.sqrt(lam) / (2 * np.pi)).tolist())
    elif mode in ("cb", "scipy"):
        from liftoff.fem import petsc_solver

        cb = craig_bampton(comp, bl, n_modes=n_modes, solver=petsc_solver() if mode == "cb" else None)
        out.update(cb.timings, freq_hz=cb.fixed_freq_hz.tolist())
    cpu = time.process_time() - c0        # CPU time of this rank (robust to other jobs on the machine)
    comm.barrier()
    out["wall_s"] = time.perf_counter() - t0
    out["cpu_s"] = _gather_sum(comm, cpu)
    peak = comm.gather(_rss("VmHWM"), root=0)
    maxrss = _gather_sum(comm, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024 / 1e9)
    if comm.rank == 0:
        out.update(ranks=comm.size, peak_rss_gb=sum(peak), peak_rss_per_rank_gb=peak, process_maxrss_gb=maxrss)
        print("RESULT " + json.dumps(out), flush=True)


def _rss(field: str) -> float:
    """VmRSS (now) or VmHWM (peak since the last reset) of this process, GB."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith(field + ":"):
            return int(line.split()[1]) * 1024 / 1e9
    raise RuntimeError(f"no {field} in /proc/self/status")


def _reset_peak() -> None:
    """Reset the peak resident set size (VmHWM) to the current one (Linux >= 4.0)."""
    Path("/proc/self/clear_refs").write_text("5")


def _gather_sum(comm, x: float) -> float:
    return float(sum(comm.allgather(x)))


def _build(h: float, work: Path) -> Path:
    """The core stage at mesh size h as a saved Component (built once, in a child process:
    the driver stays small while the measurements run)."""
    path = work / f"core_h{h:g}.npz"
    if not path.is_file():
        subprocess.run([sys.executable, str(HERE), "--child", "build", "--component", str(path),
                        "--mesh-size", str(h)], check=True, env=dict(os.environ, PYVISTA_OFF_SCREEN="true"))
    return path


def _build_child(h: float, path: Path) -> None:
    work = path.parent
    os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")
    import pyvista  # noqa: F401  (before dolfinx)

    from liftoff import fem
    from liftoff.meshes.vehicle import build_core_stage
    from liftoff.reduction import Component

    t0 = time.perf_counter()
    g = build_core_stage(work / f"mesh_h{h:g}", mesh_size=h)
    t1 = time.perf_counter()
    m = fem.build_model(g, degree=1)
    comp = Component(name="core", **m.component_fields())
    comp.save(path)
    print(f"core stage h = {h:g} m: {comp.n_dof} DOFs; gmsh {t1 - t0:.0f} s, FE model {time.perf_counter() - t1:.0f} s",
          flush=True)


# ------------------------------------------------------------------ the driver
def measure(mode: str, path: Path, n_modes: int, ranks: int, timeout: float) -> dict:
    env = dict(os.environ, PYVISTA_OFF_SCREEN="true", OMPI_MCA_rmaps_base_oversubscribe="1")
    if os.geteuid() == 0:
        env.update(OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    cmd = [sys.executable, str(HERE), "--child", mode, "--component", str(path), "--modes", str(n_modes)]
    if ranks > 1:
        cmd = [shutil.which("mpirun"), "--quiet", "-n", str(ranks), *cmd]
    res = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=timeout)
    lines = [ln for ln in res.stdout.splitlines() if ln.startswith("RESULT ")]
    if res.returncode or not lines:
        return {"error": (res.stderr.strip().splitlines() or ["?"])[-1], "returncode": res.returncode}
    return json.loads(lines[0][7:])


def best(runs: list[dict]) -> dict:
    """Minimum of every timing over the runs (peak memory: the largest)."""
    ok = [r for r in runs if "error" not in r]
    if not ok:
        return runs[-1]
    out = dict(ok[0])
    for k, v in ok[0].items():
        if k.endswith("_s"):
            out[k] = min(r[k] for r in ok)
    out["peak_rss_gb"] = max(r["peak_rss_gb"] for r in ok)
    return out


def bench(sizes, ranks, modes, repeat, work: Path, scipy_too: bool, timeout: float,
          what=("eig", "cb")) -> list[dict]:
    rows = []
    for h in sizes:
        path = _build(h, work)
        for r in ranks:
            row = {"h": h, "ranks": r}
            for mode in tuple(what) + (("scipy",) if scipy_too and r == 1 else ()):
                row[mode] = best([measure(mode, path, modes, r, timeout) for _ in range(repeat)])
            rows.append(row)
            print(_row_text(row), flush=True)
    return rows


def _row_text(row: dict) -> str:
    e, c = row.get("eig", {"error": "not measured"}), row.get("cb", {"error": "not measured"})
    if "error" in c:
        return f"| h = {row['h']:g} m | {row['ranks']} | failed: {c.get('error')} |"
    if "error" in e:
        return (f"| {c['n_dof']:,} | {row['ranks']} | {c['wall_s']:.1f} | {c.get('factor_s', 0):.1f} | "
                f"{c.get('constraint_solve_s', 0):.2f} | {c.get('eigensolve_s', 0):.1f} | - | - | "
                f"{c['peak_rss_gb']:.2f} | - | - | {c['loaded_rss_gb']:.2f} |")
    if "error" in e or "error" in c:
        return f"| h = {row['h']:g} m | {row['ranks']} | failed: {e.get('error') or c.get('error')} |"
    extra = ""
    if "scipy" in row and "error" not in row["scipy"]:
        s = row["scipy"]
        extra = f" scipy CB {s['wall_s']:.1f} s, {s['peak_rss_gb']:.2f} GB |"
    return (f"| {c['n_dof']:,} | {row['ranks']} | {c['wall_s']:.1f} | {c.get('factor_s', 0):.1f} | "
            f"{c.get('constraint_solve_s', 0):.2f} | {c.get('eigensolve_s', 0):.1f} | {e['wall_s']:.1f} | "
            f"{c['wall_s'] / e['wall_s']:.2f} | {c['peak_rss_gb']:.2f} | {e['peak_rss_gb']:.2f} | "
            f"{c['peak_rss_gb'] / e['peak_rss_gb']:.2f} | {c['loaded_rss_gb']:.2f} |{extra}")


HEADER = ("| DOFs | ranks | CB (s) | factor | constraint modes | eigensolve | eigensolve alone (s) | CB / alone | "
          "CB peak (GB) | alone peak (GB) | ratio | component resident (GB) |\n|" + "---|" * 12)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=float, nargs="+", default=SIZES, help="core-stage mesh sizes (m)")
    ap.add_argument("--ranks", type=int, nargs="+", default=(1, 2))
    ap.add_argument("--modes", type=int, default=40)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--scipy", action="store_true", help="also the scipy CB (1 rank)")
    ap.add_argument("--measure", nargs="+", choices=("eig", "cb"), default=("eig", "cb"),
                    help="what to measure (default both)")
    ap.add_argument("--work", type=Path, default=Path("out/bench_cb"))
    ap.add_argument("--timeout", type=float, default=3600.0, help="per measurement (s)")
    ap.add_argument("--child", choices=("eig", "cb", "scipy", "build"), help=argparse.SUPPRESS)
    ap.add_argument("--component", help=argparse.SUPPRESS)
    ap.add_argument("--mesh-size", type=float, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.child == "build":
        return _build_child(args.mesh_size, Path(args.component))
    if args.child:
        return _child(args.child, args.component, args.modes)
    args.work.mkdir(parents=True, exist_ok=True)
    load0 = os.getloadavg()[0]
    print(f"load average at start {load0:.1f}; {args.modes} fixed-interface modes; best of {args.repeat}\n{HEADER}",
          flush=True)
    rows = bench(args.sizes, args.ranks, args.modes, args.repeat, args.work, args.scipy, args.timeout, args.measure)
    result = {"load_average": [load0, os.getloadavg()[0]], "modes": args.modes, "repeat": args.repeat, "rows": rows}
    out = args.work / "bench_cb.json"
    old = json.loads(out.read_text()) if out.is_file() else {"runs": []}
    old.setdefault("runs", []).append(result)
    out.write_text(json.dumps(old, indent=1))
    print(f"load average at end {os.getloadavg()[0]:.1f}; written {out}")


if __name__ == "__main__":
    main()
