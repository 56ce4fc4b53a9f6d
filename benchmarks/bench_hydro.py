"""Craig-Bampton reduction of the core stage with hydroelastic propellants against the same
component dry (no propellant mass) and with smeared propellants, same mesh: wall time and
peak memory (issue 10).

The three core-stage components (meshes.vehicle.core_stage_params(liquid=...), P1, mesh
``--mesh-size``) are built once and saved under ``--work``: ``smeared`` (wetted-wall mass),
``hydroelastic`` (liquid volumes, fem.liquid; the component carries the liquid's sparse
H and G) and ``dry`` (the hydroelastic component without its liquid: the same K and M,
the same mesh). Each reduction then runs in a fresh process: load the component, reset
the peak resident set size (VmHWM), reduction.craig_bampton(component, boundary,
n_modes, solver=fem.petsc_solver()), with the boundary of the workflow (the core stage's
8 spider reference points, 48 DOFs). Times are the minimum over ``--repeat`` runs.
Writes ``WORK/bench_hydro.json`` and prints a Markdown table.

    .venv/bin/python benchmarks/bench_hydro.py                  # mesh 0.9 m (the default run's)
    .venv/bin/python benchmarks/bench_hydro.py --mesh-size 0.6 --modes 60
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve()
VARIANTS = ("dry", "smeared", "hydroelastic")


def _rss(field: str) -> float:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith(field + ":"):
            return int(line.split()[1]) * 1024 / 1e9
    raise RuntimeError(f"no {field} in /proc/self/status")


def _child_cb(path: str, n_modes: int) -> None:
    import numpy as np
    from liftoff.fem import petsc_solver
    from liftoff.reduction import craig_bampton, load_component

    comp = load_component(path)
    Path("/proc/self/clear_refs").write_text("5")         # peak from here: the reduction's
    base = _rss("VmRSS")
    t0 = time.perf_counter()
    cb = craig_bampton(comp, comp.dof_labels, n_modes=n_modes, solver=petsc_solver())
    wall = time.perf_counter() - t0
    out = {"n_dof": comp.n_dof, "n_pressure": 0 if comp.liquid is None else comp.liquid.H.shape[0],
           "wall_s": wall, "peak_rss_gb": _rss("VmHWM"), "loaded_rss_gb": base,
           "freq_hz": cb.fixed_freq_hz.tolist(), **{k: v for k, v in cb.timings.items()}}
    rec = {it.name: it for it in cb.recovery}
    if "ullage_volume" in rec:
        dv = rec["ullage_volume"].disp[:, :cb.n_modes]
        f = rec["liquid_axial_inertia"].acc[:, :cb.n_modes]
        out["bulge"] = {}
        for k, name in enumerate(rec["ullage_volume"].labels):
            j = int(np.flatnonzero(np.abs(dv[k]) >= 0.25 * np.abs(dv[k]).max())[0])
            out["bulge"][name] = {"mode": j, "hz": float(cb.fixed_freq_hz[j]), "dV_m3": float(dv[k, j]),
                                  "m_eff_kg": float(f[k, j] ** 2)}
    print("RESULT " + json.dumps(out), flush=True)


def _child_build(h: float, work: Path) -> None:
    os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")
    import pyvista  # noqa: F401  (before dolfinx)
    from liftoff.fem import build_model
    from liftoff.meshes.tank import build_tank
    from liftoff.meshes.vehicle import core_stage_params
    from liftoff.reduction import Component
    from liftoff.reduction.liquid import LiquidMass

    for liquid in ("smeared", "hydroelastic"):
        p = core_stage_params(mesh_size=h, liquid=liquid)
        m = build_model(build_tank(p, work / f"mesh_{liquid}"))
        lf = m.liquid_fields()
        comp = Component(name="core", **m.component_fields(), liquid=None if lf is None else LiquidMass(**lf))
        comp.save(work / f"core_{liquid}.npz")
        if liquid == "hydroelastic":
            comp.liquid = None
            comp.save(work / "core_dry.npz")


def _run(args: list[str]) -> dict:
    out = subprocess.run([sys.executable, str(HERE), *args], check=True, capture_output=True, text=True,
                         env=dict(os.environ, PYVISTA_OFF_SCREEN="true", OMP_NUM_THREADS="1"))
    line = next(ln for ln in out.stdout.splitlines() if ln.startswith("RESULT "))
    return json.loads(line[7:])


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mesh-size", type=float, default=0.9)
    ap.add_argument("--modes", type=int, default=40)
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--work", type=Path, default=Path("out/bench_hydro"))
    ap.add_argument("--child", choices=("cb", "build"))
    ap.add_argument("--component")
    a = ap.parse_args(argv)
    if a.child == "cb":
        return _child_cb(a.component, a.modes)
    if a.child == "build":
        return _child_build(a.mesh_size, a.work)
    a.work.mkdir(parents=True, exist_ok=True)
    if not all((a.work / f"core_{v}.npz").is_file() for v in VARIANTS):
        t0 = time.perf_counter()
        subprocess.run([sys.executable, str(HERE), "--child", "build", "--mesh-size", str(a.mesh_size),
                        "--work", str(a.work)], check=True, env=dict(os.environ, PYVISTA_OFF_SCREEN="true"))
        print(f"components built in {time.perf_counter() - t0:.1f} s")
    res = {}
    for v in VARIANTS:
        runs = [_run(["--child", "cb", "--component", str(a.work / f"core_{v}.npz"), "--modes", str(a.modes)])
                for _ in range(a.repeat)]
        res[v] = min(runs, key=lambda r: r["wall_s"])
    (a.work / "bench_hydro.json").write_text(json.dumps({"mesh_size": a.mesh_size, "modes": a.modes, **res}, indent=1))
    dry = res["dry"]["wall_s"]
    print(f"\nCore stage, mesh {a.mesh_size} m, {res['dry']['n_dof']} DOFs, {a.modes} fixed-interface modes, "
          f"PETSc/SLEPc CB (min of {a.repeat}):\n")
    print("| variant | pressure DOFs | CB wall (s) | / dry | peak RSS (GB) | first mode (Hz) |")
    print("|---|---|---|---|---|---|")
    for v in VARIANTS:
        r = res[v]
        print(f"| {v} | {r['n_pressure']} | {r['wall_s']:.2f} | {r['wall_s'] / dry:.2f} | {r['peak_rss_gb']:.2f} | "
              f"{r['freq_hz'][0]:.2f} |")
    for name, b in res["hydroelastic"].get("bulge", {}).items():
        print(f"\n{name}: first bulge mode {b['hz']:.2f} Hz (fixed-interface mode {b['mode'] + 1}), "
              f"ullage dV {b['dV_m3']:.3g} m^3 per unit modal coordinate, axial effective liquid mass "
              f"{b['m_eff_kg'] / 1e3:.0f} t")


if __name__ == "__main__":
    main()
