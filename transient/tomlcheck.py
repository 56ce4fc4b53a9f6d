"""Value checks for TOML input files, shared by the scenario loaders.

Used by transient/scenario.py and workflows/scenario.py (workflows may import transient,
never the reverse, so this lives here; numpy only). Every check raises
:class:`transient.errors.InputError` with a one-line message naming the file and the key,
``file: key.path[3]: message``, built by :class:`Where`.
"""
from __future__ import annotations

import math
from typing import Any

import numpy as np

from liftoff.core.errors import InputError

# wordings for a vector of the wrong length ({got} entries, {length} expected)
LENGTH_ENTRIES = "has {got} entries, expected {length}"
LENGTH_NUMBERS = "expected {length} numbers, got {got}"


class Where:
    """Key path for one-line messages: ``file: post[2].stiffness``.

    ``where / "key"`` appends ``.key``; ``where / 3`` and ``where / "[3]"`` append ``[3]``.
    """

    def __init__(self, source: str, key: str = ""):
        self.source, self.key = source, key

    def __truediv__(self, sub: str | int) -> Where:
        if isinstance(sub, int):
            return Where(self.source, f"{self.key}[{sub}]")
        if sub.startswith("["):
            return Where(self.source, f"{self.key}{sub}")
        return Where(self.source, f"{self.key}.{sub}" if self.key else sub)

    def error(self, msg: str) -> InputError:
        return InputError(f"{self.source}: {self.key}: {msg}" if self.key else f"{self.source}: {msg}")


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


def number(where: Where, value: Any, *, positive: bool = False, nonneg: bool = False,
           allow_inf: bool = False) -> float:
    """``value`` as a float: never NaN, finite unless ``allow_inf``, optionally > 0 or >= 0."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise where.error(f"expected a number, got {type(value).__name__} {value!r}")
    x = float(value)
    if math.isnan(x):
        raise where.error("value is NaN")
    if math.isinf(x) and not allow_inf:
        raise where.error(f"value is {x} (must be finite)")
    if positive and not x > 0:
        raise where.error(f"must be positive, got {x:g}")
    if nonneg and x < 0:
        raise where.error(f"negative value {x:g}")
    return x


def integer(where: Where, value: Any, lo: int = 0, hi: int | None = None) -> int:
    """``value`` as an int (not a bool) in ``[lo, hi]`` (``hi`` None: no upper bound)."""
    if isinstance(value, bool) or not isinstance(value, int):
        raise where.error(f"expected an integer, got {type(value).__name__} {value!r}")
    if value < lo or (hi is not None and value > hi):
        raise where.error(f"{value} out of range [{lo}, {hi if hi is not None else 'inf'}]")
    return value


def string(where: Where, value: Any, *, nonempty: bool = False) -> str:
    """``value`` as a string, optionally non-empty."""
    if not isinstance(value, str):
        raise where.error(f"expected a string, got {type(value).__name__} {value!r}")
    if nonempty and not value:
        raise where.error(f"expected a non-empty string, got {value!r}")
    return value


def boolean(where: Where, value: Any) -> bool:
    """``value`` as a bool (TOML true/false; 0 and 1 are refused)."""
    if not isinstance(value, bool):
        raise where.error(f"expected true or false, got {value!r}")
    return value


def vector(where: Where, value: Any, *, length: int | None = None, positive: bool = False,
           nonneg: bool = False, length_msg: str = LENGTH_ENTRIES) -> np.ndarray:
    """``value`` (an array of numbers, each checked by :func:`number`) as a float array.

    ``length``: the required number of entries; a mismatch is reported with ``length_msg``
    (a format string with ``{got}`` and ``{length}``), after the entries are checked.
    """
    if not isinstance(value, list):
        raise where.error(f"expected an array of numbers, got {type(value).__name__}")
    out = np.array([number(where / i, v, positive=positive, nonneg=nonneg) for i, v in enumerate(value)],
                   dtype=float)
    if length is not None and out.size != length:
        raise where.error(length_msg.format(got=out.size, length=length))
    return out
