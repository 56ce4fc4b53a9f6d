"""The same model under `mpirun -n 2` gives the serial frequencies, mass and static answer."""
import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest

from liftoff.workflows.parallel import mpirun_env

from ..roundoff import sum_rtol

pytestmark = [pytest.mark.fem, pytest.mark.slow]   # ~9 s idle, >20 s on a loaded machine
HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]


def _run(n, path, degree, script="mpi_modes_script.py", extra=()):
    return run_script(n, script, [path, *extra, str(degree)])


def run_script(n: int, script: str, args) -> dict:
    """``mpirun -n n python tests/fem/<script> args...``: the JSON its rank 0 prints on its
    "RESULT " line. Each rank's own stdout and stderr go to files (mpirun --output-filename)
    and are shown when the run fails. Under the parallel fem suite, runs whose output went
    through mpirun's forwarding alone exited 1 with none of it, in most of 16 runs of
    tests/fem (2026-12-07; once on 2026-11-28 too); with the files, 6 of 6 passed. It still
    happened once in a whole suite under load (2026-12-07: a rank exited 1 having written
    nothing, not a line of Python's output or traceback), so a run that fails before any rank
    wrote anything, its script never having started, is started once more (said on stdout);
    a script that starts and fails, or prints no result, fails the test at once."""
    mpirun = shutil.which("mpirun")
    if mpirun is None:
        pytest.skip("mpirun not installed (Debian package openmpi-bin comes with python3-dolfinx-real)")
    env = dict(mpirun_env(os.environ), PYTHONPATH=str(ROOT), OMPI_MCA_rmaps_base_oversubscribe="1",
               PYVISTA_OFF_SCREEN="true")      # this process may have initialised MPI (parallel.mpirun_env)
    for attempt in (1, 2):
        with tempfile.TemporaryDirectory() as logs:
            cmd = [mpirun, "--output-filename", logs, "-n", str(n), sys.executable, str(HERE / script), *map(str, args)]
            res = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=300, cwd=ROOT)
            own = {f.relative_to(logs).as_posix(): f.read_text(errors="replace")
                   for f in sorted(Path(logs).rglob("std*"))}
        lines = [ln for text in [res.stdout, *own.values()] for ln in text.splitlines() if ln.startswith("RESULT ")]
        ranks = "\n".join(f"--- {name}:\n{text[-1500:]}" for name, text in own.items() if text.strip())
        silent = res.returncode != 0 and not res.stdout.strip() and not ranks
        if not (silent and attempt == 1):
            break
        print(f"mpirun exited {res.returncode} before any rank wrote a line; starting it once more")
    assert res.returncode == 0 and lines, f"mpirun failed ({res.returncode}): {res.stderr[-1000:]}\n{ranks}"
    return json.loads(lines[0][7:])


def test_two_ranks_match_serial(msh):
    path = msh("box", L=1.0, W=0.1, H=0.1, n=(16, 2, 2))
    serial, parallel = _run(1, path, 2), _run(2, path, 2)
    assert parallel["size"] == 2 and serial["n_dof"] == parallel["n_dof"]
    print(f"serial {np.round(serial['freq'][6:], 3)} Hz\n2 ranks {np.round(parallel['freq'][6:], 3)} Hz")
    # same matrices up to DOF ordering; the eigensolver tolerance is 1e-10
    assert parallel["n_rigid"] == serial["n_rigid"] == 6
    assert np.allclose(parallel["freq"][6:], serial["freq"][6:], rtol=1e-8)
    assert np.allclose(parallel["clamped_freq"], serial["clamped_freq"], rtol=1e-8)
    # the mass is a sum over all DOFs, in another order in parallel: n_dof eps
    assert parallel["mass"] == pytest.approx(serial["mass"], rel=sum_rtol(serial["n_dof"]))
    assert np.allclose(parallel["tip"], serial["tip"], rtol=1e-8, atol=1e-14)
    for run in (serial, parallel):      # gathered nodes, cells and field_map are consistent
        # rot_err: one product per node (a few eps of the 1.1 m size); volume: a sum over the cells
        assert run["rot_err"] < sum_rtol(6) * 1.1
        assert run["volume"] == pytest.approx(1.0 * 0.1 * 0.1, rel=sum_rtol(run["n_cells"]))
    assert parallel["n_cells"] == serial["n_cells"]


def test_two_ranks_match_serial_shells(msh):
    """Shell, shell-on-solid and beam-on-shell models: nodes are gathered by position across
    ranks and parts (the beam part lives on rank 0)."""
    tube = msh("shell_tube", R=0.1, L=1.0, n_around=24, n_along=20)
    glued = msh("glued_plate", a=0.2, L=1.0, b=0.2, d=0.1, h=0.05)
    for degree in (1, 2):
        serial = _run(1, tube, degree, "mpi_shell_script.py", (glued,))
        parallel = _run(2, tube, degree, "mpi_shell_script.py", (glued,))
        assert parallel["size"] == 2 and serial["n_dof"] == parallel["n_dof"]
        assert parallel["n_rigid"] == serial["n_rigid"] == 6
        assert np.allclose(parallel["freq"][6:], serial["freq"][6:], rtol=1e-8)
        assert np.allclose(parallel["hybrid_freq"][6:], serial["hybrid_freq"][6:], rtol=1e-8)
        assert parallel["framed_n_dof"] == serial["framed_n_dof"]
        assert np.allclose(parallel["framed_freq"], serial["framed_freq"], rtol=1e-8)
        assert parallel["mass"] == pytest.approx(serial["mass"], rel=1e-12)
        assert parallel["hybrid_mass"] == pytest.approx(serial["hybrid_mass"], rel=1e-12)
        assert np.allclose(parallel["tip"], serial["tip"], rtol=1e-8, atol=1e-14)
        assert parallel["n_cells"] == serial["n_cells"]
        assert serial["rot_err"] < 1e-12 and parallel["rot_err"] < 1e-12
        # interpolation patches (RBE3) eliminate the same DOFs on every rank
        assert parallel["ring_n_dof"] == serial["ring_n_dof"]
        assert np.allclose(parallel["ring"], serial["ring"], rtol=1e-8, atol=1e-14)
