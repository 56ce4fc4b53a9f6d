"""Stage cache integrity (workflows/cache.py): an entry is used only when its record matches
its files; damaged or foreign entries are rebuilt with a warning; one key is built once
under concurrency; an unwritable cache folder is a warning, never a failed run."""
import json
import os
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from liftoff.workflows.cache import StageCache, library_versions, load_arrays, save_arrays, stage_key


def _get(cache, key, value, builds):
    def build():
        builds.append(key)
        time.sleep(0.05)
        return value
    return cache.get_or_build("system", key, ".npz", build, lambda v, p: save_arrays({"v": v}, p),
                              lambda p: load_arrays(p)["v"], label=key)


def test_hit_damaged_and_foreign_entries(tmp_path):
    cache, builds = StageCache(tmp_path), []
    a, b = np.arange(5.0), np.arange(7.0)
    assert np.array_equal(_get(cache, "ka", a, builds), a) and builds == ["ka"]
    assert np.array_equal(_get(cache, "ka", a, builds), a) and builds == ["ka"]          # a hit
    _get(cache, "kb", b, builds)
    entry_a, entry_b = tmp_path / "system" / "ka.npz", tmp_path / "system" / "kb.npz"
    entry_a.write_bytes(entry_b.read_bytes())             # a valid file of another key copied over
    with pytest.warns(UserWarning, match=r"entry ka \(ka\) file ka.npz does not match its checksum"):
        assert np.array_equal(_get(cache, "ka", a, builds), a)
    raw = bytearray(entry_b.read_bytes())
    raw[len(raw) // 2] ^= 0xFF                            # a flipped byte
    entry_b.write_bytes(bytes(raw))
    with pytest.warns(UserWarning, match="rebuilding it"):
        assert np.array_equal(_get(cache, "kb", b, builds), b)
    (tmp_path / "system" / "kb.entry.json").unlink()        # a product without its record
    with pytest.warns(UserWarning, match="has no readable record"):
        _get(cache, "kb", b, builds)
    assert builds == ["ka", "kb", "ka", "kb", "kb"]


def _counting_sha(monkeypatch):
    import liftoff.workflows.cache as cache_mod

    calls = []
    real = cache_mod.file_sha256
    monkeypatch.setattr(cache_mod, "file_sha256", lambda f: calls.append(f) or real(f))
    return calls


def test_a_stamped_entry_is_not_read_again_and_any_write_is_caught(tmp_path, monkeypatch):
    """A hit on an entry whose files keep the stat stamp of their last checksum reads none of
    them (the margin RACY_NS set to 0 here: the next test checks it); a file rewritten with
    the same size and its modification time set back has a new change time (no user call sets
    it), so it is checksummed again and caught."""
    import liftoff.workflows.cache as cache_mod

    monkeypatch.setattr(cache_mod, "RACY_NS", 0)
    calls = _counting_sha(monkeypatch)
    cache, builds = StageCache(tmp_path), []
    a = np.arange(5.0)
    _get(cache, "ka", a, builds)
    time.sleep(0.05)                  # past the file clock's tick (its times are coarse: a few ms)
    _get(cache, "ka", a, builds)      # (stamped at the build in the same tick as the files: checksummed, stamped)
    calls.clear()
    assert np.array_equal(_get(cache, "ka", a, builds), a) and builds == ["ka"] and calls == []   # a hit, no read
    entry = tmp_path / "system" / "ka.npz"
    st = entry.stat()
    raw = bytearray(entry.read_bytes())
    raw[len(raw) // 2] ^= 0xFF
    entry.write_bytes(bytes(raw))
    os.utime(entry, ns=(st.st_atime_ns, st.st_mtime_ns))    # same size, same modification time
    assert entry.stat().st_size == st.st_size and entry.stat().st_mtime_ns == st.st_mtime_ns
    with pytest.warns(UserWarning, match="does not match its checksum"):
        assert np.array_equal(_get(cache, "ka", a, builds), a)
    assert builds == ["ka", "ka"] and calls


def test_a_file_rewritten_while_it_is_checksummed_is_never_stamped(tmp_path, monkeypatch):
    """A file rewritten while a hit reads it for its checksum (after the read, before the stamp)
    must not be vouched for by that hit's stamp: the stamp's stats are taken before the read
    and given only if none moved, so the next hit checksums again and catches it."""
    import liftoff.workflows.cache as cache_mod

    monkeypatch.setattr(cache_mod, "RACY_NS", 0)
    cache, builds = StageCache(tmp_path), []
    a, other = np.arange(5.0), np.arange(0.0, 35.0, 7.0)
    _get(cache, "ka", a, builds)
    time.sleep(0.05)
    entry = tmp_path / "system" / "ka.npz"
    record = tmp_path / "system" / "ka.entry.json"
    rec = json.loads(record.read_text())        # unstamped, so that the next hit reads the file (the build's
    rec.pop("stat", None)                       # own stamp holds when the clock ticked between the file's
    rec.pop("stat_ns", None)                    # write and the stamp: then no hit read it, 1 run in 3)
    record.write_text(json.dumps(rec))
    real = cache_mod.file_sha256

    def rewrite_after_reading(f):
        digest = real(f)
        if Path(f) == entry:                        # another writer, right after the read
            save_arrays({"v": other}, entry)
        return digest

    monkeypatch.setattr(cache_mod, "file_sha256", rewrite_after_reading)
    assert np.array_equal(_get(cache, "ka", a, builds), other)     # this hit read the old bytes, loads the new
    monkeypatch.setattr(cache_mod, "file_sha256", real)
    with pytest.warns(UserWarning, match="does not match its checksum"):
        assert np.array_equal(_get(cache, "ka", a, builds), a)     # ... but stamped nothing: caught, rebuilt
    assert builds == ["ka", "ka"]


def test_an_entry_changed_near_its_stamp_is_checksummed(tmp_path, monkeypatch):
    """Within RACY_NS of the stamp (here: right after the build) a file's times cannot vouch for
    it (the kernel's file clock is coarse): a hit checksums every file."""
    calls = _counting_sha(monkeypatch)
    cache, builds = StageCache(tmp_path), []
    _get(cache, "ka", np.arange(5.0), builds)
    calls.clear()
    _get(cache, "ka", np.arange(5.0), builds)
    assert builds == ["ka"] and [f.name for f in calls] == ["ka.npz"]


def test_memory_short_lock_refused_and_malformed_records(tmp_path, monkeypatch):
    """A hit whose product cannot be read for memory now (a ResourceError or MemoryError
    from its load) is a one-line ResourceError and the entry is kept (it was deleted as
    damaged and rebuilt); a lock that cannot be taken (another user's lock file, no inodes,
    no flock) is the warning "running without the cache" and a build; a record that is JSON
    but no mapping is damage (rebuilt with a warning), not an AttributeError."""
    from contextlib import contextmanager

    import liftoff.workflows.cache as cache_mod
    from liftoff.core.errors import ResourceError

    cache, builds = StageCache(tmp_path), []
    a = np.arange(5.0)
    _get(cache, "ka", a, builds)

    def short(p):
        raise ResourceError("arrays declare 9 GB, more than 1 GB of the memory available")

    with pytest.raises(ResourceError, match=r"entry system \(ka\) cannot be read now .* the entry is kept"):
        cache.get_or_build("system", "ka", ".npz", lambda: a, lambda v, p: save_arrays({"v": v}, p), short)
    assert (tmp_path / "system" / "ka.npz").is_file() and (tmp_path / "system" / "ka.entry.json").is_file()
    assert np.array_equal(_get(cache, "ka", a, builds), a) and builds == ["ka"]     # still a hit

    @contextmanager
    def refused(path):
        raise PermissionError(13, "Permission denied", str(path))
        yield

    monkeypatch.setattr(cache_mod, "_locked", refused)
    with pytest.warns(UserWarning, match="cannot lock kb .*running without the cache"):
        assert np.array_equal(_get(cache, "kb", a, builds), a)
    assert cache.root is None and builds == ["ka", "kb"]
    monkeypatch.undo()
    cache, builds = StageCache(tmp_path), []
    (tmp_path / "system" / "ka.entry.json").write_text("[]")
    with pytest.warns(UserWarning, match="has no readable record: rebuilding it"):
        assert np.array_equal(_get(cache, "ka", a, builds), a)
    assert builds == ["ka"]


def test_one_build_per_key_under_concurrency(tmp_path):
    builds = []
    threads = [threading.Thread(target=_get, args=(StageCache(tmp_path), "k", np.ones(3), builds)) for _ in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert builds == ["k"]


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into read-only folders")
def test_read_only_cache_is_a_warning(tmp_path):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o500)
    cache, builds = StageCache(ro), []
    with pytest.warns(UserWarning, match="running without the cache"):
        _get(cache, "k", np.ones(2), builds)
    assert cache.root is None and builds == ["k"]


def test_read_only_cache_is_a_warning_even_for_root(tmp_path, monkeypatch):
    """The same path for root (who can write anywhere): os.access says no."""
    monkeypatch.setattr(os, "access", lambda *a, **k: False)
    cache, builds = StageCache(tmp_path), []
    with pytest.warns(UserWarning, match="not writable; running without the cache"):
        _get(cache, "k", np.ones(2), builds)
    assert builds == ["k"] and not (tmp_path / "system" / "k.npz").exists()


def test_keys_change_with_code_and_library_versions():
    v = library_versions()
    assert v["numpy"] == np.__version__ and "gmsh" in v and "fenics-dolfinx" in v
    assert stage_key("s", {"a": 1}, ("liftoff.core",)) != stage_key("s", {"a": 1}, ("liftoff.reduction",))
    assert stage_key("s", {"a": 1}, ("liftoff.core",)) != stage_key("s", {"a": 2}, ("liftoff.core",))


def test_a_components_key_holds_only_the_materials_that_may_apply_to_it():
    """[model.materials] of one component's volume (builders name volumes after their
    component) changes that component's stage key only; a volume named after no component
    counts for every one (it may be any's)."""
    import tomllib

    from liftoff.config import default_text, parse_scenario
    from liftoff.workflows.cache import stage_key
    from liftoff.workflows.pipeline import _component_key, component_materials

    def model(materials):
        d = tomllib.loads(default_text())
        d["model"]["materials"] = materials
        return parse_scenario(d, "t.toml").cases[0].model

    deck = {"E": 1e9, "nu": 0.3, "rho": 100.0}
    base, changed, odd = model({}), model({"pad_deck": deck}), model({"wing_slab": deck})
    keys = lambda m: {n: stage_key("component", _component_key(m, c), ()) for n, c in m.components.items()}  # noqa: E731
    kb, kc, ko = keys(base), keys(changed), keys(odd)
    assert [n for n in kb if kb[n] != kc[n]] == ["pad"]
    assert all(kb[n] != ko[n] for n in kb)
    assert set(component_materials(changed, "pad")) == {"pad_deck"} and not component_materials(changed, "core")
    # srb_left's volumes are not srb_right's, though both names start with "srb_"
    both = model({"srb_left_case": deck})
    assert set(component_materials(both, "srb_left")) == {"srb_left_case"}
    assert not component_materials(both, "srb_right")


def test_a_lock_file_replaced_while_waited_on_is_locked_anew(tmp_path):
    """The cache folder removed by hand while a build holds a key's lock: a run waiting on
    that lock file got it once the holder let go and went on holding a lock on a deleted
    file, while a third run locked the new file at the path and built the same key at once.
    Now a waiter whose file was replaced locks the file at the path: the third run waits."""
    import fcntl
    import threading

    import liftoff.workflows.cache as cache_mod

    lock = tmp_path / "k.lock"
    inside, leave = threading.Event(), threading.Event()

    def waiter():
        with cache_mod._locked(lock):
            inside.set()
            leave.wait(10)

    with open(lock, "a") as fh:                      # a first run holds the key
        fcntl.flock(fh, fcntl.LOCK_EX)
        t = threading.Thread(target=waiter)
        t.start()
        time.sleep(0.2)                              # the waiter waits on this file
        lock.unlink()
        lock.write_text("")                          # the folder emptied and a new lock file made meanwhile
        fcntl.flock(fh, fcntl.LOCK_UN)
    assert inside.wait(10)
    with open(lock, "a") as third:                   # a third run: the key is taken
        with pytest.raises(BlockingIOError):
            fcntl.flock(third, fcntl.LOCK_EX | fcntl.LOCK_NB)
    leave.set()
    t.join(timeout=10)


def test_stage_keys_cover_what_the_stages_read(tmp_path):
    """A review of the keys (2026-12-07): a Nastran .op4's .asm and .pch, read from beside it
    by default, were not hashed (an edited .asm reused the old model); a user geometry's
    liquids did not put convective / slosh_gravity in the key; the component type was not in
    it (a plug-in type reusing a built-in's parameters reused its mesh)."""
    import shutil
    from dataclasses import dataclass, field
    from types import SimpleNamespace

    from liftoff.config.model import NastranSource
    from liftoff.workflows.pipeline import _component_key

    data = Path(__file__).resolve().parents[1] / "data" / "nastran"
    for ext in (".op4", ".asm"):
        shutil.copy(data / f"inboard{ext}", tmp_path / f"inboard{ext}")
    src = NastranSource(str(tmp_path / "inboard.op4"), "in-lbf-s", {}, {})
    assert [Path(f).name for f in src.files()] == ["inboard.op4", "inboard.asm"]
    shutil.copy(data / "inboard.pch", tmp_path / "inboard.pch")       # a .pch appearing changes the list
    assert [Path(f).name for f in src.files()] == ["inboard.op4", "inboard.asm", "inboard.pch"]

    @dataclass
    class Params:
        liquids: dict = field(default_factory=dict)

    def key(convective, type_="geometry", liquids=None):
        comp = SimpleNamespace(mirror=None, name="c", type=type_, mesh_size=1.0,
                               builder=Params({"fuel": {"density": 800.0}} if liquids is None else liquids))
        model = SimpleNamespace(components={"c": comp}, materials={}, convective=convective, slosh_gravity=9.8,
                                source="fe", degree=1)
        return _component_key(model, comp)

    assert key("wall") != key("free") != key("slosh")
    assert key("wall", liquids={}) == key("free", liquids={})            # no liquid: nothing to change
    assert key("wall", "geometry") != key("wall", "my_plugin_type")
