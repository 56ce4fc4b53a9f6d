"""The default run with its boosters as today's thickened solid and as a shell case bonded
to a nearly incompressible propellant grain (issue 26): ``[model.component.srb_*.params]
walls = "shell"``, ``grain = true`` (meshes.shells.build_shell_booster, fem.elasticity),
with the boosters' Craig-Bampton cut ``f_max`` at each of ``--f-max`` (the grain's own
modes are so many, thousands of fixed-interface modes below 60 Hz per booster, that
the cut is what the comparison must show converged). Cold stages (no cache), so the
boosters' FE and CB times are measured. Writes docs/figures/booster_grain.json, rendered
into README.md by benchmarks/default_figures.py.

    .venv/bin/python benchmarks/booster_grain_compare.py [--f-max 15 25] [--no-solid] [--json FILE]

Each variant is a whole cold run; run them one per process where memory is short (the
file is updated, not overwritten; each column's ``peak_rss_gb`` is its process's peak so far,
the column's own where it ran first). Measured here (24 GB): with both boosters reduced, 25 Hz
was killed for memory (24 GB resident with LIFTOFF_MODEL_WORKERS=1), and on 2026-11-28 20 Hz
after the solid and 15 Hz columns in the same process. Since 2026-12-01 the default's right
booster mirrors the left one (the edits below go to srb_left; the mirror follows), so one
grain booster is reduced: ``--f-max 15`` and then ``--f-max 20 25 --no-solid`` ran, the
second process peaking at 22.8 GB resident. On 2026-12-07 ``--f-max 30 --no-solid`` ran in
a process of its own (817 booster modes): 22.9 GB used on the machine at its peak keeping the
block Lanczos basis' B-image, 18.6 GB (17.9 in one process) without it (fem.block_lanczos
drops it for a basis this large), 16.2 GB (17.0) and a CB stage of 205 s instead of 326 s
with the band shift-inverted at its middle (fem.petsc_cb.shifted_pairs).
"""
from __future__ import annotations

import argparse
import json
import resource
import runpy
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
JSON = ROOT / "docs" / "figures" / "booster_grain.json"
BOOSTERS = ("srb_left",)       # srb_right mirrors srb_left (the default scenario): it follows


def variant_figures(grain: bool, f_max: float | None, residual: bool = False) -> dict:
    """Figures of the default run with grain boosters (``grain``) cut at ``f_max`` Hz (with
    ``residual``: and their residual vectors), or the default itself."""
    fig = runpy.run_path(str(ROOT / "benchmarks" / "default_figures.py"), run_name="default_figures")

    def edit(d):
        for b in BOOSTERS:
            if grain:
                d["model"]["component"][b]["params"].update(walls="shell", grain=True)
                d["model"]["component"][b]["f_max"] = f_max
                if residual:
                    d["model"]["component"][b]["residual_vectors"] = True
                # the default's [model.materials] srb_*_case is the thickened solid's equivalent
                # (rho 1024 kg/m^3, E 17.4 GPa): the shell case is the steel wall itself
                d["model"].get("materials", {}).pop(f"{b}_case", None)
        return d

    out, wall_s = fig["timed_variant"](edit, None)
    cut = out.results["nominal"][1].case.model.components[BOOSTERS[0]].f_max    # the run's own (default: 120 Hz)
    return {**fig["variant_summary"](out, wall_s, BOOSTERS[0]), "booster_f_max_hz": cut,
            "booster_residual_vectors": stack_residual(out), "peak_rss_gb": peak_rss_gb()}


def peak_rss_gb() -> float:
    """The largest resident set (GB) of this process and of its finished children (the model
    stages' pool, the h/2 runs) so far: a variant's own where it is the process's first."""
    return max(resource.getrusage(who).ru_maxrss for who in (resource.RUSAGE_SELF, resource.RUSAGE_CHILDREN)) * 1024 / 1e9


def stack_residual(out) -> int:
    """The booster's residual vectors in the run's CB model (0 without them)."""
    stack = next(iter(out.stacks.values()))
    return int(stack.cbs[BOOSTERS[0]].n_residual)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--f-max", type=float, nargs="*", default=[15.0, 25.0])
    ap.add_argument("--no-solid", action="store_true", help="keep the file's solid-booster figures")
    ap.add_argument("--residual", action="store_true",
                    help="the grain boosters with residual vectors (their columns under 'grain_rv')")
    ap.add_argument("--json", type=Path, default=JSON)
    args = ap.parse_args(argv)
    import pyvista  # noqa: F401  (before dolfinx, FENICSX-NOTES.md)

    out = json.loads(args.json.read_text()) if args.json.is_file() else {"solid": None, "grain": {}}
    if not args.no_solid:
        print("booster_grain_compare: the default (thickened solid boosters) ...", flush=True)
        out["solid"] = variant_figures(False, None)
    group = "grain_rv" if args.residual else "grain"
    out.setdefault(group, {})
    for f in args.f_max:
        print(f"booster_grain_compare: case + grain boosters, f_max = {f:g} Hz"
              f"{' with residual vectors' if args.residual else ''} ...", flush=True)
        out[group][f"{f:g}"] = variant_figures(True, f, args.residual)
        args.json.write_text(json.dumps(out, indent=1, default=float) + "\n")      # each column as it comes
    out[group] = dict(sorted(out[group].items(), key=lambda kv: float(kv[0])))
    args.json.write_text(json.dumps(out, indent=1, default=float) + "\n")
    print(f"wrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
