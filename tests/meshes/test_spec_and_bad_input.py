"""Geometry JSON sidecar round trip, and one-line InputErrors naming the culprit parameter."""
from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

from liftoff.meshes import (BoosterParams, Compartment, Geometry, Material, OrbiterParams, PadParams, Patch, PointMass,
                    SmearedMass, StackLayout, TankParams, build_booster, build_orbiter, build_pad, build_tank,
                    default_stack)
from liftoff.core.errors import InputError


def _geometry(msh):
    return Geometry("demo", str(msh), {"wall": Material("al", 70e9, 0.33, 2700.0)},
                    [Patch("p1", np.array([1.0, 2.0, 3.0])), Patch("p2", [0.0, 0.0, -1.5])],
                    [PointMass("m", "p1", 12.5, np.diag([1.0, 2.0, 3.0]))], [SmearedMass("wet", 7.0)], ["base"],
                    {"wall": 0.25}, 123, {"wet": 4.0})


def test_sidecar_round_trip_and_relocation(tmp_path):
    msh = tmp_path / "a" / "demo.msh"
    msh.parent.mkdir()
    msh.write_text("not read by the sidecar")
    g = _geometry(msh)
    path = g.save(tmp_path / "a" / "demo.json")
    d = json.loads(path.read_text())
    assert d["format"] == "liftoff-geometry" and d["units"].startswith("SI") and d["msh_path"] == "demo.msh"
    h = Geometry.load(path)
    assert h.name == g.name and h.volumes == g.volumes and h.clamped == g.clamped
    assert h.msh_path == str(msh.resolve())
    for a, b in zip(h.patches, g.patches):
        assert a.name == b.name and np.array_equal(a.ref_point, b.ref_point)
    np.testing.assert_array_equal(h.point_masses[0].inertia, g.point_masses[0].inertia)
    assert h.smeared_masses == g.smeared_masses and h.group_volumes == g.group_volumes
    assert h.surface_areas == g.surface_areas and h.mesh_nodes == 123
    assert h.nominal_mass() == pytest.approx(2700.0 * 0.25 + 12.5 + 7.0)
    # a folder moved as a whole keeps working (mesh path stored relative)
    shutil.move(tmp_path / "a", tmp_path / "b")
    assert Geometry.load(tmp_path / "b" / "demo.json").msh_path == str((tmp_path / "b" / "demo.msh").resolve())
    assert not list((tmp_path / "b").glob("*.tmp"))  # atomic write left no temp file


@pytest.mark.parametrize("make, culprit", [
    (lambda: Material("x", 0.0, 0.3, 1.0), "E = 0.0 Pa must be > 0"),
    (lambda: Material("x", 1e9, 0.5, 1.0), "nu = 0.5 must be in"),
    (lambda: Material("x", 1e9, 0.3, -1.0), "rho = -1.0 kg/m\\^3 must be > 0"),
    (lambda: Patch("bad name", [0, 0, 0]), "bad name"),
    (lambda: Patch("p", [0, 0]), "ref_point"),
    (lambda: PointMass("m", "p", 0.0), "mass must be > 0"),
    (lambda: PointMass("m", "p", 1.0, np.array([[1, 2, 0], [0, 1, 0], [0, 0, 1]])), "symmetric"),
    (lambda: SmearedMass("s", -1.0), "mass must be >= 0"),
    (lambda: Geometry("g", "x.msh", {}), "no volume groups"),
    (lambda: Geometry("g", "x.msh", {"v": Material("a", 1, 0, 1)}, [], [PointMass("m", "nope", 1.0)]),
     "patch 'nope'"),
])
def test_spec_bad_values(make, culprit):
    with pytest.raises(InputError, match=culprit) as e:
        make()
    assert "\n" not in str(e.value)


def test_load_rejects_foreign_files(tmp_path):
    p = tmp_path / "x.json"
    p.write_text('{"format": "something-else"}')
    with pytest.raises(InputError, match="not a liftoff-geometry"):
        Geometry.load(p)
    p.write_text("{broken")
    with pytest.raises(InputError, match="cannot read"):
        Geometry.load(p)


@pytest.mark.parametrize("build, params, culprit", [
    (build_tank, TankParams(radius=-4.2), "radius"),
    (build_tank, TankParams(wall_thickness=0.0), "wall_thickness"),
    (build_tank, TankParams(mesh_size=0.0), "mesh_size"),
    (build_tank, TankParams(mesh_size=-0.5), "mesh_size"),
    (build_tank, TankParams(compartments=(Compartment(fill_level=0.0),)), "fill_level"),
    (build_tank, TankParams(compartments=(Compartment(fill_level=1.2),)), "fill_level"),
    (build_tank, TankParams(compartments=(Compartment(cyl_length=-1.0),)), "cyl_length"),
    (build_tank, TankParams(compartments=(Compartment(liquid_density=0.0),)), "liquid_density"),
    (build_tank, TankParams(compartments=(Compartment("a"), Compartment("b")), intertank_length=2.0),
     "intertank_length"),
    (build_tank, TankParams(patches={"side": (4.3, 0.0, -5.0)}), "patch side"),
    (build_tank, TankParams(dry_mass=0.0), "dry_mass"),
    (build_booster, BoosterParams(length=-45.0), "length"),
    (build_booster, BoosterParams(case_thickness=0.0), "case_thickness"),
    (build_booster, BoosterParams(mesh_size=0.0), "mesh_size"),
    (build_booster, BoosterParams(side="middle"), "side"),
    (build_booster, BoosterParams(propellant_mass=-1.0), "propellant_mass"),
    (build_booster, BoosterParams(layout=StackLayout(srb_axis_x=5.0)), "srb_axis_x"),
    (build_orbiter, OrbiterParams(length=0.0), "length"),
    (build_orbiter, OrbiterParams(mesh_size=-1.0), "mesh_size"),
    (build_orbiter, OrbiterParams(payload_z=100.0), "payload_z"),
    (build_pad, PadParams(deck_thickness=0.0), "deck_thickness"),
    (build_pad, PadParams(mesh_size=0.0), "mesh_size"),
    (build_pad, PadParams(deck_length_x=10.0), "off the deck"),
    (build_pad, PadParams(pedestal_xy=()), "pedestal_xy"),
    (build_pad, PadParams(srb_hole_radius=2.5), "srb_hole_radius"),
])
def test_builders_reject_bad_input(build, params, culprit, tmp_path):
    with pytest.raises(InputError) as e:
        build(params, tmp_path)
    msg = str(e.value)
    assert culprit in msg and "\n" not in msg
    assert not list(tmp_path.iterdir())  # nothing written


def test_default_stack_rejects_bad_mesh_size(tmp_path):
    with pytest.raises(InputError, match="mesh_size"):
        default_stack(mesh_size=0.0, out_dir=tmp_path)


def test_builders_reject_wrong_parameter_type(tmp_path):
    with pytest.raises(InputError, match="TankParams"):
        build_tank(PadParams(), tmp_path)


def test_a_mesh_too_fine_is_refused_before_gmsh_meshes(tmp_path):
    """FE mesh size 0.01 m used to mesh for ever: the element count is estimated from the
    CAD volume before gmsh meshes (at least V / (h^3 / (6 sqrt 2)) tetrahedra) and refused
    beyond the limit with a ResourceError naming the estimate and the key that raises it;
    the same tank at its own mesh size meshes, and its tetrahedra are at least the estimate."""
    import time

    from liftoff.core.errors import ResourceError
    from liftoff.meshes._occ import REGULAR_TET, element_limit
    from liftoff.meshes.tank import TankParams, build_tank

    p = TankParams(radius=1.0, wall_thickness=0.1, compartments=(Compartment("lox", 1.5, 0.72, 1.6, 0.5, 1141.0),),
                   patches={}, mesh_size=0.01)
    t0 = time.perf_counter()
    with element_limit(1e6, "component 'tank'"):
        with pytest.raises(ResourceError, match=r"component 'tank': mesh size 0.01 m would give at least .* "
                                                r"tetrahedra .* \[model\] max_elements"):
            build_tank(p, tmp_path)
    assert time.perf_counter() - t0 < 30 and not list(tmp_path.glob("*.msh"))
    with element_limit(1e6, "component 'tank'"):
        g = build_tank(TankParams(radius=1.0, wall_thickness=0.1, compartments=p.compartments, patches={},
                                  mesh_size=0.5), tmp_path)
    import meshio

    cells = sum(len(c.data) for c in meshio.read(g.msh_path).cells if c.type == "tetra")
    assert cells >= g.group_volumes["tank_wall"] / (REGULAR_TET * 0.5 ** 3)
