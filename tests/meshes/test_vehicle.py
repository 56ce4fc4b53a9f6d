"""Default twin-booster stack: physical groups, patches, shared interface points, CAD
volumes vs closed forms, and component masses vs the documented totals (docs/meshes.md)."""
from __future__ import annotations

import numpy as np
import pytest

from liftoff.meshes import BoosterParams, OrbiterParams, StackLayout, core_stage_params
from liftoff.meshes.tank import tank_layout, wall_volume
from liftoff.meshes.vehicle import booster_closed_form_volumes, orbiter_closed_form_volumes

CAD_RTOL = 1e-5  # occ.getMass numerical integration (~1e-6), see test_tank.py

# Documented default masses (docs/meshes.md, public Shuttle figures), kg.
CORE_MASS = 760_000.0       # ET gross lift-off mass ~760 t (dry 26.5 t + LOX ~629 t + LH2 ~106 t)
SRB_MASS = 590_000.0        # each SRB at ignition
ORBITER_MASS = 110_000.0
STACK_MASS = CORE_MASS + 2 * SRB_MASS + ORBITER_MASS   # ~2,050 t ("about 2,000 t")

GROUPS = {
    "core": {(3, "core_wall"), (2, "core_lh2_wetted"), (2, "core_lox_wetted"), (2, "stack_top"),
             (2, "att_srb_left_fwd"), (2, "att_srb_left_aft"), (2, "att_srb_right_fwd"),
             (2, "att_srb_right_aft"), (2, "att_orb_fwd"), (2, "att_orb_aft_left"), (2, "att_orb_aft_right")},
    "orbiter": {(3, "orbiter_structure"), (2, "ssme_mount"), (2, "payload_station"), (2, "att_orb_fwd"),
                (2, "att_orb_aft_left"), (2, "att_orb_aft_right")},
}
for _s in ("left", "right"):
    GROUPS[f"srb_{_s}"] = {(3, f"srb_{_s}_case"), (3, f"srb_{_s}_skirt"), (2, f"srb_{_s}_case_inner"),
                           (2, f"srb_{_s}_gimbal"), (2, f"att_srb_{_s}_fwd"), (2, f"att_srb_{_s}_aft")} | {
        (2, f"srb_{_s}_hd_{k}") for k in range(1, 5)}


@pytest.mark.parametrize("comp", sorted(GROUPS))
def test_physical_groups_and_patches(stack, msh_groups, comp):
    g = stack[comp]
    groups = msh_groups(g)
    assert set(groups) == GROUPS[comp]
    assert set(g.volumes) == {n for d, n in GROUPS[comp] if d == 3}
    assert g.clamped == []  # vehicle components are free-free
    for p in g.patches:
        nodes = groups[(2, p.name)]["nodes"]
        assert len(nodes) >= 6, f"{p.name}: {len(nodes)} nodes"
        assert groups[(2, p.name)]["measure"] > 0
        # every patch is near its reference point (patches are <= 1 m across; attach
        # points lie mid-gap, <= 0.5 m off the wall; payload trunnions 2.6 m off the axis)
        reach = {"payload_station": 3.0, "ssme_mount": 2.5}.get(p.name, 2.0)  # SSME c.g. 1.8 m aft
        assert np.linalg.norm(nodes - p.ref_point, axis=1).max() < reach, p.name
    for sm in g.smeared_masses:
        assert (2, sm.surface) in groups
    # a default component stays small (pipeline on 2 cores in minutes)
    assert 2_000 < g.mesh_nodes < 20_000


def test_attach_points_are_shared(stack):
    """Same name, same reference point on both sides of every interface."""
    core = {p.name: p.ref_point for p in stack["core"].patches}
    seen = 0
    for comp in ("srb_left", "srb_right", "orbiter"):
        for p in stack[comp].patches:
            if p.name.startswith("att_"):
                np.testing.assert_array_equal(p.ref_point, core[p.name])
                seen += 1
    assert seen == 7 and sum(n.startswith("att_") for n in core) == 7


def test_patches_sit_on_the_right_surfaces(stack, msh_groups):
    lay = StackLayout()
    core = msh_groups(stack["core"])
    for name in ("att_srb_left_fwd", "att_orb_aft_right"):
        n = core[(2, name)]["nodes"]
        np.testing.assert_allclose(np.hypot(n[:, 0], n[:, 1]), lay.core_radius, rtol=1e-6)
    for side in ("left", "right"):
        srb = msh_groups(stack[f"srb_{side}"])
        axis = lay.srb_axis(side)
        for k in range(1, 5):
            n = srb[(2, f"srb_{side}_hd_{k}")]["nodes"]
            assert np.abs(n[:, 2]).max() < 1e-9  # hold-downs on the skirt bottom, z = 0
            r = np.hypot(n[:, 0] - axis[0], n[:, 1] - axis[1])
            assert np.all(np.abs(r - lay.holddown_radius) <= 0.2 + 1e-6)
        n = srb[(2, f"att_srb_{side}_aft")]["nodes"]
        np.testing.assert_allclose(np.hypot(n[:, 0] - axis[0], n[:, 1] - axis[1]), lay.srb_radius, rtol=1e-6)
        # the core-facing side
        assert np.all(np.sign(n[:, 0] - axis[0]) == (1 if side == "left" else -1))


def test_volumes_match_closed_forms(stack, msh_groups):
    expect = {"core_wall": wall_volume(core_stage_params())}
    for side in ("left", "right"):
        expect.update(booster_closed_form_volumes(BoosterParams(side=side)))
    expect.update(orbiter_closed_form_volumes(OrbiterParams()))
    for comp, g in stack.items():
        for name, v in g.group_volumes.items():
            assert v > 0
            assert v == pytest.approx(expect[name], rel=CAD_RTOL), name
            # mesh faceting of the thickened walls: opposite-sign inner/outer errors, < 2 %
            assert msh_groups(g)[(3, name)]["measure"] == pytest.approx(v, rel=0.02), name


def test_masses_add_up_to_documented_totals(stack):
    # the core's mass follows from geometry + liquid densities + fill levels: within 0.5 %
    # of the published 760 t; boosters and orbiter are set by construction (exact)
    assert stack["core"].nominal_mass() == pytest.approx(CORE_MASS, rel=5e-3)
    for side in ("left", "right"):
        assert stack[f"srb_{side}"].nominal_mass() == pytest.approx(SRB_MASS, rel=1e-9)
    assert stack["orbiter"].nominal_mass() == pytest.approx(ORBITER_MASS, rel=1e-9)
    total = sum(g.nominal_mass() for g in stack.values())
    assert total == pytest.approx(STACK_MASS, rel=5e-3)
    # the propellant loads: LOX ~629 t, LH2 ~106 t (public figures) within 2 %
    sm = {s.surface: s.mass for s in stack["core"].smeared_masses}
    assert sm["core_lox_wetted"] == pytest.approx(629_000.0, rel=0.02)
    assert sm["core_lh2_wetted"] == pytest.approx(106_000.0, rel=0.02)


def test_core_smeared_mass_is_liquid_volume_times_density(stack):
    p = core_stage_params()
    sm = {s.surface: s.mass for s in stack["core"].smeared_masses}
    for c, comp in zip(tank_layout(p), p.compartments):
        # the same closed form times the density: a few roundings (1e-12 = 4500 eps)
        assert sm[f"core_{c.name}_wetted"] == pytest.approx(comp.liquid_density * c.liquid_volume(), rel=1e-12)
        assert stack["core"].surface_areas[f"core_{c.name}_wetted"] == pytest.approx(c.wetted_area(), rel=CAD_RTOL)


def test_equivalent_materials_keep_specific_stiffness(stack):
    """Thickened walls: rho = mass / volume and E/rho of the real alloy kept."""
    g = stack["srb_left"]
    case = g.volumes["srb_left_case"]
    # rho = m / V then rho V, E = rho (E/rho): a few roundings each (1e-12 = 4500 eps)
    assert case.rho * g.group_volumes["srb_left_case"] == pytest.approx(BoosterParams().case_mass, rel=1e-12)
    assert case.E / case.rho == pytest.approx(205e9 / 7850.0, rel=1e-12)
    core = stack["core"].volumes["core_wall"]
    assert core.E / core.rho == pytest.approx(73.8e9 / 2840.0, rel=1e-12)


def test_core_stage_ring_frames_and_stringers(tmp_path):
    """The external tank's shell wall with ring frames and stringers (beams; issue 26): their
    groups on the geometry, the frames' circles at the wall's inner face (the mid-surface radius
    plus their radial offset: half the skin and the section's centroid depth inwards), the
    stringers the cylindrical wall's length each,
    and the tank's dry mass kept: wall + frames + stringers = 26.5 t (their mass comes off the
    skin's thickness; the wetted areas' CAD integration, CAD_RTOL, the only error)."""
    from liftoff.core.beam import standard_section
    from liftoff.meshes.tank import build_tank

    tee = {"shape": "t", "h": 0.25, "b": 0.1, "tw": 0.006, "tf": 0.01}
    hat = {"shape": "hat", "h": 0.05, "b": 0.04, "c": 0.02, "t": 0.003}
    frames = (13.2, 25.1, 40.5)
    p = core_stage_params(mesh_size=2.0, walls="shell", liquid="hydroelastic", frames=frames, frame_section=tee,
                          stringers=12, stringer_azimuth=7.5, stringer_section=hat)
    geo = build_tank(p, tmp_path)
    fr, st = geo.beams["core_frames"], geo.beams["core_stringers"]
    assert fr.section == standard_section(tee)[0] and st.section == standard_section(hat)[0]
    t = geo.shells["core_wall"]
    r = p.radius - p.wall_thickness / 2 + fr.radial_offset     # the shell at the drawn wall's mid-surface
    assert geo.curve_lengths["core_frames"] == pytest.approx(len(frames) * 2 * np.pi * r, rel=1e-9)
    cylinder = 25.6 + 6.9 + 4.65                     # LH2 barrel, intertank, LOX barrel (m)
    assert geo.curve_lengths["core_stringers"] == pytest.approx(12 * cylinder, rel=1e-9)
    wall = geo.volumes["core_wall"]
    dry = (wall.rho * t * geo.surface_areas["core_wall"]
           + fr.material.rho * fr.section.A * geo.curve_lengths["core_frames"]
           + st.material.rho * st.section.A * geo.curve_lengths["core_stringers"])
    assert dry == pytest.approx(26_500.0, rel=CAD_RTOL)
    bare = build_tank(core_stage_params(mesh_size=2.0, walls="shell", liquid="hydroelastic"), tmp_path / "bare")
    assert not bare.beams and t < bare.shells["core_wall"]


def test_attach_options_list_each_default_first():
    """meshes.layout.ATTACH_OPTIONS (the values each attach option takes; the config checks
    read its first as the default) against StackLayout's own field defaults; any other value
    refused, named."""
    from liftoff.core.errors import InputError
    from liftoff.meshes.layout import ATTACH_OPTIONS

    layout = StackLayout()
    for key, values in ATTACH_OPTIONS.items():
        assert getattr(layout, key) == values[0]
        with pytest.raises(InputError, match=f"StackLayout.{key} must be one of"):
            StackLayout(**{key: "glue"}).check()


def test_aft_strut_points_of_the_layout():
    """``srb_aft_attach = "struts"``: each booster's aft attach point gives way to its three
    struts' end points, on each wall's outer surface at the aft attach height (the tank's
    radius about its axis, the booster's about its own, to 1e-12), the sway braces across the
    gap at y = +-srb_aft_strut_y (upper: the orbiter's side), the diagonal from the tank's
    upper end to the booster's lower one; the right booster's are the left's mirror images
    (x -> -x). The default ("point") keeps the one aft point."""
    from liftoff.core.errors import InputError

    assert "att_srb_left_aft" in StackLayout().srb_attach_points("left")
    assert StackLayout().srb_aft_struts("left") == {}
    lay = StackLayout(srb_aft_attach="struts", srb_aft_strut_y=1.2)
    lay.check()
    assert set(lay.srb_attach_points("left")) == {"att_srb_left_fwd"}
    pts = {s: lay.srb_aft_strut_points(s) for s in ("left", "right")}
    for side, p in pts.items():
        ax = lay.srb_axis(side)
        assert set(p["core"]) == {f"et_srb_{side}_aft_upper", f"et_srb_{side}_aft_lower"}
        for name, x in p["core"].items():
            assert np.hypot(x[0], x[1]) == pytest.approx(lay.core_radius, rel=1e-12)
            assert x[2] == lay.srb_aft_attach_z and abs(x[1]) == 1.2 and (x[1] > 0) == name.endswith("upper")
        for name, x in p["booster"].items():
            assert np.hypot(x[0] - ax[0], x[1] - ax[1]) == pytest.approx(lay.srb_radius, rel=1e-12)
            assert abs(x[0]) < abs(ax[0])                              # the tank-facing side
        struts = lay.srb_aft_struts(side)
        assert struts[f"srb_{side}_aft_strut_diagonal"] == (f"et_srb_{side}_aft_upper", f"srb_{side}_aft_lower")
        for a, b in struts.values():
            assert a in p["core"] and b in p["booster"]
    for group in ("core", "booster"):
        for name, x in pts["left"][group].items():
            np.testing.assert_array_equal(pts["right"][group][name.replace("left", "right")], x * [-1, 1, 1])
    named = lay.named_points()
    assert "et_srb_right_aft_lower" in named and "srb_left_hd_1" in named and "att_srb_left_aft" not in named
    cp = core_stage_params(lay)
    assert {"et_srb_left_aft_upper", "et_srb_right_aft_lower"} <= set(cp.patches) and "att_srb_left_aft" not in cp.patches
    b = BoosterParams(side="right", layout=lay).attach_points()
    assert set(b) == {"att_srb_right_fwd", "srb_right_aft_upper", "srb_right_aft_lower"}
    for bad, match in (({"srb_aft_attach": "strut"}, "srb_aft_attach must be one of 'point', 'struts'"),
                       ({"srb_aft_attach": "struts", "srb_aft_strut_y": 1.6}, "srb_aft_strut_y = 1.6 m"),
                       ({"srb_aft_attach": "struts", "srb_aft_strut_y": float("nan")}, "srb_aft_strut_y")):
        with pytest.raises(InputError, match=match):
            StackLayout(**bad).check()


def test_booster_meshed_with_aft_strut_patches(tmp_path, msh_groups):
    """The solid booster meshed with the aft struts' layout: a patch at each strut point on
    the case's outer surface (radius to 1e-6), within 0.7 m of its point, and no aft attach
    patch."""
    from liftoff.meshes import build_booster

    lay = StackLayout(srb_aft_attach="struts")
    g = build_booster(BoosterParams(side="left", layout=lay, mesh_size=1.0), tmp_path)
    groups = msh_groups(g)
    assert (2, "att_srb_left_aft") not in groups
    ax = lay.srb_axis("left")
    refs = {p.name: p.ref_point for p in g.patches}
    for name, x in lay.srb_aft_strut_points("left")["booster"].items():
        n = groups[(2, name)]["nodes"]
        assert len(n) >= 6
        np.testing.assert_allclose(np.hypot(n[:, 0] - ax[0], n[:, 1] - ax[1]), lay.srb_radius, rtol=1e-6)
        assert np.linalg.norm(n - x, axis=1).max() < 0.7
        np.testing.assert_array_equal(refs[name], x)


def test_thrust_beam_points_of_the_layout():
    """``srb_fwd_attach = "beam"``: the forward balls move off the tank's wall onto the
    intertank's thrust beam: the core's points for each booster lose ``att_srb_<side>_fwd``
    and gain ``et_srb_<side>_fwd`` on its wall (radius, height, the x axis: exact); the beam
    is its span between the two wall points and a fitting from each booster's ball, which the
    booster keeps, to its wall point. The default ("wall") keeps the ball on the wall."""
    from liftoff.core.errors import InputError

    assert StackLayout().srb_thrust_beam() == {} and "att_srb_left_fwd" in StackLayout().srb_core_points("left")
    lay = StackLayout(srb_fwd_attach="beam")
    lay.check()
    for side, sgn in (("left", -1.0), ("right", 1.0)):
        core = lay.srb_core_points(side)
        assert f"att_srb_{side}_fwd" not in core and f"att_srb_{side}_aft" in core
        np.testing.assert_array_equal(core[f"et_srb_{side}_fwd"], [sgn * lay.core_radius, 0.0, lay.srb_fwd_attach_z])
        assert f"att_srb_{side}_fwd" in lay.srb_booster_points(side)
    beam = lay.srb_thrust_beam()
    assert beam == {"srb_left_thrust_fitting": ("att_srb_left_fwd", "et_srb_left_fwd"),
                    "srb_thrust_beam": ("et_srb_left_fwd", "et_srb_right_fwd"),
                    "srb_right_thrust_fitting": ("att_srb_right_fwd", "et_srb_right_fwd")}
    named = lay.named_points()
    assert all(e in named for ends in beam.values() for e in ends)
    cp = core_stage_params(lay)
    assert "et_srb_left_fwd" in cp.patches and "att_srb_left_fwd" not in cp.patches
    with pytest.raises(InputError, match="srb_fwd_attach must be one of 'wall', 'beam'"):
        StackLayout(srb_fwd_attach="ball").check()


def test_orbiter_bipod_feet_of_the_layout():
    """``orbiter_attach = "bipods"``: the tank's orbiter attach points give way to the feet
    of the orbiter's six attach struts on its wall (radius 1e-12); the orbiter keeps its
    three attach points, each the apex of a bipod; the forward pair lies in the plane across
    the axis (x-y), each aft pair in the plane of the axis and the orbiter's offset (y-z,
    its attach point's x), as the default's released joints carry (Tx Ty forward, Ty Tz
    aft). The default ("point") keeps the tank's attach points."""
    from liftoff.core.errors import InputError

    assert StackLayout().orbiter_bipods() == {} and "att_orb_fwd" in StackLayout().orbiter_core_points()
    lay = StackLayout(orbiter_attach="bipods")
    lay.check()
    feet, apex = lay.orbiter_bipod_feet(), lay.orbiter_attach_points()
    assert set(lay.orbiter_core_points()) == set(feet) and len(feet) == 6
    for x in feet.values():
        assert np.hypot(x[0], x[1]) == pytest.approx(lay.core_radius, rel=1e-12)
    struts = lay.orbiter_bipods()
    assert len(struts) == 6
    for name, (foot, top) in struts.items():
        d = apex[top] - feet[foot]
        if "fwd" in name:
            assert d[2] == 0 and d[0] != 0          # across the vehicle
        else:
            assert d[0] == 0 and d[1] > 0           # in the y-z plane
    assert feet["et_orb_aft_left_diagonal"][2] - apex["att_orb_aft_left"][2] == lay.orbiter_aft_bipod_dz
    assert set(core_stage_params(lay).patches) >= set(feet) and "att_orb_fwd" not in core_stage_params(lay).patches
    assert set(feet) <= set(lay.named_points())
    with pytest.raises(InputError, match="orbiter_attach must be one of 'point', 'bipods'"):
        StackLayout(orbiter_attach="bipod").check()
    with pytest.raises(InputError, match=r"orbiter_fwd_bipod_x = 3.5 m must be in \(0, 3.36\) m"):
        StackLayout(orbiter_attach="bipods", orbiter_fwd_bipod_x=3.5).check()      # (0.8 x the tank's radius)
    StackLayout(orbiter_attach="bipods", orbiter_radius=1.8).check()                 # (the orbiter's is no bound)
