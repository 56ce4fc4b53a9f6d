"""Lift-off scenario files (``liftoff run``): models, loads, vehicle effects, cases.

The format is documented key by key in docs/workflow.md; the embedded default is
liftoff/config/default_scenario.toml. Units are SI (m, kg, s, N, K). Every error is one
line ``file: key.path: what``, e.g. ``my.toml: post[3] 'left_4'.stiffness[2]: negative
value -1``. Paths inside a scenario (CSV tables) are relative to the scenario file.

A scenario is validated as a whole, then once per ``[[case]]``: a case is a partial
scenario deep-merged over the base (tables merge key by key; arrays of tables with a
``name`` merge by name; other arrays are replaced).
"""
from __future__ import annotations

import copy
import re
from dataclasses import dataclass, field, replace
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from liftoff.core.errors import InputError
from liftoff.core.labels import TRANSLATIONS, point_labels
from liftoff.transient.model import ContactPoint

from .dispersion import Dispersion, case_name, check_case_count, dispersion
from .extends import merge, read_scenario, resolve
from .files import file_path, parse_toml
from .model import ModelConfig, model_config, unit_system_at
from .postprocess import PostProcess, postprocess
from .sections import (
    FORCE_KEYS,
    LAW_KEYS,
    STANDARD_GRAVITY,
    Control,
    Cryo,
    Force,
    Softening,
    TimeSpan,
    at_point,
    contact_law,
    control,
    cryo,
    force,
    gravity,
    softening,
    tabulated,
    time_span,
)
from .values import Where, array_of_tables, boolean, number, string, strings, table, unique_name, vector

DEFAULT_NAME = "default_scenario.toml"
#: case names that output file names use for the envelope over cases
RESERVED_CASE_NAMES = frozenset({"envelope"})

_TOP = {"title", "description", "model", "profiles", "post_defaults", "post", "engine",
        "gravity", "cryo", "control", "softening", "force", "time", "recovery", "output", "case", "kind",
        "dispersion", "postprocess"}
_SCENARIO_ONLY = ("case", "title", "description", "kind", "dispersion", "postprocess")  # not per case
_PROFILE = {"time", "value", "csv"}
_POST = {"name", "vehicle", "pad"} | LAW_KEYS
_ENGINE = {"name", "mount", "direction", "start", "time", "thrust", "profile", "scale"}
_RECOVERY = {"attach", "stations", "top", "payload", "otm"}
_OTM = {"name", "file", "point", "disp", "vel", "acc", "rows", "quantity", "units"}
_OUTPUT = {"plots", "snapshots", "progress"}
_CASE = _TOP - set(_SCENARIO_ONLY) | {"name"}


# --------------------------------------------------------------------- dataclasses
@dataclass(frozen=True)
class Post:
    """A hold-down post: vehicle point on pad point, coupled in Tx, Ty, Tz by ``law`` (a
    ContactPoint over the vehicle point's directions, sections.contact_law; normal direction
    ``axial``, default Tz; bolted until ``law.release_time``)."""

    name: str
    vehicle: str
    pad: str
    law: ContactPoint

    DIRECTIONS = TRANSLATIONS

    @property
    def release_time(self) -> float:
        return self.law.release_time

    def contact(self) -> ContactPoint:
        """The transient model's contact point (vehicle = body a, pad = body b)."""
        return at_point(self.law, self.name, point_labels(self.vehicle, self.DIRECTIONS),
                        point_labels(self.pad, self.DIRECTIONS))


@dataclass(frozen=True)
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


@dataclass(frozen=True)
class RecoveryPoints:
    """``[recovery]``: interface forces at ``attach`` points (``point@component`` picks the
    side), motion of ``top``, ``payload`` and ``stations`` (vehicle points)."""

    attach: tuple[str, ...] = ()
    stations: tuple[str, ...] = ()
    top: str | None = None
    payload: str | None = None
    otm: tuple["InterfaceOTM", ...] = ()


@dataclass(frozen=True)
class InterfaceOTM:
    """``[[recovery.otm]]``: a payload provider's output transformation matrices applied at
    a vehicle ``point`` (reduction.nastran.interface_otm): matrices ``disp``/``vel``/``acc``
    of the OUTPUT4 ``file`` (rows x 6 over the point's T1..R3), row labels ``rows``, their
    ``quantity`` and the matrices' ``units`` (a unit system name or table, as Nastran
    components give theirs)."""

    name: str
    file: str
    point: str
    disp: str | None = None
    vel: str | None = None
    acc: str | None = None
    rows: tuple[str, ...] | None = None
    quantity: str | tuple[str, ...] = "displacement"
    units: Any = "SI"


@dataclass(frozen=True)
class OutputFlags:
    """``[output]``: time-history plots, deformed-shape snapshots, progress bars."""

    plots: bool = True
    snapshots: bool = True
    progress: bool = True


@dataclass
class Case:
    """One fully validated load case (the base scenario with its overrides merged).

    ``source``: the scenario file's name, for the messages of checks made once the models
    exist (point names, volumes)."""

    name: str
    source: str
    model: ModelConfig
    posts: list[Post]
    engines: list[Engine]
    gravity: np.ndarray
    cryo: Cryo
    control: Control
    softening: Softening
    forces: list[Force]
    time: TimeSpan
    recovery: RecoveryPoints
    output: OutputFlags
    from_case_table: bool = False   # a [[case]] of the file (not the base scenario alone)

    def at(self, key: str = "") -> Where:
        """The key path of a check made once the models exist, naming file and, for a
        ``[[case]]``, the case: ``my.toml: case 'hot': post[2] 'left_3'.vehicle: ...``."""
        return Where(f"{self.source}: case {self.name!r}" if self.from_case_table else self.source, key)


@dataclass
class Scenario:
    """A validated scenario: its named ``cases`` and, with ``[dispersion]``, the generated
    ones (:meth:`generated_case`), each rebuilt from ``common`` (the scenario mapping less
    the scenario-level sections) and its index alone; ``post``: ``[postprocess]``."""

    path: str
    title: str
    description: str
    cases: list[Case]
    common: dict = field(default_factory=dict)
    overrides: dict = field(default_factory=dict)      # named case -> its [[case]] overrides
    base: Path = Path(".")
    dispersion: Dispersion | None = None
    post: PostProcess = field(default_factory=PostProcess)
    data: dict = field(default_factory=dict)           # the scenario mapping as read (workers rebuild from it)

    @property
    def n_generated(self) -> int:
        return self.dispersion.n_cases if self.dispersion else 0

    def _source_raw(self) -> dict:
        """The mapping generated cases start from: the base, or the named case ``from``."""
        src = self.dispersion.source if self.dispersion else None
        return self.common if src is None else merge(self.common, self.overrides.get(src, {}))

    def generated_raw(self, index: int) -> tuple[dict, dict]:
        """(scenario mapping, {variable: value drawn}) of generated case ``index``."""
        if not 0 <= index < self.n_generated:
            raise InputError(f"{self.path}: generated case index {index} out of range 0..{self.n_generated - 1}")
        key = (self.dispersion, id(self.common))
        if getattr(self, "_expanded", (None,))[0] != key:     # targets expanded once per scenario
            raw = self._source_raw()
            self._expanded = (key, raw, self.dispersion.columns(raw, Where(self.path, "dispersion")))
        _, raw, cols = self._expanded
        return self.dispersion.generate(raw, index, Where(self.path, "dispersion"), cols)

    def generated_case(self, index: int) -> Case:
        """The validated Case of generated case ``index`` (name :func:`case_name`)."""
        raw, _ = self.generated_raw(index)
        name = case_name(index)
        return _case(Where(self.path, f"case {name}"), raw, name, self.base)

    def with_generated(self, n_cases: int) -> Scenario:
        """This scenario with ``n_cases`` generated cases (the command line's --cases)."""
        if self.dispersion is None:
            if n_cases:
                raise InputError(f"{self.path}: --cases {n_cases}: the scenario has no [dispersion] section")
            return self
        sc = replace(self, dispersion=replace(self.dispersion, n_cases=check_case_count(self.path, n_cases)))
        if n_cases:
            sc.dispersion.check(sc._source_raw(), Where(self.path, "dispersion"))
        return sc


# --------------------------------------------------------------------- sections
def _profiles(w: Where, p: Any, base: Path) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    if not isinstance(p, dict):
        raise w.error("expected a table of named time tables")
    return {name: tabulated(w / name, table(w / name, tab, _PROFILE), base) for name, tab in p.items()}


def _posts(w: Where, posts: Any, wd: Where, defaults: Any) -> list[Post]:
    d = table(wd, defaults, LAW_KEYS)
    out, names = [], set()
    entries = array_of_tables(w, posts, "post", nonempty=True)
    for i, p in enumerate(entries):
        wp = w / i
        lacking = [k for k in ("vehicle", "pad") if isinstance(p, dict) and "name" in p and k not in p]
        if lacking:      # a case override's misspelt post name arrives here as a new, incomplete post
            known = [str(e.get("name")) for e in entries if isinstance(e, dict) and "vehicle" in e and "pad" in e]
            raise wp.named(str(p["name"])).error(
                f"no '{lacking[0]}': {p['name']!r} is not one of the posts ({', '.join(known)}), so it is a new "
                "post, which needs vehicle and pad")
        p = table(wp, p, _POST, required=("name", "vehicle", "pad"))
        q = {**d, **p}
        if p.get("rigid") is True and "stiffness" not in p:
            q.pop("stiffness", None)          # a default stiffness is for the elastic posts
        for own, other in (("normal", "axial"), ("axial", "normal")):
            if own in p and other not in p:
                q.pop(other, None)            # a post's own normal (or axial) replaces the defaults' other one
        wp = wp.named(unique_name(wp / "name", q["name"], names, "post"))
        vehicle, pad = string(wp / "vehicle", q["vehicle"]), string(wp / "pad", q["pad"])
        law = contact_law(wp, q, point_labels(vehicle, Post.DIRECTIONS), default_axial="Tz")
        out.append(Post(q["name"], vehicle, pad, law))
    return out


def _engines(w: Where, engines: Any, profiles: dict) -> list[Engine]:
    out, names = [], set()
    for i, e in enumerate(array_of_tables(w, engines, "engine")):
        we = w / i
        e = table(we, e, _ENGINE, required=("name", "mount"))
        we = we.named(name := unique_name(we / "name", e["name"], names, "engine"))
        d = vector(we / "direction", e.get("direction", [0.0, 0.0, 1.0]), length=3)
        if not np.linalg.norm(d) > 0:
            raise (we / "direction").error("zero thrust direction")
        if "profile" in e:
            if "time" in e or "thrust" in e:
                raise (we / "profile").error("give either profile (+ scale) or time + thrust, not both")
            prof = string(we / "profile", e["profile"])
            if prof not in profiles:
                raise (we / "profile").error(f"unknown profile {prof!r} (defined: {', '.join(profiles) or 'none'})")
            t, v = profiles[prof]
        else:
            if "time" not in e or "thrust" not in e:
                raise we.error("missing thrust table: give time + thrust (N) or profile + scale")
            t, v = tabulated(we, e, Path("."), vkey="thrust")
        v = v * number(we / "scale", e.get("scale", 1.0))
        if v[0] != 0.0:     # (a table is held at its first value before it begins: thrust before the start)
            raise (we / ("profile" if "profile" in e else "thrust")).error(
                f"the thrust table begins at {v[0]:.6g} N (t = {t[0]:g} s): an engine gives no thrust before its "
                "start, but a table holds its first value before it begins, so this engine would push from t0; "
                "begin the table at 0 N (a step: time [0, 0.001, ...] with thrust [0, F, ...])")
        out.append(Engine(name, string(we / "mount", e["mount"]), d / np.linalg.norm(d), t, v,
                          number(we / "start", e.get("start", 0.0))))
    return out


def _forces(w: Where, forces: Any, base: Path) -> list[Force]:
    """``[[force]]``: the shared force keys plus an optional ``name`` (so that cases and
    dispersions address a force by name: ``force[wind_x].scale``)."""
    out, names = [], set()
    for i, f in enumerate(array_of_tables(w, forces, "force")):
        f = table(w / i, f, FORCE_KEYS | {"name"}, required=("label",))
        if "name" in f:
            unique_name(w / i / "name", f["name"], names, "force")
        out.append(force(w / i, {k: v for k, v in f.items() if k != "name"}, base))
    return out


def _recovery(w: Where, spec: Any, base: Path) -> RecoveryPoints:
    r = table(w, spec, _RECOVERY)
    attach = strings(w / "attach", r.get("attach", []))
    points = [a.partition("@")[0] for a in attach]       # each recovered as attach_<point> (workflows/loads.py)
    for k, p in enumerate(points):
        if p in points[:k]:
            raise (w / "attach" / k).error(f"{attach[k]!r}: a second entry at point {p!r} ({attach[points.index(p)]!r} "
                                           "is the first); one interface force a point, on the component named")
    return RecoveryPoints(attach, strings(w / "stations", r.get("stations", [])),
                          string(w / "top", r["top"]) if "top" in r else None,
                          string(w / "payload", r["payload"]) if "payload" in r else None,
                          _otms(w / "otm", r.get("otm", []), base))


def _otms(w: Where, spec: Any, base: Path) -> tuple[InterfaceOTM, ...]:
    """``[[recovery.otm]]``: the file found, the names and units understood (the matrices
    are read when the case is built: they need pyyeti, the ``nastran`` extra)."""
    out, names = [], set()
    for i, o in enumerate(array_of_tables(w, spec, "recovery.otm")):
        o = table(w / i, o, _OTM, required=("name", "file", "point"))
        name = unique_name(w / i / "name", o["name"], names, "OTM")
        path = file_path(w / i / "file", o["file"], base).resolve()
        if not path.is_file():
            raise (w / i / "file").error(f"file not found: {str(path)!r}")
        parts = {k: string(w / i / k, o[k]) for k in ("disp", "vel", "acc") if k in o}
        if not parts:
            raise (w / i).error("give at least one of disp, vel, acc: the names of its matrices in the file")
        units = o.get("units", "SI")
        unit_system_at(w / i / "units", units)
        q = o.get("quantity", "displacement")
        quantity = string(w / i / "quantity", q) if isinstance(q, str) else strings(w / i / "quantity", q)
        rows = strings(w / i / "rows", o["rows"]) if "rows" in o else None
        out.append(InterfaceOTM(name, str(path), string(w / i / "point", o["point"]), rows=rows, quantity=quantity,
                                units=units, **parts))
    return tuple(out)


def _case(w: Where, d: dict, name: str, base: Path) -> Case:
    table(w, d, _TOP | {"name"})
    profiles = _profiles(w / "profiles", d.get("profiles", {}), base)
    o = table(w / "output", d.get("output", {}), _OUTPUT)
    return Case(
        name, w.source,
        model=model_config(w / "model", d.get("model", {}), base),
        posts=_posts(w / "post", d.get("post", []), w / "post_defaults", d.get("post_defaults", {})),
        engines=_engines(w / "engine", d.get("engine", []), profiles),
        gravity=gravity(w / "gravity", d.get("gravity", {}), default=STANDARD_GRAVITY),
        cryo=cryo(w / "cryo", d.get("cryo", {})),
        control=control(w / "control", d.get("control", {})),
        softening=softening(w / "softening", d.get("softening", {})),
        forces=_forces(w / "force", d.get("force", []), base),
        time=time_span(w / "time", d.get("time", {})),
        recovery=_recovery(w / "recovery", d.get("recovery", {}), base),
        output=OutputFlags(**{k: boolean(w / "output" / k, o.get(k, True)) for k in _OUTPUT}))


def _used_profiles(d: dict) -> set:
    engines = d.get("engine", [])
    return {e.get("profile") for e in engines if isinstance(e, dict)} if isinstance(engines, list) else set()


def _check_profiles_used(w: Where, profiles: Any, used: set) -> None:
    """A profile a case override defines that no engine of the case uses is a misspelt name
    (it would be merged in and ignored): an error."""
    for name in profiles if isinstance(profiles, dict) else ():
        if name not in used:
            raise (w / "profiles" / name).error(f"no engine uses this profile (engines use: "
                                                f"{', '.join(sorted(str(u) for u in used if u)) or 'none'})")


def checked_case_name(where: Where, value: Any, seen: set[str]) -> str:
    """A ``[[case]]`` name (lift-off and barge scenarios): plain and unique
    (:func:`~.values.unique_name`), and not a name the run's envelope outputs use."""
    name = unique_name(where, value, seen, "case")
    if name in RESERVED_CASE_NAMES:
        raise where.error(f"{name!r} names the run's envelope outputs (maxmin_envelope.csv): give the case another "
                          "name")
    return name


# --------------------------------------------------------------------- entry points
def parse_scenario(data: dict, source: str = "scenario", base: Path | str = ".", n_cases: int | None = None) -> Scenario:
    """Validate a scenario mapping (as read from TOML): one Case per [[case]] (or 'base');
    CSV paths relative to ``base``; ``n_cases`` overrides ``[dispersion] n_cases``."""
    w, base = Where(source), Path(base)
    data = resolve(data, source, base)              # extends = "shuttle" or a path (liftoff.config.extends)
    table(w, data, _TOP)
    if data.get("kind", "liftoff") != "liftoff":   # "barge": liftoff.config.barge
        raise (w / "kind").error(f"expected 'liftoff' for a lift-off scenario, got {data.get('kind')!r}")
    title = string(w / "title", data.get("title", "liftoff scenario"))
    description = string(w / "description", data.get("description", ""), nonempty=False)
    common = {k: v for k, v in data.items() if k not in _SCENARIO_ONLY}
    cases_raw = array_of_tables(w / "case", data.get("case", []), "case")
    base_case = _case(w, common, "base", base)  # errors in the base name the base key, not a case
    cases, names, overrides = [] if cases_raw else [base_case], set(), {}
    for i, c in enumerate(cases_raw):
        wc = w / "case" / i
        c = table(wc, c, _CASE, required=("name",))
        name = checked_case_name(wc / "name", c["name"], names)
        over = {k: v for k, v in c.items() if k != "name"}
        try:
            merged = merge(common, over)
        except InputError as exc:            # (a case's list entries merged by name: named twice)
            raise wc.error(str(exc)) from None
        cases.append(_case(wc, merged, name, base))
        cases[-1].from_case_table = True
        _check_profiles_used(wc, over.get("profiles"), _used_profiles(merged))
        overrides[name] = over
    post = postprocess(w / "postprocess", data.get("postprocess", {}))
    if n_cases and "dispersion" not in data:
        raise InputError(f"{source}: --cases {n_cases}: the scenario has no [dispersion] section")
    disp = dispersion(w / "dispersion", data["dispersion"], base, n_cases) if "dispersion" in data else None
    sc = Scenario(source, title, description, cases, common, overrides, base, disp, post, copy.deepcopy(data))
    if disp is not None:
        for i, c in enumerate(cases_raw):
            if re.fullmatch(r"d\d{4,}", str(c.get("name", ""))):
                raise (w / "case" / i / "name").error(f"{c['name']!r} is the name of a generated case "
                                                        "(d0000, d0001, ...): give the named case another name")
        if disp.source is not None and disp.source not in overrides:
            raise (w / "dispersion" / "from").error(f"no [[case]] named {disp.source!r} "
                                                     f"(cases: {', '.join(overrides) or 'none'})")
        if disp.n_cases:       # targets are checked when cases are generated (a scenario may drop a target's table)
            disp.check(sc._source_raw(), w / "dispersion")
    return sc


def default_text() -> str:
    """The embedded default scenario (package data liftoff/config/default_scenario.toml)."""
    return resources.files("liftoff.config").joinpath(DEFAULT_NAME).read_text(encoding="utf-8")


def load_scenario(path: str | Path | None = None, n_cases: int | None = None) -> Scenario:
    """Read and validate a scenario file; ``None`` gives the embedded default; ``n_cases``:
    the number of generated cases (overrides ``[dispersion] n_cases``)."""
    if path is None:
        source = f"<default {DEFAULT_NAME}>"
        return parse_scenario(parse_toml(default_text(), source), source, n_cases=n_cases)
    path = Path(path)
    return parse_scenario(read_scenario(path), path.name, path.resolve().parent, n_cases)
