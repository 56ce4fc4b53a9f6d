"""Executors for the case runner (workflows/campaign.py): any concurrent.futures.Executor.

* a local process pool (``--workers N``; ``spawn`` start: the workers import only what a
  case needs, never the FE stack, and inherit no MPI or dolfinx state);
* Dask distributed (``--dask ADDRESS`` of a running scheduler, or ``--dask local`` for a
  LocalCluster of N single-threaded worker processes), through ``Client.get_executor``;
* MPI (``--mpi``): ``mpi4py.futures.MPIPoolExecutor``, the command started as
  ``mpiexec -n K python -m mpi4py.futures -m liftoff.workflows.cli run ... --mpi``;
* ``--workers 0``: :class:`InlineExecutor`, every case in the calling process.

Workers on other machines (Dask, MPI) need the same liftoff and the stage cache and the
scenario's files at the same paths (a shared file system): a task names them, it does
not carry the model.
"""
from __future__ import annotations

import multiprocessing
from concurrent.futures import Executor, Future, ProcessPoolExecutor
from contextlib import contextmanager
from typing import Iterator

from liftoff.core.errors import InputError


class InlineExecutor(Executor):
    """Runs each task at once in the calling process (a sequential reference)."""

    _max_workers = 1

    def submit(self, fn, /, *args, **kwargs) -> Future:
        fut: Future = Future()
        try:
            fut.set_result(fn(*args, **kwargs))
        except BaseException as exc:  # noqa: BLE001 - handed to the caller through the future
            fut.set_exception(exc)
        return fut


@contextmanager
def make_executor(workers: int = 2, dask: str | None = None, mpi: bool = False) -> Iterator[tuple[Executor, str]]:
    """(executor, description) for the options of ``liftoff run``; closed on exit."""
    if workers < 0:
        raise InputError(f"--workers {workers}: must be 0 (in process) or more")
    if dask and mpi:
        raise InputError("--dask and --mpi: give one of them")
    if mpi:
        try:
            from mpi4py.futures import MPIPoolExecutor
        except ImportError as exc:
            raise InputError(f"--mpi: mpi4py.futures is not available ({exc})") from None
        with MPIPoolExecutor(max_workers=workers or None) as ex:
            yield ex, f"MPI pool ({workers or 'all'} workers)"
        return
    if dask:
        with _dask_executor(dask, workers) as out:
            yield out
        return
    if workers == 0:
        yield InlineExecutor(), "in process"
        return
    with ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn")) as ex:
        yield ex, f"process pool of {workers}"


@contextmanager
def _dask_executor(address: str, workers: int):
    try:
        from distributed import Client, LocalCluster
    except ImportError as exc:
        raise InputError(f"--dask: dask.distributed is not installed ({exc}); pip install "
                         "'liftoff-loads[dask]'") from None
    if address == "local":
        cluster = LocalCluster(n_workers=max(workers, 1), threads_per_worker=1, processes=True,
                               dashboard_address=None, silence_logs=40)
        client = Client(cluster)
        what = f"Dask LocalCluster of {max(workers, 1)} worker processes"
    else:
        cluster = None
        try:
            client = Client(address, timeout="20s")
        except OSError as exc:
            raise InputError(f"--dask {address}: cannot reach the scheduler ({exc})") from None
        what = f"Dask scheduler {address} ({len(client.scheduler_info().get('workers', {}))} workers)"
    try:
        ex = client.get_executor(pure=False)
        ex._max_workers = max(workers, len(client.scheduler_info().get("workers", {})), 1)
        yield ex, what
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
