"""``[model]`` of a lift-off scenario: the vehicle and the pad as components of registered
types, the joints between them, and how to reduce them; checked when the file is read
(before anything is meshed).

* ``[model.component.<name>]``, any number, any names: the vehicle, assembled free-free in
  the order given. Each has a ``type`` (liftoff.config.component_types: ``shuttle_core``,
  ``shuttle_booster``, ``shuttle_orbiter``, ``tank_stage``, ``geometry`` (the user's own
  file), ... or ``nastran`` with a ``nastran`` table), its ``params`` (the type's builder
  dataclass, checked by the type), ``mesh_size`` (m), and the fixed-interface modes kept
  (``n_modes``/``f_max``).
* ``[model.pad]``: the grounded body the hold-down posts stand on, the same way
  (``launch_table``, ``geometry`` or ``nastran``).
* ``[[model.joint]]``: a named point shared by two or more vehicle components (the
  components overlay it, as the attach points of the Shuttle stack); every point that two
  components share must be a joint, and the joints must connect the vehicle. ``release``
  (DOF names, global axes: ``["Tz"]``, ``["Rx", "Ry", "Rz"]``): the directions the joint
  does not connect; the first component keeps the point's DOF there, each other one its own
  (``point@component:Tz``; reduction.assembly), so no force passes that way (a ball joint,
  a strut's line of action, a slip joint).
* ``[model.vehicle.params]``: :class:`meshes.layout.StackLayout`, the positions the Shuttle
  types (and the stick source) share;
* source ``"stick"``: the Shuttle's four components and pad as beams from one
  ``[model.stick]`` :class:`meshes.stick.StickParams` (no types);
* ``[model.materials.<volume>]``: :class:`meshes.spec.Material` replacing a volume group's
  material (volume names are checked against the geometry once it is built).

Units SI: m, Hz, Pa, kg/m^3.
"""
from __future__ import annotations

import dataclasses
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from liftoff.core.errors import InputError
from liftoff.core.labels import COMPONENTS
from liftoff.core.units import G0
from liftoff.meshes.layout import ATTACH_OPTIONS, StackLayout
from liftoff.meshes.pad import PadParams
from liftoff.meshes.spec import Material
from liftoff.meshes.stick import StickParams

from . import component_types
from .params import builder, material
from .files import file_path
from .values import Where, array_of_tables, boolean, integer, named, number, string, strings, table, unique_name

SOURCES = ("fe", "stick")
STICK_VEHICLE = ("core", "srb_left", "srb_right", "orbiter")   # the stick source's components (workflows/stick.py)
PAD = "pad"                 # the pad's component name ([model.pad])
DEFAULT_F_MAX = 60.0        # Hz, fixed-interface modes kept when neither n_modes nor f_max is given
STICK_ELEMENT = 4.0         # m, default beam element length of the stick source
# the most elements one component may have, estimated before it is built ([model] max_elements):
# a million P1 tetrahedra (~0.6 M DOFs: the limit of a sparse direct solve on a workstation),
# two thousand beams per axis (2 cm on the 47 m core: finer is meaningless for a stick, and the
# conditioning of K_ii, ~(L/h)^4, then puts the Craig-Bampton round-off above the free-free
# check of reduction/system.py: K RB 2e-6 at 1 cm elements)
MAX_ELEMENTS = {"fe": 1_000_000, "stick": 2_000}

_MODEL = {"source", "mesh_size", "degree", "zeta", "vehicle", "pad", "component", "materials", "system", "stick",
          "walls", "max_elements", "liquid", "convective", "slosh_gravity", "joint"}
WALLS = ("solid", "shell")
LIQUIDS = ("smeared", "hydroelastic")     # [model] liquid: the core stage's propellants (meshes.tank)
CONVECTIVE = ("wall", "free", "slosh")    # [model] convective: a hydroelastic liquid's sloshing part (fem.liquid, fem.slosh)
#: [model] slosh_gravity (m/s^2): the apparent axial acceleration g_eff of the slosh modes
#: (1 g on the pad); the range a launch vehicle's axial acceleration spans (0.1 g coasting
#: to 10 g), beyond which the rigid-tank slosh frequencies sqrt(g_eff) mean nothing here
SLOSH_GRAVITY_RANGE = (0.1 * G0, 10.0 * G0)
_VEHICLE = {"mesh_size", "params"}
_COMP = {"type", "mesh_size", "n_modes", "f_max", "residual_vectors", "params", "nastran", "mirror"}
_MIRROR = {"of", "normal"}
_JOINT = {"name", "components", "release"}
_NASTRAN = {"file", "units", "grids", "asm", "pch", "op4", "bulk", "stiffness", "mass", "se", "recovery"}
_NASTRAN_FILES = ("file", "asm", "pch", "op4", "bulk")
_NASTRAN_RECOVERY = {"name", "disp", "vel", "acc", "rows", "quantity"}
_SYSTEM = {"n_modes", "f_max", "pad_n_modes", "pad_f_max", "residual_vectors"}


@dataclass(frozen=True)
class NastranSource:
    """A component that comes from a Nastran Craig-Bampton model instead of a builder
    (``[model.component.<name>.nastran]``, read by liftoff.reduction.nastran.import_nastran):
    ``file`` (.op4 EXTSEOUT, .pch/.dmig/.bdf DMIG or .op2 nas2cam; absolute path), the
    model's ``units`` (a name such as "in-lbf-s" or SI factors {length, mass, time[, force]}),
    ``grid_names`` (grid ID -> point name of the stack; others are ``g<ID>``), the reader's
    ``options`` (asm, pch, op4, bulk paths; stiffness, mass matrix names; se) and
    ``recovery`` (OUTPUT4 recovery items: name, disp/vel/acc matrix names, rows, quantity)."""

    file: str
    units: Any
    grid_names: dict
    options: dict
    recovery: tuple = ()

    def files(self) -> list[str]:
        """Every file the import reads (for the cache key): those the scenario names and those
        the readers take from beside ``file`` by default (an .op4's .asm, and its .pch where
        there is one; an .op2's .op4), which a key of the named ones alone missed: an edited
        .asm or a .pch added beside the .op4 reused the old model."""
        named = [self.file] + [v for k, v in sorted(self.options.items()) if k in _NASTRAN_FILES]
        main, implied = Path(self.file), []
        if main.suffix.lower() == ".op4":
            if "asm" not in self.options:
                implied.append(main.with_suffix(".asm"))
            if "pch" not in self.options and main.with_suffix(".pch").is_file():
                implied.append(main.with_suffix(".pch"))
        elif main.suffix.lower() == ".op2" and "op4" not in self.options:
            implied.append(main.with_suffix(".op4"))
        return named + [str(f) for f in implied if f.is_file()]


@dataclass(frozen=True)
class Mirror:
    """A component that is the mirror image of vehicle component ``of`` in the plane through
    the origin normal to axis ``normal`` ("x", "y" or "z"): its FE and Craig-Bampton models
    are the source's reflected (liftoff.reduction.mirror), its points and volumes named by
    replacing the source's name with its own."""

    of: str
    normal: str


@dataclass(frozen=True)
class ComponentModel:
    """One component's model: its ``type`` (liftoff.config.component_types; "nastran";
    "stick"), its builder's parameters (the type's dataclass; None for a Nastran model),
    mesh size (m; stick: beam element length; None: the builder's default) and the
    fixed-interface modes kept by Craig-Bampton (the first ``n_modes``, at most ``f_max``
    Hz; None: no limit), with ``residual_vectors`` the static response to the boundary
    accelerations' inertia loads appended (reduction.craig_bampton, Nastran's RESVEC)."""

    name: str
    builder: Any               # the type's parameter dataclass (fe); StickParams (stick); None (nastran)
    mesh_size: float | None = None
    n_modes: int | None = None
    f_max: float | None = None
    nastran: NastranSource | None = None
    type: str = ""
    mirror: Mirror | None = None       # the source's model reflected, not built (then builder is None)
    residual_vectors: bool = False


@dataclass(frozen=True)
class Joint:
    """A point (label prefix ``name``) that the vehicle ``components`` share and overlay,
    except in the ``release`` directions (DOF names, global axes), where each component
    after the first keeps a DOF of its own (reduction.assembly)."""

    name: str
    components: tuple[str, ...]
    release: tuple[str, ...] = ()

    def released(self) -> set[tuple[str, str]]:
        """(component, label) pairs that reduction.assembly.assemble does not overlay."""
        return {(c, f"{self.name}:{d}") for c in self.components[1:] for d in self.release}


@dataclass(frozen=True)
class SystemModel:
    """System modes kept: vehicle (free-free) ``n_modes``/``f_max`` (Hz), pad
    ``pad_n_modes``/``pad_f_max``; None: all (the default, as the reference's section 3.0).
    ``residual_vectors``: where modes are cut, append the residual vectors of every boundary
    DOF and of gravity (reduction/truncation.py), so the static flexibility stays exact."""

    n_modes: int | None = None
    f_max: float | None = None
    pad_n_modes: int | None = None
    pad_f_max: float | None = None
    residual_vectors: bool = True


@dataclass(frozen=True)
class ModelConfig:
    """``[model]``: source ``fe`` (gmsh + dolfinx solids) or ``stick`` (beams), element
    ``degree``, modal damping ratio ``zeta`` of every elastic mode, the components (the
    ``vehicle``'s, in assembly order, and the pad, :data:`PAD`), the ``joints`` between vehicle
    components, material replacements and system modes;
    ``max_elements``: the most elements a component may have (estimated before it is built;
    default MAX_ELEMENTS of the source)."""

    source: str
    degree: int
    zeta: float
    layout: StackLayout
    components: dict[str, ComponentModel]
    materials: dict[str, Material]
    system: SystemModel
    max_elements: int = MAX_ELEMENTS["fe"]
    convective: str = "wall"      # hydroelastic liquids' sloshing part: "slosh" pendulums, on the "wall" or "free"
    slosh_gravity: float = G0     # convective = "slosh": g_eff of the slosh modes, m/s^2
    vehicle: tuple[str, ...] = ()      # the vehicle's components, in assembly order
    joints: tuple[Joint, ...] = ()


# ---------------------------------------------------------------- [model]
def unit_system_at(where: Where, units: Any):
    """The reduction.nastran UnitSystem a ``units`` key gives (a system's name or a table of
    SI factors: length, mass, time, force), its one-line error naming file and key."""
    from liftoff.reduction.nastran import unit_system

    return unit_system(units if isinstance(units, str) else table(where, units, {"length", "mass", "time", "force"}),
                       f"{where.source}: {where.key}")


def _nastran(where: Where, spec: Any, base: Path) -> NastranSource:
    """``[model.component.<name>.nastran]``, files checked and units understood when read."""
    from liftoff.reduction.nastran import same_units, stated_units

    n = table(where, spec, _NASTRAN, required=("file", "units"))
    paths = {}
    for key in _NASTRAN_FILES:
        if key in n:
            p = file_path(where / key, n[key], base).resolve()
            if not p.is_file():
                raise (where / key).error(f"file not found: {str(p)!r}")
            paths[key] = str(p)
    units, wu = n["units"], where / "units"
    given = unit_system_at(wu, units)
    for key in ("file", "pch"):                  # a punch that states its units (liftoff's write_dmig does)
        stated = stated_units(paths[key]) if key in paths else None
        if stated is not None and not same_units(stated, given):
            raise wu.error(f"{Path(paths[key]).name} states its units as {stated.describe()}, not "
                           f"{given.describe()}")
    grids = named(where / "grids", n.get("grids", {}))
    names: dict[int, str] = {}
    for gid, name in grids.items():
        if not re.fullmatch(r"[1-9][0-9]{0,17}", str(gid)):          # (str.isdigit takes superscripts)
            raise (where / "grids").error(f"key {gid!r} is not a grid ID (a positive integer)")
        if int(gid) in names:
            raise (where / "grids").error(f"grid {int(gid)} is given twice (as {gid!r})")
        names[int(gid)] = unique_name(where / "grids" / str(gid), name, set(names.values()), "point")
    options = {k: paths.get(k, n.get(k)) for k in ("asm", "pch", "op4", "bulk", "stiffness", "mass", "se")
               if k in n}
    for k in ("stiffness", "mass"):
        if k in options:
            string(where / k, options[k])
    if str(options.get("mass", "MAAX")).upper() == str(options.get("stiffness", "KAAX")).upper():
        raise (where / "mass").error(f"names the stiffness matrix {options.get('stiffness', 'KAAX')!r}: give the mass "
                                     "matrix's name (MAAX by default)")
    if "se" in options:
        options["se"] = integer(where / "se", options["se"], 1)
    recovery, item_names = [], set()
    for i, r in enumerate(array_of_tables(where / "recovery", n.get("recovery", []), "nastran.recovery")):
        wr = where / "recovery" / i
        r = dict(table(wr, r, _NASTRAN_RECOVERY, required=("name",)))
        unique_name(wr / "name", r["name"], item_names, "recovery item")
        for key in ("disp", "vel", "acc"):          # OUTPUT4 matrix names (they were read only when built)
            if key in r:
                string(wr / key, r[key])
        if not any(k in r for k in ("disp", "vel", "acc")):
            raise wr.error("give at least one of disp, vel, acc (OUTPUT4 matrix names)")
        for key in ("rows", "quantity"):             # one name, or one per row
            if key in r and not isinstance(r[key], str):
                r[key] = strings(wr / key, r[key], nonempty=True)
        recovery.append(r)
    return NastranSource(paths["file"], units, names, options, tuple(recovery))


def _sizes(where: Where, spec: dict, keys: set[str], base: Path = Path(".")) -> dict:
    """type, mesh_size (m), n_modes, f_max (Hz) of a [model.component.*] / [model.pad] /
    [model.vehicle] table, and a Nastran source if it has one."""
    c = table(where, spec, keys)
    out = {"params": c.get("params", {})}
    if "mirror" in c:
        others = sorted(set(c) - {"mirror"})
        if others:
            raise (where / others[0]).error("a mirror takes its source's model: no type, params, mesh_size, modes or "
                                            "nastran of its own")
        mt = table(where / "mirror", c["mirror"], _MIRROR, required=("of", "normal"))
        normal = string(where / "mirror" / "normal", mt["normal"])
        if normal not in ("x", "y", "z"):
            raise (where / "mirror" / "normal").error(f"{normal!r}: give x, y or z (the plane through the origin "
                                                      "normal to that axis)")
        out["mirror"] = Mirror(string(where / "mirror" / "of", mt["of"]), normal)
        return out
    if "type" in c:
        out["type"] = string(where / "type", c["type"])
    if "residual_vectors" in c:
        out["residual_vectors"] = boolean(where / "residual_vectors", c["residual_vectors"])
        if out["residual_vectors"] and ("nastran" in c or out.get("type") == component_types.NASTRAN):
            raise (where / "residual_vectors").error("a Nastran component's modes are Nastran's: give its residual "
                                                     "vectors there (RESVEC), not here")
    if "nastran" in c:
        if out.setdefault("type", component_types.NASTRAN) != component_types.NASTRAN:
            raise (where / "nastran").error(f"a Nastran model is type = {component_types.NASTRAN!r}, not "
                                            f"{out['type']!r} (set type = {component_types.NASTRAN!r})")
        out["nastran"] = _nastran(where / "nastran", c["nastran"], base)
        if out["params"] or "mesh_size" in c:
            raise (where / "nastran").error("a Nastran component takes no builder params or mesh_size")
    elif out.get("type") == component_types.NASTRAN:
        raise (where / "nastran").error("missing: a type = 'nastran' component needs its [nastran] table (file, units, "
                                        "grids)")
    if "mesh_size" in c:
        out["mesh_size"] = number(where / "mesh_size", c["mesh_size"], positive=True)
    if "n_modes" in c:
        out["n_modes"] = integer(where / "n_modes", c["n_modes"], 0)
    if "f_max" in c:
        out["f_max"] = number(where / "f_max", c["f_max"], positive=True)
    if not isinstance(out["params"], dict):
        raise (where / "params").error("expected a table of builder parameters")
    return out


def _check_residual_vectors(where: Where, components: dict) -> None:
    """``residual_vectors`` only where the CB stage reduces a component that takes them: not a
    type whose CB model is given directly (nothing to reduce), not a hydroelastic liquid's
    component (its mass is not M alone: reduction.craig_bampton refuses it after the FE build)."""
    for name, c in components.items():
        if not c.residual_vectors:
            continue
        w = (where / PAD if name == PAD else where / "component" / name) / "residual_vectors"
        t = component_types.types().get(c.type)
        if t is not None and t.model:
            raise w.error(f"a {c.type!r} component's Craig-Bampton model is given directly, with no interior to "
                          "reduce: residual vectors do not apply")
        if getattr(c.builder, "liquid", "") == "hydroelastic":
            raise w.error("not for a component with a hydroelastic liquid (its mass is not M alone); give it "
                          "without residual vectors or with liquid = \"smeared\"")


def _fe_builders(where: Where, ctx: dict, sel: dict[str, dict], size: dict[str, float | None],
                 vehicle: tuple[str, ...]) -> dict:
    """The builder dataclass of every FE component, read by its registered type
    (liftoff.config.component_types); None for a Nastran one."""
    out = {}
    for name in vehicle + (PAD,):
        w = where / "component" / name if name != PAD else where / PAD
        if "mirror" in sel[name]:
            out[name] = None                 # the source's model, reflected (_mirrors)
            continue
        kind = sel[name].get("type")
        if kind is None:
            raise (w / "type").error("missing: the component's type (" + ", ".join(
                sorted(component_types.types())) + f", or {component_types.NASTRAN!r} with a [nastran] table)")
        if kind == component_types.NASTRAN:
            out[name] = None
            continue
        try:
            t = component_types.get(kind, "pad" if name == PAD else "vehicle")
        except InputError as exc:
            raise (w / "type").wrap(exc) from None
        out[name] = t.read(component_types.Context(name, size[name], **ctx, mesh_size_given="mesh_size" in sel[name]),
                           w / "params", sel[name]["params"])
    return out


def _stick_builders(where: Where, layout: StackLayout, sel: dict[str, dict], spec: Any) -> dict:
    """One StickParams (beams) for all five components; the pad's geometry from PadParams."""
    for name in STICK_VEHICLE + (PAD,):
        if "mirror" in sel[name]:
            w = where / "component" / name if name != PAD else where / PAD
            raise (w / "mirror").error("the stick source builds the Shuttle's components as beams: no mirrors")
        if sel[name].get("type", component_types.NASTRAN) != component_types.NASTRAN:
            w = where / "component" / name if name != PAD else where / PAD
            raise (w / "type").error("the stick source builds the Shuttle's components as beams: it takes no type")
    for name in STICK_VEHICLE:
        if sel[name]["params"]:
            raise (where / "component" / name / "params").error(
                "the stick source takes no per-component parameters: write StickParams fields in [model.stick]")
    pad = builder(where / PAD / "params", PadParams, sel[PAD]["params"], {"layout": layout})
    stick = builder(where / "stick", StickParams, spec, {"pad": pad})
    return {name: stick for name in STICK_VEHICLE + (PAD,)}


#: the Shuttle's booster attach joints, statically determinate (the default scenario's): a
#: spherical bearing forward (forces only) and three struts aft in a plane across the axis (Tx, Ty
#: and the couple Rz), so the thrust and the tank's weight pass forward and its cryo shrinkage
#: strains no attach
SRB_ATTACH_RELEASE = {"fwd": ("Rx", "Ry", "Rz"), "aft": ("Tz", "Rx", "Ry")}
#: the orbiter's attach joints, one forward and two aft bipods (two pin-ended struts meeting at
#: a spherical fitting: forces in the struts' plane only), statically determinate (the default
#: scenario's): the forward struts splay across the vehicle (Tx, Ty), each aft pair lies in the
#: plane of the axis and the orbiter's offset (Ty, Tz), so the main engines' thrust passes aft
ORBITER_ATTACH_RELEASE = {"fwd": ("Tz", "Rx", "Ry", "Rz"), "aft": ("Tx", "Rx", "Ry", "Rz")}


def shuttle_joints(layout: StackLayout) -> tuple[Joint, ...]:
    """The Shuttle stack's joints on ``layout``: each booster's attach points with the core,
    released as :data:`SRB_ATTACH_RELEASE`, and the orbiter's, released as
    :data:`ORBITER_ATTACH_RELEASE` (those of the stick source; the default scenario lists the
    same)."""
    out = [Joint(p, ("core", f"srb_{side}"), SRB_ATTACH_RELEASE[p.rsplit("_", 1)[-1]])
           for side in ("left", "right") for p in layout.srb_attach_points(side)]
    return tuple(out + [Joint(p, ("core", "orbiter"), ORBITER_ATTACH_RELEASE["fwd" if p.endswith("fwd") else "aft"])
                        for p in layout.orbiter_attach_points()])


#: what the stick source, which joins each component at one point, says of an attach option set
_STICK_REFUSES = {"srb_aft_attach": "the stick model joins each booster at one aft point: the aft struts need "
                                    "source = \"fe\"",
                  "orbiter_attach": "the stick model joins the orbiter at its attach points: the bipods need "
                                    "source = \"fe\"",
                  "srb_fwd_attach": "the stick model joins each booster at one forward point: the thrust beam "
                                    "needs source = \"fe\""}


def _check_layout_joints(where: Where, layout: StackLayout, joints, components: dict) -> None:
    """Before any meshing: a joint on a Shuttle type (shuttle_core, shuttle_booster or its
    mirror, shuttle_orbiter) at one of the points the layout's attach options place or move
    (StackLayout.option_point_names; not the hold-downs or any other point) that this layout
    gives that component not, named with the option that moved it (``srb_aft_attach =
    "struts"`` alone leaves the default's att_srb_<side>_aft joints on points the tank and
    boosters no longer have)."""
    every = layout.option_point_names()         # (names only: an option not set places nothing)
    core = {p for s in ("left", "right") for p in layout.srb_core_points(s)} | set(layout.orbiter_core_points())

    def points(name: str):
        c = components.get(name)
        kind = c.type if c is not None else ""
        if kind == "shuttle_core":
            return core
        if kind == "shuttle_booster":
            return set(layout.srb_booster_points(c.builder.side))
        if kind == "shuttle_orbiter":
            return set(layout.orbiter_attach_points())
        if c is not None and c.mirror is not None and components.get(c.mirror.of) is not None \
                and components[c.mirror.of].type == "shuttle_booster":
            src = c.mirror.of
            return {p.replace(src, name) for p in layout.srb_booster_points(components[src].builder.side)}
        return None

    moved = ", ".join(f"{k} = {getattr(layout, k)!r}" for k, v in ATTACH_OPTIONS.items() if getattr(layout, k) != v[0])
    for i, j in enumerate(joints):
        if j.name not in every:
            continue
        for c in j.components:
            have = points(c)
            if have is not None and j.name not in have:
                raise (where / i).error(f"joint {j.name!r}: component {c!r} has no point {j.name!r} on this "
                                        f"layout ([model.vehicle.params] {moved or 'defaults'}; its interface "
                                        f"points: {', '.join(sorted(have))}): docs/workflow.md gives the joints "
                                        "of each attach option")


def _check_pinned_releases(where: Where, joints, components: dict) -> None:
    """Before any meshing: a joint that releases a rotation of a pinned strut (``type =
    "strut"``, ``pinned = true``), whose ends have none (reduction.strut), named."""
    for i, j in enumerate(joints):
        rot = [d for d in j.release if d.startswith("R")]
        for c in j.components[1:]:
            comp = components.get(c)
            if comp is not None and comp.mirror is not None:          # a mirror's is its source's
                comp = components.get(comp.mirror.of)
            if rot and comp is not None and comp.type == "strut" and getattr(comp.builder, "pinned", False):
                raise (where / i).error(f"joint {j.name!r} releases {' '.join(rot)} of {c!r}, a pinned strut, whose "
                                        "ends are translations only (it passes no moment already): release no "
                                        "rotation for it, or list it first")


def _vehicle_names(where: Where, comps: dict, source: str) -> tuple[str, ...]:
    """The vehicle's component names, in the order given (the stick source: the Shuttle's)."""
    wc = where / "component"
    if source == "stick":
        extra = sorted(set(comps) - set(STICK_VEHICLE))
        if extra:
            raise (wc / extra[0]).error(f"the stick source builds the Shuttle's components only "
                                        f"({', '.join(STICK_VEHICLE)})")
        return STICK_VEHICLE
    if not comps:
        raise wc.error("no components: list the vehicle's as [model.component.<name>] with a type")
    seen: set[str] = set()
    for name in comps:
        unique_name(wc / name, name, seen, "component")
        if name == PAD:
            raise (wc / name).error("'pad' is the pad's name: describe it in [model.pad]")
        seen.add(name)
    return tuple(comps)


def _joints(where: Where, spec: Any, vehicle: tuple[str, ...]) -> tuple[Joint, ...]:
    """[[model.joint]]: names unique, components of the vehicle, and together connecting it
    (a component joined to no other would float free: singular system modes)."""
    out, seen = [], set()
    for i, j in enumerate(array_of_tables(where, spec, "model.joint")):
        w = where / i
        j = table(w, j, _JOINT, ("name", "components"))
        name = unique_name(w / "name", j["name"], seen, "joint")
        seen.add(name)
        comps = strings(w / "components", j["components"], nonempty=True)
        for c in comps:
            if c not in vehicle:
                raise (w / "components").error(f"{c!r} is not a vehicle component ({', '.join(vehicle)})")
        if len(set(comps)) < 2:
            raise (w / "components").error("a joint joins two or more different components")
        out.append(Joint(name, tuple(comps), _release(w / "release", j.get("release", []))))
    if len(vehicle) > 1:
        reached, todo = {vehicle[0]}, [vehicle[0]]
        while todo:
            c = todo.pop()
            for j in out:
                if c in j.components:
                    for o in j.components:
                        if o not in reached:
                            reached.add(o)
                            todo.append(o)
        lone = [c for c in vehicle if c not in reached]
        if lone:
            raise where.error(f"component {lone[0]!r} is joined to none of {vehicle[0]!r}'s: give a "
                              f"[[model.joint]] with components = [..., {lone[0]!r}] (the vehicle must hang together)")
    return tuple(out)


def _release(where: Where, spec: Any) -> tuple[str, ...]:
    """A joint's ``release``: distinct DOF names (Tx Ty Tz Rx Ry Rz), not all six."""
    dofs = strings(where, spec)
    for d in dofs:
        if d not in COMPONENTS:
            raise where.error(f"{d!r} is not a DOF name ({', '.join(COMPONENTS)}: global axes)")
    if len(set(dofs)) < len(dofs):
        raise where.error("a DOF is named twice")
    if len(dofs) == len(COMPONENTS):
        raise where.error("all six DOFs released: the joint would connect nothing (remove it, or the point "
                          "from one component)")
    return tuple(d for d in COMPONENTS if d in dofs)


# keys of the stick model's [model.vehicle.params] (workflows.stick.StackParams) before the
# layout was shared: where they are now
_OLD_STICK = {"holddown_radius": "[model.vehicle.params] srb_skirt_radius - srb_skirt_thickness / 2",
              "pad_mass": "[model.pad.params] mlp_mass", "deck_top_z": "[model.pad.params] post_height (deck top "
              "at z = -post_height)", "deck_thickness": "[model.pad.params] deck_thickness",
              "pedestal_height": "[model.pad.params] pedestal_height", "pedestal_xy": "[model.pad.params] pedestal_xy"}


def _layout(where: Where, spec: Any, source: str) -> StackLayout:
    if source == "stick" and isinstance(spec, dict):
        stick_only = {f.name for f in dataclasses.fields(StickParams)} - {f.name for f in dataclasses.fields(StackLayout)}
        for key in spec:
            if key in stick_only:
                raise (where / key).error("a stick-model parameter (StickParams): write it in [model.stick]")
            if key in _OLD_STICK:
                raise (where / key).error(f"the stick model takes this from {_OLD_STICK[key]}")
        for key, message in _STICK_REFUSES.items():
            if spec.get(key, ATTACH_OPTIONS[key][0]) != ATTACH_OPTIONS[key][0]:
                raise (where / key).error(message)
    return builder(where, StackLayout, spec)


def _materials(where: Where, spec: Any, source: str) -> dict[str, Material]:
    if not isinstance(spec, dict):
        raise where.error("expected a table of volume -> {E, nu, rho}")
    if spec and source == "stick":
        raise where.error("the stick source has no material volumes (beam properties are in [model.stick])")
    return {vol: material(where / vol, vol, mat)[0] for vol, mat in spec.items()}


def model_config(where: Where, spec: Any, base: Path | str = ".") -> ModelConfig:
    """``[model]`` -> :class:`ModelConfig` (every builder parameter checked; Nastran files
    relative to ``base``, the scenario's folder)."""
    base = Path(base)
    m = table(where, spec, _MODEL)
    source = string(where / "source", m.get("source", "fe"))
    if source not in SOURCES:
        raise (where / "source").error(f"unknown model source {source!r} (use {' or '.join(SOURCES)})")
    degree = m.get("degree", 1)
    if isinstance(degree, bool) or not isinstance(degree, int) or degree not in (1, 2):     # (2.0 is no degree)
        raise (where / "degree").error(f"element degree must be 1 or 2, got {degree!r}")
    zeta = number(where / "zeta", m.get("zeta", 0.01), nonneg=True)
    if zeta >= 1:
        raise (where / "zeta").error(f"modal damping ratio must be < 1, got {zeta:g}")
    size = number(where / "mesh_size", m["mesh_size"], positive=True) if "mesh_size" in m else None
    if source == "stick":
        size = size or STICK_ELEMENT
    elif "stick" in m:
        raise (where / "stick").error("[model.stick] is for source = \"stick\"")
    vehicle = _sizes(where / "vehicle", m.get("vehicle", {}), _VEHICLE)
    comps = named(where / "component", m.get("component", {}))
    names = _vehicle_names(where, comps, source)
    sel = {name: _sizes(where / "component" / name, comps.get(name, {}), _COMP, base) for name in names}
    sel[PAD] = _sizes(where / PAD, m.get(PAD, {}), _COMP, base)
    sizes = {name: sel[name].get("mesh_size", vehicle.get("mesh_size") if name != PAD else None) or size
             for name in names + (PAD,)}
    layout = _layout(where / "vehicle" / "params", vehicle["params"], source)
    walls = string(where / "walls", m.get("walls", "solid"))
    if walls not in WALLS:
        raise (where / "walls").error(f"must be one of {', '.join(WALLS)}, got {walls!r}")
    if source == "stick" and "degree" in m:
        raise (where / "degree").error("[model] degree is for source = \"fe\" (the stick model has beams); "
                                       "it would be silently ignored")
    if source == "stick" and "mesh_size" in sel[PAD]:
        raise (where / PAD / "mesh_size").error("the stick source's pad is not meshed (a lumped model): "
                                                "it would be silently ignored")
    if source == "stick" and "walls" in m:
        raise (where / "walls").error("[model] walls is for source = \"fe\" (the stick model has beams)")
    liquid = string(where / "liquid", m.get("liquid", "smeared"))
    if liquid not in LIQUIDS:
        raise (where / "liquid").error(f"must be one of {', '.join(LIQUIDS)}, got {liquid!r}")
    if source == "stick" and "liquid" in m:
        raise (where / "liquid").error("[model] liquid is for source = \"fe\" (the stick model has lumped masses)")
    convective = string(where / "convective", m["convective"]) if "convective" in m else None
    if convective is not None and convective not in CONVECTIVE:
        raise (where / "convective").error(f"must be one of {', '.join(CONVECTIVE)}, got {convective!r}")
    slosh_gravity = number(where / "slosh_gravity", m.get("slosh_gravity", G0), positive=True)
    if not SLOSH_GRAVITY_RANGE[0] <= slosh_gravity <= SLOSH_GRAVITY_RANGE[1]:
        raise (where / "slosh_gravity").error(
            f"must lie in [{SLOSH_GRAVITY_RANGE[0]:.4g}, {SLOSH_GRAVITY_RANGE[1]:.4g}] m/s^2 (0.1 to 10 g), "
            f"got {slosh_gravity!r}")
    if source == "fe":
        ctx = {"layout": layout, "walls": walls, "liquid": liquid, "base": base}
        builders = _fe_builders(where, ctx, sel, sizes, names)
    else:
        builders = _stick_builders(where, layout, sel, m.get("stick", {}))
    components = {name: ComponentModel(name, builders[name], sizes[name], sel[name].get("n_modes"),
                                       sel[name].get("f_max", None if "n_modes" in sel[name] else DEFAULT_F_MAX),
                                       sel[name].get("nastran"), sel[name].get("type", "stick"),
                                       residual_vectors=sel[name].get("residual_vectors", False))
                  for name in names + (PAD,) if "mirror" not in sel[name]}
    materials = _materials(where / "materials", m.get("materials", {}), source)
    components = _mirrors(where, sel, names, components, materials)
    if source == "stick":
        if "joint" in m:
            raise (where / "joint").error("the stick source joins the Shuttle's components itself: no [[model.joint]]")
        joints = shuttle_joints(layout)
    else:
        joints = _joints(where / "joint", m.get("joint", []), names)
        _check_layout_joints(where / "joint", layout, joints, components)
        _check_pinned_releases(where / "joint", joints, components)
    s = table(where / "system", m.get("system", {}), _SYSTEM)
    system = SystemModel(**{k: boolean(where / "system" / k, v) if k == "residual_vectors" else
                            integer(where / "system" / k, v, 1) if "n_modes" in k else
                            number(where / "system" / k, v, positive=True) for k, v in s.items()})
    max_elements = integer(where / "max_elements", m.get("max_elements", MAX_ELEMENTS[source]), 1)
    hydroelastic = any(getattr(c.builder, "liquid", "") == "hydroelastic" for c in components.values())
    _check_residual_vectors(where, components)
    if convective is not None and not hydroelastic:      # (any of its values: each is a hydroelastic liquid's)
        raise (where / "convective").error(f'"{convective}" needs a hydroelastic liquid, and no component has one '
                                           '([model] liquid = "hydroelastic" or a component\'s own liquid); '
                                           "it would be silently ignored")
    if "slosh_gravity" in m and (convective or "slosh") != "slosh":
        raise (where / "slosh_gravity").error(f'is for convective = "slosh" (this model has {convective!r}); '
                                              "it would be silently ignored")
    if "slosh_gravity" in m and not hydroelastic:
        raise (where / "slosh_gravity").error("needs a hydroelastic liquid, and no component has one; "
                                              "it would be silently ignored")
    if m.get("liquid") == "hydroelastic" and not hydroelastic:      # (a review: accepted and ignored)
        raise (where / "liquid").error('"hydroelastic", but no component takes [model]\'s liquid (none holds a '
                                       "propellant whose liquid it models: a tank stage or the Shuttle core); it would "
                                       "be silently ignored")
    # the default: the liquids' slosh modes where there are hydroelastic liquids (issue 25)
    convective = convective or ("slosh" if hydroelastic else "wall")
    return ModelConfig(source, degree, zeta, layout, components, materials, system, max_elements,
                       convective, slosh_gravity, names, joints)


def _mirrors(where: Where, sel: dict, names: tuple[str, ...], components: dict, materials: dict) -> dict:
    """The components in the model's order, each mirror (``mirror = {of, normal}``) with its
    source's mesh size and modes kept. A mirror's source is another vehicle component built
    here (not a Nastran import, a given model or another mirror), the pad none; a
    [model.materials] volume of the mirror must repeat its source's (it takes the source's)."""
    out = {}
    for name in names + (PAD,):
        if "mirror" not in sel[name]:
            out[name] = components[name]
            continue
        w = (where / "component" / name if name != PAD else where / PAD) / "mirror"
        mir = sel[name]["mirror"]
        if name == PAD:
            raise w.error("the pad is one body: it cannot be a mirror")
        src = components.get(mir.of)
        if mir.of == name or src is None or mir.of == PAD:
            what = ("itself" if mir.of == name else "the pad" if mir.of == PAD
                    else "another mirror" if mir.of in names else "no vehicle component")
            raise (w / "of").error(f"{mir.of!r} is {what}: give a vehicle component built from its own "
                                   f"geometry ({', '.join(n for n in names if n in components)})")
        if src.nastran is not None or src.builder is None or not src.type:
            raise (w / "of").error(f"{mir.of!r} is not built here (a Nastran import or a given model): a mirror "
                                   "reflects an FE component's mesh and matrices")
        t = component_types.types().get(src.type)
        if t is not None and t.model:
            raise (w / "of").error(f"{mir.of!r} is type {src.type!r}, whose model is given, not built: give the "
                                   "mirror its own table instead")
        for vol, mat in materials.items():
            if vol.startswith(name + "_"):
                twin = mir.of + vol[len(name):]
                other = materials.get(twin)       # (the same E, nu, rho: the names differ by the component's)
                if other is None or (other.E, other.nu, other.rho) != (mat.E, mat.nu, mat.rho):
                    raise (where / "materials" / vol).error(
                        f"{name!r} mirrors {mir.of!r} and takes its materials: {vol!r} must repeat [model.materials."
                        f"{twin}] or be left out")
        out[name] = dataclasses.replace(src, name=name, builder=None, type="", mirror=mir)
    return out
