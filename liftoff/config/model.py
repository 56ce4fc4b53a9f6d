"""``[model]`` of a lift-off scenario: which component models to build and how, checked
when the file is read (before anything is meshed).

Builder parameters become the builders' own dataclasses here, with their types, names and
``check()`` (all importable without gmsh):

* ``[model.vehicle.params]``: :class:`meshes.layout.StackLayout`, the positions shared by
  every component and the pad, for both sources;
* source ``"fe"``: ``[model.component.<srb_left|srb_right>.params]``
  :class:`meshes.vehicle.BoosterParams`, ``[model.component.orbiter.params]``
  :class:`meshes.vehicle.OrbiterParams` (the core stage takes none: its
  :class:`meshes.tank.TankParams` follow from the layout), ``[model.pad.params]``
  :class:`meshes.pad.PadParams`; ``[model.materials.<volume>]``
  :class:`meshes.spec.Material` (its own check, the one copy of the material rules;
  volume names are checked against the geometry once it is built);
* source ``"stick"``: ``[model.pad.params]`` :class:`meshes.pad.PadParams` (deck, posts,
  pedestals, mass) and ``[model.stick]`` :class:`meshes.stick.StickParams` (beam section
  properties and masses; positions come from the layout and the pad).

Units SI: m, Hz, Pa, kg/m^3.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from liftoff.core.errors import InputError
from liftoff.meshes.layout import StackLayout
from liftoff.meshes.pad import PadParams
from liftoff.meshes.spec import Material
from liftoff.meshes.stick import StickParams
from liftoff.meshes.vehicle import BoosterParams, OrbiterParams, core_stage_params

from .values import Where, array_of_tables, boolean, integer, number, string, table, unique_name, vector

SOURCES = ("fe", "stick")
VEHICLE = ("core", "srb_left", "srb_right", "orbiter")
NAMES = VEHICLE + ("pad",)
DEFAULT_F_MAX = 60.0        # Hz, fixed-interface modes kept when neither n_modes nor f_max is given
STICK_ELEMENT = 4.0         # m, default beam element length of the stick source
# the most elements one component may have, estimated before it is built ([model] max_elements):
# a million P1 tetrahedra (~0.6 M DOFs: the limit of a sparse direct solve on a workstation),
# two thousand beams per axis (2 cm on the 47 m core: finer is meaningless for a stick, and the
# conditioning of K_ii, ~(L/h)^4, then puts the Craig-Bampton round-off above the free-free
# check of reduction/system.py: K RB 2e-6 at 1 cm elements)
MAX_ELEMENTS = {"fe": 1_000_000, "stick": 2_000}

_MODEL = {"source", "mesh_size", "degree", "zeta", "vehicle", "pad", "component", "materials", "system", "stick",
          "walls", "max_elements", "liquid", "convective"}
WALLS = ("solid", "shell")
LIQUIDS = ("smeared", "hydroelastic")     # [model] liquid: the core stage's propellants (meshes.tank)
CONVECTIVE = ("wall", "free")             # [model] convective: a hydroelastic liquid's sloshing part (fem.liquid)
_CORE_PARAMS = {"shell_bending_ratio", "ullage_pressure", "attach"}
_VEHICLE = {"mesh_size", "params"}
_COMP = {"mesh_size", "n_modes", "f_max", "params", "nastran"}
_NASTRAN = {"file", "units", "grids", "asm", "pch", "op4", "bulk", "stiffness", "mass", "se", "recovery"}
_NASTRAN_FILES = ("file", "asm", "pch", "op4", "bulk")
_NASTRAN_RECOVERY = {"name", "disp", "vel", "acc", "rows", "quantity"}
_SYSTEM = {"n_modes", "f_max", "pad_n_modes", "pad_f_max", "residual_vectors"}
_MATERIAL = {"E", "nu", "rho"}


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
        """Every file the import reads that the scenario names (for the cache key)."""
        return [self.file] + [v for k, v in sorted(self.options.items()) if k in _NASTRAN_FILES]


@dataclass(frozen=True)
class ComponentModel:
    """One component's model: its builder's parameters, mesh size (m; stick: beam element
    length; None: the builder's default) and the fixed-interface modes kept by
    Craig-Bampton (the first ``n_modes``, at most ``f_max`` Hz; None: no limit)."""

    name: str
    builder: Any               # TankParams | BoosterParams | OrbiterParams | PadParams (fe); StickParams (stick)
    mesh_size: float | None = None
    n_modes: int | None = None
    f_max: float | None = None
    nastran: NastranSource | None = None


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
    ``degree``, modal damping ratio ``zeta`` of every elastic mode, the five components
    (core, srb_left, srb_right, orbiter, pad), material replacements and system modes;
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
    convective: str = "wall"      # hydroelastic liquids: their sloshing part on the wetted wall, or "free"


# ---------------------------------------------------------------- builder dataclasses
def _field_value(where: Where, value: Any, default: Any, annotation: str = "") -> Any:
    """A TOML value for a dataclass field, typed after the field's default: true/false, a
    string (also for a default of None where the field's annotation is ``str | None``), an
    array (of numbers, or of points as long as the default's; a coordinate ``*_xy`` as long
    as the default), else a number."""
    if isinstance(default, bool):
        return boolean(where, value)
    if isinstance(default, str) or (default is None and str(annotation).replace(" ", "") == "str|None"):
        return string(where, value)
    if not isinstance(default, tuple):
        return number(where, value)
    if not isinstance(value, list) or not value:
        raise where.error("expected a non-empty array")
    if default and isinstance(default[0], tuple):
        return tuple(tuple(float(x) for x in vector(where / i, v, length=len(default[0])))
                     for i, v in enumerate(value))
    out = tuple(float(x) for x in vector(where, value))
    if where.key.endswith("_xy") and len(out) != len(default):
        raise where.error(f"has {len(out)} entries, expected {len(default)} (x, y in m)")
    return out


def builder(where: Where, cls: type, spec: Any, fixed: dict | None = None, defaults: dict | None = None):
    """``cls(**fixed, **spec)`` checked: keys are fields of ``cls`` (not those in ``fixed``,
    not nested dataclasses), values typed after the field defaults, then ``cls.check()``.
    ``defaults`` fill fields the table does not give."""
    fixed = fixed or {}
    if not isinstance(spec, dict):
        raise where.error(f"expected a table of {cls.__name__} fields, got {type(spec).__name__}")
    fields, types = {}, {}
    for f in dataclasses.fields(cls):
        default = f.default if f.default is not dataclasses.MISSING else f.default_factory()
        if f.init and f.name not in fixed and not dataclasses.is_dataclass(default):
            fields[f.name], types[f.name] = default, f.type
    unknown = sorted(set(spec) - set(fields))
    if unknown:
        raise where.error(f"unknown key {unknown[0]!r}: not a parameter of {cls.__name__} "
                          f"(parameters: {', '.join(fields)})")
    kwargs = {**(defaults or {}), **{k: _field_value(where / k, v, fields[k], types[k]) for k, v in spec.items()}}
    try:
        obj = cls(**fixed, **kwargs)
        obj.check()
    except InputError as exc:
        raise where.wrap(exc) from None
    return obj


# ---------------------------------------------------------------- [model]
def _nastran(where: Where, spec: Any, base: Path) -> NastranSource:
    """``[model.component.<name>.nastran]``, files checked and units understood when read."""
    from liftoff.reduction.nastran import unit_system

    n = table(where, spec, _NASTRAN, required=("file", "units"))
    paths = {}
    for key in _NASTRAN_FILES:
        if key in n:
            p = (base / string(where / key, n[key])).resolve()
            if not p.is_file():
                raise (where / key).error(f"file not found: {str(p)!r}")
            paths[key] = str(p)
    units, wu = n["units"], where / "units"
    unit_system(units if isinstance(units, str) else table(wu, units, {"length", "mass", "time", "force"}),
                f"{wu.source}: {wu.key}")           # its one-line error then names file and key
    grids = table(where / "grids", n.get("grids", {}), set(n.get("grids", {})))
    names: dict[int, str] = {}
    for gid, name in grids.items():
        if not str(gid).isdigit():
            raise (where / "grids").error(f"key {gid!r} is not a grid ID (a positive integer)")
        names[int(gid)] = unique_name(where / "grids" / str(gid), name, set(names.values()), "point")
    options = {k: paths.get(k, n.get(k)) for k in ("asm", "pch", "op4", "bulk", "stiffness", "mass", "se")
               if k in n}
    for k in ("stiffness", "mass"):
        if k in options:
            string(where / k, options[k])
    if "se" in options:
        options["se"] = integer(where / "se", options["se"], 1)
    recovery = []
    for i, r in enumerate(array_of_tables(where / "recovery", n.get("recovery", []), "nastran.recovery")):
        r = table(where / "recovery" / i, r, _NASTRAN_RECOVERY, required=("name",))
        recovery.append(dict(r))
    return NastranSource(paths["file"], units, names, options, tuple(recovery))


def _sizes(where: Where, spec: dict, keys: set[str], base: Path = Path(".")) -> dict:
    """mesh_size (m), n_modes, f_max (Hz) of a [model.component.*] / [model.pad] / [model.vehicle]
    table, and a Nastran source if it has one."""
    c = table(where, spec, keys)
    out = {"params": c.get("params", {})}
    if "nastran" in c:
        out["nastran"] = _nastran(where / "nastran", c["nastran"], base)
        if out["params"] or "mesh_size" in c:
            raise (where / "nastran").error("a Nastran component takes no builder params or mesh_size")
    if "mesh_size" in c:
        out["mesh_size"] = number(where / "mesh_size", c["mesh_size"], positive=True)
    if "n_modes" in c:
        out["n_modes"] = integer(where / "n_modes", c["n_modes"], 0)
    if "f_max" in c:
        out["f_max"] = number(where / "f_max", c["f_max"], positive=True)
    if not isinstance(out["params"], dict):
        raise (where / "params").error("expected a table of builder parameters")
    return out


def _fe_builders(where: Where, layout: StackLayout, sel: dict[str, dict], size: dict[str, float | None],
                 walls: str, liquid: str = "smeared") -> dict:
    """Builder dataclasses of the FE components (gmsh geometry of meshes/); ``walls`` the
    vehicle walls' model ([model] walls: thickened solids or shells), overridable per
    booster/orbiter in their params."""
    out = {}
    wc = where / "component"
    core = dict(sel["core"]["params"])
    extra = sorted(set(core) - _CORE_PARAMS)
    if extra:
        raise (wc / "core" / "params").error(
            f"unknown key {extra[0]!r}: the core stage takes only {', '.join(sorted(_CORE_PARAMS))} (shell walls); "
            "its tank follows from [model.vehicle.params] (StackLayout)")
    ratio = number(wc / "core" / "params" / "shell_bending_ratio", core.get("shell_bending_ratio", 1.0),
                   positive=True)
    ullage = _ullage(wc / "core" / "params", core)
    attach = string(wc / "core" / "params" / "attach", core["attach"]) if "attach" in core else None
    try:
        out["core"] = core_stage_params(layout, **_size(size["core"]), walls=walls, shell_bending_ratio=ratio,
                                        liquid=liquid, ullage_pressure=ullage, attach=attach)
        out["core"].check()
    except InputError as exc:
        raise (wc / "core").wrap(exc) from None
    for name in ("srb_left", "srb_right"):
        out[name] = builder(wc / name / "params", BoosterParams, sel[name]["params"],
                            {"side": name[4:], "layout": layout}, {**_size(size[name]), "walls": walls})
    out["orbiter"] = builder(wc / "orbiter" / "params", OrbiterParams, sel["orbiter"]["params"], {"layout": layout},
                             {**_size(size["orbiter"]), "walls": walls})
    out["pad"] = builder(where / "pad" / "params", PadParams, sel["pad"]["params"], {"layout": layout},
                         _size(size["pad"]))
    return out


def _ullage(where: Where, core: dict) -> dict | None:
    """[model.component.core.params] ullage_pressure = {lh2 = Pa, lox = Pa} (gauge), or None."""
    if "ullage_pressure" not in core:
        return None
    w = where / "ullage_pressure"
    t = table(w, core["ullage_pressure"], {"lh2", "lox"}, ("lh2", "lox"))
    return {k: number(w / k, v, nonneg=True) for k, v in t.items()}


def _size(size: float | None) -> dict:
    return {} if size is None else {"mesh_size": size}


def _stick_builders(where: Where, layout: StackLayout, sel: dict[str, dict], spec: Any) -> dict:
    """One StickParams (beams) for all five components; the pad's geometry from PadParams."""
    for name in VEHICLE:
        if sel[name]["params"]:
            raise (where / "component" / name / "params").error(
                "the stick source takes no per-component parameters: write StickParams fields in [model.stick]")
    pad = builder(where / "pad" / "params", PadParams, sel["pad"]["params"], {"layout": layout})
    stick = builder(where / "stick", StickParams, spec, {"pad": pad})
    return {name: stick for name in NAMES}


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
    return builder(where, StackLayout, spec)


def _materials(where: Where, spec: Any, source: str) -> dict[str, Material]:
    if not isinstance(spec, dict):
        raise where.error("expected a table of volume -> {E, nu, rho}")
    if spec and source == "stick":
        raise where.error("the stick source has no material volumes (beam properties are in [model.stick])")
    out = {}
    for vol, mat in spec.items():
        wm = where / vol
        mat = table(wm, mat, _MATERIAL, required=("E", "nu", "rho"))
        try:
            out[vol] = Material(vol, *(number(wm / k, mat[k]) for k in ("E", "nu", "rho")))
        except InputError as exc:
            raise wm.wrap(exc) from None
    return out


def model_config(where: Where, spec: Any, base: Path | str = ".") -> ModelConfig:
    """``[model]`` -> :class:`ModelConfig` (every builder parameter checked; Nastran files
    relative to ``base``, the scenario's folder)."""
    base = Path(base)
    m = table(where, spec, _MODEL)
    source = string(where / "source", m.get("source", "fe"))
    if source not in SOURCES:
        raise (where / "source").error(f"unknown model source {source!r} (use {' or '.join(SOURCES)})")
    degree = m.get("degree", 1)
    if isinstance(degree, bool) or degree not in (1, 2):
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
    comps = table(where / "component", m.get("component", {}), set(VEHICLE))
    sel = {name: _sizes(where / "component" / name, comps.get(name, {}), _COMP, base) for name in VEHICLE}
    sel["pad"] = _sizes(where / "pad", m.get("pad", {}), _COMP, base)
    sizes = {name: sel[name].get("mesh_size", vehicle.get("mesh_size") if name != "pad" else None) or size
             for name in NAMES}
    layout = _layout(where / "vehicle" / "params", vehicle["params"], source)
    walls = string(where / "walls", m.get("walls", "solid"))
    if walls not in WALLS:
        raise (where / "walls").error(f"must be one of {', '.join(WALLS)}, got {walls!r}")
    if source == "stick" and "walls" in m:
        raise (where / "walls").error("[model] walls is for source = \"fe\" (the stick model has beams)")
    liquid = string(where / "liquid", m.get("liquid", "smeared"))
    if liquid not in LIQUIDS:
        raise (where / "liquid").error(f"must be one of {', '.join(LIQUIDS)}, got {liquid!r}")
    if source == "stick" and "liquid" in m:
        raise (where / "liquid").error("[model] liquid is for source = \"fe\" (the stick model has lumped masses)")
    convective = string(where / "convective", m.get("convective", "wall"))
    if convective not in CONVECTIVE:
        raise (where / "convective").error(f"must be one of {', '.join(CONVECTIVE)}, got {convective!r}")
    builders = _fe_builders(where, layout, sel, sizes, walls, liquid) if source == "fe" else \
        _stick_builders(where, layout, sel, m.get("stick", {}))
    components = {name: ComponentModel(name, builders[name], sizes[name], sel[name].get("n_modes"),
                                       sel[name].get("f_max", None if "n_modes" in sel[name] else DEFAULT_F_MAX),
                                       sel[name].get("nastran"))
                  for name in NAMES}
    s = table(where / "system", m.get("system", {}), _SYSTEM)
    system = SystemModel(**{k: boolean(where / "system" / k, v) if k == "residual_vectors" else
                            integer(where / "system" / k, v, 1) if "n_modes" in k else
                            number(where / "system" / k, v, positive=True) for k, v in s.items()})
    max_elements = integer(where / "max_elements", m.get("max_elements", MAX_ELEMENTS[source]), 1)
    return ModelConfig(source, degree, zeta, layout, components,
                       _materials(where / "materials", m.get("materials", {}), source), system, max_elements,
                       convective)
