"""The MPI world of fem/ for the layers above, which do not import mpi4py themselves
(workflows/parallel.py uses it under ``mpirun``)."""
from __future__ import annotations

from mpi4py import MPI


def world() -> MPI.Comm:
    """MPI.COMM_WORLD: every process of the run (dolfinx meshes and PETSc matrices of
    fem.build_model and fem.petsc_solver live on it by default)."""
    return MPI.COMM_WORLD
