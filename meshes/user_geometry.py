"""A component from the user's own geometry: a gmsh ``.geo`` or ``.msh`` file, or a STEP /
BREP file read through gmsh's OpenCASCADE import, with the roles of its physical groups
given by name (:class:`GeometryFileParams`, the scenario's ``type = "geometry"``).

Roles (every group named in a role must exist with the right dimension, and every volume
group of the file must have a role; an InputError names the file, the group and the
scenario key otherwise):

* ``materials``: volume group -> :class:`Material` (solid tetrahedra), and shell surface
  group -> Material with its thickness in ``shells`` (Reissner-Mindlin shells, fem.shell);
* ``points``: 6-DOF named points, each a surface (or shell curve) group tied to a reference
  point rigidly (RBE2, ``tie = "rigid"``) or by interpolation (RBE3, ``"interpolate"``);
  the reference point is ``at`` (m) or, by default, the area (length) centroid of the
  group's mesh; attach, hold-down, engine-mount and output points are all such points;
* ``masses``: lumped masses (kg, inertia kg m^2 about the point) at named points;
* ``clamped``: surface groups fixed to ground (a pad's foundations);
* ``liquids``: volume group -> :class:`Liquid` (fem.liquid: wetted and free-surface groups);
* ``groups`` (STEP/BREP files, which carry no physical groups): a group made of the
  entities of one dimension that lie inside a box (m), ``gmsh.model.getEntitiesInBoundingBox``.

``.geo`` and STEP/BREP are meshed with P1 tetrahedra (triangles for shells) no larger
than ``mesh_size`` (m; a ``.geo`` may set its own sizes when it is None); a ``.msh`` is
taken as it is. The solids of a STEP/BREP assembly are fragmented against each other
(``occ.removeAllDuplicates``) so that touching parts share their faces and nodes. Group
volumes and areas are measured on the mesh. Every solid must lie in a volume group with a
role, and every surface that bounds no solid (nor is embedded in one) in a shell group (an
entity outside them would be left out of the model without a word). Units SI; the file's lengths are metres: a
STEP file is read in metres whatever unit it declares (OpenCASCADE converts it,
``Geometry.OCCTargetUnit``); a BREP file carries no unit and is taken as metres.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from liftoff.core.errors import InputError, ResourceError
from liftoff.core.records import atomic_path, geometry_sha256

from . import _occ
from .spec import Geometry, Liquid, Material, Patch, PointMass

#: m: a CAD component smaller than this is taken for a unit error (a launch-vehicle part is not)
SMALLEST_CAD = 0.01
#: file suffixes read, by how
GMSH_FILES = (".geo", ".msh")
CAD_FILES = (".step", ".stp", ".brep")
TIES = ("rigid", "interpolate")


@dataclass
class GeometryFileParams:
    """A user geometry file and the roles of its groups (SI; see the module docstring).
    ``origin``: the scenario key of these parameters, for messages; ``file_sha256``: the
    file's hash when the scenario was read, with those a .geo merges or includes
    (liftoff.core.records.geometry_sha256: the stage cache's key; a file changed since is
    refused)."""

    name: str
    file: str
    file_sha256: str = ""
    mesh_size: float | None = None
    materials: dict = field(default_factory=dict)     # group -> Material
    shells: dict = field(default_factory=dict)        # surface group -> thickness (m)
    points: dict = field(default_factory=dict)        # point -> {"group", "at" (or None), "tie"}
    masses: dict = field(default_factory=dict)        # name -> {"point", "mass", "inertia"}
    clamped: tuple = ()
    liquids: dict = field(default_factory=dict)       # volume group -> Liquid fields (dict)
    groups: dict = field(default_factory=dict)        # name -> {"dim", "box"} (STEP/BREP)
    origin: str = "params"

    def check(self) -> None:
        o = f"{self.origin}"
        path = Path(self.file)
        if path.suffix.lower() not in GMSH_FILES + CAD_FILES:
            raise InputError(f"{o}.file: {path.name!r} is not a geometry file gmsh reads here "
                             f"({', '.join(GMSH_FILES + CAD_FILES)})")
        if not path.is_file():
            raise InputError(f"{o}.file: file not found: {str(path)!r}")
        if path.suffix.lower() in CAD_FILES and self.mesh_size is None:
            raise InputError(f"{o}: a {path.suffix} file has no mesh sizes: give the component's mesh_size (m)")
        if self.mesh_size is not None and not (math.isfinite(self.mesh_size) and self.mesh_size > 0):
            raise InputError(f"{o}: mesh_size must be a finite number > 0 m (got {self.mesh_size!r})")
        if not self.materials and not self.liquids:
            raise InputError(f"{o}: no solids or shells: give each volume group a material ({o}.solids)")
        for g in self.shells:
            if g not in self.materials:
                raise InputError(f"{o}.shells.{g}: a shell needs E, nu, rho and thickness")
        for name, m in self.masses.items():
            if m["point"] not in self.points:
                raise InputError(f"{o}.masses.{name}.point: {m['point']!r} is not one of the points "
                                 f"({', '.join(self.points) or 'none'})")
        for name, pt in self.points.items():
            if pt.get("tie", "rigid") not in TIES:
                raise InputError(f"{o}.points.{name}.tie must be one of {', '.join(TIES)} (got {pt.get('tie')!r})")
        if path.suffix.lower() not in CAD_FILES and self.groups:
            raise InputError(f"{o}.groups: boxes make groups of STEP/BREP files only; a {path.suffix} file "
                             "names its own physical groups")


def _physical(gmsh) -> dict[str, tuple[int, int]]:
    """{name: (dim, tag)} of the model's physical groups (an unnamed one is an error later,
    fem.mesh; here it is listed as ``<dim>:<tag>``)."""
    out = {}
    for dim, tag in gmsh.model.getPhysicalGroups():
        out[gmsh.model.getPhysicalName(dim, tag) or f"{dim}:{tag}"] = (dim, tag)
    return out


def _open(gmsh, p: GeometryFileParams) -> None:
    path = Path(p.file)
    # OpenCASCADE converts a STEP file's lengths to this unit (default: millimetres, so that a
    # file declaring metres was read 1000 times too large); also for a .geo's Merge of one
    gmsh.option.setString("Geometry.OCCTargetUnit", "M")
    try:
        if path.suffix.lower() in CAD_FILES:
            _occ.occ.importShapes(str(path))
            _occ.occ.removeAllDuplicates()     # solids of an assembly share their faces: one conforming mesh
            _occ.occ.synchronize()
        else:
            gmsh.open(str(path))
    except Exception as exc:       # gmsh raises plain Exceptions with its log line
        raise InputError(f"{path}: gmsh cannot read it ({' '.join(str(exc).split())})") from None
    if not gmsh.model.getEntities():
        raise InputError(f"{path}: no geometry in the file")
    if path.suffix.lower() in CAD_FILES:
        box = np.asarray(gmsh.model.getBoundingBox(-1, -1), float)
        size = float(np.max(box[3:] - box[:3]))
        if size < SMALLEST_CAD:
            raise InputError(f"{path}: the geometry spans {size:.3g} m, in metres read from the unit the file "
                             f"declares: a file whose numbers are metres but is declared in mm (gmsh writes such "
                             f"files unless Geometry.OCCTargetUnit = \"M\") comes out 1000 times small; "
                             f"export it with its true unit")


def _make_groups(gmsh, p: GeometryFileParams) -> None:
    for name, g in p.groups.items():
        ents = gmsh.model.getEntitiesInBoundingBox(*g["box"], g["dim"])
        if not ents:
            raise InputError(f"{Path(p.file).name}: {p.origin}.groups.{name}: no entity of dimension {g['dim']} "
                             f"inside the box {list(g['box'])} m")
        _occ.add_physical(g["dim"], name, [t for _, t in ents])


def _check_roles(p: GeometryFileParams, groups: dict[str, tuple[int, int]]) -> None:
    """Every role's group exists with its dimension; every volume group has a role."""
    f, o = Path(p.file).name, p.origin
    listed = {d: sorted(n for n, (dd, _) in groups.items() if dd == d) for d in (1, 2, 3)}
    what = {3: "volume", 2: "surface", 1: "curve"}

    def need(group: str, dims: tuple[int, ...], key: str) -> None:
        if group in groups and groups[group][0] in dims:
            return
        have = [n for d in dims for n in listed[d]]
        kinds = " or ".join(what[d] for d in dims)
        got = f" (it is a {what.get(groups[group][0], 'point')} group)" if group in groups else ""
        raise InputError(f"{f}: no {kinds} group {group!r}{got}, named in {o}.{key} "
                         f"(the file's {kinds} groups: {', '.join(have) or 'none'})")

    for g in p.materials:
        need(g, (2,) if g in p.shells else (3,), f"{'shells' if g in p.shells else 'solids'}.{g}")
    for name, pt in p.points.items():
        need(pt["group"], (1, 2), f"points.{name}.group")
    for g in p.clamped:
        need(g, (1, 2), "clamped")
    for g, liq in p.liquids.items():
        need(g, (3,), f"liquids.{g}")
        for k in ("wetted", "free_surface", "cavity"):
            if liq.get(k):
                need(liq[k], (2,), f"liquids.{g}.{k}")
    for g in listed[3]:
        if g not in p.materials and g not in p.liquids:
            raise InputError(f"{f}: volume group {g!r} has no role: give it a material in {o}.solids.{g} "
                             f"(or make it a liquid in {o}.liquids.{g})")


def _check_assigned(gmsh, p: GeometryFileParams, groups: dict[str, tuple[int, int]]) -> None:
    """Every solid of the file lies in a volume group with a role, and every surface in a
    shell group, on the boundary of a solid or embedded in one: gmsh writes only the
    elements of physical groups, so an entity outside them would be left out of the model
    without a word (its mass and stiffness with it). In a .msh file, the entities that have
    elements, and a surface counts as a solid's when its nodes are nodes of volume elements
    (an MSH 2 file has no topology)."""
    f, o = Path(p.file).name, p.origin
    msh = Path(p.file).suffix.lower() == ".msh"

    def members(dim: int, names) -> set:
        return {t for n in names if n in groups and groups[n][0] == dim
                for t in gmsh.model.getEntitiesForPhysicalGroup(dim, groups[n][1])}

    def nodes(dim: int, tag: int) -> np.ndarray:
        return np.unique(np.concatenate([np.asarray(n, np.int64) for n in gmsh.model.mesh.getElements(dim, tag)[2]]
                                        + [np.zeros(0, np.int64)]))

    def where(dim: int, tag: int) -> str:
        b = gmsh.model.getBoundingBox(dim, tag)
        return f"bounding box [{', '.join(f'{v:.6g}' for v in b)}] m"

    solids = members(3, list(p.materials) + list(p.liquids))
    volumes = [t for _, t in gmsh.model.getEntities(3) if not msh or nodes(3, t).size]
    for tag in volumes:
        if tag not in solids:
            raise InputError(f"{f}: volume {tag} ({where(3, tag)}) is in no volume group with a role, so it would be "
                             f"left out of the model: add it to a group given a material in {o}.solids (or a liquid)"
                             + (f", or cover it with a box in {o}.groups" if Path(p.file).suffix.lower() in CAD_FILES
                                else ""))
    grouped = members(2, [g for g in p.materials if g in p.shells])      # shells; a point's group alone is not one
    if msh:
        solid_nodes = np.unique(np.concatenate([nodes(3, t) for t in volumes] + [np.zeros(0, np.int64)]))
    else:
        solid_faces = {t for v in volumes for _, t in gmsh.model.getBoundary([(3, v)], combined=False, oriented=False)}
        solid_faces |= {t for v in volumes for d, t in gmsh.model.mesh.getEmbedded(3, v) if d == 2}
    for _, tag in gmsh.model.getEntities(2):
        if tag in grouped:
            continue
        if msh:
            own = nodes(2, tag)
            if own.size == 0 or np.all(np.isin(own, solid_nodes)):
                continue
        elif tag in solid_faces:
            continue
        raise InputError(f"{f}: surface {tag} ({where(2, tag)}) is in no shell group and bounds no solid, so it would be "
                         f"left out of the model: add it to a surface group given a material and a thickness in "
                         f"{o}.shells")


def _mesh_measures(gmsh, groups: dict[str, tuple[int, int]]) -> tuple[dict, dict, dict]:
    """(volume of each volume group, area of each surface group, centroid of each surface
    or curve group), from the mesh's linear elements (m^3, m^2, m)."""
    tags, coords, _ = gmsh.model.mesh.getNodes()
    xyz = np.asarray(coords, float).reshape(-1, 3)
    x = dict(zip(np.asarray(tags, int).tolist(), range(len(tags))))
    vols, areas, centroids = {}, {}, {}
    for name, (dim, tag) in groups.items():
        total, moment = 0.0, np.zeros(3)
        for ent in gmsh.model.getEntitiesForPhysicalGroup(dim, tag):
            etypes, _, enodes = gmsh.model.mesh.getElements(dim, ent)
            for et, nodes in zip(etypes, enodes):
                n_vert = {1: 2, 2: 3, 3: 4}[dim]
                nodes = np.asarray(nodes, int).reshape(-1, gmsh.model.mesh.getElementProperties(et)[3])[:, :n_vert]
                if nodes.size == 0:
                    continue
                idx = np.vectorize(x.__getitem__)(nodes)
                P = xyz[idx]
                if dim == 3:
                    m = np.abs(np.einsum("ij,ij->i", P[:, 1] - P[:, 0],
                                         np.cross(P[:, 2] - P[:, 0], P[:, 3] - P[:, 0]))) / 6.0
                elif dim == 2:
                    m = 0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1)
                else:
                    m = np.linalg.norm(P[:, 1] - P[:, 0], axis=1)
                total += m.sum()
                moment += (m[:, None] * P.mean(axis=1)).sum(axis=0)
        if dim == 3:
            vols[name] = total
        elif dim == 2:
            areas[name] = total
        if dim in (1, 2) and total > 0:
            centroids[name] = moment / total
    return vols, areas, centroids


def build_user_geometry(p: GeometryFileParams, out_dir) -> Geometry:
    """The meshed Geometry of a user file (module docstring): ``<out_dir>/<name>.msh`` and
    its JSON sidecar."""
    if not isinstance(p, GeometryFileParams):
        raise InputError(f"build_user_geometry expects GeometryFileParams, got {type(p).__name__}")
    p.check()
    path = Path(p.file)
    try:
        digest = geometry_sha256(path) if p.file_sha256 else ""
    except ValueError as exc:       # a merged or included file gone since the scenario was read
        raise InputError(f"{p.origin}.file: {exc}") from None
    if p.file_sha256 and digest != p.file_sha256:
        raise InputError(f"{path}: the file changed after the scenario was read; run again")
    out_dir = Path(out_dir)
    gmsh = _occ.gmsh
    with _occ.gmsh_session(p.name):
        _open(gmsh, p)
        _make_groups(gmsh, p)
        groups = _physical(gmsh)
        _check_roles(p, groups)
        _check_assigned(gmsh, p, groups)
        if path.suffix.lower() != ".msh":
            if path.suffix.lower() in CAD_FILES:
                _occ.check_element_count(p.mesh_size)
            if p.mesh_size is not None:
                gmsh.option.setNumber("Mesh.MeshSizeMax", p.mesh_size)
            gmsh.option.setNumber("Mesh.Optimize", 1)
            try:
                gmsh.model.mesh.generate(3 if any(d == 3 for d, _ in groups.values()) else 2)
            except Exception as exc:
                raise InputError(f"{path}: gmsh cannot mesh it ({' '.join(str(exc).split())})") from None
        n_tets = sum(len(t) for t in gmsh.model.mesh.getElements(3)[1])
        limit = _occ._ELEMENT_LIMIT.get()
        if limit is not None and n_tets > limit[0]:
            raise ResourceError(f"{limit[1]}: {path.name} meshed into {n_tets} tetrahedra, beyond the limit of "
                                f"{limit[0]:.3g}; use a larger mesh_size or raise [model] max_elements")
        vols, areas, centroids = _mesh_measures(gmsh, groups)
        patches = []
        for name, pt in p.points.items():
            dim, tag = groups[pt["group"]]
            at = pt.get("at")
            ref = np.asarray(at if at is not None else centroids[pt["group"]], float)
            if pt.get("tie", "rigid") == "rigid":
                if pt["group"] != name:     # the spider's group carries the point's name (meshes.spec.Patch)
                    if name in groups:
                        raise InputError(f"{path.name}: point {name!r} ties group {pt['group']!r}, but the file has "
                                         f"another group named {name!r}: name the point after its group")
                    _occ.add_physical(dim, name, list(gmsh.model.getEntitiesForPhysicalGroup(dim, tag)))
                patches.append(Patch(name, ref))
            else:
                patches.append(Patch(name, ref, nodes=pt["group"]))
        gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
        n_nodes = len(gmsh.model.mesh.getNodes()[0])
        msh = out_dir / f"{p.name}.msh"
        with atomic_path(msh, suffix=".msh") as tmp:
            gmsh.write(str(tmp))
    masses = [PointMass(n, m["point"], m["mass"], np.asarray(m.get("inertia", np.zeros((3, 3))), float))
              for n, m in p.masses.items()]
    liquids = {g: Liquid(**spec) for g, spec in p.liquids.items()}
    geo = Geometry(p.name, str(msh), dict(p.materials), patches, masses, [], list(p.clamped),
                   {g: v for g, v in vols.items()}, n_nodes, areas, dict(p.shells), {}, liquids)
    geo.save(out_dir / f"{p.name}.json")
    return geo
