"""A builder's parameter dataclass from a TOML table, typed and checked (numpy only).

The builders of meshes/ take plain dataclasses (scikit-fem style) with documented
defaults and a ``check()``; :func:`builder` fills one from a scenario table: keys are the
dataclass's fields, values typed after the field defaults, errors one line naming the key.
"""
from __future__ import annotations

import dataclasses
from typing import Any

from liftoff.core.errors import InputError, ResourceError

from .values import Where, boolean, integer, number, string, table, vector

MATERIAL_KEYS = ("E", "nu", "rho")
#: the most a builder's count field takes (stringers, beam elements, stations)
MAX_COUNT = 1_000_000


def _field_value(where: Where, value: Any, default: Any, annotation: str = "", length: int | None = None) -> Any:
    """A TOML value for a dataclass field, typed after the field's default: true/false, a
    string (also for a default of None where the field's annotation is ``str | None``), an
    array (of numbers, or of points as long as the default's; a coordinate ``*_xy`` as long
    as the default; ``length`` entries where the field's metadata fixes it, e.g. a deck's
    (x, y) size), else a number."""
    if isinstance(default, bool):
        return boolean(where, value)
    if isinstance(default, str) or (default is None and str(annotation).replace(" ", "") == "str|None"):
        return string(where, value)
    if isinstance(default, int):        # a count (stringers, elements, stations): 2.5 or 1e20 is none
        return integer(where, value, 0, MAX_COUNT)
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
    if length is not None and len(out) != length:
        raise where.error(f"has {len(out)} entries, expected {length}")
    return out


def builder(where: Where, cls: type, spec: Any, fixed: dict | None = None, defaults: dict | None = None):
    """``cls(**fixed, **spec)`` checked: keys are fields of ``cls`` (not those in ``fixed``,
    not nested dataclasses), values typed after the field defaults, then ``cls.check()``.
    ``defaults`` fill fields the table does not give."""
    fixed = fixed or {}
    if not isinstance(spec, dict):
        raise where.error(f"expected a table of {cls.__name__} fields, got {type(spec).__name__}")
    fields, types, lengths = {}, {}, {}
    for f in dataclasses.fields(cls):
        default = f.default if f.default is not dataclasses.MISSING else f.default_factory()
        if f.init and f.name not in fixed and not dataclasses.is_dataclass(default):
            fields[f.name], types[f.name], lengths[f.name] = default, f.type, f.metadata.get("length")
    unknown = sorted(set(spec) - set(fields))
    if unknown:
        raise where.error(f"unknown key {unknown[0]!r}: not a parameter of {cls.__name__} "
                          f"(parameters: {', '.join(fields)})")
    kwargs = {**(defaults or {}), **{k: _field_value(where / k, v, fields[k], types[k], lengths[k])
                                     for k, v in spec.items()}}
    try:
        obj = cls(**fixed, **kwargs)
        obj.check()
    except InputError as exc:
        raise where.wrap(exc) from None
    except ResourceError as exc:        # (a size the input asks for: an input error, at its table)
        raise where.error(" ".join(str(exc).split())) from None
    except (ValueError, TypeError) as exc:   # a check that met a value of the wrong shape (an array's length)
        raise where.error(f"{cls.__name__}: {' '.join(str(exc).split())}") from None
    return obj




def material(where: Where, name: str, spec: Any, extra: tuple[str, ...] = ()):
    """(meshes.spec.Material ``name`` from a ``{E, nu, rho}`` table (Pa, -, kg/m^3), the
    table): its keys checked (``extra`` allowed and required too), the material's own check
    worded at ``where``."""
    from liftoff.meshes.spec import Material

    m = table(where, spec, set(MATERIAL_KEYS) | set(extra), MATERIAL_KEYS + tuple(extra))
    values = [number(where / k, m[k]) for k in MATERIAL_KEYS]       # (their own errors: at their keys, once)
    try:
        return Material(name, *values), m
    except InputError as exc:
        raise where.wrap(exc) from None


def beam_section(where: Where, spec: Any) -> dict:
    """A beam section table ``{shape = "i", h = ..., ...}`` (liftoff.core.beam.standard_section:
    tube, rectangle, box, i, t, hat; m) checked, errors worded at ``where``; the table."""
    from liftoff.core.beam import standard_section

    try:
        standard_section(spec, "section")
    except InputError as exc:
        raise where.error(" ".join(str(exc).removeprefix("section: ").split())) from None
    return dict(spec)


def beam_members(where: Where, params: Any, name: str, kinds: tuple[str, ...]) -> dict:
    """The beam members ``kinds`` (e.g. "frame", "stringer") of a builder's params table:
    {``<kind>_section``: its checked table (:func:`beam_section`) or {}, ``<kind>_material``:
    a Material named ``<name>-<kind>s`` or None}, errors worded at their keys."""
    params = params if isinstance(params, dict) else {}
    out = {}
    for kind in kinds:
        key, mat = f"{kind}_section", f"{kind}_material"
        out[key] = beam_section(where / key, params[key]) if key in params else {}
        out[mat] = material(where / mat, f"{name}-{kind}s", params[mat])[0] if mat in params else None
    return out


def mesh_size_kw(mesh_size: float | None) -> dict:
    """``{"mesh_size": mesh_size}``, or nothing when it is None (the builder's default)."""
    return {} if mesh_size is None else {"mesh_size": mesh_size}
