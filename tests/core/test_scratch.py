"""Arrays on disk while written (liftoff/core/scratch.py; TransientProblem.modal_scratch).

References: the same arrays in memory (the values must be identical, bit for bit: the
scratch file only changes where the bytes live), and the kernel's own account of the
process's resident pages (/proc/self/smaps of the map), which must fall when rows are
released and must not grow by the array when a record is written from it.
"""
import errno
import mmap
import os
import shutil
import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from liftoff.core import scratch
from liftoff.core.errors import InputError, ResourceError
from liftoff.core.records import read_record, write_record
from liftoff.transient import Forcing, TabulatedForce, TransientProblem, load_result, solve
from liftoff.transient.examples import holddown_contacts, toy_pad, toy_vehicle

MB = 2 ** 20


@pytest.fixture
def disk(tmp_path):
    """A folder on disk: pytest's own, or (where that is tmpfs, as on some CI machines) a
    temporary folder in the working directory, removed afterwards."""
    if scratch.on_disk(tmp_path):
        yield tmp_path
        return
    here = Path(tempfile.mkdtemp(prefix=".test-scratch-", dir=Path.cwd()))
    try:
        if not scratch.on_disk(here):
            pytest.skip("no folder on disk here: neither pytest's tmp_path nor the working directory")
        yield here
    finally:
        shutil.rmtree(here, ignore_errors=True)


def _resident(a: np.ndarray) -> int:
    """Bytes of the map under ``a`` resident in this process (its smaps entry's Rss)."""
    start = np.frombuffer(scratch.scratch_map(a), np.uint8).ctypes.data
    with open("/proc/self/smaps") as fh:
        lines = fh.read().splitlines()
    for k, line in enumerate(lines):
        head = line.split()[0]
        if "-" in head and all(c in "0123456789abcdef-" for c in head):
            lo, hi = (int(x, 16) for x in head.split("-"))
            if lo <= start < hi:
                for entry in lines[k + 1:]:
                    if entry.startswith("Rss:"):
                        return int(entry.split()[1]) * 1024
    raise AssertionError("map not found in /proc/self/smaps")


def test_scratch_array_keeps_its_bytes_and_releases_its_pages(disk):
    """Zeroed, unlinked at once (nothing in the folder), written rows resident until
    released, then read back unchanged from the file; a view's rows release the right pages."""
    a = scratch.scratch_array((2048, 4096), disk)          # 64 MiB
    assert os.listdir(disk) == [] and scratch.scratch_map(a) is not None
    assert not a.any()
    ref = np.random.default_rng(1).standard_normal(a.shape)
    a[:] = ref
    assert _resident(a) >= 60 * MB                              # all of it written: resident
    scratch.release_rows(a, 0, 1024)
    assert 28 * MB <= _resident(a) <= 36 * MB                   # half released (pages at the edge: 4 kB)
    scratch.release_rows(a[1024:], 0, 1024)                     # the other half, through a view
    assert _resident(a) <= 1 * MB
    assert np.array_equal(a, ref)                               # the file kept every byte
    scratch.release_rows(np.zeros((4, 4)), 0, 4)                # any other array: nothing to do
    assert scratch.scratch_map(np.zeros(3)) is None


def test_scratch_errors_name_the_folder(disk, monkeypatch):
    with pytest.raises(ResourceError, match="no-such-folder.*cannot create"):
        scratch.scratch_array((10, 10), disk / "no-such-folder")

    def full(fd, offset, length):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(os, "posix_fallocate", full)
    with pytest.raises(ResourceError, match=f"{disk.name}.*no room for 0.0008 GB"):
        scratch.scratch_array((100, 1000), disk)
    assert os.listdir(disk) == []


@pytest.mark.parametrize("suffix", [".h5", ".npz"])
def test_record_written_from_a_scratch_array(disk, suffix):
    """A record written from a scratch array holds the same bytes as from memory, and the
    writer goes through it in blocks: its resident pages stay near one block, not the array."""
    (disk / "s").mkdir()
    a = scratch.scratch_array((3000, 8192), disk / "s")      # 188 MiB, 6 blocks of 32 MiB
    a[:] = np.arange(a.size, dtype=float).reshape(a.shape) * 0.5
    scratch.release_rows(a, 0, a.shape[0])
    write_record(disk / f"r{suffix}", "test-scratch", 1, {"g": {"q": a}, "small": np.arange(3)}, units="SI")
    assert _resident(a) <= scratch.BLOCK_BYTES + 1 * MB
    rec = read_record(disk / f"r{suffix}", "test-scratch")
    assert np.array_equal(rec.data["g"]["q"], a) and np.array_equal(rec.data["small"], np.arange(3))


def _problem(**kw) -> TransientProblem:
    v, p = toy_vehicle(3), toy_pad(3)
    fo = Forcing(tables=[TabulatedForce("a", "top:Tz", [0.0, 0.05], [0.0, 1e6])], gravity=(0, 0, -9.81))
    return TransientProblem(v, p, holddown_contacts(3, 1e10, release_time=0.02), fo, t_end=0.06, h=5e-6,
                            outputs={"a": ["top:Tz"], "b": ["pad_2:Tz"]}, progress=False, **kw)


@pytest.mark.parametrize("keep", ["q", True])
def test_transient_with_modal_scratch_is_the_same_run(disk, keep):
    """modal_scratch changes where the modal histories live, nothing else: q (v, acc) and
    every output bit for bit the same as in memory over 12,000 steps (3 chunks), the
    histories on scratch maps, their rows released as marched, and the results file the same."""
    mem = solve(_problem(keep_modal=keep))
    res = solve(_problem(keep_modal=keep, modal_scratch=str(disk)))
    assert mem.time.size == 12001 and set(res.modal) == set(mem.modal) and len(mem.modal) == (6 if keep is True else 2)
    for k, q in mem.modal.items():
        assert scratch.scratch_map(res.modal[k]) is not None
        assert _resident(res.modal[k]) <= 64 * 1024 + 0.02 * q.nbytes   # the last chunk's edge at most
        assert np.array_equal(res.modal[k], q)
    assert np.array_equal(res.contact_force, mem.contact_force)
    assert np.array_equal(res.displacement["a"], mem.displacement["a"])
    assert os.listdir(disk) == []
    back = load_result(res.save(disk / "r.h5"))
    for k, q in mem.modal.items():
        assert np.array_equal(back.modal[k], q)


def test_modal_scratch_must_be_a_folder(disk):
    with pytest.raises(InputError, match="modal_scratch = .*nowhere.*not a folder"):
        _problem(keep_modal="q", modal_scratch=str(disk / "nowhere"))
    p = _problem(keep_modal="q", modal_scratch=str(disk))
    from liftoff.transient.stepping import memory_estimate

    assert memory_estimate(p, 1000)["modal histories (keep_modal)"] == 0.0
    assert memory_estimate(replace(p, modal_scratch=None), 1000)["modal histories (keep_modal)"] > 0.0


def test_memory_file_systems_and_platforms_keep_the_array_in_memory(disk, monkeypatch):
    """On tmpfs (its pages are memory) or without posix_fallocate/madvise a scratch file
    saves nothing: an ordinary array, and the transient's memory estimate counts it."""
    assert scratch.file_system("/proc") == "proc" and scratch.on_disk(disk)
    if scratch.file_system("/dev/shm") == "tmpfs":
        assert not scratch.on_disk("/dev/shm")
        assert scratch.scratch_map(scratch.scratch_array((8, 8), "/dev/shm")) is None
    p = _problem(keep_modal="q", modal_scratch=str(disk))
    from liftoff.transient.stepping import memory_estimate

    monkeypatch.setattr(scratch, "file_system", lambda folder: "tmpfs")
    a = scratch.scratch_array((8, 8), disk)
    assert scratch.scratch_map(a) is None and not a.any() and os.listdir(disk) == []
    assert memory_estimate(p, 1000)["modal histories (keep_modal)"] > 0.0
    monkeypatch.undo()
    monkeypatch.delattr(os, "posix_fallocate")
    assert scratch.scratch_map(scratch.scratch_array((8, 8), disk)) is None


@pytest.mark.parametrize("suffix", [".h5", ".npz"])
def test_other_maps_and_orders_are_written_whole(disk, suffix):
    """Only a C-ordered scratch array is written a block at a time: another memory map (a
    copy-on-write np.load, whose changes a dropped page would lose) and a transposed
    scratch array (Fortran order in .npz) are written as numpy writes them, and unchanged."""
    np.save(disk / "x.npy", np.ones((300, 20)))
    m = np.load(disk / "x.npy", mmap_mode="c")
    m[:] = 7.0
    assert scratch.scratch_map(m) is None and isinstance(m.base, mmap.mmap)
    t = scratch.scratch_array((40, 30), disk)
    t[:] = np.arange(1200.0).reshape(40, 30)
    write_record(disk / f"r{suffix}", "test-scratch", 1, {"m": m, "t": t.T}, units="SI")
    assert np.all(m == 7.0)
    rec = read_record(disk / f"r{suffix}", "test-scratch")
    assert np.array_equal(rec.data["m"], m) and np.array_equal(rec.data["t"], t.T)
