"""Vehicle effects of section 4 (transient/effects.py) against independent references."""
import numpy as np
import pytest

from liftoff.transient.effects import (center_of_gravity, cg_motion_matrix, control_forces,
                               control_gimbal_matrix, cryo_point_loads, load_resultant,
                               modal_resultant_about, resultant_about, body_rb,
                               softening_matrix)
from liftoff.core.errors import InputError

from ..roundoff import eig_rtol, solve_rtol, sum_rtol

G = np.array([0.0, 0.0, -9.80665])
GIMBALS = ["n0_0:Tx", "n0_0:Ty", "n0_2:Tx", "n0_2:Ty"]


def _applied(body):
    """Thrust at the four base corners (unequal: a net moment) and a lateral wind at the top."""
    labels = ["n0_0:Tz", "n0_1:Tz", "n0_2:Tz", "n0_3:Tz", "n6_1:Tx", "n6_3:Ty"]
    values = np.array([[1.0e6, 1.2e6, 0.9e6, 1.1e6, 3.0e4, -2.0e4],
                       [2.0e6, 1.5e6, 2.2e6, 1.8e6, -1.0e4, 5.0e4]])  # two time points
    return labels, values


def test_cg_matches_lumped_masses(truss_tower):
    body, K, M, Phi, RB = truss_tower(top_mass=8000.0, offset=(0.3, -0.2))
    m_nodes = np.diag(M)[::3]
    cg_ref = (m_nodes[:, None] * body.point_coords).sum(0) / m_nodes.sum()
    m, cg = center_of_gravity(body)
    # RB^T M RB and the reference are sums over the n DOFs (positive masses): n eps; the c.g.
    # is a first moment over the mass: the same, of the tower's size
    tol = sum_rtol(M.shape[0])
    assert m == pytest.approx(m_nodes.sum(), rel=tol)
    np.testing.assert_allclose(cg, cg_ref, rtol=0, atol=tol * np.abs(body.point_coords).max())


def test_control_system_zeroes_moment_about_cg(truss_tower):
    body, K, M, Phi, RB = truss_tower(top_mass=8000.0)
    _, cg = center_of_gravity(body)
    labels, P = _applied(body)
    FSL = control_forces(body, GIMBALS, labels, P)
    M_before = resultant_about(body, labels, P, cg)[:, 3:]
    total = resultant_about(body, labels + GIMBALS, np.hstack([P, FSL]), cg)
    # the corrective forces cancel the applied moment about the c.g. to round-off: a solve with
    # the gimbal matrix (eps cond) and moment sums over the forces (n eps, lever arms ~ the tower)
    G = control_gimbal_matrix(body, GIMBALS, cg)
    n = len(labels) + len(GIMBALS)
    tol = solve_rtol(np.linalg.cond(G), n) * np.abs(np.hstack([P, FSL])).sum(axis=1).max() \
        * np.abs(body.point_coords - cg).max()
    assert np.abs(M_before).max() > 1e5
    np.testing.assert_allclose(total[:, 3:], 0.0, atol=tol)
    # lateral only: the gimbal forces do not change the vertical resultant (a sum of the same
    # vertical forces plus exact zeros)
    np.testing.assert_allclose(total[:, 2], resultant_about(body, labels, P, cg)[:, 2], rtol=sum_rtol(n))


def test_control_modal_form_equals_physical_form(truss_tower):
    """Eq. 20-21: the resultant from generalised forces through Phi^-1 = Phi^T M equals the
    physical one (all modes kept, and also truncated: the rigid modes alone carry it)."""
    for n_modes in (None, 12):
        body, K, M, Phi, RB = truss_tower(n_modes=n_modes)
        labels, P = _applied(body)
        _, cg = center_of_gravity(body)
        F_A = P @ body.rows(labels)                                     # generalised forces
        if n_modes is None:
            P_back = (M @ Phi @ F_A.T).T                                # Phi^-T F_A = M Phi F_A
            idx = [body.dof_index(l) for l in labels]
            np.testing.assert_allclose(P_back[:, idx], P, rtol=1e-8, atol=1e-6)
        np.testing.assert_allclose(modal_resultant_about(body, F_A, cg),
                                   resultant_about(body, labels, P, cg), rtol=1e-9, atol=1e-3)


def test_controlled_vehicle_has_no_rigid_rotation(truss_tower):
    """Free flight: with the control forces the rigid-body angular acceleration about the
    c.g. is zero to round-off; without them it is not. Bound stated: < 1e-12 of the
    uncontrolled value (elastic modes then only deform the vehicle about a vertical axis)."""
    body, K, M, Phi, RB = truss_tower(top_mass=8000.0)
    m, cg = center_of_gravity(body)
    labels, P = _applied(body)
    FSL = control_forces(body, GIMBALS, labels, P)
    RBc = body_rb(body, body.dof_labels, cg)
    I_cg = (RBc.T @ M @ RBc)[3:, 3:]
    rows = [body.dof_index(l) for l in labels + GIMBALS]
    f = np.zeros((2, len(body.dof_labels)))
    f[:, rows[:len(labels)]] = P
    alpha_free = np.linalg.solve(I_cg, (f @ RBc)[:, 3:].T)
    f[:, rows[len(labels):]] = FSL
    alpha_ctrl = np.linalg.solve(I_cg, (f @ RBc)[:, 3:].T)
    assert np.abs(alpha_free).max() > 1e-3
    # round-off of the moment cancellation (n forces, gimbal solve) through the 3 x 3 inertia solve
    G = control_gimbal_matrix(body, GIMBALS, cg)
    tol = solve_rtol(np.linalg.cond(G) * np.linalg.cond(I_cg), len(rows)) * np.abs(f).sum(axis=1).max() \
        * np.abs(body.point_coords - cg).max() / np.linalg.eigvalsh(I_cg).min()
    assert np.abs(alpha_ctrl).max() < tol < 1e-6 * np.abs(alpha_free).max()


def test_control_needs_gimbals_off_cg_height(truss_tower):
    body, *_ = truss_tower()
    with pytest.raises(InputError, match="control system"):
        control_gimbal_matrix(body, ["n0_0:Tx", "n0_2:Tx"])


def test_cg_motion_of_rigid_column(rigid_column):
    """ERV q (eq. 23) equals the c.g. point's own mode rows for a rigid body."""
    body = rigid_column()
    ERV = cg_motion_matrix(body, [l for l in body.dof_labels if l.startswith("base")])
    cg_rows = body.rows([f"cg:{c}" for c in ("Tx", "Ty", "Tz", "Rx", "Ry", "Rz")])
    # ERV: a 6 x 6 solve with the rigid-body mass (eps cond) of rows that carry lever arms
    # (rotations times the column's size, in m)
    tol = solve_rtol(np.linalg.cond(body.rigid_body_mass), 6) * np.abs(cg_rows).max() \
        * (1.0 + np.abs(body.point_coords).max())
    np.testing.assert_allclose(ERV, cg_rows, rtol=0, atol=tol)


@pytest.mark.parametrize("g", [0.0, 3.0, 9.80665, 15.0])
def test_softening_matches_inverted_pendulum(rigid_column, g):
    """Rigid column on a pinned base with rotational springs k: the rocking frequency with
    gravity softening is omega^2 = (k - m g l)/(I + m l^2) (inverted pendulum, closed form).
    The pin is imposed exactly (modal coordinates restricted to the null space of the base
    translations), so only round-off separates the two: rtol 1e-10."""
    import scipy.linalg as sla

    m, I, l, k = 1000.0, 500.0, 10.0, 2.0e5
    body = rigid_column(m=m, inertia=(I, I, 200.0), l=l)
    base = [f"base:{c}" for c in ("Tx", "Ty", "Tz", "Rx", "Ry", "Rz")]
    Phib = body.rows(base)
    N = sla.null_space(Phib[:3])                       # pinned: base translations zero
    Kc = np.diag([k, k, 1e6])                          # rotational springs at the base
    KSOF = softening_matrix(body, [0, 0, -g], boundary_labels=base)
    Keff = N.T @ (Phib[3:].T @ Kc @ Phib[3:] - KSOF) @ N
    w2 = np.sort(sla.eigvals(Keff, N.T @ N).real)
    expected = (k - m * g * l) / (I + m * l * l)
    # the two rocking modes (about x and y) are the two lowest; a generalised eigenvalue of
    # the small pencil: n eps ||Keff|| / |lambda|, times cond(N^T N) (= 1: N is orthonormal)
    np.testing.assert_allclose(w2[:2], expected, rtol=eig_rtol(Keff.shape[0], np.linalg.norm(Keff, 2), expected))


def test_softening_lowers_lateral_frequency_of_flexible_column(truss_tower):
    """A flexible column clamped at its base: the first (lateral) frequency falls
    monotonically as gravity (the axial load) grows."""
    body, K, M, Phi, RB = truss_tower(top_mass=20000.0, EA=2e8)
    base = [f"n0_{j}:{c}" for j in range(4) for c in ("Tx", "Ty", "Tz")]
    Phib = body.rows(base)
    Kc = Phib.T @ (1e12 * np.eye(len(base))) @ Phib
    freqs = []
    for g in (0.0, 5.0, 9.80665, 20.0):
        KSOF = softening_matrix(body, [0, 0, -g])
        w2 = np.sort(np.linalg.eigvals(np.diag(body.omega ** 2) + Kc - KSOF).real)
        freqs.append(np.sqrt(w2[0]) / 2 / np.pi)
    print("first lateral frequency (Hz) vs g:", np.round(freqs, 5))
    assert all(b < a for a, b in zip(freqs, freqs[1:]))


def test_cryo_loads_sum_and_self_equilibrium(truss_tower):
    """A load K u from any imposed strain is self-equilibrated (RB^T K = 0): zero resultant."""
    body, K, M, Phi, RB = truss_tower()
    u = np.random.default_rng(1).normal(size=K.shape[0]) * 1e-3
    f = K @ u
    labels = list(body.dof_labels)
    half = len(labels) // 2
    loads = cryo_point_loads([(labels[:half], f[:half]), (labels[half:], f[half:]),
                              (labels[:2], np.zeros(2))])
    assert len(loads) == len(labels)
    R = load_resultant(body, loads)
    assert np.abs(R).max() < 1e-9 * np.abs(f).max()
    with pytest.raises(InputError, match="2 labels but 3 values"):
        cryo_point_loads([(labels[:2], np.zeros(3))])


def test_softening_feedback_in_transient_matches_inverted_pendulum(rigid_column):
    """The same pendulum through the transient core: KSOF as a ModalFeedback held over each
    step (eq. 26), base pinned by penalty contacts to ground, released from a small tilt,
    h = 0.25/f_h (eq. 12). The rocking period must be 2 pi sqrt((I + m l^2)/(k - m g l)).
    Errors: penalty pin ~k/(k_t l^2) = 2e-6; the held feedback lags by half a step,
    (omega h) ~ 1e-4 at most; zero crossings interpolated linearly, ~(omega h)^2:
    rtol 1e-5 (measured 1e-6). Without softening the period is shorter."""
    from liftoff.transient import ContactPoint, Forcing, InitialState, ModalFeedback, TransientProblem, ground, solve

    m, I, l, k, kt, g = 1000.0, 500.0, 10.0, 2.0e5, 1.0e9, 9.80665
    body = rigid_column(m=m, inertia=(I, I, 200.0), l=l)
    six = ("Tx", "Ty", "Tz", "Rx", "Ry", "Rz")
    pin = ContactPoint("base", [f"base:{c}" for c in six], [None] * 6, [kt, kt, kt, k, k, 1e4], axial=2)
    theta = 1e-3
    x_cg = np.array([theta * l, 0, 0, 0, theta, 0])                  # tilted about the base pin
    q0 = np.sqrt(np.diag(body.rigid_body_mass)) * x_cg                # modal coordinates about the c.g.
    periods = {}
    for soft in (True, False):
        fb = [ModalFeedback("a", softening_matrix(body, [0, 0, -g], [f"base:{c}" for c in six]))] if soft else []
        prob = TransientProblem(body, ground(), [pin], Forcing(feedback=fb, gravity=(0, 0, -g)), t_end=20.0,
                                h=None, initial=InitialState(q0, np.zeros(6), np.zeros(0), np.zeros(0)),
                                progress=False)
        res = solve(prob)
        ry = res.rigid_body_motion_a[:, 4]
        s = np.flatnonzero(np.sign(ry[:-1]) != np.sign(ry[1:]))
        tz = res.time[s] - ry[s] * (res.time[s + 1] - res.time[s]) / (ry[s + 1] - ry[s])
        periods[soft] = 2 * np.mean(np.diff(tz))
    expected = 2 * np.pi * np.sqrt((I + m * l * l) / (k - m * g * l))
    print(f"rocking period: softening {periods[True]:.6f} s (closed form {expected:.6f} s), "
          f"without {periods[False]:.6f} s, h = {res.h:.3g} s")
    assert periods[True] == pytest.approx(expected, rel=1e-5)
    assert periods[False] == pytest.approx(2 * np.pi * np.sqrt((I + m * l * l) / k), rel=1e-5)
