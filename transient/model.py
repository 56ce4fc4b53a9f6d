"""Problem description of a two-body transient: contact points, forcing, outputs, initial state.

Plain dataclasses; each validates itself at construction and raises InputError with a
one-line message naming the culprit. Units are SI (N, N m, m, rad, s).
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from liftoff.core.errors import InputError
from liftoff.core.labels import split_label

from .body import ModalBody
from .result import COLUMNS

INF = math.inf


MAX_MAGNITUDE = 1e100  # as liftoff.config.values: beyond any SI quantity here, and overflow-safe when squared


def _finite(name: str, value) -> np.ndarray:
    """``value`` as a real float array of finite entries no larger than MAX_MAGNITUDE."""
    arr = np.asarray(value)
    if arr.dtype.kind == "c":
        raise InputError(f"{name} is complex; expected real numbers")
    try:
        arr = arr.astype(float)
    except (TypeError, ValueError):
        raise InputError(f"{name} is not numeric") from None
    if not arr.size:
        return arr
    # two reductions, no temporaries (a case checks n x n feedback matrices): NaN or inf in any
    # entry makes the max or the min NaN or infinite
    big = max(abs(float(arr.max())), abs(float(arr.min())))
    if not math.isfinite(big):
        raise InputError(f"{name} contains NaN or inf")
    if big > MAX_MAGNITUDE:
        raise InputError(f"{name} has a value of magnitude {big:.3g}, beyond {MAX_MAGNITUDE:g} "
                         "(SI units): it would overflow inside")
    return arr


def _body_key(who: str, body: str) -> str:
    if body not in ("a", "b"):
        raise InputError(f"{who}: body must be 'a' or 'b', got {body!r}")
    return body


@dataclass
class ContactPoint:
    """One contact point coupling ``len(labels_a)`` directions (eq. 2-3, section 2.7).

    ``labels_b[i]`` is the matching DOF on body B (None: B is ground at that point).
    ``stiffness`` K_C per direction (N/m or N m/rad), ignored when ``rigid`` (Lagrange bolt).
    ``axial`` indexes the normal direction; ``normal_sign = +1`` means A lies on the + side
    of B, so the separation is ``s = gap + normal_sign (x_a - x_b)`` on that direction.
    Bolted (all directions, tension and compression) while ``t < release_time``; after
    release compression-only on the axial direction, lateral directions free; recontact
    re-closes the axial direction only. While coupled, the force on A in direction i is
    ``-K_C (c_i + x_a - x_b)`` with ``c_axial = normal_sign gap`` and 0 laterally (a bolted
    point with a gap therefore starts preloaded).

    Contact laws beyond the reference's (all off by default; transient/contact_laws.py):

    * ``normal``: a direction over the point's DOFs (one entry per label, all translations),
      e.g. ``(0.6, 0, 0.8)`` over ``p:Tx, p:Ty, p:Tz``; the coupled directions become the
      normal and an orthonormal tangent basis (:func:`contact_frame`), ``axial`` is then the
      normal (row 0) and the separation is ``s = gap + normal_sign n . (x_a - x_b)``.
    * ``friction``: Coulomb coefficient mu on the tangent (non-axial) directions while the
      released point is closed: stick (the tangent K_C as an elastic stick spring,
      anchored where sticking began) or slip with ``|f_t| = mu N``.
    * ``damping``: a dashpot (N s/m per direction) in parallel with K_C while coupled;
      a closed normal carries ``max(0, K_C d + c d')`` and only while it penetrates.
    * ``latch_force``: a capture latch: once the released point, having been open at a step
      end since its release (or at t0), is closed again with a normal compression >=
      latch_force (N; 0: on first contact), it is bolted from the end of that step on,
      laterals anchored where they were (docking capture). A point released while at rest in
      contact (a post under the vehicle's weight) is not captured until it has separated; one
      closing at t0 (a docking begun in contact) counts as open.
    * ``release_force = (travel, force)``: a soft (controlled) release, e.g. tapered pins
      drawn through dies (m, N; travel strictly increasing from 0, forces >= 0, at least
      two points, F(s) linear between them). Let s = gap + normal_sign n . (x_a - x_b) be
      the separation of the normal row (s > 0 open). After release and until the point is
      *drawn out* (its separation has once reached travel[-1] at a step end) the normal
      row carries, besides compression, a **tension** up to F(s):

      - elastic: the spring K_C as when closed, anchored at the pin's drawn travel p
        (p = 0 until it first yields): tension K_C (s - p) while that is <= F(s);
      - yielding: when the tension demand exceeds F(s) the row carries the known tensile
        force F(s) (force on A towards B, f = -normal_sign F), with s taken at the start
        of the step (explicit: F varies over centimetres, dF/ds << K_C, so the lag is
        stable and O(h)); p follows so that K_C (s - p) = F(s) (the pin is drawn:
        plastic, the work F ds is dissipated, as for slipping friction);
      - yielding -> elastic when the elastic trial (the row's end position with the
        solved forces) gives a tension below F(s) or a compression (a mass that stops
        in the dies stays there, held by the pin);
      - a pin pushed back after it has yielded (p > 0) goes slack: the row then follows
        the ordinary released rules (the post in compression at s < 0) and the pin takes
        tension again once s >= p;
      - drawn out (s >= travel[-1] at a step end): for good, an ordinary released point
        (compression-only, recontact allowed).

      The point's state is CLOSED while its pin carries it (yielding included) and OPEN
      while the pin is slack or after it is drawn out, so its separation_time is the first
      step end at which neither pin nor post carries it: the time it is drawn out, or
      earlier where a yielded pin goes slack (a mass stopped in the dies that falls back
      onto the post separates there and recontacts). The result's
      metadata["soft_release"] gives each point's first yield and drawn-out times (None:
      never drawn out), which say which.

      Not with rigid=True, friction, a latch or damping on the normal (refused).
      Bolted before release_time as any post.
    """

    name: str
    labels_a: Sequence[str]
    labels_b: Sequence[str | None]
    stiffness: float | Sequence[float] = 0.0
    axial: int = 0
    normal_sign: float = 1.0
    gap: float = 0.0
    release_time: float = INF
    rigid: bool = False
    normal: Sequence[float] | None = None
    friction: float = 0.0
    damping: float | Sequence[float] = 0.0
    latch_force: float | None = None
    release_force: tuple[Sequence[float], Sequence[float]] | None = None

    def __post_init__(self) -> None:
        who = f"contact {self.name!r}"
        self.labels_a = tuple(self.labels_a)
        self.labels_b = tuple(None if b is None else str(b) for b in self.labels_b)
        n = len(self.labels_a)
        if n == 0:
            raise InputError(f"{who}: no directions (labels_a is empty)")
        if len(self.labels_b) != n:
            raise InputError(f"{who}: {n} labels_a but {len(self.labels_b)} labels_b")
        if not 0 <= int(self.axial) < n:
            raise InputError(f"{who}: axial index {self.axial} out of range 0..{n - 1}")
        self.axial = int(self.axial)
        if self.normal_sign not in (1, -1, 1.0, -1.0):
            raise InputError(f"{who}: normal_sign must be +1 or -1, got {self.normal_sign!r}")
        self.normal_sign = float(self.normal_sign)
        self.gap = float(_finite(f"{who}: gap", self.gap))
        if math.isnan(float(self.release_time)):
            raise InputError(f"{who}: release_time is NaN")
        self.release_time = float(self.release_time)
        k = np.broadcast_to(np.asarray(self.stiffness, dtype=float), (n,)).copy() \
            if np.ndim(self.stiffness) == 0 else np.asarray(self.stiffness, dtype=float).reshape(-1)
        if k.shape != (n,):
            raise InputError(f"{who}: {k.size} stiffness values for {n} directions")
        if not self.rigid:
            if not np.all(np.isfinite(k)):
                raise InputError(f"{who}: stiffness contains NaN or inf (use rigid=True for a rigid bolt)")
            _finite(f"{who}: stiffness", k)
            if np.any(k <= 0):
                raise InputError(f"{who}: stiffness must be positive, got {k.tolist()}")
        self.stiffness = k
        self.rigid = bool(self.rigid)
        self._laws(who, n)

    def _laws(self, who: str, n: int) -> None:
        """Check and normalise normal, friction, damping, latch_force and release_force."""
        translations = all(split_label(lab)[1] < 3 for lab in self.labels_a)
        if self.normal is not None:
            nv = np.asarray(self.normal, dtype=float).reshape(-1)
            if nv.shape != (n,) or not np.all(np.isfinite(nv)) or not np.linalg.norm(nv) > 0:
                raise InputError(f"{who}: normal must be {n} finite numbers (one per label), not all zero")
            if not translations:
                raise InputError(f"{who}: a normal needs translation labels (Tx, Ty, Tz) only")
            if self.axial != 0:
                raise InputError(f"{who}: with a normal, the normal is direction 0 (axial must be 0)")
            self.normal = nv / np.linalg.norm(nv)
        mu = float(self.friction)
        if not (math.isfinite(mu) and mu >= 0):
            raise InputError(f"{who}: friction coefficient must be >= 0, got {self.friction!r}")
        if mu > 0 and (self.rigid or n < 2 or not translations):
            raise InputError(f"{who}: friction needs a penalty (not rigid) contact with a normal and at least "
                             "one tangent direction, all translations")
        self.friction = mu
        c = np.asarray(self.damping, dtype=float)
        c = np.full(n, float(c)) if c.ndim == 0 else c.reshape(-1)
        if c.shape != (n,) or not np.all(np.isfinite(c)) or np.any(c < 0):
            raise InputError(f"{who}: damping must be one value or {n} values >= 0 (N s/m), got {self.damping!r}")
        if self.rigid and np.any(c > 0):
            raise InputError(f"{who}: a rigid contact takes no damping (the dashpot is in parallel with K_C)")
        self.damping = c
        if self.latch_force is not None:
            lf = float(self.latch_force)
            if not (math.isfinite(lf) and lf >= 0):
                raise InputError(f"{who}: latch_force must be >= 0 N, got {self.latch_force!r}")
            self.latch_force = lf
        if self.release_force is not None:
            self.release_force = self._release_table(who)

    def _release_table(self, who: str) -> tuple[np.ndarray, np.ndarray]:
        """(travel m, force N) of ``release_force``, checked (one-line InputError naming the key)."""
        key = f"{who}: release_force"
        rf = self.release_force
        if isinstance(rf, dict):
            rf = (rf.get("travel"), rf.get("force"))
        try:
            travel, force = rf
            s = np.asarray(travel, dtype=float).reshape(-1)
            F = np.asarray(force, dtype=float).reshape(-1)
        except (TypeError, ValueError):
            raise InputError(f"{key} must be (travel, force): two lists of numbers (m, N)") from None
        if s.size != F.size:
            raise InputError(f"{key}: {s.size} travel values but {F.size} forces")
        if s.size < 2:
            raise InputError(f"{key}: needs at least 2 points (travel, force), got {s.size}")
        if not (np.all(np.isfinite(s)) and np.all(np.isfinite(F))):
            raise InputError(f"{key} contains NaN or inf")
        if np.abs(np.concatenate([s, F])).max() > MAX_MAGNITUDE:
            raise InputError(f"{key} has a value beyond {MAX_MAGNITUDE:g} (SI units)")
        if s[0] != 0.0:
            raise InputError(f"{key}: travel must start at 0 m, got {s[0]!r}")
        if np.any(np.diff(s) <= 0):
            raise InputError(f"{key}: travel must be strictly increasing (m)")
        if np.any(F < 0):
            raise InputError(f"{key}: forces must be >= 0 N (the tension the pins carry), got {F.min()!r}")
        if self.rigid:
            raise InputError(f"{key} needs a penalty contact (not rigid): the pins' tension is carried by K_C")
        if self.friction > 0 or self.latch_force is not None or self.damping[self.axial] > 0:
            raise InputError(f"{key} cannot be combined with friction, a latch or damping on the normal "
                             "(not supported)")
        return s, F

    @property
    def n_dirs(self) -> int:
        return len(self.labels_a)

    @property
    def has_laws(self) -> bool:
        """True when the point uses friction, damping, a latch or a soft release (the kernel's extended path)."""
        return self.friction > 0 or bool(np.any(self.damping > 0)) or self.latch_force is not None \
            or self.release_force is not None

    def frame(self) -> np.ndarray:
        """(n_dirs, n_dirs) rows: the coupled directions over the labels (identity without a normal)."""
        return np.eye(self.n_dirs) if self.normal is None else contact_frame(self.normal)


def contact_frame(normal) -> np.ndarray:
    """Orthonormal rows: the unit ``normal`` first, then tangents by Gram-Schmidt on the unit
    vectors in label order (deterministic: a normal along the third label gives tangents
    along the first and second)."""
    n = np.asarray(normal, dtype=float)
    rows = [n / np.linalg.norm(n)]
    for e in np.eye(n.size):
        v = e - sum((r @ e) * r for r in rows)
        if np.linalg.norm(v) > 1e-8:
            rows.append(v / np.linalg.norm(v))
        if len(rows) == n.size:
            break
    return np.array(rows)


@dataclass
class PointForce:
    """Constant force (N) or moment (N m) at a labelled DOF of body 'a' or 'b'."""

    body: str
    label: str
    value: float

    def __post_init__(self) -> None:
        _body_key(f"force at {self.label!r}", self.body)
        self.value = float(_finite(f"force at {self.label!r}", self.value))


@dataclass
class TabulatedForce:
    """Force at a labelled DOF, piecewise linear in time, held at the end values outside."""

    body: str
    label: str
    time: np.ndarray
    value: np.ndarray

    def __post_init__(self) -> None:
        who = f"force table at {self.label!r}"
        _body_key(who, self.body)
        self.time = _finite(f"{who}: time", self.time).reshape(-1)
        self.value = _finite(f"{who}: value", self.value).reshape(-1)
        if self.time.size == 0 or self.time.size != self.value.size:
            raise InputError(f"{who}: {self.time.size} times but {self.value.size} values")
        if np.any(np.diff(self.time) <= 0):
            raise InputError(f"{who}: times must be strictly increasing")


@dataclass
class ModalForce:
    """Generalised forcing table (section 4.1): values (n_t, n_modes), piecewise linear in time."""

    body: str
    time: np.ndarray
    values: np.ndarray

    def __post_init__(self) -> None:
        who = f"modal force table on body {self.body!r}"
        _body_key(who, self.body)
        self.time = _finite(f"{who}: time", self.time).reshape(-1)
        self.values = _finite(f"{who}: values", self.values)
        if self.values.ndim != 2 or self.values.shape[0] != self.time.size or self.time.size == 0:
            raise InputError(f"{who}: values have shape {self.values.shape}, expected ({self.time.size}, n_modes)")
        if np.any(np.diff(self.time) <= 0):
            raise InputError(f"{who}: times must be strictly increasing")


@dataclass
class ModalFeedback:
    """Modal force ``matrix @ q + rate_matrix @ v`` taken at the start of each step and held
    over it (eq. 26; a control law's proportional and derivative parts).

    Active while ``since <= t < until``; in :func:`static_equilibrium` it enters as
    ``-matrix`` in the stiffness (the 'softening stiffness' KSOF of eq. 27). ``factors =
    (U, V)`` (n x r, r x n, ``matrix = U @ V``) give the displacement part in rank-factored
    form, so that the solver never factors an n x n matrix (KSOF has rank 3, eq. 27);
    ``(U, V, W)`` the rate part too (``rate_matrix = U @ W``: a control law's P and D terms
    through the same actuators); without them the solver finds factors by an SVD (cubic in n).
    Given its factors, a feedback needs no n x n matrix at all (``matrix`` and ``rate_matrix``
    None: the solver uses the factors alone, and :meth:`dense` forms the matrices for who
    wants them): the default's attitude hold and softening held 46 MB of them a case."""

    body: str
    matrix: np.ndarray | None = None
    until: float = INF
    rate_matrix: np.ndarray | None = None
    since: float = -INF
    factors: tuple | None = None

    def __post_init__(self) -> None:
        who = f"modal feedback on body {self.body!r}"
        _body_key(who, self.body)
        if self.matrix is None:
            if self.factors is None:
                raise InputError(f"{who}: give its matrix or its factors (U, V)")
            if self.rate_matrix is not None:
                raise InputError(f"{who}: a rate_matrix without its matrix; give the rate part as a factor W "
                                 "(factors = (U, V, W)) or both matrices")
        else:
            self.matrix = _finite(f"{who}: matrix", self.matrix)
            if self.matrix.ndim != 2 or self.matrix.shape[0] != self.matrix.shape[1]:
                raise InputError(f"{who}: matrix has shape {self.matrix.shape}, expected (n_modes, n_modes)")
        if self.rate_matrix is not None:
            self.rate_matrix = _finite(f"{who}: rate_matrix", self.rate_matrix)
            if self.rate_matrix.shape != self.matrix.shape:
                raise InputError(f"{who}: rate_matrix has shape {self.rate_matrix.shape}, expected {self.matrix.shape}")
        self.until, self.since = float(self.until), float(self.since)
        if math.isnan(self.since) or math.isnan(self.until) or not self.since < self.until:
            raise InputError(f"{who}: since = {self.since!r} s must be before until = {self.until!r} s")
        if self.factors is not None:
            if len(self.factors) not in (2, 3):
                raise InputError(f"{who}: factors are (U, V) or (U, V, W), got {len(self.factors)} arrays")
            U, V, *W = (_finite(f"{who}: factors", x) for x in self.factors)
            alone = self.matrix is None         # factors alone: nothing to check them against
            n = U.shape[0] if alone else self.matrix.shape[0]
            for part, A, name in ((V, self.matrix, "matrix"), *((w, self.rate_matrix, "rate_matrix") for w in W)):
                if A is None and not alone:
                    raise InputError(f"{who}: a rate factor W without a rate_matrix")
                if U.ndim != 2 or part.ndim != 2 or U.shape[0] != n or part.shape != (U.shape[1], n):
                    raise InputError(f"{who}: factors of shapes {U.shape}, {part.shape}, expected (n, r), (r, n) "
                                     f"with n = {n}")
                if alone:
                    continue
                x = np.cos(np.arange(n) + 0.5)      # one product checks U V = matrix (O(n^2), not O(n^3))
                y, z = A @ x, U @ (part @ x)
                if not np.allclose(y, z, rtol=1e-9, atol=1e-12 * max(float(np.abs(y).max(initial=0.0)), 1e-300)):
                    raise InputError(f"{who}: factors differ from the {name}")
            self.factors = (U, V, *W)

    @property
    def n_modes(self) -> int:
        """The modes of the body it acts on (the matrices' size)."""
        return int(self.matrix.shape[0] if self.matrix is not None else self.factors[0].shape[0])

    def dense(self) -> tuple[np.ndarray, np.ndarray | None]:
        """(matrix, rate_matrix or None), formed from the factors where not given (n x n each)."""
        if self.matrix is not None:
            return self.matrix, self.rate_matrix
        U, V, *W = self.factors
        return U @ V, (U @ W[0] if W else None)

    def active(self, t: float) -> bool:
        return self.since <= t < self.until


@dataclass
class Forcing:
    """All applied loads. ``gravity``: uniform acceleration (m/s^2) on both bodies (eq. 14)."""

    constant: list = field(default_factory=list)
    tables: list = field(default_factory=list)
    modal: list = field(default_factory=list)
    feedback: list = field(default_factory=list)
    gravity: Sequence[float] = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        self.constant, self.tables = list(self.constant), list(self.tables)
        self.modal, self.feedback = list(self.modal), list(self.feedback)
        g = _finite("gravity", self.gravity).reshape(-1)
        if g.shape != (3,):
            raise InputError(f"gravity must be a 3-vector (m/s^2), got shape {g.shape}")
        self.gravity = g


@dataclass
class Recovery:
    """Linear output y = disp @ q + vel @ qdot + acc @ qddot + const of one body (k rows
    each; ``const``: a fixed offset per row, in the row's unit, e.g. the applied-load term
    of an interface force, reduction.recovery).

    ``labels``: one per row (column of the history). ``units``: one string for every
    column, or one per column. ``category`` says what the item is, so that reports select
    items without reading names: ``"interface_force"``, ``"cg_motion"``, ``"modal"``,
    ``"displacement"``, or any word of the user's (default ``"user"``); ``description``:
    free text kept with it (e.g. the component an interface force acts on)."""

    name: str
    body: str
    labels: Sequence[str]
    disp: np.ndarray | None = None
    vel: np.ndarray | None = None
    acc: np.ndarray | None = None
    units: str | Sequence[str] = "SI"
    category: str = "user"
    description: str = ""
    const: np.ndarray | None = None

    def __post_init__(self) -> None:
        who = f"recovery {self.name!r}"
        _body_key(who, self.body)
        if not isinstance(self.name, str) or not self.name or "/" in self.name or self.name.endswith(COLUMNS):
            raise InputError(f"{who}: the name must be a non-empty string without '/' and not end in {COLUMNS!r}")
        self.labels = tuple(str(s) for s in self.labels)
        k = len(self.labels)
        units = (self.units,) * k if isinstance(self.units, str) else tuple(str(u) for u in self.units)
        if len(units) != k:
            raise InputError(f"{who}: {len(units)} units for {k} labels")
        self.units = units
        if not isinstance(self.category, str) or not self.category.strip():
            raise InputError(f"{who}: category must be a non-empty string, got {self.category!r}")
        if self.disp is None and self.vel is None and self.acc is None:
            raise InputError(f"{who}: needs at least one of disp, vel, acc")
        for key in ("disp", "vel", "acc"):
            m = getattr(self, key)
            if m is not None:
                m = _finite(f"{who}: {key}", m)
                if m.ndim != 2 or m.shape[0] != k:
                    raise InputError(f"{who}: {key} has shape {m.shape}, expected ({k}, n_modes)")
                setattr(self, key, m)
        if self.const is not None:
            self.const = _finite(f"{who}: const", self.const)
            if self.const.shape != (k,):
                raise InputError(f"{who}: const has shape {self.const.shape}, expected ({k},)")


@dataclass
class InitialState:
    """Modal displacements and velocities of both bodies at t0."""

    q_a: np.ndarray
    v_a: np.ndarray
    q_b: np.ndarray
    v_b: np.ndarray

    def __post_init__(self) -> None:
        for key in ("q_a", "v_a", "q_b", "v_b"):
            setattr(self, key, _finite(f"initial {key}", getattr(self, key)).reshape(-1))

    def check(self, body_a: ModalBody, body_b: ModalBody) -> None:
        for key, body in (("q_a", body_a), ("v_a", body_a), ("q_b", body_b), ("v_b", body_b)):
            if getattr(self, key).size != body.n_modes:
                raise InputError(f"initial {key} has {getattr(self, key).size} entries, "
                                 f"body {body.name!r} has {body.n_modes} modes")


METHODS = ("direct", "fixed-point")
#: the automatic step's steps a period of the bodies' highest mode unless a problem gives its own
DEFAULT_MODE_SAMPLES = 4.0
#: the fewest automatic steps a period of the bodies' highest mode: the Nyquist rate
MIN_MODE_SAMPLES = 2.0
#: the most: beyond it a finer step is asked for with h or [time] accuracy, not by sampling a
#: kHz mode that finely (64 samples a period of the default's 2.8 kHz mode: 1.7 million steps)
MAX_MODE_SAMPLES = 64.0


@dataclass
class TransientProblem:
    """Everything :func:`transient.solve` needs. ``h=None``: the automatic step (0.25/f_h,
    eq. 12, bounded by ``mode_samples`` steps a period of the bodies' highest mode and by
    the run; transient/stepping.py). ``mode_samples``: at least 2 (the Nyquist rate: fewer
    and the highest mode aliases in the recovered histories); 4 by default.
    ``accuracy``: the step is halved until the estimated error of every peak contact force
    is below this fraction of the largest one (transient/accuracy.py; None: off).
    ``memory_limit``: bytes the run may use (None: 80 % of the memory available).
    ``static_above_hz``: the elastic modes above it are residual-flexibility modes, solved
    quasi-statically (q = P/omega^2, no velocity or acceleration; pyyeti's ``rfcut``): their
    static flexibility is kept, their periods no longer set the step (None: every mode
    dynamic; transient/coefficients.py, docs/transient.md "Residual-flexibility modes").
    ``modal_scratch``: a folder (on disk) in which the histories of ``keep_modal`` are kept
    as they are marched, instead of memory: an unlinked file mapped into the result's arrays,
    the rows of each chunk handed to the page cache once written (liftoff/core/scratch.py),
    so that a long run's 0.6 GB of modal displacements do not stay resident (None: memory)."""

    body_a: ModalBody
    body_b: ModalBody
    contacts: list
    forcing: Forcing
    t_end: float
    h: float | None = None
    t0: float = 0.0
    method: str = "direct"
    tol: float = 1.0
    max_iter: int = 100
    initial: object = "static"
    outputs: dict = field(default_factory=dict)
    recoveries: list = field(default_factory=list)
    keep_modal: bool | str = False  # True: q, v, acc of both bodies; "q": q only
    progress: bool = True
    accuracy: float | None = None
    memory_limit: float | None = None
    mode_samples: float = DEFAULT_MODE_SAMPLES
    static_above_hz: float | None = None
    modal_scratch: str | None = None

    def __post_init__(self) -> None:
        self.contacts = list(self.contacts)
        self.recoveries = list(self.recoveries)
        if self.body_a.is_ground:
            raise InputError("body a must have modes (only body b may be ground)")
        if not (math.isfinite(self.t0) and math.isfinite(self.t_end) and self.t_end > self.t0):
            raise InputError(f"t_end = {self.t_end!r} s must be finite and greater than t0 = {self.t0!r} s")
        _finite("t0", self.t0), _finite("t_end", self.t_end)
        if self.h is not None and not (math.isfinite(self.h) and self.h > 0):
            raise InputError(f"time step h = {self.h!r} s must be positive and finite")
        if self.method not in METHODS:
            raise InputError(f"method must be one of {', '.join(METHODS)}, got {self.method!r}")
        if not (self.tol > 0 and math.isfinite(self.tol)):
            raise InputError(f"tol = {self.tol!r} N must be positive")
        if self.accuracy is not None and not (0 < self.accuracy < 1):
            raise InputError(f"accuracy = {self.accuracy!r} must be a fraction of the peak force in (0, 1)")
        if self.accuracy is not None and not any(len(c.labels_a) for c in self.contacts):
            raise InputError(f"accuracy = {self.accuracy!r}: it is a bound on the contact forces' estimated error, "
                             "and the problem has no contacts (nothing would be checked); give h instead")
        if not (math.isfinite(self.mode_samples) and MIN_MODE_SAMPLES <= self.mode_samples <= MAX_MODE_SAMPLES):
            raise InputError(f"mode_samples = {self.mode_samples!r} steps a period of the highest mode must be from "
                             f"{MIN_MODE_SAMPLES:g} (the Nyquist rate: fewer and that mode aliases) to "
                             f"{MAX_MODE_SAMPLES:g} (a finer step: give h or accuracy)")
        if self.static_above_hz is not None and not (math.isfinite(self.static_above_hz) and self.static_above_hz > 0):
            raise InputError(f"static_above_hz = {self.static_above_hz!r} Hz must be positive and finite (or None: "
                             "every mode dynamic)")
        if self.memory_limit is not None and not self.memory_limit > 0:
            raise InputError(f"memory_limit = {self.memory_limit!r} bytes must be positive")
        if int(self.max_iter) < 1:
            raise InputError(f"max_iter = {self.max_iter!r} must be at least 1")
        self.max_iter = int(self.max_iter)
        if self.keep_modal not in (True, False, "q"):
            raise InputError(f"keep_modal must be true, false or 'q' (modal displacements only), got {self.keep_modal!r}")
        if self.modal_scratch is not None and not os.path.isdir(self.modal_scratch):
            raise InputError(f"modal_scratch = {str(self.modal_scratch)!r}: not a folder (the modal histories' scratch "
                             "files go there)")
        if isinstance(self.initial, str):
            if self.initial not in ("static", "zero"):
                raise InputError(f"initial must be 'static', 'zero' or an InitialState, got {self.initial!r}")
        elif isinstance(self.initial, InitialState):
            self.initial.check(self.body_a, self.body_b)
        else:
            raise InputError(f"initial must be 'static', 'zero' or an InitialState, got {type(self.initial).__name__}")
        self.outputs = {k: list(self.outputs.get(k, [])) for k in ("a", "b")}
        for k in self.outputs:
            body = self.body(k)
            for lab in self.outputs[k]:
                body.dof_index(lab)
        names = set()
        for c in self.contacts:
            if not isinstance(c, ContactPoint):
                raise InputError(f"contacts must be ContactPoint objects, got {type(c).__name__}")
            if c.name in names:
                raise InputError(f"duplicate contact name {c.name!r}")
            names.add(c.name)
            for lab in c.labels_a:
                self.body_a.dof_index(lab)
            for lab in c.labels_b:
                if lab is not None:
                    if self.body_b.is_ground:
                        raise InputError(f"contact {c.name!r}: body b is ground, labels_b must be None, got {lab!r}")
                    self.body_b.dof_index(lab)
            if self.method == "fixed-point" and c.rigid:
                raise InputError(f"contact {c.name!r}: rigid contacts need method 'direct' "
                                 "(the fixed-point iteration needs a finite K_C)")
            if self.method == "fixed-point" and c.has_laws:
                raise InputError(f"contact {c.name!r}: friction, damping, latches and soft release need method "
                                 "'direct' (the fixed-point iteration is the reference's contact law only)")
        if self.static_above_hz is not None and (self.static_modes("a").any() or self.static_modes("b").any()):
            for c in self.contacts:
                if c.rigid or c.friction > 0 or np.any(np.asarray(c.damping) > 0):
                    what = "is rigid" if c.rigid else "has friction" if c.friction > 0 else "has a dashpot"
                    raise InputError(f"contact {c.name!r} {what}: its rows work on relative velocities, in which "
                                     f"the residual-flexibility modes (static_above_hz = {self.static_above_hz:g} Hz) "
                                     "have no part (their deformation rate is not modelled); make it a penalty "
                                     "contact without friction or damping, or keep every mode dynamic")
        f = self.forcing
        for p in f.constant + f.tables:
            self.body(p.body).dof_index(p.label)
        for m in f.modal:
            if m.values.shape[1] != self.body(m.body).n_modes:
                raise InputError(f"modal force table on body {m.body!r} has {m.values.shape[1]} columns, "
                                 f"body has {self.body(m.body).n_modes} modes")
        for fb in f.feedback:
            n = self.body(fb.body).n_modes
            if fb.n_modes != n:
                raise InputError(f"modal feedback on body {fb.body!r}: its matrix is {fb.n_modes} x {fb.n_modes}, "
                                 f"the body has {n} modes")
        rnames = set()
        for r in self.recoveries:
            if r.name in rnames:
                raise InputError(f"duplicate recovery name {r.name!r}")
            rnames.add(r.name)
            n = self.body(r.body).n_modes
            for key in ("disp", "vel", "acc"):
                m = getattr(r, key)
                if m is not None and m.shape[1] != n:
                    raise InputError(f"recovery {r.name!r}: {key} has {m.shape[1]} columns, body has {n} modes")

    def body(self, key: str) -> ModalBody:
        return self.body_a if key == "a" else self.body_b

    def static_modes(self, key: str) -> np.ndarray:
        """Boolean mask of body ``key``'s residual-flexibility modes: the elastic modes above
        ``static_above_hz`` (none when it is None), solved quasi-statically
        (transient/coefficients.py)."""
        return static_mask(self.body(key).omega, self.static_above_hz)


def static_mask(omega: np.ndarray, static_above_hz: float | None) -> np.ndarray:
    """Boolean mask of the residual-flexibility modes among ``omega`` (rad/s): those above
    ``static_above_hz`` (Hz; None: none)."""
    omega = np.asarray(omega, dtype=float)
    if static_above_hz is None:
        return np.zeros(omega.size, dtype=bool)
    return omega > 2.0 * math.pi * static_above_hz
