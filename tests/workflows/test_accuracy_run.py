"""``[time] accuracy`` reaches the transient of `liftoff run` (issue 27: it was silently
ignored, and the metadata recorded None)."""
from __future__ import annotations

import tomllib

from liftoff.config import default_text, parse_scenario
from liftoff.workflows.run import run

# the stick stack bolted under the first engine start (tests/cli/test_fuzz.py's cheap run),
# with a given step coarse enough that a tight accuracy needs the step halved
STICK = {"source": "stick", "mesh_size": 6.0, "zeta": 0.01,
         "system": {"f_max": 60.0, "pad_f_max": 100.0, "residual_vectors": False}, "pad": {"f_max": 100.0}}


def _scenario(accuracy):
    data = tomllib.loads(default_text())
    data["model"] = STICK
    data["time"].update(t_end=0.05, h=1.6e-3)
    if accuracy is not None:
        data["time"]["accuracy"] = accuracy
    data["output"] = {"plots": False}
    data["case"] = [{"name": "nominal"}]
    return parse_scenario(data, "s.toml")


def test_accuracy_setting_halves_the_step(tmp_path):
    loose = run(_scenario(None), tmp_path / "a", cache_dir=tmp_path / "c", progress=False, plots=False,
                snapshots=False, echo=lambda *a: None)
    res, _ = loose.results["nominal"]
    assert res.metadata.get("accuracy") is None and res.metadata.get("halvings") == 0
    tight = run(_scenario(1e-8), tmp_path / "b", cache_dir=tmp_path / "c", progress=False, plots=False,
                snapshots=False, echo=lambda *a: None)
    res_t, _ = tight.results["nominal"]
    assert res_t.metadata["accuracy"] == 1e-8
    assert res_t.metadata["halvings"] >= 1                  # the setting acted: the step was halved
    assert len(res_t.time) > len(res.time)


def test_static_modes_setting_reaches_the_run_and_its_summary(tmp_path):
    """``[time] static_above_hz`` reaches the transient of `liftoff run` (the problem, the
    results' metadata) and the summary says how many modes it made static."""
    data = tomllib.loads(default_text())
    data["model"] = STICK
    data["time"].update(t_end=0.05, static_above_hz=20.0)
    data["output"] = {"plots": False}
    data["case"] = [{"name": "nominal"}]
    out = run(parse_scenario(data, "s.toml"), tmp_path / "a", cache_dir=tmp_path / "c", progress=False, plots=False,
              snapshots=False, echo=lambda *a: None, error_estimate=False)
    res, cp = out.results["nominal"]
    n_a, n_b = res.metadata["static_modes"]
    assert cp.problem.static_above_hz == 20.0 == res.metadata["static_above_hz"]
    assert n_a == int((cp.problem.body_a.omega > 2 * 3.141592653589793 * 20.0).sum()) > 0
    assert f"residual-flexibility modes: {n_a} of the vehicle's and {n_b} of the pad's, above 20 Hz" in out.summary
