"""``type = "beam"``: a component as a stick of Timoshenko beams along its axis (a stage, a
booster, a payload in an early loads cycle; reduction.beam_stick.BeamStick), beside meshed,
Nastran and rigid components; no gmsh, its matrices reduced by the CB stage. Params:
``stations`` (z, m), per segment ``radius``, ``thickness`` (m, a thin-walled tube) and
``mass_per_length`` (kg/m; default rho A), ``E``, ``nu``, ``rho``, ``shear`` [true],
``axis_xy``; ``points = {name = z or [x, y, z]}`` (on the axis, or off it on a stiff link);
``masses = {point = [kg, Ixx, Iyy, Izz]}``. The component's mesh_size is the longest
element (m, default 1)."""
from __future__ import annotations

import numpy as np

from ..params import builder
from ..values import Where, named, number, vector, xyz
from . import ComponentType, Context


def read(ctx: Context, where: Where, params: dict):
    from liftoff.reduction.beam_stick import BeamStick

    if not isinstance(params, dict):
        raise where.error("expected a table of BeamStick fields")
    points = named(where / "points", params.get("points", {}),
                   lambda w, v: xyz(w, v) if isinstance(v, list) else number(w, v))
    masses = named(where / "masses", params.get("masses", {}),
                   lambda w, v: tuple(float(x) for x in vector(w, v, length=4)))
    fixed = {"name": ctx.name, "points": points, "masses": masses}
    if ctx.mesh_size is not None:
        fixed["element_length"] = float(ctx.mesh_size)
    p = builder(where, BeamStick, {k: v for k, v in params.items() if k not in ("points", "masses")}, fixed)
    p.stations = tuple(float(z) for z in np.asarray(p.stations, float))
    return p


TYPE = ComponentType("beam", read, "", "vehicle",
                     "a stick of Timoshenko beams along an axis (reduction.beam_stick.BeamStick)",
                     matrices="liftoff.reduction.beam_stick:beam_stick_component")
