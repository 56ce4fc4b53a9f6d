"""Round-off tolerances for tests that compare two computations of the same quantity.

A fixed 1e-12 is not what floating point guarantees: a sum of a few thousand terms, a
solve with a condition number of 1e6 or another BLAS's summation order can exceed it
(issue 16: a mass summed over a fresh machine's FE model differed by 1.7e-12). These
helpers give the standard bounds (Higham, Accuracy and Stability of Numerical
Algorithms, 2nd ed., ch. 3, 7, 8), times SAFETY for their constants:

* a sum or dot product of n terms: |error| <= gamma_n sum |terms|, gamma_n ~ n eps;
* a matrix-vector or matrix product of inner dimension n: n eps |A| |B| elementwise;
* a backward-stable solve of A x = b: relative error ~ n eps cond(A);
* a symmetric eigenvalue: |error| ~ n eps ||A|| (relative to the eigenvalue: n eps
  ||A|| / |lambda|; a frequency, its square root, half of that).

Each test states which bound it uses and what n (and cond) are.
"""
from __future__ import annotations

import numpy as np

EPS = float(np.finfo(float).eps)   # 2.2e-16
SAFETY = 10.0                      # the constants of the bounds (c n eps): generous, still far below any physics


def sum_rtol(n: int) -> float:
    """Relative round-off of a sum of n terms of one sign (or of a product of inner dimension n)."""
    return SAFETY * max(int(n), 1) * EPS


def solve_rtol(cond: float, n: int = 1) -> float:
    """Relative error of a backward-stable solve with a matrix of condition number ``cond``."""
    return SAFETY * max(int(n), 1) * EPS * max(float(cond), 1.0)


def eig_rtol(n: int, norm: float, value: float) -> float:
    """Relative error of a symmetric eigenvalue ``value`` of an n x n matrix of 2-norm ``norm``."""
    return SAFETY * max(int(n), 1) * EPS * float(norm) / max(abs(float(value)), 1e-300)


def product_atol(A, B) -> float:
    """Absolute round-off of the entries of A @ B: inner dimension n, n eps (|A| |B|), the
    largest entry (the bound for two orders of summation of the same products)."""
    A, B = np.atleast_2d(np.asarray(A, float)), np.atleast_2d(np.asarray(B, float))
    return sum_rtol(A.shape[-1]) * float((np.abs(A) @ np.abs(B)).max(initial=0.0))


def cond_estimate(K) -> float:
    """1-norm condition number of a sparse (or dense) nonsingular matrix: ||K||_1 ||K^-1||_1,
    the inverse's norm estimated from a sparse LU (Hager-Higham, scipy's onenormest)."""
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla

    K = sp.csc_matrix(K)
    lu = spla.splu(K)
    n = K.shape[0]
    inv = spla.LinearOperator((n, n), matvec=lu.solve, rmatvec=lambda x: lu.solve(x, trans="T"), dtype=float)
    return float(spla.norm(K, 1) * spla.onenormest(inv))


def interior_cond(component, boundary_labels) -> float:
    """cond(K_ii) of a component with its boundary DOFs fixed: the bound of the constraint
    modes Psi = -K_ii^-1 K_ib of a Craig-Bampton reduction, and so of everything built on them."""
    i = np.setdiff1d(np.arange(component.n_dof), component.dofs_of(boundary_labels))
    return cond_estimate(component.K[i][:, i])
