"""The committed example body files are what their make_bodies.py writes from transient/examples.py.

Compared through basis-independent quantities (eigenvectors of repeated frequencies, e.g. the six
rigid-body modes, are any orthonormal basis of their subspace, which may differ between LAPACK
builds): labels, frequencies, Phi Phi^T at the labelled DOFs (= the DOF-space inverse mass for a
complete mode set, invariant under a rotation within a degenerate subspace), rigid-body mass."""
from __future__ import annotations

import runpy
from pathlib import Path

import numpy as np
import pytest

from liftoff.transient import load_body

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
NAMES = sorted(p.parent.name for p in EXAMPLES.glob("*/make_bodies.py"))


@pytest.mark.parametrize("name", NAMES)
def test_example_files_match_builders(name: str, tmp_path: Path):
    runpy.run_path(str(EXAMPLES / name / "make_bodies.py"), run_name="make_bodies")["main"](tmp_path)
    written = sorted(p.name for p in tmp_path.iterdir())
    assert written, "make_bodies.py wrote nothing"
    for fname in written:
        committed, fresh = EXAMPLES / name / fname, tmp_path / fname
        assert committed.is_file(), f"{name}/{fname} is written by make_bodies.py but not committed"
        if fname.endswith(".csv"):
            assert committed.read_text() == fresh.read_text(), fname
            continue
        a, b = load_body(committed), load_body(fresh)
        assert a.dof_labels == b.dof_labels
        # 1e-9: the same closed forms / the same eigh, up to LAPACK rounding
        np.testing.assert_allclose(a.omega, b.omega, rtol=1e-9, atol=1e-6 * max(b.omega.max(), 1.0))
        np.testing.assert_allclose(a.zeta, b.zeta, rtol=1e-12)      # written as given: no arithmetic
        pa, pb = a.phi @ a.phi.T, b.phi @ b.phi.T
        np.testing.assert_allclose(pa, pb, rtol=0, atol=1e-9 * np.abs(pb).max())
        np.testing.assert_allclose(a.rigid_body_mass, b.rigid_body_mass, rtol=1e-9,
                                   atol=1e-9 * np.abs(b.rigid_body_mass).max())
