"""Struts between components (``type = "strut"``, reduction/strut.py, issue 26): a core stick
and a side booster stick (both ``type = "beam"``) joined by two horizontal tube struts, as
the ET-SRB attach struts join the Shuttle's tank and boosters, assembled through their
joints by Craig-Bampton.

A second method for the vehicle's free-free modes: every component's full FE matrices
(the sticks', the struts', the payload's rigid mass) assembled by their point labels and
solved densely, without Craig-Bampton. The nodes are the same, so the difference is the CB
truncation at f_max = 100 Hz, from above (Ritz upper bounds): 2e-4 asked, as
tests/workflows/test_beam_component.py. The struts carry the booster: without them its
modes would be rigid (more than six zero modes)."""
from __future__ import annotations

import copy
import tomllib
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sla

SCENARIO = Path(__file__).resolve().parents[1] / "data" / "beam_stick" / "scenario.toml"
TUBE = {"shape": "tube", "r_out": 0.15, "t": 0.01}


def _with_booster(data: dict) -> dict:
    d = copy.deepcopy(data)
    comp = d["model"]["component"]
    comp["stage1"]["params"]["points"].update(s_fwd=[1.83, 0.0, 30.0], s_aft=[1.83, 0.0, 8.0])
    comp["booster"] = {"type": "beam", "mesh_size": 1.0, "f_max": 100.0, "params": {
        "stations": [5.0, 35.0], "radius": [0.9], "thickness": [0.01], "mass_per_length": [2000.0],
        "axis_xy": [4.5, 0.0], "points": {"b_fwd": 30.0, "b_aft": 8.0}}}
    for k, z in (("fwd", 30.0), ("aft", 8.0)):
        comp[f"strut_{k}"] = {"type": "strut", "f_max": 100.0, "params": {
            "ends": {f"s_{k}": [1.83, 0.0, z], f"b_{k}": [4.5, 0.0, z]}, "section": TUBE, "elements": 4}}
        d["model"]["joint"] += [{"name": f"s_{k}", "components": ["stage1", f"strut_{k}"]},
                                {"name": f"b_{k}", "components": ["booster", f"strut_{k}"]}]
    return d


def _b_aft_releasing(data: dict, strut: str, dof: str) -> dict:
    """``data`` (changed) with joint b_aft joining the booster to ``strut``, releasing ``dof``."""
    for j in data["model"]["joint"]:
        if j["name"] == "b_aft":
            j["components"], j["release"] = ["booster", strut], [dof]
    return data


def test_struts_join_components_as_their_full_matrices_do(tmp_path):
    pytest.importorskip("petsc4py")
    from liftoff.config import parse_scenario
    from liftoff.core.labels import COMPONENTS
    from liftoff.reduction.beam_stick import beam_stick_component
    from liftoff.reduction.strut import strut_component
    from liftoff.workflows.cache import StageCache
    from liftoff.workflows.run import prepare_models

    sc = parse_scenario(_with_booster(tomllib.loads(SCENARIO.read_text())), "struts.toml", SCENARIO.parent)
    stacks, _ = prepare_models(sc, StageCache(tmp_path / "cache"), False, lambda *a, **k: None)
    stack = next(iter(stacks.values()))
    model = sc.cases[0].model
    labels, K, M = {}, {}, {}

    def add(comp):                                         # full matrices by point label
        idx = np.array([labels.setdefault(lb, len(labels)) for lb in comp.dof_labels])
        for acc, A in ((K, comp.K), (M, comp.M)):
            A = A.tocoo()
            for i, j, v in zip(idx[A.row], idx[A.col], A.data):
                acc[(i, j)] = acc.get((i, j), 0.0) + v

    for name in ("stage1", "stage2", "booster"):
        add(beam_stick_component(model.components[name].builder, name)[0])
    for name in ("strut_fwd", "strut_aft"):
        add(strut_component(model.components[name].builder, name)[0])
    n = len(labels)
    Kd, Md = np.zeros((n, n)), np.zeros((n, n))
    for acc, D in ((K, Kd), (M, Md)):
        for (i, j), v in acc.items():
            D[i, j] += v
    pay = model.components["payload"].builder                # the rigid payload: its c.g. at its point
    for c, v in zip(COMPONENTS, (pay.mass,) * 3 + tuple(pay.inertia)):
        Md[labels[f"payload_if:{c}"], labels[f"payload_if:{c}"]] += v
    w = sla.eigh(Kd, Md, eigvals_only=True, subset_by_index=[0, 13])
    ref = np.sqrt(np.abs(w[6:])) / (2 * np.pi)
    got = stack.vehicle.omega[6:14] / (2 * np.pi)
    print("free-free (Hz), CB:", np.round(got, 4), "\n          dense:", np.round(ref, 4))
    assert w[6] > (2 * np.pi * 0.5) ** 2                    # six rigid modes only: the struts hold the booster
    assert np.all(got >= ref * (1 - 1e-12))
    np.testing.assert_allclose(got, ref, rtol=2e-4)


def test_strut_bad_input():
    from liftoff.config import parse_scenario
    from liftoff.core.errors import InputError

    d = _with_booster(tomllib.loads(SCENARIO.read_text()))
    bad = copy.deepcopy(d)
    bad["model"]["component"]["strut_fwd"]["params"]["ends"] = {"s_fwd": [1.83, 0.0, 30.0]}
    with pytest.raises(InputError, match=r"strut_fwd.*ends: give exactly two named end points"):
        parse_scenario(bad, "s.toml", SCENARIO.parent)
    bad = copy.deepcopy(d)
    del bad["model"]["component"]["strut_fwd"]["params"]["section"]
    with pytest.raises(InputError, match=r"strut_fwd\.params\.section: missing"):
        parse_scenario(bad, "s.toml", SCENARIO.parent)


@pytest.mark.parametrize("key, value, message", [("E", -2e11, "Young's modulus E = -200000000000.0 Pa must be > 0"),
                                                 ("nu", 0.5, "Poisson's ratio nu = 0.5 must be in (-1, 0.5)"),
                                                 ("rho", 0.0, "density rho = 0.0 kg/m^3 must be > 0")])
def test_strut_material_is_checked_as_every_material(key, value, message):
    """The strut's E, nu and rho go through the project's one elastic-material check
    (liftoff.core.elastic), as a meshed Material's: the same bounds and words."""
    from liftoff.config import parse_scenario
    from liftoff.core.errors import InputError

    bad = _with_booster(tomllib.loads(SCENARIO.read_text()))
    bad["model"]["component"]["strut_fwd"]["params"][key] = value
    with pytest.raises(InputError) as exc:
        parse_scenario(bad, "s.toml", SCENARIO.parent)
    assert "strut_fwd" in str(exc.value) and message in str(exc.value) and "\n" not in str(exc.value)


PIN_AFT = {"s_aft": ["Ry", "Rz"], "b_aft": ["Rx", "Ry", "Rz"]}   # the aft strut (along x) pin-ended


def test_a_pin_ended_strut_passes_no_moment(tmp_path):
    """``[[model.joint]] release``: the aft strut pinned at both ends (bending rotations
    released at the stage, all three at the booster; its torsion held at one end, else it
    would spin free). Checked against (1) the same dense full matrices as above with the
    strut's released end DOFs kept as its own (2e-4, the CB truncation, from above but for
    the round-off of the soft first mode, 2.2e-8 below, 1e-6 allowed); (2)
    Rayleigh's constraint theorem: releasing DOFs removes a constraint, so no frequency
    rises (the welded vehicle's, same CB models; round-off 1e-9); (3) the strut's ends:
    in every system mode the moments the rest of the vehicle applies there, K x - w^2 M x
    on the released rows, vanish to round-off (1e-7 of the largest end force over the
    mass-normalised modes; 3e-14 here, 0.40 welded), while its axial force does not."""
    pytest.importorskip("petsc4py")
    from liftoff.config import parse_scenario
    from liftoff.core.labels import COMPONENTS
    from liftoff.reduction import interface_force_recovery
    from liftoff.reduction.assembly import released_label
    from liftoff.reduction.beam_stick import beam_stick_component
    from liftoff.reduction.strut import strut_component
    from liftoff.workflows.cache import StageCache
    from liftoff.workflows.run import prepare_models

    welded = _with_booster(tomllib.loads(SCENARIO.read_text()))
    pinned = copy.deepcopy(welded)
    for j in pinned["model"]["joint"]:
        j["release"] = PIN_AFT.get(j["name"], [])
    cache = StageCache(tmp_path / "cache")
    stacks = {}
    for key, data in (("welded", welded), ("pinned", pinned)):
        sc = parse_scenario(data, f"{key}.toml", SCENARIO.parent)
        stacks[key] = next(iter(prepare_models(sc, cache, False, lambda *a, **k: None)[0].values()))
    model = sc.cases[0].model
    stack = stacks["pinned"]
    freed = {(f"{p}:{c}") for p, cs in PIN_AFT.items() for c in cs}
    labels, K, M = {}, {}, {}

    def add(comp, name):
        own = [released_label(lb, name) if name == "strut_aft" and lb in freed else lb for lb in comp.dof_labels]
        idx = np.array([labels.setdefault(lb, len(labels)) for lb in own])
        for acc, A in ((K, comp.K), (M, comp.M)):
            A = A.tocoo()
            for i, j, v in zip(idx[A.row], idx[A.col], A.data):
                acc[(i, j)] = acc.get((i, j), 0.0) + v

    for name in ("stage1", "stage2", "booster"):
        add(beam_stick_component(model.components[name].builder, name)[0], name)
    for name in ("strut_fwd", "strut_aft"):
        add(strut_component(model.components[name].builder, name)[0], name)
    n = len(labels)
    Kd, Md = np.zeros((n, n)), np.zeros((n, n))
    for acc, D in ((K, Kd), (M, Md)):
        for (i, j), v in acc.items():
            D[i, j] += v
    pay = model.components["payload"].builder
    for c, v in zip(COMPONENTS, (pay.mass,) * 3 + tuple(pay.inertia)):
        Md[labels[f"payload_if:{c}"], labels[f"payload_if:{c}"]] += v
    w = sla.eigh(Kd, Md, eigvals_only=True, subset_by_index=[0, 13])
    ref = np.sqrt(np.abs(w[6:])) / (2 * np.pi)
    got = stack.vehicle.omega[6:14] / (2 * np.pi)
    before = stacks["welded"].vehicle.omega[6:14] / (2 * np.pi)
    print("free-free (Hz), pinned:", np.round(got, 4), "\n   dense:", np.round(ref, 4), "\n  welded:", np.round(before, 4))
    assert w[6] > (2 * np.pi * 0.05) ** 2                   # six rigid modes only (0.14 Hz: the booster rocking
    #                                                         about the aft strut on the fwd strut's bending)
    assert np.all(got >= ref * (1 - 1e-6))                  # from above, but for the 0.14 Hz mode's round-off: -2.2e-8
    np.testing.assert_allclose(got, ref, rtol=2e-4)
    assert np.all(got <= before * (1 + 1e-9)) and np.any(got < before * (1 - 1e-3))
    ends = [f"{p}:{c}" for p in PIN_AFT for c in COMPONENTS]
    D, A = interface_force_recovery(stack.vehicle_asm, stack.vehicle_modes, "strut_aft", ends)
    F = D - A * stack.vehicle_modes.omega ** 2              # the end forces of each mode shape
    moments = [ends.index(lb) for lb in freed]
    scale = np.abs(F[:, 6:]).max()                          # mass-normalised modes: one scale for all
    assert np.abs(F[moments, 6:]).max() <= 1e-7 * scale
    pinned_ends = np.abs(F[[ends.index("s_aft:Tx"), ends.index("b_aft:Tx")], 6:]).max()
    assert pinned_ends > 0.1 * scale                        # the strut still carries its axial force


def test_pinned_strut_against_the_joint_releases_of_a_strut(tmp_path):
    """``pinned = true`` (the strut's end elements' bending released in its own axes, its
    torsion left out, its end points three translations each) against the joint releases of
    the test above (the same strut welded in the element, its end rotations released in
    global axes at the joints, the aft strut lying along x): the vehicle's first eight
    free-free frequencies agree. They differ only in the strut's end rotations' and torsion's
    inertia (the joint releases keep them as DOFs, which the strut's Craig-Bampton cut at 100
    Hz then truncates): measured 3e-7 or less, 1e-6 allowed. The pinned strut's end forces
    carry no moment rows at all (its end points have no rotations), and a pinned strut may
    lie at any angle, which global-axis releases cannot express."""
    pytest.importorskip("petsc4py")
    from liftoff.config import parse_scenario
    from liftoff.workflows.cache import StageCache
    from liftoff.workflows.run import prepare_models

    released = _with_booster(tomllib.loads(SCENARIO.read_text()))
    for j in released["model"]["joint"]:
        j["release"] = PIN_AFT.get(j["name"], [])
    pinned = _with_booster(tomllib.loads(SCENARIO.read_text()))
    pinned["model"]["component"]["strut_aft"]["params"]["pinned"] = True
    cache = StageCache(tmp_path / "cache")
    stacks = {}
    for key, data in (("released", released), ("pinned", pinned)):
        sc = parse_scenario(data, f"{key}.toml", SCENARIO.parent)
        stacks[key] = next(iter(prepare_models(sc, cache, False, lambda *a, **k: None)[0].values()))
    got = stacks["pinned"].vehicle.omega[6:14]
    ref = stacks["released"].vehicle.omega[6:14]
    print("pinned / joint releases - 1:", got / ref - 1)
    np.testing.assert_allclose(got, ref, rtol=1e-6)
    assert stacks["pinned"].cbs["strut_aft"].boundary_labels == ("s_aft:Tx", "s_aft:Ty", "s_aft:Tz",
                                                                 "b_aft:Tx", "b_aft:Ty", "b_aft:Tz")


def test_pinned_strut_is_a_two_force_member():
    """A pinned strut at an oblique angle, statically reduced to its end translations
    (Guyan, exact for statics): one stiffness, EA/L along its axis (1e-12), none across it
    or about it (five zero eigenvalues, 1e-12 of it), so its end forces are equal, opposite
    and axial whatever its ends do; its mass the bar's, rho A L in each direction (1e-12)."""
    import scipy.linalg as la

    from liftoff.core.beam import tube
    from liftoff.reduction.strut import Strut, strut_component

    a, b = np.array([0.3, -0.2, 1.0]), np.array([1.1, 0.7, 1.6])
    L = np.linalg.norm(b - a)
    sec = tube(0.1, 0.02)
    for n in (1, 4):
        comp, _ = strut_component(Strut("s", {"a": a.tolist(), "b": b.tolist()}, dict(TUBE, r_out=0.1, t=0.02),
                                        elements=n, pinned=True))
        assert comp.dof_labels == ("a:Tx", "a:Ty", "a:Tz", "b:Tx", "b:Ty", "b:Tz")
        K, M = comp.K.toarray(), comp.M.toarray()
        e = comp.label_dofs
        i = np.setdiff1d(np.arange(K.shape[0]), e)
        T = np.eye(K.shape[0])[:, e]
        if i.size:
            T[i] = -la.solve(K[np.ix_(i, i)], K[np.ix_(i, e)])
        Kb = T.T @ K @ T
        k = 2e11 * sec.A / L
        w = np.sort(la.eigvalsh(Kb))
        assert np.abs(w[:5]).max() < 1e-12 * k and w[5] == pytest.approx(2 * k, rel=1e-12)
        d = (b - a) / L
        np.testing.assert_allclose(Kb @ np.r_[-d, d] / 2, k * np.r_[-d, d], rtol=1e-12, atol=1e-12 * k)
        for j in range(3):
            u = np.zeros(K.shape[0])
            u[e[[j, j + 3]]] = 1.0
            if i.size:
                u[i] = T[i] @ u[e]
            assert u @ M @ u == pytest.approx(7850.0 * sec.A * L, rel=1e-12)


def test_strut_pinned_checked():
    from liftoff.config import parse_scenario
    from liftoff.core.errors import InputError

    bad = _with_booster(tomllib.loads(SCENARIO.read_text()))
    bad["model"]["component"]["strut_aft"]["params"]["pinned"] = "yes"
    with pytest.raises(InputError, match=r"strut_aft.*pinned"):
        parse_scenario(bad, "s.toml", SCENARIO.parent)


def test_the_documented_attach_hardware_is_the_comparisons_model():
    """docs/workflow.md's TOML for the booster's aft struts and for the intertank's thrust
    beam (the left booster's, and the same with "right"), put into the default scenario in
    place of its attach joints there, parses to the struts, joints and layout that
    benchmarks/strut_compare.py builds (its "struts_beam" variant): the documented example
    is the compared model."""
    import re
    import runpy

    from liftoff.config import default_text, parse_scenario, parse_toml

    root = Path(__file__).resolve().parents[2]
    doc = (root / "docs" / "workflow.md").read_text()
    block = re.search(r"```toml\n(\[model\.vehicle\.params\]\nsrb_aft_attach = \"struts\".*?)```", doc, re.S).group(1)
    left = tomllib.loads(block)
    right = tomllib.loads(block.replace("left", "right"))
    data = parse_toml(default_text(), "default_scenario.toml")
    model = data["model"]
    model.setdefault("vehicle", {}).setdefault("params", {}).update(left["model"]["vehicle"]["params"])
    model["component"].update({**left["model"]["component"], **right["model"]["component"]})
    model["joint"] = [j for j in model["joint"] if not re.fullmatch(r"att_srb_\w+_aft", j["name"])] \
        + left["model"]["joint"] + right["model"]["joint"]
    data["recovery"]["attach"] = [a for a in data["recovery"]["attach"] if not re.fullmatch(r"att_srb_\w+_aft", a)]
    beam = re.search(r"```toml\n(\[model\.vehicle\.params\]\nsrb_fwd_attach = \"beam\".*?)```", doc, re.S).group(1)
    left, right = tomllib.loads(beam), tomllib.loads(beam.replace("left", "right"))
    model["vehicle"]["params"].update(left["model"]["vehicle"]["params"])
    model["component"].update({**left["model"]["component"],          # the span once, the right fitting
                               **{k: v for k, v in right["model"]["component"].items() if "fitting" in k}})
    balls = {j["name"] for j in left["model"]["joint"] + right["model"]["joint"]}
    model["joint"] = [j for j in model["joint"] if j["name"] not in balls] + left["model"]["joint"] \
        + right["model"]["joint"]
    documented = parse_scenario(data, "documented.toml").cases[0].model
    bench = runpy.run_path(str(root / "benchmarks" / "strut_compare.py"), run_name="strut_compare")
    compared = parse_scenario(bench["edit_for"]("struts_beam")(parse_toml(default_text(), "default_scenario.toml")),
                              "compared.toml").cases[0].model
    assert documented.layout == compared.layout
    struts = {n for n, c in compared.components.items() if c.type == "strut"}
    assert len(struts) == 9 and struts == {n for n, c in documented.components.items() if c.type == "strut"}
    for n in struts:
        assert documented.components[n].builder == compared.components[n].builder

    def joints(m):                  # without releases the components' order says nothing
        return {(j.name, j.components if j.release else frozenset(j.components), j.release) for j in m.joints}

    assert joints(documented) == joints(compared)


def test_strut_ends_by_layout_names_and_their_errors():
    """``ends = [name, other]``: two of the layout's points (StackLayout.named_points), their
    coordinates the layout's; a name the layout has not is one line naming the key and the
    names it has; the stick source, which joins each booster at one aft point, refuses the
    aft struts' layout."""
    import runpy

    from liftoff.config import default_text, parse_scenario, parse_toml
    from liftoff.core.errors import InputError
    from liftoff.meshes.layout import StackLayout

    root = Path(__file__).resolve().parents[2]
    bench = runpy.run_path(str(root / "benchmarks" / "strut_compare.py"), run_name="strut_compare")
    data = bench["edit_for"]("struts")(parse_toml(default_text(), "default_scenario.toml"))
    model = parse_scenario(copy.deepcopy(data), "s.toml").cases[0].model
    named = StackLayout(srb_aft_attach="struts").named_points()
    ends = model.components["srb_right_aft_strut_diagonal"].builder.ends
    assert list(ends) == ["et_srb_right_aft_upper", "srb_right_aft_lower"]
    for n, x in ends.items():
        np.testing.assert_array_equal(x, named[n])
    bad = copy.deepcopy(data)
    bad["model"]["component"]["srb_left_aft_strut_upper"]["params"]["ends"] = ["et_srb_left_aft_uper",
                                                                                "srb_left_aft_upper"]
    with pytest.raises(InputError, match=r"srb_left_aft_strut_upper\.params\.ends\[0\]: 'et_srb_left_aft_uper' is "
                                         r"not a point of the layout .*et_srb_left_aft_upper") as exc:
        parse_scenario(bad, "s.toml")
    assert "\n" not in str(exc.value)
    stick = parse_toml(default_text(), "default_scenario.toml")
    stick["model"]["source"] = "stick"
    stick["model"].setdefault("vehicle", {}).setdefault("params", {})["srb_aft_attach"] = "struts"
    with pytest.raises(InputError, match=r"srb_aft_attach: the stick model joins each booster at one aft point"):
        parse_scenario(stick, "s.toml")


def test_the_documented_forward_bipod_is_the_comparisons():
    """docs/workflow.md's TOML for the orbiter's forward bipod: its struts and joints are
    those benchmarks/strut_compare.py's "all" variant builds (the aft bipods, described in
    words there, are that variant's too: StackLayout.orbiter_bipods)."""
    import re
    import runpy

    from liftoff.config import default_text, parse_scenario, parse_toml

    root = Path(__file__).resolve().parents[2]
    doc = (root / "docs" / "workflow.md").read_text()
    block = tomllib.loads(re.search(r"```toml\n(\[model\.vehicle\.params\]\norbiter_attach = \"bipods\".*?)```",
                                    doc, re.S).group(1))
    bench = runpy.run_path(str(root / "benchmarks" / "strut_compare.py"), run_name="strut_compare")
    data = bench["edit_for"]("all")(parse_toml(default_text(), "default_scenario.toml"))
    assert data["model"]["vehicle"]["params"]["orbiter_attach"] == "bipods"
    for name, comp in block["model"]["component"].items():
        assert data["model"]["component"][name] == comp
    joints = {j["name"]: j for j in data["model"]["joint"]}
    for j in block["model"]["joint"]:
        assert joints[j["name"]] == j
    model = parse_scenario(data, "all.toml").cases[0].model
    assert sum(c.type == "strut" for c in model.components.values()) == 15


def test_attach_recovery_at_a_pinned_strut_and_bad_specs(tmp_path):
    """An attach recovery on a component at a point it shares only with a pinned strut: the
    force rows (Tx Ty Tz) as any joint's, the moment rows exactly zero (the strut brings no
    rotation there: a pin passes no moment; the component's own boundary rows held its modal
    truncation's residual, 29 N m); a recovery on a component without that point, or on no
    vehicle component, is one line naming the spec (the first was an all-zero recovery); a
    joint releasing a pinned strut's rotation is refused on reading, before any stage."""
    import dataclasses

    pytest.importorskip("petsc4py")
    from liftoff.config import parse_scenario
    from liftoff.core.errors import InputError
    from liftoff.workflows.cache import StageCache
    from liftoff.workflows.loads import recoveries
    from liftoff.workflows.run import prepare_models

    data = _with_booster(tomllib.loads(SCENARIO.read_text()))
    data["model"]["component"]["strut_aft"]["params"]["pinned"] = True
    data.setdefault("recovery", {})["attach"] = ["b_aft@booster"]
    sc = parse_scenario(copy.deepcopy(data), "pinned.toml", SCENARIO.parent)
    stack = next(iter(prepare_models(sc, StageCache(tmp_path / "cache"), False, lambda *a, **k: None)[0].values()))
    case = sc.cases[0]
    out, attach, _ = recoveries(case, stack)
    rec = next(r for r in out if r.name == "attach_b_aft")
    assert attach["attach_b_aft"] == ("b_aft", "booster")
    D, A = np.asarray(rec.disp), np.asarray(rec.acc)
    assert np.all(D[3:] == 0) and np.all(A[3:] == 0) and np.abs(D[:3]).max() > 0
    from liftoff.reduction import interface_force_recovery

    own = interface_force_recovery(stack.vehicle_asm, stack.vehicle_modes, "booster",   # what those rows held
                                   [f"b_aft:{c}" for c in ("Rx", "Ry", "Rz")])[0]
    assert np.abs(own).max() > 0                    # (the residual the zeroing takes out)
    for spec, message in (("b_aft@stage1", "'b_aft@stage1': component 'stage1' has no point 'b_aft'"),
                          ("b_aft@nowhere", "'b_aft@nowhere': no vehicle component 'nowhere'")):
        bad = dataclasses.replace(case, recovery=dataclasses.replace(case.recovery, attach=(spec,)))
        with pytest.raises(InputError, match=message):
            recoveries(bad, stack)
    with pytest.raises(InputError, match=r"joint 'b_aft' releases Rz of 'strut_aft', a pinned strut"):
        parse_scenario(_b_aft_releasing(data, "strut_aft", "Rz"), "pinned.toml", SCENARIO.parent)


def test_stick_source_refuses_the_attach_options():
    from liftoff.config import default_text, parse_scenario, parse_toml
    from liftoff.core.errors import InputError

    for key, value in (("srb_fwd_attach", "beam"), ("orbiter_attach", "bipods")):
        stick = parse_toml(default_text(), "default_scenario.toml")
        stick["model"]["source"] = "stick"
        stick["model"].setdefault("vehicle", {}).setdefault("params", {})[key] = value
        with pytest.raises(InputError, match=rf"{key}: the stick model joins"):
            parse_scenario(stick, "s.toml")


@pytest.mark.parametrize("key, value, joint", [("srb_aft_attach", "struts", "att_srb_left_aft"),
                                               ("srb_fwd_attach", "beam", "att_srb_left_fwd"),
                                               ("orbiter_attach", "bipods", "att_orb_fwd")])
def test_an_attach_option_alone_is_named_on_reading(key, value, joint):
    """The layout option without its struts and joints: the default's joint at the moved
    point is refused on reading (before: after every FE and CB stage), naming the option."""
    from liftoff.config import default_text, parse_scenario, parse_toml
    from liftoff.core.errors import InputError

    d = parse_toml(default_text(), "default_scenario.toml")
    d["model"].setdefault("vehicle", {}).setdefault("params", {})[key] = value
    with pytest.raises(InputError, match=rf"joint '{joint}': component 'core' has no point '{joint}' on this "
                                         rf"layout \(\[model.vehicle.params\] {key} = '{value}'") as exc:
        parse_scenario(d, "s.toml")
    assert "\n" not in str(exc.value)


def test_parse_time_attach_checks_leave_other_points_and_unused_options_alone():
    """The layout checks on reading look at the points the attach options place or move
    only: a joint at a booster's hold-down point (a shoe, a brace) parses as before, and an
    option's parameters that place nothing while it is off (the sway braces' offset, the
    bipods' spread; a small tank) are not evaluated (a math domain error before); a mirror
    of a pinned strut is a pinned strut (its rotation release refused on reading)."""
    from liftoff.config import default_text, parse_scenario, parse_toml
    from liftoff.core.errors import InputError

    d = parse_toml(default_text(), "d.toml")
    d["model"]["component"]["hd_shoe"] = {"type": "rigid_mass", "params": {
        "point": "srb_left_hd_1", "at": [-8.0, 1.0, 0.0], "mass": 100.0}}
    d["model"]["joint"].append({"name": "srb_left_hd_1", "components": ["srb_left", "hd_shoe"]})
    parse_scenario(d, "d.toml")
    for kw in ({"srb_aft_strut_y": 3.0}, {"orbiter_fwd_bipod_x": 5.0}):
        d = parse_toml(default_text(), "d.toml")
        d["model"].setdefault("vehicle", {}).setdefault("params", {}).update(kw)
        parse_scenario(d, "d.toml")
    data = _with_booster(tomllib.loads(SCENARIO.read_text()))
    data["model"]["component"]["strut_aft"]["params"]["pinned"] = True
    data["model"]["component"]["strut_aft2"] = {"mirror": {"of": "strut_aft", "normal": "y"}}
    with pytest.raises(InputError, match=r"joint 'b_aft' releases Rx of 'strut_aft2', a pinned strut"):
        parse_scenario(_b_aft_releasing(data, "strut_aft2", "Rx"), "m.toml", SCENARIO.parent)
