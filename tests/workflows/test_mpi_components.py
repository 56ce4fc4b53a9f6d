"""The pieces of the MPI runs' shared-out components (workflows/pipeline.reduce_over_ranks;
the whole under mpirun: tests/workflows/test_mpi_run.py): a rank alone sees a serial
world, a component is claimed by one rank only, and the mode is checked."""
from pathlib import Path

import pytest

from liftoff.core.errors import InputError
from liftoff.workflows import parallel, pipeline
from liftoff.workflows.cache import StageCache


def test_alone_makes_the_world_serial_and_restores_it(monkeypatch):
    monkeypatch.setattr(parallel, "launched_size", lambda: 2)
    monkeypatch.setattr(parallel.sys, "modules", dict(parallel.sys.modules))
    sentinel = object()
    monkeypatch.setattr("liftoff.fem.parallel.world", lambda: sentinel)
    assert parallel.world() is sentinel
    with parallel.alone():
        assert parallel.world() is parallel.SERIAL
        with parallel.alone():
            assert parallel.world() is parallel.SERIAL
        assert parallel.world() is parallel.SERIAL
    assert parallel.world() is sentinel


def test_a_component_is_claimed_once(tmp_path):
    assert pipeline._claim(tmp_path, "run-core")
    assert not pipeline._claim(tmp_path, "run-core")
    assert pipeline._claim(tmp_path, "run-pad")


def test_the_mode_is_checked(monkeypatch, tmp_path):
    monkeypatch.setenv(pipeline.MPI_COMPONENTS_ENV, "sideways")
    with pytest.raises(InputError, match="LIFTOFF_MPI_COMPONENTS = 'sideways': give 'concurrent' or 'distributed'"):
        pipeline.reduce_over_ranks(None, [], StageCache(tmp_path), Path(tmp_path))
    monkeypatch.setenv(pipeline.MPI_COMPONENTS_ENV, "distributed")
    assert pipeline.reduce_over_ranks(None, [], StageCache(tmp_path), Path(tmp_path)) == {}
