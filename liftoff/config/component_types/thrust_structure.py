"""``type = "thrust_structure"``: an engine thrust structure, a conical shell (a thrust cone)
from its ring joined to the stage above to a ring of engine mounts below, each mount carrying
its engine's mass (meshes.barrel.BarrelParams, built as a barrel). Params: ``radius_top``,
``z_top`` (the stage ring), ``radius_bottom``, ``z_bottom`` (the mount ring), ``thickness``
(m), ``mass`` (kg, the structure; its density set from it), ``material = {E, nu, rho}`` [Al
7075]; ``joints = {point = azimuth deg}`` on the top ring (where the stage's patches of the
same names sit); ``mounts = {point = azimuth deg}`` on the bottom ring (the engines'
``mount``s); ``engine_mass`` (kg, each engine, at its mount) and ``engine_inertia = [Ixx,
Iyy, Izz]`` (kg m^2 about the mount); ``arc_deg``, ``axis_xy``. A centre engine on the axis
needs cross beams, which the shell cone does not have: give it its own mount on the stage's
aft dome (a tank_stage patch on the axis)."""
from __future__ import annotations

from ..params import builder, mesh_size_kw
from ..params import material as read_material
from ..values import Where, named, number, vector
from . import ComponentType, Context

OWN = {"joints", "mounts", "engine_mass", "engine_inertia", "material"}


def read(ctx: Context, where: Where, params: dict):
    from liftoff.meshes.barrel import BarrelParams

    if not isinstance(params, dict):
        raise where.error("expected a table of thrust structure parameters")
    for key in ("joints", "mounts", "engine_mass"):
        if key not in params:
            raise (where / key).error("missing: " + {
                "joints": "the points joining the stage, {point = azimuth deg} on the top ring",
                "mounts": "the engine mounts, {point = azimuth deg} on the bottom ring",
                "engine_mass": "each engine's mass (kg), at its mount"}[key])
    mounts = named(where / "mounts", params["mounts"], number)
    if not mounts:
        raise (where / "mounts").error("no mounts: a thrust structure carries at least one engine")
    m = number(where / "engine_mass", params["engine_mass"], positive=True)
    inertia = [float(x) for x in vector(where / "engine_inertia", params.get("engine_inertia", [0.0, 0.0, 0.0]),
                                        length=3, nonneg=True)]
    barrel = {k: v for k, v in params.items() if k not in OWN}
    for key in ("joints_top", "joints_bottom", "top_point", "bottom_point", "point_masses"):
        if key in barrel:
            raise (where / key).error("not a thrust structure key (joints, mounts, engine_mass, engine_inertia)")
    fixed = {"name": ctx.name, "joints_top": named(where / "joints", params["joints"], number), "joints_bottom": mounts,
             "point_masses": {n: [m, *inertia] for n in mounts}}
    if "material" in params:
        fixed["material"] = read_material(where / "material", f"{ctx.name}-wall", params["material"])[0]
    return builder(where, BarrelParams, barrel, fixed, mesh_size_kw(ctx.mesh_size))


TYPE = ComponentType("thrust_structure", read, "liftoff.meshes.barrel:build_barrel", "vehicle",
                     "an engine thrust cone with engine mounts and engine masses (meshes.barrel)")
