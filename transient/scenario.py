"""Two-body scenario files (TOML) -> :class:`transient.TransientProblem`.

A scenario names two modal body files, the contact points that couple them, the
forcing, the time span and what to record; the format is documented key by key in
docs/transient-cli.md. Paths inside a scenario are relative to the scenario file.
Units are SI (m, kg, s, N, rad).

Every check raises :class:`transient.errors.InputError` with a one-line message that
starts with the scenario file name and the key at fault, e.g.
``lift.toml: contact[2] 'post_3'.stiffness[1]: negative value -1e+09 (N/m)``.
"""
from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from liftoff.core.errors import InputError

from .body import ModalBody, ground, load_body
from .effects import softening_matrix
from .model import (
    METHODS,
    ContactPoint,
    Forcing,
    InitialState,
    ModalFeedback,
    ModalForce,
    PointForce,
    Recovery,
    TabulatedForce,
    TransientProblem,
)
from .tomlcheck import Where
from .tomlcheck import boolean as _bool
from .tomlcheck import integer as _integer
from .tomlcheck import number as _number
from .tomlcheck import string as _string
from .tomlcheck import table as _table
from .tomlcheck import vector as _vector

INITIAL_MODES = ("static", "zero", "given")

# keys allowed in each table; anything else is an InputError (a typo must not be ignored)
_TOP = {"title", "description", "bodies", "time", "gravity", "contact", "force",
        "modal_force", "initial", "output", "recovery"}
_BODIES = {"a", "b"}
_TIME = {"t_end", "h", "t0", "method", "tol", "max_iter"}
_GRAVITY = {"accel", "softening", "softening_until", "softening_labels"}
_CONTACT = {"name", "labels_a", "labels_b", "stiffness", "rigid", "axial", "normal_sign",
            "gap", "release_time"}
_FORCE = {"body", "label", "value", "time", "csv", "scale"}
_MODAL_FORCE = {"body", "time", "values", "csv", "scale"}
_INITIAL = {"mode", "q_a", "v_a", "q_b", "v_b", "rigid_displacement_a", "rigid_velocity_a",
            "rigid_displacement_b", "rigid_velocity_b"}
_OUTPUT = {"a", "b", "keep_modal"}
_RECOVERY = {"name", "body", "file"}


@dataclass
class Scenario:
    """A loaded scenario: the problem to solve plus where it came from."""

    path: Path
    title: str
    problem: TransientProblem
    body_files: dict[str, str] = field(default_factory=dict)


# ---------------------------------------------------------------- value checks
def _labels(where: Where, value: Any, body: ModalBody, *, allow_empty: bool = False) -> tuple[str, ...]:
    if isinstance(value, str):
        value = [value]
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise where.error("expected a DOF label 'point:Tx' or an array of them")
    if not value and not allow_empty:
        raise where.error("empty list of DOF labels")
    if len(set(value)) != len(value):
        raise where.error("duplicate DOF label")
    for i, lab in enumerate(value):
        try:
            body.dof_index(lab)
        except InputError as exc:
            raise (where / f"[{i}]").error(str(exc)) from None
    return tuple(value)


def _time_table(where: Where, time: np.ndarray, values: np.ndarray) -> None:
    if time.size < 2:
        raise where.error(f"a table needs at least 2 time points, got {time.size}")
    if values.shape[0] != time.size:
        raise where.error(f"time has {time.size} entries but value has {values.shape[0]} (unequal lengths)")
    bad = np.flatnonzero(np.diff(time) <= 0)
    if bad.size:
        i = int(bad[0]) + 1
        raise where.error(f"time is not strictly increasing at entry {i} ({time[i - 1]:g} -> {time[i]:g} s)")


def read_csv_table(path: Path, where: Where, columns: int | None = None) -> np.ndarray:
    """Read a numeric CSV table (comma separated, optional one-line header, '#' comments).

    Returns an array (rows, columns); every value must be finite.
    """
    if not path.is_file():
        raise where.error(f"CSV file not found: {str(path)!r}")
    rows: list[list[float]] = []
    header_allowed = True
    try:
        with open(path, encoding="utf-8") as fh:
            for lineno, line in enumerate(fh, start=1):
                text = line.split("#", 1)[0].strip()
                if not text:
                    continue
                try:
                    row = [float(c) for c in text.split(",")]
                except ValueError:
                    if header_allowed:  # the first non-comment line may be a header
                        header_allowed = False
                        continue
                    raise where.error(f"{path.name} line {lineno}: not a number in {text!r}") from None
                header_allowed = False
                if not all(math.isfinite(x) for x in row):
                    raise where.error(f"{path.name} line {lineno}: NaN or inf in {text!r}")
                if rows and len(row) != len(rows[0]):
                    raise where.error(f"{path.name} line {lineno}: {len(row)} columns, expected {len(rows[0])}")
                rows.append(row)
    except UnicodeDecodeError as exc:
        raise where.error(f"{path.name} is not a UTF-8 text file ({exc.reason})") from None
    if not rows:
        raise where.error(f"{path.name}: no data rows")
    table = np.array(rows, dtype=float)
    if columns is not None and table.shape[1] != columns:
        what = " (time, value)" if columns == 2 else " (time, then one per mode)"
        raise where.error(f"{path.name}: {table.shape[1]} columns, expected {columns}{what}")
    return table


# ---------------------------------------------------------------- sections
def _load_bodies(where: Where, spec: Any, base: Path) -> tuple[ModalBody, ModalBody, dict[str, str]]:
    spec = _table(where, spec, _BODIES, required=("a", "b"))
    bodies, files = {}, {}
    for key in ("a", "b"):
        w = where / key
        name = _string(w, spec[key])
        if name == "ground":
            if key == "a":
                raise w.error("body a cannot be 'ground' (use body b for a fixed support)")
            bodies[key], files[key] = ground(), "ground"
            continue
        path = (base / name).resolve()
        try:  # load_body names a missing or unreadable file
            bodies[key] = load_body(path)
        except InputError as exc:
            raise w.error(str(exc)) from None
        files[key] = str(path)
        if bodies[key].is_ground:
            raise w.error(f"body file {name!r} has no modes; write b = \"ground\" for a fixed support")
    return bodies["a"], bodies["b"], files


def _gravity(where: Where, spec: Any, body_a: ModalBody) -> tuple[tuple, list]:
    """[gravity]: uniform acceleration (eq. 14) and, optionally, gravity softening of body a
    (section 4.5: KSOF of eq. 27 as a modal feedback force held over each step, eq. 26)."""
    g = _table(where, spec, _GRAVITY, required=("accel",))
    accel = tuple(_vector(where / "accel", g["accel"], length=3))
    feedback = []
    if _bool(where / "softening", g.get("softening", False)):
        until = _number(where / "softening_until", g.get("softening_until", math.inf), allow_inf=True)
        labels = None
        if "softening_labels" in g:
            labels = list(_labels(where / "softening_labels", g["softening_labels"], body_a))
        try:
            ksof = softening_matrix(body_a, accel, boundary_labels=labels)
            feedback.append(ModalFeedback("a", ksof, until=until))
        except InputError as exc:
            raise (where / "softening").error(str(exc)) from None
    else:
        for key in ("softening_until", "softening_labels"):
            if key in g:
                raise (where / key).error("given without softening = true")
    return accel, feedback


def _contacts(where: Where, spec: Any, body_a: ModalBody, body_b: ModalBody) -> list:
    if not isinstance(spec, list) or not spec:
        raise where.error("expected at least one [[contact]] table")
    out, names = [], set()
    for i, raw in enumerate(spec):
        w = where / f"[{i}]"
        c = _table(w, raw, _CONTACT, required=("name", "labels_a"))
        name = _string(w / "name", c["name"])
        if name in names:
            raise (w / "name").error(f"duplicate contact name {name!r}")
        names.add(name)
        w = Where(where.source, f"{where.key}[{i}] {name!r}")
        labels_a = _labels(w / "labels_a", c["labels_a"], body_a)
        if body_b.is_ground:
            if c.get("labels_b"):
                raise (w / "labels_b").error("body b is ground: omit labels_b (ground DOFs are fixed at zero)")
            labels_b: tuple = (None,) * len(labels_a)  # ground: fixed at zero
        else:
            if "labels_b" not in c:
                raise w.error("missing required key 'labels_b'")
            labels_b = _labels(w / "labels_b", c["labels_b"], body_b)
            if len(labels_b) != len(labels_a):
                raise (w / "labels_b").error(f"has {len(labels_b)} labels but labels_a has {len(labels_a)}")
        ndir = len(labels_a)
        rigid = _bool(w / "rigid", c.get("rigid", False))
        if rigid:
            if "stiffness" in c:
                raise (w / "stiffness").error("a rigid contact takes no stiffness (remove one of the two)")
            stiffness = np.zeros(ndir)
        else:
            if "stiffness" not in c:
                raise w.error("missing required key 'stiffness' (N/m or N m/rad) or rigid = true")
            s = c["stiffness"]
            if isinstance(s, list):
                stiffness = _vector(w / "stiffness", s, length=ndir, nonneg=True)
            else:
                stiffness = np.full(ndir, _number(w / "stiffness", s, nonneg=True))
            if not np.all(stiffness > 0):
                raise (w / "stiffness").error("zero stiffness: give a positive coupling stiffness")
        axial = _integer(w / "axial", c.get("axial", 0), 0, ndir - 1)
        sign = _number(w / "normal_sign", c.get("normal_sign", 1.0))
        if sign not in (1.0, -1.0):
            raise (w / "normal_sign").error(f"must be 1 or -1, got {sign:g}")
        gap = _number(w / "gap", c.get("gap", 0.0), nonneg=True)
        release = _number(w / "release_time", c.get("release_time", math.inf), allow_inf=True)
        try:
            out.append(ContactPoint(name, list(labels_a), list(labels_b), stiffness, axial=axial,
                                    normal_sign=sign, gap=gap, release_time=release, rigid=rigid))
        except InputError as exc:
            raise w.error(str(exc)) from None
    return out


def _bodies_by_key(body_a: ModalBody, body_b: ModalBody) -> dict[str, ModalBody]:
    return {"a": body_a, "b": body_b}


def _body_key(where: Where, value: Any, bodies: dict[str, ModalBody]) -> str:
    key = _string(where, value)
    if key not in bodies:
        raise where.error(f"must be 'a' or 'b', got {key!r}")
    if bodies[key].is_ground:
        raise where.error(f"body {key} is ground: it takes no force")
    return key


def _forces(where: Where, spec: Any, bodies: dict[str, ModalBody], base: Path):
    if not isinstance(spec, list):
        raise where.error("expected [[force]] tables")
    constant, tables = [], []
    for i, raw in enumerate(spec):
        w = where / f"[{i}]"
        f = _table(w, raw, _FORCE, required=("body", "label"))
        key = _body_key(w / "body", f["body"], bodies)
        label = _labels(w / "label", f["label"], bodies[key])
        if len(label) != 1:
            raise (w / "label").error("one DOF label per [[force]]")
        label = label[0]
        w = Where(where.source, f"{where.key}[{i}] {label!r}")
        scale = _number(w / "scale", f.get("scale", 1.0))
        kinds = [k for k in ("csv", "time") if k in f]
        if len(kinds) > 1:
            raise w.error("give either time/value arrays or csv, not both")
        if "csv" in f:
            if "value" in f:
                raise w.error("give either value or csv, not both")
            path = base / _string(w / "csv", f["csv"])
            table = read_csv_table(path, w / "csv", columns=2)
            time, value = table[:, 0], table[:, 1]
            _time_table(w / "csv", time, value)
            tables.append(TabulatedForce(key, label, time, scale * value))
        elif "time" in f:
            if "value" not in f:
                raise w.error("time given without value")
            time = _vector(w / "time", f["time"])
            value = _vector(w / "value", f["value"])
            _time_table(w, time, value)
            tables.append(TabulatedForce(key, label, time, scale * value))
        else:
            if "value" not in f:
                raise w.error("missing 'value' (N or N m), 'time'+'value' or 'csv'")
            constant.append(PointForce(key, label, scale * _number(w / "value", f["value"])))
    return constant, tables


def _modal_forces(where: Where, spec: Any, bodies: dict[str, ModalBody], base: Path):
    if not isinstance(spec, list):
        raise where.error("expected [[modal_force]] tables")
    out = []
    for i, raw in enumerate(spec):
        w = where / f"[{i}]"
        f = _table(w, raw, _MODAL_FORCE, required=("body",))
        key = _body_key(w / "body", f["body"], bodies)
        n = bodies[key].n_modes
        scale = _number(w / "scale", f.get("scale", 1.0))
        if "csv" in f:
            if "time" in f or "values" in f:
                raise w.error("give either time/values arrays or csv, not both")
            table = read_csv_table(base / _string(w / "csv", f["csv"]), w / "csv", columns=n + 1)
            time, values = table[:, 0], table[:, 1:]
        else:
            if "time" not in f or "values" not in f:
                raise w.error("missing 'time' and 'values' (or 'csv')")
            time = _vector(w / "time", f["time"])
            if not isinstance(f["values"], list):
                raise (w / "values").error("expected an array of rows, one per time point")
            values = np.array([_vector(w / f"values[{j}]", row, length=n)
                               for j, row in enumerate(f["values"])]).reshape(-1, n)
        _time_table(w, time, values)
        out.append(ModalForce(key, time, scale * values))
    return out


def _initial(where: Where, spec: Any, body_a: ModalBody, body_b: ModalBody):
    """mode static|zero, or given: modal q/v (full length) plus rigid-body motion about ref_point.

    A rigid-body motion u (Tx Ty Tz m, Rx Ry Rz rad; 3 or 6 entries) of a body adds the modal
    coordinates Phi^T M RB u = participation @ u (exact for a rigid motion, eq. 14 quantities).
    """
    spec = _table(where, spec, _INITIAL)
    mode = _string(where / "mode", spec.get("mode", "static"))
    if mode not in INITIAL_MODES:
        raise (where / "mode").error(f"must be one of {', '.join(INITIAL_MODES)}, got {mode!r}")
    given = [k for k in sorted(_INITIAL - {"mode"}) if k in spec]
    if mode != "given":
        if given:
            raise (where / given[0]).error(f"initial values need mode = \"given\" (mode is {mode!r})")
        return mode
    vec = {}
    for key, body in (("q_a", body_a), ("v_a", body_a), ("q_b", body_b), ("v_b", body_b)):
        vec[key] = (_vector(where / key, spec[key], length=body.n_modes) if key in spec
                    else np.zeros(body.n_modes))
    for kind, target in (("displacement", "q"), ("velocity", "v")):
        for b, body in (("a", body_a), ("b", body_b)):
            key = f"rigid_{kind}_{b}"
            if key not in spec:
                continue
            if body.is_ground:
                raise (where / key).error("body b is ground: it has no rigid-body motion")
            u = _vector(where / key, spec[key])
            if u.size not in (3, 6):
                raise (where / key).error(f"has {u.size} entries, expected 3 (Tx Ty Tz) or 6 (+ Rx Ry Rz)")
            vec[f"{target}_{b}"] = vec[f"{target}_{b}"] + body.participation[:, :u.size] @ u
    return InitialState(vec["q_a"], vec["v_a"], vec["q_b"], vec["v_b"])


def _outputs(where: Where, spec: Any, body_a: ModalBody, body_b: ModalBody) -> tuple[dict, bool]:
    spec = _table(where, spec, _OUTPUT)
    outputs = {}
    for key, body in (("a", body_a), ("b", body_b)):
        if key in spec:
            if body.is_ground and spec[key]:
                raise (where / key).error("body b is ground: it has no outputs")
            outputs[key] = list(_labels(where / key, spec[key], body, allow_empty=True))
        else:
            outputs[key] = []
    keep = _bool(where / "keep_modal", spec.get("keep_modal", False))
    return outputs, keep


def _recoveries(where: Where, spec: Any, bodies: dict[str, ModalBody], base: Path) -> list:
    """[[recovery]]: linear output matrices from an .npz file (labels, disp/vel/acc, optional units)."""
    if not isinstance(spec, list):
        raise where.error("expected [[recovery]] tables")
    out, names = [], set()
    for i, raw in enumerate(spec):
        w = where / f"[{i}]"
        r = _table(w, raw, _RECOVERY, required=("name", "body", "file"))
        name = _string(w / "name", r["name"])
        if name in names:
            raise (w / "name").error(f"duplicate recovery name {name!r}")
        names.add(name)
        key = _body_key(w / "body", r["body"], bodies)
        path = base / _string(w / "file", r["file"])
        wf = w / "file"
        if not path.is_file():
            raise wf.error(f"recovery file not found: {str(path)!r}")
        try:
            with np.load(path, allow_pickle=False) as z:
                data = {k: z[k] for k in z.files}
        except Exception as exc:  # not an npz, pickled content ...
            raise wf.error(f"{path.name} cannot be read as .npz: {exc}") from None
        unknown = sorted(set(data) - {"labels", "disp", "vel", "acc", "units"})
        if unknown:
            raise wf.error(f"{path.name}: unknown array {unknown[0]!r} (allowed: labels, disp, vel, acc, units)")
        if "labels" not in data:
            raise wf.error(f"{path.name}: missing array 'labels'")
        labels = [str(x) for x in np.atleast_1d(data["labels"])]
        n = bodies[key].n_modes
        mats = {}
        for kind in ("disp", "vel", "acc"):
            if kind in data:
                m = np.asarray(data[kind], dtype=float)
                if m.shape != (len(labels), n):
                    raise wf.error(f"{path.name}: {kind} has shape {m.shape}, expected ({len(labels)}, {n}) "
                                   f"(labels x modes of body {key})")
                if not np.all(np.isfinite(m)):
                    raise wf.error(f"{path.name}: {kind} contains NaN or inf")
                mats[kind] = m
        units = str(data["units"]) if "units" in data else "SI"
        try:
            out.append(Recovery(name, key, labels, units=units, **mats))
        except InputError as exc:
            raise wf.error(str(exc)) from None
    return out


# ---------------------------------------------------------------- entry points
def parse_scenario(data: dict, base: Path, source: str = "scenario", *, method: str | None = None,
                   progress: bool = True) -> Scenario:
    """Build a :class:`Scenario` from an already-parsed TOML mapping; paths relative to ``base``."""
    top = Where(source)
    _table(top, data, _TOP, required=("bodies", "time", "contact"))
    title = _string(top / "title", data.get("title", Path(source).stem))
    if "description" in data:
        _string(top / "description", data["description"])
    body_a, body_b, files = _load_bodies(top / "bodies", data["bodies"], base)
    bodies = _bodies_by_key(body_a, body_b)

    wt = top / "time"
    tspec = _table(wt, data["time"], _TIME, required=("t_end",))
    t0 = _number(wt / "t0", tspec.get("t0", 0.0))
    t_end = _number(wt / "t_end", tspec["t_end"])
    if not t_end > t0:
        raise (wt / "t_end").error(f"must be greater than t0 = {t0:g} s, got {t_end:g}")
    h = _number(wt / "h", tspec["h"], positive=True) if "h" in tspec else None
    if h is not None and h > t_end - t0:
        raise (wt / "h").error(f"step {h:g} s is longer than the run ({t_end - t0:g} s)")
    meth = method if method is not None else _string(wt / "method", tspec.get("method", "direct"))
    if meth not in METHODS:
        raise (wt / "method").error(f"must be one of {', '.join(METHODS)}, got {meth!r}")
    tol = _number(wt / "tol", tspec.get("tol", 1.0), positive=True)
    max_iter = _integer(wt / "max_iter", tspec.get("max_iter", 100), 1)

    contacts = _contacts(top / "contact", data["contact"], body_a, body_b)

    gravity, feedback = (0.0, 0.0, 0.0), []
    if "gravity" in data:
        gravity, feedback = _gravity(top / "gravity", data["gravity"], body_a)
    constant, tables = _forces(top / "force", data.get("force", []), bodies, base)
    modal = _modal_forces(top / "modal_force", data.get("modal_force", []), bodies, base)
    forcing = Forcing(constant=constant, tables=tables, modal=modal, feedback=feedback, gravity=gravity)

    initial = _initial(top / "initial", data.get("initial", {}), body_a, body_b)
    outputs, keep_modal = _outputs(top / "output", data.get("output", {}), body_a, body_b)
    recoveries = _recoveries(top / "recovery", data.get("recovery", []), bodies, base)
    try:
        problem = TransientProblem(body_a, body_b, contacts, forcing, t_end, h=h, t0=t0, method=meth,
                                   tol=tol, max_iter=max_iter, initial=initial, outputs=outputs,
                                   recoveries=recoveries, keep_modal=keep_modal, progress=progress)
    except InputError as exc:
        raise top.error(str(exc)) from None
    return Scenario(path=base / source, title=title, problem=problem, body_files=files)


def load_scenario(path, *, method: str | None = None, progress: bool = True) -> Scenario:
    """Read a scenario TOML file; relative paths inside it are taken from its directory."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"scenario file not found: {str(path)!r}")
    try:
        with open(path, "rb") as fh:
            data = tomllib.load(fh)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{path.name}: TOML syntax error: {exc}") from None
    except UnicodeDecodeError as exc:
        raise InputError(f"{path.name}: not a UTF-8 text file ({exc.reason})") from None
    scenario = parse_scenario(data, path.resolve().parent, path.name, method=method, progress=progress)
    scenario.path = path.resolve()
    return scenario
