"""``type = "launch_table"``: a mobile-launcher-platform-like deck on pedestals clamped to
the ground, with hold-down posts under the StackLayout's booster hold-down points
(meshes.pad.PadParams)."""
from __future__ import annotations

from ..params import builder, mesh_size_kw
from ..values import Where
from . import ComponentType, Context


def read(ctx: Context, where: Where, params: dict):
    from liftoff.meshes.pad import PadParams

    size = mesh_size_kw(ctx.mesh_size)
    return builder(where, PadParams, params, {"layout": ctx.layout}, size)


TYPE = ComponentType("launch_table", read, "liftoff.meshes.pad:build_pad", "pad",
                     "the Shuttle's mobile launcher platform on the StackLayout (meshes.pad.PadParams)")
