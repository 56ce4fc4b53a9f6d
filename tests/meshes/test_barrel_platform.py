"""The parametric barrel (meshes/barrel.py) and platform (meshes/platform.py) against closed
forms: the frustum's lateral area pi (r1 + r2) sqrt(h^2 + (r2 - r1)^2) and the mass it is
given, the joint points on their rings, the platform's posts where asked and its mass."""
from __future__ import annotations

import math

import numpy as np
import pytest

from liftoff.core.errors import InputError

pytest.importorskip("gmsh")


def _mesh_area(path: str, group: str) -> float:
    import gmsh

    gmsh.initialize([], False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.open(path)
        tag = next(t for d, t in gmsh.model.getPhysicalGroups(2) if gmsh.model.getPhysicalName(2, t) == group)
        area = 0.0
        for ent in gmsh.model.getEntitiesForPhysicalGroup(2, tag):
            for et, nodes in zip(*gmsh.model.mesh.getElements(2, ent)[::2]):
                for tri in np.asarray(nodes).reshape(-1, 3):
                    p = np.array([gmsh.model.mesh.getNode(int(n))[0] for n in tri])
                    area += 0.5 * np.linalg.norm(np.cross(p[1] - p[0], p[2] - p[0]))
        return area
    finally:
        gmsh.finalize()


def test_conical_barrel_area_mass_and_joints(tmp_path):
    from liftoff.meshes.barrel import BarrelParams, build_barrel

    p = BarrelParams("is2", 5.03, 3.3, 59.4, 65.285, 0.02, mass=3600.0, mesh_size=0.5,
                     joints_bottom={f"lo_{k}": 45.0 + 90 * k for k in range(4)},
                     joints_top={f"up_{k}": 45.0 + 90 * k for k in range(4)})
    geo = build_barrel(p, tmp_path)
    area = math.pi * (5.03 + 3.3) * math.hypot(65.285 - 59.4, 5.03 - 3.3)
    assert p.wall_area() == pytest.approx(area, rel=1e-12)
    # the meshed (faceted) area: 0.5 m triangles on radii of 3.3-5.0 m, chord sag ~ h^2 / (8 r) ~ 0.5 %
    assert _mesh_area(geo.msh_path, "is2_wall") == pytest.approx(area, rel=1e-2)
    assert geo.nominal_mass() == pytest.approx(3600.0, rel=1e-12)      # density set from the mass
    ref = {q.name: q.ref_point for q in geo.patches}
    assert np.allclose(ref["lo_0"], [5.03 * math.cos(math.pi / 4), 5.03 * math.sin(math.pi / 4), 59.4])
    assert np.allclose(ref["up_2"], [-3.3 * math.cos(math.pi / 4), -3.3 * math.sin(math.pi / 4), 65.285])


def _arc_span(path: str, group: str) -> tuple[float, float, float]:
    """(lowest azimuth, highest azimuth (deg, -180..180), length (m)) of a curve group's mesh."""
    import gmsh

    gmsh.initialize([], False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.open(path)
        tag = next(t for d, t in gmsh.model.getPhysicalGroups(1) if gmsh.model.getPhysicalName(1, t) == group)
        az, length = [], 0.0
        for ent in gmsh.model.getEntitiesForPhysicalGroup(1, tag):
            _, xyz, _ = gmsh.model.mesh.getNodes(1, ent, includeBoundary=True)
            xyz = np.asarray(xyz).reshape(-1, 3)
            az += [math.degrees(math.atan2(y, x)) for x, y, _ in xyz]
            for et, nodes in zip(*gmsh.model.mesh.getElements(1, ent)[::2]):
                for seg in np.asarray(nodes).reshape(-1, 2):
                    a, b = (np.array(gmsh.model.mesh.getNode(int(n))[0]) for n in seg)
                    length += float(np.linalg.norm(b - a))
        return min(az), max(az), length
    finally:
        gmsh.finalize()


@pytest.mark.parametrize("bottom, top", [({"bp": 0.0}, {"jt": 10.0}), ({"a": 0.0}, {"jt": 10.0})])
def test_a_joint_arc_split_by_the_other_ends_breaks_is_tied_whole(tmp_path, bottom, top):
    """Both rings are split at both ends' break azimuths: a joint at 10 deg (+-15) meets the
    other end's breaks at 0 deg (an axis-tied ring's quarters) or at -15 and 15 deg (a joint at
    0), and only the piece whose middle lay within half the arc of the joint was tied (25 of
    its 30 deg; a review, 2026-12-07). Every piece inside +-arc_deg is: -5 to 25 deg, a
    length of r pi/6 within the chords' shortfall ((h/r)^2/24 = 2.0e-3 for h = 0.4 m on r = 1.83 m)."""
    from liftoff.meshes.barrel import BarrelParams, build_barrel

    axis = "bp" in bottom
    p = BarrelParams("b", z_top=2.0, mesh_size=0.4, joints_top=top,
                     **({"bottom_point": bottom} if axis else {"joints_bottom": bottom}))
    geo = build_barrel(p, tmp_path)
    lo, hi, length = _arc_span(geo.msh_path, "jt")
    assert lo == pytest.approx(-5.0, abs=1e-6) and hi == pytest.approx(25.0, abs=1e-6)
    assert length == pytest.approx(1.83 * math.pi / 6, rel=3e-3)
    if not axis:
        lo, hi, _ = _arc_span(geo.msh_path, "a")
        assert lo == pytest.approx(-15.0, abs=1e-6) and hi == pytest.approx(15.0, abs=1e-6)


def test_barrel_axis_point_carries_its_mass(tmp_path):
    from liftoff.meshes.barrel import BarrelParams, build_barrel

    p = BarrelParams("sc", 3.3, 1.95, 75.5, 87.3, 0.02, mass=3800.0, mesh_size=0.8,
                     joints_bottom={f"sc_{k}": 45.0 + 90 * k for k in range(4)}, top_point={"cg": 90.0},
                     point_masses={"cg": [45000.0, 4.18e5, 4.18e5, 8.6e4]})
    geo = build_barrel(p, tmp_path)
    assert geo.nominal_mass() == pytest.approx(3800.0 + 45000.0, rel=1e-12)
    assert np.allclose(geo.patch("cg").ref_point, [0.0, 0.0, 90.0])


@pytest.mark.parametrize("change, expect", [
    ({"z_top": 0.0}, "z_top 0.0 m must be above z_bottom"),
    ({"joints_bottom": {"a": 0.0, "b": 20.0}}, r"joint arcs of \+-15\.0 deg overlap"),
    ({"point_masses": {"x": [1.0, 0, 0, 0]}}, "'x' is not one of its points"),
])
def test_barrel_bad_parameters_are_one_line(change, expect):
    from liftoff.meshes.barrel import BarrelParams

    with pytest.raises(InputError, match=expect):
        BarrelParams(**{"joints_bottom": {"a": 0.0}, **change}).check()


def test_platform_posts_mass_and_clamps(tmp_path):
    from liftoff.meshes.pad import STEEL
    from liftoff.meshes.platform import PlatformParams, build_platform

    posts = {f"arm_{k}": (3.5, 3.5 * (-1) ** k, 6.3) for k in range(2)}
    p = PlatformParams("ml", deck_size=(30.0, 30.0), deck_thickness=6.0, deck_top_z=0.0, posts=posts,
                       holes=((0.0, 0.0, 2.0),), square_holes=((-8.0, 0.0, 1.5),),
                       pedestals=((-10.0, -10.0), (10.0, 10.0), (-10.0, 10.0)), mass=2.0e6, mesh_size=3.0)
    geo = build_platform(p, tmp_path)
    for n, xyz in posts.items():
        assert np.allclose(geo.patch(n).ref_point, xyz)
    # deck and posts weigh `mass` (the deck's density set from it), over the CAD volumes
    vols = geo.group_volumes
    deck_posts = geo.volumes["ml_deck"].rho * vols["ml_deck"] + STEEL.rho * vols["ml_posts"]
    assert deck_posts == pytest.approx(2.0e6, rel=1e-9)
    assert vols["ml_posts"] == pytest.approx(2 * 1.0 * 1.0 * 6.3, rel=1e-9)
    assert vols["ml_deck"] == pytest.approx(30 * 30 * 6.0 - (math.pi * 2.0 ** 2 + 3.0 ** 2) * 6.0, rel=1e-6)
    assert len(geo.clamped) == 3


def test_platform_post_off_the_deck_is_one_line():
    from liftoff.meshes.platform import PlatformParams

    with pytest.raises(InputError, match=r"PlatformParams\(pad\)\.posts\.far: the post at \(50.0, 0.0\) is off the deck"):
        PlatformParams(posts={"far": (50.0, 0.0, 3.0)}).check()
    with pytest.raises(InputError, match=r"PlatformParams\(pad\)\.square_holes\[0\]: the exhaust hole undercuts the post 'p'"):
        PlatformParams(posts={"p": (2.0, 0.0, 3.0)}, square_holes=((0.0, 0.0, 1.6),)).check()


def test_the_launch_table_is_a_platform_placed_by_the_layout():
    """meshes.pad.build_pad builds PadParams.platform(): posts at the layout's hold-down
    points (their tops at z = 0), the boosters' round exhaust holes and the orbiter's square
    one, the deck top at -post_height; its closed-form volumes (pad_closed_form_volumes) are
    the platform's."""
    from liftoff.meshes.pad import PadParams, pad_closed_form_volumes

    pad = PadParams()
    p = pad.platform()
    p.check()
    assert p.name == "pad" and p.deck_top_z == -pad.post_height and len(p.posts) == 8
    assert all(xyz[2] == 0.0 for xyz in p.posts.values()) and len(p.holes) == 2 and len(p.square_holes) == 1
    lo, hi = p.deck_bounds()
    deck = float(np.prod(hi - lo) - sum(math.pi * r ** 2 for *_, r in p.holes) * p.deck_thickness
                 - sum((2 * a) ** 2 for *_, a in p.square_holes) * p.deck_thickness)
    assert deck == pytest.approx(pad_closed_form_volumes(pad)["pad_deck"], rel=1e-12)


def test_girder_segment_against_a_square_hole_exactly():
    """meshes.platform._segment_enters_square (interval clipping) against dense sampling
    (20,001 points per segment) on 1,000 random segments and squares (a third of them
    axis-aligned, as the girders are), leaving out the grazes closer than the sampling's
    spacing; and the grazes sampling misses: a segment 1e-6 inside an edge enters, one
    along the edge or leaving from a corner does not (the hole is open)."""
    from liftoff.meshes.platform import _segment_enters_square

    rng = np.random.default_rng(7)
    s = np.linspace(0.0, 1.0, 20_001)
    checked = 0
    for _ in range(1000):
        a, b = rng.uniform(-2, 2, 2), rng.uniform(-2, 2, 2)
        if rng.random() < 0.3:                         # axis-aligned, as the girders are
            k = rng.integers(2)
            b[k] = a[k]
        c, h = rng.uniform(-1, 1, 2), rng.uniform(0.1, 1.0)
        pts = a + s[:, None] * (b - a)
        depth = np.minimum(h - np.abs(pts[:, 0] - c[0]), h - np.abs(pts[:, 1] - c[1]))   # > 0 inside
        if abs(depth.max()) < 4e-4 * (1 + np.hypot(*(b - a))):
            continue                                   # a graze finer than the sampling
        assert _segment_enters_square(a, b - a, c, h) == (depth.max() > 0), (a, b, c, h)
        checked += 1
    assert checked > 950
    d = np.array([2.0, 0.0])
    assert _segment_enters_square(np.array([-1.0, 1.0 - 1e-6]), d, (0.0, 0.0), 1.0)      # corner strip, inside
    assert not _segment_enters_square(np.array([-1.0, 1.0]), d, (0.0, 0.0), 1.0)          # along the edge
    assert not _segment_enters_square(np.array([1.0, 1.0]), np.array([1.0, 1.0]), (0.0, 0.0), 1.0)  # from a corner out
    assert _segment_enters_square(np.array([-5.0, 0.0]), np.array([10.0, 0.0]), (0.0, 0.0), 1.0)   # straight through
