"""Value checks for scenario files, shared by both formats (numpy only).

Every check raises :class:`liftoff.core.errors.InputError` with one line naming the file
and the key, ``file: key.path[3]: what``, built by :class:`Where`. This is the one
wording of every scenario error.
"""
from __future__ import annotations

import math
import re
from typing import Any, Callable

import numpy as np

from liftoff.core.errors import InputError
from liftoff.core.labels import split_label

# wording of a vector of the wrong length ({got} entries, {length} expected)
LENGTH_ENTRIES = "has {got} entries, expected {length}"
# the largest magnitude of a finite number in a scenario: no SI quantity of a lift-off comes
# near it, and squares and products of two such numbers stay finite (no overflow inside)
MAX_MAGNITUDE = 1e100


class Where:
    """Key path for one-line messages: ``file: post[2].stiffness: what``.

    ``where / "key"`` appends ``.key``; ``where / 3`` and ``where / "[3]"`` append ``[3]``;
    ``where.named(i, name)`` gives ``post[3] 'left_1'`` (an array entry with its name).
    """

    def __init__(self, source: str, key: str = ""):
        self.source, self.key = source, key

    def __truediv__(self, sub: str | int) -> Where:
        if isinstance(sub, int):
            return Where(self.source, f"{self.key}[{sub}]")
        if sub.startswith("["):
            return Where(self.source, f"{self.key}{sub}")
        return Where(self.source, f"{self.key}.{sub}" if self.key else sub)

    def named(self, name: str) -> Where:
        """This key with an entry's name appended: ``contact[0] 'post'``."""
        return Where(self.source, f"{self.key} {name!r}")

    def error(self, msg: str) -> InputError:
        return InputError(f"{self.source}: {self.key}: {msg}" if self.key else f"{self.source}: {msg}")

    def wrap(self, exc: InputError) -> InputError:
        """An InputError raised below (a model's own check) re-worded at this key."""
        return self.error(" ".join(str(exc).split()))


def table(where: Where, value: Any, allowed: set[str], required: tuple[str, ...] = ()) -> dict:
    """``value`` as a table whose keys are all in ``allowed`` and include ``required``."""
    if not isinstance(value, dict):
        raise where.error(f"expected a table, got {type(value).__name__}")
    unknown = sorted(set(value) - allowed)
    if unknown:
        raise where.error(f"unknown key {unknown[0]!r} (allowed: {', '.join(sorted(allowed))})")
    for key in required:
        if key not in value:
            raise where.error(f"missing required key {key!r}")
    return value


def require(where: Where, value: dict, required: dict[str, str]) -> None:
    """InputError at the first key of ``required`` (key -> what it is) missing from ``value``:
    a type's parameters whose dataclass defaults are another vehicle's, which a user's own
    component must therefore give."""
    for key, what in required.items():
        if key not in value:
            raise (where / key).error(f"missing: {what}")


def named(where: Where, value: Any, read: Callable[[Where, Any], Any] | None = None) -> dict:
    """A table of any names (points, joints, masses), each value read by ``read(where /
    name, value)`` (None: as given)."""
    t = table(where, value, set(value) if isinstance(value, dict) else set())
    return t if read is None else {n: read(where / n, v) for n, v in t.items()}


def xyz(where: Where, value: Any) -> tuple[float, float, float]:
    """A point ``[x, y, z]`` (m) as a tuple of floats."""
    return tuple(float(x) for x in vector(where, value, length=3))


def array_of_tables(where: Where, value: Any, what: str, *, nonempty: bool = False) -> list[dict]:
    """``value`` as an array of tables ``[[what]]`` (at least one when ``nonempty``)."""
    if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
        raise where.error(f"expected an array of tables [[{what}]]")
    if nonempty and not value:
        raise where.error(f"expected at least one [[{what}]] table")
    return value


def number(where: Where, value: Any, *, positive: bool = False, nonneg: bool = False,
           allow_inf: bool = False) -> float:
    """``value`` as a float: never NaN, finite unless ``allow_inf``, at most MAX_MAGNITUDE
    when finite, optionally > 0 or >= 0."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise where.error(f"expected a number, got {type(value).__name__} {value!r}")
    try:
        x = float(value)
    except OverflowError:
        raise where.error(f"the integer {value} is too large (at most {MAX_MAGNITUDE:g})") from None
    if math.isnan(x):
        raise where.error("value is NaN")
    if math.isinf(x) and not allow_inf:
        raise where.error(f"value is {x} (must be finite)")
    if math.isfinite(x) and abs(x) > MAX_MAGNITUDE:
        raise where.error(f"magnitude {x:g} is beyond {MAX_MAGNITUDE:g} (SI units; it would overflow inside)")
    if positive and not x > 0:
        raise where.error(f"must be positive, got {x:g}")
    if nonneg and x < 0:
        raise where.error(f"negative value {x:g}")
    return x


#: the largest integer a key takes when it names no bound of its own: counts and iteration
#: limits reach compiled code as 64-bit integers (10**400 reached numba after the model stages)
MAX_INTEGER = 2 ** 53


def integer(where: Where, value: Any, lo: int = 0, hi: int | None = None) -> int:
    """``value`` as an int (not a bool) in ``[lo, hi]`` (``hi`` None: MAX_INTEGER)."""
    if isinstance(value, bool) or not isinstance(value, int):
        raise where.error(f"expected an integer, got {type(value).__name__} {value!r}")
    hi = MAX_INTEGER if hi is None else hi
    if value < lo or value > hi:
        shown = f"{value:.3g}" if abs(value) > 10 ** 15 else str(value)
        raise where.error(f"{shown} out of range [{lo}, {hi}]")
    return value


def string(where: Where, value: Any, *, nonempty: bool = True) -> str:
    """``value`` as a string, non-empty unless ``nonempty`` is False."""
    if not isinstance(value, str):
        raise where.error(f"expected a string, got {type(value).__name__} {value!r}")
    if nonempty and not value:
        raise where.error(f"expected a non-empty string, got {value!r}")
    return value


def strings(where: Where, value: Any, *, nonempty: bool = False) -> tuple[str, ...]:
    """``value`` as an array of non-empty strings (at least one when ``nonempty``)."""
    if not isinstance(value, list):
        raise where.error(f"expected an array of strings, got {type(value).__name__}")
    if nonempty and not value:
        raise where.error("expected a non-empty array of strings")
    return tuple(string(where / i, v) for i, v in enumerate(value))


def choice(where: Where, value: Any, options: tuple[str, ...]) -> str:
    """``value`` as one of the strings ``options``."""
    s = string(where, value)
    if s not in options:
        raise where.error(f"must be one of {', '.join(options)}, got {s!r}")
    return s


def boolean(where: Where, value: Any) -> bool:
    """``value`` as a bool (TOML true/false; 0 and 1 are refused)."""
    if not isinstance(value, bool):
        raise where.error(f"expected true or false, got {value!r}")
    return value


def vector(where: Where, value: Any, *, length: int | None = None, positive: bool = False,
           nonneg: bool = False) -> np.ndarray:
    """``value`` (an array of numbers, each checked by :func:`number`) as a float array;
    ``length``: the required number of entries (checked after the entries)."""
    if not isinstance(value, list):
        raise where.error(f"expected an array of numbers, got {type(value).__name__}")
    out = np.array([number(where / i, v, positive=positive, nonneg=nonneg) for i, v in enumerate(value)],
                   dtype=float)
    if length is not None and out.size != length:
        raise where.error(LENGTH_ENTRIES.format(got=out.size, length=length))
    return out


def label(where: Where, value: Any) -> str:
    """``value`` as a well-formed DOF label ``point:Tx|Ty|Tz|Rx|Ry|Rz``."""
    s = string(where, value)
    try:
        split_label(s)
    except InputError as exc:
        raise where.wrap(exc) from None
    return s


def labels(where: Where, value: Any, *, allow_empty: bool = False) -> tuple[str, ...]:
    """``value`` (one label or an array of them) as distinct well-formed DOF labels."""
    if isinstance(value, str):
        value = [value]
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise where.error("expected a DOF label 'point:Tx' or an array of them")
    if not value and not allow_empty:
        raise where.error("empty list of DOF labels")
    if len(set(value)) != len(value):
        raise where.error("duplicate DOF label")
    return tuple(label(where / i, v) for i, v in enumerate(value))


SAFE_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.+-]{0,99}$")


def unique_name(where: Where, value: Any, seen: set[str], what: str) -> str:
    """A name not in ``seen`` (added to it): ``duplicate post name 'left_1'``. Names become
    file names and HDF5 keys, so they are plain: a letter or digit, then letters, digits
    and ``_ . + -`` (at most 100 characters; no '/', no spaces, not '.' or '..')."""
    name = string(where, value)
    if not SAFE_NAME.match(name):
        raise where.error(f"{what} name {name!r} is not a plain name (letters, digits, _ . + -; it becomes a "
                          "file name or an HDF5 key)")
    if name in seen:
        raise where.error(f"duplicate {what} name {name!r}")
    seen.add(name)
    return name
