"""A mirror-image component end to end (``[model.component.<name>] mirror = {of, normal}``):
tests/data/mirror_beams/scenario.toml (a core stick with two strap-on sticks, the right one
the mirror of the left, off-axis points and masses, engines canted in x, a lateral gust)
against mirrored_explicit.toml, the same vehicle with the right strap-on built from its own
mirrored stations, points and masses. The second is an independent build (its element
matrices formed in the mirrored geometry), so the two runs must agree to the round-off of
two Craig-Bampton reductions: system frequencies 1e-9 (measured 2e-11), the post and attach
force histories 1e-8 of their peaks (measured 1.4e-10: the post forces are K_C times small
relative displacements, which two reductions round differently), the same separations."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

DATA = Path(__file__).resolve().parents[1] / "data" / "mirror_beams"


def _run(path: Path, folder: Path):
    from liftoff.workflows.run import run as run_api

    return run_api(path, out=folder / "out", cache_dir=folder / "cache", progress=False, plots=False,
                   snapshots=False, echo=lambda *a, **k: None, error_estimate=False)


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    pytest.importorskip("petsc4py")
    root = tmp_path_factory.mktemp("mirror")
    return _run(DATA / "scenario.toml", root / "m"), _run(DATA / "mirrored_explicit.toml", root / "e")


def test_mirror_equals_the_component_built_mirrored(runs):
    mir, exp = runs
    sm, se = next(iter(mir.stacks.values())), next(iter(exp.stacks.values()))
    assert sm.cbs["b_right"].points == se.cbs["b_right"].points
    np.testing.assert_allclose(sm.cbs["b_right"].point_coords, se.cbs["b_right"].point_coords, atol=1e-12)
    np.testing.assert_allclose(sm.cbs["b_right"].fixed_omega, se.cbs["b_right"].fixed_omega, rtol=1e-9)
    np.testing.assert_allclose(sm.vehicle.omega[6:40], se.vehicle.omega[6:40], rtol=1e-9)
    rm, _ = mir.results["nominal"]
    re, _ = exp.results["nominal"]
    assert rm.contact_names == re.contact_names
    np.testing.assert_allclose(rm.separation_time, re.separation_time, atol=1e-12)
    peak = np.abs(re.contact_force).max()
    assert np.abs(rm.contact_force - re.contact_force).max() <= 1e-8 * peak
    for name, hist in re.recovered.items():
        scale = max(np.abs(hist).max(), 1e-300)
        assert np.abs(rm.recovered[name] - hist).max() <= 1e-8 * scale, name
    # the pair is symmetric but the loads are not (gust in y, motors canted in x): the mirror
    # is not the left booster copied
    left = [j for j, d in enumerate(re.contact_directions) if d.label.startswith("l1/")]
    right = [j for j, d in enumerate(re.contact_directions) if d.label.startswith("r1/")]
    assert not np.allclose(re.contact_force[:, left], re.contact_force[:, right], rtol=1e-3)


def test_mirror_table_refused_where_it_cannot_stand(tmp_path):
    """A mirror with a type of its own, of itself, of the pad, of a rigid mass (a given
    model), under the stick source, and with a material different from its source's."""
    from liftoff.config import load_scenario
    from liftoff.core.errors import InputError

    base = (DATA / "scenario.toml").read_text()
    cases = {
        'mirror = { of = "b_left", normal = "x" }\ntype = "beam"': "no type, params",
        'mirror = { of = "b_right", normal = "x" }': "'b_right' is itself",
        'mirror = { of = "b_left", normal = "w" }': "give x, y or z",
        'mirror = { of = "nobody", normal = "x" }': "'nobody' is no vehicle component",
    }
    for text, msg in cases.items():
        p = tmp_path / "s.toml"
        p.write_text(base.replace('mirror = { of = "b_left", normal = "x" }', text))
        with pytest.raises(InputError, match=msg):
            load_scenario(p)
    p = tmp_path / "m.toml"
    p.write_text(base + '\n[model.materials.b_right_wall]\nE = 1e11\nnu = 0.3\nrho = 7800.0\n')
    with pytest.raises(InputError, match="mirrors 'b_left' and takes its materials"):
        load_scenario(p)


def test_a_post_joins_one_place_of_both_bodies(tmp_path):
    """A post whose vehicle point and pad point are apart (here the right strap-on's first
    hold-down on the pad point under its second, 2 m away, as a mirror numbered otherwise
    than the pad's posts would be) is refused with both places, not run as if they were one."""
    pytest.importorskip("petsc4py")
    from liftoff.core.errors import InputError

    p = tmp_path / "s.toml"
    p.write_text((DATA / "scenario.toml").read_text().replace('vehicle = "b_right_hd_1"\npad = "pad_r1"',
                                                              'vehicle = "b_right_hd_1"\npad = "pad_r2"'))
    with pytest.raises(InputError, match=r"post\[2\] 'r1'.*'b_right_hd_1' at \[2.2, 0.6, 0.0\] m and pad point "
                                         r"'pad_r2' at \[3.8, -0.6, 0.0\] m are 2 m apart"):
        _run(p, tmp_path)


def test_a_mirror_that_keeps_a_source_point_name_says_to_rename_it(tmp_path):
    """A source point whose name lacks the source's name keeps it in the mirror, so both
    components have it: the error says so and how to rename it, not 'declare a joint', which
    would weld the mirror to its source (a review)."""
    pytest.importorskip("petsc4py")
    from liftoff.config import Where, load_scenario
    from liftoff.core.errors import InputError
    from liftoff.workflows.cache import StageCache
    from liftoff.workflows.pipeline import build_stack

    p = tmp_path / "s.toml"
    p.write_text((DATA / "scenario.toml").read_text().replace("b_left_hd_2 = [-3.8, -0.6, 0.0]",
                                                              "b_left_hd_2 = [-3.8, -0.6, 0.0]\nhd_x = [-3.0, 0.9, 0.0]"))
    sc = load_scenario(p)
    with pytest.raises(InputError, match=r"component 'b_right', the mirror of 'b_left', kept 'b_left''s point name "
                                         r"'hd_x'.*put 'b_left' in the name"):
        build_stack(sc.cases[0].model, StageCache(tmp_path / "cache"), progress=False, where=Where(p.name, "model"))
