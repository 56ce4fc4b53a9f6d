"""Exact step coefficients (eq. 7-10) against scipy.signal.lsim (first-order hold = force linear
over the step) for every mode kind, and against 50-digit mpmath where lsim itself loses digits."""
import numpy as np
import pytest
import scipy.signal as sig

from liftoff.transient.coefficients import step_coefficients

RTOL = 1e-10  # issue 2; the closed forms are exact, both sides carry only rounding (~1e-14)


def lsim_step(w, z, h, q0, v0, P0, P1):
    A = np.array([[0.0, 1.0], [-w * w, -2.0 * z * w]])
    B = np.array([[0.0], [1.0]])
    _, _, x = sig.lsim((A, B, np.eye(2), np.zeros((2, 1))), U=np.array([P0, P1]), T=np.array([0.0, h]),
                       X0=[q0, v0], interp=True)
    return x[-1]


CASES = {
    "rigid": [(0.0, 0.0)],
    "zeta=0": [(1.0, 0.0), (300.0, 0.0), (2e4, 0.0)],
    "underdamped": [(5.0, 0.02), (800.0, 0.3), (3e4, 0.7)],
    "near-critical below": [(50.0, 1 - 1e-9), (2e3, 1 - 1e-6), (50.0, 1 - 1e-14)],
    "critical": [(10.0, 1.0), (5e3, 1.0)],
    "near-critical above": [(50.0, 1 + 1e-12), (2e3, 1 + 1e-7), (7e3, 1 + 1e-4)],
    "overdamped": [(20.0, 1.5), (500.0, 5.0), (100.0, 100.0), (4e3, 30.0)],
}


@pytest.mark.parametrize("kind", list(CASES))
def test_coefficients_against_lsim(kind):
    rng = np.random.default_rng(7)
    worst = 0.0
    for w, z in CASES[kind]:
        for h in (1e-4, 1e-3, 1e-2):  # omega h from 1e-4 (Taylor branch) to 300 (closed forms)
            c = step_coefficients([w], [z], h)
            for _ in range(3):
                q0, v0, P0, P1 = rng.normal(size=4) * np.array([1e-3, 1e-1, 1e2, 1e2])
                q1, v1 = (x[0] for x in c.step(q0, v0, P0, P1))
                ref = lsim_step(w, z, h, q0, v0, P0, P1)
                # relative to the size of the terms being combined, so that a result that is
                # legitimately ~0 (a cancellation inside the exact solution) is not over-demanded
                scale_q = abs(ref[0]) + 1e-3 * (abs(q0) + abs(v0) * h + (abs(P0) + abs(P1)) * h * h)
                scale_v = abs(ref[1]) + 1e-3 * (abs(q0) * w * w * h + abs(v0) + (abs(P0) + abs(P1)) * h)
                err = max(abs(q1 - ref[0]) / scale_q, abs(v1 - ref[1]) / scale_v)
                worst = max(worst, err)
    print(f"{kind}: worst relative error vs lsim {worst:.2e}")
    assert worst < RTOL


def test_coefficients_extreme_overdamped_against_mpmath():
    """omega h up to 1e4 with zeta = 1e4: lsim's expm loses ~1e-8 here, so the reference is the
    two-root closed form evaluated with 50 digits (no overflow: exp of negative arguments only)."""
    mp = pytest.importorskip("mpmath")
    mp.mp.dps = 50
    for w, z, h in [(1e6, 1e4, 1e-2), (1e5, 1e4, 1e-3), (1e6, 3.0, 1e-2), (1e7, 0.5, 1e-2)]:
        c = step_coefficients([w], [z], h)
        W, Z, H = mp.mpf(w), mp.mpf(z), mp.mpf(h)
        if z > 1:
            s = W * mp.sqrt(Z * Z - 1)
        else:
            s = 1j * W * mp.sqrt(1 - Z * Z)
        r1, r2 = -Z * W + s, -Z * W - s

        def g(t):
            return (mp.exp(r1 * t) - mp.exp(r2 * t)) / (r1 - r2)

        def I(k):  # int_0^h u^k g(u) du in closed form: int u^k e^{r u} = derivative formulas
            def one(r):
                e = mp.exp(r * H)
                return (e - 1) / r if k == 0 else (e * (r * H - 1) + 1) / r ** 2
            return (one(r1) - one(r2)) / (r1 - r2)

        ref = {"G": g(H), "Ac": I(1) / H, "Bc": I(0) - I(1) / H, "Bcd": I(0) / H}
        for key, val in ref.items():
            val = float(mp.re(val))
            got = getattr(c, key)[0]
            # closed forms of a few tens of operations without cancellation, or a series summed
            # to machine precision (coefficients.py): tens of eps; 1e-12 is 4500 eps
            assert abs(got - val) <= 1e-12 * abs(val), (w, z, h, key, got, val)


def test_rigid_coefficients_are_polynomials():
    """omega = 0 (eq. 9): q1 = q0 + v0 h + P0 h^2/3 + P1 h^2/6, v1 = v0 + (P0 + P1) h/2 exactly."""
    h = 0.01
    c = step_coefficients([0.0], [0.0], h)
    assert c.F[0] == 1 and c.G[0] == h and c.Fd[0] == 0 and c.Gd[0] == 1
    # I1/h and I0 - I1/h from h^3/3, h^2/2: three roundings at most (3 eps = 6.7e-16)
    assert np.isclose(c.Ac[0], h * h / 3, rtol=1e-15) and np.isclose(c.Bc[0], h * h / 6, rtol=1e-15)
    assert np.isclose(c.Acd[0], h / 2, rtol=1e-15) and np.isclose(c.Bcd[0], h / 2, rtol=1e-15)


def test_no_overflow_for_huge_omega_h():
    c = step_coefficients([1e9, 1e9, 1e9], [0.0, 1.0, 50.0], 1.0)
    for key in ("F", "G", "Ac", "Bc", "Fd", "Gd", "Acd", "Bcd"):
        assert np.all(np.isfinite(getattr(c, key))), key
    # static limit: a constant force P gives q -> P/omega^2 (Ac + Bc -> 1/omega^2)
    assert np.allclose(c.Ac + c.Bc, 1e-18, rtol=1e-9)


def test_recent_coefficients_are_the_computed_ones_and_their_own():
    """A set of modes seen before (a campaign's cases share the bodies and the step) gets its
    coefficients from the recent ones (transient.coefficients._RECENT): the same numbers, bit
    for bit, as evaluated anew, in arrays of the caller's own (a change to one set does not
    reach the next caller); another step, damping or static mask is evaluated anew."""
    from liftoff.transient import coefficients as co

    rng = np.random.default_rng(3)
    omega = np.concatenate([np.zeros(6), np.sort(rng.uniform(1.0, 4000.0, 60))])
    zeta = np.full(omega.size, 0.01)
    static = omega > 3000.0
    with co._RECENT_LOCK:
        co._RECENT.clear()
    first = step_coefficients(omega, zeta, 1e-3, static)
    assert len(co._RECENT) == 1
    first.Bc[:] = -1.0                                   # the caller's arrays only
    again = step_coefficients(omega, zeta, 1e-3, static)
    with co._RECENT_LOCK:
        co._RECENT.clear()
    fresh = step_coefficients(omega, zeta, 1e-3, static)
    for k in ("F", "G", "Ac", "Bc", "Fd", "Gd", "Acd", "Bcd"):
        assert np.array_equal(getattr(again, k), getattr(fresh, k)), k
    assert np.all(again.Bc != -1.0)
    other = [step_coefficients(omega, zeta, 0.5e-3, static), step_coefficients(omega, 2 * zeta, 1e-3, static),
             step_coefficients(omega, zeta, 1e-3, None)]
    assert not np.array_equal(other[0].G, fresh.G) and not np.array_equal(other[1].F, fresh.F)
    assert not np.array_equal(other[2].Bc, fresh.Bc)
    assert len(co._RECENT) == 4
    few = step_coefficients(omega[:3], zeta[:3], 1e-3)  # below RECENT_MIN_MODES: not kept
    assert len(co._RECENT) == 4 and few.G.size == 3


def test_a_forked_child_gets_a_free_lock_of_the_recent_coefficients():
    """workflows/beside.py forks while the error estimate's thread may be inside
    step_coefficients: the child's lock of the recent coefficients is a new one, free, so the
    child never waits on a thread it does not have (here the parent holds the lock across the
    fork; the child evaluates a body's coefficients and exits 0 within the time limit)."""
    import os
    import signal
    import time

    from liftoff.transient import coefficients as co

    omega = np.linspace(1.0, 100.0, 40)
    with co._RECENT_LOCK:
        pid = os.fork()
        if pid == 0:                                   # the child: must not block
            signal.alarm(20)
            try:
                step_coefficients(omega, np.full(40, 0.02), 1e-3)
                os._exit(0)
            except BaseException:                      # noqa: BLE001
                os._exit(1)
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline:
        done, status = os.waitpid(pid, os.WNOHANG)
        if done:
            break
        time.sleep(0.05)
    else:
        os.kill(pid, 9)
        os.waitpid(pid, 0)
        raise AssertionError("the forked child blocked on the recent coefficients' lock")
    assert os.WIFEXITED(status) and os.WEXITSTATUS(status) == 0
