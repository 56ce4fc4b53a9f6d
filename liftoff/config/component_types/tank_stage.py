"""``type = "tank_stage"``: a propellant tank stage of any number of compartments
(meshes.tank.TankParams: cylinder with end domes, compartments joined by intertank skirts,
walls solid or shell, liquids smeared or hydroelastic), with its named points as
``patches = {name = [x, y, z]}`` (m): a point on the axis is a disk patch on the nearest
dome apex (an engine mount, a payload adapter), any other a patch on the cylindrical wall
(an attach fitting, a hold-down point). Compartments bottom to top as
``[[model.component.<name>.params.compartments]]`` (meshes.tank.Compartment fields), the wall
material as ``material = {E, nu, rho}`` (default Al 2219). ``radius``, ``wall_thickness``
(and ``intertank_length`` with two compartments or more) and each compartment's
``cyl_length`` and ``liquid_density`` are required (TankParams' defaults are the Shuttle
external tank's); ``dry_mass`` (kg), if given, sets the wall's density (E scaled with it),
else the material's density makes the mass. walls and liquid default to
[model]'s; the volume groups are named after the component (``<name>_wall``, ...). Shell
walls may carry ring frames and stringers as beams (fem.beam): ``frames = [z, ...]`` (m, on
the cylindrical wall), ``frame_section = {shape = "t", h = ..., b = ..., tw = ..., tf =
...}`` (liftoff.core.beam.SHAPES: tube, rectangle, i, t, hat; m) and ``frame_material =
{E, nu, rho}`` (default: the wall's); ``stringers = N`` (equally spaced from
``stringer_azimuth``, deg), ``stringer_section``, ``stringer_material`` likewise."""
from __future__ import annotations

from ..params import beam_members, builder, mesh_size_kw
from ..params import material as read_material
from ..values import Where, array_of_tables, named, require, xyz
from . import ComponentType, Context

#: what a tank stage must give (meshes.tank.TankParams' defaults are the Shuttle external tank's: a
#: user's stage took them without a word)
REQUIRED = {"radius": "the tank's outer radius (m)", "wall_thickness": "the wall thickness (m)",
            "intertank_length": "the intertank skirt's length between compartments (m)"}
REQUIRED_COMPARTMENT = {"cyl_length": "the compartment's cylinder length (m)",
                        "liquid_density": "the propellant's density (kg/m^3; Compartment's default is LOX's)"}


def read(ctx: Context, where: Where, params: dict):
    from liftoff.meshes.tank import AL2219, Compartment, TankParams

    if not isinstance(params, dict):
        raise where.error("expected a table of TankParams fields")
    own = {"compartments", "patches", "material", "frame_section", "frame_material", "stringer_section",
           "stringer_material"}
    comps = []
    for i, c in enumerate(array_of_tables(where / "compartments", params.get("compartments", []), "compartment",
                                          nonempty=True)):
        if "name" not in c:
            raise (where / "compartments" / i / "name").error("missing: the compartment's name (lox, lh2, rp1, ...)")
        if isinstance(c, dict):
            require(where / "compartments" / i, c, REQUIRED_COMPARTMENT)
        comps.append(builder(where / "compartments" / i, Compartment, c))
    names = [c.name for c in comps]
    if len(set(names)) != len(names):
        raise (where / "compartments").error(f"compartment names repeat: {names}")
    require(where, params, REQUIRED if len(comps) > 1 else
            {k: v for k, v in REQUIRED.items() if k != "intertank_length"})
    patches = named(where / "patches", params.get("patches", {}), xyz)
    material = AL2219 if "material" not in params else \
        read_material(where / "material", f"{ctx.name}-wall", params["material"])[0]
    members = beam_members(where, params, ctx.name, ("frame", "stringer"))
    rest = {k: v for k, v in params.items() if k not in own}
    size = mesh_size_kw(ctx.mesh_size)
    fixed = {"name": ctx.name, "compartments": tuple(comps), "patches": patches, "material": material, **members,
             # not given: the wall weighs what its material's density makes it (TankParams' default, 5.5 t,
             # is the Shuttle LOX tank's, and rescaled a user's density and E to it without a word)
             **({} if "dry_mass" in params else {"dry_mass": None})}
    p = builder(where, TankParams, rest, fixed, {**size, "walls": ctx.walls, "liquid": ctx.liquid})
    _warn_far_axis_points(where, p)
    return p


def _warn_far_axis_points(where: Where, p) -> None:
    """Warn of a point on the axis farther than the tank's radius from the nearer dome apex: it
    is tied to the apex's disk patch by a rigid arm of that length, as a gimbal or an adapter
    below or above the dome is, but a z typed wrong gives one too, silently (a review: a point at
    12 m on a tank whose top apex is at 5.5 m)."""
    import warnings

    import numpy as np

    from liftoff.meshes.tank import tank_height

    z_lo = float(p.z_bottom)
    z_hi = z_lo + tank_height(p)
    for name, ref in p.patches.items():
        ref = np.asarray(ref, float)
        if np.hypot(*(ref[:2] - np.asarray(p.axis_xy, float))) >= 1e-6:
            continue
        z = float(ref[2])
        apex = z_hi if z >= 0.5 * (z_lo + z_hi) else z_lo
        if abs(z - apex) > p.radius:
            msg = (f"on the axis {abs(z - apex):.3g} m from the nearer dome apex (z = {apex:.4g} m), more than the "
                   "tank's radius: a rigid arm of that length ties it to the apex; if it is no gimbal or adapter "
                   "offset, check its z")
            warnings.warn(str((where / "patches" / name).error(msg)), stacklevel=2)


TYPE = ComponentType("tank_stage", read, "liftoff.meshes.tank:build_tank", "vehicle",
                     "a tank stage of any compartments, walls and liquids (meshes.tank.TankParams)")
