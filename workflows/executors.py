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
import re
from concurrent.futures import Executor, Future, ProcessPoolExecutor
from contextlib import ExitStack, contextmanager
from typing import Callable, ContextManager, Iterator

from liftoff.core.errors import InputError


def die_with_parent() -> None:
    """Pool worker initializer, the first call of a child forked beside the run
    (workflows/beside.py), and ``preexec_fn`` of the mpirun that ``--ranks`` starts
    (workflows/run.launch) (Linux): the kernel sends this process SIGTERM when the process
    that started it dies, however it dies (SIGKILL included), so nothing outlives a killed
    run (issue 27). Elsewhere a no-op; a process whose parent is already gone exits."""
    import ctypes
    import os
    import signal

    try:
        libc = ctypes.CDLL(None, use_errno=True)
        PR_SET_PDEATHSIG = 1
        libc.prctl(PR_SET_PDEATHSIG, signal.SIGTERM, 0, 0, 0)
    except (OSError, AttributeError):
        return
    if os.getppid() == 1:                 # the parent died before the call: nobody to work for
        os._exit(1)


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


class OnDemand(Executor):
    """The executor of ``opener()`` (a context manager yielding (executor, description), such
    as :func:`make_executor`), opened at the first submit and closed by ``shutdown``: a pool
    for work that is seldom needed, which costs nothing (no worker processes, no memory)
    when none comes. A campaign's end re-runs a case only when its captured histories are
    missing (workflows/campaign.py, write_envelope_histories)."""

    def __init__(self, opener: Callable[[], ContextManager], max_workers: int):
        self._opener, self._scope, self._inner = opener, None, None
        self._max_workers = max(1, max_workers)

    @property
    def opened(self) -> bool:
        return self._inner is not None

    def submit(self, fn, /, *args, **kwargs) -> Future:
        if self._inner is None:
            scope = ExitStack()
            self._inner, _ = scope.enter_context(self._opener())
            self._scope = scope
        return self._inner.submit(fn, *args, **kwargs)

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        scope, self._scope, self._inner = self._scope, None, None
        if scope is not None:
            scope.close()


@contextmanager
def make_executor(workers: int = 2, dask: str | None = None, mpi: bool = False) -> Iterator[tuple[Executor, str]]:
    """(executor, description) for the options of ``liftoff run``; closed on exit."""
    if workers < 0:
        raise InputError(f"--workers {workers}: must be 0 (in process) or more")
    if dask and mpi:
        raise InputError("--dask and --mpi: give one of them")
    if mpi:
        check_mpi(mpi)
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
    with ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn"),
                             initializer=die_with_parent) as ex:
        yield ex, f"process pool of {workers}"


#: a Dask scheduler address: protocol://host:port (the dashboard's http:// address is not one)
_DASK_ADDRESS = re.compile(r"^(tcp|tls|ucx|ws|wss)://[A-Za-z0-9_.\-\[\]:]+:\d{1,5}$")
#: seconds to reach a scheduler before the run gives up with one line
DASK_CONNECT_S = 20
#: bytes a scheduler's handshake may announce (it sends a few hundred; distributed would
#: allocate whatever a server's first 8 bytes say)
DASK_HANDSHAKE_MAX = 1 << 20


def check_mpi(mpi: bool) -> None:
    """--mpi outside mpiexec is refused: spawning the pool's ranks there waits for slots that
    never come (issue 27: a hang after Open MPI's "not enough slots")."""
    from .parallel import launched_size

    if mpi and launched_size() < 2:
        raise InputError("--mpi: start the run under mpiexec with the pool's ranks: mpiexec -n K python -m "
                         "mpi4py.futures -m liftoff.workflows.cli run ... --mpi (K >= 2)")


def check_dask_address(address: str | None) -> None:
    """One-line InputError unless ``address`` is None, "local" or a scheduler address."""
    if address is None or address == "local":
        return
    if address.startswith(("http://", "https://")):
        raise InputError(f"--dask {address}: that is a web (dashboard) address; a Dask scheduler's is "
                         "tcp://host:8786")
    if not _DASK_ADDRESS.match(address):
        raise InputError(f"--dask {address!r}: not a Dask scheduler address (tcp://host:port, or 'local')")


def probe_dask_scheduler(address: str, timeout: float | None = None) -> None:
    """One-line InputError unless the ``tcp://`` ``address`` answers as a Dask scheduler does,
    within ``timeout`` s (default DASK_CONNECT_S): on accepting a connection a scheduler
    writes its handshake (distributed.comm: an 8-byte frame length, then that many bytes,
    a few hundred). Another server is named here, before distributed reads its answer as a
    frame length (issue 27: a proxy's "HTTP/1.1 ..." gave "Unable to allocate 3.07 EiB"); a
    web server, which waits for a request, sends nothing. Other protocols (tls://, ...)
    are left to the Client."""
    import socket
    import struct
    import time
    from urllib.parse import urlsplit

    if not address.startswith("tcp://"):
        return
    timeout = DASK_CONNECT_S if timeout is None else timeout
    url = urlsplit(address)
    try:
        conn = socket.create_connection((url.hostname, url.port), timeout=timeout)
    except OSError as exc:
        raise InputError(f"--dask {address}: cannot connect ({type(exc).__name__}: {exc})") from None
    got, need, deadline = b"", 8, time.monotonic() + timeout
    nope = f"--dask {address}: not a Dask scheduler:"
    with conn:
        while len(got) < need:
            conn.settimeout(max(deadline - time.monotonic(), 1e-3))
            try:
                chunk = conn.recv(min(need - len(got), 1 << 16))
            except TimeoutError:
                if got:
                    raise InputError(f"{nope} it sent {len(got)} bytes, not a whole handshake, within {timeout:g} "
                                     "s") from None
                raise InputError(f"{nope} it sent nothing within {timeout:g} s (a Dask scheduler greets first; a web "
                                 "server waits for a request)") from None
            except OSError as exc:
                raise InputError(f"{nope} the connection failed ({type(exc).__name__}: {exc})") from None
            if not chunk:
                raise InputError(f"{nope} it closed the connection after {len(got)} bytes, before a Dask handshake")
            got += chunk
            if need == 8 and len(got) >= 8:
                (n,) = struct.unpack("Q", got[:8])        # distributed's frame length (native order)
                if not 0 < n <= DASK_HANDSHAKE_MAX:
                    raise InputError(f"{nope} its first bytes {got[:8]!r} are no Dask handshake (it announces "
                                     f"{n} bytes; a scheduler's is under {DASK_HANDSHAKE_MAX} bytes)")
                need = 8 + n


def _connect(Client, address: str):
    """A Client of the scheduler at ``address``, or a one-line InputError within about
    DASK_CONNECT_S seconds: the address first probed (:func:`probe_dask_scheduler`), then
    Client's own timeout covers the TCP connection, not the handshake: a server of another
    protocol that accepts and never answers (a web server) would hold it for ever, so the
    connection is made in a daemon thread that is given up."""
    import threading

    probe_dask_scheduler(address)
    box: dict = {}

    def work():
        try:
            box["client"] = Client(address, timeout=f"{DASK_CONNECT_S}s")
        except Exception as exc:      # OSError, TimeoutError, a peer that speaks another protocol ...
            box["error"] = exc

    t = threading.Thread(target=work, name="liftoff-dask-connect", daemon=True)
    t.start()
    t.join(DASK_CONNECT_S + 5)
    if "client" in box:
        return box["client"]
    why = "no answer" if "error" not in box else \
        f"{type(box['error']).__name__}: {' '.join(str(box['error']).split())[:160]}"
    raise InputError(f"--dask {address}: cannot reach a Dask scheduler there within {DASK_CONNECT_S} s ({why})")


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
        check_dask_address(address)
        client = _connect(Client, address)
        what = f"Dask scheduler {address} ({len(client.scheduler_info().get('workers', {}))} workers)"
    try:
        ex = client.get_executor(pure=False)
        ex._max_workers = max(workers, len(client.scheduler_info().get("workers", {})), 1)
        yield ex, what
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
