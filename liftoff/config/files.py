"""Reading the text files of a scenario: the TOML file itself and numeric CSV tables.

Both are read as bytes and decoded here, so that every format reports a file that is not
UTF-8 text, a TOML syntax error or a bad CSV cell with the same one line
(``file: what`` or ``file: key.path: what``). A UTF-8 byte-order mark is accepted.
"""
from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np

from liftoff.core.errors import InputError

from .values import Where, string


def _text(raw: bytes, error) -> str:
    """``raw`` decoded as UTF-8; ``error(reason)`` gives the InputError otherwise."""
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise error(exc.reason) from None


def parse_toml(raw: bytes | str, source: str) -> dict:
    """The mapping of a TOML document (``raw``: the file's bytes or its text)."""
    if isinstance(raw, bytes):
        raw = _text(raw, lambda why: InputError(f"{source}: not a UTF-8 text file ({why})"))
    try:
        return tomllib.loads(raw)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{source}: TOML syntax error: {' '.join(str(exc).split())}") from None
    except RecursionError:
        raise InputError(f"{source}: TOML nested too deep for a scenario (arrays or tables inside one another "
                         "hundreds of levels deep)") from None
    except ValueError as exc:          # an integer of thousands of digits (Python's int-to-str limit)
        why = "an integer with thousands of digits" if "digits" in str(exc) else " ".join(str(exc).split())[:200]
        raise InputError(f"{source}: TOML value not usable: {why}") from None


def file_path(where: Where, value, base: Path) -> Path:
    """The file a scenario names (``value``, relative to ``base``): a non-empty string without
    NUL; a path that cannot be resolved (a symlink loop, too long) is an InputError."""
    name = string(where, value)
    if "\x00" in name or len(name) > 4096:
        raise where.error(f"not a usable file name: {name[:60]!r}")
    path = base / name
    try:
        path.resolve()
        path.stat()
    except FileNotFoundError:
        pass                       # the reader says "not found", naming the file
    except (OSError, RuntimeError, ValueError) as exc:
        raise where.error(f"file {name[:200]!r} cannot be opened: {' '.join(str(exc).split())}") from None
    return path


def read_toml(path: str | Path) -> dict:
    """Read a scenario TOML file; errors are named by the file's name."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: scenario file not found")
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise InputError(f"{path}: cannot be read ({exc.strerror or exc})") from None
    return parse_toml(raw, path.name)


def _is_number(cell: str) -> bool:
    try:
        float(cell)
        return True
    except ValueError:
        return False


def read_csv_table(path: Path, where: Where, columns: int | None = None) -> np.ndarray:
    """A numeric CSV table (comma separated, optional one-line header, '#' comments) as an
    array (rows, columns) of finite numbers; ``columns``: the required column count."""
    path = Path(path)
    if not path.is_file():
        raise where.error(f"CSV file not found: {str(path)!r}")
    rows: list[list[float]] = []
    header_allowed = True
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise where.error(f"{path.name} cannot be read ({exc.strerror or exc})") from None
    text = _text(raw, lambda why: where.error(f"{path.name} is not a UTF-8 text file ({why})"))
    for lineno, line in enumerate(text.splitlines(), start=1):
        text = line.split("#", 1)[0].strip()
        if not text:
            continue
        try:
            row = [float(c) for c in text.split(",")]
        except ValueError:
            # the first non-comment line may be a header: one without a number in it (a data row
            # with a typo, '0.0, 0.0O', was taken for one and the table started a row late)
            if header_allowed and not any(_is_number(c) for c in text.split(",")):
                header_allowed = False
                continue
            raise where.error(f"{path.name} line {lineno}: not a number in {text!r}") from None
        header_allowed = False
        if not all(math.isfinite(x) for x in row):
            raise where.error(f"{path.name} line {lineno}: NaN or inf in {text!r}")
        if rows and len(row) != len(rows[0]):
            raise where.error(f"{path.name} line {lineno}: {len(row)} columns, expected {len(rows[0])}")
        rows.append(row)
    if not rows:
        raise where.error(f"{path.name}: no data rows")
    table = np.array(rows, dtype=float)
    if columns is not None and table.shape[1] != columns:
        what = " (time, value)" if columns == 2 else " (time, then one per mode)"
        raise where.error(f"{path.name}: {table.shape[1]} columns, expected {columns}{what}")
    return table
