"""``type = "barrel"``: a thin-walled interstage, skirt, fairing or payload adapter,
cylindrical or conical, as a shell joined at named points on its end rings
(meshes.barrel.BarrelParams). Params: ``radius_bottom``, ``radius_top``, ``z_bottom``,
``z_top``, ``thickness`` (m), ``material = {E, nu, rho}`` [Al 7075], ``mass`` (kg: the
stiffened barrel's, its density set from it), ``joints_bottom``/``joints_top = {point =
azimuth deg}``, ``bottom_point``/``top_point = {point = z}`` (a whole ring tied to one axis
point), ``point_masses = {point = [kg, Ixx, Iyy, Izz]}``, ``arc_deg``, ``axis_xy``."""
from __future__ import annotations

from ..params import builder, mesh_size_kw
from ..params import material as read_material
from ..values import Where, named, number, vector
from . import ComponentType, Context


def read(ctx: Context, where: Where, params: dict):
    from liftoff.meshes.barrel import BarrelParams

    if not isinstance(params, dict):
        raise where.error("expected a table of BarrelParams fields")
    own = {"joints_bottom", "joints_top", "bottom_point", "top_point", "point_masses", "material"}
    fixed = {"name": ctx.name}
    for key in ("joints_bottom", "joints_top", "bottom_point", "top_point"):
        fixed[key] = named(where / key, params.get(key, {}), number)
    fixed["point_masses"] = named(where / "point_masses", params.get("point_masses", {}),
                                  lambda w, v: [float(x) for x in vector(w, v, length=4)])
    if "material" in params:
        fixed["material"] = read_material(where / "material", f"{ctx.name}-wall", params["material"])[0]
    size = mesh_size_kw(ctx.mesh_size)
    return builder(where, BarrelParams, {k: v for k, v in params.items() if k not in own}, fixed, size)


TYPE = ComponentType("barrel", read, "liftoff.meshes.barrel:build_barrel", "vehicle",
                     "an interstage, skirt, fairing or payload adapter as a shell barrel (meshes.barrel)")
