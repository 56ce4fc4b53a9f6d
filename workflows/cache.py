"""Stage cache: each stage's products stored under a hash of everything they depend on.

The key of a stage is the SHA-256 of (stage name, its parameters as canonical JSON, the
keys of the stages it consumes, and the source code of the packages that compute it), so
a changed parameter or a changed line of code gives a new key: a cached product is never
stale, only unused. Products are plain files (npz/h5, no pickle) written atomically by
their own save functions; deleting the cache directory at any time is safe.
"""
from __future__ import annotations

import hashlib
import importlib.util
import json
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np

from liftoff.core.records import read_record, write_record

from .parallel import SERIAL, on_root

_CODE_CACHE: dict[tuple[str, ...], str] = {}
ARRAYS_FORMAT = "liftoff-stage-arrays"


def _source_files(module: str) -> list[Path]:
    """The .py files of a module or package (``liftoff.reduction``), found without importing it."""
    spec = importlib.util.find_spec(module)
    if spec is None or spec.origin is None:
        raise ModuleNotFoundError(module)
    if spec.submodule_search_locations:
        return sorted(f for d in spec.submodule_search_locations for f in Path(d).rglob("*.py"))
    return [Path(spec.origin)]


def code_version(*modules: str) -> str:
    """SHA-256 of the source of the given modules / packages (dotted names)."""
    modules = tuple(sorted(modules))
    if modules not in _CODE_CACHE:
        h = hashlib.sha256()
        for mod in modules:
            for f in _source_files(mod):
                h.update(f"{mod}:{f.name}".encode())
                h.update(f.read_bytes())
        _CODE_CACHE[modules] = h.hexdigest()
    return _CODE_CACHE[modules]


def _canonical(obj: Any) -> Any:
    if isinstance(obj, dict):
        return {str(k): _canonical(v) for k, v in sorted(obj.items(), key=lambda kv: str(kv[0]))}
    if isinstance(obj, (list, tuple)):
        return [_canonical(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _canonical(obj.tolist())
    if isinstance(obj, (np.floating, float)):
        return repr(float(obj))
    if isinstance(obj, (np.integer,)):
        return int(obj)
    return obj


def stage_key(stage: str, params: dict, code: tuple[str, ...] = (), inputs: tuple[str, ...] = ()) -> str:
    payload = json.dumps({"stage": stage, "params": _canonical(params), "inputs": list(inputs),
                          "code": code_version(*code) if code else ""}, sort_keys=True)
    return hashlib.sha256(payload.encode()).hexdigest()[:24]


@dataclass
class StageCache:
    """Cache directory (None: no caching) plus a record of hits, misses and wall times.

    ``comm``: the processes of the run (workflows/parallel.py). Rank 0 decides hit or
    miss and alone writes entries; every rank loads a hit, and a miss is built by every
    rank (collectively for the distributed FE stages)."""

    root: Path | None
    log: list = field(default_factory=list)
    comm: Any = field(default=SERIAL, repr=False)

    def path(self, stage: str, key: str, suffix: str) -> Path | None:
        if self.root is None:
            return None
        return Path(self.root) / stage / f"{key}{suffix}"

    def get_or_build(self, stage: str, key: str, suffix: str, build: Callable[[], Any],
                     save: Callable[[Any, Path], Any], load: Callable[[Path], Any], label: str = "") -> Any:
        """Load the product of ``stage`` under ``key`` if present, else build and save it."""
        p = self.path(stage, key, suffix)
        comm = self.comm
        t0 = time.perf_counter()
        if on_root(comm, lambda: p is not None and p.is_file()):
            try:
                out, ok = load(p), True
            except Exception:  # unreadable (e.g. interrupted write by an older version): rebuild
                out, ok = None, False
            if all(comm.allgather(ok)):
                self.log.append((stage, label, "hit", time.perf_counter() - t0))
                return out
            on_root(comm, lambda: p.unlink(missing_ok=True), share=False)
        out = build()
        if p is not None:
            on_root(comm, lambda: (p.parent.mkdir(parents=True, exist_ok=True), save(out, p)), share=False)
        self.log.append((stage, label, "built", time.perf_counter() - t0))
        return out


def default_cache_dir(out_dir: Path) -> Path:
    """``$LIFTOFF_CACHE`` if set, else DIR/../.liftoff-cache next to the output directory."""
    env = os.environ.get("LIFTOFF_CACHE")
    if env:
        return Path(env)
    return Path(out_dir).resolve().parent / ".liftoff-cache"


def save_arrays(arrays: dict, path: Path) -> None:
    """Atomic .npz record of plain arrays (no pickle)."""
    write_record(path, ARRAYS_FORMAT, 1, arrays, units="SI", suffixes=(".npz",))


def load_arrays(path: Path) -> dict:
    return read_record(path, ARRAYS_FORMAT, what="cache entry").data
