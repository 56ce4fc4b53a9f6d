"""Hydroelastic liquid: an incompressible, inviscid liquid in a tank as an added-mass
operator on the wall's DOFs, applied by one sparse fluid solve (issue 10; DESIGN.md).

Small motion about rest, p the liquid's perturbation pressure, n the liquid's outward
normal, u the wall displacement on the wetted surface (Morand & Ohayon, Fluid-Structure
Interaction, Wiley 1995, ch. 5, the "incompressible liquid, p = 0 free surface" limit):

    lap p = 0 in the liquid,   p = 0 on the free surface,   dp/dn = -rho u''.n on the wall   (1)

Galerkin with P_k pressure shape functions N_i (k = 1 or 2, on the liquid's tetrahedra)
and the wall's translations interpolated in a P_c vector space psi_j on the same mesh
(the *coupling space*; its nodes on the wetted faces are nodes of the structure):

    H p = -rho G u'',   H_ij = int grad N_i . grad N_j dV,   G_ij = int_wet N_i psi_j.n dS   (2)

(coded with H/rho in place of H, so that several liquids of different densities, in
separate regions, share one operator and one factor)

(rows and columns of the free-surface pressure DOFs removed). The pressure load on the wall
is f = G^T p, so the structure sees the **added mass**

    M_a = rho G^T H^-1 G,     (M + M_a) x'' + K x = f_ext                                 (3)

symmetric positive semi-definite. It is never formed: M_a x is one solve with the MUMPS
Cholesky factor of H (factored once). A set of vectors X is one multi-right-hand-side
solve (X^T M_a X = rho (G X)^T H^-1 (G X)), so a Craig-Bampton mass Psi^T (M + M_a) Psi
costs one solve. On a coarse mesh the discrete M_a is below the exact one (the Galerkin
pressure minimises the liquid's energy functional over a subspace).

Recovery rows (linear in the model's DOFs; the transient multiplies them by q, q''):

* pressure at a liquid node x_k (the tank bottom), from the accelerations:
  p_k = e_k^T p = -rho (H^-1 e_k)^T G x''  (one solve per point, H symmetric);       (4)
  a uniform apparent acceleration a (gravity: a = -g) of the tank is the rigid translation
  field x'' = RB_t a in (4); for a flat free surface it gives the hydrostatic head
  rho |a| (z_free - z_k) exactly (p linear in z is in every P_k space);
* volume change of a closed cavity (the ullage's, the liquid being incompressible):
  dV = int_cavity u . n_c dS, n_c out of the cavity (away from ``center``)             (5)
  summed over the cavity wall's flat triangles with the rule exact for P1 (vertices) or
  P2 (edge midpoints) displacements.

The gravity free surface (slosh) and compressibility are not in (1): p = 0 is the
high-frequency limit, right for the wall's bulge modes (several Hz) above the slosh modes
(below 1 Hz for metre-size tanks). The operator is serial: under MPI every process holds the
whole liquid (small beside the structure; fem.model). Units SI (m, kg, Pa, m^3).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
from petsc4py import PETSc

from liftoff.core.errors import InputError

from . import petsc_backend as pb


@dataclass
class LiquidOperator:
    """The liquid(s) of a mesh, factored (module docstring, eq. 2-4): one compartment or
    several (block-diagonal H, one density each).

    ``G`` maps the coupling space's wetted DOFs (``c_coords``, ``c_comp``) to the kept
    pressure DOFs; after :meth:`couple`, ``Gm`` maps the structure's DOFs."""

    name: str
    density: dict                  # liquid volume group -> kg/m^3
    G: sp.csr_matrix               # (n_p, n_c) m^2
    H: PETSc.Mat                   # (n_p, n_p) kept pressure DOFs of int grad N_i . grad N_j / rho dV
    ksp: PETSc.KSP                 # MUMPS Cholesky factor of H
    p_coords: np.ndarray           # (n_p, 3) m
    c_coords: np.ndarray           # (n_c, 3) m: coupling DOF positions (on the wetted faces)
    c_comp: np.ndarray             # (n_c,) 0, 1, 2 = x, y, z
    volume: float                  # m^3, of the meshed liquid
    centroid: np.ndarray           # (3,) m, of the meshed liquid
    mass: float                    # kg, of the meshed liquid
    volumes: dict = field(default_factory=dict)  # liquid volume group -> meshed volume m^3
    points: dict = field(default_factory=dict)   # pressure point name -> kept pressure DOF
    Gm: sp.csr_matrix | None = None              # (n_p, n_dof) after couple()
    Hs: sp.csr_matrix | None = None              # H as scipy CSR (for reduction.liquid.LiquidMass)
    groups: tuple = ()                           # liquid volume groups, in volume_ids order
    p_group: np.ndarray | None = None            # (n_p,) index into groups of each kept pressure DOF
    free: "FreeSurface | None" = None            # the free surface's pressure DOFs (fem.slosh)
    centroids: dict = field(default_factory=dict)  # liquid volume group -> (3,) m, of its meshed volume

    @property
    def n_p(self) -> int:
        return self.G.shape[0]

    # ---- solves ------------------------------------------------------------------------
    def solve(self, B: np.ndarray) -> np.ndarray:
        """H^-1 B for B (n_p,) or (n_p, k): one (multi-right-hand-side) solve of the factor."""
        B = np.asarray(B, float)
        one = B.ndim == 1
        B2 = B.reshape(self.n_p, -1)
        if B2.shape[1] == 0:
            return B2.copy()
        n = self.n_p
        Bp = PETSc.Mat().createDense((n, B2.shape[1]), array=np.asfortranarray(B2).copy(), comm=PETSc.COMM_SELF)
        Xp = Bp.duplicate()
        try:
            self.ksp.getPC().getFactorMatrix().matSolve(Bp, Xp)
            X = np.array(Xp.getDenseArray(), copy=True)
        finally:
            Bp.destroy()
            Xp.destroy()
        return X[:, 0] if one else X

    def _g(self, coupled: bool) -> sp.csr_matrix:
        if not coupled:
            return self.G
        if self.Gm is None:
            raise RuntimeError(f"liquid {self.name!r}: couple() it to a structure first")
        return self.Gm

    def apply(self, X: np.ndarray, coupled: bool = True) -> np.ndarray:
        """M_a X (eq. 3) for X (n, ) or (n, k) over the structure's DOFs (``coupled``) or the
        coupling space's columns: one solve."""
        G = self._g(coupled)
        return G.T @ self.solve(G @ np.asarray(X, float))

    def project(self, X: np.ndarray, coupled: bool = True) -> np.ndarray:
        """X^T M_a X (k x k), one multi-right-hand-side solve."""
        GX = self._g(coupled) @ np.asarray(X, float).reshape(self._g(coupled).shape[1], -1)
        Y = self.solve(GX)
        out = GX.T @ Y
        return 0.5 * (out + out.T)

    def pressure_rows(self, names=None) -> np.ndarray:
        """(n_points, n_dof) rows r_k with p_k = r_k . x'' (eq. 4, Pa per m/s^2)."""
        names = list(self.points) if names is None else list(names)
        E = np.zeros((self.n_p, len(names)))
        for j, nm in enumerate(names):
            if nm not in self.points:
                raise InputError(f"liquid {self.name!r} has no pressure point {nm!r} "
                                 f"(has: {', '.join(self.points) or 'none'})")
            E[self.points[nm], j] = 1.0
        return -(self._g(True).T @ self.solve(E)).T

    # ---- coupling to a structure ----------------------------------------------------------
    def couple(self, nodes: np.ndarray, T: sp.csr_matrix, tol: float | None = None) -> sp.csr_matrix:
        """Tie the coupling DOFs to the structure: ``nodes`` (n_nodes, 3) and the field map
        ``T`` (3 n_nodes x n_dof, nodal translations = T x). Every wetted coupling node must
        be a structure node (the liquid shares the wetted faces' nodes with the wall).
        Sets and returns Gm = G C (n_p x n_dof)."""
        from scipy.spatial import cKDTree

        nodes = np.asarray(nodes, float)
        if tol is None:
            span = float(np.ptp(np.vstack([nodes, self.c_coords]), axis=0).max()) if nodes.size else 1.0
            tol = 1e-7 * max(span, 1e-300)
        dist, idx = cKDTree(nodes).query(self.c_coords)
        bad = np.flatnonzero(dist > tol)
        if bad.size:
            raise InputError(f"liquid {self.name!r}: wetted node at {np.round(self.c_coords[bad[0]], 6).tolist()} m "
                             "is not a node of the structure (the liquid must share the wetted surface's nodes "
                             "with the wall)")
        C = sp.csr_matrix(T)[3 * idx + self.c_comp]
        self.Gm = sp.csr_matrix(self.G @ C)
        self.Gm.eliminate_zeros()
        return self.Gm

    def liquid_fields(self, volume_rows: dict) -> dict:
        """Keyword fields of ``reduction.liquid.LiquidMass`` (sparse H and G over the
        structure's DOFs, pressure points, the cavity volume rows {name: row})."""
        names = tuple(volume_rows)
        V = sp.csr_matrix(np.vstack([volume_rows[k] for k in names])) if names else \
            sp.csr_matrix((0, self._g(True).shape[1]))
        return dict(H=self.Hs, G=self._g(True), pressure_points=tuple(self.points),
                    pressure_dofs=np.array(list(self.points.values()), np.int64), volume_names=names,
                    volume_rows=V, mass=self.mass, centroid=self.centroid.copy(), liquids=self.groups,
                    pressure_liquid=self.p_group)

    def destroy(self) -> None:
        self.ksp.destroy()
        self.H.destroy()


@dataclass
class FreeSurface:
    """The pressure DOFs on the free surface(s) that the p = 0 model removes, kept for the
    gravity free-surface condition (fem.slosh): the blocks of the liquid's Laplacian between
    the kept DOFs (k) and these (f), the surface mass, and the wall coupling of these rows.
    All divided by each liquid's density, as LiquidOperator.H."""

    Hkf: sp.csr_matrix             # (n_p, n_f) m / (kg/m^3)
    Hff: sp.csr_matrix             # (n_f, n_f)
    Sff: sp.csr_matrix             # (n_f, n_f) int_fs N_i N_j dS / rho, m^2 / (kg/m^3)
    Gf: sp.csr_matrix              # (n_f, n_c) m^2: int_wet N_i psi_j.n dS of the surface DOFs
    coords: np.ndarray             # (n_f, 3) m
    group: np.ndarray              # (n_f,) index into LiquidOperator.groups
    pinned: np.ndarray             # (n_groups,) bool: the liquid also has p = 0 DOFs off its surface

    @property
    def n_f(self) -> int:
        return self.Hff.shape[0]


# ---- building -----------------------------------------------------------------------------
def _facets(tm, name: str, liquid: str, what: str) -> np.ndarray:
    tags = tm.surface_tags.get(name)
    if tags is None:
        raise InputError(f"liquid {liquid!r}: {what} {name!r} is not a physical surface of mesh {tm.path!r}")
    return np.asarray(tags.indices[tags.values == 1], np.int32)


def _factor(H: sp.csr_matrix, name: str) -> tuple[PETSc.Mat, PETSc.KSP]:
    """MUMPS Cholesky factor of the (SPD) kept block of H; InputError if it is singular."""
    A = pb.csr_matrix(PETSc.COMM_SELF, H.shape[0], H.shape[0], H.shape[0], H)
    A.setOption(PETSc.Mat.Option.SYMMETRIC, True)
    ksp = PETSc.KSP().create(PETSc.COMM_SELF)
    ksp.setOperators(A)
    pb._mumps_cholesky(ksp)
    try:
        ksp.setUp()
        F = ksp.getPC().getFactorMatrix()
        ok = F.getMumpsInfog(1) >= 0
    except PETSc.Error:
        ok = False
    if not ok:
        ksp.destroy()
        A.destroy()
        raise InputError(f"liquid {name!r}: the liquid's Laplacian is singular (a liquid region without a free "
                         "surface, p = 0)")
    return A, ksp


def _densities(tm, name: str, density) -> tuple[dict, object]:
    """{volume group: rho} and a DG0 function 1/rho on the liquid's cells."""
    from dolfinx import fem

    groups = dict(density) if isinstance(density, dict) else {g: density for g in tm.volume_ids}
    for g, rho in groups.items():
        if g not in tm.volume_ids:
            raise InputError(f"liquid {name!r}: {g!r} is not a liquid volume of mesh {tm.path!r} "
                             f"(has: {', '.join(tm.volume_ids) or 'none'})")
        if isinstance(rho, bool) or not isinstance(rho, (int, float, np.floating)) or not (np.isfinite(rho) and rho > 0):
            raise InputError(f"liquid {g if isinstance(density, dict) else name!r}: density {rho!r} kg/m^3 must be > 0")
    missing = [g for g in tm.volume_ids if g not in groups]
    if missing:
        raise InputError(f"liquid {name!r}: no density for liquid volume {missing[0]!r}")
    Q0 = fem.FunctionSpace(tm.mesh, ("DG", 0))
    inv = fem.Function(Q0)
    for g, gid in tm.volume_ids.items():
        inv.x.array[Q0.dofmap.list.array[tm.cell_tags.find(gid)]] = 1.0 / float(groups[g])
    return {g: float(r) for g, r in groups.items()}, inv


def _union(tm, names, name: str, what: str) -> np.ndarray:
    names = [names] if isinstance(names, str) else list(names)
    return np.unique(np.concatenate([_facets(tm, n, name, what) for n in names] + [np.zeros(0, np.int32)]))


def _check_each_region_fixed(H: sp.csr_matrix, fixed: np.ndarray, tm, Q, name: str) -> None:
    """Every connected region of the liquid holds some pressure at p = 0. The check over all
    liquids together let a region without a free surface of its own through (one liquid's
    free_surface naming a face of another, a compartment full to the top): its Laplacian is
    singular only up to round-off, which MUMPS factored, and its added mass came out at
    5e17 kg instead of 1000 kg (a review, 2026-12-07). InputError naming the region's liquid
    volume groups."""
    from scipy.sparse.csgraph import connected_components

    n_regions, region = connected_components(H, directed=False)
    held = np.zeros(n_regions, bool)
    held[region[fixed]] = True
    if held.all():
        return
    r = int(np.flatnonzero(~held)[0])
    cells_dofs = Q.dofmap.list.array.reshape(-1, Q.dofmap.dof_layout.num_dofs)
    groups = sorted(g for g, gid in tm.volume_ids.items()
                    if np.any(region[cells_dofs[tm.cell_tags.find(gid)]] == r))
    raise InputError(f"liquid {name!r}: the liquid region of volume group(s) {', '.join(groups) or '?'} has no "
                     f"free surface (p = 0) of its own, so its pressure is undetermined: give it a free_surface "
                     f"group on its own boundary (a compartment full to the top has none: leave ullage)")


def liquid_operator(tm, name: str, density, wetted, free_surface=None, dirichlet: np.ndarray | None = None,
                    degree: int = 1, coupling_degree: int = 1, points: dict | None = None) -> LiquidOperator:
    """Assemble and factor the liquid of ``tm`` (a fem.mesh.TaggedMesh of tetrahedra;
    eq. 2, with H_ij = int grad N_i . grad N_j / rho dV so that liquids of different
    densities share one operator: M_a = G^T H^-1 G, p = -H^-1 G x''): ``density`` (kg/m^3,
    or {liquid volume group: density}); pressure P_``degree``, wall translations
    P_``coupling_degree`` on the facets of the surface group(s) ``wetted``; p = 0 on the
    surface group(s) ``free_surface`` and/or at the pressure DOFs ``dirichlet`` (indices
    into the P_k space, e.g. a symmetry axis); ``points``: {name: (x, y, z)} pressure
    recovery points, each at a pressure DOF."""
    import ufl
    from dolfinx import fem
    from scipy.spatial import cKDTree

    if tm.mesh.comm.size > 1:
        raise InputError(f"liquid {name!r}: hydroelastic liquids run on one process (got {tm.mesh.comm.size})")
    if degree not in (1, 2) or coupling_degree not in (1, 2):
        raise InputError(f"liquid {name!r}: degrees must be 1 or 2 (got {degree}, {coupling_degree})")
    rho, inv_rho = _densities(tm, name, density)
    mesh = tm.mesh
    wet = _union(tm, wetted, name, "wetted surface")
    if wet.size == 0:
        raise InputError(f"liquid {name!r} does not touch the wall: its wetted surface {wetted!r} has no faces")
    Q = fem.FunctionSpace(mesh, ("CG", degree))
    p, q = ufl.TrialFunction(Q), ufl.TestFunction(Q)
    H = pb.gather_csr(pb.assemble_matrix(inv_rho * ufl.inner(ufl.grad(p), ufl.grad(q)) * ufl.dx))
    fixed = [] if dirichlet is None else [np.asarray(dirichlet, np.int64)]
    surface = np.zeros(0, np.int64)
    if free_surface is not None:
        fs_facets = _union(tm, free_surface, name, "free surface")
        surface = np.asarray(fem.locate_dofs_topological(Q, 2, fs_facets), np.int64)
        fixed.append(surface)
    fixed = np.unique(np.concatenate(fixed)) if fixed else np.zeros(0, np.int64)
    if fixed.size == 0:
        raise InputError(f"liquid {name!r} has no free surface (p = 0): its free surface "
                         f"{free_surface!r} has no faces")
    _check_each_region_fixed(H, fixed, tm, Q, name)
    keep = np.setdiff1d(np.arange(H.shape[0]), fixed)
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=dolfinx_meshtags(mesh, wet))(1)
    Vc = fem.VectorFunctionSpace(mesh, ("CG", coupling_degree))
    G = pb.gather_csr(pb.assemble_matrix(q * ufl.dot(ufl.TrialFunction(Vc), ufl.FacetNormal(mesh)) * ds))
    blocks = np.asarray(fem.locate_dofs_topological(Vc, 2, wet), np.int64)
    G = sp.csr_matrix(G[:, (3 * blocks[:, None] + np.arange(3)).ravel()])
    G.eliminate_zeros()
    free_dofs = np.setdiff1d(surface, np.zeros(0, np.int64) if dirichlet is None else np.asarray(dirichlet, np.int64))
    if free_dofs.size:
        dfs = ufl.Measure("ds", domain=mesh, subdomain_data=dolfinx_meshtags(mesh, fs_facets))(1)
        S = pb.gather_csr(pb.assemble_matrix(inv_rho * p * q * dfs))
        Gf = sp.csr_matrix(G[free_dofs])
    G = sp.csr_matrix(G[keep])
    Xc, Xp = Vc.tabulate_dof_coordinates(), Q.tabulate_dof_coordinates()[keep]
    x, dx = ufl.SpatialCoordinate(mesh), ufl.Measure("dx", domain=mesh, subdomain_data=tm.cell_tags)
    vols = {g: fem.assemble_scalar(fem.form(fem.Constant(mesh, 1.0) * dx(gid))) for g, gid in tm.volume_ids.items()}
    vol = sum(vols.values())
    mass = sum(rho[g] * v for g, v in vols.items())
    cg = np.array([fem.assemble_scalar(fem.form(x[i] / inv_rho * ufl.dx)) for i in range(3)]) / mass
    cgs = {g: np.array([fem.assemble_scalar(fem.form(x[i] * dx(gid))) for i in range(3)]) / vols[g]
           for g, gid in tm.volume_ids.items()}
    Hk, ksp = _factor(sp.csr_matrix(H[keep][:, keep]), name)
    pts = {}
    if points:
        tree, scale = cKDTree(Xp), float(np.ptp(Xp, axis=0).max())
        for nm, xyz in points.items():
            d, i = tree.query(np.asarray(xyz, float))
            if d > 1e-6 * scale:
                raise InputError(f"liquid {name!r}: pressure point {nm!r} at {np.round(xyz, 6).tolist()} m is not a "
                                 "node of the liquid mesh (or lies on its free surface, p = 0)")
            pts[nm] = int(i)
    groups = tuple(tm.volume_ids)
    p_group = np.zeros(Q.dofmap.index_map.size_local * Q.dofmap.index_map_bs, np.int64)
    for k, gid in enumerate(tm.volume_ids.values()):          # a pressure DOF belongs to one liquid
        p_group[np.unique(Q.dofmap.list.array.reshape(-1, Q.dofmap.dof_layout.num_dofs)[tm.cell_tags.find(gid)])] = k
    free = None
    if free_dofs.size:
        f_group = p_group[free_dofs]
        pinned = np.array([np.any(p_group[np.setdiff1d(fixed, free_dofs)] == k) for k in range(len(groups))], bool)
        free = FreeSurface(sp.csr_matrix(H[keep][:, free_dofs]), sp.csr_matrix(H[free_dofs][:, free_dofs]),
                           sp.csr_matrix(S[free_dofs][:, free_dofs]), Gf,
                           Q.tabulate_dof_coordinates()[free_dofs].copy(), f_group, pinned)
    return LiquidOperator(name, rho, G, Hk, ksp, Xp, np.repeat(Xc[blocks], 3, axis=0), np.tile(np.arange(3), blocks.size),
                          float(vol), cg, float(mass), vols, pts, Hs=sp.csr_matrix(H[keep][:, keep]), groups=groups,
                          p_group=p_group[keep], free=free, centroids=cgs)


def dolfinx_meshtags(mesh, facets: np.ndarray, value: int = 1):
    """MeshTags over the facets (dim 2), all ``value``."""
    from dolfinx import mesh as dmesh

    f = np.unique(np.asarray(facets, np.int32))
    return dmesh.meshtags(mesh, 2, f, np.full(f.size, value, np.int32))


def rigid_translation(op: LiquidOperator, direction) -> np.ndarray:
    """The coupling-space vector of a rigid translation of the wall along ``direction``."""
    return np.asarray(direction, float)[op.c_comp]


# ---- cavity volume (eq. 5) ------------------------------------------------------------------
def surface_triangles(tm, name: str) -> np.ndarray:
    """(n_tri, 3, 3) vertex coordinates (m) of the 2-D entities of surface group ``name``
    (tet facets of a solid part, or triangles of a shell part)."""
    tags = tm.surface_tags.get(name)
    if tags is None:
        raise InputError(f"surface {name!r} is not a physical surface of mesh {tm.path!r}")
    ents = np.asarray(tags.indices[tags.values == 1], np.int32)
    mesh = tm.mesh
    tdim = mesh.topology.dim
    nv = tdim + 1                                       # vertices per (simplex) cell
    mesh.topology.create_connectivity(tdim, 0)
    c2v = mesh.topology.connectivity(tdim, 0).array.reshape(-1, nv)
    geo = np.asarray(mesh.geometry.dofmap.array).reshape(c2v.shape[0], -1)[:, :nv]   # vertices first
    v2x = np.zeros(int(c2v.max()) + 1 if c2v.size else 0, np.int64)
    v2x[c2v.ravel()] = geo.ravel()
    if tdim == 2:
        verts = c2v[ents]
    else:
        mesh.topology.create_connectivity(2, 0)
        verts = mesh.topology.connectivity(2, 0).array.reshape(-1, 3)[ents]
    return mesh.geometry.x[v2x[verts]].reshape(-1, 3, 3)


def cavity_volume_row(tris: np.ndarray, center, nodes: np.ndarray, T: sp.csr_matrix,
                      what: str = "cavity") -> np.ndarray:
    """Row r (n_dof,) with dV = r . x (eq. 5) over the flat triangles ``tris`` (n, 3, 3),
    normals away from ``center`` (a point inside the convex cavity); nodes/T as in
    LiquidOperator.couple. Uses the edge midpoints (exact for P2) when they are nodes, else
    the vertices (exact for P1)."""
    from scipy.spatial import cKDTree

    tris = np.asarray(tris, float)
    if tris.shape[0] == 0:
        raise InputError(f"{what}: the cavity surface has no triangles")
    a = 0.5 * np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    out = np.einsum("ij,ij->i", a, tris.mean(axis=1) - np.asarray(center, float)) < 0
    a[out] *= -1.0
    tree = cKDTree(nodes)
    tol = 1e-7 * float(np.ptp(nodes, axis=0).max())
    mids = 0.5 * (tris + tris[:, [1, 2, 0]])
    dm, im = tree.query(mids.reshape(-1, 3))
    if np.all(dm <= tol):
        idx = im
    else:
        dv, idx = tree.query(tris.reshape(-1, 3))
        if np.any(dv > tol):
            raise InputError(f"{what}: a cavity triangle's vertex is not a node of the structure")
    w = np.repeat(a / 3.0, 3, axis=0)                      # (3 n_tri, 3): area vector / 3 per node
    rows = (3 * np.asarray(idx)[:, None] + np.arange(3)).ravel()
    coef = sp.csr_matrix((w.ravel(), (np.zeros(rows.size, np.int64), rows)), shape=(1, T.shape[0]))
    return np.asarray((coef @ T).todense()).ravel()


# ---- M + M_a as a PETSc operator ------------------------------------------------------------------
class _MassWithLiquid:
    """PETSc shell context: y = M x + sum_l rho_l G_l^T H_l^-1 G_l x[dofs] (eq. 3)."""

    def __init__(self, M: PETSc.Mat, ops: list, dofs: np.ndarray | None):
        self.M, self.ops = M, ops
        self.G = [sp.csr_matrix(op.Gm if dofs is None else op.Gm[:, dofs]) for op in ops]   # sliced once

    def mult(self, mat, x, y):
        self.M.mult(x, y)
        xa = x.getArray(readonly=True)
        acc = np.zeros(xa.size)
        for op, G in zip(self.ops, self.G):
            acc += G.T @ op.solve(G @ xa)
        y.axpy(1.0, PETSc.Vec().createWithArray(acc, comm=PETSc.COMM_SELF))


def mass_with_liquid(M: PETSc.Mat, ops: list, dofs: np.ndarray | None = None) -> PETSc.Mat:
    """M + sum M_a (eq. 3) as a PETSc shell matrix (serial); ``dofs``: the structure DOFs
    that M's rows are (e.g. the interior DOFs of a Craig-Bampton component), None = all."""
    n = M.getSize()[0]
    ctx = _MassWithLiquid(M, list(ops), None if dofs is None else np.asarray(dofs, np.int64))
    A = PETSc.Mat().createPython(((n, n), (n, n)), ctx, comm=PETSc.COMM_SELF)
    A.setOption(PETSc.Mat.Option.SYMMETRIC, True)
    A.setUp()
    return A


class _DistributedWetMass:
    """PETSc shell context over a distributed M_ii: y = M_ii x + G_i^T H^-1 G_i x, the
    liquid part computed on every process from the gathered x (the liquid's H is factored
    on each process: it is small beside the structure) and each process keeping its rows."""

    def __init__(self, Mii: PETSc.Mat, H: sp.spmatrix, Gi: sp.spmatrix):
        self.M, self.Gi = Mii, sp.csr_matrix(Gi)
        self.A, self.ksp = _factor(sp.csr_matrix(H), "liquid")
        self.comm = Mii.getComm().tompi4py()
        self.r0, self.r1 = Mii.getOwnershipRange()

    def _liquid(self, X: np.ndarray) -> np.ndarray:
        """This process's rows of G_i^T H^-1 G_i X for a dense block X (its rows here): the
        liquid's solves as one multi-right-hand-side solve of its factor."""
        from .petsc_cb import _factor_solve, gather_rows

        GX = np.asarray(self.Gi @ gather_rows(self.comm, X))
        return (self.Gi.T @ _factor_solve(self.ksp, GX, GX.shape[0]))[self.r0:self.r1]

    def mult(self, mat, x, y):
        self.M.mult(x, y)
        add = self._liquid(np.array(x.getArray(readonly=True))[:, None])[:, 0]
        y.setArray(np.array(y.getArray(readonly=True)) + add)

    def mult_block(self, X: np.ndarray) -> np.ndarray:
        """This process's rows of (M_ii + G_i^T H^-1 G_i) X for a dense block X (its rows here)."""
        from .petsc_cb import _mat_block

        return _mat_block(self.M, X) + self._liquid(X)

    def destroy(self, mat=None) -> None:       # PETSc calls it when the shell matrix is destroyed
        self.ksp.destroy()
        self.A.destroy()


def wet_mass(Mii: PETSc.Mat, H: sp.spmatrix, Gi: sp.spmatrix) -> tuple[PETSc.Mat, object]:
    """M_ii + G_i^T H^-1 G_i as a PETSc shell matrix with M_ii's (distributed) layout, for
    any process count (reduction.liquid.LiquidMass's H and G restricted to the interior
    columns); returns (shell, context); destroying the shell frees the liquid's factor."""
    ctx = _DistributedWetMass(Mii, H, Gi)
    (m, n), (M_, N_) = Mii.getLocalSize(), Mii.getSize()
    B = PETSc.Mat().createPython(((m, M_), (n, N_)), ctx, comm=Mii.getComm())
    B.setOption(PETSc.Mat.Option.SYMMETRIC, True)
    B.setUp()
    return B, ctx


def wet_eigensolve(K: PETSc.Mat, M: PETSc.Mat, ops: list, n_modes: int, dofs: np.ndarray | None = None,
                   tol: float = 1e-10, max_it: int = 500, what: str = "model") -> tuple[np.ndarray, np.ndarray]:
    """The ``n_modes`` lowest eigenpairs of K phi = lambda (M + M_a) phi for a K that is
    positive definite (a clamped model or the fixed-interface block of a component):
    SLEPc Krylov-Schur, shift-invert at sigma = 0 with a MUMPS Cholesky factor of K, the
    mass applied as a shell operator (mass_with_liquid: one fluid solve per product).
    Returns (lambda ascending, Phi with Phi^T (M + M_a) Phi = I), serial."""
    from slepc4py import SLEPc


    B = mass_with_liquid(M, ops, dofs)
    eps = SLEPc.EPS().create(PETSc.COMM_SELF)
    try:
        eps.setOperators(K, B)
        eps.setProblemType(SLEPc.EPS.ProblemType.GHEP)
        n = K.getSize()[0]
        eps.setDimensions(n_modes, min(n, max(2 * n_modes + 1, n_modes + 24)), PETSc.DECIDE)
        eps.setType(SLEPc.EPS.Type.KRYLOVSCHUR)
        st = eps.getST()
        st.setType(SLEPc.ST.Type.SINVERT)
        st.setShift(0.0)
        st.setMatMode(SLEPc.ST.MatMode.INPLACE)
        pb._mumps_cholesky(st.getKSP())
        eps.setTarget(0.0)
        eps.setWhichEigenpairs(SLEPc.EPS.Which.TARGET_MAGNITUDE)
        eps.setTolerances(tol, max_it)
        eps.setPurify(False)
        try:
            eps.solve()
        except PETSc.Error as exc:
            raise InputError(f"{what}: the wet eigensolve failed to factor K (PETSc error {exc.ierr}): "
                             "K is singular (a floating part, or a free-free model: clamp it or reduce it)") from None
        from .petsc_cb import solved_pairs

        return solved_pairs(eps, B, n_modes, f"{what}: SLEPc (wet modes)")
    finally:
        eps.destroy()
        B.destroy()




def count_below_wet(comm, Kii: sp.spmatrix, Mii: sp.spmatrix, Gi: sp.spmatrix, H: sp.spmatrix, lam: float,
                    who: str = "component") -> int:
    """Number of eigenvalues mu <= ``lam`` of K_ii x = mu (M_ii + G_i^T H^-1 G_i) x, by
    Sylvester's law of inertia without forming M_a: the sparse symmetric matrix

        A = [[K_ii - lam M_ii, G_i^T], [G_i, H / lam]]

    has the Schur complement K_ii - lam (M_ii + G_i^T H^-1 G_i) of its positive definite
    (2,2) block, so (Haynsworth) its negative and null pivots are that complement's: one
    MUMPS LDL^T factor of A (``comm``: rows split evenly). H here is the liquid's Laplacian
    already divided by rho (reduction.liquid.LiquidMass.H), G_i its coupling over the
    interior DOFs."""
    if not lam > 0:
        raise InputError(f"{who}: the wet mode count needs a positive eigenvalue bound (got {lam!r})")
    A = sp.bmat([[sp.csr_matrix(Kii) - lam * sp.csr_matrix(Mii), sp.csr_matrix(Gi).T],
                 [sp.csr_matrix(Gi), sp.csr_matrix(H) / lam]], format="csr")
    from .petsc_cb import nonpositive_pivots, row_range

    n = A.shape[0]
    r0, r1 = row_range(comm, n)
    Ap = pb.csr_matrix(comm, r1 - r0, r1 - r0, n, A[r0:r1])
    try:
        Ap.setOption(PETSc.Mat.Option.SYMMETRIC, True)
        return nonpositive_pivots(Ap, "the wet count matrix", who)
    finally:
        Ap.destroy()


# ---- a model's liquids ----------------------------------------------------------------------------
def _cad_ratio(tm, geometry, group: str) -> float:
    """CAD volume / meshed volume of a liquid group (1 without a CAD volume): the density is
    scaled by it so that the meshed liquid carries the liquid's exact mass (the faceted
    mesh of a curved tank holds a little less volume than the CAD cavity)."""
    import ufl
    from dolfinx import fem

    cad = geometry.group_volumes.get(group)
    if not cad:
        return 1.0
    dx = ufl.Measure("dx", domain=tm.mesh, subdomain_data=tm.cell_tags)
    v = fem.assemble_scalar(fem.form(fem.Constant(tm.mesh, 1.0) * dx(tm.volume_ids[group])))
    return float(cad) / float(v) if v > 0 else 1.0


def geometry_liquid_operator(tm, geometry, degree: int = 1, coupling_degree: int = 1) -> LiquidOperator:
    """The liquids of a ``meshes.spec.Geometry`` as one operator (uncoupled), each with its
    density scaled to carry the CAD volume's mass (:func:`_cad_ratio`)."""
    liquids = geometry.liquids
    points, owner = {}, {}
    for g, liq in liquids.items():
        for n, xyz in liq.points.items():
            if n in points:         # one name, one pressure history: a second would replace the first
                raise InputError(f"geometry {geometry.name!r}: pressure point {n!r} is named in liquids "
                                 f"{owner[n]!r} and {g!r}: give each liquid's points their own names")
            points[n], owner[n] = xyz, g
    density = {g: liq.density * _cad_ratio(tm, geometry, g) for g, liq in liquids.items()}
    return liquid_operator(tm, f"{geometry.name} liquids", density,
                           [liq.wetted for liq in liquids.values()], [liq.free_surface for liq in liquids.values()],
                           None, degree, coupling_degree, points)


def model_liquid(tm, geometry, parts, nodes: np.ndarray, T: sp.csr_matrix, coupling_degree: int,
                 degree: int = 1, slosh: bool = False) -> tuple[LiquidOperator, dict]:
    """The liquids of a ``meshes.spec.Geometry`` (its ``liquids``: one operator for all, each
    with its density scaled to carry the CAD volume's mass, :func:`_cad_ratio`), coupled to
    the structure's ``nodes`` and field map ``T``; and the
    volume-change row (eq. 5) of each liquid's cavity, {liquid group: row}, from the
    cavity's triangles on the structural ``parts`` (solid facets or shell cells)."""
    liquids = geometry.liquids
    for g, liq in liquids.items():
        if liq.slosh_modes and not slosh:
            raise InputError(f"liquid {g!r}: slosh_modes = {liq.slosh_modes} needs the slosh pendulums "
                             "(convective = 'slosh', docs/hydro.md); use 0 with 'wall' or 'free'")
        if g not in tm.volume_ids:
            raise InputError(f"liquid {g!r} is not a physical volume of mesh {tm.path!r}")
        if liq.wetted not in tm.surface_tags or not np.any(tm.surface_tags[liq.wetted].values == 1):
            raise InputError(f"liquid {g!r} does not touch the wall: no face of its wetted surface {liq.wetted!r} "
                             "lies on the liquid")
    op = geometry_liquid_operator(tm, geometry, degree, coupling_degree)
    op.couple(nodes, T)
    rows = {}
    for g, liq in liquids.items():
        if liq.cavity is None:
            continue
        tris = [surface_triangles(p.tagged, liq.cavity) for p in parts if liq.cavity in p.tagged.surface_tags]
        comm = parts[0].tagged.mesh.comm
        if comm.size > 1:                   # each process has its own triangles of a distributed wall,
            tris = [t for ts in comm.allgather(tris) for t in ts]
            if tris:                        # and ghost cells repeat some: keep one of each
                allt = np.vstack(tris)
                _, first = np.unique(np.round(allt.mean(axis=1), 9), axis=0, return_index=True)   # centroids
                tris = [allt[np.sort(first)]]
        if not tris:
            raise InputError(f"liquid {g!r}: cavity surface {liq.cavity!r} is not a physical surface of the structure")
        rows[g] = cavity_volume_row(np.vstack(tris), liq.center, nodes, T, f"liquid {g!r}")
    return op, rows


def _exp_weights(a: np.ndarray, z: np.ndarray, z_target: float, what: str) -> np.ndarray:
    """Positive weights a_i exp(k z_i), sum 1, whose weighted mean of z is ``z_target`` (k by
    bisection; the mean is increasing in k)."""
    lo_z, hi_z = float(z.min()), float(z.max())
    if not lo_z < z_target < hi_z:
        raise InputError(f"{what}: the convective mass's height {z_target:.4g} m lies outside its wetted wall "
                         f"({lo_z:.4g} .. {hi_z:.4g} m)")
    zs = (z - lo_z) / (hi_z - lo_z)
    t = (z_target - lo_z) / (hi_z - lo_z)

    def mean(k):
        e = a * np.exp(k * (zs - 1.0 if k > 0 else zs))
        return e / e.sum()

    lo, hi = -800.0, 800.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if mean(mid) @ zs < t else (lo, mid)
    return mean(0.5 * (lo + hi))


def wetted_nodes(tm, liq, g: str, nodes: np.ndarray, tree=None) -> tuple[np.ndarray, np.ndarray]:
    """(structure node indices, nodal wetted area m^2) of liquid ``g``'s wetted surface
    (``liq.wetted``: its flat triangles' vertices, each a third of the triangle's area)."""
    from scipy.spatial import cKDTree

    tree = cKDTree(nodes) if tree is None else tree
    tris = surface_triangles(tm, liq.wetted)
    area = np.repeat(0.5 * np.linalg.norm(np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0]), axis=1) / 3, 3)
    dist, idx = tree.query(tris.reshape(-1, 3))
    if np.any(dist > 1e-7 * float(np.ptp(nodes, axis=0).max())):
        raise InputError(f"liquid {g!r}: a wetted vertex is not a node of the structure")
    node, inv = np.unique(idx, return_inverse=True)
    return node, np.bincount(inv, weights=area)


def convective_mass(op: LiquidOperator, tm, geometry, nodes: np.ndarray, T: sp.csr_matrix,
                    rb: np.ndarray, carried: dict | None = None) -> sp.csr_matrix:
    """Lateral (x, y) lumped mass M_c on each liquid's wetted nodes that carries the part of
    the liquid the p = 0 model leaves free laterally (its convective, sloshing part), with
    the first moment that puts the liquid's rigid-body mass and c.g. where a rigid liquid
    would: for liquid c (axis along z), RB^T (M_a,c + M_c,c) RB has the translational masses
    m_c and the lateral first moments m_c z_c (z_c the liquid's centroid). Weights
    w_i = A_i e^{k z_i} (A_i the nodal wetted area, k such that the weights' mean height is
    the deficit's), positive; M_c = T_x^T W T_x + T_y^T W T_y. The slosh-frequency-to-infinity
    limit for the convective part (the smeared model's assumption for the whole liquid);
    ``rb``: the model DOFs' rigid-body shape about the origin (n_dof, 6); ``carried``:
    {liquid group: ((m_x, m_x z_x), (m_y, m_y z_y))} of the convective part that something
    else already carries (the slosh pendulums of fem.slosh), left out of the lumped mass."""
    from scipy.spatial import cKDTree

    out = sp.csr_matrix((T.shape[1], T.shape[1]))
    GR = op.Gm @ rb[:, [0, 1, 3, 4]]
    Y = op.solve(GR)
    tree = cKDTree(nodes)
    for c, g in enumerate(op.groups):
        liq = geometry.liquids[g]
        on = (op.p_group == c).astype(float)[:, None]
        Mi = (on * GR).T @ Y                              # impulsive: [Tx, Ty, Rx, Ry] block of liquid c
        zc = float(op.centroids[g][2])                    # the meshed liquid's centroid and volume (liquid_operator)
        m = op.density[g] * op.volumes[g]
        node, a = wetted_nodes(tm, liq, g, nodes, tree)
        have = (carried or {}).get(g, ((0.0, 0.0), (0.0, 0.0)))
        # per direction: the convective part and its first moment (Tx-Ry: + sum m z, Ty-Rx: - sum m z)
        for k, (dm, ds) in enumerate(((m - Mi[0, 0], m * zc - Mi[0, 3]), (m - Mi[1, 1], m * zc + Mi[1, 2]))):
            dm, ds = dm - have[k][0], ds - have[k][1]
            if dm <= 1e-9 * m:
                continue
            w = dm * _exp_weights(a, nodes[node, 2], ds / dm, f"liquid {g!r}")
            Tk = sp.csr_matrix(T)[3 * node + k]
            out = out + Tk.T @ sp.diags(w) @ Tk
    return sp.csr_matrix(out)


__all__ = ["LiquidOperator", "FreeSurface", "liquid_operator", "geometry_liquid_operator", "rigid_translation", "surface_triangles", "cavity_volume_row",
           "mass_with_liquid", "wet_eigensolve", "model_liquid", "count_below_wet", "wet_mass",
           "convective_mass", "wetted_nodes"]
