"""Component types: what a ``[model.component.<name>]`` (or ``[model.pad]``) table with
``type = "<name>"`` builds, registered by name (one file per type, scikit-fem style).

A type is a :class:`ComponentType`: ``read`` turns the table's ``params`` into the
builder's checked parameter dataclass (at scenario load, without gmsh), ``build`` names
the gmsh builder of meshes/ that turns that dataclass into a meshed
:class:`liftoff.meshes.spec.Geometry` (``"module:function"``, imported when the component
is built). A new type is one new file here defining ``TYPE`` plus its module name in
:data:`BUILTIN`; a package outside liftoff registers its own under the entry-point group
``liftoff.component_types`` (a module with a ``TYPE``). README, "A new component type".

``nastran`` is a type too (the component is imported, not built: its table's
``nastran`` key, liftoff.config.model); the stick source builds the Shuttle's components
as beams and takes no types.
"""
from __future__ import annotations

import importlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

from liftoff.core.errors import InputError

#: the types shipped with liftoff: module names of this package, each with a ``TYPE``
BUILTIN = ("shuttle_core", "shuttle_booster", "shuttle_orbiter", "launch_table", "tank_stage", "barrel", "platform",
           "solid_motor", "beam", "strut", "thrust_structure", "geometry", "barge_hull", "barge_cargo", "dock", "rigid_mass",
           "rigid_ground")
#: the type of a component imported from a Nastran Craig-Bampton model (no builder)
NASTRAN = "nastran"
ENTRY_POINTS = "liftoff.component_types"
ROLES = ("vehicle", "pad", "any")


@dataclass(frozen=True)
class Context:
    """What a type's ``read`` may use besides its table: the component's ``name``, its
    ``mesh_size`` (m; None: the builder's default), the scenario's ``layout``
    (meshes.layout.StackLayout: shared positions of the Shuttle types), the ``[model]``
    defaults ``walls`` and ``liquid``, and ``base``, the scenario's folder (files)."""

    name: str
    mesh_size: float | None
    layout: Any
    walls: str = "solid"
    liquid: str = "smeared"
    base: Path = Path(".")
    extra: dict = field(default_factory=dict)
    #: whether ``mesh_size`` is the component's own (its table's), not [model]'s or [model.vehicle]'s:
    #: a type without a mesh refuses its own and ignores an inherited one
    mesh_size_given: bool = True


@dataclass(frozen=True)
class ComponentType:
    """A registered component type: ``name`` (the scenario's ``type``), ``read(ctx, where,
    params) -> dataclass`` (checked; ``where`` names the params table in errors),
    ``build`` ("module:function", ``function(params, out_dir) -> Geometry``), ``role``
    (where it may stand: "vehicle", "pad" or "any"), a one-line ``doc`` and, for a type
    without a mesh, ``model`` ("module:function", ``function(params, name) -> CBModel``: the
    component's Craig-Bampton model given directly; then ``build`` is empty) or ``matrices``
    ("module:function", ``function(params, name) -> (Component, {volume: load})``: its FE
    matrices given directly, reduced by the CB stage; the beam stick)."""

    name: str
    read: Callable
    build: str
    role: str = "any"
    doc: str = ""
    model: str = ""         # "module:function": function(params, name) -> reduction.CBModel, no mesh nor FE
    matrices: str = ""      # "module:function": function(params, name) -> (reduction.Component, {volume: load}):
                            # FE matrices given directly (no gmsh), reduced by the CB stage as a meshed one's

    def matrices_builder(self) -> Callable | None:
        """The function that gives the component's FE matrices directly (``matrices``), or None."""
        if not self.matrices:
            return None
        module, func = self.matrices.split(":")
        return getattr(importlib.import_module(module), func)

    def builder(self) -> Callable:
        """The gmsh builder function (imports meshes/ and gmsh)."""
        module, func = self.build.split(":")
        return getattr(importlib.import_module(module), func)

    def model_builder(self) -> Callable | None:
        """The function that gives the component's Craig-Bampton model directly (a type
        without a mesh, ``model``), or None."""
        if not self.model:
            return None
        module, func = self.model.split(":")
        return getattr(importlib.import_module(module), func)


_TYPES: dict[str, ComponentType] = {}
_LOADED = False


def register(t: ComponentType) -> ComponentType:
    """Add ``t`` to the registry (an InputError if its name is taken by another type)."""
    if not isinstance(t, ComponentType):
        raise InputError(f"component type registration expects a ComponentType, got {type(t).__name__}")
    if t.role not in ROLES:
        raise InputError(f"component type {t.name!r}: role must be one of {', '.join(ROLES)} (got {t.role!r})")
    old = _TYPES.get(t.name)
    if old is not None and old is not t:
        raise InputError(f"component type {t.name!r} is registered twice ({old.build} and {t.build})")
    _TYPES[t.name] = t
    return t


def _load() -> None:
    global _LOADED
    if _LOADED:
        return
    _LOADED = True
    for mod in BUILTIN:
        register(importlib.import_module(f"{__name__}.{mod}").TYPE)
    from importlib.metadata import entry_points

    for ep in entry_points(group=ENTRY_POINTS):
        try:
            register(ep.load().TYPE)
        except InputError:
            raise
        except Exception as exc:   # a broken plug-in is named, not a traceback
            raise InputError(f"component type plug-in {ep.name!r} ({ep.value}) failed to load: {exc}") from None


def types() -> dict[str, ComponentType]:
    """Every registered type, by name."""
    _load()
    return dict(_TYPES)


def get(name: str, role: str) -> ComponentType:
    """The type ``name`` allowed in ``role`` ("vehicle" or "pad"), else an InputError whose
    message lists the types that are."""
    _load()
    fit = sorted(n for n, t in _TYPES.items() if t.role in (role, "any")) + [NASTRAN]
    t = _TYPES.get(name)
    if t is None or t.role not in (role, "any"):
        why = "unknown component type" if t is None else f"type {name!r} is not for the {role}"
        raise InputError(f"{why} {name!r} (types for the {role}: {', '.join(fit)})")
    return t
