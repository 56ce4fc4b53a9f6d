"""Residual vectors on a small FE stack (gmsh + dolfinx solids, two components): with the
system modes cut, the static flexibility at every interface DOF equals the exact static
solve of the assembled CB models (held statically determinately at one end and projected
to the mean axes, numpy, without the modes)."""
from dataclasses import replace

import numpy as np
import pytest

from liftoff.reduction import (assemble, craig_bampton, keep_modes, label_transform, system_modes, system_rb,
                               truncation_check)
from liftoff.reduction.models import six_labels

from ..roundoff import solve_rtol
from .test_fem_pipeline import L, bar  # noqa: F401  (the module's FE bar fixture)

pytestmark = pytest.mark.fem


def shifted(comp, name: str, rename: dict, dx: float):
    """The same FE component moved by dx along x, its points renamed."""
    labels = [f"{rename[p]}:{c}" for p, c in (lab.split(":") for lab in comp.dof_labels)]
    return replace(comp, name=name, dof_labels=labels, points=[rename[p] for p in comp.points],
                   point_coords=np.asarray(comp.point_coords) + [dx, 0.0, 0.0],
                   nodes=None if comp.nodes is None else np.asarray(comp.nodes) + [dx, 0.0, 0.0])


def exact_flexibility(asm, labels, held_point: str) -> tuple[np.ndarray, float]:
    """Mean-axis static flexibility of the free assembly at ``labels`` from K and M alone."""
    K, M = 0.5 * (asm.K + asm.K.T), 0.5 * (asm.M + asm.M.T)
    R = system_rb(asm)
    held = np.array([asm.boundary_dof(lab) for lab in six_labels(held_point)])
    free = np.setdiff1d(np.arange(asm.n_dof), held)
    mr = R.T @ M @ R
    Lt = label_transform(asm, labels)
    F = Lt.T - M @ R @ np.linalg.solve(mr, R.T @ Lt.T)            # balanced by rigid-body inertia
    X = np.zeros_like(F)
    Kff = K[np.ix_(free, free)]
    X[free] = np.linalg.solve(Kff, F[free])
    X -= R @ np.linalg.solve(mr, R.T @ M @ X)                      # about the mean axes
    return Lt @ X, float(np.linalg.cond(Kff))


def test_residual_vectors_make_the_fe_stacks_interface_flexibility_exact(bar):  # noqa: F811
    _, comp = bar
    a = replace(comp, name="a")
    b = shifted(comp, "b", {"x0": "x1", "x1": "x2"}, L)
    cbs = [craig_bampton(a, six_labels("x0") + six_labels("x1"), n_modes=6),
           craig_bampton(b, six_labels("x1") + six_labels("x2"), n_modes=6)]
    asm = assemble(cbs, "two bars")
    full = system_modes(asm)
    labels = [lab for p in ("x0", "x1", "x2") for lab in six_labels(p)]
    G, cond = exact_flexibility(asm, labels, "x0")
    tol = solve_rtol(cond, asm.n_dof)
    n = 6 + 4
    for residual in (False, True):
        kept = keep_modes(full, n_modes=n, residual=residual)
        rows = label_transform(asm, labels) @ kept.phi
        el = kept.omega > 0
        Gk = (rows[:, el] / kept.omega[el] ** 2) @ rows[:, el].T
        err = np.abs(Gk - G).max() / np.abs(G).max()
        chk = truncation_check(full, kept, labels, [f"{p}:{c}" for p in ("x0", "x2") for c in ("Tx", "Ty", "Tz")])
        print(f"two FE bars ({asm.n_dof} CB DOFs, cond {cond:.1e}): {n} of {full.n_modes} modes"
              f"{f' + {kept.n_residual} residual vectors' if residual else ''}: flexibility error {err:.1e} "
              f"(bound {tol:.1e}); check: {chk.flex_error:.1e} at {chk.flex_label}")
        if residual:        # exact statics (static_error); the check itself counts the eigenmodes only
            assert err <= tol and chk.static_error <= tol and chk.flex_error > 0.01 and not chk.ok
        else:
            assert err > 0.01 and chk.flex_error > 0.01 and not chk.ok
