"""Whole-run atomic output directories: a run's files appear together or not at all.

A command writes everything into a staging folder beside DIR (``.DIR.liftoff-tmp-<pid>-*``)
and, when every file is written, adds ``MANIFEST.json`` (format, liftoff version,
command, each file with its size and SHA-256, units) and puts the staging folder in
DIR's place in one step (Linux ``renameat2(RENAME_EXCHANGE)``; elsewhere two renames, so
that DIR holds the old set or the new set, never a mix). A failed, interrupted or killed
run leaves DIR as it was; its staging folder is removed on the way out, or by the next
run when the process was killed (the folder carries its pid).

DIR may be new, empty, or a previous output of liftoff, proven by its own manifest: a
liftoff MANIFEST.json that lists exactly the folder's files with their SHA-256. Anything
else is refused before the run, so a run never replaces a folder of the user's own files
(nor one where a user added a file to a previous output).
"""
from __future__ import annotations

import ctypes
import json
import os
import shutil
import tempfile
import time
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

from liftoff.core.errors import InputError
from liftoff.core.records import current_umask, files_sha256, fsync_dir, sweep_stale, temp_prefix, write_text

MANIFEST = "MANIFEST.json"
FORMAT = "liftoff-run-manifest"


class Terminated(BaseException):
    """SIGTERM (the command line's handler, workflows.cli), raised in the main thread so that
    every cleanup (finally) runs."""


#: SIGTERMs received (the command line's handler appends). Its exception may surface as
#: another one, or be lost: raised while Python runs an import's or a destructor's code, it
#: is printed as "Exception ignored" and the run goes on (a run signalled so exited 0 with
#: its files published). A run that saw one is not published (:func:`staged_output`).
SIGNALLED: list[int] = []


NAME_MAX = 255              # bytes of one file name (Linux, most file systems)
STAGING_EXTRA = 48          # the staging folder's name: "." + name + TEMP_TAG + pid + "." + host + "-old-" + random


def _check_writable(out: Path) -> None:
    """The folder that will hold ``out`` can take the staging folder: a probe folder made
    and removed in the nearest existing ancestor (creating ``out``'s parents waits for the
    run's end); a run cannot write there otherwise (read-only, /proc, not a folder)."""
    anc = out.absolute().parent
    while not anc.exists() and anc != anc.parent:
        anc = anc.parent
    if not anc.is_dir():
        raise InputError(f"--out {str(out)!r}: {str(anc)!r} is not a folder")
    try:
        probe = tempfile.mkdtemp(prefix=temp_prefix(".liftoff-probe"), dir=anc)
    except OSError as exc:
        raise InputError(f"--out {str(out)!r}: cannot write in {str(anc)!r} "
                         f"({exc.strerror or exc}); give a writable folder") from None
    os.rmdir(probe)


def check_target(out: Path) -> None:
    """InputError (one line) unless ``out`` is new, empty or a folder that liftoff wrote:
    its MANIFEST.json is liftoff's (format), and it lists exactly the files the folder holds,
    each with its size and SHA-256 (:func:`verify`). Output-like names prove nothing (a
    user's data.csv or photo.png), nor does a MANIFEST.json of another origin."""
    if not str(out) or str(out) in (".", "/"):
        raise InputError(f"--out {str(out)!r}: give a folder of its own for the results")
    if out.is_symlink() and not out.exists():
        raise InputError(f"--out {str(out)!r}: a symbolic link to nothing ({os.readlink(out)!r}); give a folder")
    if out.exists() and not out.is_dir():
        raise InputError(f"--out {str(out)!r}: exists and is not a folder")
    if out.is_dir() and os.path.ismount(out):
        raise InputError(f"--out {str(out)!r}: a mount point; a run publishes its folder by renaming a folder staged "
                         "beside it, which cannot cross file systems: give a folder inside it")
    if len(os.fsencode(out.absolute().name)) > NAME_MAX - STAGING_EXTRA:
        raise InputError(f"--out {str(out)!r}: a folder name longer than {NAME_MAX - STAGING_EXTRA} bytes (liftoff "
                         f"stages the run beside it under a name {STAGING_EXTRA} bytes longer; the file system takes "
                         f"{NAME_MAX}); give a shorter name")
    _check_writable(out)
    if not out.is_dir() or not any(out.iterdir()):
        return
    refuse = (f"--out {str(out)!r}: {{}}; a run replaces its output folder as a whole, so it takes only a "
              "new or empty folder or one that liftoff wrote: give another folder")
    try:
        man = json.loads((out / MANIFEST).read_text())
    except FileNotFoundError:
        first = sorted(e.name for e in out.iterdir())[0]
        raise InputError(refuse.format(f"holds {first!r} and no {MANIFEST}, so liftoff did not write it")) from None
    except (OSError, ValueError) as exc:
        raise InputError(refuse.format(f"its {MANIFEST} cannot be read ({' '.join(str(exc).split())})")) from None
    if not isinstance(man, dict) or man.get("format") != FORMAT:
        raise InputError(refuse.format(f"its {MANIFEST} is not a liftoff run manifest"))
    problems = [p for p in verify(out) if not p.startswith("missing ")]   # a file the user removed is no loss
    if problems:
        raise InputError(refuse.format(f"it does not match its {MANIFEST} ({problems[0]}), so it holds files "
                                       "liftoff did not write"))


def _manifest(stage: Path, command: str) -> dict:
    from liftoff import __version__
    from liftoff.core.openblas import describe

    paths = sorted(p for p in stage.rglob("*") if p.is_file())
    files = [{"name": str(f.relative_to(stage)), "bytes": f.stat().st_size, "sha256": digest}
             for f, digest in zip(paths, files_sha256(paths))]
    return {"format": FORMAT, "version": 1, "liftoff": __version__, "command": command,
            "written": time.strftime("%Y-%m-%dT%H:%M:%S%z"), "units": "SI (m, kg, s, N, rad) unless a file says",
            "blas": describe(), "files": files}


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
        old = Path(tempfile.mkdtemp(prefix=f"{temp_prefix('.' + out.name)}old-", dir=out.parent))
        os.rename(out, old / "previous")
        os.rename(stage, out)
        shutil.rmtree(old, ignore_errors=True)
    fsync_dir(out.parent)


#: the folders published by this process's current command (the command line says so when a
#: signal comes after its results were in place); cleared by workflows.cli.main
PUBLISHED: list[str] = []


@contextmanager
def _signals_held():
    """SIGTERM and SIGINT held while a run publishes its folder: one then could stop the swap
    half done (the fallback's two renames: no output folder) or land after the new set is in
    place while the run says no results were written. Their handlers are replaced by one that
    records them, and a recorded signal is handed to the handler before (or delivered again,
    for the default action) once the publication is done. Handlers, not a signal mask: a
    process-directed signal goes to any thread that does not block it (OpenBLAS's, say), and
    Python runs its handler in the main thread at once."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        yield
        return
    got: list[int] = []
    before = {}
    for sig in (signal.SIGTERM, signal.SIGINT):
        before[sig] = signal.signal(sig, lambda signum, frame: got.append(signum))
    try:
        yield
    finally:
        for sig, handler in before.items():
            signal.signal(sig, handler)
        for sig in dict.fromkeys(got):
            handler = before[sig]
            if callable(handler):
                handler(sig, None)               # (the command line's: raises Terminated; Python's: KeyboardInterrupt)
            elif handler == signal.SIG_DFL:
                os.kill(os.getpid(), sig)


def _listing(out: Path) -> list | None:
    """What ``out`` holds: (relative name, size, modification and change times) of each entry,
    None if it does not exist."""
    if not out.is_dir():
        return None
    out_list = []
    for p in sorted(out.rglob("*")):
        st = p.lstat()
        out_list.append((str(p.relative_to(out)), st.st_size, st.st_mtime_ns, st.st_ctime_ns))
    return out_list


@contextmanager
def staged_output(out, command: str = "") -> Iterator[Path]:
    """Yield a staging folder for a run's files; on success publish it as ``out``. A symbolic
    link ``out`` is followed (the folder it names is replaced, the link kept). The folder is
    checked again before it is replaced when anything in it changed during the run (a file a
    user put there is never deleted: the run ends with check_target's error instead). The
    published folder takes the process's umask, as a folder made with mkdir would."""
    out = Path(out)
    if out.is_symlink() and out.exists():
        out = Path(os.path.realpath(out))
    check_target(out)
    before = _listing(out)
    mask = current_umask()
    parent = out.absolute().parent
    parent.mkdir(parents=True, exist_ok=True)
    if not os.access(parent, os.W_OK):
        raise PermissionError(13, "output folder's parent is not writable", str(parent))
    sweep_stale(parent)
    stage = Path(tempfile.mkdtemp(prefix=temp_prefix(f".{out.name}"), dir=parent))
    try:
        yield stage
        if SIGNALLED:               # a SIGTERM whose exception was lost on the way (SIGNALLED)
            raise Terminated()
        with _signals_held():       # a SIGTERM or SIGINT now is taken after the swap, not in its middle
            write_text(stage / MANIFEST, json.dumps(_manifest(stage, command), indent=1) + "\n")
            if _listing(out) != before:  # changed meanwhile: replaced only if still new, empty or liftoff's
                check_target(out)
            os.chmod(stage, 0o777 & ~mask)                # (mkdtemp made it 0700)
            _publish(stage, out)
            PUBLISHED.append(str(out))
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
    files = man.get("files") if isinstance(man, dict) else None
    if not isinstance(files, list) or not all(isinstance(f, dict) and isinstance(f.get("name"), str)
                                              and isinstance(f.get("sha256"), str) for f in files):
        return [f"{MANIFEST} lists no files in liftoff's format"]
    problems, listed = [], set()
    present = [f for f in files if (out / f["name"]).is_file()]
    digests = dict(zip((f["name"] for f in present), files_sha256(out / f["name"] for f in present)))
    for f in files:
        listed.add(f["name"])
        if f["name"] not in digests:
            problems.append(f"missing {f['name']}")
        elif digests[f["name"]] != f["sha256"]:
            problems.append(f"changed {f['name']}")
    listed_dirs = {str(parent) for name in listed for parent in Path(name).parents}
    extra = [str(p.relative_to(out)) for p in sorted(out.rglob("*"))
             if (p.is_file() or p.is_symlink()) and str(p.relative_to(out)) not in listed | {MANIFEST}
             or p.is_dir() and not p.is_symlink() and str(p.relative_to(out)) not in listed_dirs]
    problems += [f"extra {e}" for e in extra]
    return problems
