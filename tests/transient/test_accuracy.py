"""Error estimates of peak loads and the accuracy setting (transient/accuracy.py), against
the closed form of a mass dropped on a one-sided spring (tests/transient/test_drop.py).

At the automatic step, eq. 12 gives four steps a period of the contact frequency: the
peak contact force comes out ~25 % low (issue 16: 22 %). The estimate 4/3 (F_h/2 - F_h)
must be within a factor 2 of that true error; with accuracy = 0.01 the step is halved
until the estimate is below 1 % of the peak, and the true error must then be below 1 %.
"""
import math

import numpy as np
import pytest

from liftoff.transient import (ContactPoint, ConvergenceError, Forcing, ModalBody, TransientProblem, ground, solve,
                               solve_estimated)
from liftoff.transient.accuracy import peak_errors

from .test_drop import G, G0, K, M, closed_form


def _drop(accuracy=None, t_end=0.25, h=None):
    mass = ModalBody("mass", omega=[0.0], zeta=[0.0], dof_labels=["m:Tz"], phi=[[1 / math.sqrt(M)]],
                     participation=[[0, 0, math.sqrt(M), 0, 0, 0]], rigid_body_mass=np.diag([M, M, M, 0, 0, 0]))
    spring = ContactPoint("spring", ["m:Tz"], [None], K, gap=G0, release_time=-math.inf)
    return TransientProblem(mass, ground(), [spring], Forcing(gravity=(0, 0, -G)), t_end=t_end, h=h, initial="zero",
                            progress=False, accuracy=accuracy)


def test_estimate_at_the_automatic_step_is_within_a_factor_2_of_the_true_error():
    fmax = closed_form()[1]
    est = solve_estimated(_drop())
    r = est.result
    period = 2 * math.pi / math.sqrt(K / M)
    true = fmax - r.contact_force[:, 0].max()
    estimate = est.force_max_error[0]
    print(f"\nh = T/{period / r.h:.2f}: peak {r.contact_force[:, 0].max():.2f} N (exact {fmax:.2f} N), "
          f"true error {true / fmax:+.3%}, estimate {estimate / fmax:+.3%}")
    assert 3.9 < period / r.h < 4.1                          # eq. 12: four steps a contact period
    assert 0.2 < true / fmax < 0.3                           # the 22 % (here 24.7 %)
    assert 0.5 < estimate / true < 2.0
    assert r.metadata["error_estimate"]["contact_force_max_error"] == pytest.approx([estimate], rel=1e-15)


def test_accuracy_one_percent_gives_a_peak_within_one_percent():
    fmax = closed_form()[1]
    r = solve(_drop(accuracy=0.01))
    true = abs(fmax - r.contact_force[:, 0].max()) / fmax
    meta = r.metadata["error_estimate"]
    print(f"\naccuracy 0.01: h = {r.h:.4g} s after {r.metadata['halvings']} halvings, estimated "
          f"{meta['worst_relative']:.3%}, true {true:.3%}")
    assert meta["worst_relative"] <= 0.01 and r.metadata["halvings"] >= 1
    assert true < 0.01


def test_accuracy_that_cannot_be_reached_is_an_error(monkeypatch):
    from liftoff.transient import accuracy

    monkeypatch.setattr(accuracy, "MAX_HALVINGS", 1)
    with pytest.raises(ConvergenceError, match=r"accuracy 1e-06 not reached after 1 halvings"):
        solve(_drop(accuracy=1e-6))


def test_peak_errors_of_a_second_order_sequence():
    """y_h = y + c h^2 exactly: the estimate 4/3 (y_h/2 - y_h) is the error y - y_h exactly."""
    t = np.linspace(0, 1, 101)
    y = np.column_stack([np.sin(3 * t), -np.cos(2 * t)])
    c, h = np.array([0.3, -0.2]), 0.01
    emax, emin = peak_errors(y + c * h ** 2, y + c * (h / 2) ** 2)
    # the differences are 3e-5 of values ~1: round-off 1e-16 / 3e-5 ~ 1e-11 relative
    assert emax == pytest.approx(-c * h ** 2, rel=1e-9) and emin == pytest.approx(-c * h ** 2, rel=1e-9)


def test_memory_of_the_run_and_its_h2_check_is_counted_once_before_both():
    """The coarse run and its h/2 check are held together: 3 coarse-run histories (1 + 2).
    A limit below that refuses at once; above it both run (issue 27: the h/2 run was counted
    as 3 of its own, 6 coarse, and refused after the coarse run had taken its time and memory)."""
    from dataclasses import replace

    from liftoff.core.errors import ResourceError
    from liftoff.transient import solve_estimated
    from liftoff.transient.stepping import choose_step, memory_estimate

    pr = _drop(t_end=0.25)
    n = choose_step(pr).n_steps
    unit = memory_estimate(pr, n, 1)["histories"]
    # the rest as the pair counts it (its output copies: the h/2 run's, twice one run's)
    rest = sum(v for k, v in memory_estimate(pr, n, 3).items() if k != "histories")
    est = solve_estimated(replace(pr, memory_limit=4.0 * unit + rest))          # 3 units needed: runs
    assert est.check.time.size == 2 * n + 1
    with pytest.raises(ResourceError, match="the transient needs about"):
        solve_estimated(replace(pr, memory_limit=2.5 * unit + rest))


def test_the_pair_marched_together_is_the_pair_marched_in_turn(monkeypatch):
    """The run at h and its h/2 check march together on two threads (the kernel releases
    the GIL): the same results, bit for bit, as one after the other (two independent runs
    of the same arithmetic), with and without the accuracy loop."""
    from liftoff.transient import accuracy, kernel

    assert kernel.march.targetoptions.get("nogil") is True
    for accuracy_setting in (None, 0.01):
        runs = {}
        for together in (True, False):
            monkeypatch.setattr(accuracy, "CONCURRENT_PAIR", together)
            runs[together] = solve_estimated(_drop(accuracy=accuracy_setting, t_end=0.5))
        a, b = runs[True], runs[False]
        assert a.result.h == b.result.h and a.check.h == b.check.h
        for x, y in ((a.result, b.result), (a.check, b.check)):
            assert np.array_equal(x.contact_force, y.contact_force) and np.array_equal(x.time, y.time)
        assert a.relative == b.relative


def test_a_failure_of_either_run_of_the_pair_stops_the_other():
    """A failed run of the pair stops the other at its next chunk (no run outlives the
    call): the h/2 run's error reaches the caller although the h run was still marching,
    and the h run's error stops the h/2 run (its Cancelled is not the error raised)."""
    import threading

    from liftoff.core.errors import InputError
    from liftoff.transient.accuracy import _first_pair
    from liftoff.transient.solver import Cancelled
    from liftoff.transient.stepping import choose_step

    pr = _drop()
    step = choose_step(pr)
    seen = {}

    def marching(stop):                          # a run that marches until it is stopped
        if not stop.wait(30.0):
            raise AssertionError("never stopped")
        seen[threading.current_thread().name] = True
        raise Cancelled("stopped")

    def fine_fails(problem, st, runs, stop=None):
        if st.h < step.h:
            raise InputError("the h/2 run's own error")
        return marching(stop)

    with pytest.raises(InputError, match="the h/2 run's own error"):
        _first_pair(pr, pr, step, fine_fails)

    def coarse_fails(problem, st, runs, stop=None):
        if st.h == step.h:
            raise InputError("the h run's own error")
        return marching(stop)

    with pytest.raises(InputError, match="the h run's own error"):
        _first_pair(pr, pr, step, coarse_fails)
    assert seen == {"MainThread": True, "liftoff-h/2": True}      # each run was stopped by the other's failure
    assert not any(t.name == "liftoff-h/2" for t in threading.enumerate())


def test_an_interrupt_while_waiting_for_the_h2_run_stops_it(monkeypatch):
    """SIGTERM or Ctrl-C in the calling thread while it waits for the h/2 run (the h run
    done) stops the h/2 run too: the interrupt is raised and no run outlives the call."""
    import threading

    from liftoff.transient import accuracy
    from liftoff.transient.solver import Cancelled
    from liftoff.transient.stepping import choose_step

    pr = _drop()
    step = choose_step(pr)
    stopped = []

    def solve_at(problem, st, runs, stop=None):
        if st.h == step.h:
            return "coarse"                      # the h run ends at once
        if not stop.wait(30.0):                  # the h/2 run marches until stopped
            raise AssertionError("never stopped")
        stopped.append(True)
        raise Cancelled("stopped")

    join = threading.Thread.join
    calls = []

    def interrupted_join(self, timeout=None):
        calls.append(self.name)
        if len(calls) == 1 and self.name == "liftoff-h/2":
            raise KeyboardInterrupt               # as the SIGTERM handler's exception, raised in the wait
        return join(self, timeout)

    monkeypatch.setattr(threading.Thread, "join", interrupted_join)
    with pytest.raises(KeyboardInterrupt):
        accuracy._first_pair(pr, pr, step, solve_at)
    monkeypatch.setattr(threading.Thread, "join", join)
    assert stopped == [True]
    assert not any(t.name == "liftoff-h/2" for t in threading.enumerate())


# ------------------------------------------------------------------ several cases in order
def _cases():
    return [_drop(t_end=0.3), None, _drop(t_end=0.4), _drop(t_end=0.5)]


def _no_ahead_thread():
    import threading

    return not any(t.name == "liftoff-h/2-ahead" for t in threading.enumerate())


def test_estimates_in_order_are_the_estimates_one_by_one():
    """EstimatesInOrder (the h/2 runs one case ahead on a second thread) gives each case
    the estimate solve_estimated gives it, bit for bit (the same runs of the same
    arithmetic); an index left to the caller (None) is refused; no thread outlives it."""
    from liftoff.transient.accuracy import EstimatesInOrder

    probs = _cases()
    with EstimatesInOrder(probs) as ahead:
        assert ahead.concurrent
        got = {k: ahead.get(k) for k in (0, 2, 3)}
        with pytest.raises(ValueError, match="solved by the caller"):
            ahead.get(1)
        with pytest.raises(ValueError, match="taken already"):
            ahead.get(2)
        assert ahead._done == {}         # each h/2 result dropped when taken
    assert _no_ahead_thread()
    for k, est in got.items():
        ref = solve_estimated(probs[k])
        for x, y in ((est.result, ref.result), (est.check, ref.check)):
            assert x.h == y.h and np.array_equal(x.time, y.time) and np.array_equal(x.contact_force, y.contact_force)
        assert est.relative == ref.relative
        for key in ("error_estimate", "accuracy", "halvings"):
            assert est.result.metadata[key] == ref.result.metadata[key]
    with pytest.raises(ValueError, match="has an accuracy"):
        with EstimatesInOrder([_drop(accuracy=0.01), _drop()]):
            pass


MARCHES_UNTIL_STOPPED = 400.0     # _logged: the h/2 run of this t_end marches until it is stopped


def _logged(monkeypatch, log, fail_fine_of=None, coarse_waits_for=None):
    """solver._solve, logging (t_end, 'h' or 'h/2', event) and failing the h/2 run of the
    problem whose t_end is ``fail_fine_of``; the run at h of the problem whose t_end is
    ``coarse_waits_for[0]`` starts once ``coarse_waits_for[1]`` is in the log."""
    import time

    from liftoff.core.errors import InputError
    from liftoff.transient import solver
    from liftoff.transient.stepping import choose_step

    real = solver._solve

    def logged(problem, step=None, runs=1, stop=None, gate=None):
        kind = "h/2" if step.h < choose_step(problem).h else "h"
        log.append((problem.t_end, kind, "start"))
        if kind == "h/2" and problem.t_end == fail_fine_of:
            log.append((problem.t_end, kind, "failed"))
            raise InputError(f"the h/2 run of t_end {problem.t_end} fails")
        if coarse_waits_for and kind == "h" and problem.t_end == coarse_waits_for[0]:
            for _ in range(3000):
                if coarse_waits_for[1] in log:
                    break
                time.sleep(0.01)
        if kind == "h/2" and problem.t_end == MARCHES_UNTIL_STOPPED:
            if not stop.wait(30.0):
                raise AssertionError("never stopped")
            log.append((problem.t_end, kind, "cancelled"))
            raise solver.Cancelled("stopped")
        try:
            return real(problem, step, runs, stop, gate)
        except solver.Cancelled:
            log.append((problem.t_end, kind, "cancelled"))
            raise

    monkeypatch.setattr(solver, "_solve", logged)


def test_the_second_thread_runs_at_most_one_case_ahead(monkeypatch):
    import time

    from liftoff.transient.accuracy import EstimatesInOrder

    log: list = []
    _logged(monkeypatch, log)
    probs = _cases()
    with EstimatesInOrder(probs) as ahead:
        time.sleep(0.5)                  # case 0's h/2 run is done; case 2's waits for get(0)
        log.append("get 0")
        ahead.get(0)
        time.sleep(0.5)                  # case 2's h/2 run marches while the caller works on case 0
        log.append("get 2")
        ahead.get(2)
        log.append("get 3")
        ahead.get(3)
    fine = [e for e in log if isinstance(e, tuple) and e[1] == "h/2"]
    assert [e[0] for e in fine] == [0.3, 0.4, 0.5]
    assert log.index((0.3, "h/2", "start")) < log.index("get 0")
    assert log.index("get 0") < log.index((0.4, "h/2", "start")) < log.index("get 2")
    assert log.index("get 2") < log.index((0.5, "h/2", "start"))


def test_a_failed_h2_run_is_raised_for_its_case_and_stops_everything(monkeypatch):
    """The h/2 run of case 2 fails: case 0 is still delivered, get(2) raises that error, and
    the thread ends (no case 3 run); leaving the block early stops a run still marching."""
    from liftoff.core.errors import InputError
    from liftoff.transient.accuracy import EstimatesInOrder

    log: list = []
    _logged(monkeypatch, log, fail_fine_of=0.4)
    with EstimatesInOrder(_cases()) as ahead:
        ahead.get(0)
        with pytest.raises(InputError, match="the h/2 run of t_end 0.4 fails"):
            ahead.get(2)
    assert _no_ahead_thread() and (0.5, "h/2", "start") not in log


def test_a_failed_h2_run_does_not_fail_the_case_before_it(monkeypatch):
    """Case 2's h/2 run fails while the caller's run at h of case 0 still marches: case 0 is
    delivered, the same as solve_estimated gives it, and get(2) raises case 2's own error."""
    from liftoff.core.errors import InputError
    from liftoff.transient.accuracy import EstimatesInOrder

    log: list = []
    probs = _cases()
    ref = solve_estimated(probs[0])
    _logged(monkeypatch, log, fail_fine_of=0.4, coarse_waits_for=(0.3, (0.4, "h/2", "failed")))
    with EstimatesInOrder(probs) as ahead:
        est = ahead.get(0)
        assert (0.4, "h/2", "failed") in log
        with pytest.raises(InputError, match="the h/2 run of t_end 0.4 fails"):
            ahead.get(2)
    assert np.array_equal(est.result.contact_force, ref.result.contact_force)
    assert np.array_equal(est.check.contact_force, ref.check.contact_force)
    assert _no_ahead_thread()


def test_leaving_the_block_stops_a_run_still_marching(monkeypatch):
    from liftoff.transient.accuracy import EstimatesInOrder

    log: list = []
    _logged(monkeypatch, log)
    long = [_drop(t_end=0.3), _drop(t_end=MARCHES_UNTIL_STOPPED)]
    with pytest.raises(RuntimeError, match="the caller's own failure"):
        with EstimatesInOrder(long) as ahead:
            ahead.get(0)
            while (400.0, "h/2", "start") not in log:
                pass
            raise RuntimeError("the caller's own failure")
    assert _no_ahead_thread() and (400.0, "h/2", "cancelled") in log


def test_paused_holds_the_second_thread_between_chunks(monkeypatch):
    """While paused() is held (a fork in workflows/beside.py) the second thread marches no
    chunk; it marches each chunk (and runs its set-up) marked busy, so paused() waits for
    the next chunk boundary."""
    import threading
    import time

    from liftoff.transient import solver
    from liftoff.transient.accuracy import EstimatesInOrder

    calls: list = []
    real = solver.march

    def march(*args):
        if threading.current_thread().name == "liftoff-h/2-ahead":
            calls.append(ahead.gate._busy)
            time.sleep(0.02)             # 51 chunks: a run of about a second
        return real(*args)

    monkeypatch.setattr(solver, "march", march)
    ahead = EstimatesInOrder([_drop(t_end=2000.0), _drop(t_end=0.3)])   # bound before its thread starts
    with ahead:
        for _ in range(5000):
            if len(calls) >= 2 or ahead._error is not None:
                break
            time.sleep(0.001)
        assert ahead._error is None and len(calls) >= 2
        with ahead.paused():
            n = len(calls)
            time.sleep(0.3)
            assert len(calls) == n
        for _ in range(5000):
            if len(calls) >= n + 2:
                break
            time.sleep(0.001)
        assert n + 2 <= len(calls) < 40  # marching again, and still marching: stopped by the block's end
    assert all(calls) and _no_ahead_thread()


def test_halved_runs_carry_their_own_stability_margin():
    """The runs at h/2 (the error estimate's check, the accuracy halvings) carry the penalty
    coupling's stability margin at their own step, not the one at h (the results file
    recorded the coarse step's margin and "eq. 12" after three halvings); an accuracy
    halving's result says the step was set by the accuracy."""
    from liftoff.transient.assembly import contact_rows
    from liftoff.transient.stepping import _modes, choose_step, coupling_margin

    p = _drop(accuracy=0.01)
    step = choose_step(p)
    half = step.halved(p, "accuracy")
    omega, zeta, static = _modes(p)
    rows = contact_rows(p.body_a, p.body_b, p.contacts)
    assert half.h == 0.5 * step.h and half.n_steps == 2 * step.n_steps and half.governed_by == "accuracy"
    assert half.margin == coupling_margin(rows, omega, zeta, 0.5 * step.h, static) != step.margin
    r = solve(p)
    assert r.metadata["halvings"] >= 1                      # (this drop needs at least one)
    assert r.metadata["step_governed_by"] == "accuracy"
    assert r.metadata["stability_margin"] == pytest.approx(coupling_margin(rows, omega, zeta, r.h, static))


def test_memory_check_counts_the_accuracy_pairs_modal_histories():
    """With an accuracy target the finer run keeps its modal histories too (it may become
    the result), so the pair holds three coarse runs' of them, as of its histories: a limit
    that fits the histories and one run's modal histories refuses at once (counted once
    before, the pair ran past its estimate); with room for three runs' it runs. An error
    estimate alone (no target) keeps one run's modal histories: it runs within that limit."""
    from dataclasses import replace

    from liftoff.core.errors import ResourceError
    from liftoff.transient import solve_estimated
    from liftoff.transient.stepping import choose_step, memory_estimate

    pr = replace(_drop(t_end=0.25), keep_modal=True)
    n = choose_step(pr).n_steps
    parts = memory_estimate(pr, n, 1)
    unit, modal = parts["histories"], parts["modal histories (keep_modal)"]
    rest = sum(v for k, v in memory_estimate(pr, n, 3, 3).items()
               if k not in ("histories", "modal histories (keep_modal)"))      # (the pair's output copies)
    assert memory_estimate(pr, n, 3, 3)["modal histories (keep_modal)"] == 3 * modal
    tight = 3.2 * unit + 1.2 * modal + rest           # the histories of the pair, one run's modal
    solve_estimated(replace(pr, memory_limit=tight))   # no target: the h/2 run keeps no modal histories
    with pytest.raises(ResourceError, match="modal histories|the transient needs about"):
        solve_estimated(replace(pr, memory_limit=tight, accuracy=0.5))
    est = solve_estimated(replace(pr, memory_limit=3.2 * unit + 3.2 * modal + rest, accuracy=0.5))
    assert est.result.time.size == n + 1
