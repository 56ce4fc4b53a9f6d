"""Two-body scenario files (``liftoff transient``) -> :class:`liftoff.transient.TransientProblem`.

A scenario names two modal body files, the contact points that couple them, the forcing,
the time span and what to record; the format is documented key by key in
docs/transient-cli.md. Paths inside a scenario are relative to the scenario file. Units
are SI (m, kg, s, N, rad). Every error is one line ``file: key.path: what``, e.g.
``lift.toml: contact[2] 'post_3'.stiffness[1]: negative value -1e+09``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from liftoff.core.errors import InputError
from liftoff.transient.body import ModalBody, ground, load_body
from liftoff.transient.model import Forcing, InitialState, ModalForce, Recovery, TransientProblem

from .files import file_path, read_toml
from .sections import (
    FORCE_KEYS,
    LAW_KEYS,
    Softening,
    check_table,
    at_point,
    contact_law,
    csv_table,
    force,
    gravity,
    softening,
    time_span,
)
from .values import Where, array_of_tables, boolean, labels, number, string, table, unique_name, vector

INITIAL_MODES = ("static", "zero", "given")

# keys allowed in each table; anything else is an InputError (a typo must not be ignored)
_TOP = {"title", "description", "bodies", "time", "gravity", "softening", "contact", "force",
        "modal_force", "initial", "output", "recovery"}
_CONTACT = {"name", "labels_a", "labels_b"} | LAW_KEYS
_FORCE = FORCE_KEYS | {"body"}
_MODAL_FORCE = {"body", "time", "values", "csv", "scale"}
_INITIAL = {"mode", "q_a", "v_a", "q_b", "v_b", "rigid_displacement_a", "rigid_velocity_a",
            "rigid_displacement_b", "rigid_velocity_b"}
_OUTPUT = {"a", "b", "keep_modal"}
_RECOVERY = {"name", "body", "file"}
# the softening keys of [gravity] before [softening] existed (still accepted)
_OLD_SOFTENING = ("softening", "softening_until", "softening_labels")


@dataclass
class TwoBodyScenario:
    """A loaded two-body scenario: the problem to solve plus where it came from."""

    path: Path
    title: str
    description: str
    problem: TransientProblem


# ---------------------------------------------------------------- helpers
def _on_body(where: Where, value: Any, body: ModalBody, *, allow_empty: bool = False) -> tuple[str, ...]:
    """DOF labels that exist on ``body``."""
    labs = labels(where, value, allow_empty=allow_empty)
    for i, lab in enumerate(labs):
        try:
            body.dof_index(lab)
        except InputError as exc:
            raise (where / i).wrap(exc) from None
    return labs


def _body_key(where: Where, value: Any, bodies: dict[str, ModalBody]) -> str:
    key = string(where, value)
    if key not in bodies:
        raise where.error(f"must be 'a' or 'b', got {key!r}")
    if bodies[key].is_ground:
        raise where.error(f"body {key} is ground: it takes no force")
    return key


# ---------------------------------------------------------------- sections
def _bodies(where: Where, spec: Any, base: Path) -> dict[str, ModalBody]:
    spec = table(where, spec, {"a", "b"}, required=("a", "b"))
    bodies = {}
    for key in ("a", "b"):
        w = where / key
        name = string(w, spec[key])
        if name != "ground":
            file_path(w, name, base)
        if name == "ground":
            if key == "a":
                raise w.error("body a cannot be 'ground' (use body b for a fixed support)")
            bodies[key] = ground()
            continue
        try:  # load_body names a missing or unreadable file
            bodies[key] = load_body((base / name).resolve())
        except InputError as exc:
            raise w.wrap(exc) from None
        if bodies[key].is_ground:
            raise w.error(f"body file {name!r} has no modes; write b = \"ground\" for a fixed support")
    return bodies


def _softening(top: Where, data: dict) -> tuple[Softening, Where, Where]:
    """[softening], or its older spelling in [gravity]: softening, softening_until,
    softening_labels; with the keys of the section and of its labels."""
    g = data.get("gravity", {})
    old = {k: g[k] for k in _OLD_SOFTENING if isinstance(g, dict) and k in g}
    if not old:
        w = top / "softening"
        return softening(w, data.get("softening", {})), w, w / "labels"
    w = top / "gravity"
    if "softening" in data:
        raise (w / next(iter(old))).error("softening is given in [softening]: remove it from [gravity]")
    if not boolean(w / "softening", old.get("softening", False)):
        for key in _OLD_SOFTENING[1:]:
            if key in old:
                raise (w / key).error("given without softening = true")
        return Softening(), w, w
    soft = Softening(True, number(w / "softening_until", old.get("softening_until", math.inf), allow_inf=True),
                     labels(w / "softening_labels", old["softening_labels"]) if "softening_labels" in old else None)
    return soft, w / "softening", w / "softening_labels"


def _forcing(top: Where, data: dict, bodies: dict[str, ModalBody], base: Path) -> Forcing:
    """[gravity], [softening] of body a (section 4.5), [[force]] and [[modal_force]]."""
    g = data.get("gravity")
    accel = np.zeros(3)
    if g is not None:
        g = {k: v for k, v in g.items() if k not in _OLD_SOFTENING} if isinstance(g, dict) else g
        accel = gravity(top / "gravity", g)
    soft, w, wl = _softening(top, data)
    feedback = []
    if soft.enabled:
        if g is None:
            raise w.error("needs [gravity] accel (softening is the moment of the weight)")
        if soft.labels is not None:
            _on_body(wl, list(soft.labels), bodies["a"])
        try:
            feedback.append(soft.feedback(bodies["a"], accel))
        except InputError as exc:
            raise w.wrap(exc) from None
    constant, tables = [], []
    for i, raw in enumerate(array_of_tables(top / "force", data.get("force", []), "force")):
        w = top / "force" / i
        f = table(w, raw, _FORCE, required=("body", "label"))
        key = _body_key(w / "body", f["body"], bodies)
        fo = force(w, f, base)
        try:
            bodies[key].dof_index(fo.label)
        except InputError as exc:
            raise (w / "label").wrap(exc) from None
        (constant if fo.time is None else tables).append(fo.on(key))
    modal = _modal_forces(top / "modal_force", data.get("modal_force", []), bodies, base)
    return Forcing(constant=constant, tables=tables, modal=modal, feedback=feedback, gravity=accel)


def _contacts(where: Where, spec: Any, body_a: ModalBody, body_b: ModalBody) -> list:
    out, names = [], set()
    for i, raw in enumerate(array_of_tables(where, spec, "contact", nonempty=True)):
        w = where / i
        c = table(w, raw, _CONTACT, required=("name", "labels_a"))
        name = unique_name(w / "name", c["name"], names, "contact")
        w = w.named(name)
        labels_a = _on_body(w / "labels_a", c["labels_a"], body_a)
        if body_b.is_ground:
            if c.get("labels_b"):
                raise (w / "labels_b").error("body b is ground: omit labels_b (ground DOFs are fixed at zero)")
            labels_b: tuple = (None,) * len(labels_a)  # ground: fixed at zero
        else:
            if "labels_b" not in c:
                raise w.error("missing required key 'labels_b'")
            labels_b = _on_body(w / "labels_b", c["labels_b"], body_b)
            if len(labels_b) != len(labels_a):
                raise (w / "labels_b").error(f"has {len(labels_b)} labels but labels_a has {len(labels_a)}")
        law = contact_law(w, c, labels_a)           # its errors name their key already
        try:
            out.append(at_point(law, name, labels_a, labels_b))
        except InputError as exc:
            raise w.wrap(exc) from None
    return out


def _modal_forces(where: Where, spec: Any, bodies: dict[str, ModalBody], base: Path) -> list[ModalForce]:
    out = []
    for i, raw in enumerate(array_of_tables(where, spec, "modal_force")):
        w = where / i
        f = table(w, raw, _MODAL_FORCE, required=("body",))
        key = _body_key(w / "body", f["body"], bodies)
        n = bodies[key].n_modes
        scale = number(w / "scale", f.get("scale", 1.0))
        if "csv" in f:
            if "time" in f or "values" in f:
                raise w.error("give either time/values arrays or csv, not both")
            time, values = csv_table(w / "csv", f["csv"], base, columns=n + 1)
        else:
            if "time" not in f or "values" not in f:
                raise w.error("missing 'time' and 'values' (or 'csv')")
            time = vector(w / "time", f["time"])
            if not isinstance(f["values"], list):
                raise (w / "values").error("expected an array of rows, one per time point")
            values = np.array([vector(w / "values" / j, row, length=n)
                               for j, row in enumerate(f["values"])]).reshape(-1, n)
            check_table(w / "time", w / "values", time, values)
        out.append(ModalForce(key, time, scale * values))
    return out


def _initial(where: Where, spec: Any, body_a: ModalBody, body_b: ModalBody):
    """mode static|zero, or given: modal q/v (full length) plus rigid-body motion about ref_point.

    A rigid-body motion u (Tx Ty Tz m, Rx Ry Rz rad; 3 or 6 entries) of a body adds the modal
    coordinates Phi^T M RB u = participation @ u (exact for a rigid motion, eq. 14 quantities).
    """
    spec = table(where, spec, _INITIAL)
    mode = string(where / "mode", spec.get("mode", "static"))
    if mode not in INITIAL_MODES:
        raise (where / "mode").error(f"must be one of {', '.join(INITIAL_MODES)}, got {mode!r}")
    given = [k for k in sorted(_INITIAL - {"mode"}) if k in spec]
    if mode != "given":
        if given:
            raise (where / given[0]).error(f"initial values need mode = \"given\" (mode is {mode!r})")
        return mode
    vec = {}
    for key, body in (("q_a", body_a), ("v_a", body_a), ("q_b", body_b), ("v_b", body_b)):
        vec[key] = (vector(where / key, spec[key], length=body.n_modes) if key in spec
                    else np.zeros(body.n_modes))
    for kind, target in (("displacement", "q"), ("velocity", "v")):
        for b, body in (("a", body_a), ("b", body_b)):
            key = f"rigid_{kind}_{b}"
            if key not in spec:
                continue
            if body.is_ground:
                raise (where / key).error("body b is ground: it has no rigid-body motion")
            u = vector(where / key, spec[key])
            if u.size not in (3, 6):
                raise (where / key).error(f"has {u.size} entries, expected 3 (Tx Ty Tz) or 6 (+ Rx Ry Rz)")
            vec[f"{target}_{b}"] = vec[f"{target}_{b}"] + body.participation[:, :u.size] @ u
    return InitialState(vec["q_a"], vec["v_a"], vec["q_b"], vec["v_b"])


def _outputs(where: Where, spec: Any, body_a: ModalBody, body_b: ModalBody) -> tuple[dict, bool]:
    spec = table(where, spec, _OUTPUT)
    outputs = {}
    for key, body in (("a", body_a), ("b", body_b)):
        if key in spec:
            if body.is_ground and spec[key]:
                raise (where / key).error("body b is ground: it has no outputs")
            outputs[key] = list(_on_body(where / key, spec[key], body, allow_empty=True))
        else:
            outputs[key] = []
    return outputs, boolean(where / "keep_modal", spec.get("keep_modal", False))


def _recovery_file(where: Where, path: Path, key: str, n: int) -> dict:
    """The arrays of one recovery .npz: labels, any of disp/vel/acc (labels x n modes), units."""
    if not path.is_file():
        raise where.error(f"recovery file not found: {str(path)!r}")
    try:
        with np.load(path, allow_pickle=False) as z:
            data = {k: z[k] for k in z.files}
    except Exception as exc:  # not an npz, pickled content ...
        raise where.error(f"{path.name} cannot be read as .npz: {' '.join(str(exc).split())}") from None
    unknown = sorted(set(data) - {"labels", "disp", "vel", "acc", "units"})
    if unknown:
        raise where.error(f"{path.name}: unknown array {unknown[0]!r} (allowed: labels, disp, vel, acc, units)")
    if "labels" not in data:
        raise where.error(f"{path.name}: missing array 'labels'")
    out = {"labels": [str(x) for x in np.atleast_1d(data["labels"])],
           "units": str(data["units"]) if "units" in data else "SI"}
    for kind in ("disp", "vel", "acc"):
        if kind in data:
            if np.iscomplexobj(data[kind]) or data[kind].dtype.kind not in "biuf":
                raise where.error(f"{path.name}: {kind} is {data[kind].dtype} (a recovery matrix of a modal model "
                                  "is real numbers)")
            m = np.asarray(data[kind], dtype=float)
            if m.shape != (len(out["labels"]), n):
                raise where.error(f"{path.name}: {kind} has shape {m.shape}, expected ({len(out['labels'])}, {n}) "
                                  f"(labels x modes of body {key})")
            if not np.all(np.isfinite(m)):
                raise where.error(f"{path.name}: {kind} contains NaN or inf")
            out[kind] = m
    return out


def _recoveries(where: Where, spec: Any, bodies: dict[str, ModalBody], base: Path) -> list[Recovery]:
    """[[recovery]]: linear output matrices from an .npz file (labels, disp/vel/acc, optional units)."""
    out, names = [], set()
    for i, raw in enumerate(array_of_tables(where, spec, "recovery")):
        w = where / i
        r = table(w, raw, _RECOVERY, required=("name", "body", "file"))
        name = unique_name(w / "name", r["name"], names, "recovery")
        key = _body_key(w / "body", r["body"], bodies)
        wf = w / "file"
        arrays = _recovery_file(wf, file_path(wf, r["file"], base), key, bodies[key].n_modes)
        try:
            out.append(Recovery(name, key, **arrays))
        except InputError as exc:
            raise wf.wrap(exc) from None
    return out


def check_step(where: Where, problem: TransientProblem) -> None:
    """The run's step (transient/stepping.py) chosen now, so that a step beyond the stability
    limit or the time axis's resolution names the file and ``[time]`` (warnings are given
    again when the run starts)."""
    import warnings

    from liftoff.transient.stepping import choose_step

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            choose_step(problem)
        except InputError as exc:
            raise where.wrap(exc) from None


# ---------------------------------------------------------------- entry points
def parse_twobody(data: dict, base: Path, source: str = "scenario", *, method: str | None = None,
                  progress: bool = True) -> TwoBodyScenario:
    """A :class:`TwoBodyScenario` from a parsed TOML mapping; paths relative to ``base``;
    ``method`` (the command line's --method) overrides ``[time] method``. Without
    ``[[contact]]`` it is a plain modal transient (pyyeti's ``SolveUnc.tsolve``)."""
    top = Where(source)
    table(top, data, _TOP, required=("bodies", "time"))
    title = string(top / "title", data.get("title", Path(source).stem))
    description = string(top / "description", data.get("description", ""), nonempty=False)
    bodies = _bodies(top / "bodies", data["bodies"], base)
    body_a, body_b = bodies["a"], bodies["b"]
    t = time_span(top / "time", data["time"], method=method)
    contacts = _contacts(top / "contact", data["contact"], body_a, body_b) if "contact" in data else []
    forcing = _forcing(top, data, bodies, base)
    initial = _initial(top / "initial", data.get("initial", {}), body_a, body_b)
    outputs, keep_modal = _outputs(top / "output", data.get("output", {}), body_a, body_b)
    recoveries = _recoveries(top / "recovery", data.get("recovery", []), bodies, base)
    try:
        problem = t.problem(body_a, body_b, contacts, forcing, initial=initial, outputs=outputs,
                            recoveries=recoveries, keep_modal=keep_modal, progress=progress)
    except InputError as exc:
        raise top.wrap(exc) from None
    check_step(top / "time", problem)
    return TwoBodyScenario(path=base / source, title=title, description=description, problem=problem)


def load_twobody(path: str | Path, *, method: str | None = None, progress: bool = True) -> TwoBodyScenario:
    """Read a two-body scenario file; relative paths inside it are taken from its directory."""
    path = Path(path)
    data = read_toml(path)
    scenario = parse_twobody(data, path.resolve().parent, path.name, method=method, progress=progress)
    scenario.path = path.resolve()
    return scenario

