"""Body files that cannot be right are refused (issue 27): a transposed square phi, a
negated rigid-body mass, units other than SI. Files and models that are right pass."""
from __future__ import annotations

import tomllib
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from liftoff.core.errors import InputError
from liftoff.transient.body import consistency_problems, load_body, save_body
from liftoff.core.records import read_record, write_record

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def _vehicle():
    return load_body(EXAMPLES / "vehicle_on_pad" / "vehicle.npz")


def test_the_examples_bodies_are_consistent():
    for f in sorted(EXAMPLES.glob("*/*.npz")):
        if f.name not in ("thrust.npz",):
            assert consistency_problems(load_body(f)) == [], f


def test_transposed_square_phi_is_refused(tmp_path):
    v = _vehicle()
    assert v.phi.shape[0] == v.phi.shape[1]          # square: the shape check cannot see it
    bad = replace(v, phi=v.phi.T.copy())
    with pytest.raises(InputError, match=r"not rigid motions .*not transposed"):
        load_body(save_body(bad, tmp_path / "t.npz"))


def test_negated_rigid_body_mass_is_refused(tmp_path):
    bad = replace(_vehicle(), rigid_body_mass=-_vehicle().rigid_body_mass)
    with pytest.raises(InputError, match="not positive semidefinite"):
        load_body(save_body(bad, tmp_path / "m.npz"))
    other = replace(_vehicle(), rigid_body_mass=2.0 * _vehicle().rigid_body_mass)   # another body's mass
    with pytest.raises(InputError, match="unit modal masses"):
        load_body(save_body(other, tmp_path / "m2.npz"))


@pytest.mark.parametrize("units", ["mm-kg-s", "in-lbf-s"])
def test_non_si_units_are_refused(tmp_path, units):
    src = EXAMPLES / "vehicle_on_pad" / "vehicle.npz"
    rec = read_record(src, "liftoff-modal-body")
    path = write_record(tmp_path / "u.npz", "liftoff-modal-body", 1, rec.data, units=units,
                        attrs={"name": "vehicle"})
    with pytest.raises(InputError, match=f"units '{units}', but a body file holds SI"):
        load_body(path)


def test_the_pipelines_own_bodies_are_consistent():
    """The stick stack's vehicle (free, six rigid modes) and pad: the checks hold on the
    bodies liftoff itself builds (a user may save and reload them)."""
    from liftoff.config import default_text, parse_scenario
    from liftoff.workflows.cache import StageCache
    from liftoff.workflows.pipeline import build_stack

    d = tomllib.loads(default_text())
    d["model"] = {"source": "stick", "mesh_size": 6.0, "zeta": 0.01}
    stack = build_stack(parse_scenario(d, "s").cases[0].model, StageCache(None), progress=False)
    for body in (stack.vehicle, stack.pad):
        assert consistency_problems(body) == [], body.name
    assert int(np.sum(stack.vehicle.omega < 0.1)) == 6


def test_declared_sizes_are_checked_before_reading(tmp_path):
    """A few-kB file that declares gigabytes is refused from its headers, before anything
    is allocated (issue 27: 11.8 GB before the shape error): an .npz whose compressed phi
    claims 29 GB, an HDF5 dataset never written, a phi of the wrong declared shape."""
    import resource
    import zipfile

    import h5py

    from liftoff.core.errors import ResourceError

    npz = tmp_path / "big.npz"
    with zipfile.ZipFile(npz, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        for name, shape in (("omega", (60000,)), ("dof_labels", (60000,)), ("phi", (60000, 60000))):
            with zf.open(f"{name}.npy", "w", force_zip64=True) as fh:
                np.lib.format.write_array_header_1_0(fh, {"descr": "<f8", "fortran_order": False, "shape": shape})
    h5 = tmp_path / "big.h5"
    with h5py.File(h5, "w") as f:
        f.create_dataset("phi", shape=(25_000_000, 27), dtype="f8")    # 5.4 GB declared, never written
        f.create_dataset("omega", data=np.arange(27.0))
        f.create_dataset("dof_labels", data=np.array(["a:Tx"] * 3, dtype="S"))
        f.attrs["format"] = "liftoff-modal-body"
    rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    with pytest.raises(ResourceError, match=r"big\.npz': its arrays declare .* GB \('phi' alone"):
        load_body(npz)
    with pytest.raises(InputError, match=r"phi has shape \(25000000, 27\), expected \(3, 27\)"):
        load_body(h5)
    assert resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - rss0 < 500_000     # kB: nothing big was read


@pytest.mark.parametrize("edit, match", [
    (lambda b: replace(b, phi=np.zeros_like(b.phi)), "phi is all zero"),
    (lambda b: replace(b, omega=np.zeros_like(b.omega)), "27 modes below 0.1 rad/s: a body has at most six"),
])
def test_zero_phi_or_omega_named_with_the_file(tmp_path, edit, match):
    """Issue 27: these gave "static equilibrium singular" without naming the body file."""
    with pytest.raises(InputError, match=rf"body file .*z\.npz': {match}"):
        load_body(save_body(edit(_vehicle()), tmp_path / "z.npz"))
