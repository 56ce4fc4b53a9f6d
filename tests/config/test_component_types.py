"""Component types (liftoff/config/component_types): one file per type, registered by name,
and a new type added as one file plus its registration (README, "A new component type")."""
from __future__ import annotations

import copy
import importlib
import sys
import textwrap
import tomllib

import pytest

from liftoff.config import component_types
from liftoff.config.scenario import default_text, parse_scenario
from liftoff.core.errors import InputError

NEW_TYPE = '''
"""``type = "lying_tank"``: a cylinder lying on two saddles (meshes.barge.CargoParams)."""
from liftoff.config.component_types import ComponentType, Context
from liftoff.config.params import builder
from liftoff.config.values import Where


def read(ctx: Context, where: Where, params: dict):
    from liftoff.meshes.barge import CargoParams

    size = {} if ctx.mesh_size is None else {"mesh_size": ctx.mesh_size}
    return builder(where, CargoParams, params, defaults=size)


TYPE = ComponentType("lying_tank", read, "liftoff.meshes.barge:build_cargo", "vehicle", "a lying tank")
'''


def test_every_builtin_type_is_its_own_file_and_name():
    types = component_types.types()
    for module in component_types.BUILTIN:
        t = importlib.import_module(f"liftoff.config.component_types.{module}").TYPE
        assert t.name == module and types[module] is t
        if t.model:                                       # a type given as its CB model (rigid_mass): no mesh
            assert not t.build and callable(t.model_builder())
            assert t.model.split(":")[0].startswith("liftoff.reduction.")
            continue
        if t.matrices:                                    # a type given as its FE matrices (beam): no mesh
            assert not t.build and callable(t.matrices_builder())
            assert t.matrices.split(":")[0].startswith("liftoff.reduction.")
            continue
        mod, func = t.build.split(":")
        assert mod.startswith("liftoff.meshes.")           # gmsh builders live in meshes/
    assert component_types.NASTRAN not in types           # imported, not built


def test_a_new_type_is_one_file_plus_its_registration(tmp_path, monkeypatch):
    (tmp_path / "my_types.py").write_text(textwrap.dedent(NEW_TYPE))
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setattr(component_types, "_TYPES", dict(component_types.types()))
    component_types.register(importlib.import_module("my_types").TYPE)
    d = tomllib.loads(default_text())
    d["model"]["component"]["spare"] = {"type": "lying_tank", "params": {"length": 20.0, "saddle_x": [-5.0, 5.0]}}
    d["model"]["joint"].append({"name": "cargo_1", "components": ["core", "spare"]})
    model = parse_scenario(d, "s.toml").cases[0].model
    assert model.vehicle[-1] == "spare" and model.components["spare"].type == "lying_tank"
    assert model.components["spare"].builder.length == 20.0
    bad = copy.deepcopy(d)
    bad["model"]["component"]["spare"]["params"] = {"lenght": 20.0}
    with pytest.raises(InputError, match=r"s\.toml: model\.component\.spare\.params: unknown key 'lenght'"):
        parse_scenario(bad, "s.toml")
    sys.modules.pop("my_types", None)


def test_a_type_name_is_registered_once(monkeypatch):
    monkeypatch.setattr(component_types, "_TYPES", dict(component_types.types()))
    t = component_types.types()["tank_stage"]
    other = component_types.ComponentType("tank_stage", t.read, "liftoff.meshes.barge:build_cargo")
    with pytest.raises(InputError, match="component type 'tank_stage' is registered twice"):
        component_types.register(other)


def test_the_default_is_described_by_types_and_joints():
    """The Shuttle default in the new description gives the builders of the old one, field by
    field: today's core, booster, orbiter and pad builders on its layout (the whole run was
    compared when it was rewritten: maxmin_envelope.csv and table1.txt byte for byte)."""
    import json
    from dataclasses import asdict, replace

    import numpy as np

    from liftoff.config.model import Mirror, shuttle_joints
    from liftoff.meshes.pad import PadParams
    from liftoff.meshes.vehicle import BoosterParams, OrbiterParams, core_stage_params

    def same(a, b) -> bool:        # dataclasses holding numpy arrays: compared as JSON
        def js(x):
            return json.dumps(asdict(x), default=lambda v: np.asarray(v).tolist(), sort_keys=True)
        return type(a) is type(b) and js(a) == js(b)

    model = parse_scenario(tomllib.loads(default_text()), "d").cases[0].model
    lay, c = model.layout, model.components
    assert model.vehicle == ("core", "srb_left", "srb_right", "orbiter")
    assert same(c["core"].builder, core_stage_params(lay, mesh_size=0.85, walls="shell", liquid="hydroelastic"))
    assert same(c["srb_left"].builder, BoosterParams(side="left", layout=lay, walls="solid"))
    # the right booster is the left one's mirror (liftoff.reduction.mirror), not built
    assert c["srb_right"].builder is None and c["srb_right"].mirror == Mirror("srb_left", "x")
    assert c["srb_right"].f_max == c["srb_left"].f_max
    assert same(c["orbiter"].builder, OrbiterParams(layout=lay, mesh_size=0.5, walls="shell"))
    assert same(c["pad"].builder, replace(PadParams(layout=lay), mesh_size=2.4))
    assert set(model.joints) == set(shuttle_joints(lay))


def test_tank_stage_frames_and_stringers_from_toml():
    """A tank stage's ring frames and stringers (beams, fem.beam) from the scenario: heights
    or a count, a standard section by shape and dimensions, their own material; a wrong
    section named by its key."""
    d = tomllib.loads(default_text())
    d["model"]["component"]["spare"] = {"type": "tank_stage", "params": {
        "walls": "shell", "radius": 4.2, "wall_thickness": 0.15, "frames": [4.0, 5.0], "frame_section": {"shape": "i", "h": 0.2, "b": 0.1, "tw": 0.005,
                                                                   "tf": 0.008},
        "frame_material": {"E": 70e9, "nu": 0.33, "rho": 2700.0},
        "stringers": 12, "stringer_section": {"shape": "hat", "h": 0.05, "b": 0.04, "c": 0.02, "t": 0.003},
        "compartments": [{"name": "lox", "cyl_length": 4.6, "liquid_density": 1141.0}],
        "patches": {"foot": [0.0, 0.0, 0.0]}}}
    d["model"]["joint"].append({"name": "spare_1", "components": ["core", "spare"]})
    b = parse_scenario(d, "s.toml").cases[0].model.components["spare"].builder
    assert b.frames == (4.0, 5.0) and b.frame_section["shape"] == "i" and b.frame_material.rho == 2700.0
    assert b.stringers == 12 and b.stringer_section["shape"] == "hat" and b.stringer_material is None
    bad = copy.deepcopy(d)
    bad["model"]["component"]["spare"]["params"]["frame_section"] = {"shape": "z", "h": 0.2}
    with pytest.raises(InputError, match=r"s\.toml: model\.component\.spare\.params\.frame_section: .*unknown shape 'z'"):
        parse_scenario(bad, "s.toml")
    bad = copy.deepcopy(d)
    bad["model"]["component"]["spare"]["params"]["frames"] = [4.0, 40.0]
    with pytest.raises(InputError, match=r"frames: height 40.0 m is not on the cylindrical wall"):
        parse_scenario(bad, "s.toml")


def test_launch_table_girder_deck_from_toml():
    """``deck = "girders"`` with a girder section on the launch table (and any platform):
    the builder's parameters carry them; a wrong section or deck kind is named by its key."""
    d = tomllib.loads(default_text())
    d["model"]["pad"]["params"] = {"deck": "girders",
                                   "girder_section": {"shape": "i", "h": 7.0, "b": 3.0, "tw": 0.03, "tf": 0.05}}
    b = parse_scenario(d, "s.toml").cases[0].model.components["pad"].builder
    assert b.deck == "girders" and b.platform().girder_section["h"] == 7.0
    bad = copy.deepcopy(d)
    bad["model"]["pad"]["params"]["girder_section"] = {"shape": "i", "h": 7.0}
    with pytest.raises(InputError, match=r"s\.toml: model\.pad\.params\.girder_section: .*missing b, tw, tf"):
        parse_scenario(bad, "s.toml")
    bad["model"]["pad"]["params"] = {"deck": "trusses"}
    with pytest.raises(InputError, match=r"deck must be 'solid' or 'girders'"):
        parse_scenario(bad, "s.toml")


def test_core_stage_frames_and_stringers_from_toml():
    """The external tank's ring frames and stringers from the scenario (its shell wall, as a
    tank stage's): heights, sections, count and azimuth reach its TankParams; a height off the
    cylindrical wall, a wrong section and an unknown key are named by their keys."""
    d = tomllib.loads(default_text())
    d["model"]["component"]["core"]["params"] = {
        "frames": [13.2, 25.1, 40.5], "frame_section": {"shape": "t", "h": 0.25, "b": 0.1, "tw": 0.006, "tf": 0.01},
        "stringers": 24, "stringer_azimuth": 7.5,
        "stringer_section": {"shape": "hat", "h": 0.05, "b": 0.04, "c": 0.02, "t": 0.003},
        "stringer_material": {"E": 73e9, "nu": 0.33, "rho": 2800.0}}
    b = parse_scenario(d, "s.toml").cases[0].model.components["core"].builder
    assert b.frames == (13.2, 25.1, 40.5) and b.frame_section["shape"] == "t" and b.frame_material is None
    assert b.stringers == 24 and b.stringer_azimuth == 7.5 and b.stringer_material.name == "core-stringers"
    assert b.walls == "shell" and b.dry_mass == 26_500.0
    plain = parse_scenario(tomllib.loads(default_text()), "s.toml").cases[0].model.components["core"].builder
    assert plain.frames == () and plain.stringers == 0          # the default: a bare skin
    for key, value, match in (("frames", [13.2, 60.0], r"core\.params: .*frames: height 60.0 m is not on the cylindrical"),
                              ("frame_section", {"shape": "t", "h": 0.25}, r"core\.params\.frame_section: .*missing"),
                              ("frames", 13.2, r"core\.params\.frames: expected a list"),
                              ("stringers", float("nan"), r"core\.params\.stringers: expected an integer"),
                              ("stringers", 2.5, r"core\.params\.stringers: expected an integer, got float 2\.5"),
                              ("stringers", 10 ** 20, r"core\.params\.stringers: 1e\+20 out of range"),
                              ("ribs", 3, r"core\.params: unknown key 'ribs'")):
        bad = copy.deepcopy(d)
        bad["model"]["component"]["core"]["params"][key] = value
        with pytest.raises(InputError, match=match):
            parse_scenario(bad, "s.toml")


def test_orbiter_skin_frames_from_toml():
    """The orbiter's ring frames from the scenario (shell skin): heights and a standard
    section; a wrong shape named by its key."""
    d = tomllib.loads(default_text())
    d["model"]["component"]["orbiter"]["params"] = {
        "frames": [14.0, 20.0], "frame_section": {"shape": "t", "h": 0.2, "b": 0.08, "tw": 0.004, "tf": 0.006}}
    b = parse_scenario(d, "s.toml").cases[0].model.components["orbiter"].builder
    assert b.frames == (14.0, 20.0) and b.frame_section["shape"] == "t" and b.walls == "shell"
    d["model"]["component"]["orbiter"]["params"]["frame_section"] = {"shape": "q"}
    with pytest.raises(InputError, match=r"model\.component\.orbiter\.params\.frame_section: .*unknown shape 'q'"):
        parse_scenario(d, "s.toml")


def test_orbiter_skin_stringers_from_toml():
    """The orbiter's stringers from the scenario (shell skin): count, section, material;
    a wrong section and a stringer through a wing root named by their keys."""
    d = tomllib.loads(default_text())
    d["model"]["component"]["orbiter"]["params"] = {
        "stringers": 12, "stringer_section": {"shape": "hat", "h": 0.05, "b": 0.03, "c": 0.02, "t": 0.002},
        "stringer_material": {"E": 70e9, "nu": 0.33, "rho": 2700.0}}
    b = parse_scenario(d, "s.toml").cases[0].model.components["orbiter"].builder
    assert b.stringers == 12 and b.stringer_section["shape"] == "hat" and b.stringer_material.rho == 2700.0
    assert b.stringer_material.name == "orbiter-stringers" and b.stringer_azimuth is None
    d["model"]["component"]["orbiter"]["params"]["stringer_section"] = {"shape": "hat", "h": 0.05}
    with pytest.raises(InputError, match=r"model\.component\.orbiter\.params\.stringer_section: shape 'hat' takes"):
        parse_scenario(d, "s.toml")
    d["model"]["component"]["orbiter"]["params"]["stringer_section"] = {"shape": "rectangle", "h": 0.05, "b": 0.01}
    d["model"]["component"]["orbiter"]["params"]["stringer_azimuth"] = 180.0
    with pytest.raises(InputError, match=r"orbiter.*stringer_azimuth: stringer 1 of 12, at 180 deg, runs through"):
        parse_scenario(d, "s.toml")


def test_a_mirror_may_repeat_its_sources_materials():
    """[model.materials] of a mirrored component that repeat its source's (the same E, nu and
    rho under the mirror's volume name) are accepted (they were always refused: the two
    materials' names differ); different values are refused, naming the key."""
    d = tomllib.loads(default_text())
    d["model"]["materials"]["srb_right_case"] = dict(d["model"]["materials"]["srb_left_case"])
    parse_scenario(d, "s.toml")
    d["model"]["materials"]["srb_right_case"]["E"] *= 1.5
    with pytest.raises(InputError, match=r"model\.materials\.srb_right_case: .*must repeat"):
        parse_scenario(d, "s.toml")


def test_a_tank_stage_takes_no_shuttle_default():
    """A tank stage's size, its compartments' length and propellant density must be given (the
    defaults were the Shuttle external tank's: a compartment without liquid_density got LOX,
    16 times LH2's mass), and without dry_mass its wall weighs what its material makes it (the
    default 5,500 kg rescaled a user's density and E by 26 % without a word; a review)."""
    d = tomllib.loads(default_text())
    params = {"radius": 1.5, "wall_thickness": 0.05, "material": {"E": 70e9, "nu": 0.33, "rho": 2700.0},
              "compartments": [{"name": "lh2", "cyl_length": 10.0, "liquid_density": 70.85}],
              "patches": {"foot": [0.0, 0.0, 0.0]}}
    d["model"]["component"]["spare"] = {"type": "tank_stage", "params": params}
    d["model"]["joint"].append({"name": "spare_1", "components": ["core", "spare"]})
    b = parse_scenario(d, "s.toml").cases[0].model.components["spare"].builder
    assert b.dry_mass is None and b.material.rho == 2700.0 and b.compartments[0].liquid_density == 70.85
    for path, key in ((params, "radius"), (params, "wall_thickness"), (params["compartments"][0], "liquid_density"),
                      (params["compartments"][0], "cyl_length")):
        bad = copy.deepcopy(d)
        target = bad["model"]["component"]["spare"]["params"]
        target = target if path is params else target["compartments"][0]
        del target[key]
        with pytest.raises(InputError, match=rf"spare\.params\..*{key}: missing"):
            parse_scenario(bad, "s.toml")
    two = copy.deepcopy(d)
    two["model"]["component"]["spare"]["params"]["compartments"].append(
        {"name": "lox", "cyl_length": 2.0, "liquid_density": 1141.0})
    with pytest.raises(InputError, match=r"spare\.params\.intertank_length: missing"):
        parse_scenario(two, "s.toml")


def test_a_hydroelastic_liquid_without_a_liquid_component_is_refused():
    """[model] liquid = "hydroelastic" on a model none of whose components holds a liquid (a
    stick of beams) did nothing, silently (a review; convective and slosh_gravity were
    refused so already)."""
    from pathlib import Path

    path = Path(__file__).resolve().parents[1] / "data" / "beam_stick" / "scenario.toml"
    d = tomllib.loads(path.read_text())
    d["model"]["liquid"] = "hydroelastic"
    with pytest.raises(InputError, match=r"model\.liquid: \"hydroelastic\", but no component takes"):
        parse_scenario(d, "s.toml", path.parent)


def test_an_axis_point_far_from_its_dome_apex_is_warned_of():
    """A tank stage's point on the axis is tied by a rigid arm to the nearer dome apex,
    whatever its distance: beyond the tank's radius a warning names it (a review: z = 12 m on
    a tank whose top apex is at 5.5 m went through)."""
    d = tomllib.loads(default_text())
    params = {"radius": 1.5, "wall_thickness": 0.05,
              "compartments": [{"name": "lox", "cyl_length": 3.0, "liquid_density": 1141.0}],
              "patches": {"foot": [0.0, 0.0, 0.0], "mount": [0.0, 0.0, -1.0]}}
    d["model"]["component"]["spare"] = {"type": "tank_stage", "params": params}
    d["model"]["joint"].append({"name": "spare_1", "components": ["core", "spare"]})
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        parse_scenario(copy.deepcopy(d), "s.toml")          # a gimbal 1 m below the apex: no warning
    params["patches"]["top"] = [0.0, 0.0, 12.0]
    with pytest.warns(UserWarning, match=r"patches\.top: on the axis .* m from the nearer dome apex"):
        parse_scenario(d, "s.toml")
