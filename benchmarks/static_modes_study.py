"""The default run with its highest modes solved quasi-statically: ``[time] static_above_hz``
(residual-flexibility modes, transient/coefficients.py) at 600 (the default's), 300 and
150 Hz, each compared row by row with the default with every mode dynamic; each cut also at
that run's step, to tell the quasi-static solution's share of a change from the larger step's.

    python benchmarks/static_modes_study.py [--cache DIR] [--json docs/figures/static_modes_study.json]

Each run is the default scenario (both named cases, no pictures, no h/2 error estimate) with
``[time] static_above_hz`` set (600 Hz in the default scenario; None: removed). The modes above the cut keep
their static flexibility (q = P/omega^2) and no longer set the step: the step becomes
min(0.25/f_h, 1/(m f_s)) of the dynamic modes, f_h with the static modes' flexibility in
series with the posts' springs (transient/stepping.py). The deviation of an envelope row is
the larger change of its max and min from the all-dynamic run's, relative to that row's
largest magnitude there (benchmarks/convergence_study.py's measure; accelerations and liquid
pressures low-pass filtered to the default's acceleration band, as the run's tables are).
Writes the JSON file that benchmarks/default_figures.py renders into docs/transient.md
("Residual-flexibility modes").
"""
from __future__ import annotations

import argparse
import copy
import json
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import liftoff  # noqa: E402,F401  (before numpy: OpenBLAS's kernels, liftoff/core/openblas.py)
from convergence_study import against  # noqa: E402
from default_figures import ROOT, run_default_like, twang_figures  # noqa: E402

CUTS = (None, 600.0, 300.0, 150.0)      # Hz; None: every mode dynamic, the reference


def run_cut(cut: float | None, cache: Path, tmp: Path, h: float | None = None) -> dict:
    """The default with ``[time] static_above_hz = cut`` (and ``h``, s, if given): its
    envelope rows, step, twang."""
    def edit(d):
        d = copy.deepcopy(d)
        if cut is None:
            d["time"].pop("static_above_hz", None)
        else:
            d["time"]["static_above_hz"] = cut
        if h is not None:
            d["time"]["h"] = h
        return d

    t0 = time.perf_counter()
    out = run_default_like(edit, tmp / f"cut{cut}_{h}", cache, error_estimate=False)
    res = out.results["nominal"][0]
    md = res.metadata
    transient_s = sum(s for label, s in out.stage_times if label.startswith("transient ["))
    return {"static_above_hz": cut, "same_step": h is not None, "static_modes": md["static_modes"], "steps": int(res.time.size - 1),
            "h_s": float(res.h), "f_s_hz": float(md["f_s"]), "f_h_hz": float(md["f_h"]),
            "twang": twang_figures(out), "wall_s": time.perf_counter() - t0, "transients_s": transient_s,
            "rows": [{k: r[k] for k in ("item", "category", "unit", "max", "min")} for r in out.envelope]}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cache", type=Path, default=ROOT / "out" / ".liftoff-cache")
    ap.add_argument("--json", type=Path, default=ROOT / "docs" / "figures" / "static_modes_study.json")
    args = ap.parse_args(argv)
    import pyvista  # noqa: F401  (before dolfinx, FENICSX-NOTES.md)
    import tempfile

    from liftoff.core import write_text

    runs = []
    with tempfile.TemporaryDirectory() as tmp:
        for cut in CUTS:
            for h in ((None,) if cut is None else (None, runs[0]["h_s"])):
                runs.append(run_cut(cut, args.cache, Path(tmp), h))
                r = runs[-1]
                print(f"static_above_hz {cut}: {r['static_modes']} static modes, {r['steps']} steps of "
                      f"{r['h_s'] * 1e6:.1f} us, transients {r['transients_s']:.1f} s, run {r['wall_s']:.0f} s",
                      flush=True)
    ref = runs[0]["rows"]
    table = against(runs, ref)
    from liftoff.config import load_scenario

    default = load_scenario().cases[0].time.static_above_hz            # the default scenario's own cut
    write_text(args.json, json.dumps({"date": time.strftime("%Y-%m-%d"), "default_static_above_hz": default,
                                      "variants": table}, indent=1) + "\n")
    print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
