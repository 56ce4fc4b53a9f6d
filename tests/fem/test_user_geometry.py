"""A component from the user's own geometry file (meshes/user_geometry.py, ``type =
"geometry"``) against the parametric builder of the same shape.

Reference: the barge scenario's cargo tank, built by meshes.barge.build_cargo (defaults:
a closed 40 m x R 4.2 m cylinder, 0.3 m wall, two 1.6 m saddle patches), and the same
shape written by hand as a gmsh ``.geo`` (tests/data/geometry/cargo.geo), then exported
by gmsh as a STEP file and read back with its groups made from boxes. The three give the
same mass, c.g. and first five fixed-interface frequencies (Craig-Bampton, both saddle
points held). Tolerances: the .geo repeats the builder's OpenCASCADE operations, so its
mesh is the builder's (same nodes) and the figures agree to round-off (1e-9); the STEP
copy is re-imported and re-meshed, its surface triangulation may differ by a facet, and
at mesh size 1.6 m on a 4.2 m radius the faceting changes volume (mass) by ~0.1 %: the
mass and c.g. within 0.5 % (of the mass, of the length), the frequencies within 1 %.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from liftoff.core.errors import InputError
from liftoff.core.records import file_sha256

GEO = Path(__file__).resolve().parents[1] / "data" / "geometry" / "cargo.geo"
H = 1.6
SADDLES = {"cargo_1": [-12.0, 0.0, 6.0], "cargo_2": [12.0, 0.0, 6.0]}
# STEP files carry no physical groups: the wall is everything, each patch the wall's outer
# face under its saddle (the thin box keeps out the faces the saddle cut inside the wall)
STEP_GROUPS = {"wall": {"dim": 3, "box": [-21.0, -5.0, 5.0, 21.0, 5.0, 15.0]},
               "saddle_1": {"dim": 2, "box": [-12.801, -0.801, 5.9, -11.199, 0.801, 6.1]},
               "saddle_2": {"dim": 2, "box": [11.199, -0.801, 5.9, 12.801, 0.801, 6.1]}}


def _params(file, material, wall="cargo_wall", points=None, groups=None, **kw):
    from liftoff.meshes.user_geometry import GeometryFileParams

    points = points or {n: {"group": n, "at": xyz, "tie": "rigid"} for n, xyz in SADDLES.items()}
    return GeometryFileParams("cargo", str(file), file_sha256(file), H, {wall: material}, {}, points,
                              groups=groups or {}, origin="s.toml: model.component.cargo.params", **kw)


def _figures(geo):
    from liftoff.core.labels import named_points, points_labels
    from liftoff.fem import build_model
    from liftoff.reduction import Component, craig_bampton
    from liftoff.reduction.checks import cb_check

    c = Component(name="cargo", **build_model(geo, 2).component_fields())
    cb = craig_bampton(c, points_labels(named_points(c.points)), 5, None)
    mp = cb_check(cb, ref_point=[0.0, 0.0, 0.0]).summary["mass_properties_cb"]
    return mp["mass"], np.array(mp["cg"]), cb.fixed_freq_hz[:5]


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    from liftoff.meshes.barge import CargoParams, build_cargo

    geo = build_cargo(CargoParams(mesh_size=H), tmp_path_factory.mktemp("builder"))
    return geo, _figures(geo)


def test_geo_file_gives_the_builders_component(reference, tmp_path):
    from liftoff.meshes.spec import Material
    from liftoff.meshes.user_geometry import build_user_geometry

    ref_geo, (m0, cg0, f0) = reference
    mat = ref_geo.volumes["cargo_wall"]
    geo = build_user_geometry(_params(GEO, Material("wall", mat.E, mat.nu, mat.rho)), tmp_path)
    assert geo.mesh_nodes == ref_geo.mesh_nodes
    m, cg, f = _figures(geo)
    assert m == pytest.approx(m0, rel=1e-9)
    assert np.allclose(cg, cg0, atol=1e-9 * 40.0)
    assert np.allclose(f, f0, rtol=1e-9)


def test_step_file_gives_the_builders_component(reference, tmp_path):
    """The .geo exported to STEP as CAD writes it (millimetres, declared) and read back in
    metres: mass and centre within 5e-3, the five lowest frequencies within 2e-2. The STEP
    route meshes its own tetrahedra (1117 nodes against the .geo's 1121 at this coarse
    mesh_size): the differences are those of two P1 meshes, 0.9 % and 1.4 % on the first
    frequency over two machines' meshers, not of the units (a unit error is 1e3 in length)."""
    import gmsh

    from liftoff.meshes.spec import Material
    from liftoff.meshes.user_geometry import build_user_geometry

    step = tmp_path / "cargo.step"
    gmsh.initialize([], False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.option.setString("Geometry.OCCTargetUnit", "M")   # the model in m, the file in mm as CAD writes it
        gmsh.open(str(GEO))
        gmsh.write(str(step))
    finally:
        gmsh.finalize()
    ref_geo, (m0, cg0, f0) = reference
    mat = ref_geo.volumes["cargo_wall"]
    points = {"cargo_1": {"group": "saddle_1", "at": SADDLES["cargo_1"], "tie": "rigid"},
              "cargo_2": {"group": "saddle_2", "at": SADDLES["cargo_2"], "tie": "rigid"}}
    (tmp_path / "out").mkdir()
    geo = build_user_geometry(_params(step, Material("wall", mat.E, mat.nu, mat.rho), "wall", points, STEP_GROUPS),
                              tmp_path / "out")
    m, cg, f = _figures(geo)
    assert m == pytest.approx(m0, rel=5e-3)
    assert np.allclose(cg, cg0, atol=5e-3 * 40.0)
    assert np.allclose(f, f0, rtol=2e-2), (f, f0)


@pytest.mark.parametrize("change, expect", [
    ({"wall": "cargo_skin"}, "cargo.geo: no volume group 'cargo_skin', named in s.toml: "
                             "model.component.cargo.params.solids.cargo_skin (the file's volume groups: cargo_wall)"),
    ({"points": {"cargo_1": {"group": "saddle_left", "at": None, "tie": "rigid"}}},
     "cargo.geo: no curve or surface group 'saddle_left', named in s.toml: "
     "model.component.cargo.params.points.cargo_1.group"),
    ({"points": {"cargo_1": {"group": "cargo_wall", "at": None, "tie": "rigid"}}},
     "cargo.geo: no curve or surface group 'cargo_wall' (it is a volume group)"),
])
def test_a_missing_group_or_role_is_one_line_naming_file_group_and_key(tmp_path, change, expect):
    from liftoff.meshes.spec import Material
    from liftoff.meshes.user_geometry import build_user_geometry

    p = _params(GEO, Material("wall", 1e9, 0.3, 1000.0), **{k: v for k, v in change.items() if k == "wall"},
                **({"points": change["points"]} if "points" in change else {}))
    with pytest.raises(InputError) as exc:
        build_user_geometry(p, tmp_path)
    assert "\n" not in str(exc.value) and expect in str(exc.value), str(exc.value)


def test_a_volume_group_without_a_role_is_refused(tmp_path):
    from liftoff.meshes.spec import Material
    from liftoff.meshes.user_geometry import build_user_geometry

    geo = tmp_path / "two.geo"
    geo.write_text(GEO.read_text() + 'Box(10) = {30, 0, 0, 1, 1, 1};\nPhysical Volume("ballast") = {10};\n')
    with pytest.raises(InputError, match=r"two\.geo: volume group 'ballast' has no role: give it a material in "
                                         r"s\.toml: model\.component\.cargo\.params\.solids\.ballast"):
        build_user_geometry(_params(geo, Material("wall", 1e9, 0.3, 1000.0)), tmp_path)


def _two_boxes_step(path, unit: str):
    """A STEP file of two boxes, 2 x 1 x 1 and 1 x 1 x 1 side by side along x, written by gmsh
    with Geometry.OCCTargetUnit = ``unit`` (its numbers' unit; gmsh declares mm)."""
    import gmsh

    gmsh.initialize([], False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.option.setString("Geometry.OCCTargetUnit", unit)
        gmsh.model.occ.addBox(0, 0, 0, 2, 1, 1)
        gmsh.model.occ.addBox(2, 0, 0, 1, 1, 1)
        gmsh.model.occ.synchronize()
        gmsh.write(str(path))
    finally:
        gmsh.finalize()
    return path


@pytest.mark.parametrize("declared", ["SI_UNIT($,.METRE.)", "SI_UNIT(.MILLI.,.METRE.)"])
def test_a_step_file_is_read_in_the_unit_it_declares(tmp_path, declared):
    """Two boxes (2 x 1 x 1 and 1 x 1 x 1) written with the numbers 0..3 and the length unit
    declared as metres or millimetres. Declared in metres: 3 m^3 (OpenCASCADE's default had
    converted it to millimetres, 1e9 times the volume; a review, 2026-12-07). Declared in mm
    (as gmsh writes metre numbers unless told otherwise): 3 mm across, refused as a unit error
    rather than read 1000 times small (meshes.user_geometry.SMALLEST_CAD, 1 cm). Measured on
    the mesh of the group (exact for boxes: 1e-9)."""
    from liftoff.meshes.spec import Material
    from liftoff.meshes.user_geometry import GeometryFileParams, build_user_geometry

    raw = _two_boxes_step(tmp_path / "raw.step", "MM")     # the numbers as given, declared mm
    text = raw.read_text()
    assert "SI_UNIT(.MILLI.,.METRE.)" in text
    step = tmp_path / "boxes.step"
    step.write_text(text.replace("SI_UNIT(.MILLI.,.METRE.)", declared))
    big = 1e4
    p = GeometryFileParams("boxes", str(step), file_sha256(step), 0.5, {"v": Material("al", 7e10, 0.3, 2700.0)},
                           groups={"v": {"dim": 3, "box": [-big, -big, -big, big, big, big]}}, origin="s.toml: boxes")
    (tmp_path / "out").mkdir()
    if "MILLI" in declared:
        with pytest.raises(InputError, match=r"boxes.step: the geometry spans 0.003 m, in metres read from the unit"):
            build_user_geometry(p, tmp_path / "out")
        return
    geo = build_user_geometry(p, tmp_path / "out")
    assert geo.group_volumes["v"] == pytest.approx(3.0, rel=1e-9)


def test_a_solid_in_no_group_is_refused_not_left_out(tmp_path):
    """gmsh writes only the elements of physical groups: a STEP solid outside every group box
    was left out of the model without a word (its mass with it). Refused, naming the volume
    and where it is."""
    from liftoff.meshes.spec import Material
    from liftoff.meshes.user_geometry import GeometryFileParams, build_user_geometry

    step = _two_boxes_step(tmp_path / "boxes.step", "M")
    p = GeometryFileParams("boxes", str(step), file_sha256(step), 0.5, {"v": Material("al", 7e10, 0.3, 2700.0)},
                           groups={"v": {"dim": 3, "box": [-0.1, -0.1, -0.1, 2.1, 1.1, 1.1]}}, origin="s.toml: boxes")
    (tmp_path / "out").mkdir()
    with pytest.raises(InputError, match=r"boxes.step: volume \d+ \(bounding box \[2, .*3, 1, 1\] m\) is in no "
                                         r"volume group with a role, so it would be left out of the model") as exc:
        build_user_geometry(p, tmp_path / "out")
    assert "\n" not in str(exc.value)


def test_a_geo_file_is_keyed_with_the_files_it_merges(tmp_path):
    """The stage key of a .geo covers the files its Merge / Include statements read: editing
    a merged file changes it (a mesh built from the old one was reused). A .geo reading no
    file keeps its own hash; a path that is not a plain string, or a missing file, is said."""
    from liftoff.core.records import file_sha256, geometry_sha256

    (tmp_path / "dims.geo").write_text("L = 2;\n")
    top = tmp_path / "part.geo"
    top.write_text('// Include "old.geo";\nInclude "dims.geo";\nPoint(1) = {0, 0, 0};\n')
    first = geometry_sha256(top)
    assert first != file_sha256(top)
    (tmp_path / "dims.geo").write_text("L = 3;\n")
    assert geometry_sha256(top) != first
    alone = tmp_path / "alone.geo"
    alone.write_text("Point(1) = {0, 0, 0};\n")
    assert geometry_sha256(alone) == file_sha256(alone)
    (tmp_path / "dyn.geo").write_text('Merge StrCat("a", ".step");\n')
    with pytest.raises(ValueError, match="not a plain"):
        geometry_sha256(tmp_path / "dyn.geo")
    (tmp_path / "gone.geo").write_text('Merge "missing.step";\n')
    with pytest.raises(ValueError, match="names a file that does not exist"):
        geometry_sha256(tmp_path / "gone.geo")
    # a keyword inside a string is not a statement; // inside a quoted path is not a comment;
    # MergeWithBoundingBox reads a file too
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "part.step").write_text("one")
    odd = tmp_path / "odd.geo"
    odd.write_text('Printf("Include %g", 1);\nMergeWithBoundingBox "sub//part.step"; // Merge "x";\n')
    first = geometry_sha256(odd)
    (tmp_path / "sub" / "part.step").write_text("two")
    assert geometry_sha256(odd) != first


@pytest.mark.parametrize("version", [2.2, 4.1])
def test_a_msh_file_of_either_version_with_a_surface_group_builds(tmp_path, version):
    """An MSH 2 file has no topology (gmsh gives its volumes no boundary): a grouped surface
    (here a point's tie patch) is not refused as left out (a review of the check's first
    version, which refused MSH 2.2 files that built before)."""
    import gmsh

    from liftoff.meshes.spec import Material
    from liftoff.meshes.user_geometry import GeometryFileParams, build_user_geometry

    path = tmp_path / f"b{version}.msh"
    gmsh.initialize([], False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("b")
        gmsh.model.occ.addBox(0, 0, 0, 1, 1, 1)
        gmsh.model.occ.synchronize()
        gmsh.model.setPhysicalName(3, gmsh.model.addPhysicalGroup(3, [1]), "body")
        gmsh.model.setPhysicalName(2, gmsh.model.addPhysicalGroup(2, [6]), "top")
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.5)
        gmsh.model.mesh.generate(3)
        gmsh.option.setNumber("Mesh.MshFileVersion", version)
        gmsh.write(str(path))
    finally:
        gmsh.finalize()
    p = GeometryFileParams("b", str(path), file_sha256(path), None, {"body": Material("al", 7e10, 0.3, 2700.0)},
                           points={"top": {"group": "top", "at": None, "tie": "rigid"}}, origin="s.toml: b")
    (tmp_path / "out").mkdir()
    geo = build_user_geometry(p, tmp_path / "out")
    assert geo.group_volumes["body"] == pytest.approx(1.0, rel=1e-9)


def test_a_surface_embedded_in_a_solid_is_not_refused(tmp_path):
    """A .geo surface embedded in a volume (Surface In Volume) is not on its boundary, and
    needs no group: its triangles are faces of the solid's tetrahedra."""
    from liftoff.meshes.spec import Material
    from liftoff.meshes.user_geometry import GeometryFileParams, build_user_geometry

    geo_file = tmp_path / "emb.geo"
    geo_file.write_text('SetFactory("OpenCASCADE");\nBox(1) = {0, 0, 0, 1, 1, 1};\n'
                        'Rectangle(7) = {0.2, 0.2, 0.5, 0.6, 0.6};\nSurface{7} In Volume{1};\n'
                        'Physical Volume("body") = {1};\n')
    p = GeometryFileParams("emb", str(geo_file), file_sha256(geo_file), 0.25,
                           {"body": Material("al", 7e10, 0.3, 2700.0)}, origin="s.toml: emb")
    (tmp_path / "out").mkdir()
    geo = build_user_geometry(p, tmp_path / "out")
    assert geo.group_volumes["body"] == pytest.approx(1.0, rel=1e-9)
