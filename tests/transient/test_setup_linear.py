"""The transient's set-up, linear in the number of modes: the interface-reduced static
solve against a dense solve of the full coupled system, the step estimate's Lanczos path
against the dense constrained eigenproblem, factored feedback, keep_modal = "q"."""
import numpy as np
import pytest

from liftoff.core.errors import InputError
from liftoff.transient import (ContactPoint, Forcing, ModalBody, ModalFeedback, PointForce, TransientProblem,
                               estimate_step, load_result, solve, static_solution)
from liftoff.transient.assembly import contact_rows
from liftoff.transient.examples import holddown_contacts, toy_pad, truss_body, vehicle_truss


def _big_body(n: int, n_rigid: int = 6, seed: int = 0) -> ModalBody:
    """A synthetic free body: n modes (the first n_rigid rigid), random mode-shape rows at
    4 points x 3 translations (the posts) plus a 'top' point."""
    rng = np.random.default_rng(seed)
    omega = np.concatenate([np.zeros(n_rigid), 2 * np.pi * np.geomspace(1.0, 300.0, n - n_rigid)])
    names = [f"post_{i + 1}" for i in range(4)] + ["top"]
    labels = [f"{p}:{c}" for p in names for c in ("Tz", "Tx", "Ty")]
    phi = rng.standard_normal((len(labels), n)) * 1e-3 / np.sqrt(1 + np.arange(n) / 50)
    return ModalBody(name="big", omega=omega, zeta=np.where(omega > 0, 0.02, 0.0), dof_labels=labels, phi=phi,
                     participation=np.zeros((n, 6)), points=tuple(names),
                     point_coords=rng.standard_normal((len(names), 3)))


def _dense_static(a, b, contacts, forcing, fb):
    """Reference: K q = P with K = diag(omega^2) - F + D_p^T K_C D_p and the rigid rows as
    Lagrange constraints, all n x n, numpy.linalg.solve (independent of solver.py)."""
    rows = contact_rows(a, b, contacts)
    n, na = a.n_modes + b.n_modes, a.n_modes
    D = np.hstack([rows.Phi_a, -rows.Phi_b])
    pen = rows.compliance > 0
    K = np.diag(np.concatenate([a.omega, b.omega]) ** 2)
    K[:na, :na] -= fb
    K += D[pen].T @ ((1 / rows.compliance[pen])[:, None] * D[pen])
    P = np.zeros(n)
    for pf in forcing.constant:
        P[:na] += a.phi[a.dof_index(pf.label)] * pf.value
    Dr = D[~pen]
    S = np.block([[K, Dr.T], [Dr, np.zeros((Dr.shape[0], Dr.shape[0]))]])
    x = np.linalg.solve(S, np.concatenate([P, np.zeros(Dr.shape[0])]))
    f = np.zeros(rows.n)
    f[pen] = -(1 / rows.compliance[pen]) * (D[pen] @ x[:n])
    f[~pen] = -x[n:]
    return x[:n], f


@pytest.mark.parametrize("rigid_post", [False, True])
def test_interface_reduced_statics_equal_the_dense_solve(rigid_post):
    """1,200 + 45 modes, 4 posts (one of them a rigid bolt), a rank-3 feedback given by its
    factors, point loads: q and the contact forces equal the dense n x n solve to 1e-9
    (both are direct solves of the same well-conditioned system: round-off)."""
    a = _big_body(1200)
    b = toy_pad(4, zeta=0.05)
    contacts = holddown_contacts(4, 5e9)
    if rigid_post:
        contacts[0] = ContactPoint("holddown_1", ["post_1:Tz", "post_1:Tx", "post_1:Ty"],
                                   ["pad_1:Tz", "pad_1:Tx", "pad_1:Ty"], rigid=True)
    rng = np.random.default_rng(4)
    U, V = rng.standard_normal((a.n_modes, 3)) * 1e-2, rng.standard_normal((3, a.n_modes)) * 1e-2
    U[6:], V[:, 6:] = U[6:] / 10, V[:, 6:] / 10
    fo = Forcing(constant=[PointForce("a", "top:Tx", 3e5), PointForce("a", "top:Tz", -2e7)],
                 feedback=[ModalFeedback("a", U @ V, factors=(U, V))])
    st, f = static_solution(a, b, contacts, fo)
    q_ref, f_ref = _dense_static(a, b, contacts, fo, U @ V)
    q = np.concatenate([st.q_a, st.q_b])
    np.testing.assert_allclose(q, q_ref, rtol=1e-9, atol=1e-9 * np.abs(q_ref).max())
    np.testing.assert_allclose(f, f_ref, rtol=1e-9, atol=1e-9 * np.abs(f_ref).max())


def test_feedback_factors_are_checked_and_used():
    vt = vehicle_truss(4)
    a, b = truss_body(vt, "vehicle", zeta=0.05), toy_pad(4, zeta=0.05)
    rng = np.random.default_rng(2)
    U, V = rng.standard_normal((a.n_modes, 2)), rng.standard_normal((2, a.n_modes))
    with pytest.raises(InputError, match="factors differ from the matrix"):
        ModalFeedback("a", U @ V + 1e-3, factors=(U, V))
    with pytest.raises(InputError, match="factors of shapes"):
        ModalFeedback("a", U @ V, factors=(U, V[:1]))
    S = 1e-3 * U @ V
    runs = []
    for fb in (ModalFeedback("a", S), ModalFeedback("a", S, factors=(1e-3 * U, V))):
        p = TransientProblem(a, b, holddown_contacts(4, 1e10), Forcing(gravity=(0, 0, -9.81), feedback=[fb]),
                             t_end=0.05, progress=False)
        runs.append(solve(p).contact_force)
    np.testing.assert_allclose(runs[0], runs[1], rtol=1e-9, atol=1e-9 * np.abs(runs[0]).max())


def test_step_estimate_lanczos_equals_dense():
    """Rigid bolts: the largest eigenvalue of the coupled system on the constraints' null
    space, by Lanczos on the projected operator (n > 400) and densely on a null-space
    basis (scipy.linalg.null_space): rtol 1e-8 (Lanczos tolerance 1e-10)."""
    import scipy.linalg as sla

    from liftoff.transient.stepping import _constrained_max_eig

    a, b = _big_body(700, seed=3), toy_pad(4, zeta=0.05)
    contacts = holddown_contacts(4, 5e9)
    contacts[2] = ContactPoint("holddown_3", ["post_3:Tz", "post_3:Tx", "post_3:Ty"],
                               ["pad_3:Tz", "pad_3:Tx", "pad_3:Ty"], rigid=True)
    rows = contact_rows(a, b, contacts)
    D = np.hstack([rows.Phi_a, -rows.Phi_b])
    pen = rows.compliance > 0
    Om2 = np.concatenate([a.omega, b.omega]) ** 2
    K = np.diag(Om2) + D[pen].T @ ((1 / rows.compliance[pen])[:, None] * D[pen])
    N = sla.null_space(D[~pen])
    ref = np.linalg.eigvalsh(N.T @ K @ N).max()
    assert _constrained_max_eig(Om2, D[pen], 1 / rows.compliance[pen], D[~pen]) == pytest.approx(ref, rel=1e-8)
    f_h, h = estimate_step(a, b, contacts)
    assert f_h >= np.sqrt(ref) / (2 * np.pi) * (1 - 1e-8)


def test_keep_modal_q_keeps_the_displacements_only(tmp_path):
    vt = vehicle_truss(4)
    a, b = truss_body(vt, "vehicle", zeta=0.05), toy_pad(4, zeta=0.05)
    base = dict(contacts=holddown_contacts(4, 1e10, release_time=0.02), forcing=Forcing(gravity=(0, 0, -9.81)),
                t_end=0.05, progress=False)
    full = solve(TransientProblem(a, b, keep_modal=True, **base))
    q = solve(TransientProblem(a, b, keep_modal="q", **base))
    assert set(q.modal) == {"q_a", "q_b"} and set(full.modal) == {"q_a", "v_a", "acc_a", "q_b", "v_b", "acc_b"}
    np.testing.assert_array_equal(q.modal["q_a"], full.modal["q_a"])
    np.testing.assert_array_equal(q.contact_force, full.contact_force)
    back = load_result(q.save(tmp_path / "r.h5"))
    np.testing.assert_array_equal(back.modal["q_b"], q.modal["q_b"])
    with pytest.raises(InputError, match="keep_modal must be"):
        TransientProblem(a, b, keep_modal="v", **base)
