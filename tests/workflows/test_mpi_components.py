"""The pieces of the MPI runs' shared-out components (workflows/pipeline.reduce_over_ranks;
the whole under mpirun: tests/workflows/test_mpi_run.py): a rank's worker leaves the MPI
job, a component is claimed by one rank only, and the mode is checked."""
import pytest

from liftoff.core.errors import InputError
from liftoff.workflows import pipeline
from liftoff.workflows.cache import StageCache


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
