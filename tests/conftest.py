"""Test-session set-up shared by all test directories."""
import os
from pathlib import Path

import liftoff  # noqa: F401 - before numpy (pyvista loads it): it picks the OpenBLAS kernels (liftoff/core/openblas.py)

os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")
try:  # pyvista must be imported before dolfinx (FENICSX-NOTES.md: std::bad_alloc otherwise)
    import pyvista

    pyvista.OFF_SCREEN = True
except ImportError:  # pragma: no cover - pyvista is installed by `make test`
    pass


# The longest test files first (seconds, setup and calls summed, in `make test` of a clean
# clone on a 2-core AMD EPYC, 2026-12-08: 1,507 s over both workers, 777 s of wall time), so
# that `make test`'s two pytest-xdist workers (--dist loadfile --no-loadscope-reorder)
# start them at once and finish together: longest-processing-time-first scheduling. The
# order changes no result (every file's tests stay in their order, on one worker); a file
# missing here runs after these, in collection order. (The default figures' file, whose
# recomputation is `make check-figures`, 15 s here.)
LONGEST_FILES = {
    "workflows/test_run.py": 188, "workflows/test_examples_liftoff.py": 163, "workflows/test_campaign.py": 155,
    "workflows/test_mpi_run.py": 116, "workflows/test_hydro_run.py": 73, "cli/test_fuzz.py": 59,
    "fem/test_slosh.py": 52, "fem/test_beam_model.py": 46, "fem/test_mpi.py": 39,
    "fem/test_default_components.py": 38, "workflows/test_slosh_cli.py": 30, "workflows/test_beside.py": 29,
    "meshes/test_vehicle.py": 27, "cli/test_kill.py": 27, "workflows/test_atomic_outputs.py": 25,
    "fem/test_snapshot.py": 24, "fem/test_case_grain.py": 24, "fem/test_petsc_cb.py": 22,
    "workflows/test_truncation_run.py": 19, "fem/test_shell_core.py": 18, "workflows/test_default_figures.py": 15,
}


def pytest_collection_modifyitems(session, config, items):
    tests = Path(__file__).resolve().parent

    def weight(item):
        path = Path(item.path).resolve()
        return -LONGEST_FILES.get(path.relative_to(tests).as_posix(), 0) if path.is_relative_to(tests) else 0

    items.sort(key=weight)     # stable: the files' own order otherwise
