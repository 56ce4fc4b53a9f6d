"""Checks a loads engineer runs on every Craig-Bampton model (after pyyeti's ``cbcheck``):
symmetry, definiteness, geometric rigid-body check (K_B RB = 0), mass / c.g. / inertia from
M_B against the FE model, modal effective mass of the fixed-interface modes, free-free
frequencies of the CB model against the full FE model. Numerical kernel: no I/O.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse.linalg as spla

from liftoff.core.labels import COMPONENTS
from liftoff.core.rigid import cg_mass, nodal_rb, rb_rows

from .component import Component
from .craig_bampton import CBModel
from .system import MASSLESS_TOL, eigh_massless

RB_TOL = 1e-6       # relative residual |K RB| / (|K| |RB|) accepted as rigid (round-off ~1e-12)
DENSE_FE_LIMIT = 2000   # full FE models up to this size are eigensolved densely, else eigsh


@dataclass
class CBCheck:
    summary: dict       # JSON-able numbers and pass flags
    text: str           # readable report


def _rel_asym(A: np.ndarray) -> float:
    return float(np.abs(A - A.T).max() / max(np.abs(A).max(), 1e-300))


def _rb_residual(K, rb, k_scale=None) -> np.ndarray:
    kn = float(abs(K).sum(axis=1).max()) if k_scale is None else k_scale
    return np.linalg.norm(K @ rb, axis=0) / (max(kn, 1e-300) * np.maximum(np.linalg.norm(rb, axis=0), 1e-300))


def stiffness_scale(cb: CBModel) -> float:
    """Stiffness scale of a CB model: |K_B| or, when K_B is (near) zero as for a
    statically determinate interface, omega_max^2 x the largest boundary mass term."""
    kb = float(np.abs(cb.K_B).sum(axis=1).max())
    if cb.n_eigenmodes:                          # (residual vectors lie far above them)
        kb = max(kb, float(cb.fixed_omega[:cb.n_eigenmodes].max() ** 2 * np.abs(np.diag(cb.M_B)).max()))
    return kb


def with_own_inertia(asm, name: str, component: Component, cb: CBModel):
    """``asm`` with the rigid-body inertia loads and mass of component ``name`` from its own
    physical rigid-body field r (:func:`full_rb`, about the origin): T^T M r over its CB DOFs
    (CBModel.generalized_load) and r^T M r (reduction.system.rigid_inertia). For a grounded
    component, clamped inside its interior, the boundary's geometric RB is not that field's image
    (its constraint modes die out at the clamp): the default launch table's gravity load and mass
    came out 1250 t in z against its 3852 t. ``asm``: an assembly of that component alone;
    returned as it is where there is no FE component or the CB model has no recovery arrays (a
    Nastran import: the boundary's geometric RB stays, docs/workflow.md says so)."""
    from dataclasses import replace

    if component is None or cb.fixed_interface_modes is None or cb.constraint_modes is None:
        return asm
    if len(asm.components) != 1:
        raise ValueError(f"assembly {asm.name!r}: the own-inertia loads are those of a one-component assembly")
    r, _ = full_rb(component, cb, np.zeros(3))
    Mr = component.M @ r
    return replace(asm, inertia=asm.scatter(name, cb.generalized_load(Mr)), rigid_mass=r.T @ Mr)


def full_rb(component: Component, cb: CBModel, ref) -> tuple[np.ndarray, str]:
    """Geometric rigid-body shape of all component DOFs, built independently of the CB
    model where the component allows: labelled DOFs from point coordinates, others from
    the mesh nodes through single-entry rows of field_map; any DOF left gets T_c RB_b."""
    n = component.n_dof
    rb = np.full((n, 6), np.nan)
    rb[component.label_dofs] = rb_rows(component.dof_labels, component.points, component.point_coords, ref)
    if component.nodes is not None and component.field_map is not None:
        F = component.field_map.tocsr()
        nnz = np.diff(F.indptr)
        single = np.flatnonzero(nnz == 1)
        cols = F.indices[F.indptr[single]]
        ok = np.isclose(F.data[F.indptr[single]], 1.0)
        node_rb = nodal_rb(component.nodes, ref)
        unset = np.isnan(rb[cols[ok], 0])
        rb[cols[ok][unset]] = node_rb[single[ok][unset]]
    missing = np.isnan(rb[:, 0])
    if not missing.any():
        return rb, "geometry"
    if cb.constraint_modes is None:
        return None, "unavailable (no recovery arrays)"
    rb_b = rb_rows(cb.boundary_labels, cb.points, cb.point_coords, ref)
    rb[missing] = (cb.constraint_modes @ rb_b)[missing]
    if missing.all():
        return rb, "constraint modes x boundary RB (not independent)"
    return rb, f"geometry, constraint modes for {int(missing.sum())} DOFs"


def cb_check(cb: CBModel, component: Component | None = None, ref_point=None,
             n_freefree: int = 12, own_mass: np.ndarray | None = None) -> CBCheck:
    """Check report of a CB model. ``ref_point`` (m) defaults to the first boundary point;
    with ``component`` (the FE model it came from) FE mass properties and free-free
    frequencies are compared. ``own_mass``: a grounded component's own rigid-body mass
    (6 x 6 about ``ref_point``: Assembly.rigid_mass moved, reduction.system.rigid_inertia),
    whose boundary is no rigid-body support: its rigid-body check does not apply, and M_B is
    the mass its boundary carries with the clamp held, not its own."""
    nq = cb.n_modes
    ref = cb.point_coord(cb.boundary_points[0]) if ref_point is None else np.asarray(ref_point, float)
    s: dict = {"name": cb.name, "n_modes": nq, "n_residual": cb.n_residual, "n_boundary": cb.n_boundary,
               "ref_point": list(map(float, ref)), "units": "SI (kg, m, kg m^2, Hz)"}
    s["M_asymmetry"], s["K_asymmetry"] = _rel_asym(cb.M), _rel_asym(cb.K)
    m_eig = sla.eigvalsh(0.5 * (cb.M + cb.M.T))         # PSD is enough: massless DOFs are condensed below
    kb_eig = sla.eigvalsh(0.5 * (cb.K_B + cb.K_B.T))
    s["M_min_eig_rel"] = float(m_eig[0] / m_eig[-1])
    k_scale = stiffness_scale(cb)
    s["K_B_min_eig_rel"] = float(kb_eig[0] / k_scale) if k_scale > 0 else 0.0    # 0: no stiffness (a rigid mass)
    s["K_B_n_zero_eig"] = int(np.sum(np.abs(kb_eig) <= 1e-9 * k_scale))     # <=: a rigid mass (K_B = 0) has 6
    s["M_positive_definite"] = bool(m_eig[0] > MASSLESS_TOL * m_eig[-1])
    s["M_n_massless"] = int(np.sum(m_eig <= MASSLESS_TOL * m_eig[-1]))
    s["K_positive_semidefinite"] = bool(kb_eig[0] > -1e-9 * k_scale and np.all(cb.fixed_omega >= 0))
    rb = rb_rows(cb.boundary_labels, cb.points, cb.point_coords, ref)
    res = _rb_residual(cb.K_B, rb, k_scale)
    s["rb_residual"] = res.tolist()
    s["grounded"] = own_mass is not None
    s["rb_ok"] = None if own_mass is not None else bool(res.max() < RB_TOL)
    m6 = rb.T @ cb.M_B @ rb
    s["rigid_body_mass"] = m6.tolist()
    s["mass_properties_cb"] = cg_mass(m6, ref).as_dict()
    if own_mass is not None:
        s["mass_properties_own"] = cg_mass(np.asarray(own_mass, float), ref).as_dict()
    # modal effective mass of the fixed-interface modes (unit modal mass): (C_M RB)^2
    L = cb.C_M @ rb
    eff = L**2
    total = np.maximum(np.diag(m6), 1e-300)
    pct = 100 * eff / total
    s["effective_mass"] = eff.tolist()
    s["effective_mass_percent"] = pct.tolist()
    s["effective_mass_cumulative_percent"] = np.cumsum(pct, axis=0).tolist()
    s["fixed_interface_freq_hz"] = cb.fixed_freq_hz.tolist()
    lam = eigh_massless(cb.K, cb.M, f"CB model {cb.name!r}")[0]      # massless DOFs condensed (Nastran models)
    ncmp = min(n_freefree, lam.size)
    f_cb = np.sqrt(np.abs(lam[:ncmp])) / (2 * np.pi)
    s["freefree_freq_hz_cb"] = f_cb.tolist()
    if component is not None:
        rbf, source = full_rb(component, cb, ref)
        s["fe_rb_source"] = source
        if rbf is not None:
            m6f = rbf.T @ (component.M @ rbf)
            s["mass_properties_fe"] = cg_mass(m6f, ref).as_dict()
            s["fe_rb_residual"] = _rb_residual(component.K, rbf).tolist()
            s["rigid_body_mass_rel_error"] = float(np.abs(m6 - m6f).max() / np.abs(m6f).max())
        ncmp = min(ncmp, component.n_dof - 2)
        shift = -(0.01 * cb.fixed_omega[0]) ** 2 if nq else -1.0
        if component.n_dof <= DENSE_FE_LIMIT:
            lf = sla.eigvalsh(component.K.toarray(), component.M.toarray())[:ncmp]
        else:
            lf = np.sort(spla.eigsh(component.K.tocsc(), k=ncmp, M=component.M.tocsc(), sigma=shift,
                                    which="LM", return_eigenvectors=False))
        f_fe = np.sqrt(np.abs(lf)) / (2 * np.pi)
        s["freefree_freq_hz_fe"] = f_fe.tolist()
        with np.errstate(divide="ignore", invalid="ignore"):
            err = np.where(f_fe[:ncmp] > 1e-3 * max(f_fe.max(), 1e-300),
                           f_cb[:ncmp] / f_fe[:ncmp] - 1, np.nan)
        s["freefree_rel_error"] = [None if np.isnan(e) else float(e) for e in err]
    return CBCheck(summary=s, text=_report(s))


def _report(s: dict) -> str:
    m_def = "PD" if s["M_positive_definite"] else f"NOT PD: {s['M_n_massless']} massless, condensed"
    n_res = s.get("n_residual", 0)
    of_them = f", the last {n_res} residual vectors" if n_res else ""
    out = [f"Craig-Bampton check: {s['name']}  ({s['n_modes']} modes{of_them}, {s['n_boundary']} boundary DOFs; "
           "SI units)",
           f"  symmetry      M {s['M_asymmetry']:.1e}   K {s['K_asymmetry']:.1e}  (max |A-A^T| / max |A|)",
           f"  definiteness  M min/max eig {s['M_min_eig_rel']:.2e} ({m_def})"
           f"   K_B min eig / scale {s['K_B_min_eig_rel']:.1e}, {s['K_B_n_zero_eig']} zero"
           f" ({'PSD' if s['K_positive_semidefinite'] else 'NOT PSD'})",
           f"  rigid body    |K_B RB| / (k_scale |RB|) max {max(s['rb_residual']):.1e} about {s['ref_point']} m -> "
           + ("not applicable: grounded (clamped inside its interior), its boundary is no rigid-body support; "
              "M_B's mass below is what the boundary carries with the clamp held, 'own' the component's"
              if s.get("grounded") else 'OK' if s['rb_ok'] else 'FAIL (not free-free or non-geometric)')]
    for tag, key in (("CB (M_B)", "mass_properties_cb"), ("own (r^T M r)", "mass_properties_own"),
                     ("FE (full M)", "mass_properties_fe")):
        if key in s:
            mp = s[key]
            cg = ", ".join(f"{c:.6g}" for c in mp["cg"])
            inertia = np.array(mp["inertia_cg"])
            out.append(f"  {tag:12s} mass {mp['mass']:.6g} kg  c.g. ({cg}) m  I_cg diag "
                       + " ".join(f"{v:.6g}" for v in np.diag(inertia)) + " kg m^2")
    if "fe_rb_source" in s:
        out.append(f"  FE rigid-body shape from {s['fe_rb_source']}")
        if "rigid_body_mass_rel_error" in s:
            out.append(f"  rigid-body mass CB vs FE: max rel. difference {s['rigid_body_mass_rel_error']:.1e};"
                       f" FE |K RB| rel. {max(s['fe_rb_residual']):.1e}")
    out.append("  modal effective mass (% of total, per fixed-interface mode):")
    out.append("    mode   f (Hz)   " + "".join(f"{d:>8s}" for d in COMPONENTS))
    pct = np.array(s["effective_mass_percent"]).reshape(-1, 6)
    n_eig = pct.shape[0] - n_res
    for j, f in enumerate(s["fixed_interface_freq_hz"]):
        out.append(f"    {j + 1:4d} {f:9.3f}  " + "".join(f"{v:8.2f}" for v in pct[j]) + ("  residual" if j >= n_eig else ""))
    if n_eig:
        out.append("    total           " + "".join(f"{v:8.2f}" for v in pct[:n_eig].sum(axis=0))
                   + ("  (eigenmodes)" if n_res else ""))
    if n_res:
        out.append("    residual vectors" + "".join(f"{v:8.2f}" for v in pct[n_eig:].sum(axis=0)))
    out.append("  free-free frequencies (Hz): CB" + (" vs FE, rel. error" if "freefree_freq_hz_fe" in s else ""))
    for j, f in enumerate(s["freefree_freq_hz_cb"]):
        line = f"    {j + 1:4d} {f:12.5f}"
        if "freefree_freq_hz_fe" in s and j < len(s["freefree_freq_hz_fe"]):
            e = s["freefree_rel_error"][j]
            line += f" {s['freefree_freq_hz_fe'][j]:12.5f}  " + ("   (rigid)" if e is None else f"{e:10.2e}")
        out.append(line)
    return "\n".join(out)
