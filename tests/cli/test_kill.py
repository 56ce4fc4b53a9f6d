"""Killed `liftoff transient` runs (issue 16): SIGTERM exits 143 and cleans up, SIGKILL
leaves at most a staging folder that the next run removes; in both cases the output folder
keeps the previous run's complete, manifest-checked result (workflows/outdir.py)."""
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

from liftoff.workflows.outdir import MANIFEST, verify

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "vehicle_on_pad"


def _cmd(*args):
    exe = os.path.join(os.path.dirname(sys.executable), "liftoff")
    return [exe, *args] if os.path.exists(exe) else [sys.executable, "-m", "liftoff.workflows.cli", *args]


def _scenario(tmp_path: Path, h: float) -> Path:
    """The vehicle_on_pad example with its files copied, at step h (s)."""
    for f in EXAMPLE.iterdir():
        if f.suffix in (".npz", ".csv"):
            (tmp_path / f.name).write_bytes(f.read_bytes())
    text = (EXAMPLE / "scenario.toml").read_text()
    text = re.sub(r"(?m)^t_end = 1.2.*$", f"t_end = 1.2\nh = {h!r}", text)
    p = tmp_path / f"h{h:g}.toml"
    p.write_text(text)
    return p


def _handles_sigterm(pid: int) -> bool:
    """The process has installed its SIGTERM handler (Linux: bit 15 of SigCgt in /proc)."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return False
    caught = int(re.search(r"SigCgt:\s*([0-9a-f]+)", status).group(1), 16)
    return bool(caught & (1 << (signal.SIGTERM - 1)))


def _leftovers(tmp_path: Path):
    return [p.name for p in tmp_path.iterdir() if ".liftoff-tmp-" in p.name or p.name.endswith(".tmp")]


def test_sigterm_and_sigkill_during_a_transient(tmp_path: Path):
    out = tmp_path / "out"
    first = subprocess.run(_cmd("transient", str(_scenario(tmp_path, 4e-4)), "--out", str(out), "--no-progress"),
                           capture_output=True, text=True, timeout=300)
    assert first.returncode == 0, first.stderr
    before = (out / MANIFEST).read_text()
    slow = _scenario(tmp_path, 1e-5)           # 120,000 steps, 3 runs with the error estimate: seconds
    for sig, code in ((signal.SIGTERM, 143), (signal.SIGKILL, -9)):
        proc = subprocess.Popen(_cmd("transient", str(slow), "--out", str(out), "--no-progress"),
                                stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        t0 = time.time()                       # wait for the handler (imports take seconds under load)
        while not _handles_sigterm(proc.pid) and proc.poll() is None and time.time() - t0 < 120:
            time.sleep(0.02)
        time.sleep(0.5)                        # statics, marching
        assert proc.poll() is None, "the run ended before it was killed"
        proc.send_signal(sig)
        err = proc.communicate(timeout=120)[1]
        assert proc.returncode == code, err
        assert (out / MANIFEST).read_text() == before and verify(out) == []
        if sig == signal.SIGTERM:
            assert "terminated (SIGTERM), no results written" in err and not _leftovers(tmp_path)
    again = subprocess.run(_cmd("transient", str(_scenario(tmp_path, 5e-4)), "--out", str(out), "--no-progress"),
                           capture_output=True, text=True, timeout=300)
    assert again.returncode == 0, again.stderr
    assert not _leftovers(tmp_path) and verify(out) == [] and (out / MANIFEST).read_text() != before


def test_sigkill_of_a_campaign_leaves_no_worker(tmp_path: Path):
    """SIGKILL of `liftoff run --cases N --workers 2` (issue 27: the pool workers went on
    running): the workers get SIGTERM from the kernel when their parent dies
    (executors.die_with_parent) and are gone within seconds."""
    import pytest

    psutil = pytest.importorskip("psutil")
    s = tmp_path / "c.toml"
    s.write_text('extends = "shuttle"\n[model]\nsource = "stick"\nmesh_size = 6.0\n[time]\nt_end = 2.0\n'
                 '[output]\nplots = false\nsnapshots = false\n')
    proc = subprocess.Popen(_cmd("run", str(s), "--out", str(tmp_path / "out"), "--cases", "400", "--workers", "2",
                                 "--no-progress", "--no-error-estimate", "--cache", str(tmp_path / "cache")),
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        parent = psutil.Process(proc.pid)
        workers = []
        deadline = time.time() + 240
        while time.time() < deadline and len(workers) < 2:
            workers = [c for c in parent.children(recursive=True) if "spawn" in " ".join(c.cmdline())]
            time.sleep(0.5)
        assert len(workers) >= 2, "the campaign's pool workers never started"
        time.sleep(2.0)                                  # the workers are inside cases now
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=30)
        gone, alive = psutil.wait_procs(workers, timeout=20)
        assert not alive, f"workers outlived the killed campaign: {[p.pid for p in alive]}"
    finally:
        if proc.poll() is None:
            proc.kill()


def test_sigterm_of_a_ranks_run_stops_its_ranks(tmp_path: Path):
    """SIGTERM to `liftoff run --ranks 2` (issue 27: it printed "no results written", exited
    143, and 40 s later the surviving ranks replaced the output): mpirun and its ranks stop
    with it, and no output appears afterwards."""
    import shutil

    import pytest

    psutil = pytest.importorskip("psutil")
    if shutil.which("mpirun") is None:
        pytest.skip("no mpirun")
    s = tmp_path / "r.toml"
    s.write_text('extends = "shuttle"\n[model]\nsource = "stick"\nmesh_size = 6.0\n[time]\nt_end = 9.6\n'
                 '[output]\nplots = false\nsnapshots = false\n')
    out = tmp_path / "out"
    # no MPI state of this process (an MPI singleton's variables) reaches mpirun; oversubscription
    # allowed as in tests/workflows/test_mpi_run.py
    env = {k: v for k, v in os.environ.items() if not k.startswith(("OMPI_COMM_", "PMIX_", "PMI_", "OMPI_MCA_ess"))}
    env.update(OMPI_MCA_rmaps_base_oversubscribe="1")
    err = open(tmp_path / "stderr.txt", "w")
    proc = subprocess.Popen(_cmd("run", str(s), "--out", str(out), "--ranks", "2", "--no-progress",
                                 "--cache", str(tmp_path / "cache")),
                            stdout=subprocess.DEVNULL, stderr=err, env=env)
    try:
        parent = psutil.Process(proc.pid)
        ranks = []
        deadline = time.time() + 120
        while time.time() < deadline and len(ranks) < 2 and proc.poll() is None:
            try:                                       # the ranks: the processes below mpirun
                ranks = [c for c in parent.children(recursive=True)
                         if c.ppid() != proc.pid and "python" in c.name().lower()]
            except psutil.Error:
                ranks = []
            time.sleep(0.2)
        assert len(ranks) >= 2, (f"the ranks never started (liftoff exit {proc.poll()}): "
                                 f"{(tmp_path / 'stderr.txt').read_text()[-2000:]}")
        family = parent.children(recursive=True)
        time.sleep(1.0)
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(timeout=60) == 143
        gone, alive = psutil.wait_procs(family, timeout=30)
        assert not alive, f"processes outlived the terminated run: {[p.pid for p in alive]}"
        time.sleep(3.0)
        assert not out.exists()
    finally:
        if proc.poll() is None:
            proc.kill()
        err.close()
