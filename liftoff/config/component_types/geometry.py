"""``type = "geometry"``: a component from the user's own gmsh ``.geo`` / ``.msh`` or
STEP / BREP file, its groups' roles given by name (meshes.user_geometry.GeometryFileParams)::

    [model.component.payload]
    type = "geometry"
    mesh_size = 0.25                                   # m (required for STEP/BREP)
    [model.component.payload.params]
    file = "payload.geo"                               # relative to the scenario
    solids = { adapter = { E = 70e9, nu = 0.33, rho = 2700.0 } }         # volume group -> material
    shells = { skin = { thickness = 0.004, E = 70e9, nu = 0.33, rho = 2700.0 } }
    points = { payload_if = { group = "adapter_bottom" } }               # rigid spider at its centroid
    masses = { sc = { point = "payload_top", mass = 2000.0 } }           # kg (inertia: 3x3 kg m^2)
    clamped = ["foundation"]                                             # surface groups fixed (a pad)
    liquids = { fuel = { density = 800.0, wetted = "fuel_wet", free_surface = "fuel_top" } }
    groups = { adapter = { dim = 3, box = [x0, y0, z0, x1, y1, z1] } }   # STEP/BREP only

A point's ``at = [x, y, z]`` (m) places its reference point (default: the group's centroid);
``tie = "interpolate"`` makes it an RBE3 (no stiffness) instead of a rigid spider. Files are
checked here (exists, readable suffix); groups and roles when the component is built, with
one line naming the file, the group and the key."""
from __future__ import annotations

from pathlib import Path

from liftoff.core.records import geometry_sha256

from ..params import material as read_material
from ..files import file_path
from ..values import Where, integer, named, number, string, strings, table, vector
from . import ComponentType, Context

_KEYS = {"file", "solids", "shells", "points", "masses", "clamped", "liquids", "groups"}
_LIQUID = {"density", "wetted", "free_surface", "cavity", "center", "points"}


def read(ctx: Context, where: Where, params: dict):
    from liftoff.meshes.user_geometry import GeometryFileParams

    p = table(where, params, _KEYS, ("file",))
    path = file_path(where / "file", p["file"], Path(ctx.base)).resolve()
    if not path.is_file():
        raise (where / "file").error(f"file not found: {str(path)!r}")
    materials, shells = {}, {}
    for g, spec in named(where / "solids", p.get("solids", {})).items():
        materials[g], _ = read_material(where / "solids" / g, g, spec)
    for g, spec in named(where / "shells", p.get("shells", {})).items():
        if g in materials:
            raise (where / "shells" / g).error("is a solid too: a group is one or the other")
        materials[g], m = read_material(where / "shells" / g, g, spec, ("thickness",))
        shells[g] = number(where / "shells" / g / "thickness", m["thickness"], positive=True)
    points = {}
    for name, spec in named(where / "points", p.get("points", {})).items():
        w = where / "points" / name
        s = table(w, spec, {"group", "at", "tie"}, ("group",))
        points[name] = {"group": string(w / "group", s["group"]),
                        "at": [float(x) for x in vector(w / "at", s["at"], length=3)] if "at" in s else None,
                        "tie": string(w / "tie", s.get("tie", "rigid"))}
    masses = {}
    for name, spec in named(where / "masses", p.get("masses", {})).items():
        w = where / "masses" / name
        s = table(w, spec, {"point", "mass", "inertia"}, ("point", "mass"))
        inertia = [[0.0] * 3 for _ in range(3)]
        if "inertia" in s:
            rows = s["inertia"]
            if not isinstance(rows, list) or len(rows) != 3:
                raise (w / "inertia").error("expected a 3 x 3 array (kg m^2 about the point)")
            inertia = [[float(x) for x in vector(w / "inertia" / i, r, length=3)] for i, r in enumerate(rows)]
        masses[name] = {"point": string(w / "point", s["point"]), "mass": number(w / "mass", s["mass"], positive=True),
                        "inertia": inertia}
    liquids = {}
    for g, spec in named(where / "liquids", p.get("liquids", {})).items():
        w = where / "liquids" / g
        s = table(w, spec, _LIQUID, ("density", "wetted", "free_surface"))
        liquids[g] = {"density": number(w / "density", s["density"], positive=True),
                      "wetted": string(w / "wetted", s["wetted"]),
                      "free_surface": string(w / "free_surface", s["free_surface"]),
                      **({"cavity": string(w / "cavity", s["cavity"])} if "cavity" in s else {}),
                      **({"center": [float(x) for x in vector(w / "center", s["center"], length=3)]}
                         if "center" in s else {})}
    groups = {}
    for name, spec in named(where / "groups", p.get("groups", {})).items():
        w = where / "groups" / name
        s = table(w, spec, {"dim", "box"}, ("dim", "box"))
        groups[name] = {"dim": integer(w / "dim", s["dim"], 1, 3),
                        "box": [float(x) for x in vector(w / "box", s["box"], length=6)]}
    try:        # the file and, for a .geo, those it merges or includes: the stage cache's key
        digest = geometry_sha256(path)
    except ValueError as exc:
        raise (where / "file").error(str(exc)) from None
    params = GeometryFileParams(
        name=ctx.name, file=str(path), file_sha256=digest, mesh_size=ctx.mesh_size,
        materials=materials, shells=shells, points=points, masses=masses,
        clamped=strings(where / "clamped", p.get("clamped", [])), liquids=liquids, groups=groups,
        origin=f"{where.source}: {where.key}")
    params.check()       # its messages start with origin: the file and the key
    return params


TYPE = ComponentType("geometry", read, "liftoff.meshes.user_geometry:build_user_geometry", "any",
                     "the user's gmsh .geo/.msh or STEP/BREP file, roles by group name (meshes.user_geometry)")
