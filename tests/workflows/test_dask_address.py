"""--dask addresses (issue 27): a malformed or web address is refused before any stage, and
a server that accepts but never answers (a web server) is given up within the time box."""
from __future__ import annotations

import socket
import threading
import time

import pytest

from liftoff.core.errors import InputError
from liftoff.workflows import executors


@pytest.mark.parametrize("address, match", [
    ("not-an-address", "not a Dask scheduler address"),
    ("http://localhost:8787", "a web \\(dashboard\\) address"),
    ("tcp://host", "not a Dask scheduler address"),
])
def test_bad_addresses_are_refused(address, match):
    with pytest.raises(InputError, match=match):
        executors.check_dask_address(address)


def test_good_addresses_pass():
    for a in (None, "local", "tcp://127.0.0.1:8786", "tls://scheduler.example.org:8786"):
        executors.check_dask_address(a)


def test_silent_server_is_given_up(monkeypatch):
    pytest.importorskip("distributed")
    from distributed import Client

    srv = socket.socket()
    srv.bind(("127.0.0.1", 0))
    srv.listen(4)
    held = []
    stop = threading.Event()

    def accept():                    # accept and never answer, as a web server waiting for a request
        srv.settimeout(0.2)
        while not stop.is_set():
            try:
                held.append(srv.accept()[0])
            except OSError:
                pass

    threading.Thread(target=accept, daemon=True).start()
    monkeypatch.setattr(executors, "DASK_CONNECT_S", 1)
    t0 = time.perf_counter()
    try:
        with pytest.raises(InputError, match="cannot reach a Dask scheduler there within 1 s"):
            executors._connect(Client, f"tcp://127.0.0.1:{srv.getsockname()[1]}")
    finally:
        stop.set()
        srv.close()
    assert time.perf_counter() - t0 < 1 + 5 + 2


def test_mpi_outside_mpiexec_is_refused(monkeypatch):
    """--mpi without mpiexec hung after Open MPI's "not enough slots" (issue 27)."""
    for var in ("OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE", "MPI_LOCALNRANKS"):
        monkeypatch.delenv(var, raising=False)
    with pytest.raises(InputError, match="--mpi: start the run under mpiexec"):
        executors.check_mpi(True)
    executors.check_mpi(False)
