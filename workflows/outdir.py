"""Whole-run atomic output directories: a run's files appear together or not at all.

A command writes everything into a staging folder beside DIR (``.DIR.liftoff-tmp-<pid>-*``)
and, when every file is written, adds ``MANIFEST.json`` (format, liftoff version,
command, each file with its size and SHA-256, units) and puts the staging folder in
DIR's place in one step (Linux ``renameat2(RENAME_EXCHANGE)``; elsewhere two renames, so
that DIR holds the old set or the new set, never a mix). A failed, interrupted or killed
run leaves DIR as it was; its staging folder is removed on the way out, or by the next
run when the process was killed (the folder carries its pid).

DIR may be new, empty, or a previous output of liftoff (it holds a MANIFEST.json written by
liftoff, or only files with liftoff's output names); anything else is refused, so a run
never replaces a folder of the user's own files.
"""
from __future__ import annotations

import ctypes
import json
import os
import shutil
import tempfile
import time
from contextlib import contextmanager
from fnmatch import fnmatch
from pathlib import Path
from typing import Iterator

from liftoff.core.errors import InputError
from liftoff.core.records import TEMP_TAG, file_sha256, fsync_dir, sweep_stale, write_text

MANIFEST = "MANIFEST.json"
FORMAT = "liftoff-run-manifest"
OUTPUT_NAMES = ("MANIFEST.json", "results*.h5", "maxmin_*.csv", "table1.*", "summary.txt", "*.png", "*.csv",
                "*.h5", "*.vtu", "*.pvd", "*.gif", "*.mp4", "*.json")


def check_target(out: Path) -> None:
    """InputError (one line) unless ``out`` is new, empty or a previous liftoff output folder."""
    if not str(out) or str(out) in (".", "/"):
        raise InputError(f"--out {str(out)!r}: give a folder of its own for the results")
    if out.exists() and not out.is_dir():
        raise InputError(f"--out {str(out)!r}: exists and is not a folder")
    if not out.is_dir():
        return
    entries = [e for e in out.iterdir()]
    if not entries or (out / MANIFEST).is_file():
        return
    foreign = [e.name for e in entries if e.is_dir() or not any(fnmatch(e.name, pat) for pat in OUTPUT_NAMES)]
    if foreign:
        raise InputError(f"--out {str(out)!r}: holds {foreign[0]!r}, which liftoff did not write; give a new "
                         "or empty folder (a run replaces its output folder as a whole)")


def _manifest(stage: Path, command: str) -> dict:
    from liftoff import __version__

    files = []
    for f in sorted(p for p in stage.rglob("*") if p.is_file()):
        files.append({"name": str(f.relative_to(stage)), "bytes": f.stat().st_size,
                      "sha256": file_sha256(f)})
    return {"format": FORMAT, "version": 1, "liftoff": __version__, "command": command,
            "written": time.strftime("%Y-%m-%dT%H:%M:%S%z"), "units": "SI (m, kg, s, N, rad) unless a file says",
            "files": files}


def _exchange(a: Path, b: Path) -> bool:
    """Swap two paths atomically (Linux renameat2 RENAME_EXCHANGE); False where unsupported."""
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        fn = libc.renameat2
    except (OSError, AttributeError):
        return False
    AT_FDCWD, RENAME_EXCHANGE = -100, 2
    fn.argtypes = [ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_uint]
    return fn(AT_FDCWD, os.fsencode(a), AT_FDCWD, os.fsencode(b), RENAME_EXCHANGE) == 0


def _publish(stage: Path, out: Path) -> None:
    """Put ``stage`` in ``out``'s place; the previous ``out`` (if any) is removed after."""
    if not out.exists():
        os.rename(stage, out)
    elif _exchange(stage, out):
        shutil.rmtree(stage, ignore_errors=True)      # stage now holds the previous set
    else:
        old = Path(tempfile.mkdtemp(prefix=f".{out.name}{TEMP_TAG}{os.getpid()}-old-", dir=out.parent))
        os.rename(out, old / "previous")
        os.rename(stage, out)
        shutil.rmtree(old, ignore_errors=True)
    fsync_dir(out.parent)


@contextmanager
def staged_output(out, command: str = "") -> Iterator[Path]:
    """Yield a staging folder for a run's files; on success publish it as ``out``."""
    out = Path(out)
    check_target(out)
    parent = out.absolute().parent
    parent.mkdir(parents=True, exist_ok=True)
    if not os.access(parent, os.W_OK):
        raise PermissionError(13, "output folder's parent is not writable", str(parent))
    sweep_stale(parent)
    stage = Path(tempfile.mkdtemp(prefix=f".{out.name}{TEMP_TAG}{os.getpid()}-", dir=parent))
    try:
        yield stage
        write_text(stage / MANIFEST, json.dumps(_manifest(stage, command), indent=1) + "\n")
        _publish(stage, out)
    finally:
        if stage.exists():
            shutil.rmtree(stage, ignore_errors=True)


def verify(out) -> list[str]:
    """Problems of an output folder against its manifest (missing, changed or extra files)."""
    out = Path(out)
    try:
        man = json.loads((out / MANIFEST).read_text())
    except (OSError, ValueError) as exc:
        return [f"no readable {MANIFEST}: {exc}"]
    problems, listed = [], set()
    for f in man.get("files", []):
        p = out / f["name"]
        listed.add(f["name"])
        if not p.is_file():
            problems.append(f"missing {f['name']}")
        elif file_sha256(p) != f["sha256"]:
            problems.append(f"changed {f['name']}")
    extra = [str(p.relative_to(out)) for p in out.rglob("*") if p.is_file()
             and str(p.relative_to(out)) not in listed | {MANIFEST}]
    problems += [f"extra {e}" for e in extra]
    return problems
