"""gmsh test geometries for fem/ tests (written once per session into a temp folder).

Each factory returns the .msh path; physical groups are named. Boxes can be meshed
*structured* (transfinite, each hex split into tetrahedra) so that refinement halves h
exactly and observed convergence orders are clean.
"""
from __future__ import annotations

import os

import pytest

os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")
import pyvista  # noqa: E402,F401  (before dolfinx: FENICSX-NOTES.md)

gmsh = pytest.importorskip("gmsh")
pytest.importorskip("dolfinx")
from .gmsh_cases import gmsh_file  # noqa: E402


def _name_box_faces(vol, L, W, H, x0=0.0, prefix=""):
    """Name the 6 faces x0,x1,y0,y1,z0,z1 of an axis-aligned box volume."""
    for _, s in gmsh.model.getBoundary([(3, vol)], oriented=False):
        c = gmsh.model.occ.getCenterOfMass(2, s)
        for nm, val, ax in (("x0", x0, 0), ("x1", x0 + L, 0), ("y0", 0, 1), ("y1", W, 1), ("z0", 0, 2), ("z1", H, 2)):
            if abs(c[ax] - val) < 1e-9 * max(1.0, L):
                t = gmsh.model.addPhysicalGroup(2, [s])
                gmsh.model.setPhysicalName(2, t, prefix + nm)


def write_box(path, L=1.0, W=0.1, H=0.1, n=(10, 1, 1), h=None, volume="solid"):
    """Box [0,L]x[0,W]x[0,H]; structured n=(nx,ny,nz) divisions, or unstructured size h."""
    with gmsh_file("box", path, h=h):
        v = gmsh.model.occ.addBox(0, 0, 0, L, W, H)
        gmsh.model.occ.synchronize()
        gmsh.model.setPhysicalName(3, gmsh.model.addPhysicalGroup(3, [v]), volume)
        _name_box_faces(v, L, W, H)
        if h is None:
            for _, c in gmsh.model.getEntities(1):
                b = gmsh.model.getBoundingBox(1, c)
                ext = [b[3] - b[0], b[4] - b[1], b[5] - b[2]]
                gmsh.model.mesh.setTransfiniteCurve(c, n[int(max(range(3), key=lambda i: ext[i]))] + 1)
            for _, s in gmsh.model.getEntities(2):
                gmsh.model.mesh.setTransfiniteSurface(s)
            gmsh.model.mesh.setTransfiniteVolume(v)
    return str(path)


def write_two_boxes(path, gap=0.05, h=0.05):
    """Two disjoint unit-ish boxes in one mesh (a floating part); faces a_x0.. and b_x0.."""
    with gmsh_file("two", path, h=h):
        a = gmsh.model.occ.addBox(0, 0, 0, 0.3, 0.1, 0.1)
        b = gmsh.model.occ.addBox(0.3 + gap, 0, 0, 0.3, 0.1, 0.1)
        gmsh.model.occ.synchronize()
        gmsh.model.setPhysicalName(3, gmsh.model.addPhysicalGroup(3, [a, b]), "solid")
        _name_box_faces(a, 0.3, 0.1, 0.1, prefix="a_")
        _name_box_faces(b, 0.3, 0.1, 0.1, x0=0.3 + gap, prefix="b_")
    return str(path)


def write_ring(path, R=1.0, t=0.05, b=0.1, h=0.1):
    """Thin ring: annulus R +- t/2 in the xy plane, axial width b; faces 'outer', 'inner'."""
    with gmsh_file("ring", path, h=h):
        o = gmsh.model.occ.addCylinder(0, 0, 0, 0, 0, b, R + t / 2)
        i = gmsh.model.occ.addCylinder(0, 0, 0, 0, 0, b, R - t / 2)
        out, _ = gmsh.model.occ.cut([(3, o)], [(3, i)])
        gmsh.model.occ.synchronize()
        v = out[0][1]
        gmsh.model.setPhysicalName(3, gmsh.model.addPhysicalGroup(3, [v]), "ring")
    return str(path)


def write_surface_only(path):
    """A mesh with only a 2-D physical group (no volume)."""
    with gmsh_file("surf", path, dim=2):
        s = gmsh.model.occ.addRectangle(0, 0, 0, 1, 1)
        gmsh.model.occ.synchronize()
        gmsh.model.setPhysicalName(2, gmsh.model.addPhysicalGroup(2, [s]), "plate")
    return str(path)


def write_shell_tube(path, R=0.1, L=1.0, n_around=24, n_along=20):
    """Structured shell tube: a prism whose cross-section is the regular n_around-gon inscribed
    in the circle of radius R (straight generators from z = 0 to L, n_along layers), surface
    'tube'; its end polygons 'root' (z = 0) and 'tip' (z = L) as curve groups, and the band
    0.4 L < z < 0.6 L as the surface group 'band' (also part of 'tube')."""
    with gmsh_file("tube", path, dim=2):
        occ = gmsh.model.occ
        c = occ.addCircle(0, 0, 0, R)
        occ.synchronize()
        gmsh.model.mesh.setTransfiniteCurve(c, n_around + 1)
        curve, surfs = (1, c), []
        for frac in (0.4, 0.2, 0.4):
            out = occ.extrude([curve], 0, 0, frac * L, numElements=[round(frac * n_along)])
            curve = next(d for d in out if d[0] == 1)
            surfs.append(next(d for d in out if d[0] == 2)[1])
        occ.synchronize()
        gmsh.model.setPhysicalName(2, gmsh.model.addPhysicalGroup(2, surfs), "tube")
        gmsh.model.setPhysicalName(2, gmsh.model.addPhysicalGroup(2, [surfs[1]]), "band")
        gmsh.model.setPhysicalName(1, gmsh.model.addPhysicalGroup(1, [c]), "root")
        gmsh.model.setPhysicalName(1, gmsh.model.addPhysicalGroup(1, [curve[1]]), "tip")
    return str(path)


def write_glued_plate(path, a=0.2, L=1.0, b=0.2, d=0.1, h=0.05):
    """A solid block [0,a]x[0,b]x[-d,0] ('block', bottom face 'base') with a plate surface
    [0,L]x[0,b] at z = 0 ('plate') fragmented onto the block's top face (shared nodes) and
    overhanging it; the plate's free edge x = L is the curve group 'tip'."""
    with gmsh_file("glued", path, h=h):
        occ = gmsh.model.occ
        blk = occ.addBox(0, 0, -d, a, b, d)
        plate = occ.addRectangle(0, 0, 0, L, b)
        out, _ = occ.fragment([(3, blk)], [(2, plate)])
        occ.synchronize()
        vols = [t for dd, t in gmsh.model.getEntities(3)]
        gmsh.model.setPhysicalName(3, gmsh.model.addPhysicalGroup(3, vols), "block")
        plate_faces = [s for _, s in gmsh.model.getEntities(2)
                       if abs(occ.getCenterOfMass(2, s)[2]) < 1e-9]
        base = [s for _, s in gmsh.model.getEntities(2) if abs(occ.getCenterOfMass(2, s)[2] + d) < 1e-9]
        gmsh.model.setPhysicalName(2, gmsh.model.addPhysicalGroup(2, plate_faces), "plate")
        gmsh.model.setPhysicalName(2, gmsh.model.addPhysicalGroup(2, base), "base")
        tip = [c for _, c in gmsh.model.getEntities(1)
               if abs(gmsh.model.getBoundingBox(1, c)[0] - L) < 1e-6 and abs(gmsh.model.getBoundingBox(1, c)[3] - L) < 1e-6]
        gmsh.model.setPhysicalName(1, gmsh.model.addPhysicalGroup(1, tip), "tip")
    return str(path)


_WRITERS = {"box": write_box, "two_boxes": write_two_boxes, "ring": write_ring, "surface": write_surface_only,
            "shell_tube": write_shell_tube, "glued_plate": write_glued_plate}


@pytest.fixture(scope="session")
def msh(tmp_path_factory):
    """msh(kind, **params) -> path of a cached test mesh."""
    root = tmp_path_factory.mktemp("fem_msh")
    cache = {}

    def make(kind, **params):
        key = (kind, tuple(sorted(params.items())))
        if key not in cache:
            tag = "_".join(f"{k}{v}" for k, v in sorted(params.items())).replace(" ", "").replace(",", "x")
            cache[key] = _WRITERS[kind](root / f"{kind}_{len(cache)}_{tag[:60]}.msh", **params)
        return cache[key]

    return make
