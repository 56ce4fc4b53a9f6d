"""Is the default converged in the mesh? The static state of the stack on its pad at t0
(gravity and the cryo preload, section 2.6) on refined meshes and with P2 solids.

    python benchmarks/mesh_study.py [--cache DIR] [--only NAME ...] [--reuse]

Statics only, so every component keeps a single fixed-interface mode (a Craig-Bampton
model's statics are exact whatever its modes: the constraint modes carry them) and every
system mode; a refinement level then costs the FE assembly and one factorisation per
component, not an eigensolve. Each level scales every component's mesh size (the default's:
core 1.2 m, boosters 0.6 m, orbiter 0.7 m, pad 2.4 m) and sets the solids' element degree
(`[model] degree`; the shells keep their own element). Figures: the post axial loads and
the attach forces and moments at t0 (N, N m), and each one's change from the finest level
relative to the largest magnitude of its kind (posts; attach forces; attach moments).
Writes docs/figures/mesh_study.json, which benchmarks/default_figures.py renders into
docs/workflow.md. Stage cache: default out/.liftoff-cache.
"""
from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import liftoff  # noqa: F401 - before numpy: it picks the OpenBLAS kernels (liftoff/core/openblas.py)
import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks"))
from default_figures import _fe_dofs, run_default_like  # noqa: E402

#: the mesh sizes (m) before issue 22, which the levels scale (the default's are core 0.85 m and
#: orbiter 0.5 m, the others the same; srb_right, the mirror of srb_left, takes its mesh)
SIZES = {"core": 1.2, "srb_left": 0.6, "orbiter": 0.7, "pad": 2.4}
DEFAULT = "P2 x1, core 0.85 m, orbiter 0.5 m (the default)"
#: level -> (mesh-size factor, solid element degree, factors of single components)
LEVELS = {"P1 x1 (the default before issue 22)": (1.0, 1, {}), "P1 x0.7": (0.7, 1, {}), "P1 x0.5": (0.5, 1, {}),
          "P2 x1": (1.0, 2, {}), "P2 x1, core x0.7": (1.0, 2, {"core": 0.7}),
          DEFAULT: (1.0, 2, {"core": 0.85 / 1.2, "orbiter": 0.5 / 0.7}), "P2 x0.7": (0.7, 2, {}),
          "P2 x0.5": (0.5, 2, {})}
FINEST = "P2 x0.5"


def level(factor: float, degree: int, single: dict):
    def edit(data: dict) -> dict:
        m = data["model"]
        m["degree"] = degree
        for name, h in SIZES.items():
            sel = m["pad"] if name == "pad" else m["component"][name]
            sel["n_modes"] = 1
            sel.pop("f_max", None)
            sel["mesh_size"] = h * single.get(name, factor)
        data["time"]["t_end"] = 0.002            # the state at t0 is what is studied
        data["case"] = [data["case"][0]]
        return data
    return edit


def statics(name: str, cache: Path, tmp: Path) -> dict:
    t0 = time.perf_counter()
    out = run_default_like(level(*LEVELS[name]), tmp / name.replace(" ", "_"), cache, error_estimate=False)
    res, cp = out.results["nominal"]
    stack = next(iter(out.stacks.values()))
    tz = [j for j, d in enumerate(res.contact_directions) if d.component == "Tz"]
    return {"level": name, "factor": LEVELS[name][0], "degree": LEVELS[name][1], "single": LEVELS[name][2],
            "dofs": {n: _fe_dofs(c) for n, c in stack.components.items()},   # less slosh pendulums, as the default figures
            "posts_tz_n": {res.contact_directions[j].contact: float(res.contact_force[0, j]) for j in tz},
            "attach": {point: [float(x) for x in res.recovered[rec][0]] for rec, (point, _) in cp.attach.items()},
            "wall_s": time.perf_counter() - t0}


def changes(row: dict, ref: dict) -> dict:
    """Largest change from ``ref`` of the post loads, attach forces and attach moments, each
    relative to the largest magnitude of its kind in ``ref`` (with the item that moves most)."""
    def worst(pairs):
        scale = max(abs(b) for _, _, b in pairs)
        k, a, b = max(pairs, key=lambda p: abs(p[1] - p[2]))
        return {"change": abs(a - b) / scale, "item": k}
    posts = [(k, v, ref["posts_tz_n"][k]) for k, v in row["posts_tz_n"].items()]
    comp = ("Tx", "Ty", "Tz", "Rx", "Ry", "Rz")
    att = [(f"{p} {comp[i]}", v[i], ref["attach"][p][i]) for p, v in row["attach"].items() for i in range(6)]
    return {"posts": worst(posts), "attach_forces": worst([a for a in att if a[0][-2] == "T"]),
            "attach_moments": worst([a for a in att if a[0][-2] == "R"])}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cache", type=Path, default=ROOT / "out" / ".liftoff-cache")
    ap.add_argument("--only", nargs="*", default=None)
    ap.add_argument("--reuse", action="store_true", help="take the levels not run from the existing --json file")
    ap.add_argument("--json", type=Path, default=ROOT / "docs" / "figures" / "mesh_study.json")
    args = ap.parse_args(argv)
    import pyvista  # noqa: F401  (before dolfinx, FENICSX-NOTES.md)

    old = {r["level"]: r for r in json.loads(args.json.read_text())["levels"]} \
        if args.reuse and args.json.is_file() else {}
    todo = list(LEVELS if args.only is None else args.only)
    rows = {n: old[n] for n in LEVELS if n in old and n not in todo}
    with tempfile.TemporaryDirectory() as tmp:
        for name in todo:
            rows[name] = r = statics(name, args.cache, Path(tmp))
            print(f"{name:22s} {sum(r['dofs'].values()):8d} DOFs  posts Tz (MN) "
                  f"{np.round(np.array(list(r['posts_tz_n'].values())) / 1e6, 3)}  {r['wall_s']:.0f} s", flush=True)
    out = [rows[n] for n in LEVELS if n in rows]
    if FINEST in rows:
        for r in out:
            r["change_from_finest"] = changes(r, rows[FINEST])
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps({"finest": FINEST, "levels": out}, indent=1) + "\n")
    print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
