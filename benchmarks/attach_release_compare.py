"""The default run with its booster attach joints welded (every DOF joined, the default
before issue 26's load path) and released as the Shuttle's attach hardware carries load
(``[[model.joint]] release``, reduction/assembly.py): the SRB thrust and weight pass to the
external tank at the forward attach alone, a spherical bearing on the intertank's thrust
beam (forces, no moments), while the three aft struts (upper, diagonal, lower, in a plane
across the vehicle axis) carry only in-plane load: Tx, Ty and the couple Rz. Together the
six reactions hold each booster statically determinately, so the external tank's cryo
shrinkage strains no attach.

Variants (each a whole run of both named cases without the error estimate, stage cache
shared, so only the vehicle's system modes and the transients are rebuilt):

* ``welded``: all six DOFs of each attach point joined;
* ``aft_axial``: the aft attach points (``att_srb_*_aft``) release Tz, the axial direction;
* ``determinate``: the Shuttle's, the forward points release Rx Ry Rz, the aft points Tz
  Rx Ry (the default scenario's joints).

Writes docs/figures/attach_release.json, rendered into README.md by
benchmarks/default_figures.py (block ``attach-release``).

    .venv/bin/python benchmarks/attach_release_compare.py [--cache DIR] [--json FILE]
"""
from __future__ import annotations

import argparse
import json
import runpy
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
JSON = ROOT / "docs" / "figures" / "attach_release.json"
#: variant -> {joint name suffix: released DOFs}
VARIANTS = {
    "welded": {},
    "aft_axial": {"aft": ["Tz"]},
    "determinate": {"fwd": ["Rx", "Ry", "Rz"], "aft": ["Tz", "Rx", "Ry"]},
}


def variant_figures(name: str, cache: Path) -> dict:
    """Figures of the default run with the booster attach joints released as ``VARIANTS[name]``."""
    fig = runpy.run_path(str(ROOT / "benchmarks" / "default_figures.py"), run_name="default_figures")
    release = VARIANTS[name]

    def edit(d):
        for j in d["model"]["joint"]:
            if j["name"].startswith("att_srb_"):
                j.pop("release", None)
                end = j["name"].rsplit("_", 1)[-1]
                if end in release:
                    j["release"] = release[end]
        return d

    out, wall_s = fig["timed_variant"](edit, cache)
    return {**fig["variant_summary"](out, wall_s, "srb_left"), "release": release}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cache", type=Path, default=ROOT / "out" / ".liftoff-cache")
    ap.add_argument("--variants", nargs="*", default=list(VARIANTS), choices=list(VARIANTS))
    ap.add_argument("--json", type=Path, default=JSON)
    args = ap.parse_args(argv)
    import pyvista  # noqa: F401  (before dolfinx, FENICSX-NOTES.md)

    out = json.loads(args.json.read_text()) if args.json.is_file() else {}
    for name in args.variants:
        print(f"attach_release_compare: {name} ...", flush=True)
        out[name] = variant_figures(name, args.cache)
    out = {k: out[k] for k in VARIANTS if k in out}
    args.json.write_text(json.dumps(out, indent=1, default=float) + "\n")
    print(f"wrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
