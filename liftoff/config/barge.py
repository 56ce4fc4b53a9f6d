"""Barge-impact scenario files (``liftoff run``, ``kind = "barge"``) -> typed objects.

The reference's other problem (Prabhakar & Palermo, section 5, figures 7-9): a barge
carrying a tank on its transporter cradle, set moving by a wave, hits a pile-supported
dock; cases sweep the dock's stiffness. The format is documented key by key in
docs/barge.md; the embedded example is liftoff/config/barge_scenario.toml. Units SI (m, kg,
s, N). Errors are one line ``file: key.path: what``. ``[[case]]`` tables are merged over
the base as in lift-off scenarios (:func:`liftoff.config.extends.merge`).
"""
from __future__ import annotations

from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from liftoff.meshes.barge import BargeParams, CargoParams, DockParams, default_positions
from liftoff.meshes.layout import StackLayout

from .extends import read_scenario, resolve
from .files import parse_toml
from .model import ComponentModel, ModelConfig, SystemModel
from .params import builder
from .scenario import checked_case_name, merge
from .sections import FORCE_KEYS, Force, TimeSpan, force, time_span
from .values import Where, array_of_tables, boolean, integer, number, string, table

EXAMPLE_NAME = "barge_scenario.toml"
KIND = "barge"
PARTS = ("barge", "cargo", "dock")
_TOP = {"kind", "title", "description", "model", "impact", "fender", "force", "time", "output", "case"}
_MODEL = {"degree", "zeta", "barge", "cargo", "dock", "system"}
_PART = {"mesh_size", "n_modes", "f_max", "params"}
_SYSTEM = {"f_max", "dock_f_max", "residual_vectors"}
_IMPACT = {"velocity", "gap"}
_FENDER = {"stiffness", "lateral_stiffness", "friction", "damping"}
_OUTPUT = {"plots", "snapshots", "frames", "progress"}
_CASE = _TOP - {"case", "kind"} | {"name"}
_CLASSES = {"barge": BargeParams, "cargo": CargoParams, "dock": DockParams}
_TYPES = {"barge": "barge_hull", "cargo": "barge_cargo", "dock": "dock"}    # liftoff.config.component_types


@dataclass(frozen=True)
class BargeModel:
    """``[model]``: the three FE components (barge hull with cradle, cargo tank, dock), element
    degree, modal damping ratio and the system modes kept (Hz; None: all)."""

    degree: int
    zeta: float
    components: dict           # part -> ComponentModel (builder: BargeParams | CargoParams | DockParams)
    f_max: float | None = None
    dock_f_max: float | None = None
    residual_vectors: bool = True   # where modes are cut (reduction/truncation.py)

    def model_config(self) -> ModelConfig:
        """The lift-off ModelConfig view the model stages (workflows.pipeline) take."""
        return ModelConfig("fe", self.degree, self.zeta, StackLayout(), dict(self.components), {}, SystemModel())


@dataclass(frozen=True)
class Fender:
    """The rubber fender at each bow point as the contact spring (eq. 2-3): ``stiffness`` (N/m)
    along x (the normal), ``lateral_stiffness`` (N/m) in y and z, Coulomb ``friction`` on
    the hull, a ``damping`` dashpot (N s/m) in parallel."""

    stiffness: float
    lateral_stiffness: float
    friction: float = 0.0
    damping: float = 0.0


@dataclass(frozen=True)
class BargeOutput:
    plots: bool = True
    snapshots: bool = True
    frames: int = 8            # deformed-shape frames of the impact wave
    progress: bool = True


@dataclass
class BargeCase:
    """One validated case: models, impact velocity (m/s, +x towards the dock) and contact gap
    (m), fender law, applied forces on the barge (wave force tables), time span, outputs."""

    name: str
    source: str
    model: BargeModel
    velocity: float
    gap: float
    fender: Fender
    forces: list[Force]
    time: TimeSpan
    output: BargeOutput


@dataclass
class BargeScenario:
    path: str
    title: str
    description: str
    cases: list[BargeCase]


# ---------------------------------------------------------------- sections
def _part(where: Where, name: str, spec: Any, defaults: dict) -> ComponentModel:
    c = table(where, spec, _PART)
    params = c.get("params", {})
    size = number(where / "mesh_size", c["mesh_size"], positive=True) if "mesh_size" in c else None
    extra = {**defaults, **({} if size is None else {"mesh_size": size})}
    obj = builder(where / "params", _CLASSES[name], params, defaults=extra)
    n_modes = integer(where / "n_modes", c["n_modes"], 0) if "n_modes" in c else None
    f_max = number(where / "f_max", c["f_max"], positive=True) if "f_max" in c else None
    return ComponentModel(name, obj, size, n_modes, f_max if (f_max or n_modes) else 150.0, type=_TYPES[name])


def _check_fit(where: Where, comps: dict) -> None:
    """The cargo sits on the barge's saddles and the dock's fenders face the barge's bow points."""
    b, c, d = (comps[k].builder for k in PARTS)
    for name, pt in c.interface_points().items():
        if not np.allclose(pt, b.cargo_points()[name], atol=1e-9):
            raise (where / "cargo" / "params").error(f"interface point {name} at {pt.tolist()} is not on the barge's "
                                                     f"saddle top {b.cargo_points()[name].tolist()}")
    fend, bow = list(d.fender_points().values()), list(b.bow_points().values())
    if len(fend) != len(bow) or not all(np.allclose(f, p, atol=1e-9) for f, p in zip(fend, bow)):
        raise (where / "dock" / "params").error("the fender points must face the barge's bow points (face_x = "
                                                "barge length / 2 + fender depth, fender_yz = the barge's)")


def barge_model(where: Where, spec: Any) -> BargeModel:
    m = table(where, spec, _MODEL)
    degree = m.get("degree", 1)
    if isinstance(degree, bool) or degree not in (1, 2):
        raise (where / "degree").error(f"element degree must be 1 or 2, got {degree!r}")
    zeta = number(where / "zeta", m.get("zeta", 0.02), nonneg=True)
    if zeta >= 1:
        raise (where / "zeta").error(f"modal damping ratio must be < 1, got {zeta:g}")
    comps = {"barge": _part(where / "barge", "barge", m.get("barge", {}), {})}
    fit = default_positions(comps["barge"].builder)
    comps["cargo"] = _part(where / "cargo", "cargo", m.get("cargo", {}), fit["cargo"])
    comps["dock"] = _part(where / "dock", "dock", m.get("dock", {}), fit["dock"])
    _check_fit(where, comps)
    s = table(where / "system", m.get("system", {}), _SYSTEM)
    f_max = {k: number(where / "system" / k, v, positive=True) for k, v in s.items() if k != "residual_vectors"}
    rv = boolean(where / "system" / "residual_vectors", s.get("residual_vectors", True))
    return BargeModel(degree, zeta, comps, f_max.get("f_max"), f_max.get("dock_f_max"), rv)


def _fender(where: Where, spec: Any) -> Fender:
    f = table(where, spec, _FENDER, required=("stiffness",))
    k = number(where / "stiffness", f["stiffness"], positive=True)
    mu = number(where / "friction", f.get("friction", 0.0), nonneg=True)
    if "lateral_stiffness" in f and mu == 0.0:   # a released contact's laterals are free without friction
        raise (where / "lateral_stiffness").error("acts only as the stick spring of the fender's friction; with "
                                                  "friction = 0 the laterals are free: give friction > 0 or drop it")
    return Fender(k, number(where / "lateral_stiffness", f.get("lateral_stiffness", k), positive=True), mu,
                  number(where / "damping", f.get("damping", 0.0), nonneg=True))


def _velocity(where: Where, value, forces) -> float:
    """The barge's velocity towards the dock (m/s); away from it (< 0) only where forces push
    it back (without them nothing would ever touch)."""
    v = number(where, value)
    if v < 0 and not forces:
        raise where.error(f"{v:g} m/s is away from the dock and no [[force]] pushes the barge back: it would never "
                          "touch (give the velocity towards the dock, >= 0)")
    return v


def _case(w: Where, d: dict, name: str, base: Path) -> BargeCase:
    table(w, d, _TOP | {"name"})
    imp = table(w / "impact", d.get("impact", {}), _IMPACT, required=("velocity",))
    o = table(w / "output", d.get("output", {}), _OUTPUT)
    forces = [force(w / "force" / i, table(w / "force" / i, f, FORCE_KEYS, required=("label",)), base)
              for i, f in enumerate(array_of_tables(w / "force", d.get("force", []), "force"))]
    if "fender" not in d:
        raise w.error("missing required table [fender] (stiffness of the rubber fenders, N/m)")
    return BargeCase(
        name, w.source, barge_model(w / "model", d.get("model", {})),
        velocity=_velocity(w / "impact" / "velocity", imp["velocity"], forces),
        gap=number(w / "impact" / "gap", imp.get("gap", 0.0), nonneg=True),
        fender=_fender(w / "fender", d["fender"]), forces=forces,
        time=time_span(w / "time", d.get("time", {})),
        output=BargeOutput(boolean(w / "output" / "plots", o.get("plots", True)),
                           boolean(w / "output" / "snapshots", o.get("snapshots", True)),
                           integer(w / "output" / "frames", o.get("frames", 8), 0, 24),
                           boolean(w / "output" / "progress", o.get("progress", True))))


# ---------------------------------------------------------------- entry points
def parse_barge(data: dict, source: str = "scenario", base: Path | str = ".") -> BargeScenario:
    """Validate a barge scenario mapping: one BargeCase per [[case]] (or 'base')."""
    w, base = Where(source), Path(base)
    data = resolve(data, source, base)              # extends = "barge" or a path (liftoff.config.extends)
    table(w, data, _TOP)
    if data.get("kind", KIND) != KIND:
        raise (w / "kind").error(f"expected {KIND!r} for a barge scenario, got {data.get('kind')!r}")
    title = string(w / "title", data.get("title", "barge impact on a dock"))
    description = string(w / "description", data.get("description", ""), nonempty=False)
    common = {k: v for k, v in data.items() if k not in ("case", "title", "description", "kind")}
    cases_raw = array_of_tables(w / "case", data.get("case", []), "case")
    base_case = _case(w, common, "base", base)
    cases, names = [] if cases_raw else [base_case], set()
    for i, c in enumerate(cases_raw):
        wc = w / "case" / i
        c = table(wc, c, _CASE, required=("name",))
        name = checked_case_name(wc / "name", c["name"], names)
        cases.append(_case(wc, merge(common, {k: v for k, v in c.items() if k != "name"}), name, base))
    return BargeScenario(source, title, description, cases)


def example_text() -> str:
    """The embedded barge example (package data liftoff/config/barge_scenario.toml)."""
    return resources.files("liftoff.config").joinpath(EXAMPLE_NAME).read_text(encoding="utf-8")


def load_barge(path: str | Path | None = None) -> BargeScenario:
    """Read and validate a barge scenario file; ``None`` gives the embedded example."""
    if path is None:
        source = f"<example {EXAMPLE_NAME}>"
        return parse_barge(parse_toml(example_text(), source), source)
    path = Path(path)
    return parse_barge(read_scenario(path), path.name, path.resolve().parent)


def scenario_kind(path: str | Path | None) -> str:
    """``kind`` of a ``liftoff run`` scenario file: "liftoff" (the default) or "barge"."""
    if path is None:
        return "liftoff"
    kind = read_scenario(path).get("kind", "liftoff")
    return kind if isinstance(kind, str) else "liftoff"

