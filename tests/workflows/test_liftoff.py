"""Lift-off workflow physics on the stick stack (fast, no dolfinx), against independent
references: the static solution (settle check, section 2.6), a monolithic coupled model
integrated by scipy (bolted phase), rigid-body mechanics (control system), statics
(cryo self-equilibrium, Table-1 directions)."""
import tomllib
from dataclasses import replace

import numpy as np
import pytest

from liftoff.transient import Forcing, PointForce, solve, static_solution
from liftoff.workflows.cache import StageCache
from liftoff.workflows.loads import build_problem, table1
from liftoff.workflows.pipeline import build_stack
from liftoff.config import default_text, parse_scenario


# the default scenario on a coarse stick model (6 m beam elements): fast, no dolfinx
# (system modes cut without residual vectors on purpose: a small modal model with a large step;
# the modes kept and their convergence are tests/workflows/test_truncation_run.py's)
STICK = {"source": "stick", "mesh_size": 6.0, "zeta": 0.01,
         "system": {"f_max": 60.0, "pad_f_max": 100.0, "residual_vectors": False}, "pad": {"f_max": 100.0}}


def scenario(**over):
    d = tomllib.loads(default_text())
    d["model"] = STICK
    d.pop("case")
    for k, v in over.items():
        d[k] = v if not isinstance(v, dict) else {**d.get(k, {}), **v}
    return parse_scenario(d, "test.toml").cases[0]


@pytest.fixture(scope="module")
def stack():
    return build_stack(scenario().model, StageCache(None), progress=False)


def test_bolted_phase_matches_monolithic_model(stack, monolithic):
    """Before release the two uncoupled bodies + contact forces must reproduce the coupled
    system (vehicle + pad + K_C as one modal model, eq. 2) integrated by scipy DOP853
    (rtol 1e-10). SSME build-up over 0-3 s, gravity and cryo preload, static start.
    The two-body step treats the contact force as linear over a step (eq. 8), a
    second-order approximation: the error must fall ~4x when h halves (> 3 asserted; the
    reference's own error, ~1e-8, limits the finest level), and at h0/2 (h0 = 0.25/f_h,
    eq. 12) be below 1e-5 of the peak post force (measured 3.0e-7, then 8.5e-8 and 2.4e-8:
    ratios 3.5, 3.6, with every attach joint released)."""
    case = scenario(time={"t_end": 3.0}, control={"enabled": False}, softening={"enabled": False})
    cp = build_problem(case, stack, progress=False)
    errs = monolithic.errors(cp.problem, (2, 4, 8))
    ratios = [errs[i] / errs[i + 1] for i in range(2)]
    print(f"bolted phase: max error / peak post force at h0/2, h0/4, h0/8: {errs}; ratios {ratios}")
    assert errs[0] < 1e-5
    assert all(r > 3.0 for r in ratios)          # second order: 4 per halving


def test_settle_check_oscillates_about_static_solution(stack, monolithic):
    """Section 2.6: started from zero under constant loads only (gravity, cryo; softening
    as held feedback), the run oscillates about the static solution. With zeta = 0.2 the
    elastic modes decay fast; the mean (fitted, see below) equals the static post forces
    within 1e-5 of their peak (measured ~4e-8; the fit leaves out modes below 1e-4)."""
    case = scenario(time={"t_end": 20.0}, control={"enabled": False},
                    post_defaults={"release_time": float("inf")}, softening={"until": float("inf")})
    case = replace(case, engines=[])
    st = replace(stack, vehicle=replace(stack.vehicle, zeta=np.where(stack.vehicle.omega > 0, 0.2, 0.0)),
                 pad=replace(stack.pad, zeta=np.full(stack.pad.n_modes, 0.2)))
    cp = build_problem(case, st, progress=False)
    prob = replace(cp.problem, initial="zero", progress=False)
    res = solve(prob)
    _, f_static = static_solution(prob.body_a, prob.body_b, prob.contacts, prob.forcing)
    # Modes that are mostly rigid-body motion of the vehicle on the posts (rocking ~0.3 Hz,
    # bounce) are lightly damped (rigid modes carry no modal damping), so the mean is found
    # by a least-squares fit over the last 12 s of c + sum_k (A_k cos w_k t + B_k sin w_k t)
    # over every coupled mode not yet decayed below 1e-4 at the window start; w_k, sigma_k
    # from the damped monolithic eigenproblem (state space), independent of transient/.
    K, D, ks = monolithic.coupled_K(prob)
    na, n = prob.body_a.n_modes, K.shape[0]
    K[:na, :na] -= cp.softening.dense()[0]
    C = np.diag(2 * np.concatenate([prob.body_a.zeta * prob.body_a.omega, prob.body_b.zeta * prob.body_b.omega]))
    lam = np.linalg.eigvals(np.block([[np.zeros((n, n)), np.eye(n)], [-K, -C]]))
    t_w = res.time[-1] - 12.0
    alive = lam[(lam.imag > 0) & (np.exp(lam.real * t_w) > 1e-4)]
    late = res.time >= t_w
    t = res.time[late] - t_w
    cols = [np.ones_like(t)]
    for z in alive:
        e = np.exp(z.real * t)
        cols += [e * np.cos(z.imag * t), e * np.sin(z.imag * t)]
    mean = np.linalg.lstsq(np.column_stack(cols), res.contact_force[late], rcond=None)[0][0]
    scale = np.abs(f_static).max()
    print(f"settle: {alive.size} slow modes fitted ({np.round(alive.imag / 2 / np.pi, 3)} Hz); "
          f"max |mean - static| / peak static = {np.abs(mean - f_static).max() / scale:.2e}; "
          f"sum of static post Tz = {f_static[2::3].sum() / 1e6:.4f} MN")
    assert np.abs(mean - f_static).max() < 1e-5 * scale
    # vertical equilibrium: the posts carry the weight (gravity only; cryo is self-equilibrated)
    weight = -stack.vehicle.mass * case.gravity[2]
    assert f_static[2::3].sum() == pytest.approx(weight, rel=1e-9)


def test_cryo_preload_is_self_equilibrated(stack, monkeypatch):
    """The cryo load at boundary DOFs has zero resultant; statically the post forces it
    causes sum to zero (the pad sees only internal restraint loads, section 4.3). With the
    booster attach joints welded, the core's shrinkage between its forward and aft attaches
    loads the posts (above 10 kN); with the default's statically determinate joints
    (config.model.SRB_ATTACH_RELEASE) it passes to no booster, and the posts see less than
    1 % of that."""
    from liftoff.config import model as config_model
    from liftoff.transient.effects import load_resultant

    monkeypatch.setattr(config_model, "SRB_ATTACH_RELEASE", {"fwd": (), "aft": ()})
    welded = build_stack(scenario().model, StageCache(None), progress=False)
    post = {}
    for key, st in (("determinate", stack), ("welded", welded)):
        case = scenario()
        cp = build_problem(case, st, progress=False)
        assert cp.cryo, "default scenario has cryo on"
        R = load_resultant(st.vehicle, cp.cryo)
        scale = max(abs(v) for v in cp.cryo.values())
        assert np.abs(R[:3]).max() < 1e-9 * scale
        forcing = Forcing(constant=[PointForce("a", k, v) for k, v in cp.cryo.items()])
        _, f = static_solution(cp.problem.body_a, cp.problem.body_b, cp.problem.contacts, forcing)
        for j in range(3):
            assert abs(f[j::3].sum()) < 1e-8 * np.abs(f).max()   # zero net force
        post[key] = np.abs(f).max()
    print(f"largest post force from the cryo preload: {post}")
    assert post["welded"] > 1e4 and post["determinate"] < 1e-2 * post["welded"]


def test_released_attach_directions_carry_no_force():
    """An attach joint's released directions (config.model.SRB_ATTACH_RELEASE for a booster,
    ORBITER_ATTACH_RELEASE for the orbiter's bipods) pass no force between the core and the
    component: their attach recovery rows are zero for the whole run (the component's own
    boundary rows there would hold only residuals: the modal damping's, the softening's, the
    truncation's). Statics at t0 (on the posts, with the cryo preload, every system mode kept:
    the stick's 196): a booster's posts and attach forces hold up its weight, sum of Tz = m g
    (the axial attach force is the forward joint's alone: the aft one releases Tz); the
    orbiter's three bipods hold up its weight, Tz at the aft ones alone, and pass no net
    lateral force, and the tank's cryo shrinkage changes none of their forces (a determinate
    mount; welded, the shrinkage between the fittings loads them); the
    gravity softening is off, its feedback forces being loads on the component too (1.7 kN
    here). Tolerance 1e-9: static solves of cond ~1e8 (measured 4e-11)."""
    from liftoff.config.model import ORBITER_ATTACH_RELEASE, SRB_ATTACH_RELEASE
    from liftoff.core.labels import COMPONENTS
    from liftoff.reduction import cg_acceleration_recovery

    every_mode = {**STICK, "system": {**STICK["system"], "residual_vectors": True}}
    base = scenario(model=every_mode, softening={"enabled": False})
    stack = build_stack(base.model, StageCache(None), progress=False)
    assert stack.vehicle.omega.size == stack.vehicle_asm.n_dof
    case = replace(base, time=replace(base.time, t_end=base.time.t0 + 0.05))
    assert case.cryo.enabled
    cp = build_problem(case, stack, progress=False)
    res = solve(cp.problem)
    g = -case.gravity[2]
    checked = 0
    for name, (point, comp) in cp.attach.items():
        free = (SRB_ATTACH_RELEASE[point.rsplit("_", 1)[-1]] if comp.startswith("srb") else
                ORBITER_ATTACH_RELEASE[point.split("_")[2]])
        hist = res.recovered[name]
        for k, c in enumerate(COMPONENTS):
            assert np.all(hist[:, k] == 0.0) if c in free else np.any(hist[:, k] != 0.0), (name, c)
            checked += c in free
    assert checked == 12 + 12
    for side in ("left", "right"):
        _, mass = cg_acceleration_recovery(stack.vehicle_asm, stack.vehicle_modes, f"srb_{side}")
        tz = sum(res.recovered[f"attach_att_srb_{side}_{p}"][0, 2] for p in ("fwd", "aft"))
        posts = sum(res.contact_force[0, j] for j, d in enumerate(res.contact_directions)
                    if d.component == "Tz" and d.contact.startswith(side))
        assert tz + posts == pytest.approx(mass[2] * g, rel=1e-9), side
    _, mass = cg_acceleration_recovery(stack.vehicle_asm, stack.vehicle_modes, "orbiter")
    bipods = sum(res.recovered[f"attach_att_orb_{p}"][0, :3] for p in ("fwd", "aft_left", "aft_right"))
    assert bipods[2] == pytest.approx(mass[2] * g, rel=1e-9)
    assert np.abs(bipods[:2]).max() < 1e-9 * mass[2] * g
    dry = build_problem(replace(case, cryo=replace(case.cryo, enabled=False)), stack, progress=False)
    res_dry = solve(dry.problem)
    for p in ("fwd", "aft_left", "aft_right"):           # the tank's shrinkage reaches no bipod
        cryo = res.recovered[f"attach_att_orb_{p}"][0, :3] - res_dry.recovered[f"attach_att_orb_{p}"][0, :3]
        assert np.abs(cryo).max() < 1e-9 * mass[2] * g, p


def test_control_system_holds_attitude_in_flight(stack):
    """After release, with the reference's control law on (eq. 15-21, law = "moment"), the
    applied forces have no moment about the c.g., so once the posts have separated the
    vehicle's rigid rotation has no angular acceleration: it stays within its release
    value + rate * time. The bound: |fitted angular acceleration| < 1e-6 of the
    uncontrolled run's."""
    out = {}
    for on in (True, False):
        case = scenario(time={"t_end": 8.6}, control={"enabled": on, "law": "moment"})
        cp = build_problem(case, stack, progress=False)
        res = solve(replace(cp.problem, progress=False))
        free = np.all(res.contact_state == 2, axis=1) & (res.time > 7.0)
        assert free.sum() > 100 and np.all(free[np.argmax(free):])
        t = res.time[free]
        rot = res.rigid_body_motion_a[free, 3:]
        out[on] = np.array([np.polyfit(t, rot[:, j], 2)[0] * 2 for j in range(3)])
    print("fitted angular acceleration in flight (rad/s^2): control on", out[True], "off", out[False])
    assert np.abs(out[False]).max() > 1e-5
    assert np.abs(out[True]).max() < 1e-6 * np.abs(out[False]).max()


def test_table1_rows_change_in_expected_direction(stack):
    """Gravity softening increases the lateral c.g. lean (towards the orbiter, +y: the c.g.
    is offset that way from the post pattern) with and without cryo; gravity alone moves
    the c.g. down; the cryo shrinkage of the core moves it up: the core hangs on its
    forward booster attaches (the aft ones release Tz), so its LH2 tank below them rises as
    it shrinks and lifts the orbiter attached to it, while the LOX tank above sinks less
    far (welded at both attaches, the core's shrinkage was held between them, and the c.g.
    went down)."""
    case = scenario()
    cp = build_problem(case, stack, progress=False)
    rep = table1(stack, cp, case)
    print(rep.table())
    g, gs, gc, gsc = rep.motion
    assert g[1] > 0 and g[2] < 0
    assert gs[1] > g[1] and gsc[1] > gc[1]                   # softening: more lean
    assert gs[1] / g[1] < 1.5                                # ... a second-order effect
    assert gc[2] > g[2]                                      # cryo: c.g. up
    assert abs(g[0]) < 1e-9 * abs(g[1])                      # symmetric stack: no x motion


def test_model_dependent_checks_name_file_and_key(stack):
    """Checks that need the models (points, DOF labels, volumes, gimbal geometry) use the
    one wording 'file: key.path: what' too."""
    from dataclasses import replace

    from liftoff.core.errors import InputError

    bad = [(dict(control={"gimbals": ["srb_left_gimbal:Tx", "srb_left_gimbal:Ty", "stack_top:Tq"]}),
            "test.toml: control.gimbals[2]: malformed DOF label"),
           (dict(control={"gimbals": ["srb_left_gimbal:Tx", "srb_left_gimbal:Ty", "nowhere:Tx"]}),
            "test.toml: control.gimbals[2]: unknown DOF label 'nowhere:Tx'"),
           (dict(control={"gimbals": ["srb_left_gimbal:Tx", "srb_right_gimbal:Tx", "stack_top:Tx"]}),
            "test.toml: control.gimbals: control system: the gimbal DOFs"),
           (dict(softening={"labels": ["stack_top:Tq"]}), "test.toml: softening.labels[0]: malformed DOF label"),
           (dict(cryo={"volumes": ["core_skin"]}), "test.toml: cryo.volumes: 'core_skin' is not a volume of component"),
           (dict(recovery={"payload": "cargo_bay"}), "test.toml: recovery.payload: point 'cargo_bay' is not on the vehicle"),
           (dict(force=[{"label": "stack_top:Rq", "value": 1.0}]), "test.toml: force[0].label: malformed DOF label")]
    for over, expect in bad:
        with pytest.raises(InputError) as exc:
            build_problem(scenario(**over), stack, progress=False)
        assert str(exc.value).startswith(expect), str(exc.value)
    case = scenario(force=[{"label": "stack_top:Tx", "value": 1.0}])
    with pytest.raises(InputError, match=r"^test.toml: force\[0\] 'top:Tx'.label: unknown DOF label 'top:Tx'"):
        build_problem(replace(case, forces=[replace(case.forces[0], label="top:Tx")]), stack, progress=False)
