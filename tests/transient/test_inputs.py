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
    # a 1 x 1 eigenvalue and a square root: a few roundings (1e-12 = 4500 eps); h: one division
    assert math.isclose(f_h, math.sqrt(k / m) / (2 * math.pi), rel_tol=1e-12)
    assert math.isclose(h, 0.25 / f_h, rel_tol=1e-15)
    # two equal rigid masses coupled by k: relative mode sqrt(2 k / m)
    rod = free_free_rod(1.0, 1e9, 1000.0, 1e-3, 1, name="r")  # rigid mode only, m = 1 kg
    rod_b = free_free_rod(1.0, 1e9, 1000.0, 1e-3, 1, name="s", end_labels=("b0", "b1"))
    c = [ContactPoint("c", ["end1:Tz"], ["b0:Tz"], k)]
    f_h, _ = estimate_step(rod, rod_b, c)
    assert math.isclose(f_h, math.sqrt(2 * k / 1.0) / (2 * math.pi), rel_tol=1e-12)   # 1 x 1 again


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
    p = _problem(h=0.012)  # above 0.25/f_h = 7.0e-3 s, below the stability limit 2 sqrt(3)/omega_h = 1.55e-2 s
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        solve(p)
    assert any("larger than 0.25/f_h" in str(x.message) for x in w)


def _bolted_mass(h, n_steps=3000):
    """A rigid 1 kg mass bolted to ground by a 1e6 N/m penalty spring, under gravity."""
    mass = free_free_rod(1.0, 1e9, 1000.0, 1e-3, 1, name="m")  # rigid mode only, 1 kg
    c = [ContactPoint("bolt", ["end0:Tz"], [None], 1e6)]
    return TransientProblem(mass, ground(), c, Forcing(gravity=(0, 0, -9.81)), t_end=n_steps * h, h=h, initial="zero",
                            progress=False)


def test_a_step_beyond_the_penalty_stability_limit_is_refused():
    """A rigid mass on a bolted penalty spring is Newmark's linear-acceleration scheme:
    stable for omega h < 2 sqrt(3); the criterion of stepping.coupling_margin is exact here
    (margin = -(omega h)^2/12). A step beyond the limit is refused before the run, naming the
    limit; just inside it the same run is bounded."""
    from liftoff.transient.assembly import contact_rows
    from liftoff.transient.stepping import coupling_margin

    w = 1e3  # rad/s: sqrt(1e6 N/m / 1 kg)
    p = _bolted_mass(5.0 / w)
    rows = contact_rows(p.body_a, p.body_b, p.contacts)
    for wh in (0.5, 2.0, 3.4, 5.0):
        # 1e-12: the step coefficients are summed to machine precision (coefficients.py)
        assert math.isclose(coupling_margin(rows, p.body_a.omega, p.body_a.zeta, wh / w), -wh ** 2 / 12, rel_tol=1e-12)
    with pytest.raises(InputError, match=r"exceeds the stability limit .* about 0.003464 s") as exc:
        solve(p)
    assert "\n" not in str(exc.value)
    p.h = 3.4 / w
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = solve(p)
    assert np.abs(r.contact_force).max() < 3 * 9.81


def test_growth_guard_stops_a_diverging_run(monkeypatch):
    """The second line of defence (transient/guard.py): with the up-front stability checks
    switched off, the run at omega h = 5 grows geometrically (by ~3.7 a step: 300 steps stay
    finite, the non-finite check alone would pass them) and the energy bound stops it (a
    ConvergenceError, not a result); the bounded run at omega h = 3.4 passes the guard."""
    from liftoff.transient import stepping

    monkeypatch.setattr(stepping, "coupling_margin", lambda *args: 0.0)
    monkeypatch.setattr(stepping, "check_step_map", lambda *args: 1.0)    # the step map's check too
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(ConvergenceError, match=r"the solution diverged: .* at t = "):
            solve(_bolted_mass(5.0 / 1e3, 300))
        solve(_bolted_mass(3.4 / 1e3))
