"""The lowest eigenpairs of K x = lambda B x (or those nearest a shift) by block shift-invert Lanczos: blocks of
right-hand sides through one factor of K.

A Craig-Bampton reduction needs every fixed-interface mode below f_max (section 3.0 of
Prabhakar & Palermo keeps them all): hundreds of eigenpairs of a component with 10^5 DOFs.
A one-vector Krylov solver (SLEPc's Krylov-Schur) applies K^-1 one vector at a time, and a
MUMPS triangular solve of one vector is memory-bound: on the default booster (129,000 DOFs,
a factor of 4.1e7 entries) one solve takes 74 ms, one of 16 or more vectors 13 ms a vector
(BLAS-3). Here the operator A = K^-1 B is applied to blocks:

* the basis V is B-orthonormal (V^T B V = I): each new block W = A V_j is orthogonalised
  against the last two blocks of V (the block three-term recurrence), then against all of
  V once (classical Gram-Schmidt: full reorthogonalisation), and against all of V again
  where a column lost more than 3/4 of its squared B-norm in that pass (the DGKS
  criterion, Daniel, Gragg, Kaufman & Stewart 1976: "twice is enough"); then within itself
  by a Cholesky QR in the B inner product, twice. Two full passes for every block (the
  solver before 2026-11-27) cost twice the basis products: on the default core (466 wet
  modes, 1288 basis vectors, one BLAS thread) the solve took 48-54 s against 37-38 s;
* the coefficients make the block Arnoldi relation A V = V H + Q E e_k^T, H symmetric
  (block tridiagonal in exact arithmetic; full reorthogonalisation keeps it symmetric to
  round-off, and its symmetric part is used);
* the Ritz pairs (theta, y) of H give lambda = 1 / theta and x = V y, and the residual of
  each, ||A x - theta x||_B = ||E y_last||, is exact (no estimate beyond the Arnoldi
  relation); a pair is converged when that residual is below ``tol`` times theta, the
  criterion of SLEPc's default (EPS_CONV_REL on the shift-inverted operator).

Shift: with ``shift`` sigma > 0 the operator is A = (K - sigma B)^-1 B (the caller's factor)
and lambda = sigma + 1 / theta; the ``want`` Ritz values of largest magnitude are taken, both
ends of the spectrum: for sigma = lambda_max / 2 they are the band [0, lambda_max] exactly
(fem.petsc_cb.shifted_pairs), and its top converges in a smaller basis than at sigma = 0.

Memory: V (n x dimension) and, to save a mass application a block, its B-image BV. Where
both would take more than MASS_IMAGE_SHARE of the machine's memory at the largest basis
allowed (a grain booster: 270,786 DOFs, 457 pairs below 25 Hz, a run peaking at 22.8 GB of
24), BV is not kept: the last two blocks' B-images are, and each block is B-applied twice
(before its full Gram-Schmidt pass, for the coefficients V^T (B W), and after it), three
times when the second pass is taken. The arithmetic is the same; the results agree to
round-off.

The operators are injected (``solve``: X -> K^-1 X, ``mass``: X -> B X, on this process's
rows of a block), so B may be a shell (the wet mass M + G^T H^-1 G of fem/liquid.py) and
K's factor anything that solves many right-hand sides at once. Rows are distributed over
``comm`` (each process its contiguous rows); the small dense work is done on every process.
"""
from __future__ import annotations

import os
from contextlib import contextmanager
from typing import Callable

import numpy as np
import scipy.linalg as sla
from mpi4py import MPI

from liftoff.core.errors import ConvergenceError

Block = Callable[[np.ndarray], np.ndarray]

#: the share of the machine's memory that the basis V and its B-image BV may take together
#: at the largest basis allowed (``max_dim``); beyond it BV is not kept (module docstring)
MASS_IMAGE_SHARE = 0.25


@contextmanager
def _small_pages():
    """numpy's large arrays allocated without its transparent-huge-page advice (madvise), then
    the advice restored. Where the machine's memory is fragmented (a page cache full of cached
    models) the first touch of each huge page may compact memory: filling a 1 GB basis took
    1.0-1.4 s against 0.32-0.38 s in 4 kB pages, and the default booster's CB stage 30.2-30.6 s
    against 28.0-28.4 s (one BLAS thread, 2026-12-07); the transient, whose histories are
    touched as often as written, was not faster without it (0.91-0.94 against 0.97 s a case)."""
    core = getattr(np, "_core", None) or np.core
    setter = getattr(core.multiarray, "_set_madvise_hugepage", None)
    if setter is None:
        yield
        return
    before = setter(False)
    try:
        yield
    finally:
        setter(before)


def physical_memory() -> float:
    """This machine's memory in bytes, or its container's limit where smaller (inf where the
    system does not say)."""
    try:
        total = float(os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        total = float("inf")
    try:                                     # a container's limit (cgroup v2), where smaller
        limit = open("/sys/fs/cgroup/memory.max").read().strip()
        return min(total, float(limit)) if limit.isdigit() else total
    except OSError:
        return total


def keeps_mass_image(n_global: int, dim: int) -> bool:
    """Whether :func:`block_lanczos` keeps the basis' B-image for ``dim`` basis vectors of
    ``n_global`` rows (all processes' rows: they share a machine's memory at worst)."""
    return 2 * 8.0 * n_global * dim <= MASS_IMAGE_SHARE * physical_memory()


def block_size(want: int) -> int:
    """Vectors per block: 16 (where MUMPS's per-vector solve cost levels off), 32 for
    several hundred modes (fewer Rayleigh-Ritz steps). Larger blocks need more basis
    vectors for the same pairs: on the default core (684 modes of 70,000 DOFs) 16 and 32
    took the same time, 64 a quarter more."""
    return int(np.clip(want // 20, 16, 32))


def _dot(comm: MPI.Comm, A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """A^T B over the distributed rows."""
    local = A.T @ B
    return comm.allreduce(local, op=MPI.SUM) if comm.size > 1 else local


def _second_pass(after: np.ndarray, C: np.ndarray) -> bool:
    """The DGKS criterion: whether a column of a block lost more than 3/4 of its squared
    B-norm in a Gram-Schmidt pass with coefficients ``C`` (its squared norms ``after`` the
    pass; before it: after + ||C column||^2, V being B-orthonormal), so that round-off in
    what is left may not be B-orthogonal to V and the pass must be repeated."""
    return bool(np.any(after < 0.25 * (after + np.einsum("ij,ij->j", C, C))))


def _pass_again(comm: MPI.Comm, V: np.ndarray, BV: np.ndarray | None, W: np.ndarray, BW: np.ndarray,
                work: np.ndarray, mass: Block | None = None) -> np.ndarray:
    """One more Gram-Schmidt pass of the block W against the B-orthonormal V, in place, and
    of its B-image BW with it; returns the coefficients C. With V's B-image ``BV``: C =
    (BV)^T W and BW - BV C = B (W - V C), no mass application; without it (None: not kept,
    module docstring): C = V^T BW and BW = ``mass``(W) again."""
    C = _dot(comm, BV, W) if BV is not None else _dot(comm, V, BW)
    W -= np.matmul(V, C, out=work)
    if BV is not None:
        BW -= BV @ C
    else:
        BW[...] = mass(W)
    return C


def _colsum(comm: MPI.Comm, A: np.ndarray) -> np.ndarray:
    """The column sums of A over the distributed rows."""
    local = A.sum(axis=0)
    return comm.allreduce(local, op=MPI.SUM) if comm.size > 1 else local


def _times_inverse_lt(X: np.ndarray, L: np.ndarray) -> np.ndarray:
    """X L^-T for a lower-triangular L (p x p), a new Fortran-ordered array: one BLAS trsm on
    X's columns in place of solve_triangular(L, X^T)^T, which copied X twice and checked it
    for infinities (its time a block on the default booster: 8.5 ms against 2.6)."""
    return sla.blas.dtrsm(1.0, L, np.asfortranarray(X), side=1, lower=1, trans_a=1, overwrite_b=0)


def _b_orthonormalise(comm, W, BW, V, BV, mass, rng_block):
    """(Q, BQ, R) with W = Q R and Q^T B Q = I, for a W already B-orthogonal to V: Cholesky
    QR, twice. Directions of W (numerically) inside span(V) are replaced by random ones
    B-orthogonal to V (their rows of R zero), so that the basis always grows by a full block.
    ``BV``: V's B-image, or None (not kept: B is applied to the random block instead)."""
    p = W.shape[1]
    R = np.eye(p)
    for _ in range(2):
        G = _dot(comm, W, BW)
        G = 0.5 * (G + G.T)
        s, U = np.linalg.eigh(G)
        smax = float(s[-1])
        if smax > 0 and s[0] > 1e-12 * smax:
            L = np.linalg.cholesky(G)                   # G = L L^T: W = (W L^-T) L^T
            Rk = L.T
            W, BW = _times_inverse_lt(W, L), _times_inverse_lt(BW, L)
        else:                                           # rank-deficient: keep the good directions
            good = s > 1e-12 * smax if smax > 0 else np.zeros(p, bool)
            Ug, sg = U[:, good], np.sqrt(s[good])
            Q, BQ = (W @ Ug) / sg, (BW @ Ug) / sg
            Rk = np.zeros((p, p))
            Rk[:good.sum()] = (Ug * sg).T
            Z = rng_block(p - int(good.sum()))
            for _ in range(2):
                for basis, bbasis in ((V, BV), (Q, BQ)):
                    if basis.shape[1]:
                        Z = Z - basis @ (_dot(comm, bbasis, Z) if bbasis is not None else _dot(comm, basis, mass(Z)))
            BZ = mass(Z)
            Gz = _dot(comm, Z, BZ)
            Lz = np.linalg.cholesky(0.5 * (Gz + Gz.T))
            Z, BZ = _times_inverse_lt(Z, Lz), _times_inverse_lt(BZ, Lz)
            W, BW = np.hstack([Q, Z]), np.hstack([BQ, BZ])
        R = Rk @ R
    return W, BW, R


def _ritz(H: np.ndarray, m: int, p: int, want: int, magnitude: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """The ``want`` largest eigenpairs of the symmetric part of H[:m, :m] (``magnitude``: of
    largest magnitude, both ends of the spectrum), taken as block tridiagonal (bandwidth
    2p - 1): with full reorthogonalisation the entries beyond are round-off (below 1e-15 of
    H's norm). A banded eigensolve, not a dense one: LAPACK's dense tridiagonalisation
    (Householder) loses the relative accuracy of the smallest Ritz values of this graded
    matrix (the highest modes' theta = 1 / lambda), the band reduction (rotations) keeps it:
    with a dense eigh the default components' eigenvalues moved 1e-14 - 3.5e-12 from SLEPc's
    (the wet core's, whose band spans 0.34 to 60 Hz) against 2e-15 - 5e-14 (2026-12-07)."""
    T = 0.5 * (H[:m, :m] + H[:m, :m].T)
    u = min(2 * p - 1, m - 1)
    band = np.zeros((u + 1, m))
    for k in range(u + 1):                   # upper form: band[u - k, k:] = diag(T, k)
        band[u - k, k:] = np.diagonal(T, k)
    if not magnitude:
        return sla.eig_banded(band, lower=False, select="i", select_range=(m - want, m - 1))
    ev = sla.eig_banded(band, lower=False, eigvals_only=True)          # ascending
    low = int(np.sum(np.argsort(-np.abs(ev), kind="stable")[:want] < np.sum(ev < 0)))   # of them negative
    parts = [sla.eig_banded(band, lower=False, select="i", select_range=r)
             for r in ((0, low - 1), (m - (want - low), m - 1)) if r[1] >= r[0]]
    return np.concatenate([t for t, _ in parts]), np.hstack([y for _, y in parts])


def default_max_dim(want: int, block: int) -> int:
    """The most basis vectors :func:`block_lanczos` builds for ``want`` pairs in blocks of
    ``block`` unless told (the default components needed 2.2-3.9 want), and at least 20 blocks:
    a few pairs of a cluster-rich spectrum need a basis of many blocks whatever their number (a
    grain booster's 6 pairs below 10 Hz were left at 1.7e-10 > 1e-10 at 12 blocks)."""
    return max(6 * want + 10 * block, 20 * block)


def block_lanczos(solve: Block, mass: Block, n_local: int, n_global: int, row0: int, want: int,
                  comm: MPI.Comm = MPI.COMM_SELF, *, tol: float = 1e-10, block: int | None = None,
                  max_dim: int | None = None, seed: int = 20261126, who: str = "eigensolve",
                  keep_mass_image: bool | None = None, shift: float = 0.0) -> tuple[np.ndarray, np.ndarray, dict]:
    """The ``want`` lowest eigenvalues of K x = lambda B x (K, B symmetric positive definite)
    and this process's rows (``row0`` .. ``row0 + n_local``) of their B-normalised vectors;
    returns (lambda ascending, X, info {'dimension', 'blocks', 'second_passes'}). ``solve``/``mass`` apply
    K^-1 and B to this process's rows of a block. Needs ``n_global`` > ``want`` + 4 blocks
    (a smaller problem is a dense one); ConvergenceError if ``want`` pairs have not
    converged at ``max_dim`` basis vectors (default 6 want + 10 blocks, at least 20 blocks; the
    default components needed 2.2-3.9 want). ``keep_mass_image``: keep the basis' B-image
    (None: :func:`keeps_mass_image`; module docstring); info's 'mass_image' says which.
    ``shift`` sigma > 0: ``solve`` applies (K - sigma B)^-1 (module docstring, "Shift:"): the
    ``want`` eigenvalues nearest sigma, lambda = sigma + 1 / theta for the Ritz values theta of
    largest magnitude; info's 'below_shift' counts those below sigma (the factor's inertia
    must say the same)."""
    p = block or block_size(want)
    if n_global <= want + 4 * p:
        raise ValueError(f"{who}: {n_global} DOFs for {want} modes: solve it densely")
    cap_dim = min(n_global - p, max_dim or default_max_dim(want, p))
    rng = np.random.default_rng(seed)

    def rng_block(k: int) -> np.ndarray:     # the same global random vectors whatever the ranks
        return rng.standard_normal((n_global, k))[row0:row0 + n_local]

    # the whole basis at once, Fortran order (V[:, :m] contiguous for BLAS): pages are touched
    # only as columns are written, and nothing is copied as it grows
    keep = keeps_mass_image(n_global, cap_dim) if keep_mass_image is None else bool(keep_mass_image)
    if comm.size > 1:                        # one choice on every process (their machines may differ)
        keep = bool(comm.allreduce(keep, op=MPI.LAND))
    with _small_pages():
        V = np.empty((n_local, cap_dim), order="F")
        BV = np.empty((n_local, cap_dim), order="F") if keep else None
    H = np.zeros((cap_dim, cap_dim))
    work = np.empty((n_local, p), order="F")
    none = np.empty((n_local, 0))
    W = solve(mass(rng_block(p)))            # one application damps the start's high modes
    Q, BQ, _ = _b_orthonormalise(comm, W, mass(W), none, none if keep else None, mass, rng_block)
    V[:, :p] = Q
    if keep:
        BV[:, :p] = BQ
    else:                                    # the B-images of the last two blocks only
        BL = np.zeros((n_local, 2 * p), order="F")
        BL[:, p:] = BQ
    m, blocks, next_check, again = p, 0, 0, 0
    while True:
        j0 = m - p                           # A V = V H + W e_last^T, W B-orthogonal to V
        l0 = max(0, j0 - p)                  # the blocks j - 1, j: H's block tridiagonal rows
        BVl = BV[:, l0:m] if keep else BL[:, (2 * p - (m - l0)):]
        W = np.asfortranarray(solve(BVl[:, -p:]))
        C = _dot(comm, BVl, W)
        W -= np.matmul(V[:, l0:m], C, out=work)
        C2 = _dot(comm, BV[:, :m], W) if keep else _dot(comm, V[:, :m], mass(W))   # full reorthogonalisation
        W -= np.matmul(V[:, :m], C2, out=work)
        H[:m, j0:m] = C2
        H[l0:m, j0:m] += C
        blocks += 1
        BW = mass(W)
        if _second_pass(_colsum(comm, W * BW), C2):
            H[:m, j0:m] += _pass_again(comm, V[:, :m], BV[:, :m] if keep else None, W, BW, work, mass)
            again += 1
        if m >= want and (blocks >= next_check or m + p > cap_dim):     # a last check when the basis is full
            theta, Y = _ritz(H, m, p, want, magnitude=shift != 0.0)
            G = _dot(comm, W, BW)            # ||W y_last||_B: the exact residual of each pair
            Yl = Y[j0:m]
            resid = np.sqrt(np.maximum(np.einsum("ij,ij->j", Yl, G @ Yl), 0.0))
            bad = int(np.sum(~(resid <= tol * np.abs(theta))))
            if bad == 0 and (np.all(theta > 0) if shift == 0.0 else np.all(theta != 0)):
                # V is B-orthonormal and Y orthonormal: X = V Y is B-normalised (to round-off)
                lam = shift + 1.0 / theta
                order = np.argsort(lam, kind="stable")
                with _small_pages():
                    X = np.empty((n_local, want))
                np.matmul(V[:, :m], Y[:, order], out=X)
                return lam[order], X, {"dimension": m, "blocks": blocks, "second_passes": again,
                                       "mass_image": keep, "below_shift": int(np.sum(theta < 0))}
            # a block converges about p / 3 pairs: the next check when about half the rest may have
            next_check = blocks + max(1, (3 * bad) // (2 * p))
            if m + p > cap_dim:
                raise ConvergenceError(f"{who}: block Lanczos left {bad} of {want} eigenpairs unconverged at "
                                       f"{m} basis vectors (largest relative residual "
                                       f"{float(np.max(resid / np.abs(theta))):.2g})")
        elif m < want and m + p > cap_dim:
            raise ConvergenceError(f"{who}: block Lanczos reached {m} basis vectors before {want} pairs")
        Q, BQ, R = _b_orthonormalise(comm, W, BW, V[:, :m], BV[:, :m] if keep else None, mass, rng_block)
        V[:, m:m + p] = Q
        if keep:
            BV[:, m:m + p] = BQ
        else:
            BL[:, :p] = BL[:, p:]
            BL[:, p:] = BQ
        H[m:m + p, j0:m] = R
        m += p
