"""The default run's convergence in the step: the same run at its automatic step h0
(min(0.25/f_h (eq. 12), 1/(m f_s)) of its dynamic modes, transient/stepping.py) and at
h0/2, h0/4 and h0/8, each compared row by row with the finest.

    python benchmarks/step_study.py [--cache DIR] [--json docs/figures/step_study.json]

Each run is the default scenario (both named cases, no pictures, no h/2 error estimate), the
finer ones with ``[time] h`` given. The deviation of an envelope row is the larger change
of its max and min from the finest run's, relative to that row's largest magnitude there
(as in benchmarks/convergence_study.py, whose functions it uses). Writes the JSON file that
benchmarks/default_figures.py renders into docs/workflow.md ("Convergence in the step").
(Before the default's residual-flexibility cut, 2026-12-01, the steps were those of 2, 4 and
8 samples a period of its highest mode; with the cut, eq. 12 sets the step at 2 and 4.)
"""
from __future__ import annotations

import argparse
import copy
import json
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from convergence_study import against  # noqa: E402
from default_figures import ROOT, run_default_like, twang_figures  # noqa: E402

FACTORS = (1.0, 0.5, 0.25, 0.125)     # of the default's automatic step; the last is the reference


def run_step(factor: float, h0: float | None, cache: Path, tmp: Path) -> dict:
    """The default at ``factor`` x its automatic step ``h0`` (None: the automatic step
    itself): its envelope rows, step and twang."""
    def edit(d):
        d = copy.deepcopy(d)
        if h0 is not None:
            d["time"]["h"] = factor * h0
        return d

    t0 = time.perf_counter()
    out = run_default_like(edit, tmp / f"h{factor:g}", cache, error_estimate=False)
    res = out.results["nominal"][0]
    return {"factor": factor, "steps": int(res.time.size - 1), "h_s": float(res.h),
            "f_s_hz": float(res.metadata["f_s"]), "f_h_hz": float(res.metadata["f_h"]),
            "twang": twang_figures(out), "wall_s": time.perf_counter() - t0,
            "rows": [{k: r[k] for k in ("item", "category", "unit", "max", "min")} for r in out.envelope]}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cache", type=Path, default=ROOT / "out" / ".liftoff-cache")
    ap.add_argument("--json", type=Path, default=ROOT / "docs" / "figures" / "step_study.json")
    args = ap.parse_args(argv)
    import pyvista  # noqa: F401  (before dolfinx, FENICSX-NOTES.md)
    import tempfile

    from liftoff.core import write_text

    runs = []
    with tempfile.TemporaryDirectory() as tmp:
        for f in FACTORS:
            runs.append(run_step(f, None if f == 1.0 else runs[0]["h_s"], args.cache, Path(tmp)))
            print(f"h0 x {f:g}: {runs[-1]['steps']} steps of {runs[-1]['h_s'] * 1e6:.1f} us, "
                  f"{runs[-1]['wall_s']:.0f} s", flush=True)
    ref = runs[-1]["rows"]
    table = against(runs, ref)
    write_text(args.json, json.dumps({"default_h_s": runs[0]["h_s"], "reference_factor": FACTORS[-1],
                                      "variants": table}, indent=1) + "\n")
    print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
