"""The default run with its shell walls bare (the default) and stiffened by discrete beams
(issue 26): ring frames and stringers on the external tank's wall, then on the orbiter's
skin as well, then the launch table's deck as a grid of girders.

The default's walls are bare skins (``shell_bending_ratio`` 1, no frames or stringers) and
its deck the equivalent solid; the builders take frames, stringers and girders as beams
(fem/beam.py, docs/fem.md "Beams in FE models"). The sections and stations below are
illustrative, not the Shuttle's drawings: the external tank's five major LH2 ring frames
(public: "five major ring frames") from the aft attach station (the LH2 tank's aft frame,
13.2 m here) to the orbiter's forward attach station (its forward frame, 37.0 m) equally
spaced, and one at the intertank's booster beam (40.5 m), T sections 0.25 m deep; 24 hat
stringers along the whole cylinder; the orbiter's and the girder deck's as README's example.
The frames' and stringers' mass comes off the skin's (the tank's and the orbiter's dry mass
are kept). So the table says how far discrete stiffening of this size moves the default's
loads, not what the Shuttle's stiffeners give.

Variants (each a whole run of both named cases without the error estimate, stage cache
shared, so only the changed components' stages and the system modes are rebuilt):

* ``bare``: the default;
* ``tank``: the external tank's frames and stringers;
* ``tank_orbiter``: those and the orbiter's;
* ``tank_orbiter_girders``: those and the girder deck.

Writes docs/figures/stiffeners.json, rendered into README.md by
benchmarks/default_figures.py (block ``stiffeners``).

    .venv/bin/python benchmarks/stiffener_compare.py [--cache DIR] [--json FILE] [--variants ...]
"""
from __future__ import annotations

import runpy
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
JSON = ROOT / "docs" / "figures" / "stiffeners.json"

#: the external tank's stiffeners (illustrative sizes; stations as the module docstring says)
TANK = {"frames": [13.2, 19.15, 25.1, 31.05, 37.0, 40.5],
        "frame_section": {"shape": "t", "h": 0.25, "b": 0.1, "tw": 0.006, "tf": 0.01},
        "stringers": 24, "stringer_azimuth": 7.5,
        "stringer_section": {"shape": "hat", "h": 0.05, "b": 0.04, "c": 0.02, "t": 0.003}}
#: the orbiter's (README's example, "Beams, frames, stringers, girders")
ORBITER = {"frames": [14.0, 20.0, 26.0],
           "frame_section": {"shape": "t", "h": 0.2, "b": 0.08, "tw": 0.004, "tf": 0.006},
           "stringers": 16,
           "stringer_section": {"shape": "hat", "h": 0.05, "b": 0.03, "c": 0.02, "t": 0.002}}
#: the launch table's deck as girders (README's example)
GIRDERS = {"deck": "girders", "girder_section": {"shape": "i", "h": 7.0, "b": 3.0, "tw": 0.03, "tf": 0.05}}
#: variant -> the components it stiffens
VARIANTS = {"bare": (), "tank": ("core",), "tank_orbiter": ("core", "orbiter"),
            "tank_orbiter_girders": ("core", "orbiter", "pad")}


def edit_for(name: str):
    """The edit of the default scenario's data for variant ``name``."""
    parts = VARIANTS[name]

    def edit(d):
        comps = d["model"]["component"]
        if "core" in parts:
            comps["core"].setdefault("params", {}).update(TANK)
        if "orbiter" in parts:
            comps["orbiter"].setdefault("params", {}).update(ORBITER)
        if "pad" in parts:
            d["model"]["pad"].setdefault("params", {}).update(GIRDERS)
        return d

    return edit


def variant_figures(name: str, cache: Path) -> dict:
    """Figures of the default run stiffened as variant ``name``; the FE DOFs, fixed-interface
    modes and cold stage times of the components it may change."""
    fig = runpy.run_path(str(ROOT / "benchmarks" / "default_figures.py"), run_name="default_figures")
    out, wall_s = fig["timed_variant"](edit_for(name), cache)
    stack = next(iter(out.stacks.values()))
    times = {label.split(" (")[0]: s for label, s in out.stage_times if " (built)" in label}
    parts = {}
    for comp in ("core", "orbiter", "pad"):
        parts[comp] = {"fe_dofs": fig["_fe_dofs"](stack.components.get(comp)), "cb_modes": stack.cbs[comp].n_modes,
                       "fe_s": times.get(f"fe {comp}"), "cb_s": times.get(f"cb {comp}")}
    return {**fig["variant_summary"](out, wall_s, "core"), "components": parts, "stiffened": list(VARIANTS[name])}


def main(argv=None) -> int:
    fig = runpy.run_path(str(ROOT / "benchmarks" / "default_figures.py"), run_name="default_figures")
    return fig["compare_main"](argv, __doc__, VARIANTS, variant_figures, JSON, "stiffener_compare")


if __name__ == "__main__":
    sys.exit(main())
