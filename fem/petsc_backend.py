"""All PETSc / SLEPc code of fem/: assembly to PETSc, sparse products, gathers to
scipy/numpy, the shift-invert eigensolver (GHEP, MUMPS Cholesky) and the direct static
solver. Everything else in fem/ works with numpy/scipy arrays and dolfinx forms.

Distributed vectors and matrices follow PETSc's contiguous ownership: rank r owns rows
``A.getOwnershipRange()``, so gathering rank-ordered local pieces gives global order.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from petsc4py import PETSc

from liftoff.core.errors import ConvergenceError, InputError


def assemble_matrix(form) -> PETSc.Mat:
    """Assemble a bilinear dolfinx form (no boundary conditions) into a PETSc AIJ matrix."""
    import dolfinx.fem.petsc as fpetsc
    from dolfinx import fem

    A = fpetsc.assemble_matrix(fem.form(form))
    A.assemble()
    return A


def assemble_vector(form) -> PETSc.Vec:
    """Assemble a linear dolfinx form; ghost contributions summed into owners."""
    import dolfinx.fem.petsc as fpetsc
    from dolfinx import fem

    b = fpetsc.assemble_vector(fem.form(form))
    b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    return b


def add_subset(A: PETSc.Mat, B: PETSc.Mat, alpha: float = 1.0) -> None:
    """A += alpha B where B's non-zero pattern is a subset of A's."""
    A.axpy(alpha, B, structure=PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN)


def add(A: PETSc.Mat, B: PETSc.Mat) -> PETSc.Mat:
    """A + B (any non-zero patterns, same layout); B is destroyed. Returns A."""
    A.axpy(1.0, B, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
    B.destroy()
    return A


def add_row_sums_to_diagonal(A: PETSc.Mat, B: PETSc.Mat) -> None:
    """A += diag(row sums of B) (row-sum mass lumping)."""
    d = B.getRowSum()
    A.setDiagonal(d, addv=PETSc.InsertMode.ADD_VALUES)
    A.assemble()


def csr_matrix(comm, local_rows: int, n_cols_local: int, n_cols: int, csr: sp.csr_matrix) -> PETSc.Mat:
    """Distributed AIJ matrix from this rank's rows (CSR with *global* column indices)."""
    csr = sp.csr_matrix(csr)
    csr.sort_indices()
    A = PETSc.Mat().createAIJ(size=((local_rows, PETSc.DECIDE), (n_cols_local, n_cols)),
                              csr=(csr.indptr.astype(PETSc.IntType), csr.indices.astype(PETSc.IntType),
                                   csr.data.astype(PETSc.ScalarType)), comm=comm)
    A.assemble()
    return A


def ptap(A: PETSc.Mat, T: PETSc.Mat) -> PETSc.Mat:
    """T^T A T (the spider / constraint reduction of a stiffness or mass matrix)."""
    C = A.PtAP(T)
    C.setOption(PETSc.Mat.Option.SYMMETRIC, True)
    C.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, False)
    return C


def add_block(A: PETSc.Mat, rows: np.ndarray, block: np.ndarray) -> None:
    """A[rows, rows] += block, set by the rank that owns rows[0] (rows on one rank)."""
    r0, r1 = A.getOwnershipRange()
    if rows.size and r0 <= rows[0] < r1:
        A.setValues(rows.astype(PETSc.IntType), rows.astype(PETSc.IntType), np.asarray(block, float).ravel(),
                    addv=PETSc.InsertMode.ADD_VALUES)
    A.assemble()


def add_csr(A: PETSc.Mat, B: sp.spmatrix) -> None:
    """A += B for a scipy matrix B present (whole) on every rank: each rank adds its own
    rows (new non-zeros allowed)."""
    r0, r1 = A.getOwnershipRange()
    Bl = sp.coo_matrix(sp.csr_matrix(B)[r0:r1])
    A.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, False)
    for i, j, v in zip(Bl.row + r0, Bl.col, Bl.data):
        A.setValue(int(i), int(j), float(v), addv=PETSc.InsertMode.ADD_VALUES)
    A.assemble()


def gather_csr(A: PETSc.Mat) -> sp.csr_matrix:
    """The whole distributed matrix as scipy CSR on every rank."""
    comm = A.getComm().tompi4py()
    indptr, indices, data = A.getValuesCSR()
    pieces = comm.allgather((indptr, indices, data))
    n, m = A.getSize()
    ptr = [np.zeros(1, np.int64)]
    off = 0
    for ip, _, _ in pieces:
        ptr.append(np.asarray(ip[1:], np.int64) + off)
        off += int(ip[-1])
    return sp.csr_matrix((np.concatenate([d for _, _, d in pieces]),
                          np.concatenate([j for _, j, _ in pieces]), np.concatenate(ptr)), shape=(n, m))


def gather_vec(x: PETSc.Vec) -> np.ndarray:
    """The whole distributed vector on every rank (copy)."""
    comm = x.getComm().tompi4py()
    return np.concatenate(comm.allgather(np.array(x.getArray(readonly=True))))


def vec_from_global(A: PETSc.Mat, values: np.ndarray) -> PETSc.Vec:
    """A vector with A's row layout holding this rank's slice of the global array."""
    x = A.createVecLeft()
    r0, r1 = x.getOwnershipRange()
    x.setArray(np.asarray(values, float)[r0:r1])
    return x


def mult_transpose(T: PETSc.Mat, b: PETSc.Vec) -> PETSc.Vec:
    y = T.createVecRight()
    T.multTranspose(b, y)
    return y


def _mumps_cholesky(ksp: PETSc.KSP) -> None:
    """Make ``ksp`` a direct solver: one MUMPS Cholesky factorisation, no Krylov iterations."""
    ksp.setType("preonly")
    pc = ksp.getPC()
    pc.setType("cholesky")
    pc.setFactorSolverType("mumps")


def eigensolve(K: PETSc.Mat, M: PETSc.Mat, n_modes: int, sigma: float, tol: float = 1e-10,
               max_it: int = 500, what: str = "model",
               deflation: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The ``n_modes`` eigenpairs of K phi = lambda M phi nearest ``sigma`` (shift-and-invert
    with a MUMPS Cholesky factor of K - sigma M, SLEPc Krylov-Schur, GHEP), M-orthogonal
    to the columns of ``deflation`` (global array (n, k), e.g. the rigid-body modes:
    a Krylov method can miss members of an exactly 6-fold cluster).

    Returns (lambda ascending, Phi (n, n_modes) M-orthonormal), gathered on every rank: the
    n_modes eigenpairs nearest sigma among the converged ones (the lowest for sigma < 0).
    Raises ConvergenceError if fewer than ``n_modes`` pairs converge and InputError if the
    factorisation fails (K - sigma M singular).
    """
    from slepc4py import SLEPc

    comm = K.getComm()
    eps = SLEPc.EPS().create(comm)
    eps.setOperators(K, M)
    eps.setProblemType(SLEPc.EPS.ProblemType.GHEP)
    n = K.getSize()[0]
    ncv = min(n, max(2 * n_modes + 1, n_modes + 24))    # roomy subspace: near-double modes
    eps.setDimensions(n_modes, ncv, PETSc.DECIDE)
    if deflation is not None and deflation.shape[1]:
        space = [vec_from_global(K, deflation[:, j]) for j in range(deflation.shape[1])]
        eps.setDeflationSpace(space)
    eps.setType(SLEPc.EPS.Type.KRYLOVSCHUR)
    st = eps.getST()
    st.setType(SLEPc.ST.Type.SINVERT)
    st.setShift(sigma)
    _mumps_cholesky(st.getKSP())
    eps.setTarget(sigma)
    eps.setWhichEigenpairs(SLEPc.EPS.Which.TARGET_MAGNITUDE)
    eps.setTolerances(tol, max_it)
    try:
        eps.solve()
    except PETSc.Error as exc:
        raise InputError(f"{what}: eigensolver failed to factor K - sigma M (sigma = {sigma:.4g}): "
                         f"the model is singular or the shift hits an eigenvalue (PETSc error {exc.ierr})") from None
    nconv = eps.getConverged()
    if nconv < n_modes:
        raise ConvergenceError(f"{what}: SLEPc converged {nconv} of {n_modes} eigenpairs "
                               f"(tol {tol:g}, {eps.getIterationNumber()} iterations)")
    lam = np.empty(nconv)
    vecs = []
    vr = K.createVecRight()
    for i in range(nconv):
        lam[i] = eps.getEigenpair(i, vr).real
        vecs.append(gather_vec(vr))
    near = np.argsort(np.abs(lam - sigma), kind="stable")[:n_modes]    # the n_modes nearest sigma,
    order = near[np.argsort(lam[near], kind="stable")]                 # ascending
    Phi = np.column_stack([vecs[i] for i in order]) if vecs else np.zeros((K.getSize()[0], 0))
    eps.destroy()
    return lam[order], Phi


def direct_solve(A: PETSc.Mat, b: PETSc.Vec, x: PETSc.Vec, what: str = "model") -> None:
    """x = A^-1 b (MUMPS Cholesky, A symmetric); a factorisation failure is an InputError."""
    ksp = PETSc.KSP().create(A.getComm())
    ksp.setOperators(A)
    _mumps_cholesky(ksp)
    try:
        ksp.solve(b, x)
    except PETSc.Error as exc:
        raise InputError(f"{what}: static solve failed to factor K (PETSc error {exc.ierr}): "
                         "the model is singular (floating part, missing tie or missing supports)") from None
    finally:
        ksp.destroy()


def solve(K: PETSc.Mat, f: np.ndarray, fixed: np.ndarray, what: str = "model") -> np.ndarray:
    """Solve K u = f with u[fixed] = 0 (direct, MUMPS Cholesky); u gathered on every rank."""
    A = K.copy()
    rows = np.asarray(fixed, dtype=PETSc.IntType)
    b = vec_from_global(A, np.where(np.isin(np.arange(f.size), rows), 0.0, f))
    r0, r1 = A.getOwnershipRange()
    A.zeroRowsColumns(rows[(rows >= r0) & (rows < r1)], diag=1.0)
    x = A.createVecRight()
    direct_solve(A, b, x, what)
    u = gather_vec(x)
    A.destroy()
    return u
