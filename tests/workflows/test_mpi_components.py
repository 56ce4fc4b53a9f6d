"""The pieces of the MPI runs' shared-out components (workflows/pipeline.reduce_over_ranks;
the whole under mpirun: tests/workflows/test_mpi_run.py): a rank's worker leaves the MPI
job, a component is claimed by one rank only, and the mode is checked."""
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from liftoff.core.errors import InputError
from liftoff.workflows import pipeline
from liftoff.workflows.cache import StageCache
from liftoff.workflows.parallel import mpirun_env

ROOT = Path(__file__).resolve().parents[2]


def test_a_ranks_worker_leaves_the_mpi_job():
    """The worker process of a rank drops the job's variables before anything imports
    mpi4py, so it starts as a serial process (workflows/parallel.world: SERIAL)."""
    env = {"OMPI_COMM_WORLD_SIZE": "2", "OMPI_MCA_ess": "pmi", "PMIX_RANK": "1", "PMI_SIZE": "2",
           "MPI_LOCALNRANKS": "2", "PATH": "/usr/bin", "OMPI_ALLOW_RUN_AS_ROOT": "1"}
    pipeline.drop_job_vars(env)
    assert env == {"PATH": "/usr/bin"}


def test_a_component_is_claimed_once(tmp_path):
    assert pipeline._claim(tmp_path, "run-core")
    assert not pipeline._claim(tmp_path, "run-core")
    assert pipeline._claim(tmp_path, "run-pad")


def test_the_mode_is_checked(monkeypatch, tmp_path):
    monkeypatch.setenv(pipeline.MPI_COMPONENTS_ENV, "sideways")
    with pytest.raises(InputError, match="LIFTOFF_MPI_COMPONENTS = 'sideways': give 'concurrent' or 'distributed'"):
        pipeline.reduce_over_ranks(None, [], StageCache(tmp_path))
    monkeypatch.setenv(pipeline.MPI_COMPONENTS_ENV, "distributed")
    assert pipeline.reduce_over_ranks(None, [], StageCache(tmp_path)) == {}


def test_serial_all_or_none_and_wait():
    from liftoff.workflows.parallel import SERIAL, all_or_none, wait_for_all

    wait_for_all(SERIAL)
    all_or_none(SERIAL, None)
    with pytest.raises(InputError, match="bad component"):
        all_or_none(SERIAL, InputError("bad component"))


RANKS_SCRIPT = """
from liftoff.core.errors import InputError
from liftoff.workflows.parallel import all_or_none, wait_for_all, world
comm = world()
wait_for_all(comm)
try:
    all_or_none(comm, InputError("rank 1 failed alone") if comm.rank == 1 else None)
except InputError as exc:
    print(f"rank {comm.rank}: {exc}", flush=True)
"""


@pytest.mark.skipif(shutil.which("mpirun") is None, reason="needs mpirun")
def test_an_error_of_one_rank_reaches_every_rank(tmp_path):
    """A stage each rank runs by itself (the shared-out components): an error on rank 1
    alone is raised on rank 0 too, with the same line, and nobody waits forever."""
    script = tmp_path / "ranks.py"
    script.write_text(RANKS_SCRIPT)
    env = dict(mpirun_env(os.environ), PYTHONPATH=str(ROOT), OMPI_MCA_rmaps_base_oversubscribe="1")
    res = subprocess.run([shutil.which("mpirun"), "--quiet", "-n", "2", sys.executable, str(script)],
                         capture_output=True, text=True, env=env, timeout=120)
    assert res.returncode == 0, res.stderr[-2000:]
    # mpirun interleaves the ranks' output (lines may run together): count each rank's message
    for rank in (0, 1):
        assert res.stdout.count(f"rank {rank}: rank 1 failed alone") == 1, res.stdout
