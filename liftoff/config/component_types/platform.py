"""``type = "platform"``: a launch platform for any vehicle: a deck on pedestals with
hold-down posts whose tops are named points (meshes.platform.PlatformParams). Params:
``posts = {point = [x, y, z]}`` (post tops: where the vehicle's hold-down points stand),
``holes = [[x, y, radius]]``, ``square_holes = [[x, y, half side]]``, ``pedestals = [[x, y]]``, ``deck_size``, ``deck_center_xy``,
``deck_thickness``, ``deck_top_z``, ``post_size``, ``pedestal_size``, ``pedestal_height``,
``mass`` (deck and posts, kg), ``flange_thickness``; ``deck = "girders"`` with
``girder_section = {shape = "i", h = ..., b = ..., tw = ..., tf = ...}`` models the deck as a
grid of girders and the posts and pedestals as beams (fem.beam)."""
from __future__ import annotations

from ..params import beam_section, builder, mesh_size_kw
from ..values import Where, named, xyz
from . import ComponentType, Context


def read(ctx: Context, where: Where, params: dict):
    from liftoff.meshes.platform import PlatformParams

    if not isinstance(params, dict):
        raise where.error("expected a table of PlatformParams fields")
    fixed = {"name": ctx.name, "posts": named(where / "posts", params.get("posts", {}), xyz)}
    for key, what in (("holes", "[x, y, radius]"), ("square_holes", "[x, y, half side]")):
        holes = params.get(key, [])
        if not isinstance(holes, list):
            raise (where / key).error(f"expected an array of {what} (m)")
        fixed[key] = tuple(xyz(where / key / i, h) for i, h in enumerate(holes))
    if "girder_section" in params:
        fixed["girder_section"] = beam_section(where / "girder_section", params["girder_section"])
    size = mesh_size_kw(ctx.mesh_size)
    own = ("posts", "holes", "square_holes", "girder_section")
    return builder(where, PlatformParams, {k: v for k, v in params.items() if k not in own}, fixed, size)


TYPE = ComponentType("platform", read, "liftoff.meshes.platform:build_platform", "pad",
                     "a launch platform with hold-down posts at given points (meshes.platform)")
