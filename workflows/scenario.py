"""Lift-off scenario files (TOML): geometry, models, loads, vehicle effects, cases.

The format is documented key by key in docs/workflow.md; the embedded default is
workflows/default_scenario.toml. Units are SI (m, kg, s, N, K). Every check raises
:class:`transient.errors.InputError` with one line naming the file and the key, e.g.
``my.toml: post[3].stiffness[2]: must be positive, got -1``.

A scenario is validated as a whole, then once per ``[[case]]``: a case is a partial
scenario deep-merged over the base (tables merge key by key; arrays of tables with a
``name`` merge by name; other arrays are replaced).
"""
from __future__ import annotations

import copy
import math
import tomllib
from dataclasses import dataclass, field
from functools import partial
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
from liftoff.transient.tomlcheck import LENGTH_NUMBERS, Where, string, vector
from liftoff.transient.tomlcheck import boolean as _bool
from liftoff.transient.tomlcheck import integer as _int
from liftoff.transient.tomlcheck import number as _num
from liftoff.transient.tomlcheck import table as _table

from liftoff.core.errors import InputError
from liftoff.core.labels import split_label

DEFAULT_NAME = "default_scenario.toml"
SOURCES = ("fe", "stick")
COMPONENTS = ("core", "srb_left", "srb_right", "orbiter")

_TOP = {"title", "description", "model", "profiles", "post_defaults", "post", "engine",
        "gravity", "cryo", "control", "softening", "force", "time", "recovery", "output", "case"}
_MODEL = {"source", "mesh_size", "degree", "zeta", "vehicle", "pad", "component", "materials",
          "system"}
_COMP = {"mesh_size", "n_modes", "f_max", "params"}
_SYSTEM = {"n_modes", "f_max", "pad_n_modes", "pad_f_max"}
_MATERIAL = {"E", "nu", "rho"}
_PROFILE = {"time", "value"}
_POST = {"name", "vehicle", "pad", "stiffness", "rigid", "release_time", "gap"}
_ENGINE = {"name", "mount", "direction", "start", "time", "thrust", "profile", "scale"}
_GRAVITY = {"accel"}
_CRYO = {"enabled", "component", "volumes", "delta_T", "alpha"}
_CONTROL = {"enabled", "gimbals", "start", "ramp"}
_SOFTENING = {"enabled", "until"}
_FORCE = {"label", "time", "value"}
_TIME = {"t0", "t_end", "h", "method"}
_RECOVERY = {"attach", "stations", "top", "payload"}
_OUTPUT = {"plots", "snapshots", "progress"}
_CASE = _TOP - {"case"} | {"name"}


# --------------------------------------------------------------------- value checks
# shared checks (transient/tomlcheck.py) with this format's wording: names are non-empty
# strings; a vector of the wrong length reads "expected 3 numbers, got 2"
_str = partial(string, nonempty=True)
_vec = partial(vector, length_msg=LENGTH_NUMBERS)


def _label(w: Where, v: Any) -> str:
    v = _str(w, v)
    try:
        split_label(v)
    except InputError as exc:
        raise w.error(str(exc)) from None
    return v


def _time_table(w: Where, t: Any, v: Any, tkey="time", vkey="value") -> tuple[np.ndarray, np.ndarray]:
    time = _vec(w / tkey, t)
    val = _vec(w / vkey, v)
    if time.size < 2:
        raise (w / tkey).error("a table needs at least 2 points")
    if time.size != val.size:
        raise (w / vkey).error(f"{val.size} values for {time.size} times")
    if np.any(np.diff(time) <= 0):
        raise (w / tkey).error("times must increase strictly")
    return time, val


# --------------------------------------------------------------------- dataclasses
@dataclass
class Post:
    """A hold-down post: vehicle point on pad point, bolted until ``release_time`` (s)."""

    name: str
    vehicle: str
    pad: str
    stiffness: np.ndarray  # (3,) N/m for Tx Ty Tz
    rigid: bool
    release_time: float    # inf: never releases
    gap: float


@dataclass
class Engine:
    """Thrust ``thrust(t - start)`` (N) along unit ``direction`` at vehicle point ``mount``."""

    name: str
    mount: str
    direction: np.ndarray
    time: np.ndarray
    thrust: np.ndarray
    start: float

    def table(self) -> tuple[np.ndarray, np.ndarray]:
        return self.time + self.start, self.thrust


@dataclass
class TableForce:
    label: str
    time: np.ndarray
    value: np.ndarray


@dataclass
class Case:
    """One fully validated load case (the base scenario with its overrides merged)."""

    name: str
    model: dict
    posts: list[Post]
    engines: list[Engine]
    gravity: np.ndarray
    cryo: dict
    control: dict
    softening: dict
    forces: list[TableForce]
    time: dict
    recovery: dict
    output: dict
    raw: dict = field(repr=False, default_factory=dict)


@dataclass
class Scenario:
    path: str
    title: str
    description: str
    cases: list[Case]


# --------------------------------------------------------------------- parsing
def _model(w: Where, m: Any) -> dict:
    m = _table(w, m, _MODEL)
    out = {"source": m.get("source", "fe"), "degree": m.get("degree", 1), "zeta": m.get("zeta", 0.01),
           "mesh_size": m.get("mesh_size", None), "vehicle": {}, "pad": {}, "component": {},
           "materials": {}, "system": {}}
    if out["source"] not in SOURCES:
        raise (w / "source").error(f"unknown model source {out['source']!r} (use {' or '.join(SOURCES)})")
    if out["degree"] not in (1, 2):
        raise (w / "degree").error(f"element degree must be 1 or 2, got {out['degree']!r}")
    out["zeta"] = _num(w / "zeta", out["zeta"], nonneg=True)
    if out["zeta"] >= 1:
        raise (w / "zeta").error(f"modal damping ratio must be < 1, got {out['zeta']:g}")
    if out["mesh_size"] is not None:
        out["mesh_size"] = _num(w / "mesh_size", out["mesh_size"], positive=True)
    for key in ("vehicle", "pad"):
        if key in m:
            out[key] = _component(w / key, m[key])
    comps = _table(w / "component", m.get("component", {}), set(COMPONENTS))
    out["component"] = {k: _component(w / "component" / k, v) for k, v in comps.items()}
    mats = m.get("materials", {})
    if not isinstance(mats, dict):
        raise (w / "materials").error("expected a table of volume -> {E, nu, rho}")
    for vol, mat in mats.items():
        wm = w / "materials" / vol
        mat = _table(wm, mat, _MATERIAL, required=("E", "nu", "rho"))
        E, rho = _num(wm / "E", mat["E"], positive=True), _num(wm / "rho", mat["rho"], positive=True)
        nu = _num(wm / "nu", mat["nu"])
        if not -1 < nu < 0.5:
            raise (wm / "nu").error(f"Poisson ratio must be in (-1, 0.5), got {nu:g}")
        out["materials"][vol] = {"E": E, "nu": nu, "rho": rho}
    s = _table(w / "system", m.get("system", {}), _SYSTEM)
    for k, v in s.items():
        out["system"][k] = _int(w / "system" / k, v, 1) if "n_modes" in k else \
            _num(w / "system" / k, v, positive=True)
    return out


def _component(w: Where, c: Any) -> dict:
    c = _table(w, c, _COMP)
    out = {}
    if "mesh_size" in c:
        out["mesh_size"] = _num(w / "mesh_size", c["mesh_size"], positive=True)
    if "n_modes" in c:
        out["n_modes"] = _int(w / "n_modes", c["n_modes"], 0)
    if "f_max" in c:
        out["f_max"] = _num(w / "f_max", c["f_max"], positive=True)
    if "params" in c:
        p = c["params"]
        if not isinstance(p, dict):
            raise (w / "params").error("expected a table of builder parameters")
        out["params"] = dict(p)
    return out


def _profiles(w: Where, p: Any) -> dict:
    if not isinstance(p, dict):
        raise w.error("expected a table of named time tables")
    out = {}
    for name, tab in p.items():
        tab = _table(w / name, tab, _PROFILE, required=("time", "value"))
        out[name] = _time_table(w / name, tab["time"], tab["value"])
    return out


def _posts(w: Where, posts: Any, wd: Where, defaults: Any) -> list[Post]:
    d = _table(wd, defaults, _POST - {"name", "vehicle", "pad"})
    if not isinstance(posts, list) or not posts:
        raise w.error("expected at least one [[post]] (hold-down point)")
    out, names = [], set()
    for i, p in enumerate(posts):
        wp = w / i
        p = _table(wp, p, _POST, required=("name", "vehicle", "pad"))
        q = {**d, **p}
        name = _str(wp / "name", q["name"])
        if name in names:
            raise (wp / "name").error(f"duplicate post name {name!r}")
        names.add(name)
        rigid = _bool(wp / "rigid", q.get("rigid", False))
        if "stiffness" not in q and not rigid:
            raise wp.error("missing 'stiffness' [kx, ky, kz] (N/m) or rigid = true")
        k = _vec(wp / "stiffness", q.get("stiffness", [1.0, 1.0, 1.0]), length=3, positive=True)
        rel = _num(wp / "release_time", q.get("release_time", math.inf), allow_inf=True)
        out.append(Post(name, _str(wp / "vehicle", q["vehicle"]), _str(wp / "pad", q["pad"]), k, rigid,
                        rel, _num(wp / "gap", q.get("gap", 0.0), nonneg=True)))
    return out


def _engines(w: Where, engines: Any, profiles: dict) -> list[Engine]:
    if not isinstance(engines, list):
        raise w.error("expected an array of tables [[engine]]")
    out, names = [], set()
    for i, e in enumerate(engines):
        we = w / i
        e = _table(we, e, _ENGINE, required=("name", "mount"))
        name = _str(we / "name", e["name"])
        if name in names:
            raise (we / "name").error(f"duplicate engine name {name!r}")
        names.add(name)
        d = _vec(we / "direction", e.get("direction", [0.0, 0.0, 1.0]), length=3)
        if not np.linalg.norm(d) > 0:
            raise (we / "direction").error("zero thrust direction")
        if "profile" in e:
            if "time" in e or "thrust" in e:
                raise (we / "profile").error("give either profile (+ scale) or time + thrust, not both")
            prof = _str(we / "profile", e["profile"])
            if prof not in profiles:
                raise (we / "profile").error(f"unknown profile {prof!r} (defined: {', '.join(profiles) or 'none'})")
            t, v = profiles[prof]
            v = v * _num(we / "scale", e.get("scale", 1.0))
        else:
            if "time" not in e or "thrust" not in e:
                raise we.error("missing thrust table: give time + thrust (N) or profile + scale")
            t, v = _time_table(we, e["time"], e["thrust"], vkey="thrust")
            v = v * _num(we / "scale", e.get("scale", 1.0))
        out.append(Engine(name, _str(we / "mount", e["mount"]), d / np.linalg.norm(d), t, v,
                          _num(we / "start", e.get("start", 0.0))))
    return out


def _forces(w: Where, forces: Any) -> list[TableForce]:
    if not isinstance(forces, list):
        raise w.error("expected an array of tables [[force]]")
    out = []
    for i, f in enumerate(forces):
        wf = w / i
        f = _table(wf, f, _FORCE, required=("label", "value"))
        lab = _label(wf / "label", f["label"])
        if isinstance(f["value"], list):
            if "time" not in f:
                raise wf.error("a tabulated force needs 'time' (s) with its 'value' (N)")
            t, v = _time_table(wf, f["time"], f["value"])
        else:
            v0 = _num(wf / "value", f["value"])
            t, v = np.array([0.0, 1.0]), np.array([v0, v0])
            if "time" in f:
                raise (wf / "time").error("'time' given with a constant value")
        out.append(TableForce(lab, t, v))
    return out


def _case(w: Where, d: dict, name: str) -> Case:
    _table(w, d, _TOP | {"name"})
    profiles = _profiles(w / "profiles", d.get("profiles", {}))
    model = _model(w / "model", d.get("model", {}))
    posts = _posts(w / "post", d.get("post", []), w / "post_defaults", d.get("post_defaults", {}))
    engines = _engines(w / "engine", d.get("engine", []), profiles)
    g = _table(w / "gravity", d.get("gravity", {}), _GRAVITY)
    gravity = _vec(w / "gravity" / "accel", g.get("accel", [0.0, 0.0, -9.80665]), length=3)

    c = _table(w / "cryo", d.get("cryo", {}), _CRYO)
    cryo = {"enabled": _bool(w / "cryo" / "enabled", c.get("enabled", False))}
    if cryo["enabled"]:
        wc = w / "cryo"
        _table(wc, c, _CRYO, required=("component", "volumes", "delta_T", "alpha"))
        cryo["component"] = _str(wc / "component", c["component"])
        vols = c["volumes"]
        if not isinstance(vols, list) or not vols:
            raise (wc / "volumes").error("expected a non-empty array of volume names")
        cryo["volumes"] = [_str(wc / "volumes" / i, v) for i, v in enumerate(vols)]
        cryo["delta_T"] = _num(wc / "delta_T", c["delta_T"])
        cryo["alpha"] = _num(wc / "alpha", c["alpha"], positive=True)

    c = _table(w / "control", d.get("control", {}), _CONTROL)
    wc = w / "control"
    control = {"enabled": _bool(wc / "enabled", c.get("enabled", False))}
    if control["enabled"]:
        _table(wc, c, _CONTROL, required=("gimbals",))
        if not isinstance(c["gimbals"], list) or len(c["gimbals"]) < 3:
            raise (wc / "gimbals").error("expected >= 3 lateral gimbal DOF labels (e.g. 'srb_left_gimbal:Tx')")
        control["gimbals"] = [_label(wc / "gimbals" / i, v) for i, v in enumerate(c["gimbals"])]
        control["start"] = _num(wc / "start", c.get("start", -math.inf), allow_inf=True)
        control["ramp"] = _num(wc / "ramp", c.get("ramp", 0.0), nonneg=True)

    c = _table(w / "softening", d.get("softening", {}), _SOFTENING)
    softening = {"enabled": _bool(w / "softening" / "enabled", c.get("enabled", False)),
                 "until": _num(w / "softening" / "until", c.get("until", math.inf), allow_inf=True)}

    forces = _forces(w / "force", d.get("force", []))

    t = _table(w / "time", d.get("time", {}), _TIME, required=("t_end",))
    wt = w / "time"
    time = {"t0": _num(wt / "t0", t.get("t0", 0.0)), "t_end": _num(wt / "t_end", t["t_end"]),
            "h": None if t.get("h", "auto") == "auto" else _num(wt / "h", t["h"], positive=True),
            "method": t.get("method", "direct")}
    if time["t_end"] <= time["t0"]:
        raise (wt / "t_end").error(f"t_end {time['t_end']:g} s must be after t0 {time['t0']:g} s")
    if time["method"] not in ("direct", "fixed-point"):
        raise (wt / "method").error(f"unknown method {time['method']!r} (direct or fixed-point)")

    r = _table(w / "recovery", d.get("recovery", {}), _RECOVERY)
    wr = w / "recovery"
    recovery = {"attach": [_str(wr / "attach" / i, v) for i, v in enumerate(r.get("attach", []))],
                "stations": [_str(wr / "stations" / i, v) for i, v in enumerate(r.get("stations", []))],
                "top": _str(wr / "top", r["top"]) if "top" in r else None,
                "payload": _str(wr / "payload", r["payload"]) if "payload" in r else None}
    o = _table(w / "output", d.get("output", {}), _OUTPUT)
    output = {k: _bool(w / "output" / k, o.get(k, True)) for k in _OUTPUT}
    return Case(name, model, posts, engines, gravity, cryo, control, softening, forces, time,
                recovery, output, raw=d)


def merge(base: dict, over: dict) -> dict:
    """Deep merge ``over`` into a copy of ``base`` (tables by key, named tables by name)."""
    out = copy.deepcopy(base)
    for k, v in over.items():
        if isinstance(v, dict) and isinstance(out.get(k), dict):
            out[k] = merge(out[k], v)
        elif (isinstance(v, list) and isinstance(out.get(k), list) and v and out[k]
              and all(isinstance(x, dict) and "name" in x for x in v + out[k])):
            merged = {x["name"]: copy.deepcopy(x) for x in out[k]}
            for x in v:
                merged[x["name"]] = merge(merged.get(x["name"], {}), x)
            out[k] = list(merged.values())
        else:
            out[k] = copy.deepcopy(v)
    return out


def parse_scenario(data: dict, source: str = "scenario") -> Scenario:
    """Validate a scenario dictionary (as read from TOML); one Case per [[case]] (or 'base')."""
    w = Where(source)
    _table(w, data, _TOP)
    base = {k: v for k, v in data.items() if k not in ("case", "title", "description")}
    cases_raw = data.get("case", [])
    if not isinstance(cases_raw, list):
        raise (w / "case").error("expected an array of tables [[case]]")
    base_case = _case(w, base, "base")  # errors in the base name the base key, not a case
    cases = [] if cases_raw else [base_case]
    names = set()
    for i, c in enumerate(cases_raw):
        wc = w / "case" / i
        c = _table(wc, c, _CASE, required=("name",))
        name = _str(wc / "name", c["name"])
        if name in names:
            raise (wc / "name").error(f"duplicate case name {name!r}")
        names.add(name)
        over = {k: v for k, v in c.items() if k != "name"}
        cases.append(_case(wc, merge(base, over), name))
    return Scenario(source, str(data.get("title", "liftoff scenario")), str(data.get("description", "")), cases)


def default_text() -> str:
    """The embedded default scenario (package data workflows/default_scenario.toml)."""
    return resources.files("liftoff.workflows").joinpath(DEFAULT_NAME).read_text()


def load_scenario(path: str | Path | None = None) -> Scenario:
    """Read and validate a scenario file; ``None`` gives the embedded default."""
    if path is None:
        text, source = default_text(), f"<default {DEFAULT_NAME}>"
    else:
        path = Path(path)
        if not path.is_file():
            raise InputError(f"scenario file not found: {str(path)!r}")
        text, source = path.read_text(), path.name
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{source}: not valid TOML: {exc}") from None
    return parse_scenario(data, source)
