"""The modes kept (reduction/truncation.py): residual vectors make the static flexibility at
the loaded DOFs exact, the truncation check sees a cut, and the held effective mass is what
the physical model gives. References: the monolithic frame's own static solve (numpy, no CB),
held statically determinately and projected to the mean axes (inertia relief), and the
physical eigenproblem of the assembly held at its contact DOFs."""
import numpy as np
import pytest
import scipy.linalg as sla

from liftoff.core.rigid import rb_rows
from liftoff.reduction import (assemble, craig_bampton, keep_modes, label_transform, residual_vectors,
                               system_modes, truncation_check)
from liftoff.reduction.models import chain_component, six_labels
from liftoff.reduction.modal_mass import held_effective_mass, held_modes, modal_mass_table
from liftoff.reduction.truncation import StaticFlexibility, load_vectors

from ..roundoff import solve_rtol
from .test_assembly import N_SEG, SECTION, bent_frame_nodes, pad_component

BOUNDARY = ("n0", f"n{N_SEG}", f"n{2 * N_SEG}")


@pytest.fixture(scope="module")
def frame():
    """The bent frame as two CB components with every fixed-interface mode (so the CB
    assembly is the monolithic frame in another basis), its whole eigensolution, and the
    monolithic frame itself."""
    nodes = bent_frame_nodes()
    A = chain_component("A", nodes[: N_SEG + 1], 0, **SECTION)
    B = chain_component("B", nodes[N_SEG:], N_SEG, **SECTION)
    full = chain_component("full", nodes, 0, **SECTION)
    asm = assemble([craig_bampton(A, six_labels("n0") + six_labels(f"n{N_SEG}"), n_modes=A.n_dof),
                    craig_bampton(B, six_labels(f"n{N_SEG}") + six_labels(f"n{2 * N_SEG}"), n_modes=B.n_dof)],
                   "frame")
    return asm, system_modes(asm), full


def monolithic_flexibility(full, labels) -> tuple[np.ndarray, float]:
    """Mean-axis (inertia-relief) static flexibility of the free monolithic frame at
    ``labels``: held at n0 (statically determinate), G = P^T K_ff^-1 P with the projector
    P = I - M R (R^T M R)^-1 R^T that balances a load by rigid-body inertia, then the
    rigid-body motion removed, (I - R (R^T M R)^-1 R^T M). Returns G and cond(K_ff)."""
    K, M = full.K.toarray(), full.M.toarray()
    R = np.zeros((full.n_dof, 6))
    R[full.label_dofs] = rb_rows(full.dof_labels, full.points, full.point_coords, np.zeros(3))
    held = full.dofs_of(six_labels("n0"))
    free = np.setdiff1d(np.arange(full.n_dof), held)
    Kff = K[np.ix_(free, free)]
    mr = R.T @ M @ R
    P = np.eye(full.n_dof) - M @ R @ np.linalg.solve(mr, R.T)
    L = np.zeros((len(labels), full.n_dof))
    L[np.arange(len(labels)), full.dofs_of(labels)] = 1.0
    F = P @ L.T
    X = np.zeros_like(F)
    X[free] = np.linalg.solve(Kff, F[free])
    X = X - R @ np.linalg.solve(mr, R.T @ M @ X)
    return L @ X, float(np.linalg.cond(Kff))


def kept_flexibility(modes, labels) -> np.ndarray:
    rows = label_transform(modes.assembly, labels) @ modes.phi
    el = modes.omega > 0
    return (rows[:, el] / modes.omega[el] ** 2) @ rows[:, el].T


def test_residual_vectors_restore_the_free_frames_static_flexibility(frame):
    asm, full_modes, full = frame
    labels = [lab for p in BOUNDARY for lab in six_labels(p)]
    G, cond = monolithic_flexibility(full, labels)
    # the whole CB space is the frame: its modes give the monolithic flexibility (round-off of
    # the solves, cond ~ 1e7 here, and of the eigensolution)
    tol = solve_rtol(cond, full.n_dof)
    assert np.abs(kept_flexibility(full_modes, labels) - G).max() <= tol * np.abs(G).max()
    for f_max in (5.0, 50.0):
        cut = keep_modes(full_modes, f_max=f_max, residual=False)
        rv = keep_modes(full_modes, f_max=f_max)
        assert cut.n_residual == 0 and 0 < rv.n_residual <= len(labels)
        miss = np.abs(kept_flexibility(cut, labels) - G).max() / np.abs(G).max()
        err = np.abs(kept_flexibility(rv, labels) - G).max() / np.abs(G).max()
        print(f"frame cut at {f_max} Hz: {cut.n_modes} modes miss {miss:.1e} of the flexibility; "
              f"+ {rv.n_residual} residual vectors: {err:.1e} (bound {tol:.1e})")
        assert miss > 1e-3          # the cut is visible
        assert err <= tol           # and the residual vectors restore it to round-off
        # M-orthonormal, K-diagonal, and the kept modes untouched
        Mq = rv.phi.T @ asm.M @ rv.phi
        Kq = rv.phi.T @ asm.K @ rv.phi
        assert np.abs(Mq - np.eye(rv.n_modes)).max() < 1e-8
        assert np.abs(Kq - np.diag(rv.omega ** 2)).max() < 1e-8 * rv.omega.max() ** 2
        assert np.array_equal(rv.phi[:, : cut.n_modes], cut.phi)
        assert rv.omega[cut.n_modes:].min() > 2 * np.pi * f_max   # Rayleigh quotients above the cut


def test_residual_vectors_of_a_grounded_body_are_its_exact_statics():
    pad, posts = pad_component()
    asm = assemble([craig_bampton(pad, posts, n_modes=pad.n_dof)], "pad")
    full_modes = system_modes(asm, n_rigid=0)
    K = pad.K.toarray()
    L = np.zeros((len(posts), pad.n_dof))
    L[np.arange(len(posts)), pad.dofs_of(posts)] = 1.0
    G = L @ np.linalg.solve(K, L.T)                     # the pad's own static solve, no CB
    tol = solve_rtol(np.linalg.cond(K), pad.n_dof)
    rv = keep_modes(full_modes, n_modes=3)
    cut = keep_modes(full_modes, n_modes=3, residual=False)
    rows = label_transform(asm, posts)
    flex = lambda m: (rows @ m.phi / m.omega ** 2) @ (rows @ m.phi).T  # noqa: E731
    assert np.abs(flex(rv) - G).max() <= tol * np.abs(G).max()
    assert np.abs(flex(cut) - G).max() > 1e-2 * np.abs(G).max()
    # gravity (M RB) is one of the loads: its static response is exact too
    g = asm.M @ full_modes.rb_shape()[:, 2]
    exact = np.linalg.solve(asm.K, g)
    assert np.abs(rv.phi @ ((rv.phi.T @ g) / rv.omega ** 2) - exact).max() <= tol * np.abs(exact).max()


def test_truncation_check_sees_the_cut(frame):
    asm, full_modes, _ = frame
    labels = six_labels(f"n{N_SEG}")
    contact = [f"n0:{c}" for c in ("Tx", "Ty", "Tz")] + [f"n{2 * N_SEG}:{c}" for c in ("Tx", "Ty", "Tz")]
    whole = truncation_check(full_modes, full_modes, labels + contact, contact, "frame")
    assert whole.ok and whole.f_cut is None and whole.flex_error < 1e-8 and whole.mass_kept == (1.0, 1.0, 1.0)
    n = 6 + 12                      # the rigid-body modes and the first 12 elastic ones
    cut = truncation_check(full_modes, keep_modes(full_modes, n_modes=n, residual=False), labels + contact,
                           contact, "frame")
    assert not cut.ok and cut.flex_error > 0.01 and "frame" in cut.warning() and "residual vectors" in cut.warning()
    assert cut.f_cut == pytest.approx(full_modes.freq_hz[n - 1]) and cut.n_residual == 0 and cut.n_kept == n
    rv = truncation_check(full_modes, keep_modes(full_modes, n_modes=n), labels + contact, contact, "frame")
    print("cut:", cut.line(), "\nwith residual vectors:", rv.line())
    # residual vectors restore the static flexibility (static_error ~ 0), but the check counts
    # the eigenmodes only: the cut is the same cut, and still not converged (a review: counting
    # them passed cuts whose loads were 6.6 % off)
    assert rv.static_error < 1e-8 and rv.n_residual > 0
    assert rv.flex_error == cut.flex_error and rv.mass_kept == cut.mass_kept and not rv.ok
    d = rv.as_dict()
    assert d["n_residual"] == rv.n_residual and d["f_cut_hz"] == rv.f_cut and d["ok"] == rv.ok
    assert d["flexibility_shortfall_with_residual_vectors"] == rv.static_error
    assert "residual vectors" in rv.line() and "with the residual vectors" in rv.line()


def test_held_effective_mass_equals_the_physical_held_model(frame):
    """The modal formula against the physical one: the assembly held at the contact DOFs
    (rows and columns removed), base motion = rigid translation (the contact points fix
    the frame's rigid-body motion), effective mass = sum over its modes of (psi^T M RB)^2."""
    asm, full_modes, _ = frame
    contact = [f"{p}:{c}" for p in BOUNDARY for c in ("Tx", "Ty", "Tz")]   # three points: no mechanism
    rb = full_modes.rb_shape()[:, :3]
    held = np.array([asm.boundary_dof(lab) for lab in contact])
    free = np.setdiff1d(np.arange(asm.n_dof), held)
    K, M = asm.K[np.ix_(free, free)], asm.M[np.ix_(free, free)]
    lam, psi = sla.eigh(K, M)
    Lp = psi.T @ (asm.M @ rb)[free]
    physical = np.einsum("ij,ij->j", Lp, Lp)
    u = rb_rows(contact, asm.points, asm.point_coords, np.zeros(3))[:, :3]
    modal = held_effective_mass(full_modes.omega, label_transform(asm, contact) @ full_modes.phi, u)
    np.testing.assert_allclose(modal, physical, rtol=1e-8)
    total = np.diag(rb.T @ asm.M @ rb)
    assert np.all(modal < total)        # the rest is on the held DOFs
    cut = keep_modes(full_modes, f_max=20.0, residual=False)
    part = held_effective_mass(cut.omega, label_transform(asm, contact) @ cut.phi, u)
    assert np.all(part <= modal * (1 + 1e-9)) and np.any(part < 0.99 * modal)


def test_modal_mass_table_equals_the_physical_held_and_grounded_models(frame):
    """Per mode: the held model built in modal coordinates (reduction/modal_mass.py) has the
    physical held assembly's frequencies and effective masses (its eigenproblem with the held
    rows and columns removed); they sum to the total mass less what sits on the held DOFs.
    The bent frame held at one end (a grounded body): the table is (phi^T M r)^2 and its sum
    over the whole space is r^T M r less the held point's own mass."""
    asm, full_modes, _ = frame
    contact = [f"{p}:{c}" for p in BOUNDARY for c in ("Tx", "Ty", "Tz")]
    rb = full_modes.rb_shape()[:, :3]
    held = np.array([asm.boundary_dof(lab) for lab in contact])
    free = np.setdiff1d(np.arange(asm.n_dof), held)
    lam, psi = sla.eigh(asm.K[np.ix_(free, free)], asm.M[np.ix_(free, free)])
    Lp = psi.T @ (asm.M @ rb)[free]
    table = modal_mass_table(full_modes, contact, "frame")
    assert table.condition == "held at its contact DOFs" and table.freq_hz.size == lam.size
    # eigenvalues of the same matrix pencil in two bases: round-off of the CB basis (cond ~1e8 at most here)
    np.testing.assert_allclose(table.freq_hz, np.sqrt(lam) / (2 * np.pi), rtol=1e-7)
    # per mode (distinct frequencies on this frame): the same participations, squared
    gaps = np.diff(lam) / lam[1:]
    assert gaps.min() > 1e-6
    scale = np.diag(rb.T @ asm.M @ rb)
    np.testing.assert_allclose(table.effective_mass, Lp ** 2, rtol=1e-6, atol=1e-9 * scale.max())
    np.testing.assert_allclose(table.total_mass, scale, rtol=1e-9)
    np.testing.assert_allclose(table.effective_mass.sum(axis=0) + table.on_supports, table.total_mass, rtol=1e-12)
    rows = table.rows()
    assert rows[-1]["cum_pct_x"] == pytest.approx(100 * table.effective_mass[:, 0].sum() / scale[0])
    # held_effective_mass (the truncation check's figure) is the table's sum
    u = rb_rows(contact, asm.points, asm.point_coords, np.zeros(3))[:, :3]
    np.testing.assert_allclose(held_modes(full_modes.omega, label_transform(asm, contact) @ full_modes.phi, u)[1]
                               .sum(axis=0), table.effective_mass.sum(axis=0), rtol=1e-10)


def test_modal_mass_table_of_a_grounded_body():
    """A grounded frame (tests/reduction/test_assembly.pad_component, clamped DOFs removed):
    effective masses are (phi^T M r)^2 of the CB system's modes and, over the whole space,
    sum to the mass that moves (r^T M r of the free DOFs: Phi Phi^T = M^-1)."""
    pad, posts = pad_component()
    modes = system_modes(assemble([craig_bampton(pad, posts, n_modes=pad.n_dof)], "pad"), n_rigid=0)
    table = modal_mass_table(modes, [], "grounded")
    assert table.condition == "grounded"
    rb = np.asarray(table.total_mass)
    np.testing.assert_allclose(table.effective_mass.sum(axis=0) + table.on_supports, rb, rtol=1e-12)
    # every mode of the whole space: the moving mass is all carried (the ground DOFs are not in the CB space)
    np.testing.assert_allclose(table.on_supports, 0.0, atol=1e-8 * rb.max())


def test_residual_vectors_skip_what_the_kept_modes_carry(frame):
    """All modes kept: no residual direction is left (round-off is not a vector)."""
    _, full_modes, _ = frame
    w, phi = residual_vectors(full_modes, full_modes.omega, full_modes.phi, load_vectors(full_modes),
                              StaticFlexibility(full_modes))
    assert w.size == 0 and phi.shape == (full_modes.assembly.n_dof, 0)


def test_n_modes_beyond_the_memory_is_refused_before_any_solve(monkeypatch):
    """Issue 27: n_modes = 1e9 reached 13 GB and a PETSc error. n_modes beyond the interior
    DOFs means all of them; dense modes beyond the memory available are refused in one
    line before the eigensolve (here with the memory made small)."""
    import scipy.sparse as sp

    import importlib

    from liftoff.core.errors import ResourceError
    from liftoff.reduction import Component, craig_bampton

    cbm = importlib.import_module("liftoff.reduction.craig_bampton")

    n = 12
    K = sp.diags([2.0] * n) - sp.diags([1.0] * (n - 1), 1) - sp.diags([1.0] * (n - 1), -1)
    labels = tuple(f"p{k}:Tx" for k in range(n))
    comp = Component(name="bar", K=sp.csr_matrix(K), M=sp.identity(n, format="csr"), dof_labels=labels,
                     label_dofs=np.arange(n), points=tuple(f"p{k}" for k in range(n)), point_coords=np.zeros((n, 3)))
    assert craig_bampton(comp, ["p0:Tx"], n_modes=10 ** 9).n_modes == 11       # all of them
    monkeypatch.setattr(cbm, "available_memory", lambda: 1000.0)
    with pytest.raises(ResourceError, match=r"component 'bar': 11 fixed-interface modes of 12 DOFs need about"):
        craig_bampton(comp, ["p0:Tx"], n_modes=10 ** 9)


def test_held_solve_takes_least_squares_where_the_held_dofs_leave_a_motion_free():
    """The held stiffness A is solved by Cholesky when positive definite (the same solution as
    the least-squares one, to round-off of cond(A) ~ 1e8), and by least squares (the
    minimum-norm solution, the free motion left unstrained) when a motion is left free:
    exactly (a zero pivot) or at round-off (1e-9 against 3e8, a pivot below HELD_PIVOT),
    where Cholesky would return a solution scaled by 1e9."""
    from liftoff.reduction.modal_mass import _solve_held

    rng = np.random.default_rng(7)
    V = np.linalg.qr(rng.standard_normal((5, 5)))[0]
    b = rng.standard_normal((5, 3))
    for lam in ([3e8, 4e3, 50.0, 5.0, 2.0], [3e8, 4e3, 50.0, 5.0, 0.0], [3e8, 4e3, 50.0, 5.0, 1e-9]):
        A = (V * np.array(lam)) @ V.T
        A = 0.5 * (A + A.T)
        ref = np.linalg.lstsq(A, b, rcond=None)[0]
        np.testing.assert_allclose(_solve_held(A, b), ref, rtol=1e-6, atol=1e-9 * np.abs(ref).max())
    # a free motion uncoupled from the rest (its pivot equals its own diagonal entry, 1e-20):
    # judged against the largest diagonal entry, not its own; Cholesky would give 3e12 there
    A = np.diag([3e8, 4e3, 1e-20])
    ref = np.linalg.lstsq(A, np.array([1.0, 1.0, 3e-8]), rcond=None)[0]
    assert ref[2] == 0.0
    np.testing.assert_allclose(_solve_held(A, np.array([1.0, 1.0, 3e-8])), ref, rtol=1e-12, atol=0)
