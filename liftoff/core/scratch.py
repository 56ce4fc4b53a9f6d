"""Arrays kept on disk while they are written: a long run's modal histories (numpy only).

A run that keeps every step's modal displacements (0.6 GB a case of the default) writes
them to a results file and drops them; held in memory they set the peak of a campaign, the
more so as the process writing one case's results file beside the run keeps its copy while
the run marches the next case. :func:`scratch_array` puts such an array in a file instead:
a file in a given folder, unlinked at once (it lives as long as its map, so nothing is left
behind by a killed run) and mapped shared, its disk space reserved first (a full disk is an
error before the run, not a SIGBUS in the middle). :func:`release_rows` hands rows already
written back to the page cache (``madvise(MADV_DONTNEED)``: a shared file map keeps their
bytes in the file), so the array's resident share stays that of the rows being written;
:func:`copy_rows` reads rows back the same way, for a writer that goes through it in blocks.
Where the folder's file system is memory itself (tmpfs, ramfs) or the platform lacks
``posix_fallocate`` or ``madvise``, a scratch file would save nothing: :func:`on_disk` says
so and :func:`scratch_array` returns an ordinary array in memory.

The map is never closed by hand: numpy holds no export of it, so closing it under a live
array would free memory the array still points at; it is unmapped when its last array goes.
"""
from __future__ import annotations

import errno
import mmap
import os
import tempfile

import numpy as np

from .errors import ResourceError

#: rows :func:`copy_rows`' callers take at a time: about 32 MB of a 1,372-mode history
BLOCK_BYTES = 32 * 2 ** 20

#: file systems whose pages are memory (a scratch file there saves none)
MEMORY_FILE_SYSTEMS = frozenset({"tmpfs", "ramfs", "devtmpfs", "hugetlbfs"})


class _ScratchMap(mmap.mmap):
    """The map under a :func:`scratch_array` (told apart from any other memory map)."""


def file_system(folder: str | os.PathLike) -> str | None:
    """The type of the file system holding ``folder`` (/proc/self/mounts: its longest mount
    point above the folder's real path), None where it cannot be told."""
    path = os.path.realpath(folder)
    best, kind = -1, None
    try:
        with open("/proc/self/mounts", encoding="utf-8", errors="replace") as fh:
            for line in fh:
                parts = line.split()
                if len(parts) < 3:
                    continue
                point = parts[1].replace("\\040", " ")
                inside = path == point or path.startswith(point.rstrip("/") + "/")
                if inside and len(point) > best:
                    best, kind = len(point), parts[2]
    except OSError:
        return None
    return kind


def on_disk(folder: str | os.PathLike) -> bool:
    """Whether a scratch file in ``folder`` keeps its array out of memory: the platform has
    ``posix_fallocate`` and ``madvise``, and the folder's file system is not memory."""
    if not (hasattr(os, "posix_fallocate") and hasattr(mmap, "MADV_DONTNEED") and hasattr(mmap.mmap, "madvise")):
        return False
    return file_system(folder) not in MEMORY_FILE_SYSTEMS


def scratch_array(shape: tuple[int, ...], folder: str | os.PathLike, dtype=np.float64) -> np.ndarray:
    """A zeroed C-ordered array of ``shape`` over an unlinked file in ``folder`` (shared
    map); in memory where :func:`on_disk` is false. ResourceError (one line, naming the
    folder) when the folder cannot hold it."""
    dtype = np.dtype(dtype)
    nbytes = int(np.prod(shape, dtype=np.int64)) * dtype.itemsize
    if nbytes == 0 or not on_disk(folder):
        return np.zeros(shape, dtype)
    try:
        fd, path = tempfile.mkstemp(prefix=".liftoff-scratch-", dir=folder)
    except OSError as exc:
        raise ResourceError(f"scratch folder {str(folder)!r}: cannot create a file in it ({exc.strerror})") from None
    try:
        os.unlink(path)
        try:
            os.posix_fallocate(fd, 0, nbytes)
        except OSError as exc:
            why = ("no room for" if exc.errno in (errno.ENOSPC, errno.EDQUOT, errno.EFBIG)
                   else "cannot reserve")
            raise ResourceError(f"scratch folder {str(folder)!r}: {why} {nbytes / 1e9:.3g} GB of modal histories "
                                f"({exc.strerror}); free disk space there or keep fewer histories") from None
        try:
            buf = _ScratchMap(fd, nbytes, flags=mmap.MAP_SHARED, prot=mmap.PROT_READ | mmap.PROT_WRITE)
        except OSError as exc:
            raise ResourceError(f"scratch folder {str(folder)!r}: cannot map {nbytes / 1e9:.3g} GB of modal "
                                f"histories there ({exc.strerror})") from None
    finally:
        os.close(fd)
    return np.ndarray(shape, dtype, buffer=buf)


def scratch_map(a: np.ndarray) -> mmap.mmap | None:
    """The map under a :func:`scratch_array` on disk (or a view of one); None for any
    other array, other memory maps (np.memmap, np.load's) included."""
    base = a
    while isinstance(base, np.ndarray):
        base = base.base
    return base if isinstance(base, _ScratchMap) else None


def blockwise(a: np.ndarray) -> bool:
    """Whether a writer should go through ``a`` a block of rows at a time (a C-ordered
    array, of at least one dimension, over a scratch map)."""
    return a.ndim >= 1 and a.flags.c_contiguous and scratch_map(a) is not None


def release_rows(a: np.ndarray, start: int, stop: int) -> None:
    """Drop the resident pages of rows ``start:stop`` of a C-ordered :func:`scratch_array`
    (their bytes stay in the file: the next access reads them back); nothing for any other
    array. Pages shared with the rows beside are dropped too, which costs them a re-read only."""
    if stop <= start or not blockwise(a):
        return
    buf = scratch_map(a)
    row = a.strides[0]
    origin = np.frombuffer(buf, np.uint8).ctypes.data
    first = a.ctypes.data - origin + start * row
    lo = first - first % mmap.PAGESIZE
    hi = min(first + (stop - start) * row, len(buf))
    if hi > lo:
        buf.madvise(mmap.MADV_DONTNEED, lo, hi - lo)


def copy_rows(a: np.ndarray, start: int, stop: int) -> np.ndarray:
    """``a[start:stop]`` copied into memory; for a scratch array its pages dropped again."""
    out = np.array(a[start:stop])
    release_rows(a, start, stop)
    return out


def row_blocks(a: np.ndarray) -> list[tuple[int, int]]:
    """(start, stop) of consecutive blocks of about BLOCK_BYTES of ``a``'s rows (for :func:`copy_rows`)."""
    n = a.shape[0] if a.ndim else 0
    per = max(1, BLOCK_BYTES // max(1, a.strides[0] if a.ndim else 1))
    return [(i, min(i + per, n)) for i in range(0, n, per)]
