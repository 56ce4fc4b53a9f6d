"""`liftoff run --ranks 2` (mpirun) against the serial run: the components shared out over
two processes (each reduced by one rank alone), and distributed over both
(LIFTOFF_MPI_COMPONENTS=distributed), give the serial results within solver tolerance,
only rank 0 writes, the stage cache works across runs (a CB-stage miss with a
component-stage hit), and errors end every rank with one line and exit status 2, without
hanging."""
import importlib.util
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from liftoff.transient import load_result
from liftoff.workflows.cli import main
from liftoff.workflows.parallel import mpirun_env

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
HAVE_FE = all(importlib.util.find_spec(m) is not None for m in ("dolfinx", "gmsh", "slepc4py"))
pytestmark = [pytest.mark.slow, pytest.mark.fem,
              pytest.mark.skipif(not HAVE_FE or shutil.which("mpirun") is None, reason="needs dolfinx and mpirun")]


def _test_run():
    """test_run.py as a module: its scenario writer and its coarse FE [model]."""
    spec = importlib.util.spec_from_file_location("liftoff_test_run", HERE / "test_run.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


MODEL = _test_run().COARSE_FE


def _scenario(tmp_path, model, **kw):
    """The scenario writer of test_run.py (the default scenario with another [model])."""
    return _test_run()._scenario(tmp_path, model, **kw)


def _liftoff(*args, mpirun=False, timeout=600, **extra_env):
    # mpirun_env: this pytest worker may have initialised MPI (an FE test before this one)
    env = dict(mpirun_env(os.environ), PYTHONPATH=str(ROOT), PYVISTA_OFF_SCREEN="true",
               OMPI_MCA_rmaps_base_oversubscribe="1", **extra_env)
    cmd = [sys.executable, "-m", "liftoff.workflows.cli", *map(str, args)]
    if mpirun:
        cmd = [shutil.which("mpirun"), "--quiet", "-n", "2", *cmd]
    return subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=timeout, cwd=ROOT)


def test_two_ranks_give_the_serial_run(tmp_path, capsys):
    p = _scenario(tmp_path, MODEL, t_end=7.5, cases=[{"name": "nominal"}])
    assert main(["run", str(p), "--out", str(tmp_path / "serial"), "--cache", str(tmp_path / "c1"),
                 "--no-progress", "--no-snapshots", "--no-plots"]) == 0     # (the results compared; 9 s of plots)
    capsys.readouterr()
    res = _liftoff("run", p, "--out", tmp_path / "two", "--cache", tmp_path / "c2", "--no-progress",
                   "--ranks", "2")
    assert res.returncode == 0, res.stderr[-3000:]
    assert res.stdout.count("wall time per stage") == 1          # rank 0 speaks, rank 1 is silent
    # the five components shared out over the two ranks, each reduced by one rank alone
    # (either rank may claim the core first)
    assert "(rank 1)" in res.stdout and re.search(r"fe core( \(rank 1\))? \(built", res.stdout), res.stdout[-3000:]
    assert not any((tmp_path / "c2" / "claims").iterdir())          # the claims are cleared
    a, b = load_result(tmp_path / "serial" / "results_nominal.h5"), load_result(tmp_path / "two" / "results_nominal.h5")
    # every component reduced serially by one worker, as in the serial run (its round-off
    # may differ only through BLAS threads; the distributed path below: MUMPS/SLEPc
    # round-off on 2 processes and the eigensolver tolerance, relative residual 1e-10)
    err = np.abs(a.contact_force - b.contact_force).max() / np.abs(a.contact_force).max()
    print(f"2 ranks vs serial: post forces {err:.1e} of the peak")
    assert a.contact_force.shape == b.contact_force.shape and err < 1e-7
    assert (tmp_path / "two" / "table1.txt").read_text() == (tmp_path / "serial" / "table1.txt").read_text()
    for d, n in (("fe", 5), ("cb", 5), ("system", 2)):   # one entry per product (rank 0's), no stray files
        names = sorted(f.name for f in (tmp_path / "c2" / d).iterdir() if not f.name.endswith(".lock"))
        keys = {name.split(".")[0] for name in names}
        assert len(keys) == n and all(f"{k}.entry.json" in names for k in keys), names
        assert all(name.endswith((".npz", ".entry.json")) for name in names), names
    assert (tmp_path / "two" / "snapshot_release_nominal.png").stat().st_size > 20_000
    # CB stage missing, component stage cached: the PETSc matrices are built from the
    # cached components, each distributed over both ranks (LIFTOFF_MPI_COMPONENTS)
    shutil.rmtree(tmp_path / "c2" / "cb")
    shutil.rmtree(tmp_path / "c2" / "system")
    res = _liftoff("run", p, "--out", tmp_path / "again", "--cache", tmp_path / "c2", "--no-progress",
                   "--no-snapshots", "--no-plots", mpirun=True, LIFTOFF_MPI_COMPONENTS="distributed")
    assert res.returncode == 0, res.stderr[-3000:]
    assert "fe core (hit)" in res.stdout and "cb core (built)" in res.stdout and "(rank 1)" not in res.stdout
    c = load_result(tmp_path / "again" / "results_nominal.h5")
    assert np.abs(c.contact_force - b.contact_force).max() < 1e-7 * np.abs(b.contact_force).max()


def test_errors_under_two_ranks_are_one_line(tmp_path):
    bad = _scenario(tmp_path, dict(MODEL, bogus=1), name="bad.toml")
    for how in ({"mpirun": True}, {}):            # mpirun yourself: one line per rank; --ranks: once
        args = ["run", bad, "--out", tmp_path / "o", "--no-progress"] + ([] if how else ["--ranks", "2"])
        res = _liftoff(*args, timeout=120, **how)
        lines = res.stderr.strip().splitlines()
        assert res.returncode == 2 and lines and set(lines) == {lines[0]}, res.stderr[-2000:]
        assert lines[0].startswith("liftoff: error: ") and "bogus" in lines[0]
        assert len(lines) == (2 if how else 1)
    # an error that only rank 0 meets (it alone creates the output directory) reaches rank 1
    (tmp_path / "file").write_text("")
    res = _liftoff("run", bad, "--out", tmp_path / "file", "--no-progress", "--ranks", "2", timeout=120)
    assert res.returncode == 2 and res.stderr.count("liftoff: error:") == 1, res.stderr[-2000:]
