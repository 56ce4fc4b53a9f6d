"""``type = "shuttle_core"``: the Shuttle's external-tank-like core stage
(meshes.vehicle.core_stage_params: LH2 aft, intertank, LOX forward, on the scenario's
StackLayout, with the booster and orbiter attach points). Its params: ``shell_bending_ratio``
(shell walls, 12 I / t^3), ``ullage_pressure`` {lh2, lox} (Pa gauge) and ``attach``
("patch" or "ring"); walls and liquid are [model]'s."""
from __future__ import annotations

from liftoff.core.errors import InputError

from ..params import mesh_size_kw
from ..values import Where, number, string, table
from . import ComponentType, Context

_PARAMS = {"shell_bending_ratio", "ullage_pressure", "attach"}


def read(ctx: Context, where: Where, params: dict):
    from liftoff.meshes.vehicle import core_stage_params

    extra = sorted(set(params) - _PARAMS)
    if extra:
        raise where.error(f"unknown key {extra[0]!r}: the core stage takes only {', '.join(sorted(_PARAMS))} "
                          "(shell walls); its tank follows from [model.vehicle.params] (StackLayout)")
    ratio = number(where / "shell_bending_ratio", params.get("shell_bending_ratio", 1.0), positive=True)
    ullage = None
    if "ullage_pressure" in params:
        w = where / "ullage_pressure"
        t = table(w, params["ullage_pressure"], {"lh2", "lox"}, ("lh2", "lox"))
        ullage = {k: number(w / k, v, nonneg=True) for k, v in t.items()}
    attach = string(where / "attach", params["attach"]) if "attach" in params else None
    size = mesh_size_kw(ctx.mesh_size)
    try:
        p = core_stage_params(ctx.layout, **size, walls=ctx.walls, shell_bending_ratio=ratio, liquid=ctx.liquid,
                              ullage_pressure=ullage, attach=attach)
        p.check()
    except InputError as exc:
        raise where.wrap(exc) from None
    return p


TYPE = ComponentType("shuttle_core", read, "liftoff.meshes.tank:build_tank", "vehicle",
                     "the Shuttle's external tank on the StackLayout (meshes.vehicle.core_stage_params)")
