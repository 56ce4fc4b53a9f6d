"""Tank builder: groups, CAD volume vs closed form, wetted area and liquid mass vs closed
form and an independent gmsh solid, at several fill levels."""
from __future__ import annotations

import math

import gmsh
import numpy as np
import pytest

from liftoff.meshes import Compartment, TankParams, build_tank
from liftoff.meshes.tank import liquid_volume, tank_layout, wall_volume, wetted_area

# OCC solids of revolution are exact analytic surfaces; occ.getMass integrates them
# numerically to ~1e-6 relative (observed 1.3e-6 on the default tank wall), so 1e-5.
CAD_RTOL = 1e-5


@pytest.fixture(scope="module")
def default_tank(tmp_path_factory):
    return TankParams(), build_tank(TankParams(), tmp_path_factory.mktemp("tank"))


def test_groups_and_patches(default_tank, msh_groups):
    p, g = default_tank
    groups = msh_groups(g)
    assert set(groups) == {(3, "tank_wall"), (2, "tank_lox_wetted"), (2, "tank_bottom"), (2, "tank_top")}
    for patch in g.patches:
        nodes = groups[(2, patch.name)]["nodes"]
        assert len(nodes) >= 6, patch.name
        # apex disk patches: every node within the patch half-width of the axis, at the apex
        assert np.all(np.hypot(nodes[:, 0], nodes[:, 1]) <= p.patch_half_width + 1e-6)
        assert np.all(np.abs(nodes[:, 2] - patch.ref_point[2]) < 0.05)


def test_wall_volume_matches_closed_form(default_tank, msh_groups):
    p, g = default_tank
    assert g.group_volumes["tank_wall"] == pytest.approx(wall_volume(p), rel=CAD_RTOL)
    # P1 faceting: chords of the outer surface remove wall volume, chords of the inner
    # (cavity) surface add some; each is ~(2/3) sag/t with sag = h^2/(8 rho) (a few % at
    # this mesh size) and they cancel to leading order, leaving O(t/R) of that: < 2 %.
    mesh_v = msh_groups(g)[(3, "tank_wall")]["measure"]
    assert mesh_v == pytest.approx(g.group_volumes["tank_wall"], rel=0.02)


def _independent_liquid_volume(r, a_b, a_t, L, h):
    """Volume below height h of the capsule by quadrature of its circular cross-sections
    pi rho(z)^2 (independent of the piecewise closed form used by the builder)."""
    from scipy.integrate import quad

    def area(z):
        if z < a_b:
            return math.pi * r * r * (1 - ((a_b - z) / a_b) ** 2)
        if z < a_b + L:
            return math.pi * r * r
        return math.pi * r * r * max(1 - ((z - a_b - L) / a_t) ** 2, 0.0)
    return quad(area, 0.0, h, points=[p for p in (a_b, a_b + L) if p < h], epsabs=0, epsrel=1e-12, limit=200)[0]


@pytest.mark.parametrize("fill", [0.12, 0.5, 0.93, 1.0])
def test_wetted_area_and_liquid_mass(fill, tmp_path):
    comp = Compartment("lox", 1.5, 0.72, 1.6, fill, 1141.0)  # a small tank: few elements
    p = TankParams(radius=1.0, wall_thickness=0.1, compartments=(comp,), patches={}, mesh_size=0.5)
    g = build_tank(p, tmp_path)
    c = tank_layout(p)[0]
    # the regions: bottom dome (0.12), cylinder (0.5), top dome (0.93), all (1.0)
    area = wetted_area(c.r_inner, c.a_bottom_inner, c.a_top_inner, c.cyl_length, c.fill_height)
    assert g.surface_areas["tank_lox_wetted"] == pytest.approx(area, rel=CAD_RTOL)
    if fill == 1.0:
        full = wetted_area(c.r_inner, c.a_bottom_inner, c.a_top_inner, c.cyl_length, 1e9)
        assert area == pytest.approx(full, rel=1e-12)      # the same closed form: a few roundings
    # liquid mass vs quadrature of the cavity's cross-sections (quad to 1e-12; 1e-9)
    v_ind = _independent_liquid_volume(c.r_inner, c.a_bottom_inner, c.a_top_inner, c.cyl_length, c.fill_height)
    (sm,) = g.smeared_masses
    assert sm.surface == "tank_lox_wetted"
    assert sm.mass == pytest.approx(1141.0 * v_ind, rel=1e-9)
    assert sm.mass == pytest.approx(1141.0 * liquid_volume(c.r_inner, c.a_bottom_inner, c.a_top_inner,
                                                          c.cyl_length, c.fill_height), rel=1e-12)  # same formula


def test_wetted_nodes_stop_at_fill_level(tmp_path, msh_groups):
    p = TankParams(radius=1.0, wall_thickness=0.1, compartments=(Compartment("lox", 1.5, 0.72, 1.6, 0.5, 1141.0),),
                   patches={}, mesh_size=0.5)
    g = build_tank(p, tmp_path)
    c = tank_layout(p)[0]
    nodes = msh_groups(g)[(2, "tank_lox_wetted")]["nodes"]
    assert nodes[:, 2].max() == pytest.approx(c.z_fill, abs=1e-9)
    assert nodes[:, 2].min() == pytest.approx(c.z_inner_bottom, abs=1e-6)
    assert np.all(np.hypot(nodes[:, 0], nodes[:, 1]) <= c.r_inner + 1e-9)


def test_default_tank_mass(default_tank):
    p, g = default_tank
    c = tank_layout(p)[0]
    liquid = 1141.0 * liquid_volume(c.r_inner, c.a_bottom_inner, c.a_top_inner, c.cyl_length, c.fill_height)
    # rho = m / V, then rho V (and E = rho (E/rho)): a few roundings each; 1e-12 is 4500 eps
    assert g.nominal_mass() == pytest.approx(p.dry_mass + liquid, rel=1e-12)
    # density adjusted to the dry mass, E scaled with it (E/rho of Al 2219 kept)
    mat = g.volumes["tank_wall"]
    assert mat.rho * g.group_volumes["tank_wall"] == pytest.approx(p.dry_mass, rel=1e-12)
    assert mat.E / mat.rho == pytest.approx(73.8e9 / 2840.0, rel=1e-12)    # E = rho (E/rho): 3 roundings


def test_two_compartments_closed_form(tmp_path):
    """An intertank skirt joining two compartments: volume by exact cross-section quadrature."""
    comps = (Compartment("a", 3.0, 0.7, 0.7, 0.6, 70.85), Compartment("b", 2.0, 0.7, 1.0, 0.8, 1141.0))
    p = TankParams(radius=2.0, wall_thickness=0.1, compartments=comps, intertank_length=3.5,
                   patches={"mid": (2.5, 0.0, 1.4 + 3.0 + 1.75)}, mesh_size=0.8)
    g = build_tank(p, tmp_path)
    assert g.group_volumes["tank_wall"] == pytest.approx(wall_volume(p), rel=CAD_RTOL)
    for c in tank_layout(p):
        assert g.surface_areas[f"tank_{c.name}_wetted"] == pytest.approx(c.wetted_area(), rel=CAD_RTOL)
    assert math.isclose(g.patch("mid").ref_point[0], 2.5)
