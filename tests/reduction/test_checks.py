"""cb_check against pyyeti's cbcheck (an independent implementation) and the full FE model."""
import io
import json

import numpy as np
import pytest

from liftoff.reduction import Component, cb_check, craig_bampton
from liftoff.reduction.models import chain_component, six_labels

from ..roundoff import sum_rtol

SECTION = dict(E=70e9, nu=0.33, A=4e-4, Iy=6e-8, Iz=1.1e-7, J=1.2e-7, rho=2700.0)
N = 16


@pytest.fixture(scope="module")
def frame():
    a = np.linspace(0, 1.2, N + 1)
    b = np.linspace(0, 0.8, N + 1)[1:]
    nodes = np.vstack([np.c_[a, 0 * a, 0 * a], np.c_[1.2 + 0 * b, 0.3 * b, b]])
    comp = chain_component("frame", nodes, 0, **SECTION)
    return comp, craig_bampton(comp, six_labels("n0") + six_labels(f"n{2 * N}"), n_modes=8)


def test_against_pyyeti_cbcheck(frame):
    pcb = pytest.importorskip("pyyeti.cb")
    n2p = pytest.importorskip("pyyeti.nastran.n2p")
    comp, cb = frame
    nq = cb.n_modes
    uset = n2p.addgrid(None, [1, 2], "b", 0, [cb.point_coord("n0"), cb.point_coord("n32")], 0)
    with pytest.warns(RuntimeWarning):      # pyyeti's own eigsh call on this small model
        ref = pcb.cbcheck(io.StringIO(), cb.M, cb.K, np.arange(nq, nq + 12), np.arange(nq, nq + 6), uset,
                          uref=[0.0, 0.0, 0.0])
    s = cb_check(cb, comp, ref_point=[0.0, 0.0, 0.0]).summary
    # same arithmetic on the same matrices: agreement to round-off (the frequencies are square
    # roots of the diagonal of K_qq: a few roundings; 1e-12 = 4500 eps)
    assert np.allclose(s["fixed_interface_freq_hz"], ref.cb_frq, rtol=1e-12)
    assert np.allclose(s["effective_mass_percent"], ref.effmass_percent.values, atol=1e-9)
    rbg = ref.rbg[:12]
    m6 = rbg.T @ ref.m[:12, :12] @ rbg
    # RB^T M RB over the 12 boundary DOFs (and the q rows): sums of n = M.shape[0] products
    assert np.allclose(s["rigid_body_mass"], m6, rtol=0, atol=sum_rtol(cb.M.shape[0]) * np.abs(m6).max())


def test_summary_against_full_fe(frame):
    comp, cb = frame
    chk = cb_check(cb, comp)
    s = chk.summary
    json.dumps(s)                                  # machine-readable
    assert s["rb_ok"] and s["M_positive_definite"] and s["K_positive_semidefinite"]
    assert s["K_B_n_zero_eig"] == 6                # free-free component: six rigid motions
    assert s["fe_rb_source"] == "geometry"
    # mass from geometry: rho A L for 1.2 m + sqrt(0.8^2 + 0.24^2) m of tube. M_B is built
    # from the constraint modes Psi = -K_ii^-1 K_ib, whose relative rounding error is
    # bounded by eps * cond(K_ii) (3.6e6 here: 8e-10); a fresh machine measured 1.7e-12.
    i = np.setdiff1d(np.arange(comp.n_dof), comp.dofs_of(cb.boundary_labels))
    tol = np.finfo(float).eps * np.linalg.cond(comp.K[i][:, i].toarray())
    L = 1.2 + np.hypot(0.8, 0.24)
    assert s["mass_properties_cb"]["mass"] == pytest.approx(2700 * 4e-4 * L, rel=tol)
    assert s["rigid_body_mass_rel_error"] < tol
    err = [e for e in s["freefree_rel_error"] if e is not None]
    assert len(err) == 6 and min(err) > -1e-9        # Rayleigh-Ritz: CB from above
    assert "modal effective mass" in chk.text and "free-free" in chk.text


def test_flags_a_grounded_component_and_asymmetry(frame):
    comp, _ = frame
    K = comp.K.tolil()
    d = comp.dofs_of(["n8:Ty"])[0]
    K[d, d] += 1e4                                 # a spring to ground in the middle
    grounded = Component("grounded", K.tocsr(), comp.M, comp.dof_labels, comp.label_dofs, comp.points,
                         comp.point_coords)
    cb = craig_bampton(grounded, six_labels("n0") + six_labels(f"n{2 * N}"), n_modes=4)
    s = cb_check(cb).summary
    assert not s["rb_ok"] and max(s["rb_residual"]) > 1e-4
    assert "FAIL" in cb_check(cb).text
    cb.K[0, -1] += 1.0
    assert cb_check(cb).summary["K_asymmetry"] > 0


def test_sparse_fe_eigensolve_matches_dense(frame, monkeypatch):
    import liftoff.reduction.checks as checks

    comp, cb = frame
    dense = cb_check(cb, comp).summary
    monkeypatch.setattr(checks, "DENSE_FE_LIMIT", 0)      # eigsh with a small negative shift
    sparse = cb_check(cb, comp).summary
    # converged ARPACK eigenvalues: 1e-8 relative on the elastic frequencies
    assert np.allclose(sparse["freefree_freq_hz_fe"][6:], dense["freefree_freq_hz_fe"][6:], rtol=1e-8)
    assert np.all(np.array(sparse["freefree_freq_hz_fe"][:6]) < 1e-3 * sparse["freefree_freq_hz_fe"][6])
