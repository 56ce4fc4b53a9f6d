"""Barge, cargo and dock geometry (meshes/barge.py): volume groups against the plate layout's
closed form, named points where the parameters put them (patch nodes on their faces), the
cargo's interfaces on the barge's saddle tops, the dock's fenders facing the bow, clamped
pile bases, and bad parameters refused with the parameter named."""
from __future__ import annotations

import numpy as np
import pytest

from liftoff.core.errors import InputError
from liftoff.meshes.barge import (BargeParams, CargoParams, DockParams, barge_closed_form_volumes, build_barge,
                                  build_cargo, build_dock, default_positions, hull_axial_stiffness)

COARSE = dict(mesh_size=3.0)


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    out = tmp_path_factory.mktemp("barge")
    b = BargeParams(**COARSE)
    fit = default_positions(b)
    return (b, build_barge(b, out), build_cargo(CargoParams(mesh_size=2.5, **fit["cargo"]), out),
            build_dock(DockParams(mesh_size=3.0, **fit["dock"]), out))


def test_barge_volumes_points_and_ballast(built, msh_groups):
    p, barge, _, _ = built
    # the CAD volumes are the boxes' (disjoint plates, imprinting does not change them): round-off
    for g, v in barge_closed_form_volumes(p).items():
        assert barge.group_volumes[g] == pytest.approx(v, rel=1e-9), g
    groups = msh_groups(barge)
    refs = {**p.bow_points(), **p.station_points(), **p.cargo_points(), "stern": p.stern_point()}
    assert {pt.name for pt in barge.patches} == set(refs)
    for pt in barge.patches:
        np.testing.assert_array_equal(pt.ref_point, refs[pt.name])
        nodes = groups[(2, pt.name)]["nodes"]
        axis = 0 if pt.name.startswith(("bow", "stern")) else 2     # bow/stern: on the x face; deck, saddle: z
        assert np.abs(nodes[:, axis] - pt.ref_point[axis]).max() < 1e-9, pt.name
    # bow patches: the square given by fender_patch (mesh measure = exact for a flat face)
    assert groups[(2, "bow_1")]["measure"] == pytest.approx(p.fender_patch ** 2, rel=1e-9)
    # ballast surface: inner bottom less the bulkheads' and ends' footprints
    inner = (p.length - 2 * p.wall - p.n_bulkheads * p.wall) * (p.beam - 2 * p.wall)
    assert barge.surface_areas["barge_bottom_inner"] == pytest.approx(inner, rel=1e-9)
    assert barge.smeared_masses[0].mass == p.ballast_mass
    # equivalent plates keep the membrane stiffness and mass of the real (framed) plates
    deck = barge.volumes["barge_deck"]
    assert deck.E * p.wall == pytest.approx(210e9 * p.deck_thickness * p.framing_factor, rel=1e-12)
    assert deck.E / deck.rho == pytest.approx(210e9 / 7850.0, rel=1e-12)
    ea = hull_axial_stiffness(p)
    assert ea == pytest.approx(210e9 * p.framing_factor * (p.beam * (p.deck_thickness + p.bottom_thickness)
                                                           + 2 * (p.depth - 2 * p.wall) * p.side_thickness), rel=1e-12)


def test_cargo_on_the_saddles_and_dock_facing_the_bow(built, msh_groups):
    p, barge, cargo, dock = built
    b_refs = {pt.name: pt.ref_point for pt in barge.patches}
    for pt in cargo.patches:
        np.testing.assert_allclose(pt.ref_point, b_refs[pt.name], atol=1e-12)
        nodes = msh_groups(cargo)[(2, pt.name)]["nodes"]
        assert nodes[:, 2].min() == pytest.approx(pt.ref_point[2], abs=0.02)     # the tank's bottom (faceted)
    fend = [pt.ref_point for pt in dock.patches]
    np.testing.assert_allclose(fend, list(p.bow_points().values()), atol=1e-12)
    d = DockParams()
    assert len(dock.clamped) == d.pile_grid[0] * d.pile_grid[1]
    for name in dock.clamped:
        z = msh_groups(dock)[(2, name)]["nodes"][:, 2]
        assert np.abs(z - d.seabed_z).max() < 1e-9
    mass = cargo.volumes["cargo_wall"].rho * cargo.group_volumes["cargo_wall"]
    assert mass == pytest.approx(CargoParams().dry_mass, rel=1e-12)


@pytest.mark.parametrize("cls, kw, msg", [
    (BargeParams, {"wall": 2.0}, "wall"),
    (BargeParams, {"fender_yz": ((0.0, 4.4),)}, "fender_yz"),
    (BargeParams, {"saddle_x": (39.5,)}, "saddle_x"),
    (BargeParams, {"station_y": 1.0}, "station_y"),
    (BargeParams, {"n_bulkheads": 2.5}, "n_bulkheads"),
    (BargeParams, {"beam": -1.0}, "beam"),
    (CargoParams, {"wall": 2.0}, "wall"),
    (CargoParams, {"saddle_x": (19.5,)}, "saddle_x"),
    (DockParams, {"pile_wall": 2.0}, "pile_wall"),
    (DockParams, {"seabed_z": 0.0}, "seabed_z"),
    (DockParams, {"fender_yz": ((20.0, 2.0),)}, "fender_yz"),
    (DockParams, {"pile_grid": (0, 3)}, "pile_grid"),
])
def test_bad_parameters(cls, kw, msg):
    with pytest.raises(InputError, match=msg):
        cls(**kw).check()
