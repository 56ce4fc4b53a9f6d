"""``type = "barge_hull"``: a barge hull of plates with its cargo cradle and bow fender points (meshes.barge.BargeParams; the barge scenario, docs/barge.md)."""
from __future__ import annotations

from ..params import builder, mesh_size_kw
from ..values import Where
from . import ComponentType, Context


def read(ctx: Context, where: Where, params: dict):
    from liftoff.meshes.barge import BargeParams

    size = mesh_size_kw(ctx.mesh_size)
    return builder(where, BargeParams, params, defaults=size)


TYPE = ComponentType("barge_hull", read, "liftoff.meshes.barge:build_barge", "any", "a barge hull of plates with its cargo cradle and bow fender points (meshes.barge.BargeParams)")
