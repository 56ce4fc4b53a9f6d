"""Residual-flexibility ("static") modes (TransientProblem.static_above_hz): the elastic
modes above a cut solved quasi-statically, q = P/omega^2, no velocity or acceleration.

References: pyyeti's ``SolveUnc`` with its ``rf`` modes (the same quasi-static solution,
another program); a free-free rod dropped onto a contact spring, whose rigid mode then
rides on the contact spring in series with the elastic mode's static flexibility
(closed form: a one-DOF oscillator); the step estimate against that series frequency.
"""
import math

import numpy as np
import pytest

from liftoff.core.errors import InputError
from liftoff.transient import (ContactPoint, Forcing, TabulatedForce, TransientProblem, choose_step, estimate_step,
                               ground, solve)
from liftoff.transient.coefficients import step_coefficients
from liftoff.transient.examples import free_free_rod, holddown_contacts, toy_pad, toy_vehicle


def test_static_coefficients_and_bad_input():
    """Bc = 1/omega^2 and every other coefficient 0 for a static mode; the dynamic ones
    as before (bit for bit); a rigid mode cannot be static; the cut must be positive."""
    omega, zeta = np.array([0.0, 10.0, 2000.0]), np.array([0.0, 0.02, 0.02])
    dyn = step_coefficients(omega, zeta, 1e-3)
    st = step_coefficients(omega, zeta, 1e-3, np.array([False, False, True]))
    assert np.array_equal(st.packed()[:, :2], dyn.packed()[:, :2])
    assert st.Bc[2] == 1.0 / 2000.0 ** 2
    assert np.all(np.delete(st.packed()[:, 2], 3) == 0.0)
    with pytest.raises(InputError, match="rigid-body mode"):
        step_coefficients(omega, zeta, 1e-3, np.array([True, False, False]))
    with pytest.raises(InputError, match="static_above_hz = -1.0 Hz must be positive"):
        TransientProblem(toy_vehicle(), ground(), [], Forcing(), t_end=0.1, static_above_hz=-1.0)


pyyeti_ode = pytest.importorskip("pyyeti.ode")


def test_against_pyyeti_solveunc_rf_modes():
    """A plain modal transient of the toy vehicle with its modes above 40 Hz static,
    against pyyeti SolveUnc with those modes as its ``rf`` modes (both exact for a force
    linear between samples, the rf modes q = P/k, v = a = 0): rtol 1e-10 of the peak, the
    coefficients' rounding (2.4e-14, test_modal_transient.py) times the growth over 2,000
    steps. Our static modes' acceleration, P - omega^2 (P/omega^2), is zero to round-off of P."""
    body = toy_vehicle()
    cut = 40.0
    rf = np.flatnonzero(body.omega > 2 * math.pi * cut)
    assert 0 < rf.size < body.n_modes - 6          # some static, some dynamic elastic modes
    h, n_t = 2e-4, 2001
    t = h * np.arange(n_t)
    label = body.dof_labels[2]
    ramp = TabulatedForce("a", label, [0.0, 0.05, 0.12, 0.4], [0.0, 3e4, -1e4, 0.0])
    problem = TransientProblem(body, ground(), [], Forcing(tables=[ramp]), t_end=t[-1], h=h, initial="zero",
                               keep_modal=True, outputs={"a": [label]}, progress=False, static_above_hz=cut)
    res = solve(problem)
    P = np.outer(body.phi[body.dof_index(label)], np.interp(t, ramp.time, ramp.value))
    k, c = np.diag(body.omega ** 2), np.diag(2 * body.zeta * body.omega)
    sol = pyyeti_ode.SolveUnc(None, c, k, h, order=1, rf=rf).tsolve(P, d0=np.zeros(body.n_modes),
                                                                    v0=np.zeros(body.n_modes))
    q, v, a = res.modal["q_a"], res.modal["v_a"], res.modal["acc_a"]
    print(f"max |q - pyyeti| / max |q| = {np.abs(q - sol.d.T).max() / np.abs(sol.d).max():.2e}")
    assert np.abs(q - sol.d.T).max() <= 1e-10 * np.abs(sol.d).max()
    assert np.abs(v - sol.v.T).max() <= 1e-10 * np.abs(sol.v).max()
    assert np.all(v[:, rf] == 0.0)
    assert np.abs(a - sol.a.T).max() <= 1e-10 * np.abs(sol.a).max()
    assert np.abs(a[:, rf]).max() <= 1e-14 * np.abs(P[rf]).max()
    assert np.allclose(q[:, rf], (P[rf] / body.omega[rf, None] ** 2).T, rtol=1e-13, atol=0)
    assert res.metadata["static_above_hz"] == cut and res.metadata["static_modes"] == [rf.size, 0]


def _dropped_rod(static_above_hz, h=None, t_end=0.05):
    """A 10 m steel-like free-free rod (rigid mode + first axial mode at 250 Hz) bolted at
    end0 to ground by a 1e9 N/m spring, under gravity along the rod from rest (initial
    'zero'): the contact force oscillates about the weight."""
    rod = free_free_rod(L=10.0, E=2e11, rho=8e3, A=0.01, n_modes=2)          # c = 5000 m/s: f_1 = 250 Hz
    contact = ContactPoint("c", ["end0:Tz"], [None], 1e9)
    return TransientProblem(rod, ground(), [contact], Forcing(gravity=(0.0, 0.0, -9.80665)), t_end=t_end, h=h,
                            initial="zero", progress=False, static_above_hz=static_above_hz)


def test_dropped_rod_rides_on_the_series_spring():
    """With its axial mode static, the rod's rigid mass M = 800 kg rides on the contact
    spring K_C in series with that mode's static flexibility at the end, 2/(M omega_1^2):
    k_eff = 1/(1/K_C + 2/(M omega_1^2)) (closed form; the mode's modal force of the uniform
    field is zero). From rest the contact force is M g (1 - cos(omega_eff t)), omega_eff =
    sqrt(k_eff/M). The step estimate is that frequency (f_h, eq. 12 with the series
    compliance) and no mode sets f_s. The march: the coupled step's relative frequency
    error (omega_eff h)^2/24 (the linear-acceleration method's, omega_eff h = 0.0197 here)
    accumulates a phase error omega_eff t (omega_eff h)^2/24 = 6.4e-4 rad by t = 0.05 s,
    which bounds |F - closed form|/(M g); allowed 1.5 x that (measured 6.5e-4, the
    prediction). With the mode dynamic the force rings at 250 Hz and above (the check that
    the two differ)."""
    M, w1, K = 800.0, math.pi * 5000.0 / 10.0, 1e9
    k_eff = 1.0 / (1.0 / K + 2.0 / (M * w1 ** 2))
    w_eff = math.sqrt(k_eff / M)
    p = _dropped_rod(static_above_hz=100.0)
    f_h, _ = estimate_step(p.body_a, p.body_b, p.contacts, 100.0)
    assert math.isclose(f_h, w_eff / (2 * math.pi), rel_tol=1e-12)
    step = choose_step(p)
    assert step.f_s == 0.0 and math.isclose(step.h_default, 0.25 / f_h, rel_tol=1e-12)
    h = 0.05 / 2000
    res = solve(_dropped_rod(100.0, h=h))
    F = np.abs(res.contact_force[:, 0])
    exact = M * 9.80665 * (1.0 - np.cos(w_eff * res.time))
    err = np.abs(F - exact).max() / (M * 9.80665)
    phase = w_eff * 0.05 * (w_eff * h) ** 2 / 24
    print(f"f_eff {w_eff / 2 / math.pi:.2f} Hz, max |F - closed form| = {err:.2e} M g, predicted phase error {phase:.2e}")
    assert err < 1.5 * phase
    dyn = solve(_dropped_rod(None, h=h))
    assert np.abs(np.abs(dyn.contact_force[:, 0]) - exact).max() > 0.05 * M * 9.80665


def _toy_liftoff(static_above_hz, h=2e-4):
    """The toy vehicle bolted to the toy pad, a thrust ramp, released at 0.1 s."""
    va, pb = toy_vehicle(), toy_pad()
    contacts = holddown_contacts(4, release_time=0.1)
    thrust = TabulatedForce("a", va.dof_labels[2], [0.0, 0.05, 0.3], [0.0, 8e5, 8e5])
    return TransientProblem(va, pb, contacts, Forcing(tables=[thrust], gravity=(0.0, 0.0, -9.80665)), t_end=0.3,
                            h=h, progress=False, static_above_hz=static_above_hz)


def test_a_cut_above_every_mode_changes_nothing():
    """No mode above the cut: the same run bit for bit as without one."""
    a, b = solve(_toy_liftoff(None)), solve(_toy_liftoff(1e7))
    assert np.array_equal(a.contact_force, b.contact_force) and b.metadata["static_modes"] == [0, 0]


def test_scenario_key_reaches_the_problem():
    """[time] static_above_hz through TimeSpan (the one translation); a bad value names the key."""
    from liftoff.config.sections import time_span
    from liftoff.config.values import Where

    ts = time_span(Where("s.toml", "time"), {"t_end": 1.0, "static_above_hz": 300})
    p = _dropped_rod(None)
    assert ts.problem(p.body_a, p.body_b, p.contacts, p.forcing, progress=False).static_above_hz == 300.0
    with pytest.raises(InputError, match=r"s.toml: time.static_above_hz"):
        time_span(Where("s.toml", "time"), {"t_end": 1.0, "static_above_hz": 0})
