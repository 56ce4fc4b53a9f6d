"""The form compiler's build log stays off the terminal (issue 27: the first FE run printed
~90 lines of ``INFO:root:`` gcc command lines); its warnings would still show."""
from __future__ import annotations

import os
import subprocess
import sys

import pytest

pytest.importorskip("dolfinx")

SCRIPT = """
import pyvista
import logging
import liftoff.fem.model  # noqa: F401  (quiets ffcx's root handler)
from mpi4py import MPI
import dolfinx, ufl
mesh = dolfinx.mesh.create_unit_interval(MPI.COMM_SELF, 2)
V = dolfinx.fem.FunctionSpace(mesh, ("CG", 3))
u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
dolfinx.fem.form(0.123456 * ufl.inner(u.dx(0), v.dx(0)) * ufl.dx)   # compiled in a fresh cache
logging.warning("a warning still shows")
"""


def test_first_compile_prints_no_build_log(tmp_path):
    env = dict(os.environ, XDG_CACHE_HOME=str(tmp_path), PYVISTA_OFF_SCREEN="true")
    r = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True, env=env, timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]
    assert any(tmp_path.rglob("*.so")), "nothing was compiled: the test did not test the first compile"
    out = r.stdout + r.stderr
    assert "INFO" not in out and "gcc" not in out, out[:2000]
    assert "a warning still shows" in r.stderr
