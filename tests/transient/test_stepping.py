"""The step rule, the stability criterion and the run-size guard (transient/stepping.py).

References: the number of steps and the step are integer arithmetic on t_end - t0; the
stability limit is checked against the solver's own behaviour on the vehicle-on-pad
example (bounded just below the limit, diverging just above it), independently of the
criterion that computes it; the memory estimate against the arrays the solver allocates.
"""
import math
import warnings
from pathlib import Path

import numpy as np
import pytest

from liftoff.config import load_twobody
from liftoff.transient import (ContactPoint, ConvergenceError, Forcing, InputError, ResourceError, TransientProblem,
                               choose_step, estimate_step, ground, solve)
from liftoff.transient.assembly import contact_rows
from liftoff.transient.examples import spring_block
from liftoff.transient.stepping import coupling_margin, memory_estimate, stability_limit

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def _block(t_end=0.1, h=None, k=1e5, t0=0.0, **kw):
    """A 2 kg block on a 100 N/m spring (1.1 Hz) on a penalty contact of k N/m to ground (f_h = 35.6 Hz at 1e5)."""
    block = spring_block(2.0, 100.0)
    return TransientProblem(block, ground(), [ContactPoint("c", ["block:Tz"], [None], k)], Forcing(), t_end=t_end,
                            h=h, t0=t0, progress=False, **kw)


def test_automatic_steps_end_exactly_at_t_end():
    p = _block(t_end=0.1)
    f_h, h_max = estimate_step(p.body_a, p.body_b, p.contacts)
    step = choose_step(p)
    assert step.n_steps == math.ceil(0.1 / h_max) and step.h <= h_max and step.h == 0.1 / step.n_steps
    r = solve(p)
    assert r.time[-1] == 0.1 and r.time.size == step.n_steps + 1 and np.all(np.diff(r.time) > 0)


def test_a_run_shorter_than_the_step_is_one_step_to_t_end():
    """t_end = 1e-12 s used to give a result at 5e-4 s (one eq.-12 step past t_end)."""
    r = solve(_block(t_end=1e-12))
    assert r.time.tolist() == [0.0, 1e-12]


def test_a_soft_contact_does_not_give_an_absurd_step():
    """K_C = 1e-6 N/m: eq. 12 alone gives h = 0.25/f_h = 2.2e3 s; the step is bounded by the
    body's own frequency (sqrt(100/2) rad/s: 0.25/f_s = 0.222 s) and the run."""
    p = _block(t_end=1.2, k=1e-6)
    step = choose_step(p)
    f_s = math.sqrt(50.0) / (2 * math.pi)
    assert step.h_default > 2e3 and step.n_steps == math.ceil(1.2 / (0.25 / f_s)) and step.h == 1.2 / step.n_steps
    assert solve(p).time[-1] == 1.2


def test_mode_samples_set_the_steps_a_period_of_the_highest_mode():
    """The same soft contact with the highest mode sampled 2 and 8 times a period: n =
    ceil(span f_s m), integer arithmetic; the run records m; below the Nyquist rate (2) the
    problem is refused at construction, naming the key."""
    f_s = math.sqrt(50.0) / (2 * math.pi)
    for m in (2.0, 8.0):
        step = choose_step(_block(t_end=1.2, k=1e-6, mode_samples=m))
        assert step.n_steps == math.ceil(1.2 * f_s * m) and step.mode_samples == m
    assert solve(_block(t_end=1.2, k=1e-6, mode_samples=2.0)).metadata["mode_samples"] == 2.0
    # a stiff contact: eq. 12 (0.25/f_h, f_h = 35.6 Hz) governs whatever m, the block's 1.1 Hz mode being slower
    assert choose_step(_block(mode_samples=2.0)).n_steps == choose_step(_block()).n_steps
    with pytest.raises(InputError, match=r"mode_samples = 1.5 steps a period of the highest mode must be from 2 "):
        _block(mode_samples=1.5)
    with pytest.raises(InputError, match=r"mode_samples = 100.0 .* to 64 \(a finer step: give h or accuracy\)"):
        _block(mode_samples=100.0)
    # a given h: m has no effect, and the run does not record one
    assert solve(_block(t_end=0.1, h=1e-3, mode_samples=2.0)).metadata["mode_samples"] is None
    # the scenario's [time] reaches the problem through its one translation (TimeSpan.problem)
    from liftoff.config.sections import TimeSpan

    blk = _block()
    assert TimeSpan(t_end=1.2, mode_samples=2.0).problem(blk.body_a, blk.body_b, blk.contacts, Forcing(),
                                                         progress=False).mode_samples == 2.0


def test_a_given_step_that_does_not_divide_the_run_is_rounded_down():
    with pytest.warns(UserWarning, match=r"does not divide the run .* 34 equal steps of 0.00294118 s"):
        step = choose_step(_block(t_end=0.1, h=0.003))
    assert step.n_steps == 34 and step.h == 0.1 / 34 and step.h_requested == 0.003
    with warnings.catch_warnings():
        warnings.simplefilter("error")          # a step that divides the run up to round-off: no warning
        assert choose_step(_block(t_end=1.2, h=1e-4)).n_steps == 12000


def test_the_time_axis_must_resolve_the_step():
    """t0 = 1e15 s: floats there are 0.125 s apart; a 1e-3 s step would give a time axis with
    repeated and non-increasing entries."""
    with pytest.raises(InputError, match=r"below the resolution of the time axis: floats near t = 1e\+15 s are 0.125 s"):
        choose_step(_block(t0=1e15, t_end=1e15 + 1.0, h=1e-3))
    assert choose_step(_block(t0=1e5, t_end=1e5 + 0.1, h=1e-3)).n_steps == 100   # 1.5e-11 s apart: fine


def test_stability_limit_against_the_solver_itself(monkeypatch):
    """vehicle_on_pad: the criterion puts the limit at 0.80 x 0.551/f_h (the bodies' stiffness
    lowers it from the rigid-body value). With the up-front check off, the solver stays
    bounded at 0.98 x the limit (peak post force as at the default step, +-2 %) and diverges
    at 1.05 x the limit (the growth guard stops it). The step map's radius agrees."""
    from liftoff.transient import stepping

    sc = load_twobody(EXAMPLES / "vehicle_on_pad" / "scenario.toml", progress=False)
    p = sc.problem
    rows = contact_rows(p.body_a, p.body_b, p.contacts)
    om, ze = np.r_[p.body_a.omega, p.body_b.omega], np.r_[p.body_a.zeta, p.body_b.zeta]
    f_h, h0 = estimate_step(p.body_a, p.body_b, p.contacts)
    rigid = stepping.STABILITY / f_h
    limit = stability_limit(rows, om, ze, h0, rigid)
    print(f"\nf_h {f_h:.1f} Hz, rigid-body limit {rigid:.4g} s, criterion {limit:.4g} s ({limit / rigid:.3f})")
    assert coupling_margin(rows, om, ze, rigid) < -1 < coupling_margin(rows, om, ze, h0)
    assert 0.75 < limit / rigid < 0.85
    # the step map's spectral radius (transient/step_map.py) agrees: no penalty row is damped
    # here, where the margin's criterion is exact (1e-9: round-off of the map's eigenvalues)
    from liftoff.transient.step_map import spectral_radius

    assert spectral_radius(rows, om, ze, 0.98 * limit) <= 1 + 1e-9 < 1.01 < spectral_radius(rows, om, ze, 1.05 * limit)
    peak = np.abs(solve(p).contact_force).max()
    monkeypatch.setattr(stepping, "coupling_margin", lambda *args: 0.0)
    monkeypatch.setattr(stepping, "check_step_map", lambda *args: 1.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        p.h = 0.98 * limit
        r = solve(p)
        assert abs(np.abs(r.contact_force).max() / peak - 1) < 0.02
        p.h = 1.05 * limit
        with pytest.raises(ConvergenceError, match="diverged"):
            solve(p)


def test_memory_guard_names_the_estimate_and_the_override():
    """1e8 steps of the block: ~7 GB of histories by the estimate; refused under a 1 GB limit
    before anything is allocated, accepted (estimate only) with the limit raised."""
    p = _block(t_end=1e4, h=1e-4, memory_limit=1e9)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(ResourceError, match=r"needs about .* GB .* limit is 1 GB.*--max-memory"):
            solve(p)
    est = memory_estimate(p, 100_000_000)
    # contact force (1 column) + time + iterations (int32) + state (int8) + rigid-body motion of the block (6)
    assert math.isclose(est["histories"], 8.0 * (1e8 + 1) * (1 + 1 + 0.5 + 0.125 + 6), rel_tol=1e-12)


def test_memory_estimate_matches_the_arrays_of_a_run():
    """The histories the estimate counts are the arrays of a result (within the 6-column rigid-body
    block the estimate counts for a body with modes)."""
    p = _block(t_end=0.05, h=1e-4, outputs={"a": ["block:Tz"]}, keep_modal=True)
    r = solve(p)
    n_t = r.time.size
    arrays = [r.time, r.contact_force, r.contact_state, r.iterations, r.displacement["a"], r.velocity["a"],
              r.acceleration["a"], r.rigid_body_motion_a] + list(r.modal.values())
    actual = sum(a.nbytes for a in arrays if a is not None)
    est = memory_estimate(p, n_t - 1)
    # byte counts: integers below 2^53, exact in floats but for the 0.125 and 0.5 fractions' sums
    assert math.isclose(est["histories"] + est["modal histories (keep_modal)"], actual, rel_tol=1e-12)
    # the result's output columns are copies of the kernel's, made while those are held: counted once more
    copies = sum(a.nbytes for a in (r.displacement["a"], r.velocity["a"], r.acceleration["a"], r.rigid_body_motion_a))
    assert math.isclose(est["output copies"], copies, rel_tol=1e-12)


def test_keep_modal_q_is_one_column_a_mode_and_the_error_check_keeps_none():
    """keep_modal = "q" holds the modal displacements alone: a third of True's modal bytes,
    the q arrays of the result exactly; the h/2 run of an error estimate keeps no modal
    histories (it is read for its peaks only), so a run with its estimate holds one set."""
    from dataclasses import replace

    from liftoff.transient import solve_estimated

    p = _block(t_end=0.05, h=1e-4, outputs={"a": ["block:Tz"]}, keep_modal="q")
    r = solve(p)
    est = memory_estimate(p, r.time.size - 1)["modal histories (keep_modal)"]
    assert est == sum(a.nbytes for a in r.modal.values() if a is not None)
    assert math.isclose(memory_estimate(replace(p, keep_modal=True), r.time.size - 1)["modal histories (keep_modal)"],
                        3 * est, rel_tol=1e-12)
    e = solve_estimated(p)
    assert e.result.modal and not e.check.modal
    np.testing.assert_array_equal(e.result.contact_force, r.contact_force)


def test_the_step_records_the_rule_that_set_it(monkeypatch):
    """StepChoice.governed_by and the results' metadata name the rule that set h: eq. 12 for
    the stiff contact (35.6 Hz against the block's 1.1 Hz mode), the highest mode's sampling
    for the soft one, the run's length for a run shorter than both, "given" for a given h;
    stability_halvings counts the automatic step's halvings (here forced by a margin that
    is unstable twice)."""
    assert choose_step(_block(t_end=1.2)).governed_by == "eq. 12"
    assert choose_step(_block(t_end=1.2, k=1e-6)).governed_by == "mode samples"
    assert choose_step(_block(t_end=1e-3)).governed_by == "run"
    r = solve(_block(t_end=0.1, h=1e-3))
    assert r.metadata["step_governed_by"] == "given" and r.metadata["stability_halvings"] == 0
    from liftoff.transient import stepping

    n_stable = choose_step(_block(t_end=1.2)).n_steps
    margins = iter([-2.0, -1.5, 0.0])
    monkeypatch.setattr(stepping, "coupling_margin", lambda *args: next(margins))
    step = choose_step(_block(t_end=1.2))
    assert step.stability_halvings == 2 and step.governed_by == "eq. 12" and step.n_steps == 4 * n_stable


def test_growth_guard_stops_a_run_whose_energy_or_forces_are_not_finite():
    """transient/guard.py: a run diverged past any float has a rigid-body mode's q^2 = inf,
    whose 0 x inf in the strain energy was NaN, and NaN > bound is False: the guard let a
    result with modal displacements of 1e232 through. Now a non-finite energy, or a
    non-finite force in any row (rigid rows too, which no energy bounds), stops the run;
    a finite state within the bound still passes."""
    from types import SimpleNamespace

    from liftoff.core.errors import ConvergenceError
    from liftoff.transient.guard import GrowthGuard

    modal = SimpleNamespace(w2=np.array([0.0, 4.0e4]), U=np.zeros((2, 0)), V=np.zeros((0, 2)), until=np.zeros(0),
                            const=np.array([1.0, 0.0]), tk=np.zeros(0), Pk=np.zeros((0, 2)))
    rows = SimpleNamespace(compliance=np.array([0.0, 1e-9]))        # a rigid row and a penalty row

    def state(q, v):
        return SimpleNamespace(q=np.array(q, float), v=np.array(v, float), f=np.zeros(2),
                               active=np.array([True, True]))

    g = GrowthGuard(rows, modal, state([0.0, 0.0], [0.0, 0.0]), 1e-4, float("inf"))
    g.start(0.0, 1.0)
    times, ok_forces = np.array([0.5]), np.zeros((1, 2))
    g.check(0.5, state([0.1, 1e-3], [0.5, 0.0]), ok_forces, times)             # within the bound
    with np.errstate(over="ignore"):
        huge = state([1e200, 1e-3], [0.0, 0.0])                                 # q^2 = inf on the rigid mode
    g.check(0.5, huge, ok_forces, times)       # a rigid mode's displacement is no energy: q = 1e200 alone passes
    with pytest.raises(ConvergenceError, match="the solution diverged: its energy"):
        g.check(0.5, state([1e200, 1e200], [0.0, 0.0]), ok_forces, times)       # elastic q^2 = inf
    with pytest.raises(ConvergenceError, match="the solution diverged: its energy"):
        g.check(0.5, state([0.0, 0.0], [np.nan, 0.0]), ok_forces, times)        # NaN energy
    with pytest.raises(ConvergenceError, match=r"a contact force is nan at t = 0.5 s"):
        g.check(0.5, state([0.0, 0.0], [0.0, 0.0]), np.array([[np.nan, 0.0]]), times)   # a rigid row's NaN


def test_a_given_step_runs_where_the_contact_model_has_no_frequency():
    """A rigid body held by a rigid row has no contact frequency (eq. 12 gives no step): the
    automatic step is refused, naming h; a given h was refused the same way, though any h is
    exact there. Given, it runs: the row carries the weight, m g = 9.81 N on a 1 kg rod."""
    from dataclasses import replace

    from liftoff.core.errors import InputError
    from liftoff.transient import ContactPoint, Forcing, TransientProblem, solve
    from liftoff.transient.body import ground
    from liftoff.transient.examples import free_free_rod

    rod = free_free_rod(1.0, 1e9, 1000.0, 1e-3, 1, name="r")            # its rigid mode alone, 1 kg
    c = [ContactPoint("c", ["end0:Tz"], [None], rigid=True)]
    p = TransientProblem(rod, ground(), c, Forcing(gravity=(0.0, 0.0, -9.81)), t_end=0.1, progress=False)
    with pytest.raises(InputError, match="give h explicitly"):
        solve(p)
    r = solve(replace(p, h=1e-3))
    assert r.time.size == 101 and np.allclose(r.contact_force[:, 0], 9.81, rtol=1e-12)
