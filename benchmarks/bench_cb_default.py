"""The fixed-interface eigensolve of each default component: block Lanczos (the CB solver,
fem.block_lanczos through fem.petsc_cb.fixed_interface_pairs) against SLEPc's one-vector
Krylov-Schur (the CB solver before 2026-11-26), same process, same factor of K_ii.

    .venv/bin/python benchmarks/bench_cb_default.py [--repeat 2] [--cache DIR] [--components core srb_left]
        [--json FILE]

For each component of the embedded default scenario (FE stage from the stage cache, built
if missing) the interior K_ii, M_ii (and the core's wet mass M_ii + M_a,ii) are formed
once, K_ii is factored once (MUMPS), and each solver computes the modes below the
component's f_max (their count from the inertia, as the CB stage does), and, where the CB
stage solves the band shift-inverted at its middle (dry components with at least
fem.petsc_cb.SHIFT_MIN_MODES modes, since 2026-12-07), that solve too, its own factor of
K_ii - sigma M_ii included in its time (fem.petsc_cb.shifted_pairs); wall time is the
minimum over ``--repeat`` runs (the median is printed too). The two solvers' eigenvalues
are compared (largest relative difference). Prints a Markdown table; ``--json``
(docs/figures/bench_cb_default.json) writes the figures, which benchmarks/default_figures.py
renders into README.md (machine-dependent: the test checks that the README shows the file).
"""
from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

import liftoff  # noqa: F401 - before numpy: it picks the OpenBLAS kernels (liftoff/core/openblas.py)
import numpy as np

ROOT = Path(__file__).resolve().parent.parent


def bench_component(model, name: str, cache, repeat: int) -> dict:
    import tempfile

    from mpi4py import MPI

    from liftoff.fem import petsc_cb as pc
    from liftoff.fem.liquid import wet_mass
    from liftoff.workflows import pipeline as pl

    with tempfile.TemporaryDirectory() as work:
        comp, _, _ = pl.component_stage(model, name, cache, Path(work))
    b = comp.dofs_of(pl.points_labels(pl.boundary_points(comp)))
    interior = np.setdiff1d(np.arange(comp.n_dof), b)
    comm = MPI.COMM_WORLD
    Kii, Mii, _ = pc.interior_matrices(comm, comp.K, comp.M, interior, b)
    B = wet = None
    if comp.liquid is not None:
        B, wet = wet_mass(Mii, comp.liquid.H, comp.liquid.G[:, interior])
    f_max = model.components[name].f_max
    lam_max = (2 * np.pi * f_max) ** 2
    if wet is None:
        want = pc.count_below(Kii, Mii, lam_max, name)
    else:
        from liftoff.fem.liquid import count_below_wet

        want = count_below_wet(comm, comp.K[interior][:, interior], comp.M[interior][:, interior],
                               comp.liquid.G[:, interior], comp.liquid.H, lam_max, name)
    times = {"block_lanczos": [], "slepc": [], "shifted": []}
    lam = {}
    shifted = pc.shifts_band(want, interior.size, wet is not None)
    shifted_dim = None
    try:
        for _ in range(repeat if shifted else 0):   # the CB stage's solve of this band: its own factor, timed
            t0 = time.perf_counter()
            got = pc.shifted_pairs(Kii, Mii, want, lam_max, 1e-10, name)
            if got is None:                         # sigma singular: the CB stage solves unshifted too
                shifted = False
                break
            lam["shifted"], _, sinfo = got
            times["shifted"].append(time.perf_counter() - t0)
            shifted_dim = sinfo["eigen_dimension"]
        with pc._factor_kii(Kii, name) as ksp:
            pc._set_up(ksp, name)
            for _ in range(repeat):
                t0 = time.perf_counter()
                lam["block_lanczos"], _, info = pc.fixed_interface_pairs(ksp, Kii, Mii, wet, want, 1e-10, name)
                times["block_lanczos"].append(time.perf_counter() - t0)
        for _ in range(repeat):
            t0 = time.perf_counter()
            lam["slepc"], _ = pc.eigensolve_alone(Kii, Mii if B is None else B, want)
            times["slepc"].append(time.perf_counter() - t0)
    finally:
        if B is not None:
            B.destroy()
        Kii.destroy()
        Mii.destroy()
    diff = float(np.max(np.abs(lam["block_lanczos"] / lam["slepc"] - 1)))
    return {"component": name, "interior_dofs": int(interior.size), "modes": int(want), "f_max_hz": f_max,
            "wet": wet is not None, "block_dimension": info.get("eigen_dimension"),
            "block_lanczos_s": times["block_lanczos"], "slepc_s": times["slepc"], "max_rel_eig_diff": diff,
            "shifted_s": times["shifted"], "shifted_dimension": shifted_dim,
            "shifted_max_rel_eig_diff": (float(np.max(np.abs(lam["shifted"] / lam["slepc"] - 1))) if shifted
                                         else None)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--cache", type=Path, default=ROOT / "out" / ".liftoff-cache")
    ap.add_argument("--components", nargs="*")
    ap.add_argument("--json", type=Path)
    a = ap.parse_args(argv)
    from liftoff.config import default_text, parse_scenario, parse_toml
    from liftoff.workflows.cache import StageCache

    sc = parse_scenario(parse_toml(default_text(), "default_scenario.toml"), "default_scenario.toml")
    model = sc.cases[0].model
    names = a.components or [n for n in list(model.vehicle) + ["pad"]   # (a mirror takes its source's modes: no solve)
                              if model.components[n].nastran is None and model.components[n].mirror is None]
    cache = StageCache(a.cache)
    rows = []
    for name in names:
        r = bench_component(model, name, cache, a.repeat)
        rows.append(r)
        print(f"{name}: block Lanczos {min(r['block_lanczos_s']):.1f} s, SLEPc {min(r['slepc_s']):.1f} s"
              + (f", shifted {min(r['shifted_s']):.1f} s" if r["shifted_s"] else ""), file=sys.stderr, flush=True)
    print(f"| component | interior DOFs | modes below f_max | block Lanczos (s) min / median | basis | "
          f"SLEPc Krylov-Schur (s) min / median | SLEPc / block | largest eigenvalue difference |")
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        bl, sl = r["block_lanczos_s"], r["slepc_s"]
        print(f"| {r['component']}{' (wet)' if r['wet'] else ''} | {r['interior_dofs']:,} | {r['modes']} | "
              f"{min(bl):.1f} / {statistics.median(bl):.1f} | {r['block_dimension']} | "
              f"{min(sl):.1f} / {statistics.median(sl):.1f} | {min(sl) / min(bl):.2f} | {r['max_rel_eig_diff']:.1e} |")
    if a.json:
        import datetime
        import os

        a.json.write_text(json.dumps({"date": datetime.date.today().isoformat(), "cpus": os.cpu_count(),
                                      "load_average_end": os.getloadavg()[0], "repeat": a.repeat, "rows": rows},
                                     indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
