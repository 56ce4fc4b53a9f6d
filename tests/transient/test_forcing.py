"""Applied loads against closed forms: modal and point force tables (piecewise linear, held at
their end values outside), constant forces; all integrated exactly by the step (eq. 7-10)."""
import math

import numpy as np
import pytest

from liftoff.transient import (ContactPoint, Forcing, ModalForce, PointForce, TabulatedForce, TransientProblem, ground,
                       solve)
from liftoff.transient.examples import spring_block

from ..roundoff import sum_rtol

M, K = 2.0, 800.0
W = math.sqrt(K / M)


def ramp_response(t, rate):
    """x'' + w^2 x = rate t / M from rest: x = rate/(M w^2) (t - sin(w t)/w)."""
    return rate / (M * W * W) * (t - np.sin(W * t) / W)


def run(forcing, t_end=0.5, h=1e-3):
    block = spring_block(M, K, zeta=0.0, point="b")
    never = [ContactPoint("far", ["b:Tz"], [None], 1e6, gap=10.0, release_time=-math.inf)]
    p = TransientProblem(block, ground(), never, forcing, t_end=t_end, h=h, initial="zero",
                         outputs={"a": ["b:Tz"]}, progress=False)
    return solve(p)


def test_tables_constant_forces_and_hold_against_closed_form():
    rate, t1 = 100.0, 0.3  # N/s up to t1, then held at rate * t1
    t = np.array([0.0, t1])
    point = run(Forcing(tables=[TabulatedForce("a", "b:Tz", t, rate * t)]))
    # the same load as a generalised (modal) table: P = phi F with phi = 1/sqrt(M)
    modal = run(Forcing(modal=[ModalForce("a", t, (rate * t / math.sqrt(M))[:, None])]))
    tt = point.time
    x_ref = ramp_response(tt, rate) - ramp_response(np.maximum(tt - t1, 0.0), rate)  # ramp minus delayed ramp
    scale = rate * t1 / K
    err_point = np.abs(point.displacement["a"][:, 0] - x_ref).max() / scale
    err_modal = np.abs(modal.displacement["a"][:, 0] - x_ref).max() / scale
    print(f"\nramp-and-hold vs closed form: point table {err_point:.1e}, modal table {err_modal:.1e}")
    # both tables are piecewise linear with a breakpoint on the step grid: the step is exact,
    # only rounding remains, accumulated over the steps of a stable recurrence (|x| <= 2 scale)
    tol = 2 * sum_rtol(tt.size)
    assert err_point < tol and err_modal < tol
    # a constant force: x = F/K (1 - cos w t)
    const = run(Forcing(constant=[PointForce("a", "b:Tz", 5.0)]))
    x_ref = 5.0 / K * (1 - np.cos(W * const.time))
    assert np.abs(const.displacement["a"][:, 0] - x_ref).max() < 2 * sum_rtol(const.time.size) * 5.0 / K
    # accelerations follow from the equation of motion at the step end
    acc_ref = 5.0 / M * np.cos(W * const.time)
    assert np.abs(const.acceleration["a"][:, 0] - acc_ref).max() < 1e-9 * 5.0 / M


@pytest.mark.parametrize("block", [None, 9])
def test_interp_columns_is_numpys_interp_bit_for_bit(block, monkeypatch):
    """transient.assembly.interp_columns (every column of a load table at once, the loads'
    and the growth guard's tables) against np.interp column by column, the same arithmetic:
    equal bit for bit, at and between breakpoints, outside them, at repeated breakpoints
    (a step in a table), with infinite table values and NaN points, for an array and a
    scalar x; also a few values at a time (``block``: the blocks' seams)."""
    from liftoff.transient import assembly
    from liftoff.transient.assembly import interp_columns

    if block is not None:
        monkeypatch.setattr(assembly, "INTERP_BLOCK", block)

    rng = np.random.default_rng(7)
    for trial in range(200):
        nk = int(rng.integers(1, 10))
        xp = np.sort(rng.choice(np.round(rng.uniform(-3.0, 3.0, 20), 1), nk))     # repeats possible
        fp = rng.normal(size=(nk, 4)) * 10.0 ** float(rng.integers(-3, 4))
        if trial % 5 == 0:
            fp[rng.integers(nk), rng.integers(4)] = np.inf
        x = np.concatenate([rng.uniform(-4.0, 4.0, 25), xp, [np.nan, -np.inf, np.inf]])
        ref = np.column_stack([np.interp(x, xp, fp[:, m]) for m in range(4)])
        got = interp_columns(x, xp, fp)
        assert got.shape == ref.shape
        assert np.array_equal(got, ref, equal_nan=True), (xp, fp)
        for xv in x[::7]:
            one = np.array([np.interp(xv, xp, fp[:, m]) for m in range(4)])
            assert np.array_equal(interp_columns(xv, xp, fp), one, equal_nan=True)
