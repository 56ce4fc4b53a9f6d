"""Error estimates of peak values by step halving, and a step chosen for an accuracy.

The scheme is second order in h (section 2.3; tests/transient/test_monolithic.py), so a
value y computed with step h and again with h/2 has y_h - y ~ C h^2 and
y_{h/2} - y ~ C h^2/4 (Richardson). The error of the value reported, y_h, is then
estimated as

    err(y_h) ~ y - y_h ~ 4/3 (y_{h/2} - y_h).

It is an estimate, not a bound: it assumes the asymptotic range of the scheme. Through
an impact or an active-set change mid-step the error depends on where in the step the
event falls, so with only a few steps per contact period the estimate is indicative
(tests/transient/test_accuracy.py measures it on a mass dropped on a one-sided spring).
The second run costs twice the first; a run with its estimate costs three times one run
of CPU. The run at h and the first run at h/2 are independent: they march together, the
h/2 run on a second thread (the compiled kernel releases the GIL; ``CONCURRENT_PAIR``), so
on two free cores the pair takes the time of the h/2 run alone, two thirds of the three.

With ``problem.accuracy`` set, the step is halved (from the automatic or given step,
which stays the stability bound) until the estimated error of every peak (maximum and
minimum) of every contact force direction is below ``accuracy`` times the largest
absolute contact force of its unit (N, N m) in the run.
"""
from __future__ import annotations

import os
from contextlib import contextmanager
from dataclasses import dataclass, replace

import numpy as np

from liftoff.core.errors import ConvergenceError

from .assembly import contact_rows
from .model import TransientProblem
from .result import TransientResult
from .stepping import choose_step

RICHARDSON = 4.0 / 3.0   # err(y_h) ~ RICHARDSON (y_{h/2} - y_h) for a second-order scheme
MAX_HALVINGS = 12        # the accuracy loop stops (ConvergenceError) after this many halvings
#: march the run at h and the first run at h/2 together on two threads (False, or the
#: environment's LIFTOFF_CONCURRENT_PAIR=0: one after the other, on one core; the results
#: are the same, bit for bit)
CONCURRENT_PAIR = os.environ.get("LIFTOFF_CONCURRENT_PAIR", "1") != "0"


def peak_errors(y_h: np.ndarray, y_half: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(error of the max, error of the min) of each column of y_h (n_t, k), estimated from
    the same histories at h/2 (module docstring): y - y_h, signed."""
    y_h, y_half = np.asarray(y_h), np.asarray(y_half)
    if y_h.shape[0] == 0:
        return np.zeros(y_h.shape[1:]), np.zeros(y_h.shape[1:])
    return RICHARDSON * (y_half.max(axis=0) - y_h.max(axis=0)), RICHARDSON * (y_half.min(axis=0) - y_h.min(axis=0))


def error_estimate(value_h: float, value_half: float) -> float:
    """The estimated error y - y_h of one peak value (module docstring)."""
    return RICHARDSON * (float(value_half) - float(value_h))


@dataclass
class Estimated:
    """A run at step h (``result``, the one reported and saved) and the same run at h/2
    (``check``), with the estimated errors of the peak contact forces (signed, per column,
    N or N m) and the worst of them relative to the largest force of its unit."""

    result: TransientResult
    check: TransientResult
    force_max_error: np.ndarray
    force_min_error: np.ndarray
    relative: float

    def metadata(self) -> dict:
        """What the result file keeps of the estimate (JSON-able)."""
        return {"method": "Richardson, order 2, from a second run at h/2: err = 4/3 (y_h/2 - y_h); an estimate",
                "h_check": self.check.h, "contact_force_max_error": self.force_max_error.tolist(),
                "contact_force_min_error": self.force_min_error.tolist(), "worst_relative": self.relative}


def _relative(result: TransientResult, emax: np.ndarray, emin: np.ndarray) -> float:
    """The worst |error| of a contact-force peak over the largest |force| of its unit."""
    units = np.array([d.unit for d in result.contact_directions])
    worst = 0.0
    for u in set(units.tolist()):
        cols = units == u
        scale = float(np.abs(result.contact_force[:, cols]).max()) if result.contact_force.size else 0.0
        err = float(max(np.abs(emax[cols]).max(), np.abs(emin[cols]).max()))
        if scale > 0:
            worst = max(worst, err / scale)
    return worst


def _estimate(coarse: TransientResult, fine: TransientResult) -> Estimated:
    emax, emin = peak_errors(coarse.contact_force, fine.contact_force)
    est = Estimated(coarse, fine, emax, emin, _relative(coarse, emax, emin))
    coarse.metadata["error_estimate"] = est.metadata()
    return est


def solve_estimated(problem: TransientProblem) -> Estimated:
    """Run ``problem`` at its step h and at h/2; with ``problem.accuracy``, halve h until
    the estimated peak errors meet it (module docstring). The result at h is reported."""
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1, user_api="blas"):   # as solve(): the same arithmetic, bit for bit
        return _solve_estimated(problem)


def _solve_estimated(problem: TransientProblem) -> Estimated:
    from .solver import _solve

    rows = contact_rows(problem.body_a, problem.body_b, problem.contacts)
    step = choose_step(problem, rows)
    # memory, in histories of the coarse run: the coarse run and the h/2 run (twice its time
    # points) are held together, 3 coarse = 1.5 fine; checked before the coarse run starts, so
    # a pair that cannot fit is refused at once, not after the coarse run (issue 27)
    # the h/2 run is a check: it keeps modal histories only where it may become the result
    check = problem if problem.accuracy is not None else replace(problem, keep_modal=False)
    coarse, fine = _first_pair(problem, check, step, _solve)
    for k in range(MAX_HALVINGS + 1):
        if k:
            est = None                       # (the run before's estimate let go: only coarse and the next held)
            fine = _solve(check, step.halved(check, "accuracy"), runs=1.5)
        est = _estimate(coarse, fine)
        if problem.accuracy is None or est.relative <= problem.accuracy:
            coarse.metadata["accuracy"] = problem.accuracy
            coarse.metadata["halvings"] = k
            return est
        if k == MAX_HALVINGS:
            break
        coarse, step = fine, step.halved(problem, "accuracy")
    raise ConvergenceError(f"accuracy {problem.accuracy:g} not reached after {MAX_HALVINGS} halvings of the step: "
                           f"estimated peak contact-force error {est.relative:.3g} of the peak at h = {step.h:.4g} s")


def _half(step, check: TransientProblem):
    """The h/2 run's step: its own stability margin; set by the accuracy where an accuracy
    target may make it the result."""
    return step.halved(check, "accuracy" if check.accuracy is not None else None)


def _first_pair(problem: TransientProblem, check: TransientProblem, step, solve_at):
    """(run at h, run at h/2): with ``CONCURRENT_PAIR`` the h/2 run (the longer; it shows the
    progress) on a second thread while this one marches at h. If either fails (or this one
    is interrupted) the other is stopped at its next chunk (``stop``), so no run outlives
    the call; the h run's error is raised first, then the h/2 run's."""
    half = _half(step, check)      # its stability checked before either run (stepping.StepChoice.halved)
    if not CONCURRENT_PAIR:
        return solve_at(problem, step, runs=3), solve_at(check, half, runs=1.5)
    import threading

    from .solver import Cancelled

    box: dict = {}
    stop = threading.Event()

    def fine_run():
        try:
            box["result"] = solve_at(check, half, runs=1.5, stop=stop)
        except BaseException as exc:           # noqa: BLE001 - handed to the calling thread
            box["error"] = exc
            stop.set()

    worker = threading.Thread(target=fine_run, name="liftoff-h/2", daemon=True)
    worker.start()
    try:
        coarse = solve_at(replace(problem, progress=False), step, runs=3, stop=stop)
        worker.join()
    except BaseException as exc:               # a failure, or an interrupt (SIGTERM, Ctrl-C) while waiting
        stop.set()
        worker.join()
        if isinstance(exc, Cancelled):         # the h/2 run failed first: its error
            raise box["error"] from None
        raise
    if "error" in box:
        raise box["error"]
    return coarse, box["result"]


class PauseGate:
    """Lets one thread pause another at a safe point. The marching thread holds the gate
    over a whole run (:meth:`running`) and offers it at each chunk boundary
    (:meth:`checkpoint`, called by the solver between compiled chunks); :meth:`paused` (a
    context) waits until that thread is at a boundary or between runs and holds it there.
    So the pausing thread (which forks, workflows/beside.py) never acts while the other is
    in compiled code, BLAS/LAPACK or the run's set-up."""

    def __init__(self):
        import threading

        self._cond = threading.Condition()
        self._busy = False
        self._requests = 0

    @contextmanager
    def running(self):
        with self._cond:
            self._cond.wait_for(lambda: self._requests == 0)
            self._busy = True
        try:
            yield
        finally:
            with self._cond:
                self._busy = False
                self._cond.notify_all()

    def checkpoint(self) -> None:
        with self._cond:
            if self._requests:
                self._busy = False
                self._cond.notify_all()
                self._cond.wait_for(lambda: self._requests == 0)
                self._busy = True

    @contextmanager
    def paused(self):
        with self._cond:
            self._requests += 1
            self._cond.wait_for(lambda: not self._busy)
        try:
            yield
        finally:
            with self._cond:
                self._requests -= 1
                self._cond.notify_all()


class _Either:
    """Set when either event is (the ``stop`` a run of :func:`solver._solve` polls)."""

    def __init__(self, a, b):
        self.a, self.b = a, b

    def is_set(self) -> bool:
        return self.a.is_set() or self.b.is_set()


class EstimatesInOrder:
    """:func:`solve_estimated` of several problems, taken in order with :meth:`get`, their
    runs at h/2 marched one after another on a second thread that runs one problem ahead:
    while the caller works on problem k's estimate (its reports), problem k+1's h/2 run
    marches, and the caller's run at h of problem k+1 then overlaps the rest of it. For a
    run of several cases this keeps both cores busy where :func:`solve_estimated` per case
    leaves one idle while the h/2 run finishes (the h/2 run takes twice the h run) and
    while the caller reports.

    ``problems``: one per index; None where the caller solves that index itself (a problem
    with ``accuracy``, whose halvings depend on each estimate, or one without an estimate).
    Each run is the same computation as in :func:`solve_estimated` (one BLAS thread, held
    over the object's life), so the estimates are the same, bit for bit. A failed h/2 run
    is raised by :meth:`get` of its own problem (and stops that problem's run at h, and the
    thread); the problems before it are delivered. Used as a context manager: leaving it
    (an error, an interrupt) stops the second thread's run at its next chunk and waits for
    it, so no run outlives the block. Each problem is taken once, and its h/2 result is
    dropped when taken. Without ``CONCURRENT_PAIR``, each :meth:`get` is
    :func:`solve_estimated`."""

    def __init__(self, problems: list):
        import threading

        self.problems = list(problems)
        self.concurrent = CONCURRENT_PAIR and sum(p is not None for p in self.problems) > 1
        self._cond = threading.Condition()
        self._stop = threading.Event()       # the block is left: every run stops
        self._failed = {k: threading.Event() for k, p in enumerate(self.problems) if p is not None}
        self._asked = -1                     # the highest index asked for (the thread runs one problem ahead)
        self._done: dict[int, object] = {}   # index -> its h/2 TransientResult, until taken
        self._taken: set[int] = set()
        self._error: BaseException | None = None     # the h/2 run that failed (the thread then ends)
        self._steps: dict[int, object] = {}
        self._halves: dict[int, object] = {}   # each problem's h/2 step, checked before any run
        self._thread = None
        self._limits = None
        self.gate = PauseGate()

    def __enter__(self) -> "EstimatesInOrder":
        if not self.concurrent:
            return self
        import threading

        from threadpoolctl import threadpool_limits

        self._limits = threadpool_limits(limits=1, user_api="blas")   # as solve_estimated, steps included
        try:
            for k, p in enumerate(self.problems):
                if p is not None:
                    if p.accuracy is not None:
                        raise ValueError(f"problem {k} has an accuracy: solve it with solve_estimated")
                    self._steps[k] = choose_step(p, contact_rows(p.body_a, p.body_b, p.contacts))
                    self._halves[k] = self._steps[k].halved(p)
            self._thread = threading.Thread(target=self._fine_runs, name="liftoff-h/2-ahead", daemon=True)
            self._thread.start()
        except BaseException:
            self.__exit__()
            raise
        return self

    def __exit__(self, *exc) -> None:
        self._stop.set()
        try:
            with self._cond:
                self._cond.notify_all()
            if self._thread is not None:
                self._thread.join()
                self._thread = None
        finally:
            if self._limits is not None:
                self._limits.restore_original_limits()
                self._limits = None

    def _fine_runs(self) -> None:
        from .solver import _solve

        before = -1                          # the problem this thread ran before k
        for k, p in enumerate(self.problems):
            if p is None:
                continue
            with self._cond:                 # one problem ahead: the one before has been asked for
                self._cond.wait_for(lambda: self._stop.is_set() or before <= self._asked)
            before = k
            if self._stop.is_set():
                return
            try:
                with self.gate.running():
                    # as solve_estimated's h/2 run (runs=1.5: it and its pair's run at h held at
                    # once), plus the problem before's pair, still held by the caller (1.5 more)
                    fine = _solve(replace(p, keep_modal=False, progress=p.progress and k == 0),
                                  self._halves[k], runs=3, stop=self._stop, gate=self.gate)
            except BaseException as exc:     # noqa: BLE001 - handed to the caller, at get(k)
                with self._cond:
                    self._error = exc
                    self._failed[k].set()
                    self._cond.notify_all()
                return
            with self._cond:
                self._done[k] = fine
                self._cond.notify_all()

    def paused(self):
        """A context in which the second thread is at a chunk boundary or between runs:
        outside compiled code, BLAS and a run's set-up, so that this process may fork
        (workflows/beside.py)."""
        return self.gate.paused()

    def get(self, k: int) -> Estimated:
        """The estimate of problem ``k`` (its run at h marched here, its h/2 run taken from the
        second thread); a failure of either run is raised."""
        p = self.problems[k]
        if p is None:
            raise ValueError(f"problem {k} is solved by the caller")
        if k in self._taken:
            raise ValueError(f"problem {k} was taken already")
        self._taken.add(k)
        if not self.concurrent:
            return solve_estimated(p)
        from .solver import Cancelled, _solve

        with self._cond:
            self._asked = max(self._asked, k)
            self._cond.notify_all()
        try:
            coarse = _solve(replace(p, progress=p.progress and k > 0), self._steps[k], runs=3,
                            stop=_Either(self._stop, self._failed[k]))
        except Cancelled:                    # this problem's h/2 run failed first: its error, below
            coarse = None
        with self._cond:
            self._cond.wait_for(lambda: k in self._done or self._error is not None or not self._thread.is_alive())
            fine = self._done.pop(k, None)
        if fine is None:
            if self._error is not None:      # this problem's h/2 run, or (asked out of order) an earlier one
                raise self._error
            raise RuntimeError(f"the run at h/2 of problem {k} was stopped")
        if coarse is None:
            raise RuntimeError(f"the run at h of problem {k} was stopped")
        est = _estimate(coarse, fine)
        coarse.metadata["accuracy"] = None
        coarse.metadata["halvings"] = 0
        return est
