"""The default run's convergence in the step: the same run with the automatic step sampling
the bodies' highest mode 2 (the default scenario's ``[time] mode_samples``), 4 (the
library's default, the default scenario's before 2026-11-28) and 8 times a period, each
compared row by row with the finest.

    python benchmarks/step_study.py [--cache DIR] [--json docs/figures/step_study.json]

Each run is the default scenario (both named cases, no pictures, no h/2 error estimate) with
``[time] mode_samples`` changed; the step is then min(0.25/f_h (eq. 12), 1/(m f_s))
(transient/stepping.py). The deviation of an envelope row is the larger change of its max
and min from the finest run's, relative to that row's largest magnitude there (as in
benchmarks/convergence_study.py, whose functions it uses). Writes the JSON file that
benchmarks/default_figures.py renders into docs/workflow.md ("Convergence in the step").
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

SAMPLES = (2.0, 4.0, 8.0)       # steps a period of the highest mode; the last is the reference


def run_samples(m: float, cache: Path, tmp: Path) -> dict:
    """The default with ``[time] mode_samples = m``: its envelope rows, step and twang."""
    def edit(d):
        d = copy.deepcopy(d)
        d["time"]["mode_samples"] = m
        return d

    t0 = time.perf_counter()
    out = run_default_like(edit, tmp / f"m{m:g}", cache, error_estimate=False)
    res = out.results["nominal"][0]
    return {"mode_samples": m, "steps": int(res.time.size - 1), "h_s": float(res.h),
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

    from liftoff.config import default_text, parse_scenario, parse_toml
    from liftoff.core import write_text

    default_m = parse_scenario(parse_toml(default_text(), "d"), "d").cases[0].time.mode_samples
    runs = []
    with tempfile.TemporaryDirectory() as tmp:
        for m in SAMPLES:
            runs.append(run_samples(m, args.cache, Path(tmp)))
            print(f"mode_samples {m:g}: {runs[-1]['steps']} steps of {runs[-1]['h_s'] * 1e6:.1f} us, "
                  f"{runs[-1]['wall_s']:.0f} s", flush=True)
    ref = runs[-1]["rows"]
    table = against(runs, ref)
    write_text(args.json, json.dumps({"default_mode_samples": default_m, "reference_mode_samples": SAMPLES[-1],
                                      "variants": table}, indent=1) + "\n")
    print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
