"""Synthetic modal bodies built with numpy (independent of meshes/, fem/, reduction/).

* ``truss_tower``: a free-free 3-D space truss (square cross-section, braced faces),
  lumped masses, full eigensolution: a small "vehicle" whose full M, K and modes are
  known, so modal-space results can be checked against physical-space ones.
* ``rigid_column``: a rigid body (mass m, inertia about its c.g.) standing on a base
  point at distance l below the c.g.: the inverted pendulum of the softening test.
"""
from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla

from liftoff.transient.body import ModalBody
from liftoff.core.rigid import rb_rows


def _truss(n_levels=6, half_width=2.0, height=30.0, EA=5e9, mass_per_node=2000.0,
           top_mass=0.0, offset=(0.0, 0.0)):
    a = half_width
    corners = [(-a, -a), (a, -a), (a, a), (-a, a)]
    nodes, names = [], []
    for k in range(n_levels + 1):
        z = height * k / n_levels
        for j, (x, y) in enumerate(corners):
            nodes.append((x + offset[0], y + offset[1], z))
            names.append(f"n{k}_{j}")
    nodes = np.array(nodes)
    bars = []
    for k in range(n_levels + 1):
        b = 4 * k
        for j in range(4):
            bars.append((b + j, b + (j + 1) % 4))          # ring
        bars.append((b, b + 2))                            # horizontal diagonal
        if k < n_levels:
            for j in range(4):
                bars.append((b + j, b + 4 + j))            # vertical
                bars.append((b + j, b + 4 + (j + 1) % 4))  # face diagonal
    n = 3 * len(nodes)
    K = np.zeros((n, n))
    for i, j in bars:
        d = nodes[j] - nodes[i]
        L = np.linalg.norm(d)
        e = d / L
        k_loc = EA / L * np.outer(e, e)
        for (p, q, s) in ((i, i, 1), (j, j, 1), (i, j, -1), (j, i, -1)):
            K[3 * p:3 * p + 3, 3 * q:3 * q + 3] += s * k_loc
    m = np.full(len(nodes), mass_per_node)
    m[-4:] += top_mass / 4
    M = np.diag(np.repeat(m, 3))
    labels = [f"{nm}:{c}" for nm in names for c in ("Tx", "Ty", "Tz")]
    return nodes, names, labels, K, M


def modal_body_from_matrices(name, K, M, labels, names, nodes, zeta=0.01, n_modes=None,
                             ref_point=(0, 0, 0)):
    w2, Phi = sla.eigh(K, M)
    w2 = np.where(np.abs(w2) < 1e-6 * w2.max(), 0.0, w2)
    if n_modes is not None:
        w2, Phi = w2[:n_modes], Phi[:, :n_modes]
    coords = dict(zip(names, nodes))
    RB = rb_rows(labels, list(coords), list(coords.values()), ref_point)
    part = Phi.T @ M @ RB
    zeta_v = np.where(w2 > 0, zeta, 0.0)
    return ModalBody(name=name, omega=np.sqrt(np.maximum(w2, 0)), zeta=zeta_v, dof_labels=labels,
                     phi=Phi, participation=part, ref_point=np.asarray(ref_point, float),
                     points=names, point_coords=nodes, rigid_body_mass=RB.T @ M @ RB), Phi, RB


@pytest.fixture
def truss_tower():
    """Builder: truss_tower(**kw) -> (body, K, M, Phi, RB) with all modes kept."""
    def build(name="tower", zeta=0.01, n_modes=None, **kw):
        nodes, names, labels, K, M = _truss(**kw)
        body, Phi, RB = modal_body_from_matrices(name, K, M, labels, names, nodes, zeta, n_modes)
        return body, K, M, Phi, RB
    return build


@pytest.fixture
def rigid_column():
    """Builder: rigid_column(m, I, l) -> ModalBody with 6 rigid modes; points 'base' at
    the origin and 'cg' at (0, 0, l); labelled DOFs: all six of both points."""
    def build(m=1000.0, inertia=(500.0, 500.0, 200.0), l=10.0):
        cg = np.array([0.0, 0.0, l])
        Mrb = np.diag([m, m, m, *inertia])
        Phi_g = np.diag(1.0 / np.sqrt(np.diag(Mrb)))  # mass-normalised rigid modes about the c.g.
        names = ("base", "cg")
        coords = {"base": np.zeros(3), "cg": cg}
        labels = [f"{p}:{c}" for p in names for c in ("Tx", "Ty", "Tz", "Rx", "Ry", "Rz")]
        phi = rb_rows(labels, list(coords), list(coords.values()), cg) @ Phi_g
        part = Phi_g.T @ Mrb @ np.eye(6)  # about the c.g.
        return ModalBody(name="column", omega=np.zeros(6), zeta=np.zeros(6), dof_labels=labels,
                         phi=phi, participation=part, ref_point=cg, points=names,
                         point_coords=np.array([coords["base"], cg]), rigid_body_mass=Mrb)
    return build


# ---------------------------------------------------------------- monolithic reference
def _coupled_K(problem):
    """Monolithic stiffness diag(omega^2) + D^T K_C D of vehicle + pad + penalty posts."""
    a, b = problem.body_a, problem.body_b
    na, nb = a.n_modes, b.n_modes
    K = np.zeros((na + nb, na + nb))
    K[:na, :na] = np.diag(a.omega ** 2)
    K[na:, na:] = np.diag(b.omega ** 2)
    rows, ks = [], []
    for c in problem.contacts:
        for la, lb, k in zip(c.labels_a, c.labels_b, c.stiffness):
            rows.append(np.concatenate([a.rows([la])[0], -b.rows([lb])[0]]))
            ks.append(k)
    D, ks = np.array(rows), np.array(ks)
    return K + D.T @ (ks[:, None] * D), D, ks


def _modal_loader(problem):
    """P(t) of both bodies, built here independently of transient/: gravity through the
    participation factors (eq. 14), constant and tabulated forces through mode rows."""
    a, b = problem.body_a, problem.body_b
    f = problem.forcing
    P0 = np.concatenate([a.participation @ np.r_[f.gravity, 0, 0, 0],
                         b.participation @ np.r_[f.gravity, 0, 0, 0]])
    for p in f.constant:
        P0[: a.n_modes] += a.rows([p.label])[0] * p.value
    rows = np.array([a.rows([tb.label])[0] for tb in f.tables]).reshape(-1, a.n_modes)
    tabs = [(tb.time, tb.value) for tb in f.tables]

    def load(t):
        P = P0.copy()
        if tabs:
            P[: a.n_modes] += np.array([np.interp(t, tt, vv) for tt, vv in tabs]) @ rows
        return P
    return load


def _monolithic_errors(problem, divisions=(2, 4, 8)):
    """Max |two-body - monolithic| post force / peak, for h = h0/d (h0 = 0.25/f_h, eq. 12).

    The monolithic reference: vehicle + pad + K_C as one modal system (eq. 2), same modal
    damping, same loads (built independently here), static start, integrated by scipy
    DOP853 with rtol 1e-10. Contacts must stay bolted over the run (t_end < release)."""
    from dataclasses import replace

    from scipy.integrate import solve_ivp

    from liftoff.transient import estimate_step, solve

    assert problem.t_end < min(c.release_time for c in problem.contacts)
    K, D, ks = _coupled_K(problem)
    a, b = problem.body_a, problem.body_b
    C = np.diag(2 * np.concatenate([a.zeta * a.omega, b.zeta * b.omega]))
    n = K.shape[0]
    load = _modal_loader(problem)
    q0 = np.linalg.solve(K, load(problem.t0))

    def rhs(t, y):
        return np.concatenate([y[n:], load(t) - C @ y[n:] - K @ y[:n]])

    h0 = estimate_step(a, b, problem.contacts)[1]
    # integrated a step past t_end, so that the reference never extrapolates
    ref = solve_ivp(rhs, (problem.t0, problem.t_end + h0), np.concatenate([q0, np.zeros(n)]), method="DOP853",
                    dense_output=True, rtol=1e-10, atol=1e-12 * np.abs(q0).max())
    errs = []
    for div in divisions:
        res = solve(replace(problem, h=h0 / div, progress=False, initial="static"))
        F_ref = -(ks[:, None] * (D @ ref.sol(res.time)[:n])).T       # force on the vehicle (N)
        errs.append(np.abs(res.contact_force - F_ref).max() / np.abs(F_ref).max())
    return errs


@pytest.fixture
def monolithic():
    """Namespace: coupled_K(problem), modal_loader(problem), errors(problem, divisions)."""
    from types import SimpleNamespace

    return SimpleNamespace(coupled_K=_coupled_K, modal_loader=_modal_loader, errors=_monolithic_errors)
