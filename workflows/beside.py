"""Work done beside the run (issue 28): a case's results file, plots and snapshots in a
forked child process while the parent marches the next case's transient and writes the
tables; the animation (``--fields``) while the parent writes the ParaView series.

A named case's results file (1 GB of modal histories in the default) and pictures took 40 %
of a warm default run and nothing the run computes after them reads them, so they are
forked off as soon as the case's results exist: the
child inherits the model and the results (copy-on-write, nothing pickled), draws, sends the
list of files it wrote back through a pipe and exits; :meth:`Beside.wait` collects them
before the summary. A child's error comes back as the run's one-line error naming the case;
a child dies with its parent (PR_SET_PDEATHSIG), so an interrupted run leaves no child
writing into its staging folder.

Only in a serial run on Linux (a forked MPI rank is undefined behaviour) and unless
$LIFTOFF_BESIDE = 0; otherwise the work runs inline, in the same order, with the same files.
"""
from __future__ import annotations

import json
import os
import signal
import sys
import time
from contextlib import nullcontext
from pathlib import Path
from typing import Callable

from liftoff.core.errors import InputError

from .executors import die_with_parent

#: environment variable: "0" draws every picture inline (one process), as before issue 28
ENV = "LIFTOFF_BESIDE"

#: children drawing at once at most: a submission beyond waits for the oldest (a warm default
#: run has up to 8: three per named case, the correlated loads and the spectra; a scenario of
#: many named cases would otherwise fork three drawing processes a case on two cores)
LIVE_LIMIT = 8


def available() -> bool:
    """Whether this process may fork its pictures off (serial, Linux, not switched off)."""
    if os.environ.get(ENV, "").strip() == "0" or not sys.platform.startswith("linux") or not hasattr(os, "fork"):
        return False
    from .parallel import world

    return world().size == 1


def trim_heap() -> None:
    """Return the free memory of the C heap to the system (glibc's malloc_trim; nothing
    elsewhere). glibc keeps the memory of freed arrays below its (self-raising, up to 32 MB)
    mmap threshold in the heap: at the end of a default run with 8 generated cases 0.84 GB
    of it was free but resident (40 ms to return). A child forked then would inherit those
    pages, and a worker would carry them into its next case. Called before each fork and
    by each campaign worker before a case: the campaign of 16 cases peaked at 4.08 GB of
    PSS (2.49 GB anonymous) with it against 4.30 (2.70) without (one pair, 2026-11-28);
    most of the rest was the process writing modes_vehicle.vtu: the cached models' pages it
    reads (1.3 GB, file-backed) and the parent's pages it keeps as the parent goes on
    (copy-on-write, 1.1 GB)."""
    if not sys.platform.startswith("linux"):
        return
    try:
        import ctypes

        ctypes.CDLL("libc.so.6").malloc_trim(0)
    except (OSError, AttributeError):
        pass


class Beside:
    """Runs ``work() -> list[Path]`` jobs in forked children (or inline when ``forked`` is
    False); :meth:`wait` returns their files, in submission order."""

    def __init__(self, forked: bool):
        self.forked = forked
        self._jobs: list[list] = []     # [name, pid, read fd, start, outcome (None until collected)]
        self._inline: list[Path] = []
        self.seconds: dict[str, float] = {}
        #: a context held while forking: another thread of this process that may be in compiled
        #: code or a library's lock (transient.accuracy.EstimatesInOrder.paused) waits outside it
        self.quiet = nullcontext
        self._preloads: list[Callable[[], object]] = []

    def preload(self, *loaders: Callable[[], object]) -> None:
        """Imports the children will need (``loaders``: each imports a module), done once in
        this process before the first fork, so that each child inherits them instead of
        importing them again: pyplot took 0.18 s a process, in four children of a default run
        (2026-12-07). A loader that fails is left to the child, which says why."""
        self._preloads += loaders

    def submit(self, name: str, work: Callable[[], list]) -> None:
        if not self.forked:
            t0 = time.perf_counter()
            self._inline += [Path(p) for p in work()]
            self.seconds[name] = time.perf_counter() - t0
            return
        while self._preloads:
            try:
                self._preloads.pop(0)()
            except Exception:  # noqa: BLE001 - the child imports it again and reports its error
                pass
        live = [job for job in self._jobs if job[4] is None]
        while len(live) >= LIVE_LIMIT:
            self._collect(live.pop(0))
        sys.stdout.flush()
        sys.stderr.flush()
        trim_heap()
        r, w = os.pipe()
        t0 = time.perf_counter()
        with self.quiet():
            pid = os.fork()
        if pid == 0:                                # the child: draw, report, leave without cleanup
            status = 1
            try:
                os.close(r)
                die_with_parent()
                msg = {"files": [str(p) for p in work()]}
                status = 0
            except BaseException as exc:            # noqa: BLE001 - everything goes back to the parent
                bad_input = isinstance(exc, InputError)
                msg = {"error": " ".join((str(exc) if bad_input else f"{type(exc).__name__}: {exc}").split()),
                       "input": bad_input}
            try:
                data = json.dumps(msg).encode()
                while data:
                    data = data[os.write(w, data):]
            finally:
                os._exit(status)
        os.close(w)
        self._jobs.append([name, pid, r, t0, None])

    def _collect(self, job: list) -> None:
        """Read a child's message, reap it and keep its outcome in ``job``: its files, or the
        error naming it."""
        name, pid, r, t0, _ = job
        chunks = []
        while True:
            chunk = os.read(r, 1 << 16)
            if not chunk:
                break
            chunks.append(chunk)
        os.close(r)
        _, status = os.waitpid(pid, 0)
        self.seconds[name] = time.perf_counter() - t0
        try:
            msg = json.loads(b"".join(chunks) or b"{}")
        except ValueError:
            msg = {}
        if "files" in msg and os.WEXITSTATUS(status) == 0 and os.WIFEXITED(status):
            job[4] = [Path(p) for p in msg["files"]]
        else:
            why = msg.get("error") or f"the drawing process ended with status {status}"
            job[4] = (InputError if msg.get("input") else RuntimeError)(f"{name}: {why}")

    def wait(self) -> list[Path]:
        """Every job's files, in submission order; the first failed job's error, naming it (an
        InputError stays one; the others are still waited for, so none outlives the run)."""
        files, error = list(self._inline), None
        for job in self._jobs:
            if job[4] is None:
                self._collect(job)
            if isinstance(job[4], BaseException):
                error = error or job[4]
            else:
                files += job[4]
        self._jobs = []
        if error is not None:
            raise error
        return files

    def kill(self) -> None:
        """Stop every child still drawing (the run failed)."""
        for _, pid, r, _, outcome in self._jobs:
            if outcome is not None:             # collected: reaped, its pipe closed
                continue
            try:
                os.kill(pid, signal.SIGKILL)
                os.waitpid(pid, 0)
            except OSError:
                pass
            os.close(r)
        self._jobs = []
