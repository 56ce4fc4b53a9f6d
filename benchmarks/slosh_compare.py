"""The default run with the liquids' sloshing part three ways (issue 25): ``[model]
convective = "slosh"`` (the default: the slosh modes as tank-referenced pendulums,
fem.slosh), ``"wall"`` (lumped rigidly on the wetted wall) and ``"free"`` (left out). Writes
docs/figures/slosh_compare.json, rendered into README.md by benchmarks/default_figures.py.

    .venv/bin/python benchmarks/slosh_compare.py [--cache DIR] [--json FILE]
"""
from __future__ import annotations

import argparse
import json
import runpy
import sys
from pathlib import Path

import liftoff  # noqa: F401 - before numpy: it picks the OpenBLAS kernels (liftoff/core/openblas.py)
import numpy as np

ROOT = Path(__file__).resolve().parent.parent
JSON = ROOT / "docs" / "figures" / "slosh_compare.json"
VARIANTS = ("slosh", "wall", "free")


def variant_figures(conv: str, cache: Path | None) -> dict:
    fig = runpy.run_path(str(ROOT / "benchmarks" / "default_figures.py"), run_name="default_figures")

    def edit(d):
        d["model"]["convective"] = conv
        return d

    out, wall_s = fig["timed_variant"](edit, cache)
    stack = next(iter(out.stacks.values()))
    m, cg = fig["_mass_cg"](stack.vehicle)
    rows = out.envelope
    posts = fig["post_tz_rows"](rows)
    attach = sorted((r for r in rows if r["category"] == "interface_force" and r["unit"] == "N"),
                    key=lambda r: -abs(fig["_peak"](r)[0]))[:3]
    pressure = [r for r in rows if r["item"].startswith("tank pressure core_lox")]
    slosh = [r for r in rows if "_slosh_force " in r["item"]]
    from liftoff.workflows.report import slosh_summary

    res = out.results["nominal"][0]
    return {
        "wall_s": wall_s, "vehicle_modes": stack.vehicle.n_modes, "vehicle_mass_t": m / 1e3,
        "twang_m": fig["twang_figures"](out, "nominal")["peak_m"],
        "peak_post_compression_n": max(r["max"] for r in posts),
        "largest_attach": [{"item": r["item"], "value": fig["_peak"](r)[0]} for r in attach],
        "lox_bottom_pressure_pa": [min(r["min"] for r in pressure), max(r["max"] for r in pressure)],
        "t_end_s": float(res.time[-1]),
        "cg_motion_end": [float(x) for x in res.recovered["cg_motion"][-1]],     # m, m, m, rad, rad, rad
        "slosh": slosh_summary(stack.cbs, rows),
        "peak_slosh_force_n": max((max(abs(r["max"]), abs(r["min"])) for r in slosh), default=None),
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cache", type=Path, default=ROOT / "out" / ".liftoff-cache")
    ap.add_argument("--json", type=Path, default=JSON)
    args = ap.parse_args(argv)
    import pyvista  # noqa: F401  (before dolfinx, FENICSX-NOTES.md)

    out = {}
    for conv in VARIANTS:
        print(f"slosh_compare: convective = {conv!r} ...", flush=True)
        out[conv] = variant_figures(conv, args.cache)
    args.json.write_text(json.dumps(out, indent=1, default=float) + "\n")
    print(f"wrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
