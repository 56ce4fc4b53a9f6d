"""Two equal free-free elastic rods in axial impact (closed-form modes of a uniform rod).

Rod A (speed v0) hits rod B (at rest) end to end. 1-D wave theory: the interface force is
the plateau rho c A v0 / 2 for the duration 2 L / c, after which the rods part with their
velocities exchanged (A at rest, B at v0) and no residual vibration.
"""
import math

import numpy as np

from liftoff.transient import ContactPoint, Forcing, InitialState, TransientProblem, solve
from liftoff.transient.examples import free_free_rod

L, E, RHO, A, V0 = 1.0, 70e9, 2700.0, 1e-3, 2.0
N_MODES = 200  # per rod (rigid + 199 elastic): resolves the wave front to ~ L / N


def test_rod_impact_plateau_duration_and_velocity_exchange():
    c = math.sqrt(E / RHO)
    m = RHO * A * L
    T = 2 * L / c
    ra = free_free_rod(L, E, RHO, A, N_MODES, name="rod_a", end_labels=("a0", "a1"), component="Tx")
    rb = free_free_rod(L, E, RHO, A, N_MODES, name="rod_b", end_labels=("b0", "b1"), component="Tx")
    # contact spring 250 EA/L: the force rises over Z/(2k) = T/1000 (Z = rho c A), a 0.1 % effect
    k = 250 * E * A / L
    impact = ContactPoint("impact", ["a1:Tx"], ["b0:Tx"], k, normal_sign=-1.0, release_time=-math.inf)
    va = np.zeros(N_MODES)
    va[0] = V0 * math.sqrt(m)  # rigid mode: x = q / sqrt(m)
    init = InitialState(np.zeros(N_MODES), va, np.zeros(N_MODES), np.zeros(N_MODES))
    p = TransientProblem(ra, rb, [impact], Forcing(), t_end=2 * T, initial=init, keep_modal=True, progress=False)
    r = solve(p)
    F = -r.contact_force[:, 0]  # force on A points in -x: compression > 0
    tt = r.time / T
    plateau = F[(tt > 0.2) & (tt < 0.8)].mean()
    closed = np.flatnonzero(r.contact_state[:, 0] == 1)
    duration = (r.separation_time[0] - r.time[closed[0]]) / T
    va_end = r.modal["v_a"][-1, 0] / math.sqrt(m)
    vb_end = r.modal["v_b"][-1, 0] / math.sqrt(m)
    ref = RHO * c * A * V0 / 2
    print(f"\nplateau {plateau:.2f} N (ref {ref:.2f}, {plateau / ref - 1:+.2e}), duration {duration:.5f} x 2L/c, "
          f"v_a {va_end:+.5f} v_b {vb_end:.5f} m/s (ref 0, {V0}), recontacts {r.recontact_count[0]}, "
          f"{r.time.size - 1} steps of {r.h:.3g} s")
    # plateau: the Gibbs ripple of a 200-mode series averages out over the middle 60 %;
    # the penalty spring costs ~0.1 %: 1 % is the tolerance for 200 modes
    assert abs(plateau / ref - 1) < 0.01
    # duration: the wave front is smeared over ~L/N, i.e. ~T/(2N) = 0.0025 T per passage
    assert abs(duration - 1) < 2.0 / N_MODES
    # momentum is exchanged (exactly conserved by equal and opposite contact forces)
    assert abs(va_end) < 0.01 * V0 and abs(vb_end - V0) < 0.01 * V0
    assert abs(va_end + vb_end - V0) < 1e-9 * V0
    # a single contact episode: one closing, and no recontact (the first landing of a
    # contact that starts open is not one)
    s = r.contact_state[:, 0]
    assert np.sum((s[1:] == 1) & (s[:-1] == 2)) == 1 and r.recontact_count[0] == 0
