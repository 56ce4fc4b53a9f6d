"""Any launcher as sticks (issue 23): tests/data/beam_stick/scenario.toml, a two-stage vehicle
of two ``type = "beam"`` components joined at ``is_1``, a ``rigid_mass`` payload (its c.g. at
its point) on ``rigid_ground``, run end to end by ``liftoff run``'s API.

* A second method for the vehicle's free-free modes: the same structure as ONE stick
  (stations 0, 2, 40, 52 m; the payload as a lumped mass at its point) solved densely,
  without Craig-Bampton or assembly. The nodes are the same, so the models are the same
  and the difference is the CB truncation at f_max = 100 Hz, from above (a Ritz
  reduction's eigenvalues are upper bounds): 3e-6 for the first bending at 1.54 Hz
  (required 1e-5), 7e-5 up to 7 Hz (required 2e-4).
* The vehicle's mass: the segments, the payload and the four hold-down links (LINK's line
  density over 1.83 m each), 1e-9.
* At t0 the four posts carry the vehicle's weight m g (the static initial state: 1e-9)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sla

SCENARIO = Path(__file__).resolve().parents[1] / "data" / "beam_stick" / "scenario.toml"
HD = [(1.294005, 1.294005), (-1.294005, 1.294005), (-1.294005, -1.294005), (1.294005, -1.294005)]


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    pytest.importorskip("petsc4py")
    from liftoff.workflows.run import run as run_api

    folder = tmp_path_factory.mktemp("beam_stick")
    return run_api(SCENARIO, out=folder / "out", cache_dir=folder / "cache", progress=False, plots=False,
                   snapshots=False, echo=lambda *a, **k: None, error_estimate=False)


def test_free_free_modes_equal_one_stick_solved_densely(run):
    stack = next(iter(run.stacks.values()))
    ref = _dense_one_stick_hz(6)
    got = stack.vehicle.omega[6:12] / (2 * np.pi)
    assert np.all(got >= ref * (1 - 1e-12))                 # CB is a Ritz reduction: upper bounds
    np.testing.assert_allclose(got[:2], ref[:2], rtol=1e-5)
    np.testing.assert_allclose(got, ref, rtol=2e-4)
    assert 1.0 < got[0] < 2.0


def test_vehicle_mass_and_the_posts_carry_its_weight(run):
    from liftoff.reduction.beam_stick import LINK
    from liftoff.transient.effects import center_of_gravity

    stack = next(iter(run.stacks.values()))
    m, cg = center_of_gravity(stack.vehicle)
    link = LINK["mass_per_length"] * np.hypot(*HD[0])
    assert m == pytest.approx(3000.0 * 2 + 10000.0 * 38 + 8000.0 * 12 + 5000.0 + 4 * link, rel=1e-9)
    assert stack.pad.is_ground
    res, _ = run.results["nominal"]
    g = -float(np.asarray(res.metadata["gravity"])[2])
    tz = [j for j, d in enumerate(res.contact_directions) if d.component == "Tz"]
    assert len(tz) == 4 and res.contact_force[0, tz].sum() == pytest.approx(m * g, rel=1e-9)
    assert {c["name"]: c["separation_time"] for c in res.contact_summary()}["clamp_1"] == pytest.approx(1.5, abs=1e-3)


def test_interface_forces_at_t0_carry_the_weight_above(run):
    """The attach recoveries are the forces the rest of the vehicle applies to a component
    at a joint. At t0 (the static state on the clamps) statics gives them in closed form:
    at ``is_1`` the stage below holds up stage 2 and the payload, (12 m x 8000 kg/m +
    5000 kg) g; at ``payload_if`` stage 2 holds up the payload, 5000 kg g; the lateral
    forces and the moments vanish (the stack is axisymmetric under an axial field).
    Without the applied-load term (the component's own weight, which Craig-Bampton lumps
    partly on its boundary DOFs) stage 2's force would be short by its share at is_1,
    about half its weight. Tolerance: two static solves of cond ~1e8, 1e-9 of the weight."""
    res, _ = run.results["nominal"]
    g = -float(np.asarray(res.metadata["gravity"])[2])
    for point, mass in (("is_1", 12 * 8000.0 + 5000.0), ("payload_if", 5000.0)):
        f = res.recovered[f"attach_{point}"][0]
        assert f[2] == pytest.approx(mass * g, rel=1e-9), point
        assert np.all(np.abs(f[:2]) <= 1e-9 * mass * g) and np.all(np.abs(f[3:]) <= 1e-9 * mass * g * 52.0), point


def _dense_one_stick_hz(n: int) -> np.ndarray:
    """The vehicle as ONE stick solved densely (the second method of the first test)."""
    from liftoff.reduction.beam_stick import BeamStick, beam_stick_component

    one = BeamStick(name="one", stations=(0.0, 2.0, 40.0, 52.0), radius=(1.83,), thickness=(0.01, 0.01, 0.008),
                    mass_per_length=(3000.0, 10000.0, 8000.0),
                    points={"engine_mount": 0.0, **{f"hd_{k + 1}": [x, y, 2.0] for k, (x, y) in enumerate(HD)},
                            "is_1": 40.0, "payload_if": 52.0},
                    masses={"payload_if": (5000.0, 8000.0, 8000.0, 3000.0)}, element_length=1.0)
    comp, _ = beam_stick_component(one)
    w = sla.eigh(comp.K.toarray(), comp.M.toarray(), eigvals_only=True, subset_by_index=[0, n + 5])
    return np.sqrt(np.abs(w[6:])) / (2 * np.pi)


def test_residual_vectors_of_a_scenarios_components(tmp_path):
    """``residual_vectors = true`` on a [model.component] table (reduction.craig_bampton): both
    stages cut at 5 Hz, with and without them, against the one-stick dense reference. The
    frequencies stay upper bounds (Ritz) and the residual vectors take the worst error of the
    elastic modes below 10 Hz (twice the cut; 8 modes) down by more than 50x (measured 54 % ->
    0.15 %); the CB stage's key changes only where they are asked for (the default's cached
    models keep theirs)."""
    import tomllib

    from liftoff.config import Where, parse_scenario
    from liftoff.workflows.cache import StageCache
    from liftoff.workflows.pipeline import _cb_key, build_stack

    base = tomllib.loads(SCENARIO.read_text())
    ref = _dense_one_stick_hz(12)
    errs, models = {}, {}
    for rv in (False, True):
        d = tomllib.loads(SCENARIO.read_text())
        for st in ("stage1", "stage2"):
            d["model"]["component"][st]["f_max"] = 5.0
            if rv:
                d["model"]["component"][st]["residual_vectors"] = True
        case = parse_scenario(d, str(SCENARIO), SCENARIO.parent).cases[0]
        stack = build_stack(case.model, StageCache(tmp_path / "cache"), progress=False,
                            where=Where(case.source, "model"), workers=1)
        got = stack.vehicle.omega[6:18] / (2 * np.pi)
        assert np.all(got >= ref * (1 - 1e-9))
        errs[rv] = float(np.max((got / ref - 1)[ref < 10.0]))
        models[rv] = (case.model, stack.components["stage1"])
        assert all(stack.cbs[s].n_residual > 0 for s in ("stage1", "stage2")) == rv
    print(f"both stages at 5 Hz: worst of the elastic modes below 10 Hz {errs[False]:.2e} -> {errs[True]:.2e} "
          "with residual vectors")
    assert errs[True] < errs[False] / 50
    default = parse_scenario(base, str(SCENARIO), SCENARIO.parent).cases[0].model
    comp = models[True][1]
    assert "residual_vectors" not in _cb_key(default, "stage1", comp, "k")[1]
    assert _cb_key(models[True][0], "stage1", comp, "k")[1]["residual_vectors"] is True


def test_residual_vectors_refused_for_a_nastran_component():
    import tomllib

    from liftoff.config import parse_scenario
    from liftoff.core.errors import InputError

    d = tomllib.loads(SCENARIO.read_text())
    d["model"]["component"]["payload"] = {"type": "nastran", "residual_vectors": True,
                                          "nastran": {"file": "x.op4", "units": "SI", "grids": {}}}
    with pytest.raises(InputError, match="residual_vectors: a Nastran component's modes are Nastran's"):
        parse_scenario(d, str(SCENARIO), SCENARIO.parent)


def test_residual_vectors_refused_where_nothing_takes_them():
    """A rigid mass's CB model is given directly (no interior), and a hydroelastic tank's mass
    is not M alone: ``residual_vectors`` there is a one-line error naming the key, on reading."""
    import tomllib

    from liftoff.config import default_text, parse_scenario
    from liftoff.core.errors import InputError

    d = tomllib.loads(SCENARIO.read_text())
    d["model"]["component"]["payload"]["residual_vectors"] = True
    with pytest.raises(InputError, match=r"component\.payload\.residual_vectors: a 'rigid_mass' component's"):
        parse_scenario(d, str(SCENARIO), SCENARIO.parent)
    d = tomllib.loads(default_text())                  # the default's core: hydroelastic tanks
    d["model"]["component"]["core"]["residual_vectors"] = True
    with pytest.raises(InputError, match=r"component\.core\.residual_vectors: not for a component with a hydroelastic"):
        parse_scenario(d, "default.toml")
