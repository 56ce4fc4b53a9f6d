"""Mass dropped on a one-sided spring (ground), gravity on: closed form derived below.

A rigid mass m starts at rest a gap g0 above a massless compression-only spring k:
  free fall         t_i = sqrt(2 g0 / g), impact speed v_i = g t_i;
  in contact        m x'' = -m g - k x (x = penetration coordinate, x(0) = 0, x'(0) = -v_i)
                    x = x_s - A cos(w tau + d),  x_s = -m g / k,  w = sqrt(k/m),
                    A = sqrt(x_s^2 + (v_i/w)^2), cos d = x_s / A, sin d = -v_i/(A w), d in (-pi, -pi/2)
  maximum force     F_max = k (A - x_s) = m g + sqrt((m g)^2 + k m v_i^2)
  contact duration  the spring unloads at phase -d:  tau_c = -2 d / w = 2 (pi - atan(v_i / (w |x_s|))) / w
  lift-off          t_l = t_i + tau_c, leaving at +v_i (no damping), next impact at t_l + 2 v_i / g.
"""
import math

import numpy as np

from liftoff.transient import ContactPoint, Forcing, ModalBody, TransientProblem, ground, solve

M, K, G0, G = 10.0, 1e5, 0.05, 9.81


def closed_form():
    ti = math.sqrt(2 * G0 / G)
    vi = G * ti
    w = math.sqrt(K / M)
    xs = -M * G / K
    fmax = M * G + math.sqrt((M * G) ** 2 + K * M * vi ** 2)
    tc = 2 * (math.pi - math.atan(vi / (w * abs(xs)))) / w
    return ti, fmax, tc, ti + tc, ti + tc + 2 * vi / G


def run(h, t_end=0.45):
    mass = ModalBody("mass", omega=[0.0], zeta=[0.0], dof_labels=["m:Tz"], phi=[[1 / math.sqrt(M)]],
                     participation=[[0, 0, math.sqrt(M), 0, 0, 0]], rigid_body_mass=np.diag([M, M, M, 0, 0, 0]))
    spring = ContactPoint("spring", ["m:Tz"], [None], K, gap=G0, release_time=-math.inf)
    p = TransientProblem(mass, ground(), [spring], Forcing(gravity=(0, 0, -G)), t_end=t_end, h=h,
                         initial="zero", outputs={"a": ["m:Tz"]}, progress=False)
    return solve(p)


def events(r):
    F = r.contact_force[:, 0]
    state = r.contact_state[:, 0]
    closed = np.flatnonzero(state == 1)
    t_imp = r.time[closed[0]]
    # sub-step impact/lift-off times: a coupled step ends with the force linear in the
    # penetration, so extrapolate the first/last contact-force samples to zero force
    i0 = closed[0]
    t_imp_lin = r.time[i0] - F[i0] * (r.time[i0 + 1] - r.time[i0]) / (F[i0 + 1] - F[i0])
    first_open = np.flatnonzero((state[1:] == 2) & (state[:-1] == 1))[0] + 1
    il = first_open - 1
    t_lift_lin = r.time[il] + F[il] * (r.time[il] - r.time[il - 1]) / (F[il - 1] - F[il])
    return t_imp, t_imp_lin, F.max(), t_lift_lin, r.separation_time[0]


def test_drop_on_one_sided_spring():
    ti, fmax, tc, tl, t2 = closed_form()
    w = math.sqrt(K / M)
    h = 0.01 / w  # 628 steps per spring period
    r = run(h)
    t_imp, t_imp_lin, f_max, t_lift, t_sep = events(r)
    print(f"\nimpact {t_imp_lin:.8f} (ref {ti:.8f}), F_max {f_max:.6f} N (ref {fmax:.6f}), "
          f"contact {t_lift - t_imp_lin:.8f} s (ref {tc:.8f}), lift-off {t_lift:.8f} (ref {tl:.8f})")
    # the state changes at step ends: the first closed step lies within one step after impact
    assert ti <= t_imp <= ti + h * (1 + 1e-9)
    # sub-step estimates: free flight is integrated exactly; the contact phase carries the
    # O((w h)^2) = 1e-4 error of the linear-force step and of the kinked force in the impact
    # step, so 2e-3 h on the impact time and 0.05 h on the contact duration are ample; the
    # sampled peak misses the true one by at most (w h / 2)^2 / 2 = 1.25e-5 relative
    assert abs(t_imp_lin - ti) < 2e-3 * h + 1e-12
    assert abs(f_max - fmax) < 1e-4 * fmax
    assert abs((t_lift - t_imp_lin) - tc) < 0.05 * h
    assert abs(t_lift - tl) < 0.05 * h
    # separation time is the first step end at which the spring is found open
    assert tl <= t_sep <= tl + h * (1 + 1e-9)
    # second bounce: energy is conserved, the mass returns after 2 v_i / g; the first landing
    # of a contact that starts open is not a recontact, the second one is
    assert r.recontact_count[0] == 1
    s = r.contact_state[:, 0]
    second = np.flatnonzero((s[1:] == 1) & (s[:-1] == 2))[1] + 1
    assert abs(r.time[second] - t2) <= h * 1.01
