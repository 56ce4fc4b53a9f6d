"""Data recovery (interface forces, displacements, full field) against monolithic models."""

import numpy as np
import pytest
import scipy.linalg as sla

from liftoff.reduction import (Component, acceleration_recovery, assemble, craig_bampton, displacement_recovery,
                       field_displacement, field_recovery, interface_force_recovery, system_modes)
from liftoff.reduction.models import chain_component, six_labels

SECTION = dict(E=70e9, nu=0.33, A=4e-4, Iy=6e-8, Iz=1.1e-7, J=1.2e-7, rho=2700.0)
N = 16                                      # elements per leg; joint n16, tip n32, station n24


def clamp(c: Component, point: str) -> Component:
    """Remove the six DOFs of ``point`` (clamped), as fem/ does for grounded DOFs."""
    drop = c.dofs_of(six_labels(point))
    keep = np.setdiff1d(np.arange(c.n_dof), drop)
    new = {d: k for k, d in enumerate(keep)}
    lab = [(l, new[d]) for l, d in zip(c.dof_labels, c.label_dofs) if d in new]
    pts = [p for p in c.points if p != point]
    return Component(c.name, c.K[keep][:, keep], c.M[keep][:, keep], [l for l, _ in lab], [d for _, d in lab],
                     pts, [c.point_coord(p) for p in pts])


@pytest.fixture(scope="module")
def frame():
    a = np.linspace(0, 1.2, N + 1)
    b = np.linspace(0, 0.8, N + 1)[1:]
    nodes = np.vstack([np.c_[a, 0 * a, 0 * a], np.c_[1.2 + 0 * b, 0.3 * b, b]])
    A_free = chain_component("A", nodes[: N + 1], 0, **SECTION)
    A = clamp(A_free, "n0")
    B = chain_component("B", nodes[N:], N, **SECTION)
    full = clamp(chain_component("full", nodes, 0, **SECTION), "n0")
    return A_free, A, B, full


def monolithic(full, f, Omega):
    """Harmonic (or static, Omega = 0) displacement amplitude of the clamped frame."""
    return np.linalg.solve(full.K.toarray() - Omega**2 * full.M.toarray(), f)


def a_force_at_joint(A_free, full, u, Omega):
    """Force leg A carries at the joint in the monolithic model: A's own element matrices
    (K_A - Omega^2 M_A) u_A, joint rows (the clamped root moves zero)."""
    uA = np.zeros(A_free.n_dof)
    uA[6:] = u[: A_free.n_dof - 6]          # n1..n16 of the clamped full model
    rows = A_free.dofs_of(six_labels(f"n{N}"))
    return ((A_free.K - Omega**2 * A_free.M) @ uA)[rows]


def reduced(A, B, nB_modes, nA_modes=None):
    joint, tip = six_labels(f"n{N}"), six_labels(f"n{2 * N}")
    cbA = craig_bampton(A, joint, n_modes=A.n_dof if nA_modes is None else nA_modes)
    cbB = craig_bampton(B, joint + tip, n_modes=nB_modes)
    asm = assemble([cbA, cbB], "clamped frame")
    return asm, system_modes(asm, n_rigid=0), cbB


def loads(full, B, asm, cbB):
    """The same load on both models: a force/moment at the tip (boundary DOF) and a
    lateral force at station n24 (interior of B)."""
    f_tip = np.array([120.0, -80.0, 200.0, 5.0, -3.0, 2.0])
    f_full = np.zeros(full.n_dof)
    f_full[full.dofs_of(six_labels(f"n{2 * N}"))] = f_tip
    f_full[full.dofs_of(["n24:Ty"])] += 150.0
    f_sys = np.zeros(asm.n_dof)
    for lab, v in zip(six_labels(f"n{2 * N}"), f_tip):
        f_sys[asm.boundary_dof(lab)] += v
    fB = np.zeros(B.n_dof)
    fB[B.dofs_of(["n24:Ty"])] = 150.0
    f_sys += asm.scatter("B", cbB.generalized_load(fB))
    return f_full, f_sys


def modal_response(sysm, f_sys, Omega):
    q = (sysm.phi.T @ f_sys) / (sysm.omega**2 - Omega**2)
    return q, -Omega**2 * q


@pytest.mark.parametrize("Omega_hz", [0.0, 37.0, 260.0])
def test_interface_force_all_modes_equals_monolithic(frame, Omega_hz):
    A_free, A, B, full = frame
    Omega = 2 * np.pi * Omega_hz
    asm, sysm, cbB = reduced(A, B, nB_modes=B.n_dof)
    f_full, f_sys = loads(full, B, asm, cbB)
    ref = a_force_at_joint(A_free, full, monolithic(full, f_full, Omega), Omega)
    q, qdd = modal_response(sysm, f_sys, Omega)
    D, Acc = interface_force_recovery(asm, sysm, "A")
    F = D @ q + Acc @ qdd
    # all modes kept: the modal solution is exact; what is left is round-off amplified by
    # the condition of K - Omega^2 M (measured 1e-11 .. 2e-9), hence 1e-8
    print(f"Omega {Omega_hz} Hz: joint force {np.round(ref[:3], 3)} N, rel. error "
          f"{np.abs(F - ref).max() / np.abs(ref).max():.1e}")
    assert np.allclose(F, ref, rtol=0, atol=1e-8 * np.abs(ref).max())
    # Newton's third law at the joint: A and B carry opposite forces. B is itself loaded
    # (n24), so its recovered boundary force includes that load's static reduction, which
    # has to be taken off (recovery.py docstring)
    DB, AB = interface_force_recovery(asm, sysm, "B", labels=six_labels(f"n{N}"))
    fB = np.zeros(B.n_dof)
    fB[B.dofs_of(["n24:Ty"])] = 150.0
    FB = DB @ q + AB @ qdd - cbB.boundary_load(fB)[: 6]
    assert np.allclose(F + FB, 0, atol=1e-8 * np.abs(ref).max())
    # displacement at the tip (boundary) and at station n24 (interior of B, via its CB modes)
    labs = ["n32:Tx", "n32:Tz", "n24:Ty", "n24:Rx"]
    u_ref = monolithic(full, f_full, Omega)[full.dofs_of(labs)]
    u = displacement_recovery(sysm, labs) @ q
    assert np.allclose(u, u_ref, rtol=0, atol=1e-8 * np.abs(u_ref).max())
    assert np.allclose(acceleration_recovery(sysm, labs) @ qdd, -Omega**2 * u_ref,
                       rtol=0, atol=1e-8 * max(Omega**2, 1) * np.abs(u_ref).max())
    # the matrices plug into the transient core's Recovery (y = disp q + acc qddot)
    from liftoff.transient.model import Recovery

    rec = Recovery("joint_A", "a", six_labels(f"n{N}"), disp=D, acc=Acc)
    assert np.allclose(rec.disp @ q + rec.acc @ qdd, F)


def test_interface_force_truncated_models(frame):
    A_free, A, B, full = frame
    # boundary loads only, static: CB is exact for statics whatever modes are kept
    # (the constraint modes are the exact static shapes), so 1e-8 still holds.
    asm, sysm, cbB = reduced(A, B, nB_modes=4, nA_modes=4)
    f_tip = np.zeros(full.n_dof)
    f_tip[full.dofs_of(six_labels("n32"))] = [120.0, -80.0, 200.0, 5.0, -3.0, 2.0]
    f_sys = np.zeros(asm.n_dof)
    for lab, v in zip(six_labels("n32"), [120.0, -80.0, 200.0, 5.0, -3.0, 2.0]):
        f_sys[asm.boundary_dof(lab)] = v
    ref = a_force_at_joint(A_free, full, monolithic(full, f_tip, 0.0), 0.0)
    q, _ = modal_response(sysm, f_sys, 0.0)
    D, _ = interface_force_recovery(asm, sysm, "A")
    assert np.allclose(D @ q, ref, rtol=0, atol=1e-8 * np.abs(ref).max())
    # harmonic at 37 Hz (between system modes 3 and 4: 29.9 and 40.4 Hz) with 2, 6, 12
    # fixed-interface modes per component: the truncated component modes would respond
    # quasi-statically, and their missing share (no residual flexibility in plain CB) is of
    # order (Omega / omega_truncated)^2 of the local dynamic load. Measured 0.18 %, 0.025 %,
    # 0.0016 %; tolerances 0.5 % and 0.01 %, and the error must fall as modes are added.
    Omega = 2 * np.pi * 37.0
    errs = []
    for n in (2, 6, 12):
        asm, sysm, cbB = reduced(A, B, nB_modes=n, nA_modes=n)
        f_full, f_sys = loads(full, B, asm, cbB)
        ref = a_force_at_joint(A_free, full, monolithic(full, f_full, Omega), Omega)
        q, qdd = modal_response(sysm, f_sys, Omega)
        D, Acc = interface_force_recovery(asm, sysm, "A")
        errs.append(np.abs(D @ q + Acc @ qdd - ref).max() / np.abs(ref).max())
    print("harmonic joint force, rel. error with 2/6/12 modes per component:", [f"{e:.1e}" for e in errs])
    assert errs[0] < 5e-3 and errs[-1] < 1e-4 and errs[0] > errs[1] > errs[2]


def test_field_recovery_matches_monolithic_modes():
    from .test_assembly import two_blocks

    A, B, full = two_blocks()
    asm = assemble([craig_bampton(A, six_labels("foot") + six_labels("joint"), n_modes=A.n_dof),
                    craig_bampton(B, six_labels("joint") + six_labels("top"), n_modes=B.n_dof)], "blocks")
    sysm = system_modes(asm)
    u = np.vstack([field_recovery(asm, sysm, "A", A), field_recovery(asm, sysm, "B", B)])
    lam, vec = sla.eigh(full.K.toarray(), full.M.toarray())
    u_ref = full.field_map @ vec
    for j in range(6, 16):                   # elastic modes (simple: no symmetric pairs)
        a, r = u[:, j], u_ref[:, j]
        s = np.sign(a @ r)
        # both mass-normalised: equal up to sign; all modes kept -> round-off only
        assert np.abs(a - s * r).max() < 1e-7 * np.abs(r).max()
    with pytest.raises(Exception, match="field_map"):
        field_recovery(asm, sysm, "A", Component("A", A.K, A.M, A.dof_labels, A.label_dofs, A.points,
                                                 A.point_coords))
    # the displacements of some nodes only (a picture's corner nodes), in any order, from the
    # rows of the modes they need: the same dot products as the whole field's rows
    q = np.random.default_rng(3).standard_normal((sysm.phi.shape[1], 2))
    whole = field_displacement(asm, sysm, "B", B, q).reshape(-1, 3, 2)
    nodes = np.random.default_rng(4).permutation(whole.shape[0])[: whole.shape[0] // 3]
    some = field_displacement(asm, sysm, "B", B, q, nodes).reshape(-1, 3, 2)
    assert some.shape == (nodes.size, 3, 2)
    assert np.abs(some - whole[nodes]).max() <= 1e-12 * np.abs(whole).max()    # summation order apart


def test_cg_acceleration_of_each_component_under_rigid_body_acceleration(frame):
    """The free-free frame (two CB components, a few modes each) under a rigid-body
    acceleration: linear a0 and angular alpha about the origin (no velocity). Each
    component's c.g. accelerates as a rigid body's point does, a0 + alpha x r_cg, with r_cg
    and the mass from the component's own FE matrices (cg_mass of RB^T M RB: independent of
    the CB model)."""
    from liftoff.core.rigid import cg_mass, rb_rows
    from liftoff.reduction import cg_acceleration_recovery

    A_free, _, B, _ = frame
    joint = six_labels(f"n{N}")
    asm = assemble([craig_bampton(A_free, joint, n_modes=8), craig_bampton(B, joint, n_modes=8)], "free frame")
    sysm = system_modes(asm)
    a0, alpha = np.array([0.3, -1.2, 9.0]), np.array([0.05, 0.4, -0.2])
    # the assembly's boundary DOFs accelerating rigidly; modal accelerations by M-projection
    # (the rigid-body modes are in the space, so the projection is exact)
    rb = rb_rows(asm.boundary_labels, asm.points, asm.point_coords, np.zeros(3))
    xb = np.zeros(asm.n_dof)
    xb[asm.n_dof - len(asm.boundary_labels):] = rb @ np.r_[a0, alpha]
    qdd = sysm.phi.T @ (asm.M @ xb)
    for comp in (A_free, B):
        A, mass = cg_acceleration_recovery(asm, sysm, comp.name)
        R = np.zeros((comp.n_dof, 6))
        R[comp.label_dofs] = rb_rows(comp.dof_labels, comp.points, comp.point_coords, np.zeros(3))
        props = cg_mass(R.T @ comp.M @ R)
        # round-off of the CB transformation and the M-projection (cond ~1e6 here)
        np.testing.assert_allclose(mass, props.mass, rtol=1e-9)
        np.testing.assert_allclose(A @ qdd, a0 + np.cross(alpha, props.cg), rtol=1e-8, atol=1e-9 * np.abs(a0).max())
