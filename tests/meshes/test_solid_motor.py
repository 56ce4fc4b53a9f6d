"""``type = "solid_motor"`` (meshes.solid_motor.SolidMotorParams): a solid motor placed by its
own axis, radii and points, built by the Shuttle booster's builder.

* The Shuttle booster is an instance of it: a motor given the StackLayout's axis, radii and
  points (and named srb_left) writes the same mesh, byte for byte, and the same Geometry as
  BoosterParams(side="left"): one builder, the layout only a source of numbers.
* An in-line motor on the axis with three hold-downs: its CAD volumes equal the booster's
  closed forms (CAD_RTOL: occ.getMass integration, as test_vehicle.py), its mass is its
  parts' by construction (1e-12: four additions), its hold-down patches lie on the skirt's
  bottom and its wall point's patch on the case, facing the point.
* Bad placements fail in one line naming the key, through the scenario too."""
from __future__ import annotations

import math

import numpy as np
import pytest

from liftoff.core.errors import InputError
from liftoff.meshes import BoosterParams, StackLayout
from liftoff.meshes.solid_motor import SolidMotorParams
from liftoff.meshes.vehicle import booster_closed_form_volumes, build_booster

CAD_RTOL = 1e-5
COARSE = 1.2       # m: a coarse mesh, the placement is what is tested


def _shuttle_left_as_motor(**kw) -> SolidMotorParams:
    lay = StackLayout()
    return SolidMotorParams(motor="srb_left", axis_xy=tuple(lay.srb_axis("left")), case_radius=lay.srb_radius,
                            skirt_bottom_radius=lay.srb_skirt_radius, skirt_foot_thickness=lay.srb_skirt_thickness,
                            holddown={n: tuple(p) for n, p in lay.holddown_points("left").items()},
                            points={n: tuple(p) for n, p in lay.srb_attach_points("left").items()}, **kw)


@pytest.mark.parametrize("walls", ["solid", "shell"])
def test_the_shuttle_booster_is_a_solid_motor(tmp_path, walls):
    a = build_booster(BoosterParams(side="left", mesh_size=COARSE, walls=walls), tmp_path / "booster")
    b = build_booster(_shuttle_left_as_motor(mesh_size=COARSE, walls=walls), tmp_path / "motor")
    assert (tmp_path / "booster" / "srb_left.msh").read_bytes() == (tmp_path / "motor" / "srb_left.msh").read_bytes()
    da, db = a.to_dict(), b.to_dict()
    da.pop("msh_path"), db.pop("msh_path")
    assert da == db


def test_an_inline_motor_on_three_holddowns(tmp_path, msh_groups):
    R, Rb, ts = 1.5, 2.1, 0.5
    r_foot = Rb - 0.5 * ts
    hd = {f"clamp_{k}": (r_foot * math.cos(math.radians(120 * k)), r_foot * math.sin(math.radians(120 * k)), 0.0)
          for k in range(3)}
    p = SolidMotorParams(motor="p80", case_radius=R, skirt_bottom_radius=Rb, skirt_foot_thickness=ts, length=11.0,
                         case_bottom_z=2.0, case_thickness=0.12, nose_ratio=0.7, aft_dome_ratio=0.7,
                         case_mass=8_000.0, skirt_mass=1_000.0, propellant_mass=88_000.0, nozzle_mass=2_000.0,
                         holddown=hd, points={"interstage": (0.0, R + 0.3, 8.5)}, mesh_size=0.6)
    g = build_booster(p, tmp_path)
    for name, v in booster_closed_form_volumes(p).items():
        assert g.group_volumes[name] == pytest.approx(v, rel=CAD_RTOL), name
    assert g.nominal_mass() == pytest.approx(8_000.0 + 1_000.0 + 88_000.0 + 2_000.0, rel=1e-12)
    groups = msh_groups(g)
    assert {(2, n) for n in [*hd, "interstage", "p80_gimbal", "p80_case_inner"]} <= set(groups)
    for n in hd:
        nodes = groups[(2, n)]["nodes"]
        assert np.abs(nodes[:, 2]).max() < 1e-9
        assert np.all(np.abs(np.hypot(nodes[:, 0], nodes[:, 1]) - r_foot) <= p.holddown_patch_radius + 1e-6)
    wall = groups[(2, "interstage")]["nodes"]
    np.testing.assert_allclose(np.hypot(wall[:, 0], wall[:, 1]), R, rtol=1e-6)
    assert np.all(wall[:, 1] > 0) and np.abs(wall[:, 2] - 8.5).max() <= p.attach_patch_half_width + 1e-6


@pytest.mark.parametrize("change, message", [
    ({"holddown": {"hd": (2.3, 0.0, 0.0)}}, "holddown.hd: [2.3, 0.0, 0.0] is not on the skirt's foot ring"),
    ({"holddown": {"hd": (2.45, 0.0, 0.5)}}, "is not on the skirt's foot ring (z = 0"),
    ({"points": {"if": (1.0, 0.0, 20.0)}}, "points.if: [1.0, 0.0, 20.0] is inside the case"),
    ({"points": {"if": (3.0, 0.0, 60.0)}}, "points.if: z = 60 m is off the case's cylinder"),
    ({"holddown": {}, "points": {}}, "no points (holddown or points)"),
    ({"case_radius": 2.6}, "skirt bottom inner radius must exceed the case radius"),
])
def test_bad_placements_name_their_key(change, message):
    p = SolidMotorParams(motor="m", skirt_bottom_radius=2.7, skirt_foot_thickness=0.5,
                         holddown={"hd": (2.45, 0.0, 0.0)}, points={"if": (3.0, 0.0, 20.0)})
    p.check()
    for k, v in change.items():
        setattr(p, k, v)
    with pytest.raises(InputError, match=None) as exc:
        p.check()
    assert message in str(exc.value) and "\n" not in str(exc.value)


def test_the_scenario_type_reads_it():
    """The type's reader: points as tables of [x, y, z], the component's name for the motor,
    keys of the Shuttle placement refused, errors at the key."""
    from liftoff.config.component_types import Context, get
    from liftoff.config.values import Where

    t = get("solid_motor", "vehicle")
    ctx = Context(name="booster_a", mesh_size=1.0, layout=StackLayout())
    w = Where("s.toml", "model") / "component" / "booster_a" / "params"
    given = {"case_radius": 1.855, "length": 45.46, "case_mass": 75e3, "skirt_mass": 5e3, "propellant_mass": 499e3,
             "nozzle_mass": 11e3}
    p = t.read(ctx, w, {**given, "axis_xy": [5.0, 0.0], "holddown": {"hd_1": [7.45, 0.0, 0.0]},
                        "points": {"att_fwd": [3.0, 0.0, 30.0]}})
    assert p.name == "booster_a" and p.mesh_size == 1.0 and p.attach_points()["att_fwd"].tolist() == [3.0, 0.0, 30.0]
    with pytest.raises(InputError, match="unknown key 'side'"):
        t.read(ctx, w, {**given, "side": "left", "holddown": {"hd_1": [2.45, 0.0, 0.0]}})
    with pytest.raises(InputError, match=r"s.toml: model.component.booster_a.params: .*points.x: z = 90 m"):
        t.read(ctx, w, {**given, "holddown": {"hd_1": [2.45, 0.0, 0.0]}, "points": {"x": [3.0, 0.0, 90.0]}})
    # its size and masses must be given (the defaults were the Shuttle booster's: a 12 m motor took
    # 499 t of propellant without a word; a review)
    for key in given:
        with pytest.raises(InputError, match=rf"booster_a\.params\.{key}: missing"):
            t.read(ctx, w, {**{k: v for k, v in given.items() if k != key}, "holddown": {"hd_1": [7.45, 0.0, 0.0]}})
