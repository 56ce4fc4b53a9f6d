"""The default scenario's slosh modes (issue 25): ``liftoff slosh`` of the embedded default
(each hydroelastic liquid of the core stage in its rigid tank, 1 g, P2 and P1 pressure on the
default mesh) as docs/figures/slosh_default.json, rendered into README.md by
benchmarks/default_figures.py; tests/workflows/test_default_figures.py checks that the
checked-in figures are the current code's.

    .venv/bin/python benchmarks/slosh_default.py [--json docs/figures/slosh_default.json]
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
JSON = ROOT / "docs" / "figures" / "slosh_default.json"
N_MODES = 2


def slosh_figures() -> dict:
    """{liquid: {mass_kg, impulsive_kg, impulsive_z_m, modes: [...], p1_first_hz}} of the default."""
    from liftoff.config.scenario import load_scenario
    from liftoff.workflows.slosh import tank_slosh

    out = {}
    for comp, liquids in tank_slosh(load_scenario(None), 9.80665, N_MODES, progress=lambda s: None).items():
        for g, (s, s1) in liquids.items():
            out[f"{comp}/{g}"] = {
                "mass_kg": s.mass, "centroid_z_m": float(s.centroid[2]), "impulsive_kg": s.impulsive_mass[0],
                "impulsive_z_m": s.impulsive_height[0], "g_eff": s.gravity, "mass_kept": s.mass_kept,
                "modes": [{"frequency_hz": m.frequency, "mass_kg": m.mass, "height_m": m.height} for m in s.modes],
                "p1_first_hz": s1.modes[0].frequency if s1 is not None and s1.modes else None}
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--json", type=Path, default=JSON)
    args = ap.parse_args(argv)
    import pyvista  # noqa: F401  (before dolfinx, FENICSX-NOTES.md)

    fig = slosh_figures()
    args.json.write_text(json.dumps(fig, indent=1) + "\n")
    print(f"wrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
