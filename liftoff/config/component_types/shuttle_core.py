"""``type = "shuttle_core"``: the Shuttle's external-tank-like core stage
(meshes.vehicle.core_stage_params: LH2 aft, intertank, LOX forward, on the scenario's
StackLayout, with the booster and orbiter attach points). Its params: ``shell_bending_ratio``
(shell walls, 12 I / t^3), ``ullage_pressure`` {lh2, lox} (Pa gauge) and ``attach``
("patch" or "ring"); with shell walls, ring frames and stringers as beams (fem.beam) as
tank_stage's: ``frames = [z, ...]`` (m, on the cylindrical wall), ``frame_section``,
``frame_material``, ``stringers = N``, ``stringer_azimuth`` (deg), ``stringer_section``,
``stringer_material`` (their mass comes off the wall's: the dry mass stays); walls and liquid
are [model]'s."""
from __future__ import annotations

from liftoff.core.errors import InputError

from ..params import MAX_COUNT, beam_members, mesh_size_kw
from ..values import Where, integer, number, string, table
from . import ComponentType, Context

_MEMBERS = {"frame_section", "frame_material", "stringer_section", "stringer_material"}
_PARAMS = {"shell_bending_ratio", "ullage_pressure", "attach", "frames", "stringers", "stringer_azimuth"} | _MEMBERS


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
    members = beam_members(where, params, "core", ("frame", "stringer"))
    frames = params.get("frames", ())
    if not isinstance(frames, (list, tuple)):
        raise (where / "frames").error(f"expected a list of heights (m), got {frames!r}")
    beams = {"frames": tuple(number(where / "frames" / i, z) for i, z in enumerate(frames)),
             "stringers": integer(where / "stringers", params.get("stringers", 0), 0, MAX_COUNT),
             "stringer_azimuth": number(where / "stringer_azimuth", params.get("stringer_azimuth", 0.0)), **members}
    size = mesh_size_kw(ctx.mesh_size)
    try:
        p = core_stage_params(ctx.layout, **size, walls=ctx.walls, shell_bending_ratio=ratio, liquid=ctx.liquid,
                              ullage_pressure=ullage, attach=attach, **beams)
        p.check()
    except InputError as exc:
        raise where.wrap(exc) from None
    return p


TYPE = ComponentType("shuttle_core", read, "liftoff.meshes.tank:build_tank", "vehicle",
                     "the Shuttle's external tank on the StackLayout (meshes.vehicle.core_stage_params)")
