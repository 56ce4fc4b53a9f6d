"""Atomic writes (liftoff.core.records): all or nothing, usual permissions, stale temporaries swept."""
import os
import stat

import pytest

from liftoff.core.records import atomic_path, write_text


def test_success_renames_with_umask_permissions(tmp_path):
    target = tmp_path / "sub" / "a.txt"
    old = os.umask(0o022)
    try:
        write_text(target, "hello")
    finally:
        os.umask(old)
    assert target.read_text() == "hello"
    # mkstemp makes 0600; a result file must be readable like any other file (0666 & ~umask)
    assert stat.S_IMODE(target.stat().st_mode) == 0o644
    assert sorted(p.name for p in target.parent.iterdir()) == ["a.txt"]


def test_failure_leaves_old_file_and_no_temporary(tmp_path):
    target = tmp_path / "r.h5"
    target.write_text("previous result")
    with pytest.raises(RuntimeError):
        with atomic_path(target, suffix=".h5") as tmp:
            tmp.write_text("half written")
            raise RuntimeError("solver failed")
    assert target.read_text() == "previous result"
    assert [p.name for p in tmp_path.iterdir()] == ["r.h5"]


def test_stale_temporaries_of_dead_writers_are_swept(tmp_path):
    """A writer killed by SIGKILL leaves its temporary file (named with its pid); the next
    writer in that folder removes it, but never a live process's temporary."""
    import subprocess
    import sys

    from liftoff.core.records import TEMP_TAG, sweep_stale

    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True,
                          text=True).stdout.strip()
    stale = tmp_path / f".r.h5{TEMP_TAG}{dead}-abc.h5"
    live = tmp_path / f".r.h5{TEMP_TAG}{os.getpid()}-def.h5"
    stale.write_text("half")
    live.write_text("being written")
    assert sweep_stale(tmp_path) == [stale] and live.exists() and not stale.exists()


def test_temporaries_of_another_host_are_never_swept(tmp_path):
    """Temporary names carry the writer's pid and host (this machine, boot and pid namespace:
    records.HOST_ID): on a shared file system a writer on another node or in another container
    has pids this host cannot check, so its files are left, dead-looking pid or not; this
    host's dead writers' files (and names made before hosts were) are swept as before."""
    import subprocess
    import sys

    from liftoff.core.records import HOST_ID, TEMP_TAG, sweep_stale, temp_prefix

    assert temp_prefix(".r.h5") == f".r.h5{TEMP_TAG}{os.getpid()}.{HOST_ID}-" and "-" not in HOST_ID
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True,
                          text=True).stdout.strip()
    other = "0" * 8 if HOST_ID != "0" * 8 else "1" * 8
    mine = tmp_path / f".r.h5{TEMP_TAG}{dead}.{HOST_ID}-abc.h5"
    theirs = tmp_path / f".r.h5{TEMP_TAG}{dead}.{other}-abc.h5"
    staged = tmp_path / f".out{TEMP_TAG}{dead}.{other}-xyz"
    for f in (mine, theirs):
        f.write_text("half")
    staged.mkdir()
    assert sweep_stale(tmp_path) == [mine] and theirs.exists() and staged.is_dir()


def test_the_umask_is_read_without_being_set(monkeypatch):
    """current_umask reads the process's umask (/proc/self/status) without the set-and-restore
    that gives another thread's new files a umask of 0 meanwhile; the same value either way."""
    from liftoff.core.records import current_umask

    old = os.umask(0o027)
    try:
        calls = []
        real = os.umask
        monkeypatch.setattr(os, "umask", lambda m: calls.append(m) or real(m))
        assert current_umask() == 0o027
        if os.path.exists("/proc/self/status"):
            assert calls == []                       # never set
    finally:
        monkeypatch.undo()
        os.umask(old)
