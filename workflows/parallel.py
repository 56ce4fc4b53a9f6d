"""The processes of a run: one, or the ranks of ``mpirun -n N liftoff run ...``.

Under mpirun every rank runs the same program. The model stages of the components not yet
in the stage cache are shared out: each rank takes the next unclaimed component and runs
its FE and Craig-Bampton stages in a serial worker process of its own, so the components
are reduced concurrently (workflows/pipeline.py, ``reduce_over_ranks``). With fewer such components
than ranks, or ``LIFTOFF_MPI_COMPONENTS=distributed``, they are distributed over all ranks
by dolfinx/PETSc (mesh, assembly, MUMPS factorisation, SLEPc eigensolves), one component
after another. Everything else is done by rank 0 alone, which writes every file (results,
reports) while the other ranks wait. An error is raised on
every rank with the same one-line message, so that no rank is left waiting.

mpi4py is imported only under mpirun (through liftoff.fem.parallel: the FE stack stays in
fem/); a serial run uses :data:`SERIAL`, which has the same few methods.
"""
from __future__ import annotations

import os
import sys
import time
from typing import Any, Callable

from liftoff.core.errors import ConvergenceError, InputError

_SIZE_VARS = ("OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE", "MPI_LOCALNRANKS")
_TAG = 7301


class Serial:
    """A one-process stand-in for an mpi4py communicator (the methods used here)."""

    rank, size = 0, 1

    def bcast(self, obj, root: int = 0):
        return obj

    def allgather(self, obj) -> list:
        return [obj]

    def barrier(self) -> None:
        return None


SERIAL = Serial()


#: variables of an MPI singleton (a Python that initialised MPI without mpirun): passed on
#: to an mpirun it starts, they make mpirun fail at once (exit 1, nothing said)
SINGLETON_VARS = ("OMPI_COMM_WORLD", "OMPI_MCA_ess", "OMPI_MCA_orte_ess", "PMIX_", "PMI_")


def mpirun_env(environ) -> dict:
    """The environment for an mpirun started from a process with ``environ``: without an MPI
    singleton's variables (:data:`SINGLETON_VARS`), and as root (containers) with Open MPI's
    permission to run, which it refuses otherwise."""
    env = {k: v for k, v in environ.items() if not k.startswith(SINGLETON_VARS)}
    if hasattr(os, "geteuid") and os.geteuid() == 0:
        env.update(OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    return env


def launched_size() -> int:
    """Number of processes mpirun started (1 when not under mpirun)."""
    for var in _SIZE_VARS:
        if os.environ.get(var, "").isdigit():
            return int(os.environ[var])
    return 1


def world():
    """MPI.COMM_WORLD under mpirun with more than one process, else :data:`SERIAL`. Under
    ``mpiexec -n K python -m mpi4py.futures`` (a campaign's ``--mpi`` executor) the ranks
    other than 0 serve the case pool and never run this program: the run is serial."""
    if launched_size() > 1 and "mpi4py.futures.__main__" not in sys.modules:
        from liftoff.fem.parallel import world as mpi_world

        return mpi_world()
    return SERIAL


def _outcome(exc: BaseException) -> tuple[str, str]:
    kind = "convergence" if isinstance(exc, ConvergenceError) else "input"
    if isinstance(exc, (InputError, ConvergenceError)):
        return kind, str(exc)
    if isinstance(exc, OSError) and exc.filename is not None:
        return kind, f"{exc.strerror or type(exc).__name__}: {exc.filename!s}"
    return kind, f"rank 0 failed: {type(exc).__name__}: {exc}"


def _raise(outcome: tuple[str, str]) -> None:
    kind, msg = outcome
    raise (ConvergenceError if kind == "convergence" else InputError)(msg)


def all_or_none(comm, exc: BaseException | None) -> None:
    """After a stage each rank ran by itself: every rank raises the first failing rank's
    error (a failing rank its own ``exc``), as one line; nothing when none failed. Collective."""
    outcomes = comm.allgather(None if exc is None else _outcome(exc))
    if exc is not None:
        raise exc
    for outcome in outcomes:
        if outcome is not None:
            _raise(outcome)


def wait_for_all(comm, poll_s: float = 0.05) -> None:
    """A barrier that sleeps (polling every ``poll_s``) instead of spinning in MPI, so that
    a rank done with its share leaves its core to the others' work."""
    if comm.size == 1:
        return
    req = comm.Ibarrier()
    while not req.Test():
        time.sleep(poll_s)


def on_root(comm, fn: Callable[[], Any], share: bool = True) -> Any:
    """Run ``fn`` on rank 0 only (file writes, gmsh); its result (if ``share``) or its error
    reaches every rank, which raises the same one-line error."""
    if comm.size == 1:
        return fn()
    value, outcome, error = None, None, None
    if comm.rank == 0:
        try:
            value = fn()
        except BaseException as exc:  # every rank must learn of it, then rank 0 re-raises
            outcome, error = _outcome(exc), exc
    outcome, shared = comm.bcast((outcome, value if share and outcome is None else None), root=0)
    if error is not None:
        raise error
    if outcome is not None:
        _raise(outcome)
    return value if comm.rank == 0 else shared


def root_only(comm, fn: Callable[[], Any], poll_s: float = 0.05) -> Any:
    """Rank 0 runs ``fn`` (the transient, reports: minutes perhaps) while the other ranks
    wait asleep (polling a message, not spinning in a collective); an error on rank 0 is
    raised on every rank. Returns fn's result on rank 0, None elsewhere."""
    if comm.size == 1:
        return fn()
    if comm.rank == 0:
        outcome = None
        try:
            return fn()
        except BaseException as exc:
            outcome = _outcome(exc)
            raise
        finally:
            for r in range(1, comm.size):
                comm.send(outcome, dest=r, tag=_TAG)
    req = comm.irecv(source=0, tag=_TAG)
    while True:
        done, outcome = req.test()
        if done:
            break
        time.sleep(poll_s)
    if outcome is not None:
        _raise(outcome)
    return None
