"""``type = "thrust_structure"``: an engine thrust cone with its mounts and engines, read from a
scenario table into a conical barrel (meshes.barrel) and built.

The built mass is the structure's ``mass`` plus the engines' (by construction: the wall's
density is set from ``mass`` over the CAD area, 1e-9 for the CAD area's integration), each
mount lies on the bottom ring at its azimuth (closed form, 1e-12) carrying one engine's mass
and inertia, the joints on the top ring; missing or barrel-only keys fail at their key."""
from __future__ import annotations

import math

import numpy as np
import pytest

from liftoff.config.component_types import Context, get
from liftoff.config.values import Where
from liftoff.core.errors import InputError
from liftoff.meshes import StackLayout

PARAMS = {"radius_top": 3.3, "z_top": 6.0, "radius_bottom": 2.0, "z_bottom": 3.0, "thickness": 0.01,
          "mass": 4000.0, "joints": {"j_1": 45.0, "j_2": 135.0, "j_3": 225.0, "j_4": 315.0},
          "mounts": {"f1_1": 0.0, "f1_2": 90.0, "f1_3": 180.0, "f1_4": 270.0},
          "engine_mass": 8400.0, "engine_inertia": [9000.0, 9000.0, 4000.0]}
WHERE = Where("s.toml", "model") / "component" / "thrust" / "params"


def _read(params=PARAMS, mesh_size=0.6):
    return get("thrust_structure", "vehicle").read(Context("thrust", mesh_size, StackLayout()), WHERE, params)


def test_mounts_engines_and_joints_are_the_barrels_points():
    p = _read()
    pts = p.points()
    for n, a in PARAMS["mounts"].items():
        ref = [2.0 * math.cos(math.radians(a)), 2.0 * math.sin(math.radians(a)), 3.0]
        np.testing.assert_allclose(pts[n], ref, rtol=0, atol=1e-12)
        assert p.point_masses[n] == [8400.0, 9000.0, 9000.0, 4000.0]
    assert set(p.joints_top) == set(PARAMS["joints"]) and pts["j_1"][2] == 6.0


def test_built_mass_is_structure_plus_engines(tmp_path):
    pytest.importorskip("gmsh")
    from liftoff.meshes.barrel import build_barrel

    g = build_barrel(_read(), tmp_path)
    assert g.nominal_mass() == pytest.approx(4000.0 + 4 * 8400.0, rel=1e-9)
    assert {pm.patch for pm in g.point_masses} == set(PARAMS["mounts"])


@pytest.mark.parametrize("change, message", [
    ({"mounts": None}, "params.mounts: missing: the engine mounts"),
    ({"engine_mass": -1.0}, "params.engine_mass: "),
    ({"mounts": {}}, "params.mounts: no mounts"),
    ({"joints_bottom": {"x": 0.0}}, "params.joints_bottom: not a thrust structure key"),
    ({"engine_inertia": [1.0, 2.0]}, "params.engine_inertia: "),
])
def test_bad_thrust_structures_fail_at_their_key(change, message):
    params = {k: v for k, v in {**PARAMS, **change}.items() if v is not None}
    with pytest.raises(InputError) as exc:
        _read(params)
    assert message in str(exc.value) and "\n" not in str(exc.value)
