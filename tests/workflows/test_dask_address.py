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
        with pytest.raises(InputError, match=r"not a Dask scheduler: it sent nothing within 1 s \(a Dask scheduler "
                                             r"greets first; a web server waits for a request\)"):
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


def _server(answer: bytes | None, hang_up: bool = False):
    """A TCP server on a free port that sends ``answer`` to each connection (None: nothing),
    then hangs up (``hang_up``) or holds it open; returns (address, close)."""
    srv = socket.socket()
    srv.bind(("127.0.0.1", 0))
    srv.listen(4)
    srv.settimeout(0.2)
    held, stop = [], threading.Event()

    def serve():
        while not stop.is_set():
            try:
                c = srv.accept()[0]
            except OSError:
                continue
            if answer is not None:
                c.sendall(answer)
            c.close() if hang_up else held.append(c)

    threading.Thread(target=serve, daemon=True).start()

    def close():
        stop.set()
        srv.close()
        for c in held:
            c.close()

    return f"tcp://127.0.0.1:{srv.getsockname()[1]}", close


@pytest.mark.parametrize("answer, hang_up, match", [
    (b"HTTP/1.1 407 Proxy Authentication Required\r\n\r\n", False,
     r"its first bytes b'HTTP/1\.1' are no Dask handshake"),
    (b"\x64" + bytes(7) + b"abc", True, r"closed the connection after 11 bytes, before a Dask handshake"),
], ids=["proxy", "short-answer-hang-up"])
def test_a_server_that_is_no_scheduler_is_named_before_dask_reads_it(monkeypatch, answer, hang_up, match):
    """Issue 27: a proxy's answer "HTTP/1.1 ..." was read by distributed as a frame length and
    gave "Unable to allocate 3.07 EiB". The address is probed first, as a scheduler answers (it
    writes its handshake on accept); distributed's Client is never reached."""
    def no_client(*a, **k):
        raise AssertionError("Client reached")

    monkeypatch.setattr(executors, "DASK_CONNECT_S", 1)
    address, close = _server(answer, hang_up)
    try:
        with pytest.raises(InputError, match=f"^--dask {address}: not a Dask scheduler: .*{match}") as exc:
            executors._connect(no_client, address)
    finally:
        close()
    assert "\n" not in str(exc.value)


def test_nothing_listening_is_named():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()                                   # a free port: nothing listens there
    with pytest.raises(InputError, match=rf"^--dask tcp://127\.0\.0\.1:{port}: cannot connect \(.*refused"):
        executors.probe_dask_scheduler(f"tcp://127.0.0.1:{port}")


def test_a_real_scheduler_passes_the_probe():
    """The probe's premise: a Dask scheduler writes a short handshake as soon as it accepts."""
    pytest.importorskip("distributed")
    from distributed import LocalCluster

    from distributed import Client

    with LocalCluster(n_workers=0, processes=False, protocol="tcp://", host="127.0.0.1", dashboard_address=None,
                      silence_logs=40) as cluster:
        assert cluster.scheduler_address.startswith("tcp://")          # the probe's protocol
        executors.probe_dask_scheduler(cluster.scheduler_address, 5)
        executors._connect(Client, cluster.scheduler_address).close()   # and the Client after it


def test_run_probes_the_scheduler_before_the_model_stages(tmp_path, monkeypatch, capsys):
    """`liftoff run --cases 2 --dask <proxy>`: one line naming the address, exit 2, and no
    model stage run (they would take minutes on an FE model before the connection)."""
    from liftoff.workflows import cli, run

    def no_models(*a, **k):
        raise AssertionError("model stages reached")

    monkeypatch.setattr(run, "prepare_models", no_models)
    s = tmp_path / "s.toml"
    s.write_text('extends = "shuttle"\n[model]\nsource = "stick"\n')
    address, close = _server(b"HTTP/1.1 407 Proxy Authentication Required\r\n\r\n")
    try:
        code = cli.main(["run", str(s), "--cases", "2", "--dask", address, "--out", str(tmp_path / "o"),
                         "--no-progress"])
    finally:
        close()
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and err[0].startswith(f"liftoff: error: --dask {address}: not a Dask "
                                                             "scheduler: its first bytes b'HTTP/1.1'"), err
