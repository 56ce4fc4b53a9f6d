"""The default run with its attach joints welded (every DOF joined, the default before issue
26's load paths) and released as the Shuttle's attach hardware carries load
(``[[model.joint]] release``, reduction/assembly.py).

Boosters: the SRB thrust and weight pass to the external tank at the forward attach alone, a
spherical bearing on the intertank's thrust beam (forces, no moments), while the three aft
struts (upper, diagonal, lower, in a plane across the vehicle axis) carry only in-plane load:
Tx, Ty and the couple Rz. Orbiter: one forward bipod and two aft bipods, each two pin-ended
struts meeting at a spherical fitting, which carry forces in the struts' plane only: the
forward bipod's struts splay across the vehicle (plane x-y: Tx, Ty; Tz and the rotations
released), each aft bipod's vertical and diagonal struts lie in the plane of the axis and the
orbiter's offset (plane y-z: Ty, Tz; Tx and the rotations released). Either set's six
reactions hold the component statically determinately, so the external tank's cryo
shrinkage strains no attach.

Variants (each a whole run of both named cases without the error estimate, stage cache
shared, so only the vehicle's system modes and the transients are rebuilt); the releases are
keyed by joint kind, the joint's name without its side (``att_srb_fwd`` holds
``att_srb_left_fwd`` and ``att_srb_right_fwd``):

* ``welded``: all six DOFs of each attach point joined;
* ``aft_axial``: the booster aft attach points release Tz, the axial direction;
* ``boosters``: the boosters' hardware, the forward points release Rx Ry Rz, the aft points
  Tz Rx Ry; the orbiter's attach points welded (the default before 2026-11-28's second change);
* ``bipods``: the boosters' as above and the orbiter's bipods, forward Tz Rx Ry Rz, aft Tx Rx
  Ry Rz (the default scenario's joints).

Writes docs/figures/attach_release.json, rendered into README.md by
benchmarks/default_figures.py (block ``attach-release``).

    .venv/bin/python benchmarks/attach_release_compare.py [--cache DIR] [--json FILE]
"""
from __future__ import annotations

import runpy
import sys
from pathlib import Path

from liftoff.config.model import ORBITER_ATTACH_RELEASE, SRB_ATTACH_RELEASE

ROOT = Path(__file__).resolve().parent.parent
JSON = ROOT / "docs" / "figures" / "attach_release.json"
#: the Shuttle's releases by joint kind (config.model's, which the default scenario lists)
BOOSTERS = {f"att_srb_{end}": list(dofs) for end, dofs in SRB_ATTACH_RELEASE.items()}
BIPODS = {f"att_orb_{end}": list(dofs) for end, dofs in ORBITER_ATTACH_RELEASE.items()}
#: variant -> {joint kind: released DOFs}
VARIANTS = {
    "welded": {},
    "aft_axial": {"att_srb_aft": ["Tz"]},
    "boosters": BOOSTERS,
    "bipods": {**BOOSTERS, **BIPODS},
}


def joint_kind(name: str) -> str:
    """A joint's kind: its name without the side (``att_orb_aft_left`` -> ``att_orb_aft``)."""
    return "_".join(p for p in name.split("_") if p not in ("left", "right"))


def variant_figures(name: str, cache: Path) -> dict:
    """Figures of the default run with the attach joints released as ``VARIANTS[name]``."""
    fig = runpy.run_path(str(ROOT / "benchmarks" / "default_figures.py"), run_name="default_figures")
    release = VARIANTS[name]

    def edit(d):
        for j in d["model"]["joint"]:
            if j["name"].startswith("att_"):
                j.pop("release", None)
                if joint_kind(j["name"]) in release:
                    j["release"] = release[joint_kind(j["name"])]
        return d

    out, wall_s = fig["timed_variant"](edit, cache)
    return {**fig["variant_summary"](out, wall_s, "srb_left"), "release": release}


def main(argv=None) -> int:
    fig = runpy.run_path(str(ROOT / "benchmarks" / "default_figures.py"), run_name="default_figures")
    return fig["compare_main"](argv, __doc__, VARIANTS, variant_figures, JSON, "attach_release_compare")


if __name__ == "__main__":
    sys.exit(main())
