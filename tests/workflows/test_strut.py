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
