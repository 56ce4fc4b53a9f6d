"""Step-size estimate (eq. 12) against closed forms, and one-line InputErrors for bad API input."""
import math
import warnings

import numpy as np
import pytest

from liftoff.transient import (ContactPoint, ConvergenceError, Forcing, InputError, ModalForce, TabulatedForce, TransientProblem,
                       estimate_step, ground, solve)
from liftoff.transient.examples import free_free_rod, spring_block


def test_estimate_step_closed_forms():
    # mass m on a contact spring k against ground: f_h = sqrt(k/m) / (2 pi)
    m, k = 3.0, 2e6
    block = spring_block(m, 1.0)  # its own support spring is negligible against K_C
    c = [ContactPoint("c", ["block:Tz"], [None], k)]
    f_h, h = estimate_step(block, ground(), c)
    assert math.isclose(f_h, math.sqrt(k / m) / (2 * math.pi), rel_tol=1e-12)
    assert math.isclose(h, 0.25 / f_h, rel_tol=1e-15)
    # two equal rigid masses coupled by k: relative mode sqrt(2 k / m)
    rod = free_free_rod(1.0, 1e9, 1000.0, 1e-3, 1, name="r")  # rigid mode only, m = 1 kg
    rod_b = free_free_rod(1.0, 1e9, 1000.0, 1e-3, 1, name="s", end_labels=("b0", "b1"))
    c = [ContactPoint("c", ["end1:Tz"], ["b0:Tz"], k)]
    f_h, _ = estimate_step(rod, rod_b, c)
    assert math.isclose(f_h, math.sqrt(2 * k / 1.0) / (2 * math.pi), rel_tol=1e-12)


def _problem(**kw):
    block = spring_block(2.0, 100.0)
    args = dict(body_a=block, body_b=ground(), contacts=[ContactPoint("c", ["block:Tz"], [None], 1e5)],
                forcing=Forcing(), t_end=0.1, progress=False)
    args.update(kw)
    return TransientProblem(**args)


@pytest.mark.parametrize("make, match", [
    (lambda: ContactPoint("c", ["block:Tz"], [None], -1.0), "stiffness must be positive"),
    (lambda: ContactPoint("c", ["block:Tz"], [None, None], 1.0), "1 labels_a but 2 labels_b"),
    (lambda: ContactPoint("c", ["block:Tz"], [None], float("nan")), "NaN"),
    (lambda: ContactPoint("c", ["block:Tz"], [None], 1.0, axial=1), "axial index 1 out of range"),
    (lambda: TabulatedForce("a", "block:Tz", [0.0, 1.0], [0.0, float("nan")]), "NaN"),
    (lambda: TabulatedForce("a", "block:Tz", [1.0, 0.0], [0.0, 1.0]), "strictly increasing"),
    (lambda: TabulatedForce("c", "block:Tz", [0.0], [1.0]), "body must be 'a' or 'b'"),
    (lambda: _problem(contacts=[ContactPoint("c", ["nope:Tz"], [None], 1e5)]), "unknown DOF label 'nope:Tz'"),
    (lambda: _problem(contacts=[ContactPoint("c", ["block:Tz"], ["x:Tz"], 1e5)]), "body b is ground"),
    (lambda: _problem(t_end=0.0), "greater than t0"),
    (lambda: _problem(h=-1e-3), "must be positive"),
    (lambda: _problem(method="rk4"), "method must be one of"),
    (lambda: _problem(outputs={"a": ["block:Tx"]}), "unknown DOF label 'block:Tx'"),
    (lambda: _problem(forcing=Forcing(modal=[ModalForce("a", [0.0, 1.0], np.zeros((2, 3)))])), "has 3 columns"),
    (lambda: _problem(contacts=[ContactPoint("c", ["block:Tz"], [None], rigid=True)], method="fixed-point"),
     "rigid contacts need method 'direct'"),
])
def test_bad_input_is_a_one_line_input_error(make, match):
    with pytest.raises(InputError, match=match) as exc:
        make()
    assert "\n" not in str(exc.value)


def test_large_step_warns():
    p = _problem(h=0.05)
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        solve(p)
    assert any("larger than 0.25/f_h" in str(x.message) for x in w)


def test_divergence_beyond_the_penalty_stability_limit_is_an_error():
    """A rigid mass on a bolted penalty spring is Newmark's linear-acceleration scheme:
    stable for omega h < 2 sqrt(3). At omega h = 5 it diverges; that must be an error, not a result."""
    m, k = 1.0, 1e6
    mass = free_free_rod(1.0, 1e9, 1000.0, 1e-3, 1, name="m")  # rigid mode only, 1 kg
    c = [ContactPoint("bolt", ["end0:Tz"], [None], k)]
    h = 5.0 / math.sqrt(k / m)
    p = TransientProblem(mass, ground(), c, Forcing(gravity=(0, 0, -9.81)), t_end=3000 * h, h=h, initial="zero",
                         progress=False)
    with pytest.warns(UserWarning, match="stability limit"):
        with pytest.raises(ConvergenceError, match=r"diverged .* at t = .* stable only for h below"):
            solve(p)
    # just inside the limit (omega h = 3.4) the same run is bounded
    p.h = 3.4 / math.sqrt(k / m)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = solve(p)
    assert np.abs(r.contact_force).max() < 3 * m * 9.81
