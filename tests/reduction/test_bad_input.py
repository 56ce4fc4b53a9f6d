"""Bad input gets a one-line InputError naming the culprit."""
import numpy as np
import pytest
import scipy.sparse as sp

from liftoff.reduction import Component, assemble, craig_bampton, load_cb, system_modes
from liftoff.reduction.models import chain_component, six_labels
from liftoff.transient import InputError

SECTION = dict(E=70e9, nu=0.33, A=4e-4, Iy=6e-8, Iz=1.1e-7, J=1.2e-7, rho=2700.0)


def beam(name="beam", x0=0.0, first=0, n=8, scale=1.0):
    x = (x0 + np.linspace(0, 1.0, n + 1)) * scale
    return chain_component(name, np.c_[x, 0 * x, 0 * x], first, **SECTION)


def one_line(exc):
    msg = str(exc.value)
    assert "\n" not in msg
    return msg


def test_unknown_boundary_label():
    with pytest.raises(InputError, match="'n99:Tx'") as e:
        craig_bampton(beam(), ["n0:Tx", "n99:Tx"], n_modes=3)
    assert "beam" in one_line(e)
    with pytest.raises(InputError, match="malformed"):
        craig_bampton(beam(), ["n0-Tx"], n_modes=3)
    with pytest.raises(InputError, match="twice"):
        craig_bampton(beam(), ["n0:Tx", "n0:Tx"], n_modes=3)
    with pytest.raises(InputError, match="n_modes or f_max"):
        craig_bampton(beam(), six_labels("n0"))


def test_component_that_floats_after_its_boundary_is_fixed():
    # only the three translations of one end: the beam can still spin about that point
    with pytest.raises(InputError, match="floats") as e:
        craig_bampton(beam(), ["n0:Tx", "n0:Ty", "n0:Tz"], n_modes=3)
    assert "'beam'" in one_line(e)
    # two beams in one component, only one held: the other floats
    b1, b2 = beam("a"), beam("b", x0=2.0, first=9)
    both = Component("two", sp.block_diag([b1.K, b2.K]), sp.block_diag([b1.M, b2.M]),
                     b1.dof_labels + b2.dof_labels, np.r_[b1.label_dofs, b2.label_dofs + b1.n_dof],
                     b1.points + b2.points, np.vstack([b1.point_coords, b2.point_coords]))
    with pytest.raises(InputError, match="floats"):
        craig_bampton(both, six_labels("n0"), f_max=1000.0)


def test_mismatched_units_in_assembly():
    a = craig_bampton(beam("A", first=0), six_labels("n8"), n_modes=2)
    b_mm = craig_bampton(beam("B", x0=1.0, first=8, scale=1000.0), six_labels("n8"), n_modes=2)  # mm
    with pytest.raises(InputError, match="'n8'.*mismatched units") as e:
        assemble([a, b_mm], "vehicle")
    assert "'A'" in one_line(e) and "'B'" in one_line(e)


def test_label_boundary_in_one_component_interior_in_another():
    a = craig_bampton(beam("A", first=0), six_labels("n8"), n_modes=2)
    b = craig_bampton(beam("B", x0=1.0, first=8), six_labels("n16"), n_modes=2)   # n8 interior in B
    with pytest.raises(InputError, match="interior DOF of 'B'"):
        assemble([a, b], "vehicle")
    with pytest.raises(InputError, match="used twice"):
        assemble([a, a], "vehicle")


def test_system_modes_bad_requests():
    a = craig_bampton(beam("A"), ["n0:Tx", "n0:Ty", "n0:Tz", "n0:Rx", "n0:Ry", "n0:Rz"], n_modes=2)
    with pytest.raises(InputError, match="n_rigid"):
        system_modes(assemble([a], "x"), n_rigid=3)
    with pytest.raises(InputError, match="zero-frequency mode in a grounded model"):
        system_modes(assemble([a], "x"), n_rigid=0)


def test_bad_files(tmp_path):
    p = tmp_path / "not_cb.npz"
    np.savez(p, format=np.array("something-else"))
    with pytest.raises(InputError, match="format is 'something-else', expected 'liftoff-cb-model'"):
        load_cb(p)
    with pytest.raises(InputError, match="not found"):
        load_cb(tmp_path / "missing.npz")
    cb = craig_bampton(beam(), six_labels("n0"), n_modes=2)
    with pytest.raises(InputError, match=".npz"):
        cb.save(tmp_path / "cb.h5")
    with pytest.raises(InputError, match="rows"):
        cb.boundary_load(np.zeros(5))


def test_a_component_file_with_nan_values(tmp_path):
    """A component file read as a user's file is scanned for NaN/inf in K and M; read as a
    stage-cache file (``mmap``: validated when built, its bytes checksummed since, the scan
    skipped so that a process that never uses K and M never reads them) they are not."""
    from liftoff.reduction.component import load_component, save_component

    comp = beam()
    path = save_component(comp, tmp_path / "beam.npz")
    # the same file with one stiffness value replaced by NaN (the reader's own layout, no pickle)
    bad = Component(comp.name, comp.K.copy(), comp.M, comp.dof_labels, comp.label_dofs, comp.points,
                    comp.point_coords, values_checked=True)
    bad.K.data[3] = np.nan
    bad_path = save_component(bad, tmp_path / "bad.npz")
    with pytest.raises(InputError, match="component 'beam': K contains NaN or inf") as e:
        load_component(bad_path)
    one_line(e)
    mapped = load_component(bad_path, mmap=True)
    assert np.isnan(mapped.K.data[3]) and mapped.values_checked
    good = load_component(path, mmap=True)
    np.testing.assert_array_equal(good.K.toarray(), comp.K.toarray())
