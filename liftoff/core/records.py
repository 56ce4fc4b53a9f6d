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
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterator

import numpy as np

from .errors import InputError
from .scratch import blockwise, copy_rows, row_blocks

TEMP_TAG = ".liftoff-tmp-"          # temporary names carry the writer's pid: .<name>.liftoff-tmp-<pid>-<random>


@contextmanager
def atomic_path(path: str | os.PathLike, suffix: str = ".tmp") -> Iterator[Path]:
    """Yield a temporary path in the folder of ``path`` (created if needed).

    When the ``with`` block succeeds, the temporary file is flushed to disk (fsync), given
    the usual permissions (0666 less the umask; ``mkstemp`` makes it 0600) and renamed onto
    ``path``, and the folder is synced; when the block raises, it is removed and ``path``
    is left as it was. ``suffix`` is the temporary file's extension, for writers that
    choose the format by it (``.png``, ``.vtu``). A temporary file left by a killed
    writer carries its pid and is removed by :func:`sweep_stale`.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=temp_prefix(f".{path.name}"), suffix=suffix)
    os.close(fd)
    try:
        yield Path(tmp)
        _fsync_file(tmp)
        os.chmod(tmp, 0o666 & ~current_umask())
        os.replace(tmp, path)
        fsync_dir(path.parent)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def current_umask() -> int:
    """The process's umask, read where the kernel says it (/proc/self/status, Linux 4.7+)
    without setting it: os.umask's set-and-restore gives any other thread creating a file
    in between a umask of 0 (world-writable files)."""
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _fsync_file(path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def fsync_dir(folder) -> None:
    """Make a rename in ``folder`` durable (POSIX: fsync the directory)."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def _host_id() -> str:
    """8 hex digits naming this machine and boot and its pid namespace: what makes a pid mean
    one process (a writer on another node of a shared file system, or in another container,
    has pids of its own)."""
    import hashlib
    import socket

    parts = [socket.gethostname()]
    for src in ("/proc/sys/kernel/random/boot_id", "/proc/self/ns/pid"):
        try:
            parts.append(os.readlink(src) if src.endswith("/pid") else Path(src).read_text().strip())
        except OSError:
            pass
    return hashlib.sha256("|".join(parts).encode()).hexdigest()[:8]


HOST_ID = _host_id()


def temp_prefix(name: str = "") -> str:
    """The prefix of a temporary name this process makes beside ``name``:
    ``<name><TEMP_TAG><pid>.<host>-`` (:func:`sweep_stale` removes it once its writer is gone,
    on this host only)."""
    return f"{name}{TEMP_TAG}{os.getpid()}.{HOST_ID}-"


def pid_alive(pid: int) -> bool:
    """True if a process with this pid exists (on this machine)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def temp_owner(name: str, tag: str = TEMP_TAG) -> int | None:
    """The pid in a temporary name ``...<tag><pid>[.<host>]-...`` made on this host (or named
    before hosts were: ``<pid>`` alone), None if it has none or was made on another host,
    whose pids this host cannot check."""
    _, found, rest = name.partition(tag)
    pid, _, host = rest.split("-", 1)[0].partition(".")
    if not found or not pid.isdigit() or host and host != HOST_ID:
        return None
    return int(pid)


def sweep_stale(folder, tag: str = TEMP_TAG) -> list[Path]:
    """Remove temporary files and folders in ``folder`` left by writers that no longer run
    (killed by SIGKILL or a power cut); returns what was removed."""
    import shutil

    removed = []
    folder = Path(folder)
    if not folder.is_dir():
        return removed
    for entry in folder.iterdir():
        pid = temp_owner(entry.name, tag)
        if pid is None or pid == os.getpid() or pid_alive(pid):
            continue
        try:
            shutil.rmtree(entry) if entry.is_dir() and not entry.is_symlink() else entry.unlink()
            removed.append(entry)
        except OSError:
            pass
    return removed


def file_sha256(path) -> str:
    """SHA-256 (hex) of a file's bytes, read in 1 MiB blocks."""
    import hashlib

    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


#: a .geo statement that reads another file: Merge / MergeWithBoundingBox / Include "path";
#: ShapeFromFile("path"); matched on the text with comments removed and string literals masked
_GEO_READS = r'\b(Merge|MergeWithBoundingBox|Include|ShapeFromFile)\b'
_GEO_LITERAL = (r'\b(?:Merge|MergeWithBoundingBox|Include)\s*"#(\d+)"\s*;'
                r'|\bShapeFromFile\s*\(\s*"#(\d+)"\s*\)')
_GEO_TOKENS = r'("(?:[^"\\\n]|\\.)*")|(//[^\n]*|/\*.*?\*/)'


def _geo_masked(text: str) -> tuple[str, list]:
    """(the .geo text with comments removed and each string literal replaced by "#k", the
    literals' contents): a keyword inside a string, or // inside a quoted path, is then not
    taken for what it is not."""
    import re

    strings: list = []

    def sub(m):
        if m.group(1) is not None:
            strings.append(m.group(1)[1:-1])
            return f'"#{len(strings) - 1}"'
        return " "

    return re.sub(_GEO_TOKENS, sub, text, flags=re.S), strings


def geometry_sha256(path) -> str:
    """SHA-256 (hex) of a geometry file and, for a gmsh ``.geo``, of the files its ``Merge``,
    ``Include`` and ``ShapeFromFile`` statements read (relative to its folder, recursively,
    in order; a .geo that reads none: its own hash): a stage keyed by the .geo alone reused a
    mesh after a merged STEP file or an included .geo changed. ValueError for such a
    statement whose path is not a plain string (it cannot be followed) or names a missing
    file; a file that reads itself is counted once."""
    import hashlib
    import re

    path = Path(path)
    if path.suffix.lower() != ".geo":
        return file_sha256(path)
    parts: list = []
    seen: set = set()

    def walk(p: Path) -> None:
        key = p.resolve()
        parts.append(file_sha256(p))
        if key in seen or p.suffix.lower() != ".geo":
            return
        seen.add(key)
        text, strings = _geo_masked(p.read_text(errors="replace"))
        literal = list(re.finditer(_GEO_LITERAL, text))
        if len(re.findall(_GEO_READS, text)) != len(literal):
            raise ValueError(f"{p}: a Merge, Include or ShapeFromFile statement whose file is not a plain \"string\": "
                             "write the path literally, so that a change of that file is seen")
        for m in literal:
            dep = p.parent / strings[int(m.group(1) if m.group(1) is not None else m.group(2))]
            if not dep.is_file():
                raise ValueError(f"{p}: {m.group(0).strip()} names a file that does not exist: {dep}")
            parts.append(dep.name)
            walk(dep)

    walk(path)
    if len(parts) == 1:            # a .geo that reads no other file: its own hash
        return parts[0]
    return hashlib.sha256("\n".join(parts).encode()).hexdigest()


def content_sha256(parts) -> str:
    """SHA-256 of a sequence of arrays (each by its shape and float64 bytes), strings and
    None: what a key holds of inputs too large for its parameters (an output's matrices)."""
    import hashlib

    h = hashlib.sha256()
    for x in parts:
        if x is None:
            h.update(b"none")
        elif isinstance(x, str):
            h.update(x.encode())
        else:
            a = np.ascontiguousarray(x, dtype=float)
            h.update(repr(a.shape).encode())
            h.update(a.tobytes())
    return h.hexdigest()


def files_sha256(paths) -> list[str]:
    """:func:`file_sha256` of each path, in order, on a few threads (hashlib releases the GIL
    on large blocks: a default run's 2.1 GB of outputs in 0.85 s instead of 2.2 s on two
    cores, 2026-11-27)."""
    from concurrent.futures import ThreadPoolExecutor

    paths = list(paths)
    if len(paths) < 2:
        return [file_sha256(p) for p in paths]
    with ThreadPoolExecutor(max_workers=min(4, os.cpu_count() or 1, len(paths))) as pool:
        return list(pool.map(file_sha256, paths))


def write_text(path: str | os.PathLike, text: str) -> Path:
    """Write a text file atomically; returns its path."""
    with atomic_path(path) as tmp:
        tmp.write_text(text)
    return Path(path)


def write_bytes(path: str | os.PathLike, data: bytes) -> Path:
    """Write a binary file atomically; returns its path."""
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)
    return Path(path)


# ------------------------------------------------------------------ records
class Dataset:
    """An array with HDF5 attributes (``units`` and others) for :func:`write_record`;
    in ``.npz`` records the attributes are not stored.

    ``dims``: per axis, the dataset that labels it (an HDF5 dimension scale, the
    netCDF/xarray notion of a dimension): its path, absolute (``"/time"``) or relative to
    this dataset's group, or None for an unlabelled axis. That dataset is made a scale
    named after itself and attached to the axis (HDF5 only)."""

    def __init__(self, data, units: str = "", dims=None, **attrs):
        self.data, self.attrs = np.asarray(data), {"units": units, **attrs} if units else dict(attrs)
        self.dims = tuple(dims) if dims is not None else ()
        if self.dims and len(self.dims) != self.data.ndim:
            raise ValueError(f"dims {self.dims} for an array of {self.data.ndim} axes")


@dataclass
class Record:
    """What :func:`read_record` returns: header attributes, the (nested) arrays, and the
    attributes of each HDF5 dataset by path (``group/name``; empty for ``.npz``), less the
    dimension-scale bookkeeping."""

    attrs: dict
    data: dict
    dataset_attrs: dict = field(default_factory=dict)


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
                _savez_aligned(fh, flat)
        else:
            import h5py

            with h5py.File(tmp, "w", track_order=True) as f:
                for k, v in header.items():
                    f.attrs[k] = v
                scaled: list = []
                _write_group(f, data, scaled)
                _attach_scales(f, scaled)
    return path


def read_record(path: str | os.PathLike, kind: str, versions=(1,), what: str | None = None,
                check=None, mmap: bool = False) -> Record:
    """Read a file written by :func:`write_record` (or by another tool in the same layout).
    One-line InputError naming the file when it is missing, unreadable, of another format
    or of an unsupported version. Never unpickles. Before any array is read, the shapes the
    file declares are checked: ``check(shapes)`` ({name: (shape, bytes per item)}) may
    raise the reader's own error, and arrays beyond RECORD_MEMORY_FRACTION of the memory
    available are a ResourceError. ``mmap`` (.npz): the large arrays are read-only maps of
    the file (:func:`_read_npz`), for files whose bytes are checked otherwise (the stage
    cache's checksums): a zip's own CRC is not checked for them."""
    path = Path(path)
    what = what or f"{kind} file"
    if not path.is_file():
        raise InputError(f"{what} not found: {str(path)!r}")
    if path.suffix not in SUFFIXES:
        raise InputError(f"{what} {str(path)!r}: unknown extension, use .h5 or .npz")
    _check_declared_size(path, what, check, mapped=mmap and path.suffix == ".npz")
    try:
        if path.suffix == ".npz":
            flat = _read_npz(path, mmap)
            attrs = {k: flat.pop(k).item() for k in list(flat) if flat[k].ndim == 0 and k in _HEADER_KEYS}
            data = _unflatten({k: _text(v) for k, v in flat.items()})
            ds_attrs = {}
        else:
            import h5py

            with h5py.File(path, "r") as f:
                attrs = {k: _scalar(v) for k, v in f.attrs.items()}
                ds_attrs: dict = {}
                data = _read_group(f, ds_attrs)
    except Exception as exc:  # corrupt file, pickled content, wrong HDF5 layout ...
        raise InputError(f"{what} {str(path)!r} cannot be read: {' '.join(str(exc).split())}") from None
    if attrs.get("format") != kind:
        raise InputError(f"{what} {str(path)!r}: format is {attrs.get('format')!r}, expected {kind!r}")
    if attrs.get("version", 1) not in versions:
        raise InputError(f"{what} {str(path)!r}: version {attrs.get('version')!r} is not supported "
                         f"(this liftoff reads version {', '.join(map(str, versions))})")
    return Record(attrs, data, ds_attrs)


_HEADER_KEYS = ("format", "version", "units", "name", "metadata", "source_units")
#: a record's arrays may take at most this share of the memory available when it is read
RECORD_MEMORY_FRACTION = 0.5


def _npy_header(fh):
    """(shape, fortran_order, dtype) from an .npy header at ``fh``'s position (left just
    after it), or None for a format version numpy's readers here do not know."""
    fmt = np.lib.format
    read = {(1, 0): fmt.read_array_header_1_0, (2, 0): fmt.read_array_header_2_0}.get(fmt.read_magic(fh))
    return None if read is None else read(fh)


def zipfile_like(path: Path) -> bool:
    """Whether ``path`` is a zip archive (an .npz), whatever its members."""
    import zipfile

    try:
        return zipfile.is_zipfile(path)
    except OSError:
        return False


def _stored_members(path: Path) -> set[str]:
    """The arrays of an .npz stored uncompressed (ZIP_STORED: those :func:`_read_npz` maps)."""
    import zipfile

    with zipfile.ZipFile(path) as zf:
        return {i.filename[:-4] for i in zf.infolist()
                if i.filename.endswith(".npy") and i.compress_type == zipfile.ZIP_STORED}


def declared_shapes(path: Path) -> dict[str, tuple[tuple[int, ...], int]]:
    """(shape, bytes per item) of each array of an .npz or HDF5 file, from the file's own
    headers, without reading the data: a few-kB file may declare gigabytes (a compressed
    array of zeros, an HDF5 dataset never written)."""
    out: dict[str, tuple[tuple[int, ...], int]] = {}
    if path.suffix == ".npz":
        import zipfile

        with zipfile.ZipFile(path) as zf:
            for info in zf.infolist():
                if not info.filename.endswith(".npy"):      # read as bytes by np.load: counted as such
                    out[info.filename] = ((int(info.file_size),), 1)
                    continue
                with zf.open(info) as fh:
                    header = _npy_header(fh)
                if header is None:                      # (a .npy version this reader does not parse)
                    out[info.filename[:-4]] = ((int(info.file_size),), 1)
                    continue
                shape, _, dtype = header
                out[info.filename[:-4]] = (tuple(int(n) for n in shape), int(dtype.itemsize))
    else:
        import h5py

        def visit(name, obj):
            if isinstance(obj, h5py.Dataset) and obj.shape is not None:
                out[name] = (tuple(int(n) for n in obj.shape), int(obj.dtype.itemsize))

        with h5py.File(path, "r") as f:
            f.visititems(visit)
    return out


#: arrays of at least this size are memory-mapped by read_record(..., mmap=True)
MMAP_MIN_BYTES = 1 << 20
#: write_record's .npz members start their data at a multiple of this many bytes of the file
NPZ_ALIGN = 64
_ALIGN_EXTRA_ID = 0xD935      # a zip extra field of padding (the id Android's zipalign uses)


def _savez_aligned(fh, arrays: Mapping) -> None:
    """``np.savez`` (uncompressed .npy members, zip64, no pickle) with each member's data at a
    multiple of NPZ_ALIGN bytes of the file, by a padding extra field in its local header:
    a memory map of it (:func:`_read_npz`) is then aligned, as numpy's BLAS paths and numba
    want; any zip reader (np.load) reads it as before."""
    import struct
    import zipfile

    with zipfile.ZipFile(fh, "w", zipfile.ZIP_STORED, allowZip64=True) as zf:
        for name, value in arrays.items():
            arr = np.asanyarray(value)
            info = zipfile.ZipInfo(f"{name}.npy", date_time=(1980, 1, 1, 0, 0, 0))
            info.compress_type = zipfile.ZIP_STORED
            # the local header: 30 bytes, the name, this extra field (4 + pad) and zip64's (20);
            # then the .npy header, whose length numpy pads to a multiple of 64
            base = fh.tell() + 30 + len(info.filename.encode("utf-8")) + 4 + 20
            pad = (-base) % NPZ_ALIGN
            info.extra = struct.pack("<HH", _ALIGN_EXTRA_ID, pad) + b"\0" * pad
            with zf.open(info, "w", force_zip64=True) as out:
                if not blockwise(arr):
                    np.lib.format.write_array(out, arr, allow_pickle=False)
                    continue
                np.lib.format.write_array_header_1_0(out, np.lib.format.header_data_from_array_1_0(arr))
                for i, j in row_blocks(arr):        # a scratch array a block at a time (core/scratch.py)
                    out.write(copy_rows(arr, i, j).tobytes())


def _read_npz(path: Path, mmap: bool) -> dict:
    """The arrays of an .npz file by name (never unpickled). With ``mmap``, each array of at
    least MMAP_MIN_BYTES stored uncompressed (``np.savez`` stores them so) is a read-only
    ndarray over a memory map of the file's bytes: nothing is read until used, pages are
    shared by the processes that map them (forked children included), and the file may be
    replaced (atomic writes) without changing a mapped array. A warm default run mapped
    instead of reading 2 GB of cached FE and CB products (2026-11-27). Other arrays are read."""
    import struct
    import zipfile

    if not mmap:
        with np.load(path, allow_pickle=False) as z:
            return {k: z[k] for k in z.files}
    fmt = np.lib.format
    out = {}
    with open(path, "rb") as raw, zipfile.ZipFile(raw) as zf:
        st = os.fstat(raw.fileno())
        file_id = (st.st_dev, st.st_ino)                      # the file mapped (take_rows reads it by path)
        for info in zf.infolist():
            name = info.filename[:-4] if info.filename.endswith(".npy") else info.filename
            if info.compress_type != zipfile.ZIP_STORED or info.file_size < MMAP_MIN_BYTES:
                with zf.open(info) as fh:
                    out[name] = fmt.read_array(fh, allow_pickle=False)
                continue
            raw.seek(info.header_offset)
            local = raw.read(30)
            if len(local) < 30 or local[:4] != b"PK\x03\x04":
                raise ValueError(f"member {info.filename!r}: no local header at its offset")
            n_name, n_extra = struct.unpack("<HH", local[26:30])
            start = info.header_offset + 30 + n_name + n_extra
            raw.seek(start)
            header = _npy_header(raw)
            if header is None:
                raise ValueError(f"member {info.filename!r}: its .npy version is not read")
            shape, fortran, dtype = header
            if dtype.hasobject:
                raise ValueError(f"member {info.filename!r} holds Python objects (not read: no pickle)")
            offset = raw.tell()
            nbytes = int(np.prod(shape, dtype=np.int64)) * dtype.itemsize
            if offset + nbytes > start + info.file_size:
                raise ValueError(f"member {info.filename!r} is shorter than its array")
            mm = np.memmap(path, dtype=dtype, mode="r", shape=tuple(shape), order="F" if fortran else "C",
                           offset=offset)
            mm.liftoff_file_id = file_id
            out[name] = mm.view(np.ndarray)
    return out


def take_rows(a: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """``a[rows]`` of a 2-D array, ``rows`` ascending integers. For a C-ordered array over a
    memory map (:func:`read_record` with ``mmap``) the rows are read from the mapped file
    (``os.preadv``, one call per run of consecutive rows) instead of faulted in: a page fault
    maps its whole read-around window (128 KiB), so rows a few pages apart map all of the
    array into the process (a picture's corner nodes of a mapped Craig-Bampton model did:
    1.1 GB of the default's models for 0.07 GB of rows). Where the file at the map's path is
    no longer the mapped one (replaced or deleted since: the stage cache writes by rename),
    or cannot be read, the map is indexed as numpy does."""
    rows = np.asarray(rows)
    mm = a
    while mm is not None and not isinstance(mm, np.memmap):
        mm = getattr(mm, "base", None)
    if (mm is None or getattr(mm, "liftoff_file_id", None) is None or a.ndim != 2 or not a.flags.c_contiguous
            or rows.ndim != 1 or rows.dtype.kind not in "iu" or not rows.size
            or rows.dtype.kind == "u" and int(rows.max()) > np.iinfo(np.int64).max):
        return a[rows]
    signed = rows.astype(np.int64)          # (unsigned rows' differences wrap: descending ones looked ascending)
    if np.any(np.diff(signed) <= 0) or signed[0] < 0 or signed[-1] >= a.shape[0]:
        return a[rows]
    try:
        return _pread_rows(a, mm, signed)
    except OSError:
        return a[rows]


def _pread_rows(a: np.ndarray, mm: np.memmap, rows: np.ndarray) -> np.ndarray:
    """:func:`take_rows`' reads; OSError where the file is not the mapped one."""
    out = np.empty((rows.size, a.shape[1]), a.dtype)
    row_bytes = a.shape[1] * a.dtype.itemsize
    start = int(mm.offset) + (a.ctypes.data - mm.ctypes.data)      # a[0, 0]'s byte in the file
    breaks = np.flatnonzero(np.diff(rows) != 1) + 1
    view = memoryview(out.reshape(-1).view(np.uint8))
    fd = os.open(mm.filename, os.O_RDONLY)
    try:
        st = os.fstat(fd)
        if (st.st_dev, st.st_ino) != mm.liftoff_file_id:
            raise OSError(f"{mm.filename}: not the mapped file any more")
        for i, j in zip(np.r_[0, breaks].tolist(), np.r_[breaks, rows.size].tolist()):
            done, want = i * row_bytes, j * row_bytes
            pos = start + int(rows[i]) * row_bytes
            while done < want:              # one read returns at most 2 GiB - 4 KiB on Linux
                got = os.preadv(fd, [view[done:want]], pos)
                if got <= 0:
                    raise OSError(f"{mm.filename}: ends before its array")
                done, pos = done + got, pos + got
    finally:
        os.close(fd)
    return out


def _check_declared_size(path: Path, what: str, check=None, mapped: bool = False) -> None:
    """ResourceError (one line) when the file's arrays would not fit in memory, and
    ``check(shapes)``'s error (the reader's own shape rules), before any array is read; a
    file whose headers cannot be read is left to the reader's own error. ``mapped`` (an
    .npz read with ``mmap``): its stored (uncompressed) arrays of MMAP_MIN_BYTES or more are
    maps of the file, not memory, and do not count (a warm run on a busy machine refused its
    cached models and the stage cache deleted them)."""
    from .errors import ResourceError
    from .memory import available_memory

    try:
        shapes = declared_shapes(path)
        stored = _stored_members(path) if mapped else set()
    except Exception as exc:  # noqa: BLE001 - not a zip / HDF5 file: read_record says so; an .npz
        if path.suffix == ".npz" and zipfile_like(path):  # member's header unreadable: said here, before any read
            raise InputError(f"{what} {str(path)!r} cannot be read: {' '.join(str(exc).split())}") from None
        return
    if check is not None:
        check(shapes)
    sizes = {k: float(np.prod(shape, dtype=float)) * item for k, (shape, item) in shapes.items()}
    sizes = {k: 0.0 if k in stored and v >= MMAP_MIN_BYTES else v for k, v in sizes.items()}
    total, limit = sum(sizes.values()), RECORD_MEMORY_FRACTION * available_memory()
    if total > limit:
        big = max(sizes, key=sizes.get)
        raise ResourceError(f"{what} {str(path)!r}: its arrays declare {total / 1e9:.3g} GB ({big!r} alone "
                            f"{sizes[big] / 1e9:.3g} GB), more than {limit / 1e9:.3g} GB of the memory available; "
                            "not read")


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


def _write_group(group, data: Mapping, scaled: list) -> None:
    """Write ``data`` into ``group`` in order; (dataset, dims) of datasets with dims go to ``scaled``."""
    import h5py

    for k, v in data.items():
        if isinstance(v, Mapping):
            _write_group(group.create_group(k, track_order=True), v, scaled)
            continue
        ds = v if isinstance(v, Dataset) else Dataset(v)
        arr = ds.data
        if arr.dtype.kind in "UO":
            d = group.create_dataset(k, data=arr.astype(object), dtype=h5py.string_dtype())
        elif not blockwise(arr):
            d = group.create_dataset(k, data=arr)
        else:                                   # a scratch array a block at a time (core/scratch.py)
            d = group.create_dataset(k, shape=arr.shape, dtype=arr.dtype)
            for i, j in row_blocks(arr):
                d[i:j] = copy_rows(arr, i, j)
        for a, val in ds.attrs.items():
            if isinstance(val, (list, tuple)) and all(isinstance(x, str) for x in val):
                val = np.array(val, dtype=h5py.string_dtype())  # a list of strings: a text array
            d.attrs[a] = val
        if ds.dims:
            scaled.append((d, ds.dims))


def _attach_scales(f, scaled: list) -> None:
    """Make the datasets named in ``dims`` dimension scales and attach them (after all are written)."""
    from h5py import h5ds

    for d, dims in scaled:
        for axis, where in enumerate(dims):
            if where is None:
                continue
            scale = f[where] if where.startswith("/") else d.parent[where]
            if scale.shape[0] != d.shape[axis]:
                raise ValueError(f"{d.name}: axis {axis} has {d.shape[axis]} entries, its scale {scale.name} "
                                 f"{scale.shape[0]}")
            if not h5ds.is_scale(scale.id):
                scale.make_scale(scale.name.rsplit("/", 1)[-1])
            d.dims[axis].attach_scale(scale)


_SCALE_ATTRS = ("CLASS", "NAME", "REFERENCE_LIST", "DIMENSION_LIST")


def _read_group(group, ds_attrs: dict, prefix: str = "") -> dict:
    import h5py

    out = {}
    for k in group:
        if isinstance(group.get(k, getlink=True), (h5py.SoftLink, h5py.ExternalLink)):
            # (a soft link to a parent recursed; an external one reads another file)
            raise ValueError(f"{prefix}{k} is a soft or external link; a record holds its data itself")
        v = group[k]
        if isinstance(v, h5py.Group):
            out[k] = _read_group(v, ds_attrs, f"{prefix}{k}/")
        else:
            out[k] = _text(v[()])
            ds_attrs[f"{prefix}{k}"] = {a: _scalar(x) for a, x in v.attrs.items() if a not in _SCALE_ATTRS}
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
