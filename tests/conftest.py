"""Test-session set-up shared by all test directories."""
import os

os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")
try:  # pyvista must be imported before dolfinx (FENICSX-NOTES.md: std::bad_alloc otherwise)
    import pyvista

    pyvista.OFF_SCREEN = True
except ImportError:  # pragma: no cover - pyvista is installed by `make test`
    pass
