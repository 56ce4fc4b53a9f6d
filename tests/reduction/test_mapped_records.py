"""Records read with their large arrays memory-mapped (liftoff.core.records.read_record with
mmap=True, used for the stage cache's FE and CB products, whose bytes the cache's checksums
check): the same arrays as read, read-only, the small and compressed members read as
before, a file replaced (atomic write) leaves a mapped array as it was, and a member that
is not a plain array or is cut short is an error, never a wrong array."""
from __future__ import annotations

import os
import zipfile

import numpy as np
import pytest

from liftoff.core.errors import InputError
from liftoff.core.records import MMAP_MIN_BYTES, read_record, write_record


def _arrays():
    rng = np.random.default_rng(1)
    return {"big": rng.standard_normal((600, 400)),                       # 1.9 MB: mapped
            "fortran": np.asfortranarray(rng.standard_normal((400, 500))),  # mapped, column-major
            "ints": np.arange(300_000, dtype=np.int32),                  # 1.2 MB: mapped
            "small": rng.standard_normal(10),                            # read
            "group": {"inner": rng.standard_normal((700, 300))},
            "text": np.array(["a", "bc"], dtype="U")}


def test_mapped_arrays_equal_the_read_ones_and_are_read_only(tmp_path):
    path = write_record(tmp_path / "r.npz", "test-kind", 1, _arrays(), units="SI")
    read = read_record(path, "test-kind").data
    mapped = read_record(path, "test-kind", mmap=True).data
    for name in ("big", "fortran", "ints", "small"):
        assert type(mapped[name]) is np.ndarray and mapped[name].dtype == read[name].dtype
        assert np.array_equal(mapped[name], read[name]), name
    assert np.array_equal(mapped["group"]["inner"], read["group"]["inner"])
    assert list(mapped["text"]) == ["a", "bc"]
    assert mapped["fortran"].flags.f_contiguous
    for name in ("big", "ints"):
        assert mapped[name].nbytes >= MMAP_MIN_BYTES and not mapped[name].flags.writeable
        with pytest.raises(ValueError, match="read-only"):
            mapped[name][0] = 1
    assert mapped["small"].flags.writeable                      # read, not mapped
    # write_record pads each member's local header so that its data starts at a multiple of
    # NPZ_ALIGN bytes: the maps are aligned (BLAS paths, numba); any zip reader still reads it
    from liftoff.core.records import NPZ_ALIGN

    for name in ("big", "fortran", "ints"):
        assert mapped[name].ctypes.data % NPZ_ALIGN == 0, name
    with zipfile.ZipFile(path) as zf:
        assert zf.testzip() is None
    with np.load(path) as z:
        assert np.array_equal(z["big"], read["big"]) and np.array_equal(z["group/inner"], read["group"]["inner"])


def test_a_replaced_file_leaves_a_mapped_array_as_it_was(tmp_path):
    arrays = _arrays()
    path = write_record(tmp_path / "r.npz", "test-kind", 1, arrays, units="SI")
    mapped = read_record(path, "test-kind", mmap=True).data
    other = dict(arrays, big=np.zeros_like(arrays["big"]))
    write_record(path, "test-kind", 1, other, units="SI")          # atomic: a new file under the name
    assert np.array_equal(mapped["big"], arrays["big"])
    assert not read_record(path, "test-kind", mmap=True).data["big"].any()


def test_compressed_members_are_read(tmp_path):
    path = tmp_path / "c.npz"
    big = np.arange(400_000, dtype=float)
    np.savez_compressed(path, format=np.array("test-kind"), version=np.array(1), big=big)
    data = read_record(path, "test-kind", mmap=True).data
    assert np.array_equal(data["big"], big) and data["big"].flags.writeable


def test_a_cut_member_or_an_object_member_is_an_error(tmp_path):
    path = write_record(tmp_path / "r.npz", "test-kind", 1, _arrays(), units="SI")
    with zipfile.ZipFile(path) as zf:
        info = zf.getinfo("big.npy")
    cut = tmp_path / "cut.npz"
    data = bytearray(path.read_bytes())
    # the member's header claims 600 rows but the zip entry says it holds fewer bytes
    start = info.header_offset + 30 + len(info.filename)
    at = data.index(b"(600, 400)", start)
    data[at:at + 10] = b"(900, 400)"
    cut.write_bytes(bytes(data))
    with pytest.raises(InputError, match="cannot be read.*shorter than its array"):
        read_record(cut, "test-kind", mmap=True)

    obj = tmp_path / "obj.npz"
    with zipfile.ZipFile(obj, "w", zipfile.ZIP_STORED) as zf:
        with zf.open("format.npy", "w") as fh:
            np.lib.format.write_array(fh, np.array("test-kind"))
        with zf.open("things.npy", "w") as fh:
            np.lib.format.write_array(fh, np.array([f"item {i:06d}" for i in range(100_000)], dtype=object), allow_pickle=True)
    with pytest.raises(InputError, match="cannot be read.*holds Python objects"):
        read_record(obj, "test-kind", mmap=True)
    assert os.path.getsize(obj) > MMAP_MIN_BYTES


def test_rows_of_a_mapped_array_are_read_not_mapped(tmp_path):
    """take_rows: a[rows] (ascending) of a mapped array read from its file, run by run of
    consecutive rows, also of a row-offset view; the array's pages are not faulted in (the
    process's resident memory of the map does not grow: read-around would map all of it);
    any other array or index (column-major, unsorted, out of range) as numpy indexes it."""
    from liftoff.core.records import take_rows

    rng = np.random.default_rng(2)
    big = rng.standard_normal((6000, 40))                     # 1.9 MB: mapped
    path = write_record(tmp_path / "r.npz", "test-kind", 1, {"big": big, "fortran": np.asfortranarray(big)},
                        units="SI")
    mapped = read_record(path, "test-kind", mmap=True).data
    rows = np.unique(np.r_[0, 1, 2, rng.integers(0, 6000, 300), 5998, 5999])
    got = take_rows(mapped["big"], rows)
    assert got.flags.writeable and np.array_equal(got, big[rows])
    assert np.array_equal(take_rows(mapped["big"][100:], rows[rows < 5900]), big[100:][rows[rows < 5900]])
    assert np.array_equal(take_rows(mapped["fortran"], rows), big[rows])
    assert np.array_equal(take_rows(big, rows), big[rows])
    assert np.array_equal(take_rows(mapped["big"], rows[::-1]), big[rows[::-1]])
    with pytest.raises(IndexError):
        take_rows(mapped["big"], np.array([5, 6000]))

    def resident_kb() -> int:                                 # this file's mapped pages in the process
        total, on = 0, False
        for line in open("/proc/self/smaps"):
            if line[0] in "0123456789abcdef" and "-" in line.split()[0]:
                on = line.rstrip().endswith(str(path))
            elif on and line.startswith("Rss:"):
                total += int(line.split()[1])
        return total

    fresh = read_record(path, "test-kind", mmap=True).data["big"]
    before = resident_kb()
    take_rows(fresh, rows)
    assert resident_kb() == before
    # the file replaced (an atomic rewrite) or deleted since it was mapped: the mapped rows,
    # as numpy indexes them, never the new file's
    write_record(path, "test-kind", 1, {"big": big + 1.0, "fortran": np.asfortranarray(big)}, units="SI")
    assert np.array_equal(take_rows(fresh, rows), big[rows])
    os.remove(path)
    assert np.array_equal(take_rows(fresh, rows), big[rows])
    # not a map, or not rows: numpy's indexing (a buffer's array, a boolean mask)
    plain = np.frombuffer(big.tobytes(), dtype=big.dtype).reshape(big.shape)
    assert np.array_equal(take_rows(plain, rows), big[rows])
    mask = np.zeros(6000, bool)
    mask[rows] = True
    assert np.array_equal(take_rows(mapped["big"], mask), big[mask])


def test_unsigned_rows_and_mapped_arrays_under_a_memory_limit(tmp_path, monkeypatch):
    """take_rows with unsigned rows: descending or beyond the array (whose differences wrap
    in unsigned arithmetic) are indexed as numpy does (IndexError beyond, the rows in their
    order), not read from the file past the array. read_record with ``mmap``: the mapped
    (stored, large) arrays take no memory and do not count against the memory available;
    the same file read into memory does (ResourceError, one line)."""
    from liftoff.core import memory
    from liftoff.core.errors import ResourceError
    from liftoff.core.records import take_rows

    big = np.random.default_rng(3).standard_normal((6000, 40))       # 1.9 MB: mapped
    path = write_record(tmp_path / "r.npz", "test-kind", 1, {"big": big}, units="SI")
    mapped = read_record(path, "test-kind", mmap=True).data["big"]
    down = np.array([5999, 3], dtype=np.uint64)
    assert np.array_equal(take_rows(mapped, down), big[[5999, 3]])
    with pytest.raises(IndexError):
        take_rows(mapped, np.array([6001, 3], dtype=np.uint64))
    monkeypatch.setattr(memory, "available_memory", lambda: 1e6)      # 1 MB: half of it allowed
    assert np.array_equal(read_record(path, "test-kind", mmap=True).data["big"], big)
    with pytest.raises(ResourceError, match="declare .* GB"):
        read_record(path, "test-kind")


def test_what_a_record_declares_is_all_counted_and_links_refused(tmp_path, monkeypatch):
    """read_record's memory check counts every member of an .npz (one not named .npy, which
    np.load reads as bytes, by its uncompressed size: a few-kB file may inflate to GBs), an
    .npz member whose .npy header is unreadable is a one-line InputError before anything is
    read, and an HDF5 record with a soft or external link is refused (a soft link to its root
    recursed through the file, an external one reads another file)."""
    import h5py

    from liftoff.core import memory
    from liftoff.core.errors import ResourceError

    path = write_record(tmp_path / "r.npz", "test-kind", 1, {"a": np.arange(3.0)}, units="SI")
    with zipfile.ZipFile(path, "a", zipfile.ZIP_DEFLATED) as zf:
        zf.writestr("padding", b"\0" * 4_000_000)                 # 4 MB of zeros, a few kB on disk
    assert path.stat().st_size < 100_000
    monkeypatch.setattr(memory, "available_memory", lambda: 4e6)   # half of it: 2 MB
    with pytest.raises(ResourceError, match="'padding' alone"):
        read_record(path, "test-kind")
    monkeypatch.undo()
    bad = write_record(tmp_path / "b.npz", "test-kind", 1, {"a": np.arange(3.0)}, units="SI")
    with zipfile.ZipFile(bad, "a") as zf:
        zf.writestr("c.npy", b"not an array header at all")
    with pytest.raises(InputError, match="b.npz' cannot be read"):
        read_record(bad, "test-kind")
    h5 = write_record(tmp_path / "r.h5", "test-kind", 1, {"a": np.arange(3.0)}, units="SI")
    with h5py.File(h5, "a") as f:
        f["loop"] = h5py.SoftLink("/")
    with pytest.raises(InputError, match="loop is a soft or external link"):
        read_record(h5, "test-kind")
