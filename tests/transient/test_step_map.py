"""The contact-coupled step map (transient/step_map.py) and the check of a given step
above 0.25/f_h (stepping.check_step_map), against a closed form (Newmark's linear-
acceleration scheme), against the kernel itself (the map predicts each step of a bolted
run), and against runs that diverge without the check."""
from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from liftoff.transient import ContactPoint, Forcing, InputError, TransientProblem, ground, solve
from liftoff.transient import step_map as sm
from liftoff.transient import stepping
from liftoff.transient.assembly import contact_rows
from liftoff.transient.examples import free_free_rod


def _modes(p):
    return (np.concatenate([p.body_a.omega, p.body_b.omega]), np.concatenate([p.body_a.zeta, p.body_b.zeta]),
            np.concatenate([p.static_modes("a"), p.static_modes("b")]))


def _bolted_mass(h):
    """A rigid 1 kg mass on a 1e6 N/m penalty bolt to ground (omega = 1e3 rad/s)."""
    mass = free_free_rod(1.0, 1e9, 1000.0, 1e-3, 1, name="m")
    return TransientProblem(mass, ground(), [ContactPoint("bolt", ["end0:Tz"], [None], 1e6)],
                            Forcing(gravity=(0, 0, -9.81)), t_end=300 * h, h=h, initial="zero", progress=False)


def _rod(h, rigid=True, zeta=0.0, damping=0.0, n_steps=400, both_ends=False):
    """A 10 m steel rod (6 axial modes, 0-7954 rad/s) bolted at end0 to ground: rigidly, or by
    a 1e8 N/m penalty spring with ``damping`` (N s/m); ``both_ends``: also a rigid bolt at end1."""
    rod = free_free_rod(10.0, 2e11, 7800.0, 1e-2, 6, zeta=zeta, name="r")
    c = [ContactPoint("bolt", ["end0:Tz"], [None], 1e8, rigid=rigid, damping=0.0 if rigid else damping)]
    if both_ends:
        c.append(ContactPoint("top", ["end1:Tz"], [None], rigid=True))
    return TransientProblem(rod, ground(), c, Forcing(gravity=(0, 0, -9.81)), t_end=n_steps * h, h=h,
                            initial="zero", progress=False)


@pytest.mark.parametrize("wh", [0.5, 2.0, 3.4, 3.5, 5.0, 20.0])
def test_rigid_mass_on_a_penalty_bolt_is_newmarks_linear_acceleration_scheme(wh):
    """A rigid mass under a force linear over the step, integrated exactly, is Newmark's
    beta = 1/6, gamma = 1/2 scheme: lambda^2 - 2 A lambda + 1 = 0 with
    A = 1 - (wh)^2 / (2 (1 + (wh)^2/6)); |lambda| = 1 for wh <= 2 sqrt(3), else |A| + sqrt(A^2 - 1).
    1e-12: the map's 3 x 3 entries are formed from coefficients summed to machine precision."""
    p = _bolted_mass(wh / 1e3)
    om, ze, st = _modes(p)
    A = 1 - wh ** 2 / (2 * (1 + wh ** 2 / 6))
    expected = 1.0 if abs(A) <= 1 else abs(A) + math.sqrt(A * A - 1)
    rows = contact_rows(p.body_a, p.body_b, p.contacts)
    assert sm.step_map(rows, om, ze, wh / 1e3, st).shape == (3, 3)     # q, v of the mass and the bolt's force
    assert sm.spectral_radius(rows, om, ze, wh / 1e3, st) == pytest.approx(expected, rel=1e-12)


def test_the_map_predicts_every_step_of_a_bolted_run():
    """Second method: the kernel's own steps. Under a constant load the differences of
    successive states obey dx_{k+1} = M dx_k exactly (the load cancels), with every row
    coupled (bolted). The rod has a penalty bolt with a dashpot at one end and a rigid bolt
    at the other (the rigid rows' start values g included), modes damped 2 %, h above
    0.25/f_h. Tolerance 1e-9 of the largest difference: round-off of 400 steps' products."""
    h = 3e-4
    p = _rod(h, rigid=False, zeta=0.02, damping=2e5, both_ends=True)
    p.keep_modal = True
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = solve(p)
    rows = contact_rows(p.body_a, p.body_b, p.contacts)
    om, ze, st = _modes(p)
    M = sm.step_map(rows, om, ze, r.h, st)
    keep = sm.coupled_modes(rows, st)
    pen = rows.compliance > 0
    X = np.hstack([r.modal["q_a"][:, keep], r.modal["v_a"][:, keep], r.contact_force[:, pen]])
    dX = np.diff(X, axis=0)[1:]        # from step 1 on (step 0's start force is the initial state's)
    pred = dX[:-1] @ M.T
    scale = np.abs(dX).max(axis=0)
    assert np.abs(pred - dX[1:]).max(axis=0) / scale == pytest.approx(0.0, abs=1e-9)
    assert M.shape == (2 * 6 + 1, 2 * 6 + 1)


def test_rigid_rows_on_a_flexible_rod_unstable_step_is_refused_before_the_run():
    """The review's case: a rod bolted rigidly (no penalty row, so coupling_margin has nothing
    to test). At h = 8e-4 s the map's radius is 1.146; without the check the run diverges
    (the growth guard stops it at 1e41 J); with it the step is refused before the run, naming
    the radius. At 6e-4 s (also above 0.25/f_h) the map is stable (radius 1 to round-off:
    the rod's rigid translation is held) and the run is bounded."""
    p = _rod(8e-4)
    rows = contact_rows(p.body_a, p.body_b, p.contacts)
    om, ze, st = _modes(p)
    assert sm.spectral_radius(rows, om, ze, 8e-4, st) > 1.1
    assert stepping.coupling_margin(rows, om, ze, 8e-4, st) == math.inf        # the old test saw nothing
    with pytest.raises(InputError, match=r"h = 0.0008 s is unstable with these contacts: .*\(every contact bolted\) has spectral radius 1.14") as exc:
        solve(p)
    assert "\n" not in str(exc.value)
    stable = _rod(6e-4)
    with pytest.warns(UserWarning, match=r"larger than 0.25/f_h .* stable by its step map"):
        res = solve(stable)
    assert np.abs(res.contact_force).max() < 2 * 7800 * 10 * 1e-2 * 9.81      # twice the rod's weight


def test_without_the_check_that_step_diverges(monkeypatch):
    """What the check prevents: the same rod at 8e-4 s with the check switched off grows until
    the growth guard stops it (a ConvergenceError), at the map's predicted rate."""
    from liftoff.transient import ConvergenceError

    monkeypatch.setattr(stepping, "check_step_map", lambda *args: 1.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(ConvergenceError, match="diverged"):
            solve(_rod(8e-4))


def test_a_dashpot_on_an_undersampled_rod_is_refused():
    """A penalty bolt with a dashpot (tau = 2e-3 s) on an undamped rod at h = 1e-2 s: the
    penalty test passes (coupling_margin > -1, it ignores damping) but a complex pair of the
    map lies at |lambda| = 1.04 (a mode at omega h near an odd multiple of pi, dashpot-coupled):
    refused. The growth over the run decides, not the radius alone: at 2e-3 s (also above
    0.25/f_h = 1.3e-3 s) the radius is 1 + 4.1e-6 (modes aliased to omega h = 2 pi + 0.08 and
    4 pi + 0.16), a growth of 1.002 over 400 steps, well inside step_map.GROWTH_TOLERANCE:
    the run goes on."""
    p = _rod(1e-2, rigid=False, damping=2e5)
    rows = contact_rows(p.body_a, p.body_b, p.contacts)
    om, ze, st = _modes(p)
    assert stepping.coupling_margin(rows, om, ze, 1e-2, st) > -1
    assert sm.spectral_radius(rows, om, ze, 1e-2, st) == pytest.approx(1.0402, abs=1e-4)
    with pytest.raises(InputError, match=r"spectral radius 1.040.* over the 400 steps the run spends so"):
        solve(p)
    rho = sm.spectral_radius(rows, om, ze, 2e-3, st)
    assert 1 < rho < 1 + 1e-5 and rho ** 400 < sm.GROWTH_TOLERANCE
    with pytest.warns(UserWarning, match="stable by its step map"):
        solve(_rod(2e-3, rigid=False, damping=2e5))


def test_a_map_too_large_to_check_is_said(monkeypatch):
    """Above step_map.DENSE_LIMIT states a step above 0.25/f_h is refused, saying why and
    what to give instead, rather than run unchecked."""
    monkeypatch.setattr(sm, "DENSE_LIMIT", 10)
    with pytest.raises(InputError, match=r"this model's map has 12 states \(more than 10 cannot be checked here\): "
                                         r"give h at most 0.25/f_h"):
        solve(_rod(6e-4))


def test_the_automatic_step_needs_no_map_check():
    """The check runs for steps above 0.25/f_h only; the automatic step of these rods is
    held below it and is stable by the map too (radius <= 1 + 1e-9: round-off)."""
    for p in (_rod(1e-3), _rod(1e-3, rigid=False, zeta=0.0, damping=2e5), _rod(1e-3, both_ends=True)):
        p.h = None
        step = stepping.choose_step(p)
        assert step.h <= step.h_default * (1 + 1e-9)
        rows = contact_rows(p.body_a, p.body_b, p.contacts)
        om, ze, st = _modes(p)
        assert sm.spectral_radius(rows, om, ze, step.h, st) <= 1 + 1e-9


def test_the_h2_run_of_a_stable_step_is_checked_before_either_run(monkeypatch):
    """Stability is not monotone in h: the rigidly bolted rod is stable at 2.34e-3 s (radius 1)
    but at its h/2, 1.17e-3 s, a mode lies in an unstable window (radius 1.26). The error
    estimate's h/2 run is refused before either run starts (no call of the solver)."""
    from liftoff.transient import accuracy, solver

    p = _rod(2.34e-3)
    rows = contact_rows(p.body_a, p.body_b, p.contacts)
    om, ze, st = _modes(p)
    assert sm.spectral_radius(rows, om, ze, 2.34e-3, st) == pytest.approx(1.0, abs=1e-9)
    assert sm.spectral_radius(rows, om, ze, 1.17e-3, st) > 1.2
    runs = []
    real = solver._solve
    monkeypatch.setattr(solver, "_solve", lambda *a, **k: runs.append(1) or real(*a, **k))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(InputError, match=r"h = 0.00117 s is unstable with these contacts"):
            accuracy.solve_estimated(p)
    assert runs == []


def test_the_sets_checked_follow_the_release_schedule(monkeypatch):
    """The active sets are those the run passes through, each judged over its own steps
    (a review: sets the run never reaches refused stable runs). Toy vehicle on its pad, four
    rigid posts of three rows: bolted for the whole run, one set of all 12 rows; released
    before t0, one set of the 4 normal rows; released mid-run, both, the steps shared. A
    radius above 1 in the released set is refused naming it and its steps."""
    from liftoff.transient.examples import holddown_contacts, toy_pad, toy_vehicle

    a, b = toy_vehicle(), toy_pad()
    h = 1e-3
    for release, want in ((math.inf, [("bolted", 12, 1000)]), (-1.0, [("released", 4, 1000)]),
                          (0.4, [("bolted", 12, 400), ("released", 4, 600)])):
        cs = holddown_contacts(rigid=True, release_time=release)
        rows = contact_rows(a, b, cs)
        got = [(n, int(m.sum()), k) for n, m, k in sm.coupled_sets(rows, cs, 0.0, 1.0, h)]
        assert got == want, (release, got)
    cs = holddown_contacts(release_time=0.4)
    f_h, h0 = stepping.estimate_step(a, b, cs)
    h = 1.2 * h0                                  # the penalty posts' bolted map is stable here
    p = TransientProblem(a, b, cs, Forcing(gravity=(0, 0, -9.81)), t_end=1000 * h, h=h, initial="zero",
                         progress=False)
    p.contacts = holddown_contacts(release_time=400 * h)
    rows = contact_rows(a, b, p.contacts)
    om, ze, st = _modes(p)
    real = sm.spectral_radius
    monkeypatch.setattr(sm, "spectral_radius", lambda r, *a: 1.5 if r.n < rows.n else real(r, *a))
    with pytest.raises(InputError, match=r"\(every contact released, in contact\) has spectral radius 1.5, a "
                                         r"growth of .* over the 600 steps the run spends so"):
        stepping.check_step_map(p, rows, om, ze, h, st, f_h, h0)


def test_a_set_the_run_never_reaches_does_not_refuse_it():
    """The review's case: rigid posts released before the run (a drop onto the pad). At
    1.875 x 0.25/f_h the bolted set would be unstable (radius 1.32) but the run never has it;
    the released set is stable and the run is let through, bounded (its peak post force in
    the last 200 of 2,000 steps below twice that of the first 200)."""
    from liftoff.transient.examples import holddown_contacts, toy_pad, toy_vehicle

    a, b = toy_vehicle(), toy_pad()
    cs = holddown_contacts(rigid=True, release_time=-1.0)
    f_h, h0 = stepping.estimate_step(a, b, cs)
    h = 1.875 * h0
    rows = contact_rows(a, b, cs)
    p = TransientProblem(a, b, cs, Forcing(gravity=(0, 0, -9.81)), t_end=2000 * h, h=h, initial="zero",
                         progress=False)
    om, ze, st = _modes(p)
    assert sm.spectral_radius(rows, om, ze, h, st) > 1.3
    with pytest.warns(UserWarning, match="stable by its step map"):
        r = solve(p)
    F = np.abs(r.contact_force[:, rows.axial])
    late = F[-200:].max()
    assert np.isfinite(late) and late < 2 * F[:200].max()


def test_a_batch_checks_each_cases_release_schedule(monkeypatch):
    """Cases marched together share the step, chosen for problem 0, but their release times
    may differ, and with them the active sets the step map is checked in (a review: a case
    that transient.solve refuses was marched). Case 0 never releases; case 1 releases
    mid-run, through a set (the normal rows alone) made unstable here: refused naming it."""
    from liftoff.transient.batch import solve_batch
    from liftoff.transient.examples import holddown_contacts, toy_pad, toy_vehicle

    a, b = toy_vehicle(), toy_pad()
    f_h, h0 = stepping.estimate_step(a, b, holddown_contacts())
    h = 1.2 * h0

    def case(release):
        return TransientProblem(a, b, holddown_contacts(release_time=release), Forcing(gravity=(0, 0, -9.81)),
                                t_end=200 * h, h=h, initial="zero", progress=False)

    n_all = contact_rows(a, b, holddown_contacts()).n
    real = sm.spectral_radius
    monkeypatch.setattr(sm, "spectral_radius", lambda r, *x: 1.5 if r.n < n_all else real(r, *x))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(InputError, match=r"batch problem 1: time step .* \(every contact released, in contact\)"):
            solve_batch([case(math.inf), case(100 * h)])


def test_the_radius_is_computed_once_for_cases_that_share_it(monkeypatch):
    """A campaign's cases share bodies, rows and step: the map's eigenvalues (about 5 s on the
    default) are computed once, and again for anything that differs (here the step)."""
    p = _rod(6e-4)
    rows = contact_rows(p.body_a, p.body_b, p.contacts)
    om, ze, st = _modes(p)
    calls = []
    real = np.linalg.eigvals
    monkeypatch.setattr(np.linalg, "eigvals", lambda M: calls.append(1) or real(M))
    monkeypatch.setattr(sm, "_RADII", {})
    r1 = sm.spectral_radius(rows, om, ze, 6e-4, st)
    assert sm.spectral_radius(rows, om, ze, 6e-4, st) == r1 and len(calls) == 1
    sm.spectral_radius(rows, om, ze, 5e-4, st)
    assert len(calls) == 2
