"""The PETSc/MUMPS Craig-Bampton solver: ``reduction.craig_bampton(..., solver=petsc_solver())``.

It does the linear algebra of a Craig-Bampton reduction (section 3.0, eq. 13 of Prabhakar &
Palermo) distributed over the processes of ``comm``; the CB matrices themselves are formed
by ``reduction.craig_bampton`` (one CB method, the solver injected):

* the interior block K_ii, M_ii of the component's K and M (boundary DOFs removed) as
  distributed PETSc AIJ matrices, the interior rows split evenly over the processes;
* ONE MUMPS Cholesky (LDL^T) factor of K_ii. It is the shift-invert operator (sigma = 0)
  of the fixed-interface eigensolve K_ii Phi = M_ii Phi omega^2, solved by block Lanczos
  (fem.block_lanczos: blocks of 16-32 right-hand sides through the factor, BLAS-3 in
  MUMPS; faster than SLEPc's one-vector Krylov-Schur on every default component,
  benchmarks/bench_cb_default.py), and it gives the constraint
  modes Psi = -K_ii^-1 K_ib in one multi-right-hand-side solve (``MatMatSolve`` of the
  factor: petsc4py 3.18 has no KSP.matSolve); a band of ``SHIFT_MIN_MODES`` or more of a dry
  component is solved on a second factor, of K_ii - sigma M_ii at the band's middle
  (:func:`shifted_pairs`), before K_ii's (one factor at a time);
* a band (``f_max`` without ``n_modes``): the number of eigenvalues below
  (2 pi f_max)^2 is the number of negative pivots of an LDL^T factor of
  K_ii - (2 pi f_max)^2 M_ii (Sylvester's law of inertia, MUMPS INFOG(12)); that many
  modes are then computed with the shared factor ("target and count": no growing
  mode count, and a mode missed by the Krylov solver is detected);
* Phi (mass-normalised) and Psi gathered on every process (the CB model keeps them for
  recovery); the small CB matrices are then the same on every process.

Errors: K_ii singular or indefinite (the component floats once its boundary is fixed:
MUMPS null or negative pivots) is an InputError; unconverged or missed eigenpairs a
ConvergenceError. Both are raised on every process (no deadlock). A MUMPS workspace
estimated too small (INFOG(1) = -8, -9, ...: in parallel its estimate can fall short of
the delayed pivots) is not a singular matrix: the factor is redone with a larger
workspace (ICNTL(14), ``MUMPS_WORKSPACE_TRIES``), and a ResourceError is raised if the
last try still falls short. Units SI.
"""
from __future__ import annotations

import itertools
import time
from contextlib import contextmanager
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
from mpi4py import MPI
from petsc4py import PETSc

from liftoff.core.errors import ConvergenceError, InputError, ResourceError

from . import petsc_backend as pb

_PREFIXES = itertools.count()


@dataclass(frozen=True)
class PetscSolver:
    """CB solver on PETSc/MUMPS over ``comm`` (see the module docstring). ``tol``: the
    relative residual of an eigenpair of the shift-inverted operator. ``eigensolver``:
    ``"block-lanczos"`` (fem.block_lanczos, the default) or ``"slepc"`` (SLEPc's one-vector
    Krylov-Schur on the same factor, the solver before 2026-11-26: an independent second
    method, several times slower)."""

    comm: MPI.Comm = field(default_factory=lambda: MPI.COMM_WORLD)
    tol: float = 1e-10
    eigensolver: str = "block-lanczos"

    def __post_init__(self) -> None:
        if self.eigensolver not in EIGENSOLVERS:
            raise InputError(f"CB eigensolver {self.eigensolver!r}: one of {', '.join(EIGENSOLVERS)}")

    def __call__(self, K: sp.csr_matrix, M: sp.csr_matrix, interior: np.ndarray, boundary: np.ndarray, *,
                 n_modes: int | None, f_max: float | None, band_limit: int, who: str, dof_name=str,
                 added_mass=None, inertia_residuals: bool = False):
        timings = {}
        if inertia_residuals and added_mass is not None:
            raise InputError(f"{who}: residual vectors of a component with a hydroelastic liquid are not implemented")
        t0 = time.perf_counter()
        Kii, Mii, Kib_loc, *Mib_loc = interior_matrices(self.comm, K, M, interior, boundary, inertia_residuals)
        B = wet = None
        if added_mass is not None:          # hydroelastic liquid: M_ii + M_a,ii as a shell (fem.liquid)
            from .liquid import wet_mass

            Gi = added_mass.G[:, interior]
            B, wet = wet_mass(Mii, added_mass.H, Gi)
        timings["partition_s"] = time.perf_counter() - t0
        n_i = Kii.getSize()[0]
        want = n_i if n_modes is None else min(n_modes, n_i)

        def count(mu: float) -> int:        # eigenvalues <= mu of the (wet) pencil, by the inertia
            if B is None:
                return count_below(Kii, Mii, mu, who)
            from .liquid import count_below_wet

            return count_below_wet(self.comm, K[interior][:, interior], M[interior][:, interior], Gi, added_mass.H,
                                   mu, who)

        try:
            if n_modes is None and want:
                t0 = time.perf_counter()
                lam_max = (2 * np.pi * f_max) ** 2
                count_max = count(lam_max)
                timings["count_s"] = time.perf_counter() - t0
                if count_max > band_limit:
                    from_count = f"{count_max} by the inertia of K_ii - (2 pi f_max)^2 M_ii"
                    raise InputError(_band_error(who, band_limit, f_max, from_count))
                want = count_max
            shifted = None
            if n_modes is None and self.eigensolver == "block-lanczos" and shifts_band(want, n_i, B is not None):
                #                                   the band's middle as the shift, its own factor
                t0 = time.perf_counter()
                shifted = shifted_pairs(Kii, Mii, want, lam_max, self.tol, who)
                timings["eigensolve_s" if shifted is not None else "shift_attempt_s"] = time.perf_counter() - t0
            t0 = time.perf_counter()
            with _factored_operator(Kii, Mii if B is None else B, want, self.tol, who, self.eigensolver) as (ksp, eps, _):
                timings["factor_s"] = time.perf_counter() - t0
                t0 = time.perf_counter()
                if shifted is not None:
                    lam, phi_loc, info = shifted
                    timings.update(info)
                elif eps is None:
                    lam, phi_loc, info = fixed_interface_pairs(ksp, Kii, Mii, wet, want, self.tol, who)
                    timings.update(info)
                elif want:
                    lam, phi_loc = eigenpairs(eps, Mii if B is None else B, want, who)
                else:
                    lam, phi_loc = np.zeros(0), np.zeros((Kib_loc.shape[0], 0))
                if shifted is None:
                    timings["eigensolve_s"] = time.perf_counter() - t0
                t0 = time.perf_counter()
                psi_loc = -_factor_solve(ksp, Kib_loc, n_i)
                timings["constraint_solve_s"] = time.perf_counter() - t0
                _check_finite(self.comm, psi_loc, who)
                if inertia_residuals:       # X = K_ii^-1 (M_ii Psi + M_ib), on the same factor
                    t0 = time.perf_counter()
                    res_loc = _factor_solve(ksp, _mat_block(Mii, psi_loc) + Mib_loc[0], n_i)
                    timings["residual_solve_s"] = time.perf_counter() - t0
            # n_modes: after the factor is freed (never two factors at once, as the band's count)
            if n_modes is not None and 0 < want < n_i and timings.get("eigen_blocks", 1) and lam[-1] > 0:
                t0 = time.perf_counter()
                _check_none_missed(lam, count, who)
                timings["missed_check_s"] = time.perf_counter() - t0
        finally:
            if B is not None:
                B.destroy()
            Kii.destroy()
            Mii.destroy()
        if n_modes is None and lam.size and lam[-1] > lam_max * (1 + 1e-8):
            raise ConvergenceError(f"{who}: the eigensolver returned a mode at {np.sqrt(lam[-1]) / (2 * np.pi):.6g} Hz "
                                   f"above f_max = {f_max:g} Hz although {want} modes lie below it: "
                                   "a mode of a near-multiple cluster was missed")
        t0 = time.perf_counter()
        phi, psi = gather_rows(self.comm, phi_loc), gather_rows(self.comm, psi_loc)
        timings["gather_s"] = time.perf_counter() - t0
        if inertia_residuals:
            return lam, phi, psi, timings, gather_rows(self.comm, res_loc)
        return lam, phi, psi, timings


def _check_none_missed(lam: np.ndarray, count_below_mu, who: str) -> None:
    """``n_modes`` asked for (no band to count first): the pairs found must be the lowest.
    A Krylov solver can miss an eigenvalue (a cluster with more copies than its block; a
    spectrum of few distinct values, whose Krylov space is exhausted, so that exact pairs
    that are not the lowest converge); Sylvester's law of inertia counts the eigenvalues below the
    last one found (less 1e-8 of it, so that a pair split by the cut is not an error), and
    a count above the pairs found there is a ConvergenceError, not a model with a hole."""
    edge = float(lam[-1]) * (1 - 1e-8)
    found = int(np.sum(lam < edge))
    count = count_below_mu(edge)
    if count > found:
        raise ConvergenceError(f"{who}: the eigensolver missed {count - found} fixed-interface mode(s) below "
                               f"{np.sqrt(edge) / (2 * np.pi):.6g} Hz ({count} lie below it by the inertia, "
                               f"{found} were found): a cluster of more equal eigenvalues than the solver's "
                               "block of vectors, or a Krylov space exhausted by a spectrum of few distinct values")


#: the fixed-interface eigensolvers of :class:`PetscSolver`
EIGENSOLVERS = ("block-lanczos", "slepc")


def petsc_solver(comm: MPI.Comm | None = None, tol: float = 1e-10, eigensolver: str = "block-lanczos") -> PetscSolver:
    """The PETSc/MUMPS CB solver over ``comm`` (default MPI.COMM_WORLD); ``eigensolver`` as
    :class:`PetscSolver`'s."""
    return PetscSolver(MPI.COMM_WORLD if comm is None else comm, tol, eigensolver)


@contextmanager
def _operator(Kii: PETSc.Mat, B: PETSc.Mat, want: int, tol: float, who: str, eigensolver: str,
              workspace: int | None = None):
    """(ksp, eps): the KSP that will hold the factor of K_ii and, for ``"slepc"``, the SLEPc
    solver whose shift-invert operator it is (else None); ``workspace``: MUMPS's ICNTL(14)."""
    if eigensolver == "slepc":
        with _solver(Kii, B, max(want, 1), tol, 500, who, workspace) as eps:
            yield eps.getST().getKSP(), eps
    else:
        with _factor_kii(Kii, who, workspace) as ksp:
            yield ksp, None


@contextmanager
def _factored_operator(Kii: PETSc.Mat, B: PETSc.Mat, want: int, tol: float, who: str, eigensolver: str,
                       definite: bool = True, what: str = "K_ii"):
    """(ksp, eps, (negative, null) pivots): :func:`_operator` with K_ii factored
    (:func:`_set_up`; ``definite``, ``what`` as its), the factor redone with a larger MUMPS
    workspace while MUMPS reports its workspace too small."""
    short = None
    for workspace in MUMPS_WORKSPACE_TRIES:
        with _operator(Kii, B, want, tol, who, eigensolver, workspace) as (ksp, eps):
            try:
                pivots = _set_up(ksp, who, setup=None if eps is None else eps.setUp, definite=definite, what=what)
            except _WorkspaceShort as exc:
                short = exc
                continue
            yield ksp, eps, pivots
            return
    raise _workspace_error(who, what, short)


# ------------------------------------------------------------------ pieces
def row_range(comm: MPI.Comm, n: int) -> tuple[int, int]:
    """PETSc's default contiguous split of n rows: this process owns rows r0..r1-1."""
    size, rank = comm.size, comm.rank
    r0 = rank * (n // size) + min(rank, n % size)
    return r0, r0 + n // size + (1 if rank < n % size else 0)


def interior_matrices(comm: MPI.Comm, K: sp.csr_matrix, M: sp.csr_matrix, interior: np.ndarray,
                      boundary: np.ndarray, mass_boundary: bool = False):
    """Distributed K_ii, M_ii (PETSc AIJ, interior numbering) and this process's rows of
    K_ib (dense, n_local x n_b), from the whole scipy K, M present on every process; with
    ``mass_boundary`` this process's rows of M_ib too, a fourth item (residual vectors)."""
    n_i = interior.size
    r0, r1 = row_range(comm, n_i)
    rows = interior[r0:r1]
    mats, ib = [], []
    for A in (K, M):          # one matrix at a time: its local copies live only until PETSc has its own
        A_rows = sp.csr_matrix(A)[rows]
        if not ib or mass_boundary:
            ib.append(np.asarray(A_rows[:, boundary].todense()))
        A_ii = A_rows[:, interior]
        del A_rows
        mats.append(pb.csr_matrix(comm, rows.size, rows.size, n_i, A_ii))
        del A_ii
        mats[-1].setOption(PETSc.Mat.Option.SYMMETRIC, True)
    return (mats[0], mats[1], *ib)


#: MUMPS INFOG(1) codes of a singular matrix (-6 structurally, -10 numerically)
MUMPS_SINGULAR = (-6, -10)
#: MUMPS INFOG(1) codes of a workspace it estimated too small (integer or real work
#: arrays, solve and refinement arrays, send and receive buffers: its users' guide says
#: "increase ICNTL(14)"); the other negative codes a failure of MUMPS itself (memory,
#: integer overflow: -13, -19, ...)
MUMPS_WORKSPACE_SHORT = (-8, -9, -11, -12, -14, -15, -17, -20)
#: ICNTL(14) of the successive tries of one factor, the percent of workspace added to
#: MUMPS's estimate: its own default first, then 100 % and 400 %
MUMPS_WORKSPACE_TRIES = (None, 100, 400)


class _WorkspaceShort(Exception):
    """MUMPS reported its workspace too small (``info``: INFOG(1), INFOG(2)); try again."""

    def __init__(self, info: tuple[int, int]):
        super().__init__(info)
        self.info = info


def _workspace_error(who: str, what: str, short: _WorkspaceShort) -> ResourceError:
    code, extra = short.info
    return ResourceError(f"{who}: MUMPS failed to factor {what}: its workspace was too small (INFOG(1) = {code}, "
                         f"INFOG(2) = {extra}) even with ICNTL(14) = {MUMPS_WORKSPACE_TRIES[-1]} % more than its "
                         "estimate; run again with fewer ranks or more memory")


@contextmanager
def _mumps_options(comm: MPI.Comm, inertia: bool = True, workspace: int | None = None):
    """A fresh options prefix for one MUMPS factor. With ``inertia``: null-pivot detection
    (ICNTL(24)) and, in parallel, no ScaLAPACK at the root node (ICNTL(13)), which MUMPS
    needs to report the inertia (MatGetInertia). ``workspace``: ICNTL(14), the percent of
    working space added to MUMPS's estimate (None: MUMPS's default)."""
    prefix = f"liftoff_cb{next(_PREFIXES)}_"
    opts = PETSc.Options()
    values = {"mat_mumps_icntl_24": 1} if inertia else {}
    if inertia and comm.size > 1:
        values["mat_mumps_icntl_13"] = 1
    if workspace is not None:
        values["mat_mumps_icntl_14"] = workspace
    for k, v in values.items():
        opts.setValue(prefix + k, v)
    try:
        yield prefix
    finally:
        for k in values:
            opts.delValue(prefix + k)


def _factor_error(what: str, who: str, detail: str) -> InputError:
    return InputError(f"{who} floats (or has a mechanism) once its boundary DOFs are fixed: {what} "
                      f"({detail}); add boundary DOFs that restrain it")


def _inertia(F: PETSc.Mat) -> tuple[int, int, int]:
    nneg, nzero, npos = F.getInertia()
    return int(nneg), int(nzero), int(npos)


def count_below(Kii: PETSc.Mat, Mii: PETSc.Mat, lam: float, who: str = "component") -> int:
    """Number of eigenvalues of K_ii x = mu M_ii x with mu <= ``lam``: the negative (and
    null) pivots of a MUMPS LDL^T factor of K_ii - lam M_ii (Sylvester's law of inertia)."""
    A = Kii.copy()
    try:
        A.axpy(-lam, Mii, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
        return nonpositive_pivots(A, "K_ii - (2 pi f_max)^2 M_ii", who)
    finally:
        A.destroy()


def nonpositive_pivots(A: PETSc.Mat, what: str, who: str) -> int:
    """The negative and null pivots of one MUMPS LDL^T factor of the symmetric ``A`` (its
    inertia: the number of its eigenvalues <= 0); ``what`` names A in the errors. A
    workspace that MUMPS estimated too small is enlarged (``MUMPS_WORKSPACE_TRIES``)."""
    short = None
    for workspace in MUMPS_WORKSPACE_TRIES:
        try:
            return _pivots_once(A, what, who, workspace)
        except _WorkspaceShort as exc:
            short = exc
    raise _workspace_error(who, what, short)


def _pivots_once(A: PETSc.Mat, what: str, who: str, workspace: int | None) -> int:
    comm = A.getComm().tompi4py()
    ksp = PETSc.KSP().create(comm)
    try:
        with _mumps_options(comm, workspace=workspace) as prefix:
            ksp.setOptionsPrefix(prefix)
            ksp.setOperators(A)
            pb._mumps_cholesky(ksp)
            try:
                ksp.setUp()
            except PETSc.Error as exc:
                _raise_if_short(ksp)
                raise InputError(f"{who}: factorisation of {what} failed (PETSc error {exc.ierr})") from None
            _raise_if_short(ksp)
            F = ksp.getPC().getFactorMatrix()
            if F.getMumpsInfog(1) < 0:
                raise InputError(f"{who}: MUMPS failed to factor {what} (INFOG(1) = {F.getMumpsInfog(1)})")
            nneg, nzero, _ = _inertia(F)
    finally:
        ksp.destroy()
    return nneg + nzero


@contextmanager
def _solver(Kii: PETSc.Mat, Mii: PETSc.Mat, nev: int, tol: float, max_it: int, who: str,
            workspace: int | None = None):
    """SLEPc GHEP, Krylov-Schur, shift-invert at sigma = 0 with a MUMPS factor of K_ii
    (``workspace``: its ICNTL(14))."""
    from slepc4py import SLEPc

    comm = Kii.getComm().tompi4py()
    n = Kii.getSize()[0]
    eps = SLEPc.EPS().create(comm)
    with _mumps_options(comm, workspace=workspace) as prefix:
        try:
            eps.setOperators(Kii, Mii)
            eps.setProblemType(SLEPc.EPS.ProblemType.GHEP)
            eps.setDimensions(nev, min(n, max(2 * nev + 1, nev + 24)), PETSc.DECIDE)
            eps.setType(SLEPc.EPS.Type.KRYLOVSCHUR)
            st = eps.getST()
            st.setType(SLEPc.ST.Type.SINVERT)
            st.setShift(0.0)
            st.setMatMode(SLEPc.ST.MatMode.INPLACE)   # sigma = 0: factor K_ii itself, no copy
            ksp = st.getKSP()
            ksp.setOptionsPrefix(prefix)
            pb._mumps_cholesky(ksp)
            eps.setTarget(0.0)
            eps.setWhichEigenpairs(SLEPc.EPS.Which.TARGET_MAGNITUDE)
            eps.setTolerances(tol, max_it)
            # no purification: it costs one more solve per eigenvector and serves a singular
            # M, while M_ii is positive definite (the Ritz vectors meet tol as they are)
            eps.setPurify(False)
            yield eps
        finally:
            eps.destroy()


def _mumps_infog(ksp) -> tuple[int, int] | None:
    """(INFOG(1), INFOG(2)) of the factor of a failed KSPSetUp, None if there is none."""
    try:
        F = ksp.getPC().getFactorMatrix()
        return int(F.getMumpsInfog(1)), int(F.getMumpsInfog(2))
    except Exception:            # no factor object (the failure came before it)
        return None


def _raise_if_short(ksp) -> None:
    """_WorkspaceShort if MUMPS reported its workspace too small for this KSP's factor."""
    info = _mumps_infog(ksp)
    if info is not None and info[0] in MUMPS_WORKSPACE_SHORT:
        raise _WorkspaceShort(info)


@contextmanager
def _factor_kii(Kii: PETSc.Mat, who: str, workspace: int | None = None):
    """A KSP that applies K_ii^-1 with one MUMPS Cholesky (LDL^T) factor, null-pivot
    detection on (its inertia proves K_ii positive definite); ``workspace``: ICNTL(14)."""
    comm = Kii.getComm().tompi4py()
    ksp = PETSc.KSP().create(comm)
    with _mumps_options(comm, workspace=workspace) as prefix:
        try:
            ksp.setOptionsPrefix(prefix)
            ksp.setOperators(Kii)
            pb._mumps_cholesky(ksp)
            yield ksp
        finally:
            ksp.destroy()


def _set_up(ksp, who: str, setup=None, definite: bool = True, what: str = "K_ii") -> tuple[int, int]:
    """Factor K_ii (``setup``: what factors it, default ``ksp.setUp``; SLEPc's EPSSetUp);
    a null or negative pivot means K_ii is singular (``definite`` False: a shifted K_ii -
    sigma M_ii, whose negative pivots are its eigenvalues below sigma, allowed). A failure of
    MUMPS that is not a singular matrix (INFOG(1) outside MUMPS_SINGULAR) is said as such,
    with its codes, not as a floating component; a workspace too small raises
    _WorkspaceShort (try again). Returns the factor's (negative, null) pivots."""
    try:
        (setup or ksp.setUp)()
    except PETSc.Error as exc:
        _raise_if_short(ksp)
        info = _mumps_infog(ksp)
        if info is not None and info[0] < 0 and info[0] not in MUMPS_SINGULAR:
            raise ResourceError(f"{who}: MUMPS failed to factor {what} (PETSc error {exc.ierr}, INFOG(1) = {info[0]}, "
                                f"INFOG(2) = {info[1]}: its workspace or memory, not a singular matrix); run again, "
                                "with fewer ranks or more memory") from None
        detail = f"PETSc error {exc.ierr}" + ("" if info is None else f", INFOG(1) = {info[0]}")
        raise _factor_error("factorisation of K_ii failed", who, detail) from None
    _raise_if_short(ksp)
    F = ksp.getPC().getFactorMatrix()
    if F.getMumpsInfog(1) < 0:
        raise _factor_error("MUMPS failed to factor K_ii", who, f"INFOG(1) = {F.getMumpsInfog(1)}")
    nneg, nzero, _ = _inertia(F)
    if definite and (nneg or nzero):
        raise _factor_error("K_ii is singular", who, f"{nzero} null and {nneg} negative pivots")
    return nneg, nzero


def _mat_block(A: PETSc.Mat, X_loc: np.ndarray) -> np.ndarray:
    """This process's rows of A X for a dense block X (its rows here) and a distributed A."""
    m, k = X_loc.shape
    n = A.getSize()[1]
    X = PETSc.Mat().createDense(((m, n), (PETSc.DECIDE, k)), comm=A.getComm())
    X.setUp()
    X.getDenseArray()[:] = X_loc
    X.assemble()
    Y = None
    try:
        Y = A.matMult(X)
        return np.array(Y.getDenseArray(), copy=True)
    finally:
        X.destroy()
        if Y is not None:
            Y.destroy()


def dense_interior(n_i: int, want: int) -> bool:
    """Whether :func:`fixed_interface_pairs` solves an interior of ``n_i`` DOFs densely for
    ``want`` pairs (the Krylov space block Lanczos would build is capped by the size: a beam
    stick's 234 interior DOFs left 22 of 69 pairs unconverged)."""
    from .block_lanczos import block_size, default_max_dim

    return n_i - block_size(want) <= default_max_dim(want, block_size(want))


def fixed_interface_pairs(ksp, Kii: PETSc.Mat, Mii: PETSc.Mat, wet, want: int, tol: float,
                          who: str, shift: float = 0.0) -> tuple[np.ndarray, np.ndarray, dict]:
    """The ``want`` lowest eigenpairs of K_ii phi = omega^2 (M_ii [+ M_a,ii]) phi with the
    factored ``ksp``: block shift-invert Lanczos (fem.block_lanczos: blocks of right-hand
    sides through the one factor), or a dense solve where the interior is too small for the
    Krylov space block_lanczos would build (block_lanczos.default_max_dim). ``wet``: the wet-mass context of
    fem.liquid.wet_mass, or None. ``shift`` sigma > 0: ``ksp`` holds the factor of K_ii - sigma
    M_ii (dry components, :func:`shifted_pairs`), the pairs are the ``want`` nearest sigma and
    their eigenvalues the Rayleigh quotients x^T K_ii x / x^T M_ii x (sigma + 1 / theta loses
    sigma / lambda of its digits for the lowest modes; against SLEPc's the quotients were the
    closer on the two default components tried: the booster 5e-12 against 5e-11, the orbiter
    3e-10 against 8e-10, its lowest mode, where sigma's nearness to an eigenvalue amplifies
    round-off either way). Returns (omega^2 ascending, this process's rows of the mass-normalised
    modes, {'eigen_dimension', 'eigen_blocks', 'eigen_second_passes', 'eigen_mass_image',
    'eigen_below_shift'})."""
    from .block_lanczos import block_lanczos

    comm = Kii.getComm().tompi4py()
    n_i = Kii.getSize()[0]
    r0, r1 = Kii.getOwnershipRange()
    if want == 0:
        return np.zeros(0), np.zeros((r1 - r0, 0)), {}

    def mass(X):
        return _mat_block(Mii, X) if wet is None else wet.mult_block(X)

    if dense_interior(n_i, want):
        if shift:
            raise ValueError(f"{who}: a shifted solve of an interior solved densely")
        import scipy.linalg as sla

        I_loc = np.eye(n_i)[r0:r1]
        Kd, Bd = gather_rows(comm, _mat_block(Kii, I_loc)), gather_rows(comm, mass(I_loc))
        lam, phi = sla.eigh(0.5 * (Kd + Kd.T), 0.5 * (Bd + Bd.T), subset_by_index=[0, want - 1])
        return lam, phi[r0:r1], {"eigen_dimension": n_i, "eigen_blocks": 0}
    try:
        lam, phi, info = block_lanczos(lambda X: _factor_solve(ksp, X, n_i), mass, r1 - r0, n_i, r0, want, comm,
                                       tol=tol, who=f"{who}: fixed-interface eigensolve", shift=shift)
    except np.linalg.LinAlgError as exc:
        raise ConvergenceError(f"{who}: fixed-interface eigensolve failed ({exc})") from None
    if shift:                                # Rayleigh quotients, ascending
        num = np.einsum("ij,ij->j", phi, _mat_block(Kii, phi))
        den = np.einsum("ij,ij->j", phi, mass(phi))
        if comm.size > 1:
            num, den = comm.allreduce(num, op=MPI.SUM), comm.allreduce(den, op=MPI.SUM)
        lam = num / den
        order = np.argsort(lam, kind="stable")
        lam, phi = lam[order], np.ascontiguousarray(phi[:, order])
    return lam, phi, {"eigen_dimension": info["dimension"], "eigen_blocks": info["blocks"],
                      "eigen_second_passes": info["second_passes"], "eigen_mass_image": info["mass_image"],
                      "eigen_below_shift": info["below_shift"]}


#: a band of at least this many fixed-interface modes of a dry component is solved with the
#: shift at its middle (:func:`shifted_pairs`), at the cost of one more factor. Measured on the
#: default's components (2026-12-07, benchmarks/bench_cb_default.py, two BLAS threads; the
#: shifted solve's time includes its extra factor, K_ii's is needed by the constraint modes
#: either way): srb_left's 304 modes 20.0-20.8 s shifted (a basis of 736 vectors) against
#: 23.7-24.7 s (960), its eigenvalues 5e-12 from SLEPc's; the orbiter's 166 modes 9.7 s either
#: way (432 against 544 vectors) and its lowest eigenvalue 3e-10 from SLEPc's (round-off
#: amplified where sigma nears an eigenvalue); the pad's 30 a loss (its factor 2.8 s against
#: 1.1 s saved): the shift pays from a few hundred modes
SHIFT_MIN_MODES = 200


def shifts_band(want: int, n_i: int, wet: bool) -> bool:
    """Whether a band of ``want`` modes of an interior of ``n_i`` DOFs is solved by
    :func:`shifted_pairs` (block Lanczos, no wet mass, at least SHIFT_MIN_MODES, not dense)."""
    return not wet and want >= SHIFT_MIN_MODES and not dense_interior(n_i, want)


def shifted_pairs(Kii: PETSc.Mat, Mii: PETSc.Mat, want: int, lam_max: float, tol: float,
                  who: str) -> tuple[np.ndarray, np.ndarray, dict] | None:
    """The ``want`` eigenpairs of K_ii x = lambda M_ii x in [0, ``lam_max``] (the band's count)
    by block Lanczos shift-inverted at sigma = lam_max / 2 (one MUMPS LDL^T factor of K_ii -
    sigma M_ii): the band maps to the Ritz values of largest magnitude, |theta| >= 2 / lam_max,
    both ends of the operator's spectrum, and its top converges in a smaller basis than with
    sigma = 0, where the band's top is its spectrum's interior edge. The pairs found below
    sigma must number the factor's negative pivots (Sylvester), else a ConvergenceError.
    None where sigma is (numerically) an eigenvalue: the caller solves unshifted."""
    sigma = 0.5 * lam_max
    A = Kii.copy()
    try:
        A.axpy(-sigma, Mii, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
        A.setOption(PETSc.Mat.Option.SYMMETRIC, True)
        try:
            with _factored_operator(A, Mii, want, tol, who, "block-lanczos", definite=False,
                                    what="K_ii - sigma M_ii") as (ksp, _, (nneg, nzero)):
                if nzero:
                    return None
                lam, phi, info = fixed_interface_pairs(ksp, Kii, Mii, None, want, tol, who, shift=sigma)
        except InputError:                  # _set_up's: the factor failed as singular at sigma
            return None
        if info["eigen_below_shift"] != nneg:
            raise ConvergenceError(f"{who}: the fixed-interface eigensolve found {info['eigen_below_shift']} modes "
                                   f"below {np.sqrt(sigma) / (2 * np.pi):.6g} Hz, where the inertia of K_ii - "
                                   f"sigma M_ii counts {nneg}: a mode of a near-multiple cluster was missed")
        return lam, phi, {**info, "eigen_shift": sigma}
    finally:
        A.destroy()


def _factor_solve(ksp: PETSc.KSP, B_loc: np.ndarray, n: int) -> np.ndarray:
    """X = A^-1 B for the factored operator of ``ksp`` and the dense right-hand sides
    B (this process's rows), in one MatMatSolve; returns this process's rows of X."""
    comm = ksp.getComm()
    m, k = B_loc.shape
    if k == 0:
        return np.zeros((m, 0))
    B = PETSc.Mat().createDense(((m, n), (PETSc.DECIDE, k)), comm=comm)
    B.setUp()
    B.getDenseArray()[:] = B_loc
    B.assemble()
    X = B.duplicate()
    try:
        ksp.getPC().getFactorMatrix().matSolve(B, X)
        return np.array(X.getDenseArray(), copy=True)
    finally:
        B.destroy()
        X.destroy()


def _check_finite(comm: MPI.Comm, x: np.ndarray, who: str) -> None:
    if not comm.allreduce(bool(np.all(np.isfinite(x))), op=MPI.LAND):
        raise _factor_error("K_ii is singular", who, "constraint modes not finite")


def eigenpairs(eps, Mii: PETSc.Mat, want: int, who: str = "component") -> tuple[np.ndarray, np.ndarray]:
    """Solve; the ``want`` lowest eigenvalues (ascending) and this process's rows of their
    M_ii-normalised eigenvectors."""
    try:
        eps.solve()
    except PETSc.Error as exc:
        raise ConvergenceError(f"{who}: SLEPc fixed-interface eigensolve failed (PETSc error {exc.ierr})") from None
    return solved_pairs(eps, Mii, want, f"{who}: SLEPc")


def solved_pairs(eps, B: PETSc.Mat, want: int, what: str) -> tuple[np.ndarray, np.ndarray]:
    """After ``eps.solve()``: the ``want`` lowest eigenvalues (ascending) and this process's
    rows of their B-normalised eigenvectors (ConvergenceError naming ``what`` if fewer
    converged)."""
    nconv = eps.getConverged()
    if nconv < want:
        raise ConvergenceError(f"{what} converged {nconv} of {want} fixed-interface eigenpairs "
                               f"({eps.getIterationNumber()} iterations)")
    v, Mv = B.createVecRight(), B.createVecLeft()
    lam = np.array([eps.getEigenvalue(j).real for j in range(nconv)])
    order = np.argsort(lam, kind="stable")[:want]
    cols = []
    for j in order:
        eps.getEigenvector(int(j), v)
        B.mult(v, Mv)
        cols.append(np.array(v.getArray(readonly=True)) / np.sqrt(v.dot(Mv).real))
    phi = np.column_stack(cols) if cols else np.zeros((v.getLocalSize(), 0))
    return lam[order], phi


def gather_rows(comm: MPI.Comm, local: np.ndarray) -> np.ndarray:
    """Row blocks of the processes stacked in rank order, on every process."""
    if comm.size == 1:
        return local
    return np.vstack(comm.allgather(np.ascontiguousarray(local)))


def _band_error(who: str, band_limit: int, f_max: float, found: str) -> str:
    return (f"{who}: more than {band_limit} fixed-interface modes lie below f_max = {f_max:g} Hz "
            f"({found}); lower f_max or give n_modes")


# ------------------------------------------------------------------ benchmark helper
def eigensolve_alone(Kii: PETSc.Mat, Mii: PETSc.Mat, n_modes: int, tol: float = 1e-10,
                     max_it: int = 500) -> tuple[np.ndarray, dict]:
    """The fixed-interface eigensolve by SLEPc alone, as any modal reduction could do it
    (factor K_ii, one-vector Krylov-Schur, the ``n_modes`` lowest eigenpairs, vectors left
    on their ranks): (eigenvalues, timings). The CB reduction (block Lanczos) is measured
    against this (benchmarks/bench_cb.py)."""
    timings = {}
    with _solver(Kii, Mii, n_modes, tol, max_it, "fixed-interface eigensolve") as eps:
        t0 = time.perf_counter()
        eps.setUp()
        timings["factor_s"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        lam, _ = eigenpairs(eps, Mii, n_modes)
        timings["eigensolve_s"] = time.perf_counter() - t0
    return lam, timings
