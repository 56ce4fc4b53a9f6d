"""Pressure stiffening of the shell core stage (fem.prestress), against the same shell
unpressurised and the thickened-solid wall, all with hydroelastic propellants (issue 11).

Variants of meshes.vehicle.core_stage_params(liquid="hydroelastic"): ``solid`` (the default
run's wall), ``shell`` (6.8 mm Al 2219 bare skin, no pressure) and ``shell-p`` (the same with
the external tank's ullage pressures, LH2 32 psig, LOX 20 psig). For each: DOFs, the model
build time (assembly, plus the prestress solve and K_G + K_L for shell-p), the
Craig-Bampton time (fem.petsc_solver, the pipeline's boundary, ``--modes`` modes), the first
fixed-interface frequencies, the first free-free elastic frequency of the CB model and its
first beam-bending mode (beam content > 0.5, fem.modes.beam_content of the expanded shape)
with the number of other elastic modes below it, and what its first ten elastic modes are
(beam, or the wall's circumferential wave number and region, benchmarks/bench_shells.py).
Times: min and median over ``--repeat`` builds in this process (the machine is shared).

    .venv/bin/python benchmarks/bench_prestress.py [--mesh-size 0.9] [--repeat 2]

Writes out/bench_prestress/bench_prestress.json (atomically) and prints a Markdown table.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import liftoff  # noqa: F401 - before numpy: it picks the OpenBLAS kernels (liftoff/core/openblas.py)
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def run_variant(kind: str, h: float, out: Path, n_modes: int) -> dict:
    import scipy.linalg as la

    from liftoff.core.labels import points_labels
    from liftoff.fem import build_model, petsc_solver
    from liftoff.fem.modes import beam_content
    from liftoff.meshes import build_tank
    from liftoff.meshes.vehicle import core_stage_params
    from liftoff.reduction import Component, craig_bampton
    from liftoff.reduction.liquid import LiquidMass
    from liftoff.workflows.pipeline import boundary_points

    p = core_stage_params(mesh_size=h, walls="solid" if kind == "solid" else "shell", liquid="hydroelastic",
                          ullage_pressure={"lh2": 0.0, "lox": 0.0} if kind == "shell" else None)
    geo = build_tank(p, out / kind)
    t0 = time.perf_counter()
    m = build_model(geo, convective="wall")
    build = time.perf_counter() - t0
    comp = Component(name="core", **m.component_fields(), liquid=LiquidMass(**m.liquid_fields()))
    t0 = time.perf_counter()
    cb = craig_bampton(comp, points_labels(boundary_points(comp)), n_modes=n_modes, solver=petsc_solver())
    t_cb = time.perf_counter() - t0
    from bench_shells import wave_number

    w2, Q = la.eigh(cb.K, cb.M)
    nm = cb.fixed_omega.size
    beam, kinds = None, []
    for j in range(6, w2.size):      # the first free-free mode that is beam bending (fem.modes.beam_content)
        x = cb.fixed_interface_modes @ Q[:nm, j] + cb.constraint_modes @ Q[nm:, j]
        hz, content = float(np.sqrt(w2[j]) / (2 * np.pi)), beam_content(m, x)
        if len(kinds) < 10:          # what the first elastic modes are: beam, or (n, where) of the wall
            kinds.append({"hz": hz, "beam": content > 0.5, "wave": wave_number(m, x)})
        if beam is None and content > 0.5:
            beam = {"hz": hz, "content": content, "others_below": j - 6}
        if beam is not None and len(kinds) == 10:
            break
    return {"first_beam": beam, "first_modes": kinds, "kind": kind, "mesh_size": h, "n_dof": m.n_dof, "build_s": build, "cb_s": t_cb,
            "pressure_pa": [c.ullage_pressure for c in p.compartments],
            "fixed_interface_hz": cb.fixed_freq_hz[:10].tolist(),
            "free_free_hz": (np.sign(w2[:12]) * np.sqrt(np.abs(w2[:12])) / (2 * np.pi)).tolist()}


def main(argv=None) -> None:
    os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")
    import pyvista  # noqa: F401  (before dolfinx)

    from liftoff.core.records import write_text

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--mesh-size", type=float, default=0.9)
    ap.add_argument("--modes", type=int, default=60)
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--out", default="out/bench_prestress")
    a = ap.parse_args(argv)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    for kind in ("solid", "shell", "shell-p"):
        runs = [run_variant(kind, a.mesh_size, out, a.modes) for _ in range(a.repeat)]
        r = dict(runs[0])
        for k in ("build_s", "cb_s"):
            r[k] = {"min": min(x[k] for x in runs), "median": float(np.median([x[k] for x in runs]))}
        rows.append(r)
        print(f"{kind}: done", flush=True)
    write_text(out / "bench_prestress.json", json.dumps({"runs": rows}, indent=1))
    print("| variant | DOFs | build min/median (s) | CB min/median (s) | first fixed-interface (Hz) | "
          "rigid-body (Hz, largest) | first free-free elastic (Hz) | first beam bending (Hz; other modes below) |")
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        ff = np.array(r["free_free_hz"])
        print(f"| {r['kind']} | {r['n_dof']} | {r['build_s']['min']:.1f} / {r['build_s']['median']:.1f} | "
              f"{r['cb_s']['min']:.1f} / {r['cb_s']['median']:.1f} | "
              f"{', '.join(f'{f:.2f}' for f in r['fixed_interface_hz'][:4])} | {np.abs(ff[:6]).max():.1e} | "
              f"{ff[6]:.3f} | {_beam(r['first_beam'])} |")
    print("\nFirst free-free elastic modes of the CB models (Hz; beam, or n = the radial displacement's "
          "dominant circumferential wave number and where |u|^2 is largest):")
    print("| " + " | ".join(r["kind"] for r in rows) + " |")
    print("|" + "---|" * len(rows))
    for i in range(10):
        print("| " + " | ".join(_mode(r["first_modes"][i]) if i < len(r["first_modes"]) else "" for r in rows) + " |")


def _mode(k) -> str:
    return f"{k['hz']:.2f} " + ("beam" if k["beam"] else f"n={k['wave'][0]} {k['wave'][1]}")


def _beam(b) -> str:
    return "none among the CB model's modes" if b is None else f"{b['hz']:.3f} ({b['others_below']})"


if __name__ == "__main__":
    main()
