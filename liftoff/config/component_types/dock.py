"""``type = "dock"``: a pile-supported quay deck with its fenders (meshes.barge.DockParams; the barge scenario, docs/barge.md)."""
from __future__ import annotations

from ..params import builder, mesh_size_kw
from ..values import Where
from . import ComponentType, Context


def read(ctx: Context, where: Where, params: dict):
    from liftoff.meshes.barge import DockParams

    size = mesh_size_kw(ctx.mesh_size)
    return builder(where, DockParams, params, defaults=size)


TYPE = ComponentType("dock", read, "liftoff.meshes.barge:build_dock", "any", "a pile-supported quay deck with its fenders (meshes.barge.DockParams)")
