"""``type = "shuttle_booster"``: a strap-on solid booster of the Shuttle stack
(meshes.vehicle.BoosterParams: case, aft skirt with its hold-down points, forward and aft
attach points on the StackLayout); ``side`` = "left" or "right" says which of the layout's
two booster positions it takes. walls default to [model]'s."""
from __future__ import annotations

from ..params import builder, mesh_size_kw
from ..values import Where
from . import ComponentType, Context


def read(ctx: Context, where: Where, params: dict):
    from liftoff.meshes.vehicle import BoosterParams

    size = mesh_size_kw(ctx.mesh_size)
    if "side" not in params:
        raise (where / "side").error('missing: which booster position of the layout, "left" (x < 0) or "right"')
    return builder(where, BoosterParams, params, {"layout": ctx.layout}, {**size, "walls": ctx.walls})


TYPE = ComponentType("shuttle_booster", read, "liftoff.meshes.vehicle:build_booster", "vehicle",
                     "a Shuttle solid booster on the StackLayout (meshes.vehicle.BoosterParams)")
