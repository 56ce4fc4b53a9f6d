"""Shell-wall variants of the builders (walls = "shell", meshes.shells): the same groups,
patches, cavities and masses as the solid variants, the wall as its mid-surface."""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from liftoff.core.errors import InputError
from liftoff.meshes import BoosterParams, Compartment, OrbiterParams, TankParams, build_booster, build_orbiter, \
    build_tank
from liftoff.meshes.tank import AL2219, tank_layout, wetted_area

# OCC surfaces of revolution are exact; occ.getMass integrates them to ~1e-6 (as test_tank)
CAD_RTOL = 1e-5


def _small(fill=0.6, **kw):
    comp = Compartment("lox", 1.5, 0.72, 1.6, fill, 1141.0)
    return TankParams(radius=1.0, wall_thickness=0.1, compartments=(comp,), mesh_size=0.3,
                      patches={"tank_bottom": (0, 0, 0), "tank_top": (0, 0, 0.72 + 1.5 + 1.6),
                               "side": (1.0, 0.0, 1.5)}, patch_half_width=0.2, **kw)


@pytest.mark.parametrize("fill", [0.12, 0.6, 0.93])
def test_shell_tank_areas_masses_and_groups(fill, tmp_path, msh_groups):
    p = _small(fill, walls="shell")
    g = build_tank(p, tmp_path / "shell")
    solid = build_tank(replace(p, walls="solid"), tmp_path / "solid")
    c = tank_layout(p)[0]
    rm, ab, at = 1.0 - 0.05, c.a_bottom - 0.05, c.a_top - 0.05            # mid-surface
    assert g.shells == {"tank_wall": pytest.approx(p.dry_mass / (AL2219.rho * g.surface_areas["tank_wall"]))}
    assert g.volumes["tank_wall"] == AL2219 and g.shell_bending == {"tank_wall": 1.0}
    # the wall is the closed mid-surface capsule; the wetted part lies below the fill plane
    assert g.surface_areas["tank_wall"] == pytest.approx(wetted_area(rm, ab, at, c.cyl_length, 1e9), rel=CAD_RTOL)
    h = c.z_fill - (c.z_cyl_bottom - ab)
    assert g.surface_areas["tank_lox_wetted"] == pytest.approx(wetted_area(rm, ab, at, c.cyl_length, h), rel=CAD_RTOL)
    # liquid and total mass exactly those of the solid variant (the same cavity)
    assert [s.mass for s in g.smeared_masses] == [s.mass for s in solid.smeared_masses]
    assert g.nominal_mass() == pytest.approx(solid.nominal_mass(), rel=CAD_RTOL)
    groups = msh_groups(g)
    assert set(groups) == {(2, "tank_wall"), (2, "tank_lox_wetted"), (2, "tank_bottom"), (2, "tank_top"), (2, "side")}
    for name in ("tank_bottom", "tank_top"):
        nodes = groups[(2, name)]["nodes"]
        assert len(nodes) >= 6 and np.all(np.hypot(nodes[:, 0], nodes[:, 1]) <= p.patch_half_width + 1e-6)
    side = groups[(2, "side")]["nodes"]
    assert np.allclose(np.hypot(side[:, 0], side[:, 1]), rm, rtol=1e-9)          # on the mid-surface
    assert np.all(np.abs(side[:, 1]) <= 0.2 + 1e-6) and np.all(np.abs(side[:, 2] - 1.5) <= 0.2 + 1e-6)


def test_shell_tank_thickness_options_and_bad_input(tmp_path):
    g = build_tank(_small(walls="shell", shell_thickness=0.01, shell_bending_ratio=50.0), tmp_path)
    mat = g.volumes["tank_wall"]
    assert g.shells["tank_wall"] == 0.01 and g.shell_bending["tank_wall"] == 50.0
    assert mat.rho * 0.01 * g.surface_areas["tank_wall"] == pytest.approx(5500.0, rel=1e-12)
    assert mat.E / mat.rho == pytest.approx(AL2219.E / AL2219.rho, rel=1e-12)
    with pytest.raises(InputError, match=r"walls must be one of 'solid', 'shell' \(got 'membrane'\)"):
        build_tank(_small(walls="membrane"), tmp_path)
    with pytest.raises(InputError, match="shell_bending_ratio must be a finite number > 0"):
        build_tank(_small(walls="shell", shell_bending_ratio=0.0), tmp_path)


@pytest.fixture(scope="module")
def shell_vehicle(tmp_path_factory):
    out = tmp_path_factory.mktemp("shell_vehicle")
    return (build_booster(BoosterParams(side="right", walls="shell", mesh_size=1.0), out),
            build_orbiter(OrbiterParams(walls="shell", mesh_size=1.0), out))


def test_shell_booster_and_orbiter_groups_and_masses(shell_vehicle, tmp_path, msh_groups):
    booster, orbiter = shell_vehicle
    solid_b = build_booster(BoosterParams(side="right", mesh_size=1.0), tmp_path)
    solid_o = build_orbiter(OrbiterParams(mesh_size=1.0), tmp_path)
    for shell, solid in ((booster, solid_b), (orbiter, solid_o)):
        assert {p.name for p in shell.patches} == {p.name for p in solid.patches}
        for a in shell.patches:
            assert np.allclose(a.ref_point, solid.patch(a.name).ref_point)
        assert shell.nominal_mass() == pytest.approx(solid.nominal_mass(), rel=CAD_RTOL)
        assert [(s.surface, s.mass) for s in shell.smeared_masses] == [(s.surface, s.mass) for s in solid.smeared_masses]
        assert [(q.name, q.mass) for q in shell.point_masses] == [(q.name, q.mass) for q in solid.point_masses]
        names = {n for _, n in msh_groups(shell)}
        assert {p.nodes or p.name for p in shell.patches} <= names       # rigid patch or ring group
    assert booster.shells == {"srb_right_case": pytest.approx(75_000.0 / (7850.0 * booster.surface_areas["srb_right_case"]))}
    assert set(booster.volumes) == {"srb_right_case", "srb_right_skirt"}
    assert (3, "srb_right_skirt") in msh_groups(booster) and (2, "srb_right_case_inner") in msh_groups(booster)
    assert set(orbiter.volumes) == {"orbiter_structure", "orbiter_wing"}
    assert (3, "orbiter_wing") in msh_groups(orbiter) and (2, "orbiter_structure") in msh_groups(orbiter)
    # hold-down patches stay on the solid skirt's bottom; the gimbal cap on the case mid-surface
    hd = msh_groups(booster)[(2, "srb_right_hd_1")]["nodes"]
    assert np.all(hd[:, 2] <= 0.5 * BoosterParams().skirt_foot_height + 1e-6)
    gimbal = msh_groups(booster)[(2, "srb_right_gimbal")]["nodes"]
    axis = BoosterParams(side="right").layout.srb_axis("right")
    assert np.all(np.hypot(gimbal[:, 0] - axis[0], gimbal[:, 1] - axis[1]) <= 0.45 + 1e-6)
    assert math.isclose(gimbal[:, 2].min(), 2.6 - 0.7 * 1.855 + 0.075, rel_tol=1e-6)


def test_shell_tank_ring_attach(tmp_path, msh_groups):
    """attach = "ring": an off-axis point interpolates (fem: RBE3) the wall's nodes on the
    ring imprinted at its height, over RING_REACH x the mid-surface radius; apex points stay
    rigid disk patches; the wall and its mass are those of the patch variant."""
    from liftoff.meshes.shells import RING_REACH

    g = build_tank(_small(walls="shell", attach="ring"), tmp_path / "ring")
    ref = build_tank(_small(walls="shell"), tmp_path / "patch")
    side = g.patch("side")
    assert side.nodes == "tank_ring_0" and side.reach == pytest.approx(RING_REACH * 0.95)
    assert g.patch("tank_top").nodes is None and g.patch("tank_bottom").nodes is None
    groups = msh_groups(g)
    assert (2, "side") not in groups
    ring = groups[(1, "tank_ring_0")]["nodes"]
    assert ring.shape[0] >= 12
    assert np.allclose(ring[:, 2], 1.5, rtol=0, atol=1e-9) and np.allclose(np.hypot(ring[:, 0], ring[:, 1]), 0.95)
    assert g.nominal_mass() == pytest.approx(ref.nominal_mass(), rel=CAD_RTOL)
    with pytest.raises(InputError, match="attach = 'ring' needs walls = 'shell'"):
        build_tank(_small(attach="ring"), tmp_path)
    with pytest.raises(InputError, match=r"attach must be one of 'patch', 'ring' \(got 'hoop'\)"):
        build_tank(_small(walls="shell", attach="hoop"), tmp_path)


def test_shell_booster_and_orbiter_ring_attach(tmp_path, msh_groups):
    """The core attach points of a shell booster and orbiter as rings at their heights."""
    out = tmp_path / "ring"
    for g, attach in ((build_booster(BoosterParams(side="right", walls="shell", mesh_size=1.0, attach="ring"), out),
                       BoosterParams().layout.srb_attach_points("right")),
                      (build_orbiter(OrbiterParams(walls="shell", mesh_size=1.0, attach="ring"), out),
                       OrbiterParams().layout.orbiter_attach_points())):
        groups = msh_groups(g)
        for name, pt in attach.items():
            p = g.patch(name)
            assert p.nodes is not None and (2, name) not in groups
            z = groups[(1, p.nodes)]["nodes"][:, 2]
            assert np.allclose(z, pt[2], rtol=0, atol=1e-9)
        if g.name == "orbiter":       # engines on the aft bulkhead's rim, payload on a whole ring
            p = OrbiterParams()
            z0, t = p.layout.orbiter_bottom_z, p.wall_thickness
            for name, z in (("ssme_mount", z0 + 0.5 * t), ("payload_station", p.payload_z)):
                ring = groups[(1, g.patch(name).nodes)]["nodes"]
                assert g.patch(name).reach == math.inf and np.allclose(ring[:, 2], z, rtol=0, atol=1e-9)
                r = np.hypot(ring[:, 0], ring[:, 1] - p.layout.orbiter_axis_y)
                assert ring.shape[0] >= 12 and np.allclose(r, p.layout.orbiter_radius - 0.5 * t)
    with pytest.raises(InputError, match="attach = 'ring' needs walls = 'shell'"):
        build_orbiter(OrbiterParams(attach="ring"), out)


def test_shell_orbiter_wing_carried_through(shell_vehicle):
    """The shell orbiter's wing slab runs through the fuselage (carry-through structure) with
    the solid variant's density; the skin weighs the rest of the structure mass."""
    from liftoff.meshes.vehicle import orbiter_part_volumes

    _, orbiter = shell_vehicle
    p = OrbiterParams()
    box = p.wing_span * p.wing_thickness * p.wing_root_chord
    assert orbiter.group_volumes["orbiter_wing"] == pytest.approx(box, rel=CAD_RTOL)
    rho = p.structure_mass / sum(orbiter_part_volumes(p))
    assert orbiter.volumes["orbiter_wing"].rho == pytest.approx(rho, rel=CAD_RTOL)
    skin = orbiter.volumes["orbiter_structure"].rho * orbiter.shells["orbiter_structure"] \
        * orbiter.surface_areas["orbiter_structure"]
    assert skin + rho * box == pytest.approx(p.structure_mass, rel=CAD_RTOL)
