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


# The longest test files first (seconds, serial, on this 2-core machine, 2026-11-27; the
# default figures' file without its recomputation, marker "figures", 2026-11-28), so
# that `make test`'s two pytest-xdist workers (--dist loadfile --no-loadscope-reorder)
# start them at once and finish together: longest-processing-time-first scheduling. The
# order changes no result (every file's tests stay in their order, on one worker); a file
# missing here runs after these, in collection order.
LONGEST_FILES = {
    "workflows/test_default_figures.py": 20, "workflows/test_run.py": 125, "workflows/test_examples_liftoff.py": 115,
    "workflows/test_mpi_run.py": 105, "cli/test_fuzz.py": 95, "workflows/test_campaign.py": 90,
    "cli/test_attacks_round2.py": 80, "workflows/test_hydro_run.py": 72, "workflows/test_slosh_cli.py": 40,
    "fem/test_slosh.py": 35, "fem/test_beam_model.py": 35, "workflows/test_atomic_outputs.py": 30,
    "fem/test_default_components.py": 25, "workflows/test_beside.py": 22, "cli/test_kill.py": 22,
    "fem/test_case_grain.py": 20, "workflows/test_truncation_run.py": 19, "fem/test_mpi.py": 18,
}


def pytest_collection_modifyitems(session, config, items):
    tests = Path(__file__).resolve().parent

    def weight(item):
        path = Path(item.path).resolve()
        return -LONGEST_FILES.get(path.relative_to(tests).as_posix(), 0) if path.is_relative_to(tests) else 0

    items.sort(key=weight)     # stable: the files' own order otherwise
