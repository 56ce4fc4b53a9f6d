"""``type = "shuttle_orbiter"``: the orbiter-like body of the Shuttle stack
(meshes.vehicle.OrbiterParams: fuselage, wing, main-engine mount, payload station, attach
points on the StackLayout). walls default to [model]'s; with shell walls, ``frames = [z, ...]``
(m), ``frame_section`` and ``frame_material`` put ring frames (beams) on the fuselage skin,
and ``stringers = N`` (equally spaced from ``stringer_azimuth``, deg; default half a pitch,
clear of the wing roots at 0 and 180 deg), ``stringer_section`` and ``stringer_material``
stringers along its cylinder."""
from __future__ import annotations

from ..params import beam_members, builder, mesh_size_kw
from ..values import Where
from . import ComponentType, Context


def read(ctx: Context, where: Where, params: dict):
    from liftoff.meshes.vehicle import OrbiterParams

    members = beam_members(where, params, "orbiter", ("frame", "stringer"))
    rest = {k: v for k, v in params.items() if k not in members} if isinstance(params, dict) else params
    size = mesh_size_kw(ctx.mesh_size)
    return builder(where, OrbiterParams, rest, {"layout": ctx.layout, **members}, {**size, "walls": ctx.walls})


TYPE = ComponentType("shuttle_orbiter", read, "liftoff.meshes.vehicle:build_orbiter", "vehicle",
                     "the Shuttle orbiter on the StackLayout (meshes.vehicle.OrbiterParams)")
