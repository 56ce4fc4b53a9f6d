"""Sections shared by both scenario formats (``liftoff transient`` and ``liftoff run``).

Each parser takes a :class:`Where` and the raw TOML value and returns a typed object:
time span, forces (constant, inline tables, CSV tables), gravity, the contact law of a
hold-down post or contact point (eq. 2-3, section 2.7), and the vehicle effects of
section 4 (gravity softening, control system, cryo preload). Units are SI (m, kg, s, N,
K, rad); the keys are documented in docs/transient-cli.md and docs/workflow.md.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from liftoff.core.errors import InputError
from liftoff.core.units import G0
from liftoff.transient.effects import softening_factors
from liftoff.transient.model import (DEFAULT_MODE_SAMPLES, MAX_MODE_SAMPLES, METHODS, MIN_MODE_SAMPLES, ContactPoint,
                                     ModalFeedback, PointForce, TabulatedForce, TransientProblem)

from .files import file_path, read_csv_table
from .values import Where, boolean, choice, integer, label, labels, number, string, strings, table, vector

TIME_KEYS = {"t0", "t_end", "h", "method", "tol", "max_iter", "accuracy", "mode_samples", "static_above_hz"}
#: the smallest [time] accuracy taken: 100 x the round-off of a peak after 1e6 steps (1e6 x 1.1e-16, ~1e-10 at most)
MIN_ACCURACY = 1e-8
MAX_STEPS = 1e9             # steps a run may take ([time] h): 1e9 steps of one output are 8 GB of history
#: a cryo temperature change below this (K) would be below absolute zero from any launch site's ambient
MIN_DELTA_T = -320.0
#: the largest free thermal strain |alpha delta_T| (metals from ambient to LH2: ~0.4 %); beyond it the
#: linear thermoelastic preload of section 4.3 means nothing
MAX_THERMAL_STRAIN = 0.02
FORCE_KEYS = {"label", "value", "time", "csv", "scale"}
GRAVITY_KEYS = {"accel"}
LAW_KEYS = {"stiffness", "rigid", "axial", "normal_sign", "gap", "release_time", "normal", "friction", "damping",
            "latch_force", "release_force"}
RELEASE_FORCE_KEYS = {"travel", "force"}
SOFTENING_KEYS = {"enabled", "until", "labels"}
CONTROL_KEYS = {"enabled", "gimbals", "start", "ramp", "law", "bandwidth_hz", "damping", "hold_start"}
#: the highest attitude-hold bandwidth (Hz) taken: a rigid-body attitude loop far above the
#: structure's first modes is not a control design (and its held feedback outruns any step)
MAX_BANDWIDTH_HZ = 20.0
CONTROL_LAWS = ("moment", "attitude-hold")
CRYO_KEYS = {"enabled", "component", "volumes", "delta_T", "alpha"}
STANDARD_GRAVITY = (0.0, 0.0, -G0)


# ---------------------------------------------------------------- time
@dataclass(frozen=True)
class TimeSpan:
    """``[time]``: the run from ``t0`` to ``t_end`` (s) in steps ``h`` (s; None: automatic,
    0.25/f_h of eq. 12 bounded by the bodies' highest frequency and the run); contact solve
    ``method``; fixed-point tolerance ``tol`` (N) and ``max_iter``; ``accuracy``: halve the
    step until the estimated error of every peak contact force is below this fraction of
    the largest (None: the step as given; transient/accuracy.py); ``mode_samples``: the
    automatic step's steps a period of the bodies' highest mode (>= 2, the Nyquist rate);
    ``static_above_hz``: the elastic modes above it (Hz) are residual-flexibility modes, solved
    quasi-statically (None: every mode dynamic; TransientProblem.static_above_hz)."""

    t_end: float
    t0: float = 0.0
    h: float | None = None
    method: str = "direct"
    tol: float = 1.0
    max_iter: int = 100
    accuracy: float | None = None
    mode_samples: float = DEFAULT_MODE_SAMPLES
    static_above_hz: float | None = None

    def problem(self, body_a, body_b, contacts: list, forcing, **rest) -> TransientProblem:
        """The one translation of a scenario into a :class:`TransientProblem` (lift-off
        cases, barge cases, two-body files): bodies, contacts and forcing as the scenario
        built them, this ``[time]``, and the rest (``initial``, ``outputs``, ``recoveries``,
        ``keep_modal``, ``progress``) by keyword."""
        return TransientProblem(body_a, body_b, contacts, forcing, t_end=self.t_end, h=self.h, t0=self.t0,
                                method=self.method, tol=self.tol, max_iter=self.max_iter, accuracy=self.accuracy,
                                mode_samples=self.mode_samples, static_above_hz=self.static_above_hz, **rest)


def time_span(where: Where, spec: Any, *, method: str | None = None) -> TimeSpan:
    """``[time]``; ``method`` (the command line's --method) overrides the file's."""
    t = table(where, spec, TIME_KEYS, required=("t_end",))
    t0 = number(where / "t0", t.get("t0", 0.0))
    t_end = number(where / "t_end", t["t_end"])
    if not t_end > t0:
        raise (where / "t_end").error(f"must be greater than t0 = {t0:g} s, got {t_end:g}")
    h = t.get("h", "auto")
    if isinstance(h, str):
        if h != "auto":
            raise (where / "h").error(f"expected a step in s or \"auto\" (0.25/f_h), got {h!r}")
        h = None
    else:
        h = number(where / "h", h, positive=True)
        if h > t_end - t0:
            raise (where / "h").error(f"step {h:g} s is longer than the run ({t_end - t0:g} s)")
        if (t_end - t0) / h > MAX_STEPS:
            raise (where / "h").error(f"step {h:g} s makes more than {MAX_STEPS:.0e} steps of the {t_end - t0:g} s run "
                                      "(no memory holds their histories): give a larger step or \"auto\"")
    meth = method if method is not None else choice(where / "method", t.get("method", "direct"), METHODS)
    accuracy = None
    if "accuracy" in t:
        accuracy = number(where / "accuracy", t["accuracy"], positive=True)
        if not accuracy < 1:
            raise (where / "accuracy").error(f"a fraction of the peak force below 1 (e.g. 0.01 for 1 %), got {accuracy:g}")
        if accuracy < MIN_ACCURACY:
            raise (where / "accuracy").error(
                f"{accuracy:g} is below what the arithmetic resolves: a peak force after 1e5-1e6 steps carries "
                f"round-off of ~1e-11 of itself, so halving the step cannot reach it; at least {MIN_ACCURACY:g}")
    samples = number(where / "mode_samples", t.get("mode_samples", DEFAULT_MODE_SAMPLES), positive=True)
    if not MIN_MODE_SAMPLES <= samples <= MAX_MODE_SAMPLES:
        raise (where / "mode_samples").error(
            f"steps a period of the bodies' highest mode: at least {MIN_MODE_SAMPLES:g} (the Nyquist rate: fewer "
            f"and that mode aliases in the histories) and at most {MAX_MODE_SAMPLES:g} (a finer step: give h or "
            f"accuracy), got {samples:g}")
    static = None
    if "static_above_hz" in t:
        static = number(where / "static_above_hz", t["static_above_hz"], positive=True)
    return TimeSpan(t_end, t0, h, meth, number(where / "tol", t.get("tol", 1.0), positive=True),
                    integer(where / "max_iter", t.get("max_iter", 100), 1), accuracy, samples, static)


# ---------------------------------------------------------------- tables and forces
def check_table(where_t: Where, where_v: Where, time: np.ndarray, values: np.ndarray) -> None:
    """A time table: >= 2 points, as many rows of values as times, time strictly increasing."""
    if time.size < 2:
        raise where_t.error(f"a table needs at least 2 time points, got {time.size}")
    if values.shape[0] != time.size:
        raise where_v.error(f"{time.size} times but {values.shape[0]} values (unequal lengths)")
    bad = np.flatnonzero(np.diff(time) <= 0)
    if bad.size:
        i = int(bad[0]) + 1
        raise where_t.error(f"time is not strictly increasing at entry {i} ({time[i - 1]:g} -> {time[i]:g} s)")


def csv_table(where: Where, value: Any, base: Path, columns: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """(time, values) of a CSV file named by ``value`` (relative to ``base``): time, then data columns."""
    tab = read_csv_table(file_path(where, value, base), where, columns=columns)
    time, values = tab[:, 0], (tab[:, 1] if columns == 2 else tab[:, 1:])
    check_table(where, where, time, values)
    return time, values


def inline_table(where: Where, spec: dict, vkey: str = "value") -> tuple[np.ndarray, np.ndarray]:
    """(time, values) of the arrays ``time`` (s) and ``vkey`` of a table."""
    time, values = vector(where / "time", spec["time"]), vector(where / vkey, spec[vkey])
    check_table(where / "time", where / vkey, time, values)
    return time, values


def tabulated(where: Where, spec: dict, base: Path, vkey: str = "value") -> tuple[np.ndarray, np.ndarray]:
    """A table given as ``time`` + ``vkey`` arrays or as ``csv`` (two columns), not both."""
    if "csv" in spec:
        if "time" in spec or vkey in spec:
            raise where.error(f"give either time/{vkey} arrays or csv, not both")
        return csv_table(where / "csv", spec["csv"], base)
    for key in ("time", vkey):
        if key not in spec:
            raise where.error(f"missing {key!r}: give time + {vkey} arrays or csv")
    return inline_table(where, spec, vkey)


@dataclass(frozen=True)
class Force:
    """A force (N) or moment (N m) at the DOF ``label``: ``value`` when constant, else the
    table (``time`` s, ``table``), piecewise linear and held at its end values outside."""

    label: str
    value: float = 0.0
    time: np.ndarray | None = None
    table: np.ndarray | None = None

    def on(self, body: str) -> PointForce | TabulatedForce:
        """The transient model's force on body ``'a'`` or ``'b'``."""
        if self.time is None:
            return PointForce(body, self.label, self.value)
        return TabulatedForce(body, self.label, self.time, self.table)


def force(where: Where, spec: dict, base: Path) -> Force:
    """One ``[[force]]`` (keys FORCE_KEYS, checked by the caller): constant ``value``,
    ``time`` + ``value`` arrays or ``csv``, times ``scale``."""
    lab = label(where / "label", spec["label"])
    w = where.named(lab)
    scale = number(w / "scale", spec.get("scale", 1.0))
    if "csv" in spec or isinstance(spec.get("value"), list):
        if "csv" not in spec and "time" not in spec:
            raise w.error("a tabulated force needs 'time' (s) with its 'value' (N)")
        t, v = tabulated(w, spec, base)
        return Force(lab, time=t, table=scale * v)
    if "value" not in spec:
        raise w.error("missing 'value' (N or N m), 'time' + 'value' or 'csv'")
    if "time" in spec:
        raise (w / "time").error("'time' given with a constant value")
    return Force(lab, value=scale * number(w / "value", spec["value"]))


# ---------------------------------------------------------------- gravity
def gravity(where: Where, spec: Any, default: Sequence[float] | None = None) -> np.ndarray:
    """``[gravity] accel`` (m/s^2, eq. 14); required unless a ``default`` is given."""
    g = table(where, spec, GRAVITY_KEYS, required=() if default is not None else ("accel",))
    return vector(where / "accel", g.get("accel", list(default or ())), length=3)


# ---------------------------------------------------------------- contact law
def contact_law(where: Where, spec: dict, directions: Sequence[str], default_axial: int | str = 0) -> ContactPoint:
    """The LAW_KEYS of a ``[[contact]]`` or ``[[post]]`` table coupling ``directions``: a
    ContactPoint over them (body b ground), which :func:`at_point` binds to a point's labels.

    transient.model.ContactPoint is the one description of a contact law (eq. 2-3, section
    2.7, and the laws beyond it): it checks every value and this parser only reads the
    TOML (types, the keys' spellings, stiffness or ``rigid``, ``axial`` by name, a gap >= 0:
    the scenario's posts and contacts start open or touching); its errors are re-worded at
    the key they name."""
    n = len(directions)
    rigid = boolean(where / "rigid", spec.get("rigid", False))
    if rigid:
        if "stiffness" in spec:
            raise (where / "stiffness").error("a rigid contact takes no stiffness (remove one of the two)")
        k: Any = 0.0
    else:
        if "stiffness" not in spec:
            raise where.error("missing required key 'stiffness' (N/m or N m/rad) or rigid = true")
        s = spec["stiffness"]
        k = vector(where / "stiffness", s, length=n) if isinstance(s, list) else number(where / "stiffness", s)
    law: dict[str, Any] = {"stiffness": k, "rigid": rigid,
                           "normal_sign": number(where / "normal_sign", spec.get("normal_sign", 1.0)),
                           "gap": number(where / "gap", spec.get("gap", 0.0), nonneg=True),
                           "release_time": number(where / "release_time", spec.get("release_time", math.inf),
                                                  allow_inf=True)}
    if "normal" in spec:
        if "axial" in spec:
            raise (where / "normal").error("give either axial (a direction) or normal (a vector), not both")
        law["normal"] = vector(where / "normal", spec["normal"], length=n)
    else:
        law["axial"] = axial_index(where / "axial", spec.get("axial", default_axial), directions)
    for key in ("friction", "latch_force"):
        if key in spec:
            law[key] = number(where / key, spec[key])
    if "damping" in spec:
        d = spec["damping"]
        law["damping"] = vector(where / "damping", d, length=n) if isinstance(d, list) else \
            number(where / "damping", d)
    if "release_force" in spec:
        r = table(where / "release_force", spec["release_force"], RELEASE_FORCE_KEYS, required=("travel", "force"))
        law["release_force"] = (vector(where / "release_force" / "travel", r["travel"]),
                                vector(where / "release_force" / "force", r["force"]))
    try:
        return ContactPoint("law", tuple(directions), (None,) * n, **law)
    except InputError as exc:
        msg = " ".join(str(exc).split()).removeprefix("contact 'law': ")
        key = msg.split(" ", 1)[0].rstrip(":")
        if key in LAW_KEYS:
            raise (where / key).error(msg.removeprefix(key).lstrip(": ")) from None
        raise where.error(msg) from None


def at_point(law: ContactPoint, name: str, labels_a: Sequence[str], labels_b: Sequence[str | None]) -> ContactPoint:
    """The contact point ``name`` with ``law`` (:func:`contact_law`) between ``labels_a`` and ``labels_b``."""
    return dataclasses.replace(law, name=name, labels_a=tuple(labels_a), labels_b=tuple(labels_b))


def axial_index(where: Where, value: Any, directions: Sequence[str]) -> int:
    """The normal direction: an index into ``directions`` or its name (a label of it, or
    its component ``Tz``)."""
    if isinstance(value, str):
        hits = [i for i, d in enumerate(directions) if value in (d, d.rpartition(":")[2])]
        if len(hits) != 1:
            raise where.error(f"{value!r} is not one of the directions {', '.join(directions)}")
        return hits[0]
    return integer(where, value, 0, len(directions) - 1)


# ---------------------------------------------------------------- effects (section 4)
@dataclass(frozen=True)
class Softening:
    """Gravity softening of body a (section 4.5, eq. 22-27), on while t < ``until`` (s);
    ``labels``: the DOFs that define the c.g. motion (eq. 22), None: all of body a."""

    enabled: bool = False
    until: float = math.inf
    labels: tuple[str, ...] | None = None

    def feedback(self, body, accel) -> ModalFeedback:
        """KSOF of eq. 27 for ``body`` under gravity ``accel`` as a held modal feedback (eq. 26)."""
        U, V = softening_factors(body, accel, boundary_labels=None if self.labels is None else list(self.labels))
        return ModalFeedback("a", until=self.until, factors=(U, V))        # rank 3: no n x n matrix


def softening(where: Where, spec: Any) -> Softening:
    s = table(where, spec, SOFTENING_KEYS)
    return Softening(boolean(where / "enabled", s.get("enabled", False)),
                     number(where / "until", s.get("until", math.inf), allow_inf=True),
                     labels(where / "labels", s["labels"]) if "labels" in s else None)


@dataclass(frozen=True)
class Control:
    """Control system (section 4.4, eq. 15-21): lateral forces at the ``gimbals`` DOFs that
    cancel the applied moment about the c.g., switched on at ``start`` over ``ramp`` (s).
    ``law = "attitude-hold"`` adds, from ``hold_start`` (s; default ``start``), a PD law
    on the vehicle's rigid-body attitude and rate through the same gimbals, with closed-loop
    natural frequency ``bandwidth_hz`` and damping ratio ``damping`` (transient.effects.attitude_hold;
    unused with law = "moment", so that a case can switch the law of a base that sets them)."""

    enabled: bool = False
    gimbals: tuple[str, ...] = ()
    start: float = -math.inf
    ramp: float = 0.0
    law: str = "moment"
    bandwidth_hz: float = 0.5
    damping: float = 0.7
    hold_start: float | None = None


def control(where: Where, spec: Any) -> Control:
    c = table(where, spec, CONTROL_KEYS)
    enabled = boolean(where / "enabled", c.get("enabled", False))
    if enabled:
        table(where, c, CONTROL_KEYS, required=("gimbals",))
    gimbals: tuple[str, ...] = ()
    if "gimbals" in c:
        if not isinstance(c["gimbals"], list) or len(c["gimbals"]) < 3:
            raise (where / "gimbals").error("expected >= 3 lateral gimbal DOF labels (e.g. 'srb_left_gimbal:Tx')")
        gimbals = labels(where / "gimbals", c["gimbals"])
    law = string(where / "law", c.get("law", "moment"))
    if law not in CONTROL_LAWS:
        raise (where / "law").error(f"must be one of {', '.join(CONTROL_LAWS)}, got {law!r}")
    bandwidth = number(where / "bandwidth_hz", c.get("bandwidth_hz", 0.5), positive=True)
    if bandwidth > MAX_BANDWIDTH_HZ:
        raise (where / "bandwidth_hz").error(
            f"{bandwidth:g} Hz: an attitude-hold loop acts on the rigid-body attitude and must stay well below the "
            f"vehicle's first elastic modes (a few Hz; launch vehicles: 0.1-2 Hz); at most {MAX_BANDWIDTH_HZ:g} Hz")
    damping = number(where / "damping", c.get("damping", 0.7), nonneg=True)
    if damping >= 5:
        raise (where / "damping").error(f"a damping ratio of {damping:g} is not a control design (use 0.5-1)")
    start = number(where / "start", c.get("start", -math.inf), allow_inf=True)
    hold_start = number(where / "hold_start", c["hold_start"]) if "hold_start" in c else None
    return Control(enabled, gimbals, start, number(where / "ramp", c.get("ramp", 0.0), nonneg=True), law,
                   bandwidth, damping, hold_start)


@dataclass(frozen=True)
class Cryo:
    """Cryogenic shrinkage (section 4.3): free thermal strain ``alpha`` (1/K) x ``delta_T``
    (K) of the ``volumes`` (physical volume groups) of vehicle ``component``."""

    enabled: bool = False
    component: str = ""
    volumes: tuple[str, ...] = ()
    delta_T: float = 0.0
    alpha: float = 0.0


def cryo(where: Where, spec: Any) -> Cryo:
    c = table(where, spec, CRYO_KEYS)
    enabled = boolean(where / "enabled", c.get("enabled", False))
    if enabled:
        table(where, c, CRYO_KEYS, required=("component", "volumes", "delta_T", "alpha"))
    delta_T = number(where / "delta_T", c["delta_T"]) if "delta_T" in c else 0.0
    alpha = number(where / "alpha", c["alpha"], positive=True) if "alpha" in c else 0.0
    if delta_T < MIN_DELTA_T:
        raise (where / "delta_T").error(f"{delta_T:g} K would cool below absolute zero (at most {-MIN_DELTA_T:g} K "
                                        "below ambient)")
    if abs(alpha * delta_T) > MAX_THERMAL_STRAIN:
        raise where.error(f"free thermal strain alpha delta_T = {alpha * delta_T:g} beyond {MAX_THERMAL_STRAIN:g} "
                          "(metals from ambient to LH2: ~0.004): check alpha (1/K) and delta_T (K)")
    return Cryo(enabled,
                string(where / "component", c["component"]) if "component" in c else "",
                strings(where / "volumes", c["volumes"], nonempty=True) if "volumes" in c else (),
                delta_T, alpha)
