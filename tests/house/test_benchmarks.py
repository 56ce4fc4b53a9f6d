"""The benchmarks' own problems must be ones the solver accepts at every size the benchmarks
run them (benchmarks/bench_kernel_floor.py --modes 200 3000; bench_batch.py 3,000 + 300):
a given step above 0.25/f_h is checked through the step map since 2026-12-07, which refuses
maps of more than 6,000 states, and bench_transient's fixed h = 1e-4 s was above eq. 12's step
at 3,000 modes, so the kernel-floor and batch benchmarks stopped at their largest size."""
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))

from bench_transient import H, problem  # noqa: E402

from liftoff.transient.stepping import choose_step  # noqa: E402


@pytest.mark.parametrize("n_veh, n_pad", [(200, 100), (3000, 100), (3000, 300)])
def test_benchmark_problem_is_accepted_at_its_sizes(n_veh, n_pad):
    p = problem(12_000, n_veh=n_veh, n_pad=n_pad, release=None)
    step = choose_step(p)                       # (refused before: InputError, 6,224 states)
    assert step.n_steps == 12_000
    assert step.h <= step.h_default * (1 + 1e-9) and step.h <= H
    if n_veh == 200:
        assert step.h == pytest.approx(H)       # the small problem keeps its step (figures comparable)
