"""Craig-Bampton components from Nastran: EXTSEOUT (OP4 + .asm/.pch), DMIG punch files and
nas2cam OP2/OP4, read into :class:`CBModel` (SI, liftoff's DOF order and labels).

Reader: ``pyyeti.nastran`` (BSD-3, maintained, already this project's reference for
``cbcheck`` and the modal integrator). Its ``op4`` reads ASCII and binary OUTPUT4 files of
either byte order and precision (and writes them, which the benchmark uses);
``bulk.bulk2uset``/``rdextrn``/``rdseconct``/``rddtipch`` read the EXTSEOUT .asm/.pch
(GRID, CORD2R/C/S, SECONCT, EXTRN, the TUG1/TEF1/TES1 DTI row tables); ``bulk.rddmig``
reads DMIG punch cards; ``op2.rdnas2cam`` reads nas2cam; ``n2p.rbgeom_uset`` places grids
whose output frames are rectangular, cylindrical or spherical. pyNastran was not added:
it would be a second, much larger Nastran stack next to the one already installed, and it
offers nothing these imports need. Importing ``pyyeti.nastran`` loads pandas and
matplotlib (about 0.7 s); it happens only when a Nastran file is read.

What the import does (docs/reduction.md, "Models from Nastran"):

* DOF order. Nastran's a-set is boundary first ([x_b; q], b = GRID DOFs in EXTRN/SECONCT
  order, q = the modal SPOINTs); liftoff's is [q; x_b]. Unused q-set SPOINTs (zero rows
  and columns of K and M) are dropped; a q-set that is not mass-normalised and
  diagonal is re-orthonormalised (eigh of K_qq, M_qq); K_qb must vanish (CB form).
* Frames. Boundary DOFs are in the grids' output frames (CD). Each translation and
  rotation triple is rotated to the basic frame, u_cd = T^T u_basic (T the grid's frame
  axes in basic, from pyyeti for CD of any type), so that liftoff's geometric
  rigid-body shape applies. A grid whose CD is not basic must then carry whole triples.
  Labels are ``<point>:Tx`` ... with point names from a grid map (``{3: "hd_1"}``) or
  ``g<ID>``.
* Units. The source system is declared (``"in-lbf-s"``, ``"mm-t-s"``, ``"SI"`` ... or
  length/mass/time/force factors) and converted to SI with x_SI = D x_src (D = l for
  translations, 1 for rotations, sqrt(m) l for modal coordinates): M_SI = m l^2 D^-1 M
  D^-1, K_SI = (m l^2 / t^2) D^-1 K D^-1, so M_qq stays I and K_qq becomes omega^2 in
  rad^2/s^2. The source system is recorded in ``CBModel.source_units``.
* Recovery. OUTPUT4 matrices over the a-set (EXTSEOUT's MUG1/MEF1/MES1, or a DTM, ATM,
  LTM) become :class:`CBRecovery` items with row labels and SI units per row.
  Rows stay in the output frames Nastran wrote them in, so their labels use Nastran's
  component names (``g4:T1`` ... ``g4:R3``; element items ``e10:1`` ...).

Bad input (missing or truncated files, a matrix of the wrong size, a boundary grid without
a GRID card, an unknown unit system ...) raises a one-line InputError naming the file and
the item.
"""
from __future__ import annotations

import inspect
import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.linalg as sla

from liftoff.core.errors import InputError
from liftoff.core.labels import COMPONENTS
from liftoff.core.units import FOOT, INCH, LBF  # noqa: F401  (exact; LBF is imported from here too)

from .craig_bampton import CBModel, CBRecovery, validate_cb

NASTRAN_COMPONENTS = ("T1", "T2", "T3", "R1", "R2", "R3")
CB_FORM_TOL = 1e-6     # |K_qb| / sqrt(K_qq K_bb), |M_qq - I|, off-diagonal K_qq / diagonal: CB form
FRAME_TOL = 1e-12      # |T - I| below which an output frame is taken as basic

# ------------------------------------------------------------------------------ units


@dataclass(frozen=True)
class UnitSystem:
    """A consistent unit system: SI value of one unit of length (m), mass (kg) and time (s);
    force is mass x length / time^2 (N)."""

    name: str
    length: float
    mass: float
    time: float

    @property
    def force(self) -> float:
        return self.mass * self.length / self.time**2

    def factor(self, length: int = 0, mass: int = 0, time: int = 0) -> float:
        """SI value of one source unit of dimension length^a mass^b time^c."""
        return self.length**length * self.mass**mass * self.time**time

    def describe(self) -> str:
        return (f"{self.name} (length {self.length:.10g} m, mass {self.mass:.10g} kg, "
                f"time {self.time:.10g} s, force {self.force:.10g} N)")


UNIT_SYSTEMS = {
    "SI": UnitSystem("SI", 1.0, 1.0, 1.0),                          # m, kg, s, N, Pa
    "m-kg-s": UnitSystem("m-kg-s", 1.0, 1.0, 1.0),
    "mm-t-s": UnitSystem("mm-t-s", 1e-3, 1e3, 1.0),                 # mm, tonne, s, N, MPa
    "mm-kg-s": UnitSystem("mm-kg-s", 1e-3, 1.0, 1.0),               # mm, kg, s, mN, kPa
    "mm-kg-ms": UnitSystem("mm-kg-ms", 1e-3, 1.0, 1e-3),            # mm, kg, ms, kN, GPa
    "cm-g-s": UnitSystem("cm-g-s", 1e-2, 1e-3, 1.0),                # cm, g, s, dyne
    "in-lbf-s": UnitSystem("in-lbf-s", INCH, LBF / INCH, 1.0),      # in, lbf s^2/in, s, lbf, psi
    "ft-lbf-s": UnitSystem("ft-lbf-s", FOOT, LBF / FOOT, 1.0),      # ft, slug, s, lbf
}
_DIMENSIONS = ("length", "mass", "time", "force")


def unit_system(spec, who: str = "units") -> UnitSystem:
    """A :class:`UnitSystem` from a name in UNIT_SYSTEMS (case-insensitive), a UnitSystem,
    or a mapping of SI factors with three or four of length, mass, time, force (four
    must be consistent: force = mass length / time^2 to 1e-9)."""
    if isinstance(spec, UnitSystem):
        return spec
    if isinstance(spec, str):
        for key, us in UNIT_SYSTEMS.items():
            if key.lower() == spec.strip().lower():
                return us
        raise InputError(f"{who}: unknown unit system {spec!r}; use one of {', '.join(UNIT_SYSTEMS)} "
                         "or give SI factors {length, mass, time[, force]}")
    if not isinstance(spec, Mapping):
        raise InputError(f"{who}: give a unit system name or a mapping of SI factors, got {spec!r}")
    extra = sorted(set(spec) - set(_DIMENSIONS))
    if extra:
        raise InputError(f"{who}: unknown key {extra[0]!r}; the factors are {', '.join(_DIMENSIONS)}")
    f = {}
    for k, v in spec.items():
        try:
            f[k] = float(v)
        except (TypeError, ValueError):
            f[k] = math.nan
        if not (math.isfinite(f[k]) and f[k] > 0):
            raise InputError(f"{who}: {k} factor must be a positive number (SI per unit), got {v!r}")
    if len(f) < 3:
        raise InputError(f"{who}: give at least three of {', '.join(_DIMENSIONS)}, got {', '.join(f) or 'none'}")
    if "mass" not in f:
        f["mass"] = f["force"] * f["time"] ** 2 / f["length"]
    if "length" not in f:
        f["length"] = f["force"] * f["time"] ** 2 / f["mass"]
    if "time" not in f:
        f["time"] = math.sqrt(f["mass"] * f["length"] / f["force"])
    us = UnitSystem("declared", f["length"], f["mass"], f["time"])
    if "force" in f and abs(us.force / f["force"] - 1) > 1e-9:
        raise InputError(f"{who}: inconsistent factors: mass x length / time^2 = {us.force:.6g} N "
                         f"but force = {f['force']:.6g} N")
    return us


# Quantities of recovery rows: SI unit and dimension exponents (length, mass, time).
QUANTITIES = {
    "length": ("m", (1, 0, 0)), "angle": ("rad", (0, 0, 0)),
    "velocity": ("m/s", (1, 0, -1)), "angular_velocity": ("rad/s", (0, 0, -1)),
    "acceleration": ("m/s^2", (1, 0, -2)), "angular_acceleration": ("rad/s^2", (0, 0, -2)),
    "force": ("N", (1, 1, -2)), "moment": ("N m", (2, 1, -2)), "stress": ("Pa", (-1, 1, -2)),
    "mass": ("kg", (0, 1, 0)), "1": ("1", (0, 0, 0)),
}
# Per-DOF quantities: (translation rows, rotation rows), chosen by the row's component.
DOF_QUANTITIES = {
    "displacement": ("length", "angle"), "velocity": ("velocity", "angular_velocity"),
    "acceleration": ("acceleration", "angular_acceleration"), "load": ("force", "moment"),
}


# --------------------------------------------------------------------------- recovery spec
@dataclass(frozen=True)
class NastranRecovery:
    """One recovery item to import from OUTPUT4 matrices over the component's a-set
    ([x_b; q], Nastran order): ``y = disp @ x + vel @ xdot + acc @ xddot``.

    ``disp``/``vel``/``acc`` name matrices in the component's OP4 (or in ``op4``).
    ``rows``: the .pch DTI table that names the rows ("TUG1" grid DOFs, "TEF1" element
    forces, "TES1" stresses; the default for MUG1, MEF1, MES1), or a list of labels, or
    None (``<name>_<k>``). ``quantity``: one of QUANTITIES for all rows, one of
    DOF_QUANTITIES (translation or rotation by the row's component), or one per row."""

    name: str
    disp: str | None = None
    vel: str | None = None
    acc: str | None = None
    rows: str | Sequence[str] | None = None
    quantity: str | Sequence[str] = "displacement"
    op4: str | Path | None = None

    @property
    def parts(self) -> dict:
        return {k: getattr(self, k).lower() for k in ("disp", "vel", "acc") if getattr(self, k)}


_DTI_OF = {"mug1": "TUG1", "mef1": "TEF1", "mes1": "TES1"}


# ------------------------------------------------------------------------- the raw model
@dataclass
class _Raw:
    """A Nastran CB component as read: a-set matrices in Nastran order and their DOFs."""

    K: np.ndarray
    M: np.ndarray
    iddof: np.ndarray          # (n, 2): GRID or SPOINT id, component 1..6 (0: SPOINT)
    grids: dict                # boundary grid id -> (xyz in basic (3,), T output frame -> basic (3, 3))
    where: str                 # the files, for messages


def _nastran():
    try:
        import pyyeti.nastran as nas
        from pyyeti.nastran import bulk, n2p, op2, op4
    except ImportError as exc:   # pragma: no cover - pyyeti is installed by `make setup`
        raise ImportError("reading Nastran files needs pyyeti (the Makefile installs it: "
                          "pip install --no-deps pyyeti, plus pandas)") from exc
    return nas, bulk, n2p, op2, op4


def _call(where: str, what: str, fn, *args, **kw):
    """Run a pyyeti reader; any failure becomes a one-line InputError naming file and item."""
    try:
        return fn(*args, **kw)
    except InputError:
        raise
    except Exception as exc:
        msg = " ".join(str(exc).split()) or type(exc).__name__
        raise InputError(f"{where}: {what}: cannot be read ({msg[:300]})") from None


def _need_file(path, what: str) -> Path:
    p = Path(path)
    if not p.is_file():
        raise InputError(f"{p}: {what} not found")
    return p


def _read_op4(path: Path, names) -> dict:
    """Named matrices (lower case) of an OP4 file, dense float arrays."""
    _, _, _, _, op4 = _nastran()
    names = [str(n).lower() for n in names]
    mats = _call(str(path), "OP4 file (truncated or not OP4?)", op4.read, str(path), names)
    missing = [n for n in names if n not in mats]
    if missing:
        have = _call(str(path), "OP4 directory", op4.dir, str(path), verbose=False)[0]
        raise InputError(f"{path}: matrix {missing[0]!r} not found (the file has {', '.join(have) or 'none'})")
    out = {}
    for n in names:
        m = mats[n]
        m = m.toarray() if hasattr(m, "toarray") else np.asarray(m)
        if np.iscomplexobj(m):
            raise InputError(f"{path}: {n}: complex matrix; a CB model is real")
        if not np.all(np.isfinite(m)):
            raise InputError(f"{path}: {n}: contains NaN or inf")
        out[n] = np.asarray(m, dtype=float)
    return out


def _grid_frames(uset, gids, where: str) -> dict:
    """Boundary grid id -> (xyz basic, T) from a pyyeti USET table holding all six rows of
    each grid: T^T is the translation block of pyyeti's rigid-body rows of that grid
    (rbgeom_uset, which handles rectangular, cylindrical and spherical output frames)."""
    _, _, n2p, _, _ = _nastran()
    ids = np.asarray(uset.index.get_level_values("id"))
    dof = np.asarray(uset.index.get_level_values("dof"))
    rows = []
    for g in gids:
        r = [np.flatnonzero((ids == g) & (dof == c)) for c in range(1, 7)]
        if any(x.size == 0 for x in r):
            raise InputError(f"{where}: boundary grid {g} has no GRID card (or an incomplete one)")
        rows.extend(int(x[0]) for x in r)
    sub = uset.iloc[rows].copy()
    sub["nasset"] = n2p.mkusetmask("b")
    rb = _call(where, "grid output frames", n2p.rbgeom_uset, sub, np.zeros(3))
    xyz = sub.iloc[::6][["x", "y", "z"]].to_numpy(float)
    return {int(g): (xyz[k], rb[6 * k: 6 * k + 3, :3].T.copy()) for k, g in enumerate(gids)}


# ---------------------------------------------------------------------------- conversion
def _point_names(gids, grid_names, who: str) -> dict:
    grid_names = dict(grid_names or {})
    known = {str(g) for g in gids}
    absent = [g for g in grid_names if str(g) not in known]
    if absent:
        raise InputError(f"{who}: grid_names: grid {absent[0]} is not a boundary grid of the file (boundary grids: "
                         f"{', '.join(sorted(known, key=lambda x: (len(x), x))[:20])}"
                         f"{' ...' if len(known) > 20 else ''})")
    names = {}
    for g in gids:
        nm = str(grid_names.get(g, grid_names.get(str(g), f"g{g}")))
        if not re.fullmatch(r"[^:\s]+", nm):
            raise InputError(f"{who}: grid_names: {nm!r} (grid {g}) is not a point name (no ':' or spaces)")
        names[g] = nm
    seen = {}
    for g, nm in names.items():
        if nm in seen:
            raise InputError(f"{who}: grid_names: grids {seen[nm]} and {g} are both named {nm!r}")
        seen[nm] = g
    return names


def _boundary_map(raw: _Raw, names: dict, who: str):
    """(rows of x_nas, labels, P_b) with x_b,cd = P_b x_b,basic on the boundary rows."""
    b = np.flatnonzero(raw.iddof[:, 1] > 0)
    labels, blocks = [], []
    ids = raw.iddof[b, 0]
    for g in dict.fromkeys(ids.tolist()):
        rows = b[ids == g]
        comps = raw.iddof[rows, 1]
        if len(set(comps.tolist())) != comps.size:
            raise InputError(f"{who}: grid {g} lists a component twice")
        T = raw.grids[g][1]
        basic = np.abs(T - np.eye(3)).max() < FRAME_TOL
        for lo in (1, 4):
            sel = rows[(comps >= lo) & (comps < lo + 3)]
            if not sel.size:
                continue
            c = raw.iddof[sel, 1] - lo
            if not basic and sel.size != 3:
                raise InputError(f"{who}: boundary grid {g} has only components {''.join(str(x + lo) for x in c)} "
                                 "of a triple in a non-basic output frame: cannot rotate it to basic")
            blocks.append((sel, None if basic else T.T[c]))
            labels.extend(f"{names[g]}:{COMPONENTS[lo - 1 + k]}" for k in (c if basic else range(3)))
    return blocks, labels


def _qset_basis(raw: _Raw, who: str) -> tuple[np.ndarray, np.ndarray | None]:
    """(q rows of x_nas, V) with q_nas = V q: unused SPOINTs (zero K and M rows) dropped;
    V is None (identity) when the q-set is already in CB form, else the eigenvectors of
    (K_qq, M_qq). One pass over blocks of q rows, so a large model is not copied."""
    q = np.flatnonzero(raw.iddof[:, 1] == 0)
    b = np.flatnonzero(raw.iddof[:, 1] > 0)
    dk = np.abs(raw.K[q, q])
    kb = np.sqrt(np.maximum(np.abs(raw.K[b, b]), 1e-300))
    kq = np.sqrt(np.maximum(dk, 1e-300))
    used, coupling, k_off, m_err = (np.zeros(q.size, bool), np.zeros(q.size), np.zeros(q.size), np.zeros(q.size))
    for k in range(0, q.size, 512):
        sl = slice(k, k + 512)
        Kr, Mr = raw.K[q[sl]], raw.M[q[sl]]
        used[sl] = np.any(Kr != 0, axis=1) | np.any(Mr != 0, axis=1)
        if b.size:        # |K_qb| / sqrt(K_qq K_bb)
            coupling[sl] = (np.abs(Kr[:, b]) / kb).max(axis=1) / kq[sl]
        j = np.arange(Kr.shape[0])
        Kqq, Mqq = Kr[:, q], Mr[:, q]
        Kqq[j, k + j] = 0.0
        Mqq[j, k + j] -= 1.0
        k_off[sl], m_err[sl] = np.abs(Kqq).max(axis=1, initial=0.0), np.abs(Mqq).max(axis=1, initial=0.0)
    q, dk = q[used], dk[used]
    if q.size and coupling[used].max() > CB_FORM_TOL:
        raise InputError(f"{who}: not a Craig-Bampton model: the modal-boundary stiffness K_qb is not zero "
                         f"(relative {coupling[used].max():.1e})")
    if not q.size or (m_err[used].max() <= CB_FORM_TOL and k_off[used].max() <= CB_FORM_TOL * max(dk.max(), 1e-300)):
        return q, None
    Kqq, Mqq = raw.K[np.ix_(q, q)], raw.M[np.ix_(q, q)]
    try:
        lam, V = sla.eigh(0.5 * (Kqq + Kqq.T), 0.5 * (Mqq + Mqq.T))
    except np.linalg.LinAlgError:
        raise InputError(f"{who}: the modal mass M_qq is not positive definite") from None
    return q, V


def _dof_scale(units: UnitSystem, labels, nq: int) -> np.ndarray:
    """D with x_SI = D x_src over [q; x_b] (modal sqrt(m) l, translation l, rotation 1)."""
    rot = np.array([lab.endswith((":Rx", ":Ry", ":Rz")) for lab in labels])
    return np.concatenate([np.full(nq, math.sqrt(units.mass) * units.length),
                           np.where(rot, 1.0, units.length)])


@dataclass
class _Map:
    """x_nas = P x_lo without forming P: x_lo[j] comes from x_nas[perm[j]], then the q
    columns take V (None: identity) and each triple ``rot_cols[t]`` its rotation ``rot[t]``
    (3 x 3: x_nas rows of the triple = rot[t] @ x_lo of its columns)."""

    perm: np.ndarray
    nq: int
    V: np.ndarray | None
    rot_cols: np.ndarray      # (t, 3) columns of x_lo
    rot: np.ndarray           # (t, 3, 3)

    def right(self, Y: np.ndarray) -> np.ndarray:
        """Y P (k x m) for Y (k x n)."""
        Z = Y[:, self.perm]
        if len(self.rot):
            Z[:, self.rot_cols] = np.einsum("ktj,tji->kti", Z[:, self.rot_cols], self.rot)
        if self.V is not None:
            Z[:, : self.nq] = Z[:, : self.nq] @ self.V
        return Z

    def congruence(self, A: np.ndarray, Dinv: np.ndarray, factor: float) -> np.ndarray:
        """factor D^-1 P^T A P D^-1: one permuted copy, then 3 x 3 rotations of rows and
        columns (O(n) work per triple) and V on the q rows and columns if needed."""
        B = _permuted(A, self.perm)
        if len(self.rot):
            c = self.rot_cols
            B[c] = np.einsum("tji,tjm->tim", self.rot, B[c])
            B[:, c] = np.einsum("mtj,tji->mti", B[:, c], self.rot)
        if self.V is not None:
            q = slice(0, self.nq)
            B[q] = self.V.T @ B[q]
            B[:, q] = B[:, q] @ self.V
        B *= Dinv[:, None]
        B *= Dinv[None, :] * factor
        return B


def _runs(perm: np.ndarray) -> list[tuple[int, int, int]]:
    """Contiguous runs of perm as (position, start, length)."""
    cut = np.flatnonzero(np.diff(perm) != 1) + 1
    starts = np.r_[0, cut]
    lengths = np.diff(np.r_[starts, perm.size])
    return [(int(a), int(perm[a]), int(n)) for a, n in zip(starts, lengths)]


def _permuted(A: np.ndarray, perm: np.ndarray) -> np.ndarray:
    """A[perm][:, perm]; by block copies when perm is a few contiguous runs (Nastran's
    [b; q] to [q; b] is two), which is several times faster than fancy indexing."""
    runs = _runs(perm)
    if len(runs) > 16:
        return A[np.ix_(perm, perm)]
    B = np.empty((perm.size, perm.size), dtype=A.dtype)
    for pi, si, ni in runs:
        for pj, sj, nj in runs:
            B[pi: pi + ni, pj: pj + nj] = A[si: si + ni, sj: sj + nj]
    return B


def _map(q: np.ndarray, V, blocks) -> _Map:
    perm, rot_cols, rot = [q], [], []
    col = q.size
    for rows, R in blocks:
        perm.append(rows)
        if R is not None:
            rot_cols.append(np.arange(col, col + 3))
            rot.append(R)
        col += rows.size
    return _Map(np.concatenate(perm), q.size, V, np.array(rot_cols, dtype=np.int64).reshape(-1, 3),
                np.array(rot).reshape(-1, 3, 3))


def _build(raw: _Raw, name: str, units, grid_names, recovery) -> CBModel:
    """CBModel (SI, [q; x_b], basic frame) from a raw Nastran component."""
    who = f"Nastran component {name!r} ({raw.where})"
    us = unit_system(units, f"{who}: units")
    n = raw.iddof.shape[0]
    for nm, A in (("stiffness", raw.K), ("mass", raw.M)):
        if A.shape != (n, n):
            raise InputError(f"{who}: {nm} matrix is {A.shape[0]} x {A.shape[1]}, but the boundary "
                             f"description lists {n} DOFs")
    names = _point_names(list(raw.grids), grid_names, who)
    blocks, labels = _boundary_map(raw, names, who)
    q, V = _qset_basis(raw, who)
    nq, nb = q.size, len(labels)
    if nb == 0:
        raise InputError(f"{who}: no boundary GRID DOFs")
    P = _map(q, V, blocks)                     # x_nas = P x_lo, x_lo = [q; x_b basic]
    Dinv = 1.0 / _dof_scale(us, labels, nq)
    e = us.factor(length=2, mass=1)
    M = P.congruence(raw.M, Dinv, e)
    raw.M = None                               # the caller's copy is no longer needed: free it
    K = P.congruence(raw.K, Dinv, e / us.time**2)
    raw.K = None
    lam = np.diag(K)[:nq]
    if nq and lam.min() < -CB_FORM_TOL * max(lam.max(), 1e-300):
        raise InputError(f"{who}: negative fixed-interface eigenvalue {lam.min():.3e} (K_qq)")
    gids = list(raw.grids)
    items = tuple(_recovery_item(who, us, spec, mats, rows_labels, P, Dinv, n)
                  for spec, mats, rows_labels in recovery)
    cb = CBModel(name=name, boundary_labels=tuple(labels), fixed_omega=np.sqrt(np.maximum(lam, 0.0)),
                 M=M, K=K, points=tuple(names[g] for g in gids),
                 point_coords=np.array([raw.grids[g][0] for g in gids]).reshape(-1, 3) * us.length,
                 dof_labels=tuple(labels), label_transform=np.hstack([np.zeros((nb, nq)), np.eye(nb)]),
                 n_dof=nq + nb, source_units=us.describe(), recovery=items)
    validate_cb(cb, raw.where)
    return cb


def _row_quantities(who: str, spec: NastranRecovery, comps) -> list[str]:
    """One QUANTITIES key per row; ``comps`` the rows' components 1..6 (0: unknown)."""
    k = len(comps)
    qs = [spec.quantity] * k if isinstance(spec.quantity, str) else list(spec.quantity)
    if len(qs) != k:
        raise InputError(f"{who}: recovery {spec.name!r}: {len(qs)} quantities for {k} rows")
    out = []
    for qty, c in zip(qs, comps):
        if qty in DOF_QUANTITIES:
            if not 1 <= c <= 6:
                raise InputError(f"{who}: recovery {spec.name!r}: quantity {qty!r} needs rows named by DOF "
                                 "component (TUG1 rows, or labels ending in :T1..:R3 / :Tx..:Rz)")
            qty = DOF_QUANTITIES[qty][c > 3]
        if qty not in QUANTITIES:
            raise InputError(f"{who}: recovery {spec.name!r}: unknown quantity {qty!r}; use one of "
                             f"{', '.join([*DOF_QUANTITIES, *QUANTITIES])}")
        out.append(qty)
    return out


def _recovery_item(who, us: UnitSystem, spec: NastranRecovery, mats: dict, rows, P: _Map, Dinv,
                   n_a: int) -> CBRecovery:
    """CBRecovery in SI over [q; x_b]: Y_SI = diag(r) Y_src P D^-1 t^p (p = 0, 1, 2 for
    disp, vel, acc: x_src^(p) = t^p D^-1 x_SI^(p))."""
    labels, comps = rows
    qty = _row_quantities(who, spec, comps)
    r = np.array([us.factor(*QUANTITIES[qn][1]) for qn in qty])
    parts = {}
    for key, mname in spec.parts.items():
        Y = mats[mname]
        if Y.shape != (len(labels), n_a):
            raise InputError(f"{who}: recovery {spec.name!r}: matrix {mname!r} is {Y.shape[0]} x {Y.shape[1]}, "
                             f"expected {len(labels)} x {n_a} (rows x a-set DOFs)")
        power = {"disp": 0, "vel": 1, "acc": 2}[key]
        parts[key] = r[:, None] * P.right(Y) * Dinv * us.time**power
    return CBRecovery(name=spec.name, labels=tuple(labels), units=tuple(QUANTITIES[qn][0] for qn in qty), **parts)


def _row_labels(who: str, spec: NastranRecovery, n_rows: int, pch: Path | None, grid_names) -> tuple:
    """(labels, components) of a recovery item's rows."""
    rows = spec.rows
    if rows is None and spec.parts:
        rows = _DTI_OF.get(next(iter(spec.parts.values())))
    if rows is None:
        return [f"{spec.name}_{k + 1}" for k in range(n_rows)], [0] * n_rows
    if isinstance(rows, str):
        table = rows.upper()
        if table not in ("TUG1", "TEF1", "TES1"):
            raise InputError(f"{who}: recovery {spec.name!r}: rows {rows!r}: use TUG1, TEF1, TES1 or a list of labels")
        if pch is None:
            raise InputError(f"{who}: recovery {spec.name!r}: rows from DTI {table} need the .pch file")
        _, bulk, _, _, _ = _nastran()
        iddof = np.asarray(_call(str(pch), f"DTI {table}", bulk.rddtipch, str(pch), table), dtype=np.int64)
        names = dict(grid_names or {})
        if table == "TUG1":
            labels = [f"{names.get(int(i), names.get(str(i), f'g{i}'))}:{NASTRAN_COMPONENTS[d - 1]}" for i, d in iddof]
            comps = iddof[:, 1].tolist()
        else:
            labels, comps = [f"e{i}:{d}" for i, d in iddof], [0] * iddof.shape[0]
    else:
        labels = [str(s) for s in rows]
        comps = []
        for lab in labels:
            tail = lab.rsplit(":", 1)[-1] if ":" in lab else ""
            comps.append(1 + (NASTRAN_COMPONENTS + COMPONENTS).index(tail) % 6
                         if tail in NASTRAN_COMPONENTS + COMPONENTS else 0)
    if len(labels) != n_rows:
        raise InputError(f"{who}: recovery {spec.name!r}: {len(labels)} row labels for {n_rows} matrix rows")
    return labels, comps


def _recovery_inputs(who: str, recovery, op4: Path | None, pch: Path | None, grid_names) -> list:
    """[(spec, matrices, (labels, comps))] for each NastranRecovery."""
    out = []
    for spec in recovery:
        if not isinstance(spec, NastranRecovery):
            raise InputError(f"{who}: recovery items are NastranRecovery(name, disp=..., ...), got {spec!r}")
        if not spec.parts:
            raise InputError(f"{who}: recovery {spec.name!r}: give at least one of disp, vel, acc (matrix names)")
        src = _need_file(spec.op4, f"OP4 file of recovery {spec.name!r}") if spec.op4 else op4
        if src is None:
            raise InputError(f"{who}: recovery {spec.name!r}: no OP4 file to read {', '.join(spec.parts.values())} from")
        mats = _read_op4(src, list(spec.parts.values()))
        n_rows = next(iter(mats.values())).shape[0]
        if n_rows == 1 and all(not np.any(m) for m in mats.values()):
            raise InputError(f"{src}: {', '.join(mats)}: a 1 x 1 zero placeholder (Nastran wrote no such output)")
        out.append((spec, mats, _row_labels(who, spec, n_rows, pch, grid_names)))
    return out


# ------------------------------------------------------------------------------ readers
def from_extseout(op4, *, name: str, units, asm=None, pch=None, grid_names: Mapping | None = None,
                  stiffness: str | None = None, mass: str | None = None, recovery=()) -> CBModel:
    """CB model from Nastran EXTSEOUT output: ``op4`` (ASCII or binary OUTPUT4 with KAA/MAA or
    KXX/MXX), ``asm`` (GRID and CORD cards of the boundary; default: the .asm beside it) and
    ``pch`` (EXTRN: the order of the a-set DOFs, and the DTI row tables; default: the .pch
    beside it, if present, else SECONCT of the .asm with six DOFs per grid).
    ``units`` the model's unit system (see :func:`unit_system`), ``grid_names`` grid id ->
    point name (default ``g<ID>``), ``recovery`` a list of :class:`NastranRecovery`."""
    _, bulk, _, _, _ = _nastran()
    op4 = _need_file(op4, "EXTSEOUT OP4 file")
    asm = _need_file(asm if asm is not None else op4.with_suffix(".asm"), "EXTSEOUT .asm file")
    pch = Path(pch) if pch is not None else op4.with_suffix(".pch")
    if not pch.is_file():
        if pch != op4.with_suffix(".pch"):
            raise InputError(f"{pch}: EXTSEOUT .pch file not found")
        pch = None
    who = f"Nastran component {name!r} ({op4})"
    if pch is not None:
        iddof = np.asarray(_call(str(pch), "EXTRN", bulk.rdextrn, str(pch)), dtype=np.int64).reshape(-1, 2)
    else:
        a_ids = _call(str(asm), "SECONCT", bulk.rdseconct, str(asm))[0]
        spoints = _call(str(asm), "SPOINT", bulk.rdspoints, str(asm))
        sp = set(np.asarray(spoints if spoints is not None else [], dtype=np.int64).tolist())
        iddof = np.array([(g, c) for g in np.asarray(a_ids, dtype=np.int64)
                          for c in ((0,) if g in sp else range(1, 7))], dtype=np.int64).reshape(-1, 2)
    have = _call(str(op4), "OP4 directory (truncated or not OP4?)", _op4_names, op4)
    kname = (stiffness or next((n for n in ("kaa", "kxx") if n in have), "kaa")).lower()
    mname = (mass or next((n for n in ("maa", "mxx") if n in have), "maa")).lower()
    if kname == mname:
        raise InputError(f"{op4}: stiffness and mass both name the matrix {kname!r}")
    mats = _read_op4(op4, [kname, mname])
    uset, _ = _call(str(asm), "GRID/CORD cards", bulk.bulk2uset, str(asm))
    gids = list(dict.fromkeys(iddof[iddof[:, 1] > 0, 0].tolist()))
    raw = _Raw(K=mats.pop(kname), M=mats.pop(mname), iddof=iddof, grids=_grid_frames(uset, gids, str(asm)),
               where=f"{op4}, {asm}" + (f", {pch}" if pch else ""))
    del mats                                   # the raw matrices live in raw only (freed during _build)
    for nm, A in ((kname, raw.K), (mname, raw.M)):
        if A.shape != (iddof.shape[0],) * 2:
            raise InputError(f"{op4}: {nm}: matrix is {A.shape[0]} x {A.shape[1]}, but "
                             f"{pch or asm} lists {iddof.shape[0]} a-set DOFs")
    return _build(raw, name, units, grid_names, _recovery_inputs(who, recovery, op4, pch, grid_names))


def _op4_names(path: Path) -> list[str]:
    _, _, _, _, op4 = _nastran()
    return [n.lower() for n in op4.dir(str(path), verbose=False)[0]]


def from_dmig(pch, *, name: str, units, bulk=None, stiffness: str = "KAAX", mass: str = "MAAX",
              grid_names: Mapping | None = None) -> CBModel:
    """CB model from DMIG punch cards (``matrix_factory.pch`` style, small or large field):
    stiffness and mass DMIGs over the boundary GRID DOFs and the modal SPOINTs, with the
    GRID (and CORD) cards of the boundary grids in ``bulk`` (default: the punch file itself)."""
    _, blk, _, _, _ = _nastran()
    pch = _need_file(pch, "DMIG punch file")
    bulk = _need_file(bulk if bulk is not None else pch, "bulk file with the GRID cards")
    names = [stiffness.lower(), mass.lower()]
    dct = _call(str(pch), f"DMIG {stiffness}, {mass}", blk.rddmig, str(pch), names)
    for nm in names:
        if nm not in dct:
            raise InputError(f"{pch}: DMIG {nm.upper()} not found (the file has "
                             f"{', '.join(k.upper() for k in _call(str(pch), 'DMIG', blk.rddmig, str(pch))) or 'none'})")
        if dct[nm].shape[0] != dct[nm].shape[1] or dct[nm].index.nlevels != 2 or dct[nm].columns.nlevels != 2:
            raise InputError(f"{pch}: DMIG {nm.upper()}: not a square GRID/SPOINT matrix ({dct[nm].shape})")
    Kdf, Mdf = dct[names[0]], dct[names[1]]
    index = Kdf.index.append(Mdf.index.difference(Kdf.index)) if not Kdf.index.equals(Mdf.index) else Kdf.index
    K = Kdf.reindex(index=index, columns=index, fill_value=0.0).to_numpy(float)
    M = Mdf.reindex(index=index, columns=index, fill_value=0.0).to_numpy(float)
    iddof = np.array(index.tolist(), dtype=np.int64).reshape(-1, 2)
    uset, _ = _call(str(bulk), "GRID/CORD cards", blk.bulk2uset, str(bulk))
    gids = list(dict.fromkeys(iddof[iddof[:, 1] > 0, 0].tolist()))
    raw = _Raw(K=K, M=M, iddof=iddof, grids=_grid_frames(uset, gids, str(bulk)), where=f"{pch}")
    return _build(raw, name, units, grid_names, [])


def from_nas2cam(op2, *, se: int, name: str, units, op4=None, grid_names: Mapping | None = None) -> CBModel:
    """CB model of superelement ``se`` from nas2cam output (``op2`` with its ``op4``, default
    the .op4 beside it): MAA/KAA of the superelement and its USET table (coordinates and
    output frames). GRID DOFs are the boundary, SPOINTs the modal coordinates."""
    _, _, n2p, op2mod, _ = _nastran()
    op2 = _need_file(op2, "nas2cam OP2 file")
    op4 = _need_file(op4 if op4 is not None else op2.with_suffix(".op4"), "nas2cam OP4 file")
    nas = _call(f"{op2}, {op4}", "nas2cam data", op2mod.rdnas2cam, str(op2), str(op4))
    for key in ("uset", "maa", "kaa"):
        if se not in nas.get(key, {}):
            raise InputError(f"{op2}: superelement {se}: no {key.upper()} (has {sorted(nas.get(key, {}))})")
    uset, M, K = nas["uset"][se], np.asarray(nas["maa"][se], float), np.asarray(nas["kaa"][se], float)
    if uset.shape[0] != M.shape[0]:
        uset = uset[_call(str(op2), "USET a-set", n2p.mksetpv, uset, "p", "a")]
    iddof = np.array(uset.index.tolist(), dtype=np.int64).reshape(-1, 2)
    gids = list(dict.fromkeys(iddof[iddof[:, 1] > 0, 0].tolist()))
    raw = _Raw(K=K, M=M, iddof=iddof, grids=_grid_frames(nas["uset"][se], gids, str(op2)), where=f"{op2}, se {se}")
    return _build(raw, name, units, grid_names, [])


def import_nastran(path, *, name: str, units, grid_names: Mapping | None = None, **kw) -> CBModel:
    """One entry point for scenarios: the format follows the suffix of ``path`` --
    ``.op4`` EXTSEOUT (:func:`from_extseout`; keywords asm, pch, stiffness, mass,
    recovery), ``.pch``/``.dmig``/``.bdf`` DMIG (:func:`from_dmig`; keywords bulk,
    stiffness, mass), ``.op2`` nas2cam (:func:`from_nas2cam`; keywords se, op4)."""
    suffix = Path(path).suffix.lower()
    readers = {".op4": from_extseout, ".pch": from_dmig, ".dmig": from_dmig, ".bdf": from_dmig,
               ".op2": from_nas2cam}
    if suffix not in readers:
        raise InputError(f"{path}: unknown Nastran file type {suffix!r}; use .op4 (EXTSEOUT), "
                         ".pch/.dmig/.bdf (DMIG) or .op2 (nas2cam)")
    reader = readers[suffix]
    allowed = [p for p in inspect.signature(reader).parameters if p not in ("name", "units", "grid_names")][1:]
    for key in kw:
        if key not in allowed:
            raise InputError(f"{path}: {key!r} is not an option of {reader.__name__} (options: {', '.join(allowed)})")
    return reader(path, name=name, units=units, grid_names=grid_names, **kw)


# ------------------------------------------------------------------------------ writer
OP4_NAME = re.compile(r"^[A-Z][A-Z0-9_]{0,7}$")      # Nastran's matrix names: 8 characters, a letter first


def write_op4(path, matrices: Mapping[str, np.ndarray]) -> Path:
    """Write named real matrices to a binary, double-precision OUTPUT4 file (pyyeti.nastran.op4,
    the format Nastran's DMAP OUTPUT4 and pyyeti read), atomically. Names: upper case, at most
    8 characters, a letter first; order kept."""
    from liftoff.core.records import atomic_path

    _, _, _, _, op4 = _nastran()
    names, mats = [], []
    for name, m in matrices.items():
        if not OP4_NAME.match(name):
            raise InputError(f"{path}: OP4 matrix name {name!r}: upper case, at most 8 characters, a letter first")
        a = np.atleast_2d(np.asarray(m, dtype=float))
        if a.ndim != 2 or not np.all(np.isfinite(a)):
            raise InputError(f"{path}: OP4 matrix {name!r}: a finite 2-D real matrix is needed, got shape {a.shape}")
        names.append(name)
        mats.append(a)
    with atomic_path(path, suffix=".op4") as tmp:
        op4.write(str(tmp), names, mats, binary=True, digits=16, sparse="dense")
    return Path(path)


def read_op4(path, names=None) -> dict[str, np.ndarray]:
    """Named matrices of an OP4 file (lower-case names, dense float arrays); ``names``: those
    only (a one-line InputError for a missing one), default all."""
    p = _need_file(path, "OP4 file")
    if names is None:
        _, _, _, _, op4 = _nastran()
        names = _call(str(p), "OP4 directory", op4.dir, str(p), verbose=False)[0]
    return _read_op4(p, names)


def interface_otm(path, *, name: str, units, disp: str | None = None, vel: str | None = None,
                  acc: str | None = None, rows=None, quantity="displacement") -> tuple:
    """A payload provider's output transformation matrices applied at one interface point
    (issue 24): matrices ``disp``/``vel``/``acc`` of the OUTPUT4 file ``path``, each
    (rows x 6) over the point's motion (T1 T2 T3 R1 R2 R3 in liftoff's axes, source units),
    so that y = disp @ x + vel @ xdot + acc @ xddot. Returns (labels, SI units per row,
    {part: (rows x 6) matrix in SI}): Y_SI = diag(r) Y_src diag(c) t^p, with r the rows'
    quantities' SI factors (``quantity`` as :class:`NastranRecovery`'s), c = 1/length on the
    translation columns (x_src = x_SI / length) and 1 on the rotations (rad), p = 0, 1, 2."""
    spec = NastranRecovery(name=name, disp=disp, vel=vel, acc=acc, rows=list(rows) if rows is not None else None,
                           quantity=quantity)
    who = f"OTM {name!r} ({Path(path).name})"
    if not spec.parts:
        raise InputError(f"{who}: give at least one of disp, vel, acc (matrix names)")
    us = unit_system(units, f"{who}: units")
    mats = _read_op4(_need_file(path, f"OP4 file of {who}"), list(spec.parts.values()))
    n_rows = next(iter(mats.values())).shape[0]
    for mname, Y in mats.items():
        if Y.shape != (n_rows, 6):
            raise InputError(f"{who}: matrix {mname!r} is {Y.shape[0]} x {Y.shape[1]}, expected {n_rows} x 6 "
                             "(rows x the interface point's T1 T2 T3 R1 R2 R3)")
    labels, comps = _row_labels(who, spec, n_rows, None, None)
    qty = _row_quantities(who, spec, comps)
    r = np.array([us.factor(*QUANTITIES[q][1]) for q in qty])
    c = np.array([1.0 / us.length] * 3 + [1.0] * 3)
    out = {key: r[:, None] * mats[mname] * c[None, :] * us.time ** {"disp": 0, "vel": 1, "acc": 2}[key]
           for key, mname in spec.parts.items()}
    return tuple(labels), tuple(QUANTITIES[q][0] for q in qty), out


_STATED = re.compile(r"^\$ units: (?P<name>\S+) \(length (?P<length>\S+) m, mass (?P<mass>\S+) kg, "
                     r"time (?P<time>\S+) s")


def stated_units(path, lines: int = 20) -> UnitSystem | None:
    """The unit system a punch file states in its ``$ units:`` comment (:func:`write_dmig`
    writes one), None when its first ``lines`` lines state none (Nastran's own files)."""
    try:
        with open(path, "r", errors="replace") as f:
            for _, line in zip(range(lines), f):
                m = _STATED.match(line)
                if m:
                    return UnitSystem(m["name"], float(m["length"]), float(m["mass"]), float(m["time"]))
    except (OSError, ValueError):
        return None
    return None


def same_units(a: UnitSystem, b: UnitSystem, rtol: float = 1e-9) -> bool:
    """Whether two unit systems have the same length, mass and time (``describe``'s 10
    digits: 1e-9)."""
    return all(abs(x - y) <= rtol * abs(y) for x, y in ((a.length, b.length), (a.mass, b.mass), (a.time, b.time)))


def write_dmig(cb: CBModel, path, *, units="SI", grid_ids: Mapping | None = None, spoint1: int | None = None,
               stiffness: str = "KAAX", mass: str = "MAAX"):
    """Write ``cb`` as a Nastran punch file: GRID cards of its boundary points (basic
    frame, CD = 0), SPOINTs for its modal coordinates and DMIG stiffness and mass cards in
    Nastran's order [x_b; q] and the unit system ``units`` (the inverse of
    :func:`from_dmig`, which reads the file back). Point ``g<ID>`` is grid ID unless
    ``grid_ids`` (point -> grid ID) says otherwise; SPOINTs start at ``spoint1`` (default:
    the largest grid ID + 1). Written atomically; returns the path."""
    import pandas as pd

    from liftoff.core.labels import split_label
    from liftoff.core.records import atomic_path

    _, bulk, _, _, _ = _nastran()
    who = f"CB model {cb.name!r} -> {path}"
    us = unit_system(units, f"{who}: units")
    ids = {}
    for p in cb.boundary_points:
        g = (grid_ids or {}).get(p)
        if g is None:
            m = re.fullmatch(r"g(\d+)", p)
            if not m:
                raise InputError(f"{who}: point {p!r} has no grid ID (name it g<ID> or give grid_ids)")
            g = int(m.group(1))
        ids[p] = int(g)
    if len(set(ids.values())) != len(ids):
        raise InputError(f"{who}: two points share a grid ID")
    nq = cb.n_modes
    s1 = max(ids.values()) + 1 if spoint1 is None else int(spoint1)
    rows = [(ids[pt], c + 1) for pt, c in map(split_label, cb.boundary_labels)] + [(s1 + k, 0) for k in range(nq)]
    order = np.r_[np.arange(nq, nq + cb.n_boundary), np.arange(nq)]       # [x_b; q] from [q; x_b]
    D = _dof_scale(us, cb.boundary_labels, nq)[order]
    e = us.factor(length=2, mass=1)
    index = pd.MultiIndex.from_tuples(rows, names=["id", "dof"])
    K = pd.DataFrame((us.time**2 / e) * (D[:, None] * cb.K[np.ix_(order, order)] * D), index=index, columns=index)
    M = pd.DataFrame((1.0 / e) * (D[:, None] * cb.M[np.ix_(order, order)] * D), index=index, columns=index)
    xyz = np.array([cb.point_coord(p) for p in cb.boundary_points]).reshape(-1, 3) / us.length
    with atomic_path(path) as tmp, open(tmp, "w") as f:
        f.write(f"$ liftoff CB model {cb.name!r}: {nq} modes, {cb.n_boundary} boundary DOFs\n"
                f"$ units: {us.describe()}\n")
        bulk.wtgrids(f, [ids[p] for p in cb.boundary_points], 0, xyz, 0, form="{:16.9E}")
        if nq:
            bulk.wtspoints(f, s1 + np.arange(nq))
        bulk.wtdmig(f, {stiffness: K, mass: M})
    return Path(path)
