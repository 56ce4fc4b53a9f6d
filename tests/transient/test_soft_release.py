"""Soft (controlled) release: ContactPoint.release_force (transient/contact_laws.py), against
closed forms.

A rigid mass m on a grounded post (K_C = 1e10 N/m), thrust T up, gravity g down, bolted
until t = 0, then held by pins whose tension follows a force-travel table F(s):

* T - m g > F everywhere: the mass is drawn out, m s'' = T - m g - F(s) (a piecewise
  parabola for a piecewise-constant F); exit time and velocity at travel[-1];
* T - m g < F(0): held, the post stretched by (T - m g) / K_C;
* F1 < T - m g < F2 (F = F1 up to s1, F2 beyond): the mass stops in the dies where the
  work balances, (T - m g - F1) s1 = (F2 - (T - m g)) (s_stop - s1), and stays there
  (the pins are drawn plastically: they hold it, they do not pull it back);
* thrust cut after it stopped: the pins go slack, the mass falls freely on the post and
  lands with sqrt(2 g s_stop).

Also: a table of zeros is the instantaneous release (same forces to round-off); the law
off leaves the reference path as it was (fingerprint of the base commit); two free
masses keep their momentum through a soft contact; bad input in one line.
"""
from __future__ import annotations

import copy
import math
from dataclasses import replace
import tomllib

import numpy as np
import pytest

from liftoff.config import default_text, parse_scenario
from liftoff.core.errors import InputError
from liftoff.transient import (ContactPoint, Forcing, InitialState, PointForce, TabulatedForce,
                               TransientProblem, ground, solve)
from liftoff.transient.examples import holddown_contacts, toy_pad, toy_vehicle
from liftoff.workflows.cli import main

from .test_contact_laws import mass1d

G = 9.81
M, KC = 1000.0, 1e10                       # kg, N/m
F1, F2, S1, S_END = 3000.0, 5000.0, 0.02, 0.05
TRAVEL = (0.0, S1, S1 + 1e-7, S_END)       # F1 up to S1, F2 beyond (a 0.1 um ramp between)
FORCE = (F1, F1, F2, F2)


def lift(net: float, h: float = 1e-4, t_end: float = 0.5, cut: float | None = None, table=(TRAVEL, FORCE)):
    """The mass on its post, thrust m g + net (cut to zero over 1 ms at ``cut``); x up (normal_sign +1)."""
    post = ContactPoint("post", ["a:Tx"], [None], KC, release_time=0.0, release_force=table)
    thrust = M * G + net
    if cut is None:
        loads = Forcing(constant=[PointForce("a", "a:Tx", thrust)], gravity=(-G, 0, 0))
    else:
        loads = Forcing(tables=[TabulatedForce("a", "a:Tx", [0.0, cut, cut + 1e-3], [thrust, thrust, 0.0])],
                        gravity=(-G, 0, 0))
    p = TransientProblem(mass1d("a", M), ground(), [post], loads, t_end=t_end, t0=-10 * h, h=h,
                         outputs={"a": ["a:Tx"]}, progress=False)
    return solve(p)


def crossing(r, level):
    """(time, velocity) where the displacement first reaches ``level`` (linear between steps)."""
    x, v, t = r.displacement["a"][:, 0], r.velocity["a"][:, 0], r.time
    i = int(np.argmax(x >= level))
    w = (level - x[i - 1]) / (x[i] - x[i - 1])
    return t[i - 1] + w * (t[i] - t[i - 1]), v[i - 1] + w * (v[i] - v[i - 1])


def drawn_out_closed_form(net):
    a1, a2 = (net - F1) / M, (net - F2) / M
    t1 = math.sqrt(2 * S1 / a1)
    v1 = a1 * t1
    tau = (-v1 + math.sqrt(v1 ** 2 + 2 * a2 * (S_END - S1))) / a2
    return t1 + tau, v1 + a2 * tau


@pytest.mark.parametrize("h", [1e-4, 5e-5])
def test_drawn_out_closed_form(h):
    net = 6000.0
    r = lift(net, h=h)
    t_cf, v_cf = drawn_out_closed_form(net)
    t_num, v_num = crossing(r, S_END)
    # Two O(h) effects, nothing else (the rigid mode is integrated exactly): the release
    # step ramps the post force from the bolt's to the pins' over [-h, 0] (the motion starts
    # h/2 early), and F(s) is taken at the step start, so F2 acts up to one step late at
    # S1 (an extra impulse (F2 - F1) h). Hence |dt| <= h/2 + h and |dv| <= a_max h/2 +
    # (F2 - F1) h / M; the post's static stretch (T - m g)/K_C = 0.6 um is far below both.
    a_max = (net - F1) / M
    assert abs(t_num - t_cf) < 1.5 * h, (t_num, t_cf)
    assert abs(v_num - v_cf) < a_max * h / 2 + (F2 - F1) * h / M, (v_num, v_cf)
    # the pins yield at the release and are drawn out when the travel passes 0.05 m (at a step end)
    soft = r.metadata["soft_release"]["post"]
    assert soft["first_yield"] == pytest.approx(0.0, abs=h / 2)
    assert t_num <= soft["drawn_out"] < t_num + h + 1e-12
    assert r.separation_time[0] == pytest.approx(soft["drawn_out"], abs=1e-12)   # then an ordinary open point
    # after: free flight under T - m g (the post never pulls again)
    after = r.time > soft["drawn_out"] + h
    np.testing.assert_allclose(r.contact_force[after, 0], 0.0, atol=0.0)
    np.testing.assert_allclose(r.acceleration["a"][after, 0], net / M, rtol=1e-9)


def test_held_below_the_first_force():
    net = 2000.0                                   # < F1
    r = lift(net, t_end=0.2)
    x = r.displacement["a"][:, 0]
    # the post stretches by net / K_C (0.2 um) and stays: elastic, no yield (1e-12 of it: round-off)
    np.testing.assert_allclose(x, net / KC, rtol=1e-9)
    np.testing.assert_allclose(r.contact_force[:, 0], -net, rtol=1e-9)
    assert r.metadata["soft_release"]["post"] == {"first_yield": None, "drawn_out": None}


def test_stops_where_the_work_balances_and_is_held():
    net, h = 4000.0, 1e-4                           # F1 < net < F2
    r = lift(net, h=h, t_end=1.0)
    x = r.displacement["a"][:, 0]
    s_stop = S1 + (net - F1) * S1 / (F2 - net)     # 0.04 m
    # F2 takes over up to one step late at S1 (explicit F(s_a)): the mass crosses S1 at
    # v = sqrt(2 (net - F1) S1 / M) and travels up to v h more under F1, i.e. extra work
    # (F2 - F1) v h, stopping (F2 - F1) v h / (F2 - net) further; plus the 0.1 um ramp and
    # the springs' stretches in x (the post's net / K_C before release, the pin's <= F2 / K_C).
    v1 = math.sqrt(2 * (net - F1) * S1 / M)
    tol = (F2 - F1) * v1 * h / (F2 - net) + 1e-7 + (net + F2) / KC
    assert abs(x.max() - s_stop) < tol, (x.max(), s_stop)
    # held there: the last 0.3 s move by no more than the elastic stretch F2 / K_C
    late = r.time > 0.7
    assert np.ptp(x[late]) < F2 / KC
    assert abs(x[late].mean() - x.max()) < F2 / KC
    assert r.metadata["soft_release"]["post"]["drawn_out"] is None
    assert (r.contact_state[r.time > 0, 0] == 1).all()   # closed (coupled) after release: never drawn out


def test_pins_go_slack_when_pushed_back():
    net, cut = 4000.0, 0.6
    r = lift(net, t_end=0.8, cut=cut)
    x, t = r.displacement["a"][:, 0], r.time
    v = r.velocity["a"][:, 0]
    s_stop = x[t < cut].max()
    land = int(np.argmax((x <= 0.0) & (t > cut)))         # first step end on the post
    # free fall from s_stop through the dies (pins slack: no force at all) down to the post:
    # v^2 = 2 g (s_stop - x) at the last step before it. The thrust ramps to zero over 1 ms
    # while the pins unload, which changes the start of the fall by less than g (1 ms)^2 =
    # 1e-5 m in 0.04 m: 1e-3 relative on v^2
    falling = (t > cut + 2e-3) & (t < t[land])
    assert falling.sum() > 800 and np.all(r.contact_force[falling, 0] == 0.0)
    assert np.all(r.contact_state[falling, 0] == 2)
    assert v[land - 1] ** 2 == pytest.approx(2 * G * (s_stop - x[land - 1]), rel=1e-3)
    # the post catches it in compression (the ordinary released point) and throws it back up
    assert r.contact_force[land, 0] > 0 and r.contact_state[land, 0] == 1
    assert v[land:].max() == pytest.approx(-v[land - 1], rel=1e-3)


# ------------------------------------------------------------------ the flexible vehicle
def vehicle_problem(table=None):
    veh, pad = toy_vehicle(), toy_pad()
    cps = [replace(c, release_force=table) for c in holddown_contacts(release_time=0.3)]
    thrust = TabulatedForce("a", "post_1:Tz", [0.0, 0.3, 0.5], [0.0, 0.0, 2.0 * veh.mass * G])
    return TransientProblem(veh, pad, cps, Forcing(gravity=(0, 0, -G), tables=[thrust]), t_end=0.8,
                            outputs={"a": ["post_1:Tz"]}, progress=False)


def test_law_off_is_the_reference_path_as_it_was():
    """release_force None: the reference path (kernel._solve_direct), whose results are those of
    the commit before the soft release (f75e350, this example, bit-identical on the machine that
    added it). The figures are that run's; rtol 1e-12 leaves room for another BLAS's rounding."""
    r = solve(vehicle_problem())
    assert "soft_release" not in r.metadata
    assert float(np.abs(r.contact_force).sum()) == pytest.approx(365974940.65036917, rel=1e-12)
    assert float(r.displacement["a"][-1, 0]) == pytest.approx(0.7295146217885542, rel=1e-12)
    np.testing.assert_allclose(r.separation_time, [0.33569212, 0.36052142, 0.40670391, 0.36151459], atol=1e-8)


def test_zero_table_is_the_instantaneous_release():
    """Pins that carry no force yield at once and are gone: the reference's release. Different
    active-set paths to the same solution, so round-off of the peak force apart (1e-9)."""
    ref = solve(vehicle_problem())
    soft = solve(vehicle_problem(((0.0, 0.01), (0.0, 0.0))))
    scale = np.abs(ref.contact_force).max()
    np.testing.assert_allclose(soft.contact_force, ref.contact_force, rtol=0, atol=1e-9 * scale)
    # a soft point separates (state OPEN) when it is drawn out, here after 1 cm of travel
    assert np.all(soft.separation_time > ref.separation_time)


def test_soft_release_delays_the_flexible_vehicle():
    """Pins with 20 % of the weight per post over 5 cm: every post yields and is drawn out, later
    than the instantaneous release separates."""
    veh = toy_vehicle()
    ref = solve(vehicle_problem())
    r = solve(vehicle_problem(((0.0, 0.05), (0.05 * veh.mass * G, 0.05 * veh.mass * G))))
    soft = r.metadata["soft_release"]
    assert all(v["first_yield"] is not None and v["drawn_out"] is not None for v in soft.values())
    assert np.all(r.separation_time > ref.separation_time)
    tension = -r.contact_force[:, [rows[0] for rows in _normal_rows(r)]]
    assert tension.max() <= 0.05 * veh.mass * G * (1 + 1e-9) + 1e-6 * veh.mass * G


def _normal_rows(r):
    return [[j for j, d in enumerate(r.contact_directions) if d.index == c and d.axial]
            for c in range(len(r.contact_names))]


def test_two_free_masses_keep_their_momentum():
    """A soft contact between two free masses (no ground): equal and opposite forces, rigid modes
    integrated exactly -> momentum to round-off (1e-13 of m1 v1)."""
    m1, m2, v1 = 300.0, 500.0, 0.5
    a, b = mass1d("a", m1), mass1d("b", m2)
    c = ContactPoint("c", ["a:Tx"], ["b:Tx"], 1e8, release_time=0.0, release_force=((0.0, 0.02), (200.0, 100.0)))
    init = InitialState([0.0], [math.sqrt(m1) * v1], [0.0], [0.0])
    p = TransientProblem(a, b, [c], Forcing(), t_end=0.3, t0=-1e-4, h=1e-4, initial=init,
                         outputs={"a": ["a:Tx"], "b": ["b:Tx"]}, progress=False)
    r = solve(p)
    P = m1 * r.velocity["a"][:, 0] + m2 * r.velocity["b"][:, 0]
    assert np.abs(P - m1 * v1).max() < 1e-13 * m1 * v1
    assert r.metadata["soft_release"]["c"]["drawn_out"] is not None


# ------------------------------------------------------------------ bad input
@pytest.mark.parametrize("table, kw, msg", [
    (((0.0, 0.02, 0.02), (1.0, 1.0, 1.0)), {}, "strictly increasing"),
    (((0.0, 0.03, 0.02), (1.0, 1.0, 1.0)), {}, "strictly increasing"),
    (((0.0, 0.02), (1.0, -1.0)), {}, "must be >= 0"),
    (((0.0, math.nan), (1.0, 1.0)), {}, "NaN"),
    (((0.0, 0.02), (math.nan, 1.0)), {}, "NaN"),
    (((0.0,), (1.0,)), {}, "at least 2 points"),
    (((0.01, 0.02), (1.0, 1.0)), {}, "start at 0"),
    (((0.0, 0.02), (1.0,)), {}, "1 forces"),
    ((0.0, 0.02, 0.05), {}, "two lists"),
    (((0.0, 0.02), (1.0, 1.0)), {"rigid": True}, "not rigid"),
    (((0.0, 0.02), (1.0, 1.0)), {"latch_force": 10.0}, "not supported"),
    (((0.0, 0.02), (1.0, 1.0)), {"damping": 5.0}, "not supported"),
])
def test_bad_release_force(table, kw, msg):
    with pytest.raises(InputError) as err:
        ContactPoint("post_7", ["a:Tx"], [None], KC, release_force=table, **kw)
    text = str(err.value)
    assert "'post_7'" in text and "release_force" in text and msg in text and "\n" not in text


def test_friction_with_soft_release_refused():
    with pytest.raises(InputError, match=r"'p': release_force cannot be combined with friction"):
        ContactPoint("p", ["a:Tz", "a:Tx"], [None, None], KC, friction=0.3, release_force=((0.0, 0.1), (1.0, 1.0)))


def test_post_defaults_and_post_read_release_force():
    d = tomllib.loads(default_text())
    d["post_defaults"]["release_force"] = {"travel": [0.0, 0.05], "force": [1e5, 0.0]}
    posts = parse_scenario(copy.deepcopy(d), "x.toml").cases[0].posts
    s, f = posts[0].contact().release_force
    np.testing.assert_array_equal(s, [0.0, 0.05])
    np.testing.assert_array_equal(f, [1e5, 0.0])
    d["post"][1]["release_force"] = {"travel": [0.0, 0.05, 0.04], "force": [1.0, 1.0, 1.0]}
    with pytest.raises(InputError, match=r"post\[1\] 'left_2'.release_force: travel must be strictly increasing"):
        parse_scenario(d, "x.toml")
    d["post"][1]["release_force"] = {"travel": [0.0, 0.05], "forces": [1.0, 1.0]}
    with pytest.raises(InputError, match=r"post\[1\] 'left_2'.release_force: unknown key 'forces'"):
        parse_scenario(d, "x.toml")


@pytest.mark.parametrize("inline, expect", [
    ("{ travel = [0.0, 0.02], force = [1.0, -1.0] }", "contact[0] 'post'.release_force: forces must be >= 0 N"),
    ("{ travel = [0.0, 0.02, 0.01], force = [1.0, 1.0, 1.0] }", "release_force: travel must be strictly increasing"),
    ("{ travel = [0.0], force = [1.0] }", "release_force: needs at least 2 points"),
    ("{ travel = [0.01, 0.02], force = [1.0, 1.0] }", "release_force: travel must start at 0 m"),
    ("{ travel = [0.0, 0.02], force = [1.0] }", "release_force: 2 travel values but 1 forces"),
    ("{ travel = [0.0, 0.02] }", "release_force: missing required key 'force'"),
    ("{ travel = [0.0, nan], force = [1.0, 1.0] }", "release_force.travel[1]: value is NaN"),
    ("[0.0, 0.02]", "release_force: expected a table"),
])
def test_bad_release_force_in_a_scenario(tmp_path, capsys, inline, expect):
    from tests.cli.conftest import base_scenario, pad_body, vehicle_body, write_scenario
    from liftoff.transient import save_body

    save_body(vehicle_body(), tmp_path / "vehicle.npz")
    save_body(pad_body(), tmp_path / "pad.npz")
    (tmp_path / "thrust.csv").write_text("time,force\n0.0,0.0\n0.004,0.0\n0.006,2000.0\n0.02,2000.0\n")
    path = write_scenario(tmp_path, base_scenario())
    text = path.read_text().replace("release_time = 0.005", f"release_time = 0.005\nrelease_force = {inline}")
    path.write_text(text)
    code = main(["transient", str(path), "--out", str(tmp_path / "out"), "--no-progress"])
    err = capsys.readouterr().err
    lines = [ln for ln in err.strip().splitlines() if not ln.startswith("liftoff: warning: ")]
    assert code == 2 and len(lines) == 1 and expect in lines[0], err
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())


def test_scenario_with_release_force_runs(tmp_path, capsys):
    """The fixture vehicle (40 kg, thrust 2000 N) with pins of 500 N over 1 mm runs, its pins
    yield and are drawn out, and the summary says when."""
    from tests.cli.conftest import base_scenario, pad_body, vehicle_body, write_scenario
    from liftoff.transient import save_body

    save_body(vehicle_body(), tmp_path / "vehicle.npz")
    save_body(pad_body(), tmp_path / "pad.npz")
    (tmp_path / "thrust.csv").write_text("time,force\n0.0,0.0\n0.004,0.0\n0.006,2000.0\n0.02,2000.0\n")
    path = write_scenario(tmp_path, base_scenario())
    path.write_text(path.read_text().replace(
        "release_time = 0.005",
        "release_time = 0.005\nrelease_force = { travel = [0.0, 0.001], force = [500.0, 500.0] }"))
    code = main(["transient", str(path), "--out", str(tmp_path / "out"), "--no-progress"])
    out = capsys.readouterr().out
    assert code == 0
    line = next(ln for ln in out.splitlines() if "soft release" in ln)
    assert "post yields" in line and "drawn out" in line and "never" not in line, line


def test_fixed_point_refuses_soft_release():
    post = ContactPoint("post", ["a:Tx"], [None], KC, release_time=0.0, release_force=(TRAVEL, FORCE))
    with pytest.raises(InputError, match="contact 'post': friction, damping, latches and soft release need method"):
        TransientProblem(mass1d("a", M), ground(), [post], Forcing(), t_end=0.1, method="fixed-point")
