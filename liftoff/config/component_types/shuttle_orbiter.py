"""``type = "shuttle_orbiter"``: the orbiter-like body of the Shuttle stack
(meshes.vehicle.OrbiterParams: fuselage, wing, main-engine mount, payload station, attach
points on the StackLayout). walls default to [model]'s."""
from __future__ import annotations

from ..params import builder, mesh_size_kw
from ..values import Where
from . import ComponentType, Context


def read(ctx: Context, where: Where, params: dict):
    from liftoff.meshes.vehicle import OrbiterParams

    size = mesh_size_kw(ctx.mesh_size)
    return builder(where, OrbiterParams, params, {"layout": ctx.layout}, {**size, "walls": ctx.walls})


TYPE = ComponentType("shuttle_orbiter", read, "liftoff.meshes.vehicle:build_orbiter", "vehicle",
                     "the Shuttle orbiter on the StackLayout (meshes.vehicle.OrbiterParams)")
