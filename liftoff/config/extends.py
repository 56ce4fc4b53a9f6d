"""Scenarios that start from another: ``extends = "shuttle"`` (an embedded example) or
``extends = "path/to/base.toml"``, with the file's own keys merged into the base's key by
key (:func:`merge`).

The base is resolved first (it may itself extend another; a cycle is an error), then:

* tables merge by key and arrays of named tables (``[[case]]``, ``[[engine]]``,
  ``[[post]]``, ...) by ``name``; any other value replaces the base's;
* ``[model]`` is a description of one model source: a file that sets ``[model] source``
  to another source than its base's (``"stick"`` on the ``"fe"`` Shuttle) does not inherit
  the base's ``[model]`` table at all, so that FE meshes, materials and builder parameters
  of the base never reach (or are refused by) the stick model;
* a component (``[model.component.<name>]`` or ``[model.pad]``) whose ``type`` the file
  changes (a ``nastran`` table makes it ``"nastran"``) does not inherit the base's table
  for it either: the base's builder parameters belong to the base's type;
* ``kind`` (``"liftoff"`` or ``"barge"``) is the base's: a file may repeat it, not change it;
* file paths (CSV tables, Nastran files) resolve against the folder of the file that is run,
  whichever file names them.

Unknown keys still fail with one line, naming the file that is run and the key.
"""
from __future__ import annotations

import copy
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

from liftoff.core.errors import InputError

from .files import file_path, parse_toml, read_toml
from .values import Where, string


@dataclass(frozen=True)
class Example:
    """An embedded example: its scenario ``scenario`` in package ``package`` and the
    ``files`` its scenario names (geometry, Nastran), beside it in the same folder, which
    ``liftoff init`` copies next to the scenario it writes."""

    package: str
    scenario: str
    files: tuple[str, ...] = ()

    def resource(self, name: str):
        """The package resource ``name`` (the scenario's folder)."""
        folder, _, _ = self.scenario.rpartition("/")
        return resources.files(self.package).joinpath(f"{folder}/{name}" if folder else name)


#: example name -> embedded scenario (package data of liftoff.config and liftoff.examples)
EXAMPLES = {
    "shuttle": Example("liftoff.config", "default_scenario.toml"),
    "barge": Example("liftoff.config", "barge_scenario.toml"),
    "saturn_v": Example("liftoff.config", "saturn_v_scenario.toml"),
    # examples/single_stick: the user's .geo interstage, fairing and pad, a Nastran payload
    "single_stick": Example("liftoff.examples", "single_stick/scenario.toml",
                            ("interstage.geo", "fairing.geo", "pad.geo", "payload.pch")),
}
#: how deep ``extends`` may chain (a longer chain is a mistake, not a design)
MAX_DEPTH = 8


def merge(base: dict, over: dict) -> dict:
    """Deep merge ``over`` into a copy of ``base`` (tables by key, arrays of named tables by
    name at any depth: an entry of a new name is added, one of a base's name merged into it,
    and ``{name = "x", remove = true}`` takes the base's entry x out)."""
    out = copy.deepcopy(base)
    for k, v in over.items():
        if isinstance(v, dict) and isinstance(out.get(k), dict):
            out[k] = merge(out[k], v)
        elif (isinstance(v, list) and isinstance(out.get(k), list) and v and out[k]
              and all(isinstance(x, dict) and isinstance(x.get("name"), str) for x in v + out[k])):
            merged = {x["name"]: copy.deepcopy(x) for x in out[k]}
            names = [x["name"] for x in v]
            twice = next((n for n in names if names.count(n) > 1), None)
            if twice is not None:           # (merged by name, the first would vanish into the second)
                raise InputError(f"{k}: two entries named {twice!r}; each entry of a list merged by name needs its own")
            for x in v:
                if x.get("remove") is True:      # the base's entry of that name taken out (nothing else may be given)
                    if set(x) != {"name", "remove"}:
                        raise InputError(f"{k}: entry {x['name']!r}: remove = true takes nothing but the name")
                    if merged.pop(x["name"], None) is None:
                        raise InputError(f"{k}: remove = true for {x['name']!r}, which the scenario extended has not "
                                         f"(its entries: {', '.join(merged) or 'none'})")
                    continue
                merged[x["name"]] = merge(merged.get(x["name"], {}), x)
            out[k] = list(merged.values())
        else:
            out[k] = copy.deepcopy(v)
    return out


def example_text(name: str) -> str:
    """The text of an embedded example scenario (:data:`EXAMPLES`)."""
    ex = EXAMPLES[name]
    return resources.files(ex.package).joinpath(ex.scenario).read_text(encoding="utf-8")


def example_files(name: str) -> dict[str, bytes]:
    """The files an embedded example's scenario names (file name -> content), which must lie
    beside a scenario that extends it (paths resolve against the folder of the file run)."""
    ex = EXAMPLES[name]
    return {f: ex.resource(f).read_bytes() for f in ex.files}


def _model_source(data: dict) -> str:
    model = data.get("model")
    src = model.get("source", "fe") if isinstance(model, dict) else "fe"
    return src if isinstance(src, str) else "fe"


def resolve(data: dict, source: str, folder: Path | None, _chain: tuple[str, ...] = ()) -> dict:
    """The scenario mapping ``data`` (read from ``source``, a file in ``folder``; None for
    embedded text) with its ``extends`` resolved; without ``extends``, ``data`` itself."""
    if "extends" not in data:
        return data
    w = Where(source, "extends")
    name = string(w, data["extends"])
    if len(_chain) >= MAX_DEPTH:
        raise w.error(f"more than {MAX_DEPTH} scenarios extend one another ({' -> '.join(_chain)})")
    if name in EXAMPLES:
        ident, base_source, base_folder = f"example:{name}", f"<example {name}>", None
        base = parse_toml(example_text(name), base_source)
    else:
        if folder is None:                                   # embedded text: examples only
            check_example(name, w)
        path = file_path(w, name, folder)
        if not path.is_file():
            hint = f"; examples: {', '.join(EXAMPLES)}" if "/" not in name and not name.endswith(".toml") else ""
            raise w.error(f"no example and no file {name!r} (looked in {folder}{hint})")
        ident, base_source, base_folder = str(path.resolve()), path.name, path.resolve().parent
        base = read_toml(path)
    if ident in _chain:
        raise w.error(f"scenarios extend one another in a cycle: {' -> '.join(_chain + (ident,))}")
    base = resolve(base, base_source, base_folder, _chain + (ident,))
    own = {k: v for k, v in data.items() if k != "extends"}
    kind = base.get("kind", "liftoff")
    if "kind" in own and own["kind"] != kind:
        raise Where(source, "kind").error(f"{own['kind']!r} differs from the kind of the scenario it extends "
                                          f"({name!r}: {kind!r})")
    if isinstance(own.get("model"), dict) and "source" in own["model"] \
            and own["model"]["source"] != _model_source(base):
        base = {k: v for k, v in base.items() if k != "model"}     # another model source: its own [model]
    try:
        return merge(_drop_retyped(base, own), own)
    except InputError as exc:                # (a list's entries merged by name: the file that has them)
        raise InputError(f"{source}: {exc}") from None


def _type_of(table) -> str | None:
    if not isinstance(table, dict):
        return None
    return "nastran" if "nastran" in table and "type" not in table else table.get("type")


def _drop_retyped(base: dict, own: dict) -> dict:
    """``base`` without the component tables whose type ``own`` changes."""
    bm, om = base.get("model"), own.get("model")
    if not isinstance(bm, dict) or not isinstance(om, dict):
        return base
    bm = dict(bm)
    if isinstance(om.get("pad"), dict) and _type_of(om["pad"]) not in (None, _type_of(bm.get("pad"))):
        bm.pop("pad", None)
    bc, oc = bm.get("component"), om.get("component")
    if isinstance(bc, dict) and isinstance(oc, dict):
        bm["component"] = {n: t for n, t in bc.items()
                           if not (isinstance(oc.get(n), dict) and _type_of(oc[n]) not in (None, _type_of(t)))}
    return {**base, "model": bm}


def read_scenario(path: str | Path) -> dict:
    """A scenario file's mapping with its ``extends`` resolved."""
    path = Path(path)
    return resolve(read_toml(path), path.name, path.resolve().parent, (str(path.resolve()),))


def check_example(name: str, where: Where | None = None) -> str:
    """``name`` if it is an embedded example, else a one-line InputError (at ``where``)."""
    if name not in EXAMPLES:
        msg = f"unknown example {name!r} (examples: {', '.join(EXAMPLES)})"
        raise where.error(msg) if where is not None else InputError(msg)
    return name
