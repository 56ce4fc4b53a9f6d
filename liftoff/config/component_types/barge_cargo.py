"""``type = "barge_cargo"``: an external-tank-like cylinder lying on the barge's saddles (meshes.barge.CargoParams; the barge scenario, docs/barge.md)."""
from __future__ import annotations

from ..params import builder, mesh_size_kw
from ..values import Where
from . import ComponentType, Context


def read(ctx: Context, where: Where, params: dict):
    from liftoff.meshes.barge import CargoParams

    size = mesh_size_kw(ctx.mesh_size)
    return builder(where, CargoParams, params, defaults=size)


TYPE = ComponentType("barge_cargo", read, "liftoff.meshes.barge:build_cargo", "any", "an external-tank-like cylinder lying on the barge's saddles (meshes.barge.CargoParams)")
