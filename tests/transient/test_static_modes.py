"""Residual-flexibility ("static") modes (TransientProblem.static_above_hz): the elastic
modes above a cut solved quasi-statically, q = P/omega^2, no velocity or acceleration.

References: pyyeti's ``SolveUnc`` with its ``rf`` modes (the same quasi-static solution,
another program); a free-free rod dropped onto a contact spring, whose rigid mode then
rides on the contact spring in series with the elastic mode's static flexibility
(closed form: a one-DOF oscillator); the step estimate against that series frequency.
"""
import math
from dataclasses import replace

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
    which bounds |F - closed form|/(M g); allowed 1.5 x that (measured 6.35e-4 against
    6.37e-4 predicted). With the mode dynamic the force rings at 250 Hz and above (the check that
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


def _bolted_toy(static_above_hz, h, t_end=0.05):
    """The toy vehicle (free-free truss) bolted at its 4 posts to the toy pad (grounded
    truss) by 1e10 N/m springs in x, y, z (12 penalty rows), a thrust and a side load
    ramped from zero at the top, from rest."""
    thrust = TabulatedForce("a", "top:Tz", [0.0, 0.2], [0.0, 8e5])
    side = TabulatedForce("a", "top:Tx", [0.0, 0.2], [0.0, 4e4])
    return TransientProblem(toy_vehicle(), toy_pad(), holddown_contacts(4), Forcing(tables=[thrust, side]),
                            t_end=t_end, h=h, initial="zero", progress=False, static_above_hz=static_above_hz)


def _quasi_static_reference(p: TransientProblem, times: np.ndarray) -> np.ndarray:
    """Contact forces on body a (rows in the order of the problem's contacts: Tz, Tx, Ty per
    post) of the same model written out independently of the two-body code: the dynamic
    modes q'' + 2 zeta omega q' + omega^2 q = P + Phi^T (+-f), the static modes q = (P +
    Phi^T (+-f))/omega^2, the bolted rows f = -K_C (Phi_a q_a - Phi_b q_b), so that
    (I + K_C C_s) f = -K_C (e_dyn + e_load), C_s = sum Phi_s Omega_s^-2 Phi_s^T; integrated by
    scipy's DOP853 at rtol 1e-11."""
    from scipy.integrate import solve_ivp

    a, b = p.body_a, p.body_b
    rows_a = [a.dof_index(lab) for c in p.contacts for lab in c.labels_a]
    rows_b = [b.dof_index(lab) for c in p.contacts for lab in c.labels_b]
    Pa_, Pb_ = a.phi[rows_a], b.phi[rows_b]                      # (12, n)
    K = np.concatenate([np.broadcast_to(np.asarray(c.stiffness, float), (len(c.labels_a),)) for c in p.contacts])
    sa, sb = p.static_modes("a"), p.static_modes("b")
    da, db = ~sa, ~sb
    Cs = (Pa_[:, sa] / a.omega[sa] ** 2) @ Pa_[:, sa].T + (Pb_[:, sb] / b.omega[sb] ** 2) @ Pb_[:, sb].T
    S = np.eye(Cs.shape[0]) + K[:, None] * Cs
    top = a.phi[a.dof_index("top:Tz")], a.phi[a.dof_index("top:Tx")]
    tz, tx = p.forcing.tables

    def load_a(t):
        return top[0] * np.interp(t, tz.time, tz.value) + top[1] * np.interp(t, tx.time, tx.value)

    na, nb = int(da.sum()), int(db.sum())

    def force(t, y):
        qa, qb = y[:na], y[na:na + nb]
        Pa = load_a(t)
        e = Pa_[:, da] @ qa - Pb_[:, db] @ qb + (Pa_[:, sa] / a.omega[sa] ** 2) @ Pa[sa]
        return np.linalg.solve(S, -K * e)

    def rhs(t, y):
        qa, qb, va, vb = y[:na], y[na:na + nb], y[na + nb:2 * na + nb], y[2 * na + nb:]
        f = force(t, y)
        wa, wb, za, zb = a.omega[da], b.omega[db], a.zeta[da], b.zeta[db]
        acc_a = load_a(t)[da] + Pa_[:, da].T @ f - 2 * za * wa * va - wa ** 2 * qa
        acc_b = -Pb_[:, db].T @ f - 2 * zb * wb * vb - wb ** 2 * qb
        return np.concatenate([va, vb, acc_a, acc_b])

    sol = solve_ivp(rhs, (times[0], times[-1]), np.zeros(2 * (na + nb)), method="DOP853", t_eval=times,
                    rtol=1e-11, atol=1e-14, max_step=1e-4)
    return np.array([force(t, y) for t, y in zip(sol.t, sol.y.T)])


def test_bolted_vehicle_on_pad_against_an_independent_quasi_static_model():
    """12 coupled penalty rows, static modes on both bodies (90 Hz: 17 of the vehicle's 21 elastic ones, 5
    of the pad's): the contact forces converge to the independent model's
    (:func:`_quasi_static_reference`) at second order in h (the exact modal step with the
    contact force linear over the step: the error ratio between h = 2e-5 and 1e-5 s is 4,
    allowed 3 to 5), and at 1e-5 s agree with it to 1e-5 of the largest force (measured
    7.8e-7 and 2.0e-7 at the two steps, 2026-11-28; the bound leaves room for other BLAS
    round-off, the reference's own error at rtol 1e-11 being far below both)."""
    errs = []
    for h in (2e-5, 1e-5):
        p = _bolted_toy(90.0, h)
        assert p.static_modes("a").sum() == 17 and p.static_modes("b").sum() == 5
        res = solve(p)
        ref = _quasi_static_reference(p, res.time)
        F = res.contact_force
        errs.append(np.abs(F - ref).max() / np.abs(ref).max())
    print(f"max |F - reference| / max |F|: {errs[0]:.2e} (h = 2e-5 s), {errs[1]:.2e} (1e-5 s)")
    assert errs[1] < 1e-5
    assert 3.0 < errs[0] / errs[1] < 5.0                       # second order


def test_contacts_on_velocities_are_refused_with_static_modes():
    """Rigid rows, dashpots and friction work on relative velocities, in which the static
    modes have no part: refused, naming the contact, once the cut makes a mode static."""
    base = dict(t_end=0.1, progress=False)
    va, pb = toy_vehicle(), toy_pad()
    rigid = holddown_contacts(4, rigid=True)
    with pytest.raises(InputError, match=r"contact 'holddown_1' is rigid: .*static_above_hz = 90 Hz"):
        TransientProblem(va, pb, rigid, Forcing(), static_above_hz=90.0, **base)
    TransientProblem(va, pb, rigid, Forcing(), static_above_hz=1e4, **base)        # no mode above: no change
    damped = [ContactPoint("c", ["post_1:Tz"], ["pad_1:Tz"], 1e10, damping=1e5)]
    with pytest.raises(InputError, match=r"contact 'c' has a dashpot"):
        TransientProblem(va, pb, damped, Forcing(), static_above_hz=90.0, **base)


def test_static_modes_have_no_acceleration_at_t0():
    """From rest with a load already on at t0 (initial 'zero'), a static mode's acceleration
    in row 0 is 0, not P0 (its equation has no inertia)."""
    res = solve(replace(_dropped_rod(100.0, h=1e-4), keep_modal=True))
    assert res.modal["acc_a"][0, 1] == 0.0 and res.modal["acc_a"][0, 0] != 0.0


def test_scenario_key_reaches_the_problem():
    """[time] static_above_hz through TimeSpan (the one translation); a bad value names the key."""
    from liftoff.config.sections import time_span
    from liftoff.config.values import Where

    ts = time_span(Where("s.toml", "time"), {"t_end": 1.0, "static_above_hz": 300})
    p = _dropped_rod(None)
    assert ts.problem(p.body_a, p.body_b, p.contacts, p.forcing, progress=False).static_above_hz == 300.0
    with pytest.raises(InputError, match=r"s.toml: time.static_above_hz"):
        time_span(Where("s.toml", "time"), {"t_end": 1.0, "static_above_hz": 0})
