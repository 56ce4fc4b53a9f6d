"""The MPI world of fem/ for the layers above, which do not import mpi4py themselves
(workflows/parallel.py uses it under ``mpirun``)."""
from __future__ import annotations

from mpi4py import MPI


def world() -> MPI.Comm:
    """MPI.COMM_WORLD: every process of the run (dolfinx meshes and PETSc matrices of
    fem.build_model and fem.petsc_solver live on it by default)."""
    return MPI.COMM_WORLD


def fe_comm(run_comm) -> MPI.Comm:
    """The communicator of the FE stages of a run whose processes are ``run_comm``
    (workflows/parallel.py): itself under ``mpirun -n N``, else MPI.COMM_SELF, so that a
    serial run started inside a larger MPI world (``mpi4py.futures``, whose other ranks
    serve a case pool) never waits on them."""
    return run_comm if getattr(run_comm, "size", 1) > 1 else MPI.COMM_SELF
