"""Files: atomic writes and self-describing records (format, version, units), no pickle.

A result is written to a temporary file beside its target and renamed onto it
(``os.replace``, atomic on POSIX) only when the writing succeeded, so a reader never sees
a half-written file and a failed run leaves no file that looks valid.
"""
from __future__ import annotations

import os
import tempfile
from collections.abc import Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Iterator

import numpy as np

from .errors import InputError


@contextmanager
def atomic_path(path: str | os.PathLike, suffix: str = ".tmp") -> Iterator[Path]:
    """Yield a temporary path in the folder of ``path`` (created if needed).

    When the ``with`` block succeeds, the temporary file is given the usual permissions
    (0666 less the umask; ``mkstemp`` makes it 0600) and renamed onto ``path``; when the
    block raises, it is removed and ``path`` is left as it was. ``suffix`` is the temporary
    file's extension, for writers that choose the format by it (``.png``, ``.vtu``).
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=suffix)
    os.close(fd)
    try:
        yield Path(tmp)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def write_text(path: str | os.PathLike, text: str) -> Path:
    """Write a text file atomically; returns its path."""
    with atomic_path(path) as tmp:
        tmp.write_text(text)
    return Path(path)


# ------------------------------------------------------------------ records
class Dataset:
    """An array with HDF5 attributes (``units`` and others) for :func:`write_record`;
    in ``.npz`` records the attributes are not stored."""

    def __init__(self, data, units: str = "", **attrs):
        self.data, self.attrs = np.asarray(data), {"units": units, **attrs} if units else dict(attrs)


@dataclass
class Record:
    """What :func:`read_record` returns: header attributes and the (nested) arrays."""

    attrs: dict
    data: dict


SUFFIXES = (".npz", ".h5", ".hdf5")


def write_record(path: str | os.PathLike, kind: str, version: int, data: Mapping, *, units: str,
                 attrs: Mapping | None = None, suffixes=SUFFIXES) -> Path:
    """Write one file atomically: header ``format = kind``, ``version``, ``units`` (and
    ``attrs``) plus the arrays of ``data`` (name -> array, :class:`Dataset`, or a mapping:
    an HDF5 group; in ``.npz`` its arrays are stored as ``group/name``). The format
    follows the suffix (``.npz``, ``.h5``/``.hdf5``); strings are stored as text."""
    path = Path(path)
    if path.suffix not in suffixes:
        raise InputError(f"{kind} file {str(path)!r}: unknown extension, use {' or '.join(suffixes)}")
    header = {"format": kind, "version": int(version), "units": units, **(attrs or {})}
    with atomic_path(path) as tmp:
        if path.suffix == ".npz":
            flat = {k: np.array(v) for k, v in header.items()}
            flat.update(_flatten(data))
            with open(tmp, "wb") as fh:
                np.savez(fh, **flat)
        else:
            import h5py

            with h5py.File(tmp, "w") as f:
                for k, v in header.items():
                    f.attrs[k] = v
                _write_group(f, data)
    return path


def read_record(path: str | os.PathLike, kind: str, versions=(1,), what: str | None = None) -> Record:
    """Read a file written by :func:`write_record` (or by another tool in the same layout).
    One-line InputError naming the file when it is missing, unreadable, of another format
    or of an unsupported version. Never unpickles."""
    path = Path(path)
    what = what or f"{kind} file"
    if not path.is_file():
        raise InputError(f"{what} not found: {str(path)!r}")
    if path.suffix not in SUFFIXES:
        raise InputError(f"{what} {str(path)!r}: unknown extension, use .h5 or .npz")
    try:
        if path.suffix == ".npz":
            with np.load(path, allow_pickle=False) as z:
                flat = {k: z[k] for k in z.files}
            attrs = {k: flat.pop(k).item() for k in list(flat) if flat[k].ndim == 0 and k in _HEADER_KEYS}
            data = _unflatten({k: _text(v) for k, v in flat.items()})
        else:
            import h5py

            with h5py.File(path, "r") as f:
                attrs = {k: _scalar(v) for k, v in f.attrs.items()}
                data = _read_group(f)
    except Exception as exc:  # corrupt file, pickled content, wrong HDF5 layout ...
        raise InputError(f"{what} {str(path)!r} cannot be read: {' '.join(str(exc).split())}") from None
    if attrs.get("format") != kind:
        raise InputError(f"{what} {str(path)!r}: format is {attrs.get('format')!r}, expected {kind!r}")
    if attrs.get("version", 1) not in versions:
        raise InputError(f"{what} {str(path)!r}: version {attrs.get('version')!r} is not supported "
                         f"(this liftoff reads version {', '.join(map(str, versions))})")
    return Record(attrs, data)


_HEADER_KEYS = ("format", "version", "units", "name", "metadata", "source_units")


def _flatten(data: Mapping, prefix: str = "") -> dict:
    out = {}
    for k, v in data.items():
        if isinstance(v, Mapping):
            out.update(_flatten(v, f"{prefix}{k}/"))
        else:
            arr = v.data if isinstance(v, Dataset) else np.asarray(v)
            out[f"{prefix}{k}"] = arr
    return out


def _unflatten(flat: dict) -> dict:
    out: dict = {}
    for key, v in flat.items():
        node = out
        *groups, name = key.split("/")
        for g in groups:
            node = node.setdefault(g, {})
        node[name] = v
    return out


def _write_group(group, data: Mapping) -> None:
    import h5py

    for k, v in data.items():
        if isinstance(v, Mapping):
            _write_group(group.create_group(k), v)
            continue
        ds = v if isinstance(v, Dataset) else Dataset(v)
        arr = ds.data
        if arr.dtype.kind in "UO":
            d = group.create_dataset(k, data=arr.astype(object), dtype=h5py.string_dtype())
        else:
            d = group.create_dataset(k, data=arr)
        for a, val in ds.attrs.items():
            d.attrs[a] = val


def _read_group(group) -> dict:
    import h5py

    out = {}
    for k, v in group.items():
        if isinstance(v, h5py.Group):
            out[k] = _read_group(v)
        else:
            out[k] = _text(v[()])
    return out


def _text(v):
    """Decode HDF5 byte strings; leave numbers alone."""
    if isinstance(v, bytes):
        return v.decode()
    if isinstance(v, np.ndarray) and v.dtype.kind in "OS":
        return np.array([s.decode() if isinstance(s, bytes) else str(s) for s in v.ravel()]).reshape(v.shape)
    return v


def _scalar(v):
    if isinstance(v, np.generic):
        return v.item()
    return _text(v)
