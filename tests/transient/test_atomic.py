"""Atomic writes (transient/atomic.py): all or nothing, usual permissions."""
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
