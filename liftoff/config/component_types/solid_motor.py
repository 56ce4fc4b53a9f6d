"""``type = "solid_motor"``: a solid rocket motor anywhere, an in-line solid stage or a
strap-on booster (meshes.solid_motor.SolidMotorParams, built as the Shuttle booster is:
case with aft dome and nose, aft skirt, propellant smeared on the case's inner wall, nozzle
at ``<name>_gimbal``), placed by its own ``axis_xy``, ``case_radius``,
``skirt_bottom_radius`` and ``skirt_foot_thickness`` (m), with ``holddown = {name = [x, y,
0]}`` on the skirt's foot ring and ``points = {name = [x, y, z]}`` tied to a patch of the
case wall facing them. ``case_radius``, ``length`` and the masses ``case_mass``,
``skirt_mass``, ``propellant_mass`` and ``nozzle_mass`` (kg) are required: the parameters'
defaults are the Shuttle booster's (499 t of propellant), which a user's motor took without
a word. walls default to [model]'s."""
from __future__ import annotations

from ..params import builder, mesh_size_kw
from ..values import Where, named, require, xyz
from . import ComponentType, Context

#: what a solid motor must give (SolidMotorParams' defaults are the Shuttle booster's)
REQUIRED = {"case_radius": "the case's outer radius (m)", "length": "skirt bottom to nose tip (m)",
            "case_mass": "the case, nose and skirts' structure (kg)", "skirt_mass": "the aft skirt (kg)",
            "propellant_mass": "the propellant (kg)", "nozzle_mass": "the nozzle and its actuators (kg)"}


def read(ctx: Context, where: Where, params: dict):
    from liftoff.meshes.solid_motor import SolidMotorParams

    if not isinstance(params, dict):
        raise where.error("expected a table of SolidMotorParams fields")
    require(where, params, REQUIRED)
    own = {"holddown", "points"}
    fixed = {"motor": ctx.name, "side": "left", "holddown": named(where / "holddown", params.get("holddown", {}), xyz),
             "points": named(where / "points", params.get("points", {}), xyz)}
    size = mesh_size_kw(ctx.mesh_size)
    return builder(where, SolidMotorParams, {k: v for k, v in params.items() if k not in own}, fixed,
                   {**size, "walls": ctx.walls})


TYPE = ComponentType("solid_motor", read, "liftoff.meshes.vehicle:build_booster", "vehicle",
                     "a solid motor anywhere: in-line stage or strap-on booster (meshes.solid_motor)")
