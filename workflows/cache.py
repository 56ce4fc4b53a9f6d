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
import warnings
from contextlib import contextmanager, nullcontext
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Any, Callable

import numpy as np

from liftoff.core.errors import ResourceError
from liftoff.core.records import (TEMP_TAG, content_sha256, file_sha256, read_record, sweep_stale,  # noqa: F401
                                  write_record, write_text)

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
    """Key of a stage: its parameters, the keys of its inputs, the source of the code that
    computes it and the versions of the libraries it runs on (a new numpy or dolfinx gives a
    new key, never an old product)."""
    payload = json.dumps({"stage": stage, "params": _canonical(params), "inputs": list(inputs),
                          "code": code_version(*code) if code else "",
                          "libraries": library_versions() if code else {}}, sort_keys=True)
    return hashlib.sha256(payload.encode()).hexdigest()[:24]


ENTRY_FORMAT = "liftoff-cache-entry"


@dataclass
class StageCache:
    """Cache directory (None: no caching) plus a record of hits, misses and wall times.

    An entry is the product's files ``<stage>/<key>*`` plus ``<stage>/<key>.entry.json``
    (its key and the SHA-256 of each file), written last. A product is loaded only when
    the record matches its files; a damaged, partial or foreign entry (say another mesh's
    file copied over it) is rebuilt with a warning. Builds of one key are serialised by a
    lock file, so concurrent runs on one cache write each entry once. A cache folder
    that cannot be written (read-only, full disk) is a warning: the run goes on without it.

    ``comm``: the processes of the run (workflows/parallel.py). Rank 0 checks the entry
    (holding the lock) and alone writes; every rank loads a hit, and a miss is built by
    every rank (collectively for the distributed FE stages). Components shared out over
    the ranks are built before, by serial worker processes with caches of their own on
    the same folder (workflows/pipeline.reduce_over_ranks).
    """

    root: Path | None
    log: list = field(default_factory=list)
    comm: Any = field(default=SERIAL, repr=False)
    temporary: bool = False     # a run's own folder, gone with it (--no-cache with generated cases)

    def path(self, stage: str, key: str, suffix: str) -> Path | None:
        if self.root is None:
            return None
        return Path(self.root) / stage / f"{key}{suffix}"

    def has(self, stage: str, key: str, suffix: str) -> bool:
        """Whether an entry of ``stage`` under ``key`` is recorded (its record file; loading
        it still checks its files)."""
        p = self.path(stage, key, suffix)
        return p is not None and p.with_name(f"{key}.entry.json").is_file()

    def get_or_build(self, stage: str, key: str, suffix: str, build: Callable[[], Any],
                     save: Callable[[Any, Path], Any], load: Callable[[Path], Any], label: str = "") -> Any:
        """Load the product of ``stage`` under ``key`` if its entry checks, else build and save it."""
        t0 = time.perf_counter()
        comm = self.comm
        p = self.path(stage, key, suffix)
        if p is not None and not on_root(comm, lambda: self._usable(p.parent)):
            p, self.root = None, None
        lock, locked = nullcontext(), True
        if p is not None and comm.rank == 0:
            lock = _locked(p.with_name(f"{key}.lock"))
            try:
                lock.__enter__()
            except OSError as exc:      # another user's lock file, no inodes left, no flock here
                warnings.warn(f"stage cache {str(self.root)!r}: cannot lock {key} ({exc.strerror or exc}); "
                              "running without the cache", stacklevel=2)
                lock, locked = nullcontext(), False
        if p is not None and comm.size > 1:
            locked = comm.bcast(locked if comm.rank == 0 else None)
        if p is not None and not locked:
            p, self.root = None, None
        if p is None:
            out = build()
            self.log.append((stage, label, "built", time.perf_counter() - t0))
            return out
        try:
            out = self._load_all(p, key, load, label or stage)
            if out is not None:
                self.log.append((stage, label, "hit", time.perf_counter() - t0))
                return out
            out = build()
            on_root(comm, lambda: self._save(out, p, key, stage, save), share=False)
            self.root = comm.bcast(self.root if comm.rank == 0 else None)
        finally:
            lock.__exit__(None, None, None)
        self.log.append((stage, label, "built", time.perf_counter() - t0))
        return out

    def _usable(self, folder: Path) -> bool:
        try:
            folder.mkdir(parents=True, exist_ok=True)
            sweep_stale(folder)
            if os.access(folder, os.W_OK):
                return True
            reason = "not writable"
        except OSError as exc:
            reason = exc.strerror or str(exc)
        warnings.warn(f"stage cache {str(self.root)!r}: {reason}; running without the cache", stacklevel=3)
        self.root = None
        return False

    def _load_all(self, p: Path, key: str, load: Callable[[Path], Any], what: str):
        """The product on every rank, or None on every rank (rank 0 checks the entry)."""
        comm = self.comm
        if comm.size == 1:
            return self._load(p, key, load, what)
        out = on_root(comm, lambda: self._load(p, key, load, what), share=False)
        if not comm.bcast(out is not None if comm.rank == 0 else None):
            return None
        if comm.rank != 0:
            try:
                out = load(p)
            except Exception:  # noqa: BLE001 - a rank that cannot read it: all ranks rebuild
                out = None
        return out if all(comm.allgather(out is not None)) else None

    def _load(self, p: Path, key: str, load: Callable[[Path], Any], what: str):
        record = p.with_name(f"{key}.entry.json")
        if not p.is_file() and not record.is_file():
            return None
        problem = _entry_problem(p.parent, key, record)
        if problem is None:
            try:
                return load(p)
            except (ResourceError, MemoryError) as exc:   # the machine's memory now, not the entry: kept
                raise ResourceError(f"stage cache entry {what} ({key}) cannot be read now "
                                    f"({' '.join(str(exc).split()) or 'out of memory'}); the entry is kept: free "
                                    "memory and run again") from None
            except Exception as exc:  # noqa: BLE001 - an unreadable product is rebuilt
                problem = f"cannot be read ({' '.join(str(exc).split())})"
        warnings.warn(f"stage cache entry {what} ({key}) {problem}: rebuilding it", stacklevel=4)
        for f in entry_files(p.parent, key) + [record]:
            try:
                f.unlink(missing_ok=True)
            except OSError:             # another user's file: the rebuilt entry is written over it, or not kept
                pass
        return None

    def _save(self, out, p: Path, key: str, stage: str, save: Callable[[Any, Path], Any]) -> None:
        try:
            save(out, p)
            paths = entry_files(p.parent, key)
            files, stamps = _checksums(p.parent, key, paths)
            write_text(p.with_name(f"{key}.entry.json"),
                       json.dumps({"format": ENTRY_FORMAT, "version": 1, "stage": stage, "key": key,
                                   "files": files, "libraries": library_versions(), **stamps}, indent=1))
        except OSError as exc:  # a full or read-only disk: keep the result, drop the entry
            for f in entry_files(p.parent, key):
                f.unlink(missing_ok=True)
            warnings.warn(f"stage cache {str(self.root)!r}: {exc.strerror or exc}; running without the cache",
                          stacklevel=4)
            self.root = None


def entry_files(folder: Path, key: str) -> list[Path]:
    """The product files of the entry ``key`` in a stage's ``folder`` (``<key>.*``, less its
    record, its lock and files being written)."""
    return sorted(f for f in folder.glob(f"{key}.*")
                  if f.is_file() and not f.name.endswith((".entry.json", ".lock")) and TEMP_TAG not in f.name)


#: a file's stat stamp stands for its checksum only when the file was last changed this long
#: before the stamp was taken (git's "racily clean" rule: a file's times have the kernel's
#: coarse clock, a few ms, so a change made in the same tick as the stamp could leave them equal)
RACY_NS = 2_000_000_000


def _stat(f: Path) -> list[int]:
    st = f.stat()
    return [st.st_size, st.st_mtime_ns, st.st_ctime_ns, st.st_ino, st.st_dev]


def _fs_now(folder: Path, key: str) -> int:
    """The file system's clock now (ns): the modification time it gives the entry's lock file,
    touched (on a network file system the server's clock, which sets the files' times; this
    host's clock where the lock cannot be touched)."""
    lock = Path(folder) / f"{key}.lock"
    try:
        os.utime(lock)
        return lock.stat().st_mtime_ns
    except OSError:
        return time.time_ns()


def _checksums(folder: Path, key: str, paths: list[Path]) -> tuple[dict, dict]:
    """({name: SHA-256}, the record's stat stamps) of an entry's files. The stamps (size,
    modification and change times, inode and device of each, and the file system's time when
    they were taken) are taken BEFORE the files are read, and given only if no file's stat moved
    while they were read: a file rewritten meanwhile is left to the next hit's checksum, never
    vouched for by a stamp its bytes were not read under."""
    at = _fs_now(folder, key)
    before = {f.name: _stat(f) for f in paths}
    digests = {f.name: file_sha256(f) for f in paths}
    after = {f.name: _stat(f) for f in paths}
    return digests, ({"stat": before, "stat_ns": at} if after == before else {})


def _stamped(rec: dict, files: dict[str, Path]) -> bool:
    """Whether every file of the entry is, by its stat, the one whose checksum the record holds:
    the same size, times, inode and device as just before the checksums were taken, and changed
    last well before then (RACY_NS, on the file system's clock: :func:`_fs_now`). Any write,
    copy or move over a file changes its change time (which no user call can set back), so
    such a file is checksummed again."""
    stat, at = rec.get("stat"), rec.get("stat_ns")
    if not isinstance(stat, dict) or not isinstance(at, int) or set(stat) != set(files):
        return False
    try:
        now = {name: _stat(f) for name, f in files.items()}
    except OSError:
        return False
    return all(now[name] == stat[name] and now[name][1] < at - RACY_NS and now[name][2] < at - RACY_NS
               for name in files)


def _entry_problem(folder: Path, key: str, record: Path) -> str | None:
    """Why an entry cannot be trusted, or None. A file is checksummed (SHA-256) against the
    record unless its stat stamp shows it unchanged since the checksums were last taken
    (:func:`_stamped`: a warm default run read 2.7 GB of cached models to checksum them, 1.4
    s); an entry whose files all check is stamped anew, so the next hit reads none of them."""
    try:
        rec = json.loads(record.read_text())
    except (OSError, ValueError):
        return "has no readable record"
    if not isinstance(rec, dict) or not isinstance(rec.get("files"), dict):
        return "has no readable record"
    if rec.get("format") != ENTRY_FORMAT or rec.get("key") != key:
        return f"is recorded under key {rec.get('key')!r}"
    files = {f.name: f for f in entry_files(folder, key)}
    if set(files) != set(rec.get("files", {})):
        return "has missing or extra files"
    if _stamped(rec, files):
        return None
    digests, stamps = _checksums(folder, key, list(files.values()))
    for name, digest in rec["files"].items():
        if digests[name] != digest:
            return f"file {name} does not match its checksum"
    if stamps:
        try:                            # stamped anew, under the entry's lock (get_or_build)
            write_text(record, json.dumps({**rec, **stamps}, indent=1))
        except OSError:                 # a read-only cache: checksummed again next time
            pass
    return None


@contextmanager
def _locked(path: Path):
    """An exclusive advisory lock (fcntl) held while one key is built and saved. The lock is
    the file at ``path`` when the lock is taken: a lock file deleted or replaced while another
    process held it (the cache folder removed by hand) is opened again, so that two runs
    never hold locks on two different files of one key."""
    import fcntl

    for _ in range(100):
        fh = open(path, "a")
        try:
            fcntl.flock(fh, fcntl.LOCK_EX)
            try:
                same = os.path.samestat(os.fstat(fh.fileno()), os.stat(path))
            except FileNotFoundError:
                same = False
            if not same:                 # deleted or replaced meanwhile: lock the file there now
                fcntl.flock(fh, fcntl.LOCK_UN)
                path.parent.mkdir(parents=True, exist_ok=True)
                continue
            try:
                yield
            finally:
                fcntl.flock(fh, fcntl.LOCK_UN)
            return
        finally:
            fh.close()
    raise OSError(f"the lock file {str(path)!r} keeps being replaced")


@lru_cache(maxsize=1)
def library_versions() -> dict[str, str]:
    """Versions of the libraries whose numbers a cached product depends on."""
    from importlib import metadata

    out = {}
    for dist in ("numpy", "scipy", "fenics-dolfinx", "fenics-ffcx", "fenics-basix", "fenics-ufl", "petsc4py",
                 "slepc4py", "meshio"):
        try:
            out[dist] = metadata.version(dist)
        except metadata.PackageNotFoundError:
            out[dist] = "absent"
    spec = importlib.util.find_spec("gmsh")
    out["gmsh"] = _gmsh_version(spec.origin) if spec and spec.origin else "absent"
    return out


def _gmsh_version(origin: str) -> str:
    """GMSH_API_VERSION read from gmsh.py (no import: it loads the gmsh library)."""
    import re

    try:
        m = re.search(r'GMSH_API_VERSION\s*=\s*"([^"]+)"', Path(origin).read_text(errors="ignore"))
    except OSError:
        return "unknown"
    return m.group(1) if m else "unknown"


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
