"""Static initial conditions (section 2.6) and the settle check: a run under static loads
oscillates about, and with damping settles onto, the static solution."""
import math

import numpy as np
import pytest

from liftoff.transient import (ContactPoint, Forcing, InitialState, InputError, ModalFeedback, PointForce, Recovery,
                       TransientProblem, ground, solve, static_solution)
from liftoff.transient.examples import holddown_contacts, spring_block, toy_pad, truss_body, vehicle_truss

from ..roundoff import sum_rtol

G = 9.81


@pytest.fixture(scope="module")
def bodies():
    vt = vehicle_truss(4)
    return truss_body(vt, "vehicle", zeta=0.1), toy_pad(4, zeta=0.1), vt.masses.sum()


def test_static_contact_forces_carry_the_weight(bodies):
    vehicle, pad, mass = bodies
    contacts = holddown_contacts(4, 1e10)
    st, f = static_solution(vehicle, pad, contacts, Forcing(gravity=(0, 0, -G)))
    fz = f[0::3]
    # independent: vertical equilibrium of the free vehicle, sum of post reactions = m g
    # (gravity enters through the participation factors, eq. 14)
    assert abs(fz.sum() - mass * G) < 1e-9 * mass * G
    assert abs(f[1::3].sum()) < 1e-9 * mass * G and abs(f[2::3].sum()) < 1e-9 * mass * G
    # rigid-body part: the vehicle's mass-weighted motion = rigid_body_mass^-1 participation^T q
    assert np.all(np.isfinite(np.linalg.solve(vehicle.rigid_body_mass, vehicle.participation.T @ st.q_a)))


def test_settle_about_static_solution(bodies):
    vehicle, pad, mass = bodies
    contacts = holddown_contacts(4, 1e10)
    fo = Forcing(gravity=(0, 0, -G))
    st, f_static = static_solution(vehicle, pad, contacts, fo)
    # started at the static solution: nothing moves (the exact step keeps equilibrium)
    r = solve(TransientProblem(vehicle, pad, contacts, fo, t_end=0.2, initial="static", progress=False))
    drift = np.abs(r.contact_force - f_static).max() / np.abs(f_static).max()
    print(f"\nstarted static: max contact force drift {drift:.2e} of peak")
    assert drift < 1e-9  # rounding only
    # dropped from the unloaded shape: it oscillates about the static solution. The slowest
    # coupled modes (stack rocking on the pad, 2.75 and 2.87 Hz) carry little modal damping,
    # so the check is on the time mean over ~6 periods, which removes the oscillation to
    # ~ amplitude / (2 pi n_periods) ~ 0.5 %, and on the decay of the envelope.
    r = solve(TransientProblem(vehicle, pad, contacts, fo, t_end=2.5, initial="zero", progress=False,
                               outputs={"a": ["top:Tz"]}))
    F = r.contact_force
    peak = np.abs(f_static).max()
    dev = np.abs(F - f_static).max(axis=1) / peak
    late = r.time >= 0.5
    mean_dev = np.abs(F[late].mean(axis=0) - f_static).max() / peak
    top_static = vehicle.phi[vehicle.dof_index("top:Tz")] @ st.q_a
    top_mean = r.displacement["a"][late, 0].mean()
    print(f"dropped from zero: deviation {dev[r.time < 0.5].max():.2f} of peak in the first 0.5 s, "
          f"{dev[r.time > 2.0].max():.2f} in the last 0.5 s; time-mean deviation over 0.5-2.5 s {mean_dev:.2e}; "
          f"top:Tz mean {top_mean:.6e} m (static {top_static:.6e} m)")
    assert dev[r.time < 0.5].max() > 0.5  # it really oscillates ...
    assert dev[r.time > 2.0].max() < 0.8 * dev[(r.time > 0.5) & (r.time < 1.0)].max()  # ... decaying
    assert mean_dev < 0.02  # ... about the static solution
    assert abs(top_mean / top_static - 1) < 0.02


def test_singular_static_problem_is_an_input_error(bodies):
    vehicle, pad, _ = bodies
    one = [ContactPoint("only", ["post_1:Tz"], ["pad_1:Tz"], 1e10)]
    with pytest.raises(InputError, match="static equilibrium at t = 0 s is singular"):
        static_solution(vehicle, pad, one, Forcing(gravity=(0, 0, -G)))
    with pytest.raises(InputError, match="singular"):
        solve(TransientProblem(vehicle, pad, one, Forcing(gravity=(0, 0, -G)), t_end=0.1, progress=False))


def test_feedback_softens_statics_and_holds_dynamically():
    """1-DOF block with a softening feedback k_f: static q = P / (omega^2 - k_f) (eq. 27 analogue),
    and a run started there stays there (force held over each step, eq. 26)."""
    m, k, kf, P = 2.0, 800.0, 150.0, 30.0
    block = spring_block(m, k, zeta=0.0, name="b", point="b")
    # feedback in modal units: force = kf_modal q with kf_modal = kf / m (phi = 1/sqrt(m))
    fb = ModalFeedback("a", np.array([[kf / m]]))
    fo = Forcing(constant=[PointForce("a", "b:Tz", P)], feedback=[fb])
    stop = [ContactPoint("stop", ["b:Tz"], [None], 1e6, gap=1.0, release_time=-math.inf)]  # never touched
    st, _ = static_solution(block, ground(), stop, fo)
    x = st.q_a[0] / math.sqrt(m)
    assert abs(x - P / (k - kf)) < 1e-12 * P / (k - kf)     # a scaled 1 x 1 solve: a few eps
    r = solve(TransientProblem(block, ground(), stop, fo, t_end=0.5, h=1e-3, outputs={"a": ["b:Tz"]},
                               recoveries=[Recovery("spring_force", "a", ["b"], disp=np.array([[k / math.sqrt(m)]]),
                                                    units="N")],
                               progress=False))
    # the equilibrium is a fixed point of each step up to round-off, which accumulates over the steps
    assert np.abs(r.displacement["a"][:, 0] - x).max() < sum_rtol(r.time.size) * x
    assert np.abs(r.recovered["spring_force"][:, 0] - k * x).max() < 1e-9 * k * x


def test_initial_state_shape_is_checked(bodies):
    vehicle, pad, _ = bodies
    bad = InitialState(np.zeros(3), np.zeros(3), np.zeros(pad.n_modes), np.zeros(pad.n_modes))
    with pytest.raises(InputError, match="initial q_a has 3 entries"):
        TransientProblem(vehicle, pad, holddown_contacts(4, 1e10), Forcing(), t_end=0.1, initial=bad)


def test_feedback_terms_switch_off_at_their_own_time():
    """Two softening terms, one switched off at t = 0.2 s: statics at t = 0 uses both, after 0.2 s
    only the second; a damped run started static settles on the new equilibrium P/(k - kf2)."""
    m, k, P = 2.0, 800.0, 30.0
    kf1, kf2 = 100.0, 150.0
    block = spring_block(m, k, zeta=0.2, name="b", point="b")
    fo = Forcing(constant=[PointForce("a", "b:Tz", P)],
                 feedback=[ModalFeedback("a", np.array([[kf1 / m]]), until=0.2), ModalFeedback("a", np.array([[kf2 / m]]))])
    stop = [ContactPoint("stop", ["b:Tz"], [None], 1e6, gap=1.0, release_time=-math.inf)]
    x0 = static_solution(block, ground(), stop, fo, t=0.0)[0].q_a[0] / math.sqrt(m)
    x1 = static_solution(block, ground(), stop, fo, t=0.3)[0].q_a[0] / math.sqrt(m)
    assert abs(x0 - P / (k - kf1 - kf2)) < 1e-12 * x0 and abs(x1 - P / (k - kf2)) < 1e-12 * x1  # 1 x 1 solves
    r = solve(TransientProblem(block, ground(), stop, fo, t_end=2.0, h=1e-3, outputs={"a": ["b:Tz"]}, progress=False))
    x = r.displacement["a"][:, 0]
    # held at the first equilibrium (a fixed point of each step up to round-off, accumulated over the steps)
    assert np.abs(x[r.time <= 0.2] - x0).max() < sum_rtol(np.sum(r.time <= 0.2)) * x0
    # after the switch-off it settles onto x1: the transient decays as e^(-zeta w t) with
    # zeta w = 0.2 sqrt(650/2) = 3.6 /s, i.e. to ~1.5e-3 of the jump by t = 2 s (measured 7e-4)
    assert abs(x[-1] - x1) < 1e-2 * abs(x0 - x1)
