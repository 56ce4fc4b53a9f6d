"""``type = "launch_table"``: a mobile-launcher-platform-like deck on pedestals clamped to
the ground, with hold-down posts under the StackLayout's booster hold-down points
(meshes.pad.PadParams); ``deck = "girders"`` with a ``girder_section`` makes the deck a grid
of girders and the posts and pedestals beams (meshes.platform, fem.beam)."""
from __future__ import annotations

from ..params import beam_section, builder, mesh_size_kw
from ..values import Where
from . import ComponentType, Context


def read(ctx: Context, where: Where, params: dict):
    from liftoff.meshes.pad import PadParams

    fixed = {"layout": ctx.layout}
    if isinstance(params, dict) and "girder_section" in params:
        fixed["girder_section"] = beam_section(where / "girder_section", params["girder_section"])
    size = mesh_size_kw(ctx.mesh_size)
    rest = {k: v for k, v in params.items() if k != "girder_section"} if isinstance(params, dict) else params
    return builder(where, PadParams, rest, fixed, size)


TYPE = ComponentType("launch_table", read, "liftoff.meshes.pad:build_pad", "pad",
                     "the Shuttle's mobile launcher platform on the StackLayout (meshes.pad.PadParams)")
