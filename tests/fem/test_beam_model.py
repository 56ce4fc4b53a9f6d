"""Beams in FE models (fem.beam, issue 26): 3-D Timoshenko beams on gmsh line groups,
alone or welded to shells, through fem.build_model.

References: the slope-deflection solution of a fixed-base portal frame (hand method,
independent of the element code); the Timoshenko cantilever's closed form at slenderness
1e3 and 2 (no shear locking, shear deformation kept); rigid-body mass and inertia of an
offset ring, integrated exactly; and a ring-stiffened cylinder whose frames are modelled
a second way, as shell webs.
"""
import numpy as np
import pytest
import scipy.sparse.linalg as sla

from liftoff.core.beam import Section, rectangle, tube
from liftoff.core.errors import InputError
from liftoff.fem import build_model, eigenmodes, mass_properties, write_vtu
from liftoff.meshes.spec import BeamGroup, Geometry, Material

from .gmsh_cases import gmsh_file

pytestmark = pytest.mark.fem
STEEL = Material("steel", 210e9, 0.3, 7850.0)


def _polyline(path, points, groups, h, point_groups=None):
    """Straight lines between ``points``; ``groups``: name -> line indices (line k joins
    points k and k+1); ``point_groups``: name -> point indices."""
    import gmsh

    with gmsh_file("lines", path, dim=1, h=h):
        occ = gmsh.model.occ
        p = [occ.addPoint(*x) for x in points]
        lines = [occ.addLine(p[k], p[k + 1]) for k in range(len(p) - 1)]
        occ.synchronize()
        for name, idx in groups.items():
            gmsh.model.setPhysicalName(1, gmsh.model.addPhysicalGroup(1, [lines[k] for k in idx]), name)
        for name, idx in (point_groups or {}).items():
            gmsh.model.setPhysicalName(0, gmsh.model.addPhysicalGroup(0, [p[k] for k in idx]), name)
    return str(path)


def _static_tip(model, xyz, force):
    K, _ = model.matrices()
    f = np.zeros(model.n_dof)
    d = model.node_dofs(xyz)
    f[d] = force
    u = sla.spsolve(K.tocsc(), f)
    return u[d]


@pytest.mark.parametrize("k", [0.5, 2.0])
def test_portal_frame_against_slope_deflection(tmp_path, k):
    """Fixed-base portal (columns h = 4 m, girder L = 6 m), lateral load P at the girder.
    Slope-deflection (axially rigid members; antisymmetric joint rotations theta):
    joint (2EIc/h)((2 + 3k) theta - 3 psi) = 0, storey shear (4EIc/h^2)(6 psi - 3 theta) = P,
    k = (Ib/L)/(Ic/h), hence the sway Delta = P h^3 (2 + 3k) / (12 E Ic (1 + 6k)) (limits:
    two cantilevers P h^3/(6EI) at k = 0, guided columns P h^3/(24 EI) as k -> inf).
    Euler-Bernoulli sections with A = 100 m^2: the axial flexibility the hand method drops
    is I L/(A h^3) ~ 1e-7 of the sway; with the element exact for end loads the rest is
    round-off (1e-5 asked)."""
    H, L, Ic, P = 4.0, 6.0, 1e-4, 1000.0
    msh = _polyline(tmp_path / "portal.msh", [(0, 0, 0), (0, 0, H), (L, 0, H), (L, 0, 0)],
                    {"columns": [0, 2], "girder": [1]}, h=1.0, point_groups={"feet": [0, 3]})
    Ib = k * Ic * L / H
    geo = Geometry("portal", msh, {}, clamped=["feet"],
                   beams={"columns": BeamGroup(STEEL, Section(100.0, Ic, Ic, 2 * Ic), vref=(0, 1, 0)),
                          "girder": BeamGroup(STEEL, Section(100.0, Ib, Ib, 2 * Ib), vref=(0, 1, 0))})
    model = build_model(geo)
    assert model.cell_type == "line"
    sway = _static_tip(model, (0, 0, H), (P, 0, 0))[0]
    want = P * H ** 3 * (2 + 3 * k) / (12 * STEEL.E * Ic * (1 + 6 * k))
    print(f"portal k = {k}: sway {sway:.6e} m, slope-deflection {want:.6e} m")
    assert sway == pytest.approx(want, rel=1e-5)


@pytest.mark.parametrize("slenderness", [1e3, 2.0])
def test_timoshenko_cantilever_no_shear_locking(tmp_path, slenderness):
    """A tube cantilever (r = 0.1 m, t = 0.01 m) of length slenderness * r, tip load P, 8
    elements: delta = P L^3/(3 E I) + P L/(k G A) (Timoshenko; Cowper's k, liftoff.core.beam),
    exact for the element at any slenderness: no shear locking at L/r = 1e3, and the shear
    term (half the deflection at L/r = 2) kept. Tolerance 1e-6: round-off of a chain of
    8 elements (condition ~ (L/r)^2)."""
    r, t, P = 0.1, 0.01, 1e3
    L = slenderness * r
    msh = _polyline(tmp_path / "cantilever.msh", [(0, 0, 0), (L, 0, 0)], {"tube": [0]}, h=L / 8,
                    point_groups={"root": [0]})
    sec = tube(r, t, STEEL.nu)
    model = build_model(Geometry("cantilever", msh, {}, clamped=["root"],
                                 beams={"tube": BeamGroup(STEEL, sec, vref=(0, 0, 1))}))
    G = STEEL.E / (2 * (1 + STEEL.nu))
    want = P * L ** 3 / (3 * STEEL.E * sec.Iy) + P * L / (G * sec.Az)
    tip = _static_tip(model, (L, 0, 0), (0, 0, P))[2]
    print(f"L/r = {slenderness:g}: tip {tip:.6e} m, Timoshenko {want:.6e} m, shear share "
          f"{P * L / (G * sec.Az) / want:.3g}")
    assert tip == pytest.approx(want, rel=1e-6)


def _ring(path, R, n_around):
    import gmsh

    with gmsh_file("ring", path, dim=1):
        c = gmsh.model.occ.addCircle(0, 0, 0, R)
        gmsh.model.occ.synchronize()
        gmsh.model.setPhysicalName(1, gmsh.model.addPhysicalGroup(1, [c]), "ring")
        gmsh.model.mesh.setTransfiniteCurve(c, n_around + 1)
    return str(path)


def test_offset_ring_rigid_modes_mass_and_inertia(tmp_path):
    """A free ring frame of 24 straight elements whose axis is offset 0.05 m inward of its
    nodes (radial_offset): six rigid-body modes with zero strain energy (the offset's rigid
    link preserves rigid motions), mass rho A (sum of the offset chords' lengths) and
    inertia about the axis rho A sum L (|a|^2 + a.(b - a) + |b - a|^2/3) (a, b: the offset
    ends; exact for the consistent mass, which reproduces linear velocity fields), without
    rotary inertia. Tolerance 1e-12 relative (arithmetic)."""
    R, e, n = 1.0, -0.05, 24
    sec = rectangle(0.01, 0.1)
    model = build_model(Geometry("ring", _ring(tmp_path / "ring.msh", R, n), {},
                                 beams={"ring": BeamGroup(STEEL, sec, radial_offset=e, rotary=False)}))
    K, _ = model.matrices()
    RB = model.rigid_body_shape()
    assert np.abs(K @ RB).max() <= 1e-9 * abs(K).max()
    a = (R + e) * np.column_stack([np.cos(2 * np.pi * np.arange(n) / n), np.sin(2 * np.pi * np.arange(n) / n)])
    a, b = a, np.roll(a, -1, axis=0)
    Ls = np.linalg.norm(b - a, axis=1)
    mp = mass_properties(model)
    assert mp.mass == pytest.approx(STEEL.rho * sec.A * Ls.sum(), rel=1e-12)
    Izz = STEEL.rho * sec.A * np.sum(Ls * (np.sum(a * a, 1) + np.sum(a * (b - a), 1) + np.sum((b - a) ** 2, 1) / 3))
    assert mp.inertia[2, 2] == pytest.approx(Izz, rel=1e-12)
    modes = eigenmodes(model, n_modes=8)
    assert modes.n_rigid == 6 and modes.freq_hz[6] > 1.0
    out = write_vtu(tmp_path / "ring.vtu", model.nodes, model.cells, model.cell_type,
                    {"mode_7": model.nodal_displacement(modes.shapes[:, 6])})
    assert out.stat().st_size > 0


R, LC, T, D, TW = 1.0, 2.0, 0.004, 0.08, 0.01     # cylinder and frame web (m)


def _stiffened_cylinder(path, webs: bool, h: float = 0.1) -> str:
    """Cylinder R = 1 m, 2 m long, with ring frames at z = 0, 1, 2 m: with ``webs``, each
    frame a flat annular web from R - D to R (shell, sized D/2 so that 2 elements span it),
    fragmented with the skin; else the three circles as the physical curve "frames"."""
    import gmsh

    with gmsh_file("stiffened", path, dim=2, h=h):
        occ = gmsh.model.occ
        e1 = occ.extrude([(1, occ.addCircle(0, 0, 0, R))], 0, 0, 1.0)
        e2 = occ.extrude([(1, [t for d, t in e1 if d == 1][0])], 0, 0, 1.0)
        skin = [(2, t) for d, t in e1 + e2 if d == 2]
        if webs:
            ann = []
            for z in (0.0, 1.0, 2.0):
                ann += occ.cut([(2, occ.addDisk(0, 0, z, R, R))], [(2, occ.addDisk(0, 0, z, R - D, R - D))])[0]
            occ.fragment(skin, ann)
        occ.synchronize()
        flat = {t: gmsh.model.getBoundingBox(2, t) for _, t in gmsh.model.getEntities(2)}
        skin = [t for t, b in flat.items() if b[5] - b[2] > 0.5]
        gmsh.model.setPhysicalName(2, gmsh.model.addPhysicalGroup(2, skin), "skin")
        if webs:
            ann = [t for t in flat if t not in skin]
            gmsh.model.setPhysicalName(2, gmsh.model.addPhysicalGroup(2, ann), "webs")
            f = gmsh.model.mesh.field
            box = f.add("Box")
            f.setNumber(box, "VIn", D / 2)
            f.setNumber(box, "VOut", h)
            for key, v in zip(("XMin", "XMax", "YMin", "YMax", "ZMin", "ZMax"), (-2, 2, -2, 2, -1, 3)):
                f.setNumber(box, key, v)
            only = f.add("Restrict")
            f.setNumber(only, "InField", box)
            f.setNumbers(only, "SurfacesList", ann)
            f.setAsBackgroundMesh(only)
        else:
            circles = [t for _, t in gmsh.model.getEntities(1)
                       if abs(gmsh.model.getBoundingBox(1, t)[3] - R) < 1e-5
                       and gmsh.model.getBoundingBox(1, t)[5] - gmsh.model.getBoundingBox(1, t)[2] < 1e-5]
            assert len(circles) == 3
            gmsh.model.setPhysicalName(1, gmsh.model.addPhysicalGroup(1, circles), "frames")
    return str(path)


def test_ring_stiffened_cylinder_beams_against_shell_webs(tmp_path):
    """Free-free ring-stiffened cylinder (R = 1 m, L = 2 m, t = 4 mm, three frames: flat
    webs 80 x 10 mm): frames as beams (rectangle 10 x 80 mm, axis offset D/2 inside the
    skin's mid-surface, welded through the shared nodes) against the frames as shell webs
    (a second model of the same structure). The eight lowest elastic frequencies (the
    frame-governed ovalling pairs n = 2, 3 and the next) agree within 2.5 %: beam theory
    against a 2-D web; measured -1.1 to -1.5 % at h = 0.1 m, -0.8 to -1.2 % at h = 0.07 m
    (the difference falls with the mesh). Without frames the same modes are 13x lower,
    so the beams' stiffness is what is compared."""
    webs = Geometry("webs", _stiffened_cylinder(tmp_path / "webs.msh", True), {"skin": STEEL, "webs": STEEL},
                    shells={"skin": T, "webs": TW})
    bare_msh = _stiffened_cylinder(tmp_path / "beams.msh", False)
    beams = Geometry("beams", bare_msh, {"skin": STEEL}, shells={"skin": T},
                     beams={"frames": BeamGroup(STEEL, rectangle(TW, D, STEEL.nu), radial_offset=-D / 2)})
    bare = Geometry("bare", bare_msh, {"skin": STEEL}, shells={"skin": T})
    f = {}
    for geo in (webs, beams, bare):
        m = eigenmodes(build_model(geo), n_modes=14)
        assert m.n_rigid == 6
        f[geo.name] = m.freq_hz[6:14]
    print("shell webs:", np.round(f["webs"], 2), "\nbeams:", np.round(f["beams"], 2),
          "\nbeams / webs - 1:", np.round(f["beams"] / f["webs"] - 1, 4), "\nno frames:", np.round(f["bare"], 2))
    assert np.all(np.abs(f["beams"] / f["webs"] - 1) < 0.025)
    assert f["beams"][0] > 10 * f["bare"][0]


def test_beam_geometry_round_trip_and_bad_input(tmp_path):
    msh = _polyline(tmp_path / "bar.msh", [(0, 0, 0), (1, 0, 0)], {"bar": [0]}, h=0.25, point_groups={"end": [0]})
    geo = Geometry("bar", msh, {}, clamped=["end"], curve_lengths={"bar": 1.0},
                   beams={"bar": BeamGroup(STEEL, tube(0.05, 0.005), vref="radial", axis_point=(0, -1, 0),
                                           axis_direction=(1, 0, 0), radial_offset=0.01)})
    back = Geometry.load(geo.save(tmp_path / "bar.json"))
    assert back.beams["bar"].to_dict() == geo.beams["bar"].to_dict()
    assert back.nominal_mass() == pytest.approx(STEEL.rho * tube(0.05, 0.005).A)
    model = build_model(back)
    assert model.n_dof == 6 * (len(model.nodes) - 1)          # the clamped end point removed
    with pytest.raises(InputError, match="beam curve 'spar' is not a physical curve"):
        build_model(Geometry("bar", msh, {}, beams={"spar": BeamGroup(STEEL, tube(0.05, 0.005))}))
    with pytest.raises(InputError, match="lies on the axis"):
        build_model(Geometry("bar", msh, {}, beams={"bar": BeamGroup(STEEL, tube(0.05, 0.005), radial_offset=0.01)}))
    with pytest.raises(InputError, match="vref must be"):
        BeamGroup(STEEL, tube(0.05, 0.005), vref=(0, 0, 0))
    with pytest.raises(InputError, match="shear area Ay must be"):
        BeamGroup(STEEL, {"A": 1.0, "Iy": 1.0, "Iz": 1.0, "J": 1.0, "Ay": -1.0})


def test_tank_ring_frames_from_the_builder(tmp_path):
    """meshes.tank with shell walls and ``frames``: T frames as beams on the wall's inner face
    at the given heights. Checks: the dry mass is kept (wall + frames, exactly, the frames'
    mass at their centroid circles); the beam nodes lie on the wall's mid-surface circles at
    the frame heights; the axis offset is -(t/2 + the T's centroid height); the FE mass is
    the nominal one within the facets' 0.1 %; and the frames hold the thin wall round:
    the lowest elastic frequency of the half-full tank rises more than 2x (measured 2.2 Hz
    bare, 6.4 Hz framed, seven T frames 150 mm deep on a 10 mm wall of 2 m radius)."""
    from liftoff.core.beam import t_section
    from liftoff.meshes.tank import Compartment, TankParams, build_tank

    tee = {"shape": "t", "h": 0.15, "b": 0.06, "tw": 0.004, "tf": 0.006}
    base = dict(name="t", radius=2.0, wall_thickness=0.01, mesh_size=0.4, dry_mass=3000.0, walls="shell",
                compartments=(Compartment(name="lox", cyl_length=8.0, fill_level=0.5),),
                patches={"bottom": (0.0, 0.0, 0.0)})
    z = tuple(2.44 + np.arange(7.0))
    f1 = {}
    for frames in ((), z):
        geo = build_tank(TankParams(**base, frames=frames, frame_section=tee), tmp_path / f"t{len(frames)}")
        model = build_model(geo)
        f1[len(frames)] = eigenmodes(model, n_modes=7).freq_hz[6]
        assert mass_properties(model).mass == pytest.approx(geo.nominal_mass(), rel=1e-3)
    sec, zc = t_section(0.15, 0.06, 0.004, 0.006)
    grp = geo.beams["t_frames"]
    assert grp.section == sec and grp.radial_offset == pytest.approx(-(0.005 + zc), rel=1e-12)
    wall = geo.volumes["t_wall"]
    dry = wall.rho * geo.shells["t_wall"] * geo.surface_areas["t_wall"] + grp.material.rho * sec.A * geo.curve_lengths["t_frames"]
    assert dry == pytest.approx(3000.0, rel=1e-12)
    assert geo.curve_lengths["t_frames"] == pytest.approx(7 * 2 * np.pi * (2.0 - 0.005 + grp.radial_offset), rel=1e-9)
    beam = model.part("beam")
    xyz = beam.xyz
    vertices = xyz[:beam.tagged.x.shape[0]]           # then the edge midpoints, on the facets' chords
    assert np.allclose(np.hypot(vertices[:, 0], vertices[:, 1]), 1.995, rtol=1e-9)
    assert set(np.round(xyz[:, 2], 6)) == set(np.round(z, 6))
    print(f"tank lowest elastic mode: bare {f1[0]:.2f} Hz, seven frames {f1[7]:.2f} Hz")
    assert f1[7] > 2 * f1[0]
    # eight hat stringers along the whole cylinder as well: their mass comes off the wall's too
    hat = {"shape": "hat", "h": 0.05, "b": 0.04, "c": 0.02, "t": 0.003}
    geo = build_tank(TankParams(**base, frames=z, frame_section=tee, stringers=8, stringer_azimuth=22.5,
                                stringer_section=hat), tmp_path / "ts")
    st = geo.beams["t_stringers"]
    assert st.vref == "tangential" and geo.curve_lengths["t_stringers"] == pytest.approx(8 * 8.0, rel=1e-9)
    dry = wall.rho * geo.shells["t_wall"] * geo.surface_areas["t_wall"] + sum(
        g.material.rho * g.section.A * geo.curve_lengths[n] for n, g in geo.beams.items())
    assert dry == pytest.approx(3000.0, rel=1e-12)
    model = build_model(geo)
    xyz = model.part("beam").xyz
    on = np.min(np.abs(xyz[:, 2, None] - np.array(z)[None, :]), axis=1) > 0.01      # off the frames
    az = np.degrees(np.arctan2(xyz[on, 1], xyz[on, 0])) % 45.0
    assert np.allclose(az, 22.5, atol=1e-6)
    f_st = eigenmodes(model, n_modes=7).freq_hz[6]
    print(f"with eight hat stringers too: {f_st:.2f} Hz")
    assert f_st > f1[7] * 0.9
    with pytest.raises(InputError, match=r"stringers: stringers are beams on a shell wall"):
        TankParams(**{**base, "walls": "solid"}, stringers=4, stringer_section=hat).check()
    with pytest.raises(InputError, match=r"stringers must be a whole number"):
        TankParams(**base, stringers=2.5, stringer_section=hat).check()
    with pytest.raises(InputError, match=r"frames: ring frames are beams on a shell wall"):
        TankParams(**{**base, "walls": "solid"}, frames=z, frame_section=tee).check()
    with pytest.raises(InputError, match=r"frames: height 12.0 m is not on the cylindrical wall"):
        TankParams(**base, frames=(12.0,), frame_section=tee).check()
    with pytest.raises(InputError, match=r"frame_section: shape 't' takes h, b, tw, tf \(m\); missing tf"):
        TankParams(**base, frames=z, frame_section={k: v for k, v in tee.items() if k != "tf"}).check()


def test_craig_bampton_of_a_beam_cantilever(tmp_path):
    """A beam model through the Craig-Bampton reducer: a slender tube (L/r = 100, Euler-
    Bernoulli section, no rotary inertia) whose root node is the interface (a patch on one
    beam node: its six DOFs). The fixed-interface modes are the clamped-free beam's,
    f_k = (beta_k L)^2/(2 pi L^2) sqrt(EI/(rho A)), beta_1 L = 1.875104, beta_2 L = 4.694091
    (each a bending pair); 16 cubic elements give them within 2e-5 (the error grows as
    (beta h)^4: measured 1.3e-7 and 5.1e-6).
    The Guyan mass is the beam's."""
    from liftoff.meshes.spec import Patch
    from liftoff.reduction import Component, craig_bampton

    r, t, n = 0.1, 0.01, 16
    L = 100 * r
    msh = _polyline(tmp_path / "c.msh", [(0, 0, 0), (L, 0, 0)], {"tube": [0]}, h=L / n, point_groups={"root": [0]})
    full = tube(r, t)
    sec = Section(full.A, full.Iy, full.Iz, full.J)
    model = build_model(Geometry("c", msh, {}, patches=[Patch("root", (0.0, 0.0, 0.0))],
                                 beams={"tube": BeamGroup(STEEL, sec, rotary=False)}))
    comp = Component(name="c", **model.component_fields())
    cb = craig_bampton(comp, [f"root:{c}" for c in ("Tx", "Ty", "Tz", "Rx", "Ry", "Rz")], n_modes=6)
    f = np.sort(cb.fixed_omega) / (2 * np.pi)
    ref = np.array([1.875104069, 4.694091133]) ** 2 / (2 * np.pi * L ** 2) * np.sqrt(STEEL.E * sec.Iy / (STEEL.rho * sec.A))
    print("cantilever CB fixed-interface modes / closed form - 1:", f[:4] / np.repeat(ref, 2) - 1)
    assert f[:4] == pytest.approx(np.repeat(ref, 2), rel=2e-5)
    assert cb.M[-6, -6] == pytest.approx(STEEL.rho * sec.A * L, rel=1e-12)


def _stringer_tube(path, n_str: int, R: float, L: float, h: float) -> str:
    """A cylinder (R, L) along z whose wall carries ``n_str`` straight generators at equal
    azimuths (physical curve "stringers", embedded in the wall), root and tip rims as the
    curve groups "root" and "tip"."""
    import gmsh

    with gmsh_file("stringers", path, dim=2, h=h):
        occ = gmsh.model.occ
        c = occ.addCircle(0, 0, 0, R)
        wall = [(2, t) for d, t in occ.extrude([(1, c)], 0, 0, L) if d == 2]
        a = 2 * np.pi * (np.arange(n_str) + 0.5) / n_str
        lines = [(1, occ.addLine(occ.addPoint(R * np.cos(x), R * np.sin(x), 0.0),
                                 occ.addPoint(R * np.cos(x), R * np.sin(x), L))) for x in a]
        _, out = occ.fragment(wall, lines)
        occ.synchronize()
        faces = [t for d, t in gmsh.model.getEntities(2)]
        gmsh.model.setPhysicalName(2, gmsh.model.addPhysicalGroup(2, faces), "wall")
        curves = {t: gmsh.model.getBoundingBox(1, t) for _, t in gmsh.model.getEntities(1)}
        gen = [t for t, b in curves.items() if b[5] - b[2] > 0.5 * L and abs(b[3] - b[0]) < 1e-5
               and np.min(np.hypot(b[0] - R * np.cos(a), b[1] - R * np.sin(a))) < 1e-5]   # (not the seam)
        assert len(gen) == n_str, (len(gen), n_str)
        gmsh.model.setPhysicalName(1, gmsh.model.addPhysicalGroup(1, gen), "stringers")
        for name, z in (("root", 0.0), ("tip", L)):
            ring = [t for t, b in curves.items() if abs(b[2] - z) < 1e-5 and abs(b[5] - z) < 1e-5]
            gmsh.model.setPhysicalName(1, gmsh.model.addPhysicalGroup(1, ring), name)
    return str(path)


def test_stringer_stiffened_tube_against_beam_theory(tmp_path):
    """A cantilever tube (R = 1 m, L = 8 m, 4 mm skin) with eight rectangular stringers
    (20 x 100 mm, inside the skin, local z radial: vref = "tangential") under a tip force
    through a rigid spider on its tip rim, against Timoshenko's beam with the composite
    section: I = pi R^3 t + sum A_s (r_s cos a_i)^2 + the stringers' own I (r_s: their
    centroid's radius), shear area pi R t (the skin's webs). The stringers carry a third of
    the bending stiffness, so the test sees them; tolerance 2 %: the bare tube's shell model
    against beam theory is within 1.5 % (tests/fem/test_shell_model.py: the rigid tip and
    the clamp stop the section's warping); measured +0.5 % bare, +0.9 % with stringers."""
    from liftoff.fem import point_load, static_solve
    from liftoff.meshes.spec import Patch

    R, L, t, P = 1.0, 8.0, 0.004, 1e4
    b, d = 0.02, 0.1
    e = -(t / 2 + d / 2)
    sec = rectangle(b, d, STEEL.nu)
    msh = _stringer_tube(tmp_path / "s.msh", 8, R, L, 0.25)
    G = STEEL.E / (2 * (1 + STEEL.nu))
    a = 2 * np.pi * (np.arange(8) + 0.5) / 8
    out = {}
    for with_str in (False, True):
        beams = {"stringers": BeamGroup(STEEL, sec, vref="tangential", radial_offset=e)} if with_str else {}
        model = build_model(Geometry("s", msh, {"wall": STEEL}, shells={"wall": t}, clamped=["root"],
                                     patches=[Patch("tip", (0.0, 0.0, L))], beams=beams))
        x = static_solve(model, point_load(model, "tip", force=(P, 0.0, 0.0)))
        I = np.pi * R ** 3 * t + (np.sum(sec.A * ((R + e) * np.cos(a)) ** 2) + 4 * (sec.Iy + sec.Iz) if with_str else 0.0)
        want = P * L ** 3 / (3 * STEEL.E * I) + P * L / (G * np.pi * R * t)
        out[with_str] = x[model.dof_index("tip:Tx")] / want
    print(f"tip deflection / beam theory: bare {out[False]:.4f}, with stringers {out[True]:.4f}")
    assert out[False] == pytest.approx(1.0, abs=0.02) and out[True] == pytest.approx(1.0, abs=0.02)


def test_girder_platform_against_slope_deflection(tmp_path):
    """meshes.platform with ``deck = "girders"``: the deck as a grid of girders through its
    posts and pedestals, posts and pedestals as beams. A platform with two pedestals 16 m
    apart and one post between them is a fixed-base portal whose girder carries the post's
    load at midspan; with the builder's sections made Euler-Bernoulli and nearly axially
    rigid (A = 100 m^2), slope-deflection gives the joint rotation
    theta = P L / (8 (4 E Ic/h + 2 E Ig/L)) and the post top's drop P L^3/(192 E Ig) +
    theta L/4 (fixed-fixed girder plus the sagging end rotations), plus the columns' and
    the post's axial shortening; 1e-4 for what it leaves out, the girder's axial stretch
    letting the column tops sway (measured 1.4e-5). Ig is the I girder's
    strong axis (Iy 20x its Iz): a girder turned on its side would be 20x softer. Mass:
    the platform's ``mass`` plus its pedestals' steel, exactly."""
    from dataclasses import replace

    from liftoff.core.beam import box_section, i_section
    from liftoff.meshes.pad import STEEL as PAD_STEEL
    from liftoff.meshes.platform import PlatformParams, build_platform

    P, girder = 1e6, {"shape": "i", "h": 0.8, "b": 0.4, "tw": 0.02, "tf": 0.03}
    p = PlatformParams(name="t", deck_size=(20.0, 4.0), deck_thickness=1.0, deck_top_z=0.0, posts={"p": (0.0, 0.0, 1.0)},
                       pedestals=((-8.0, 0.0), (8.0, 0.0)), pedestal_size=1.0, pedestal_height=4.0,
                       pedestal_wall_thickness=0.05, post_size=0.5, mass=2.0e5, deck="girders",
                       girder_section=girder, mesh_size=0.5)
    geo = build_platform(p, tmp_path)
    ped = box_section(1.0, 1.0, 0.05)
    assert geo.nominal_mass() == pytest.approx(2.0e5 + PAD_STEEL.rho * ped.A * 2 * 4.5, rel=1e-12)
    assert set(geo.beams) == {"t_girders_x", "t_posts", "t_pedestals"}      # (one line: no girder along y)
    assert geo.curve_lengths["t_girders_x"] == pytest.approx(16.0)
    stiff = {g: replace(b, section=Section(100.0, b.section.Iy, b.section.Iz, b.section.J)) for g, b in geo.beams.items()}
    model = build_model(replace(geo, beams=stiff))
    K, _ = model.matrices()
    f = np.zeros(model.n_dof)
    f[model.dof_index("p:Tz")] = -P
    drop = -sla.spsolve(K.tocsc(), f)[model.dof_index("p:Tz")]
    Ig, Ic, L, h = i_section(0.8, 0.4, 0.02, 0.03).Iy, ped.Iy, 16.0, 4.5
    theta = P * L / (8 * (4 * PAD_STEEL.E * Ic / h + 2 * PAD_STEEL.E * Ig / L))
    want = P * L ** 3 / (192 * PAD_STEEL.E * Ig) + theta * L / 4 + P / 2 * h / (PAD_STEEL.E * 100.0) \
        + P * 1.5 / (PAD_STEEL.E * 100.0)                  # + the columns' and the post's axial shortening
    print(f"girder platform: post drop {drop:.6e} m, slope-deflection {want:.6e} m")
    assert drop == pytest.approx(want, rel=1e-4)
    with pytest.raises(InputError, match=r"girder_section: shape 'i' takes h, b, tw, tf"):
        replace(p, girder_section={"shape": "i", "h": 0.8}).check()
    with pytest.raises(InputError, match=r"is less than its posts' and girders' steel"):
        build_platform(replace(p, mass=5.0e3), tmp_path / "light")


def test_beams_beside_shells_are_written_and_drawn(tmp_path):
    """A shell wall with beams keeps its shells as the cells and its beams as a second block
    of lines: in the FE model, the exported Component (saved and loaded), the VTU (two
    blocks, read back by meshio) and the pictures (one part each)."""
    import meshio

    from liftoff.fem import write_modes_vtu
    from liftoff.fem.snapshot import mesh_parts, snapshot_mode
    from liftoff.reduction.component import Component, load_component, save_component

    msh = _stringer_tube(tmp_path / "s.msh", 4, 1.0, 4.0, 0.5)
    model = build_model(Geometry("s", msh, {"wall": STEEL}, shells={"wall": 0.004}, clamped=["root"],
                                 beams={"stringers": BeamGroup(STEEL, rectangle(0.02, 0.1), vref="tangential",
                                                               radial_offset=-0.052)}))
    assert model.cell_type == "triangle6" and model.line_cells.shape[1] == 2
    assert np.allclose(model.nodes[model.line_cells][:, :, 2].max(), 4.0)              # along the wall
    comp = load_component(save_component(Component(name="s", **model.component_fields()), tmp_path / "s.npz"))
    assert np.array_equal(comp.line_cells, model.line_cells)
    modes = eigenmodes(model, n_modes=2)
    mesh = meshio.read(write_modes_vtu(model, modes, tmp_path / "s.vtu"))
    assert [b.type for b in mesh.cells] == ["triangle6", "line"] and len(mesh.cells[1].data) == len(model.line_cells)
    assert [p.cell_type for p in mesh_parts(comp, np.zeros((len(comp.nodes), 3)))] == ["triangle6", "line"]
    assert snapshot_mode(tmp_path / "s.png", model, modes, 0).stat().st_size > 0


def test_orbiter_skin_ring_frames(tmp_path):
    """meshes.vehicle.OrbiterParams with a shell skin and ``frames``: Z frames (as T
    sections) on the fuselage skin's inner face at the given heights; the structure mass
    is kept (the frames' share comes off the skin's: the geometry's nominal mass equals
    the frameless one's to round-off) and the beams' nodes lie on the skin's mid-surface
    circles at those heights."""
    from dataclasses import replace

    from liftoff.meshes.layout import StackLayout
    from liftoff.meshes.vehicle import OrbiterParams, build_orbiter

    lay = StackLayout()
    base = OrbiterParams(layout=lay, walls="shell", mesh_size=1.2)
    z0 = lay.orbiter_bottom_z
    z = (z0 + 6.0, z0 + 12.0, z0 + 20.0)
    tee = {"shape": "t", "h": 0.2, "b": 0.08, "tw": 0.004, "tf": 0.006}
    bare = build_orbiter(base, tmp_path / "bare")
    framed = build_orbiter(replace(base, frames=z, frame_section=tee), tmp_path / "framed")
    assert framed.nominal_mass() == pytest.approx(bare.nominal_mass(), rel=1e-12)
    grp = framed.beams["orbiter_frames"]
    assert grp.axis_point[:2] == (0.0, lay.orbiter_axis_y) and grp.radial_offset < 0
    lines = _lines_of(framed)
    r = np.hypot(lines[:, 0] - 0.0, lines[:, 1] - lay.orbiter_axis_y)
    assert np.allclose(r, lay.orbiter_radius - 0.5 * base.wall_thickness, rtol=1e-9)
    assert set(np.round(lines[:, 2], 6)) == set(np.round(z, 6))
    with pytest.raises(InputError, match=r"OrbiterParams.frames: height .* is not on the fuselage cylinder"):
        replace(base, frames=(z0 - 5.0,), frame_section=tee).check()
    with pytest.raises(InputError, match=r"OrbiterParams.frames: ring frames are beams on a shell skin"):
        replace(base, walls="solid", frames=z, frame_section=tee).check()


def test_orbiter_skin_stringers(tmp_path):
    """OrbiterParams ``stringers`` (shell skin): hat stringers along the fuselage cylinder
    at equal azimuths, half a pitch off the wing roots by default; the structure mass kept
    (1e-12, as the frames'); their lines on the skin's mid-surface at those azimuths, each
    the cylinder's length (1e-9); the FE model's mass (skin, wing, beams and point masses)
    the geometry's nominal mass within 5e-3 (the beams' lines are straight, so their mass is
    exact; the meshed skin's area differs from the CAD area it was sized on: measured 1.4e-3
    at 1.2 m cells); a stringer through a wing root is an error naming it."""
    from dataclasses import replace

    from liftoff.fem import mass_properties
    from liftoff.meshes.layout import StackLayout
    from liftoff.meshes.shells import stringer_angles
    from liftoff.meshes.vehicle import OrbiterParams, build_orbiter

    lay = StackLayout()
    base = OrbiterParams(layout=lay, walls="shell", mesh_size=1.2)
    hat = {"shape": "hat", "h": 0.05, "b": 0.03, "c": 0.02, "t": 0.002}
    n = 8
    bare = build_orbiter(base, tmp_path / "bare")
    p = replace(base, stringers=n, stringer_section=hat, frames=(lay.orbiter_bottom_z + 10.0,),
                frame_section={"shape": "rectangle", "h": 0.15, "b": 0.01})
    geo = build_orbiter(p, tmp_path / "stiff")
    assert p.stringer_azimuth is None and stringer_angles(p)[0] == pytest.approx(np.pi / n)
    assert geo.nominal_mass() == pytest.approx(bare.nominal_mass(), rel=1e-12)
    assert geo.curve_lengths["orbiter_stringers"] == pytest.approx(n * (p.cyl_length - 0.5 * p.wall_thickness), rel=1e-9)
    grp = geo.beams["orbiter_stringers"]
    assert grp.vref == "tangential" and grp.radial_offset < 0
    from liftoff.fem.mesh import read_beam_lines
    from mpi4py import MPI

    b = read_beam_lines(geo.msh_path, ("orbiter_stringers",), MPI.COMM_SELF)
    dx, dy = b.x[:, 0], b.x[:, 1] - lay.orbiter_axis_y
    assert np.allclose(np.hypot(dx, dy), lay.orbiter_radius - 0.5 * p.wall_thickness, rtol=1e-9)
    az = np.degrees(np.arctan2(dy, dx)) % 360.0
    want = (180.0 / n + 360.0 / n * np.arange(n)) % 360.0
    assert np.abs((az[:, None] - want[None, :] + 180.0) % 360.0 - 180.0).min(axis=1).max() < 1e-6
    model = build_model(geo)
    m = mass_properties(model).mass
    print(f"orbiter with {n} stringers: FE mass {m:.6e} kg, nominal {geo.nominal_mass():.6e} kg")
    assert m == pytest.approx(geo.nominal_mass(), rel=5e-3)
    with pytest.raises(InputError, match=r"OrbiterParams.stringer_azimuth: stringer 1 of 8, at 0 deg, runs through "
                                         r"the wing root"):
        replace(base, stringers=n, stringer_azimuth=0.0, stringer_section=hat).check()
    with pytest.raises(InputError, match=r"OrbiterParams.stringers: stringers are beams on a shell wall"):
        replace(base, walls="solid", stringers=n, stringer_section=hat).check()
    with pytest.raises(InputError, match=r"OrbiterParams.stringers must be a whole number"):
        replace(base, stringers=2.5, stringer_section=hat).check()


def _lines_of(geo) -> np.ndarray:
    """The nodes of a geometry's beam lines (m), read back from its mesh."""
    from liftoff.fem.mesh import read_beam_lines
    from mpi4py import MPI

    b = read_beam_lines(geo.msh_path, tuple(geo.beams), MPI.COMM_SELF)
    return b.x


@pytest.mark.parametrize("offset", [(0.0, 0.0, 0.0), (0.0, 0.3, -0.2)])
def test_a_thermal_strain_of_a_beam_is_its_free_expansion(tmp_path, offset):
    """A cantilever (8 m, 8 elements), its axis offset from its nodes or not, under a uniform
    axial thermal strain eps: the free expansion, tip moving eps L along the axis, with no
    rotation and no transverse motion (the thermal load of fem.beam.thermal_forces is K of
    that field: stress-free). 1e-9: round-off of the chain."""
    from liftoff.fem import static_solve, thermal_load

    L, eps = 8.0, -4.6e-3
    msh = _polyline(tmp_path / "bar.msh", [(0, 0, 0), (L, 0, 0)], {"bar": [0]}, h=L / 8, point_groups={"root": [0]})
    model = build_model(Geometry("bar", msh, {}, clamped=["root"],
                                 beams={"bar": BeamGroup(STEEL, tube(0.1, 0.01, STEEL.nu), vref=(0, 0, 1), offset=offset)}))
    x = static_solve(model, thermal_load(model, ["bar"], -200.0, eps / -200.0))
    d = model.node_dofs((L, 0, 0))
    assert x[d][0] == pytest.approx(eps * L, rel=1e-9)
    assert np.abs(x[d][1:]).max() < 1e-9 * abs(eps * L)


def _cryo_shrinkage(model, wall: str):
    """(f, K, u): the thermal load of ``wall`` at alpha 2.3e-5 /K, dT -200 K, the model's K and
    the homogeneous shrinkage u = eps x of its nodes (translations; no rotation)."""
    from liftoff.fem import thermal_load

    f = thermal_load(model, [wall], -200.0, 2.3e-5)
    K, _ = model.matrices()
    u = np.zeros(model.n_dof)
    tr = model.dof_comp < 3
    u[tr] = 2.3e-5 * -200.0 * model.dof_coords[tr, model.dof_comp[tr]]
    return f, K, u


def test_a_wall_and_its_stringers_shrink_together_stress_free(tmp_path):
    """A tube wall with eight stringers (BeamGroup.wall = "wall", on the mid-surface), free:
    the wall's thermal strain is the stringers' too, and the homogeneous shrinkage
    u = eps (x - x0), no rotation, is then stress-free: K u = f to round-off (1e-9 of f).
    Without the members' share (the load before 2026-12-07: the wall alone shrank) the
    residual is the stringers' restraint, E A eps at their ends: 0.73 of the largest load here
    (1.9e-14 with them), which the review found as a frame hoop stress near E alpha dT."""
    from liftoff.fem import thermal_load

    R, L, t = 1.0, 4.0, 0.004
    msh = _stringer_tube(tmp_path / "s.msh", 8, R, L, 0.5)
    sec = rectangle(0.02, 0.1, STEEL.nu)
    model = build_model(Geometry("s", msh, {"wall": STEEL}, shells={"wall": t},
                                 beams={"stringers": BeamGroup(STEEL, sec, vref="tangential", wall="wall")}))
    f, K, u = _cryo_shrinkage(model, "wall")
    assert np.abs(K @ u - f).max() < 1e-9 * np.abs(f).max()
    beams_only = thermal_load(model, ["stringers"], -200.0, 2.3e-5)
    assert np.abs(K @ u - (f - beams_only)).max() > 0.1 * np.abs(f).max()


def test_offset_ring_frames_shrink_with_their_wall_stress_free(tmp_path):
    """Ring frames whose axis lies D/2 inside the skin (the rigid offset links do not expand,
    and the lines' midpoints lie inside the circle, so the offset chords are not parallel to
    the nodes'): fem.beam.thermal_forces loads each element with k times the homogeneous
    shrinkage of its nodes, so wall and frames together are stress-free: K u = f to 1e-9 of
    f (with E A eps along each axis the residual was 1e-3 of f)."""
    from liftoff.fem import thermal_load

    msh = _stiffened_cylinder(tmp_path / "beams.msh", False, h=0.2)
    model = build_model(Geometry("rings", msh, {"skin": STEEL}, shells={"skin": T},
                                 beams={"frames": BeamGroup(STEEL, rectangle(TW, D, STEEL.nu), radial_offset=-D / 2,
                                                            wall="skin")}))
    f, K, u = _cryo_shrinkage(model, "skin")
    assert np.abs(K @ u - f).max() < 1e-9 * np.abs(f).max()
    # a member named itself takes its own alpha, whatever the order of the names
    a = {"skin": 2.3e-5, "frames": 1.0e-5}
    f1 = thermal_load(model, ["frames", "skin"], -200.0, a)
    f2 = thermal_load(model, ["skin", "frames"], -200.0, a)
    assert np.array_equal(f1, f2) and not np.allclose(f1, f)


def test_a_vref_along_the_member_is_refused_and_the_default_never_nan():
    """A user's vref along a member sets no plane: refused, naming the group (a review,
    2026-12-07: 'tangential' on a ring put every chord on the fallback, and a member along y
    with vref along y gave NaN matrices). liftoff.core.beam's own fallback for its default
    vref along the beam now picks an axis off it, so a beam along y is finite."""
    from liftoff.core.beam import beam_element
    from liftoff.fem.beam import _group_elements

    k, m = beam_element((0, 0, 0), (0, 2, 0), 2e11, 8e10, tube(0.1, 0.01, 0.3), 7850.0, (0.0, -3.0, 0.0))
    assert np.all(np.isfinite(k)) and np.all(np.isfinite(m))
    x = np.array([[0.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    grp = BeamGroup(STEEL, tube(0.1, 0.01, STEEL.nu), vref=(0.0, 1.0, 0.0))
    with pytest.raises(InputError, match=r"beam curve 'spoke': its orientation vref \(\[0.0, 1.0, 0.0\]\) lies along"):
        list(_group_elements(x, np.array([[0, 1]]), grp, "spoke"))


def test_a_default_vref_builds_a_vertical_member(tmp_path):
    """A BeamGroup without a vref on a member along z (a leg, a post) builds, on the core's
    axis off the member (the refusal is for a vref given along it; a review: the default
    (0, 0, 1) was refused there)."""
    msh = _polyline(tmp_path / "leg.msh", [(0, 0, 0), (0, 0, 2)], {"legs": [0]}, h=0.5, point_groups={"foot": [0]})
    model = build_model(Geometry("leg", msh, {}, clamped=["foot"], beams={"legs": BeamGroup(STEEL, tube(0.1, 0.01, 0.3))}))
    K, M = model.matrices()
    assert np.all(np.isfinite(K.data)) and np.all(np.isfinite(M.data))
