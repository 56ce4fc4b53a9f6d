"""Contact laws beyond the reference's (transient/contact_laws.py) against closed forms.

* Two free rigid masses m1, m2 meeting on a penalty spring K (relative coordinate, reduced
  mass m = m1 m2 / (m1 + m2), w = sqrt(K / m)): peak force v0 sqrt(m K), contact time pi / w,
  elastic rebound v1' = (m1 - m2) / (m1 + m2) v1, v2' = 2 m1 / (m1 + m2) v1; momentum
  m1 v1 + m2 v2 is exchanged by equal and opposite forces, so it is kept to round-off.
* The same with a dashpot c (zeta = c / (2 sqrt(K m)) < 1/sqrt(2)) that carries no tension
  (the bodies part when K d + c d' = 0): penetration d = v0/w_d e^(-zeta w t) sin(w_d t),
  parting at w_d t* = pi - atan(2 zeta sqrt(1 - zeta^2) / (1 - 2 zeta^2)), restitution
  e = -e^(-zeta w t*) (cos(w_d t*) - zeta / sqrt(1 - zeta^2) sin(w_d t*)).
* With a latch on first contact: the pair's c.g. velocity m1 v1 / (m1 + m2) (momentum), and
  with a dashpot both bodies end at it.
* A block sliding on rigid ground with Coulomb friction: deceleration mu g, stopping distance
  v0^2 / (2 mu g) at t = v0 / (mu g), then stuck (within the stick spring's mu N / K_t); the
  path is straight along the initial velocity (isotropic friction, two tangent directions).
* A block under a tangential force F below mu N stays stuck at F / K_t (Code_Aster SDND100A);
  above it slides with acceleration (F - mu N) / m.
* A block on an inclined plane (a contact normal that is not a global axis): held when
  mu > tan(theta), sliding with g (sin(theta) - mu cos(theta)) when mu < tan(theta).
* Docking of two free-free flexible modules (several latch points with inclined normals,
  misalignment, friction, dashpots): linear and angular momentum of the pair kept to
  round-off through contact and capture.
* The laws' path with no law active reproduces the reference's path (kernel._solve_direct).
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from liftoff.core.errors import InputError
from liftoff.transient import (ContactPoint, Forcing, InitialState, ModalBody, Recovery, TabulatedForce,
                               TransientProblem, ground, solve)
from liftoff.transient.examples import docking_contacts, holddown_contacts, module_truss, toy_pad, toy_vehicle, \
    truss_body

G = 9.81


def mass1d(name: str, m: float) -> ModalBody:
    """A rigid mass moving along x (one rigid mode)."""
    part = np.zeros((1, 6))
    part[0, 0] = math.sqrt(m)
    return ModalBody(name, omega=[0.0], zeta=[0.0], dof_labels=[f"{name}:Tx"], phi=[[1 / math.sqrt(m)]],
                     participation=part, points=(name,), point_coords=[[0.0, 0.0, 0.0]],
                     rigid_body_mass=np.diag([m, 0, 0, 0, 0, 0]))


def block(m: float) -> ModalBody:
    """A rigid point mass with its three translations (three rigid modes)."""
    return ModalBody("block", omega=np.zeros(3), zeta=np.zeros(3), dof_labels=["b:Tx", "b:Ty", "b:Tz"],
                     phi=np.eye(3) / math.sqrt(m), participation=math.sqrt(m) * np.hstack([np.eye(3), np.zeros((3, 3))]),
                     points=("b",), point_coords=[[0.0, 0.0, 0.0]], rigid_body_mass=np.diag([m, m, m, 0, 0, 0]))


# ------------------------------------------------------------------ two masses head on
M1, M2, K, V1 = 3.0, 5.0, 1e6, 2.0
MRED = M1 * M2 / (M1 + M2)
W = math.sqrt(K / MRED)


def head_on(damping=0.0, latch=None, periods=10.0, steps_per_half=400):
    a, b = mass1d("a", M1), mass1d("b", M2)
    c = ContactPoint("c", ["a:Tx"], ["b:Tx"], K, normal_sign=-1.0, gap=1e-3, release_time=-math.inf,
                     damping=damping, latch_force=latch)
    init = InitialState([0.0], [math.sqrt(M1) * V1], [0.0], [0.0])
    h = math.pi / W / steps_per_half
    p = TransientProblem(a, b, [c], Forcing(), t_end=2 * periods * math.pi / W, h=h, initial=init,
                         outputs={"a": ["a:Tx"], "b": ["b:Tx"]}, progress=False)
    return solve(p)


def test_head_on_elastic_impact():
    r = head_on()
    va, vb = r.velocity["a"][:, 0], r.velocity["b"][:, 0]
    P = M1 * va + M2 * vb
    # momentum: equal and opposite forces, rigid modes integrated exactly -> round-off (1e-14 of m1 v1)
    assert np.abs(P - M1 * V1).max() < 1e-13 * M1 * V1
    # rebound velocities: 400 steps per contact; the parting falls inside a step, O(h^2): 1e-5 of v1
    assert va[-1] == pytest.approx((M1 - M2) / (M1 + M2) * V1, abs=1e-5 * V1)
    assert vb[-1] == pytest.approx(2 * M1 / (M1 + M2) * V1, abs=1e-5 * V1)
    E = 0.5 * M1 * va ** 2 + 0.5 * M2 * vb ** 2
    assert E[-1] == pytest.approx(E[0], rel=1e-8)           # linear-acceleration scheme: no dissipation
    F = -r.contact_force[:, 0]                              # compression on a (normal_sign = -1)
    assert F.max() == pytest.approx(V1 * math.sqrt(MRED * K), rel=2e-5)   # sampled peak of a sine, 400 steps
    closed = r.time[F > 0]
    assert closed[-1] - closed[0] == pytest.approx(math.pi / W, abs=2 * math.pi / W / 400)


def test_dashpot_restitution_closed_form():
    c = 200.0
    r = head_on(damping=c)
    zeta = c / (2 * math.sqrt(K * MRED))
    ph = math.pi - math.atan(2 * zeta * math.sqrt(1 - zeta ** 2) / (1 - 2 * zeta ** 2))
    wd = W * math.sqrt(1 - zeta ** 2)
    e = -math.exp(-zeta * W * ph / wd) * (math.cos(ph) - zeta / math.sqrt(1 - zeta ** 2) * math.sin(ph))
    va, vb = r.velocity["a"][:, 0], r.velocity["b"][:, 0]
    assert (vb[-1] - va[-1]) / V1 == pytest.approx(e, abs=2e-5)        # O(h^2) at 400 steps per contact
    assert np.abs(M1 * va + M2 * vb - M1 * V1).max() < 1e-13 * M1 * V1
    F = -r.contact_force[:, 0]
    assert F.min() >= 0.0                                                # never in tension


@pytest.mark.parametrize("damping", [0.0, 300.0])
def test_latch_common_velocity(damping):
    r = head_on(damping=damping, latch=0.0, periods=20.0)
    va, vb = r.velocity["a"][:, 0], r.velocity["b"][:, 0]
    vcg = (M1 * va + M2 * vb) / (M1 + M2)
    assert np.abs(vcg - M1 * V1 / (M1 + M2)).max() < 1e-13 * V1       # momentum, round-off
    t_cap = r.metadata["capture_time"]["c"]
    assert t_cap is not None and r.contact_state[-1, 0] == 0            # bolted from capture on
    tail = slice(-r.time.size // 10, None)
    if damping:          # relative motion damped out: both at the common velocity
        # zeta = 0.11 over 18 periods after capture: exp(-zeta w t) ~ 1e-5
        assert np.abs(va[tail] - M1 * V1 / (M1 + M2)).max() < 1e-4 * V1
        assert np.abs(vb[tail] - M1 * V1 / (M1 + M2)).max() < 1e-4 * V1
    else:                # undamped: the pair never parts again (bolted) and oscillates about the c.g.
        assert (r.contact_state[np.searchsorted(r.time, t_cap):, 0] == 0).all()


def test_latch_not_reached_is_a_rebound():
    free = head_on()
    r = head_on(latch=10 * V1 * math.sqrt(MRED * K))     # the force never reaches the latch
    assert r.metadata["capture_time"]["c"] is None
    np.testing.assert_allclose(r.velocity["a"], free.velocity["a"], rtol=0, atol=1e-14 * V1)


# ------------------------------------------------------------------ friction: sliding block
MB, KN, KT, MU = 10.0, 1e7, 1e7, 0.3


def sliding(v0, t_end, h=1e-4, tangential=None, mu=MU):
    b = block(MB)
    c = ContactPoint("floor", ["b:Tz", "b:Tx", "b:Ty"], [None] * 3, [KN, KT, KT], release_time=-math.inf, friction=mu)
    z0 = -MB * G / KN                                   # resting on the floor's spring
    init = InitialState(math.sqrt(MB) * np.array([0.0, 0.0, z0]), math.sqrt(MB) * np.array([*v0, 0.0]),
                        np.zeros(0), np.zeros(0))
    tables = [] if tangential is None else [TabulatedForce("a", "b:Tx", [0.0, 0.05], [0.0, tangential])]
    p = TransientProblem(b, ground(), [c], Forcing(gravity=(0, 0, -G), tables=tables), t_end=t_end, h=h,
                         initial=init, outputs={"a": ["b:Tx", "b:Ty", "b:Tz"]}, progress=False)
    return solve(p)


@pytest.mark.parametrize("v0", [(2.0, 0.0), (1.2, 1.6)])
def test_block_slides_to_rest(v0):
    speed0 = math.hypot(*v0)
    t_stop, dist = speed0 / (MU * G), speed0 ** 2 / (2 * MU * G)
    r = sliding(v0, 1.5 * t_stop)
    x, v = r.displacement["a"], r.velocity["a"]
    along = (x[:, 0] * v0[0] + x[:, 1] * v0[1]) / speed0           # distance along the initial direction
    vel = (v[:, 0] * v0[0] + v[:, 1] * v0[1]) / speed0
    i = int(np.flatnonzero(vel <= 0)[0])                           # first step end at rest
    # slip at constant deceleration mu g is integrated exactly; the stop falls inside step i:
    # time within one step, distance within the stick spring's mu N / K_t
    assert abs(r.time[i] - t_stop) <= r.h * (1 + 1e-9)     # the stop may fall on a step end (rounding of t)
    assert along[i] == pytest.approx(dist, abs=MU * MB * G / KT + 1e-12)
    # deceleration mu g while sliding: force = mu N opposite to the velocity
    F = r.contact_force
    mid = i // 2
    assert np.hypot(F[mid, 1], F[mid, 2]) == pytest.approx(MU * F[mid, 0], rel=1e-9)
    # stuck afterwards: it never slides on; it swings on the stick spring between anchor +- mu N / K_t
    # (it stopped near one end: 2 mu N / K_t, +0.1 % as step i samples the stop within a step)
    assert np.abs(along[i:] - along[i]).max() <= 2.002 * MU * MB * G / KT
    assert np.all(np.hypot(F[i + 2:, 1], F[i + 2:, 2]) <= MU * F[i + 2:, 0] * (1 + 1e-9))
    # a straight path along the initial velocity (isotropic Coulomb cone)
    across = (-x[:, 0] * v0[1] + x[:, 1] * v0[0]) / speed0
    assert np.abs(across).max() < 1e-9 * dist


@pytest.mark.parametrize("fraction", [0.5, 0.99])
def test_block_stuck_below_mu_n(fraction):
    F = fraction * MU * MB * G
    r = sliding((0.0, 0.0), 0.5, tangential=F)
    x = r.displacement["a"][:, 0]
    # stuck: only the stick spring stretches, by F / K_t (+- its undamped oscillation about it)
    assert abs(x[-1] - F / KT) <= F / KT
    assert np.abs(x).max() <= 2 * F / KT
    np.testing.assert_array_less(np.abs(r.contact_force[:, 1]), MU * r.contact_force[:, 0] * (1 + 1e-9) + 1e-12)


def test_block_slides_above_mu_n():
    F = 1.2 * MU * MB * G
    r = sliding((0.0, 0.0), 0.5, tangential=F)
    v, t = r.velocity["a"][:, 0], r.time
    late = t > 0.2
    acc = np.polyfit(t[late], v[late], 1)[0]
    assert acc == pytest.approx((F - MU * MB * G) / MB, rel=1e-6)      # exact slip force, linear table


@pytest.mark.parametrize("mu, slides", [(0.5, False), (0.2, True)])
def test_block_on_incline(mu, slides):
    """A normal (sin th, 0, cos th) over Tx, Ty, Tz: held when mu > tan th, else g (sin th - mu cos th)."""
    th = math.radians(20.0)
    n = (math.sin(th), 0.0, math.cos(th))
    b = block(MB)
    c = ContactPoint("slope", ["b:Tx", "b:Ty", "b:Tz"], [None] * 3, [KN, KT, KT], release_time=-math.inf,
                     friction=mu, normal=n)
    pen = MB * G * math.cos(th) / KN                     # resting: normal spring compressed by N / K_n
    init = InitialState(math.sqrt(MB) * (-pen * np.array(n)), np.zeros(3), np.zeros(0), np.zeros(0))
    p = TransientProblem(b, ground(), [c], Forcing(gravity=(0, 0, -G)), t_end=0.5, h=1e-4, initial=init,
                         outputs={"a": ["b:Tx", "b:Ty", "b:Tz"]}, progress=False)
    r = solve(p)
    down = np.array([math.cos(th), 0.0, -math.sin(th)])             # down the slope
    s = r.displacement["a"] @ down
    vs = r.velocity["a"] @ down
    assert r.contact_directions[0].component == "n" and r.contact_directions[0].axial
    assert r.contact_force[:, 0].min() > 0                          # always in contact
    if slides:
        a = G * (math.sin(th) - mu * math.cos(th))
        late = r.time > 0.1
        assert np.polyfit(r.time[late], vs[late], 1)[0] == pytest.approx(a, rel=1e-6)
    else:
        # held: the undamped stick spring first overshoots (twice the static m g sin th > mu N),
        # slips by a few microns, then swings without sliding: no drift over the second half
        stretch = MB * G * math.sin(th) / KT
        assert np.abs(s).max() < 4 * stretch
        half = r.time > 0.25
        assert np.ptp(s[half]) <= 2 * stretch * (1 + 1e-6)
        assert abs(np.polyfit(r.time[half], s[half], 1)[0]) < 1e-6      # m/s: no sliding


# ------------------------------------------------------------------ docking
def _momentum(r, A, B):
    """Total linear momentum and angular momentum about the origin of the pair, per step."""
    ma, mb = r.recovered["mom_a"], r.recovered["mom_b"]
    P = ma[:, :3] + mb[:, :3]
    H = ma[:, 3:] + np.cross(A.ref_point, ma[:, :3]) + mb[:, 3:] + np.cross(B.ref_point, mb[:, :3])
    return P, H


@pytest.mark.parametrize("latch, mu, c", [(200.0, 0.0, 0.0), (200.0, 0.3, 500.0), (None, 0.3, 0.0)])
def test_docking_momentum_and_capture(latch, mu, c):
    A = truss_body(module_truss("a"), "chaser", zeta=0.02)
    B = truss_body(module_truss("b"), "target", zeta=0.02)
    u0 = np.array([0.0, 0.01, 0.0, 0.0, 0.0, math.radians(0.5)])   # 10 mm off-centre, 0.5 deg yaw
    v0 = np.array([0.15, 0.0, 0.01, 0.0, 0.0, 0.0])                 # closing at 0.15 m/s, drifting in z
    init = InitialState(A.participation @ u0, A.participation @ v0, np.zeros(B.n_modes), np.zeros(B.n_modes))
    labels = ["Px", "Py", "Pz", "Hx", "Hy", "Hz"]
    recs = [Recovery("mom_a", "a", labels, vel=A.participation.T, category="momentum"),
            Recovery("mom_b", "b", labels, vel=B.participation.T, category="momentum")]
    p = TransientProblem(A, B, docking_contacts(friction=mu, damping=c, latch_force=latch), Forcing(), t_end=1.0,
                         initial=init, recoveries=recs, progress=False)
    r = solve(p)
    P, H = _momentum(r, A, B)
    # equal and opposite forces at coincident points, rigid modes exact: round-off of |P| = 900 kg m/s
    assert np.abs(P - P[0]).max() < 1e-13 * np.abs(P[0]).max()
    assert np.abs(H - H[0]).max() < 1e-13 * (np.abs(H[0]).max() + np.abs(P[0]).max())
    assert np.abs(r.contact_force).max() > 100.0                   # they did meet
    cap = r.metadata.get("capture_time", {})
    if latch is None:
        assert not cap and (r.contact_state[-1] == 2).all()           # rebound: apart again
    else:
        assert all(t is not None for t in cap.values()) and (r.contact_state[-1] == 0).all()


def test_docking_normals_are_not_axes():
    cps = docking_contacts()
    n = cps[0].frame()
    np.testing.assert_allclose(n @ n.T, np.eye(3), atol=1e-15)
    assert abs(n[0, 0]) < 1 and abs(n[0, 1]) > 0.1


# ------------------------------------------------------------------ the reference's path is kept
def test_laws_path_without_a_law_is_the_reference_path():
    """A latch that never closes sends the problem through kernel._solve_laws; with no friction,
    no dashpot and no capture it must give the reference path's results (same arithmetic)."""
    def problem(latch):
        veh, pad = toy_vehicle(), toy_pad()
        cps = holddown_contacts(release_time=0.3)
        cps[0].latch_force = latch
        thrust = TabulatedForce("a", "post_1:Tz", [0.0, 0.3, 0.5], [0.0, 0.0, 2.0 * veh.mass * G])
        return TransientProblem(veh, pad, cps, Forcing(gravity=(0, 0, -G), tables=[thrust]), t_end=0.8,
                                outputs={"a": ["post_1:Tz"]}, progress=False)
    ref, laws = solve(problem(None)), solve(problem(1e30))
    assert laws.metadata["capture_time"] == {"holddown_1": None}
    scale = np.abs(ref.contact_force).max()
    np.testing.assert_allclose(laws.contact_force, ref.contact_force, rtol=0, atol=1e-12 * scale)
    np.testing.assert_array_equal(laws.contact_state, ref.contact_state)


# ------------------------------------------------------------------ bad input
@pytest.mark.parametrize("kw, msg", [
    ({"friction": -0.1}, "friction coefficient"),
    ({"friction": 0.3, "rigid": True}, "friction needs"),
    ({"damping": [1.0, -1.0, 0.0]}, "damping"),
    ({"damping": 5.0, "rigid": True}, "no damping"),
    ({"latch_force": -1.0}, "latch_force"),
    ({"normal": [0.0, 0.0, 0.0]}, "normal"),
    ({"normal": [1.0, 0.0]}, "normal"),
    ({"normal": [0.0, 0.0, 1.0], "axial": 2}, "axial must be 0"),
    ({"normal": [0.0, 0.0, 1.0], "labels_a": ["b:Tz", "b:Tx", "b:Rz"]}, "translation labels"),
    ({"friction": 0.3, "labels_a": ["b:Tz", "b:Tx", "b:Rz"]}, "all translations"),
])
def test_bad_laws(kw, msg):
    base = dict(name="p", labels_a=["b:Tz", "b:Tx", "b:Ty"], labels_b=[None] * 3, stiffness=1e6)
    if kw.get("rigid"):
        base.pop("stiffness")
    with pytest.raises(InputError, match=msg):
        ContactPoint(**{**base, **kw})


def test_fixed_point_refuses_laws():
    b = block(MB)
    c = ContactPoint("floor", ["b:Tz", "b:Tx", "b:Ty"], [None] * 3, KN, release_time=-math.inf, friction=0.3)
    with pytest.raises(InputError, match="need method 'direct'"):
        TransientProblem(b, ground(), [c], Forcing(), t_end=0.1, method="fixed-point", initial="zero")


def test_friction_cone_through_lift_off_and_landing():
    """A vehicle on four friction posts, released, rocked by a lateral pulse so that posts lift off
    and land again while it slides: at every step end the Coulomb cone holds on closed points
    (|f_T| <= mu N), open points carry nothing, and the run settles every step."""
    veh, pad = toy_vehicle(), toy_pad()
    mu = 0.3
    cps = holddown_contacts(release_time=0.01)            # statics bolted, then released
    for c in cps:
        c.friction = mu
    weight = veh.mass * G
    pulse = TabulatedForce("a", "top:Tx", [0.0, 0.05, 0.15, 0.2], [0.0, 0.12 * weight, 0.12 * weight, 0.0])
    p = TransientProblem(veh, pad, cps, Forcing(gravity=(0, 0, -G), tables=[pulse]), t_end=1.5,
                         outputs={"a": ["top:Tx"]}, progress=False)
    r = solve(p)
    F = r.contact_force.reshape(r.time.size, 4, 3)            # per post: Tz (normal), Tx, Ty
    N, T = F[:, :, 0], np.hypot(F[:, :, 1], F[:, :, 2])
    assert (r.recontact_count > 0).any()                         # posts lifted off and landed again
    closed = r.contact_state == 1
    assert np.all(T[closed] <= mu * N[closed] * (1 + 1e-9) + 1e-9 * weight)
    assert np.all(F[r.contact_state == 2] == 0.0)
    slipping = closed & (T >= mu * N * (1 - 1e-6)) & (N > 0)
    assert slipping.any() and (closed & ~slipping).any()        # both stick and slip happened


def test_a_latch_does_not_capture_a_post_released_in_contact():
    """Capture is an event: a hold-down with a recapture latch, released while it still
    carries the vehicle's weight, was latched at the end of the first released step and
    bolted for good (the vehicle never lifted off, the posts pulling 64 kN; a review,
    2026-12-07). Now it must have been open first: under 1.4 g of thrust the vehicle lifts
    off exactly as without a latch (same separation times, no tension), and nothing is
    captured before it separates."""
    import dataclasses

    from liftoff.transient import TabulatedForce
    from liftoff.transient.examples import holddown_contacts, toy_pad, toy_vehicle

    thrust = 1.4 * 50e3 * 9.81

    def run(latch):
        cs = [dataclasses.replace(c, latch_force=latch) for c in holddown_contacts(4, stiffness=2e9, release_time=0.05)]
        p = TransientProblem(toy_vehicle(), toy_pad(), cs,
                             Forcing(tables=[TabulatedForce("a", "top:Tz", [0, 0.2, 0.5], [0, thrust, thrust])],
                                     gravity=(0, 0, -9.81)), t_end=0.5, h=2e-4, progress=False)
        return solve(p)

    free, latched = run(None), run(5e4)
    assert np.all(np.isfinite(free.separation_time))
    assert np.array_equal(latched.separation_time, free.separation_time)
    from liftoff.transient.assembly import contact_rows

    axial = contact_rows(toy_vehicle(), toy_pad(), holddown_contacts(4)).axial
    after = latched.time > 0.05
    assert latched.contact_force[after][:, axial].min() >= 0.0             # compression only once released
    captured = latched.metadata.get("capture_time") or {}
    assert all(t is None or t > min(free.separation_time) for t in captured.values())


def test_a_docking_begun_in_contact_and_closing_is_captured():
    """A latch's 'has been open' rule must not stop a capture in progress: the head-on pair
    starting 10 um penetrated and still closing at 1 m/s is captured at once, as before the
    rule (a review: it rebounded); at rest in contact it is not (the released-post case)."""
    a, b = mass1d("a", M1), mass1d("b", M2)

    def run(v):
        c = ContactPoint("c", ["a:Tx"], ["b:Tx"], K, normal_sign=-1.0, gap=0.0, release_time=-math.inf,
                         latch_force=0.0)
        init = InitialState([math.sqrt(M1) * 1e-5], [math.sqrt(M1) * v], [0.0], [0.0])
        p = TransientProblem(a, b, [c], Forcing(), t_end=4 * math.pi / W, h=math.pi / W / 400, initial=init,
                             outputs={"a": ["a:Tx"], "b": ["b:Tx"]}, progress=False)
        return solve(p).metadata.get("capture_time")

    closing = run(1.0)["c"]
    assert closing is not None and closing < 1e-4
    assert run(0.0)["c"] is None
