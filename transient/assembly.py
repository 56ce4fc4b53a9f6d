"""Turn a problem description into the small dense arrays the kernel marches on.

Contact rows: one row per coupled direction (``contact/label_a``), with the mode-shape
rows Phi_ca, Phi_cb (zero row for ground), the compliance 1/K_C (0 for a rigid bolt)
and the offset c (normal_sign * gap on the axial row), so that while coupled the force
on A is f = -K_C (c + x_a - x_b) (eq. 3). A contact with a ``normal`` couples the rows of
its frame (normal, tangents), each a combination of the labelled rows. The contact laws
beyond the reference's (friction, dashpots, latches, soft release; transient/contact_laws.py)
add per-row damping time constants tau = c/K_C, friction coefficients, latch forces and
the release force-travel tables (concatenated, ``rptr`` the offsets per contact).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from liftoff.core.errors import InputError
from liftoff.core.labels import COMPONENTS, split_label

from .body import ModalBody
from .model import Forcing
from .result import ContactDirection


@dataclass
class ContactRows:
    directions: tuple      # (n_c,) ContactDirection: what each row is
    names: tuple           # (n_contacts,) contact names
    Phi_a: np.ndarray      # (n_c, n_a)
    Phi_b: np.ndarray      # (n_c, n_b)
    compliance: np.ndarray  # (n_c,) 1/K_C, 0 for rigid
    offset: np.ndarray     # (n_c,) c
    contact: np.ndarray    # (n_c,) index of the contact point
    axial: np.ndarray      # (n_c,) bool
    sign: np.ndarray       # (n_c,) normal_sign of the contact
    release: np.ndarray    # (n_contacts,)
    axial_column: np.ndarray  # (n_contacts,)
    normal_sign: np.ndarray   # (n_contacts,)
    tau: np.ndarray = None    # (n_c,) s, dashpot / K_C (0: no damping)
    mu: np.ndarray = None     # (n_c,) friction coefficient of the row's contact on its tangent rows, else 0
    latch: np.ndarray = None  # (n_contacts,) N, latch force (inf: no latch)
    laws: bool = False        # any friction, damping, latch or soft release: the kernel's extended path
    rtravel: np.ndarray = None  # (k,) m, release_force travel of every soft contact, concatenated
    rforce: np.ndarray = None   # (k,) N, the matching forces
    rptr: np.ndarray = None     # (n_contacts + 1,) int64, contact c's table is [rptr[c], rptr[c + 1])

    @property
    def n(self) -> int:
        return self.compliance.size

    @property
    def labels(self) -> tuple:
        """``contact/label_a`` per row."""
        return tuple(d.label for d in self.directions)


def _direction(c, ci: int, d: int, la: str, lb: str | None, oriented: bool, frame: np.ndarray) -> ContactDirection:
    """What row d of contact c is: a labelled DOF, or (with a normal) n, t1, t2 ... over its labels."""
    if not oriented:
        return ContactDirection(c.name, ci, la, lb, COMPONENTS[split_label(la)[1]], d == c.axial, c.normal_sign)
    comp = "n" if d == 0 else f"t{d}"
    pa = {split_label(x)[0] for x in c.labels_a}
    pb = {split_label(x)[0] for x in c.labels_b if x is not None}
    name_a = pa.pop() if len(pa) == 1 else c.name
    name_b = (pb.pop() if len(pb) == 1 else c.name) if pb else None
    return ContactDirection(c.name, ci, f"{name_a}:{comp}", None if name_b is None else f"{name_b}:{comp}", comp,
                            d == 0, c.normal_sign, tuple(float(x) for x in frame[d]))


def contact_rows(body_a: ModalBody, body_b: ModalBody, contacts) -> ContactRows:
    """One row per coupled direction of every contact point, in contact order."""
    na, nb = body_a.n_modes, body_b.n_modes
    dirs, Pa, Pb, comp, off, cidx, ax, sgn, axcol, tau, mu = [], [], [], [], [], [], [], [], [], [], []
    for ci, c in enumerate(contacts):
        frame = c.frame()
        oriented = getattr(c, "normal", None) is not None
        rows_a = body_a.rows(c.labels_a)
        rows_b = np.array([np.zeros(nb) if lb is None else body_b.phi[body_b.dof_index(lb)]
                           for lb in c.labels_b]).reshape(c.n_dirs, nb)
        for d, (la, lb) in enumerate(zip(c.labels_a, c.labels_b)):
            if d == c.axial:
                axcol.append(len(dirs))
            dirs.append(_direction(c, ci, d, la, lb, oriented, frame))
            Pa.append(frame[d] @ rows_a if oriented else rows_a[d])
            Pb.append(frame[d] @ rows_b if oriented else rows_b[d])
            comp.append(0.0 if c.rigid else 1.0 / c.stiffness[d])
            off.append(c.normal_sign * c.gap if d == c.axial else 0.0)
            cidx.append(ci)
            ax.append(d == c.axial)
            sgn.append(c.normal_sign)
            tau.append(0.0 if c.rigid else c.damping[d] / c.stiffness[d])
            mu.append(c.friction if d != c.axial else 0.0)
    n = len(dirs)
    latch = np.array([np.inf if c.latch_force is None else c.latch_force for c in contacts])
    tables = [(np.zeros(0), np.zeros(0)) if c.release_force is None else c.release_force
              for c in contacts]
    rptr = np.concatenate([[0], np.cumsum([t[0].size for t in tables])]).astype(np.int64)
    return ContactRows(directions=tuple(dirs), names=tuple(c.name for c in contacts),
                       Phi_a=np.array(Pa).reshape(n, na), Phi_b=np.array(Pb).reshape(n, nb),
                       compliance=np.array(comp), offset=np.array(off), contact=np.array(cidx, dtype=np.int64),
                       axial=np.array(ax, dtype=np.bool_), sign=np.array(sgn),
                       release=np.array([c.release_time for c in contacts]),
                       axial_column=np.array(axcol, dtype=np.int64),
                       normal_sign=np.array([c.normal_sign for c in contacts]),
                       tau=np.array(tau), mu=np.array(mu), latch=latch,
                       laws=any(c.has_laws for c in contacts),
                       rtravel=np.concatenate([np.zeros(0)] + [t[0] for t in tables]).astype(float),
                       rforce=np.concatenate([np.zeros(0)] + [t[1] for t in tables]).astype(float), rptr=rptr)


#: values (points x columns) interp_columns forms at once
INTERP_BLOCK = 1 << 20


def interp_columns(x, xp: np.ndarray, fp: np.ndarray) -> np.ndarray:
    """``np.interp(x, xp, fp[:, m])`` of every column m of ``fp`` (n_k, n) at once: (x.size, n),
    or (n,) for a scalar x. numpy's arithmetic (the interval's slope (fp[j+1] - fp[j]) /
    (xp[j+1] - xp[j]), then slope (x - xp[j]) + fp[j]; fp[j] at a breakpoint, the end values
    outside [xp[0], xp[-1]], NaN at a NaN x), so the same values bit for bit: one search a
    point instead of one np.interp call a column (7,000 calls, 15 ms, a default case)."""
    xp, fp = np.asarray(xp, dtype=float), np.asarray(fp, dtype=float)
    xs = np.asarray(x, dtype=float)
    scalar = xs.ndim == 0
    xs = xs.reshape(-1)
    if xp.size == 0:
        raise ValueError("interp_columns: no breakpoints (xp is empty)")
    if xp.size == 1:
        out = np.repeat(fp[:1], xs.size, axis=0)
    else:
        out = np.empty((xs.size, fp.shape[1]))
        rows = max(1, INTERP_BLOCK // max(fp.shape[1], 1))
        for r0 in range(0, xs.size, rows):   # a block of points at a time: a few temporaries of its size
            out[r0:r0 + rows] = _interp_block(xs[r0:r0 + rows], xp, fp)
    return out[0] if scalar else out


def _interp_block(xs: np.ndarray, xp: np.ndarray, fp: np.ndarray) -> np.ndarray:
    """:func:`interp_columns` at the points ``xs`` (1-D), two or more breakpoints."""
    j = np.clip(np.searchsorted(xp, xs, side="right") - 1, 0, xp.size - 2)   # xp[j] <= x < xp[j+1]
    lo, hi = fp[j], fp[j + 1]
    with np.errstate(all="ignore"):          # (a repeated breakpoint or an infinite value: set below, as numpy)
        slope = (hi - lo) / (xp[j + 1] - xp[j])[:, None]
        out = slope * (xs - xp[j])[:, None] + lo
        bad = np.isnan(out)
        if bad.any():                        # numpy's fallback for infinite values: from the other end
            out[bad] = (slope * (xs - xp[j + 1])[:, None] + hi)[bad]
            flat = np.isnan(out) & (lo == hi)
            out[flat] = lo[flat]
    out[xs == xp[j]] = lo[xs == xp[j]]       # at a breakpoint: its value
    out[xs < xp[0]] = fp[0]
    out[xs >= xp[-1]] = fp[-1]
    out[np.isnan(xs)] = np.nan
    return out


@dataclass
class ModalLoad:
    """Modal force of one body: const + piecewise-linear table on a merged time grid."""

    const: np.ndarray   # (n,)
    times: np.ndarray   # (n_k,)
    table: np.ndarray   # (n_k, n)

    def at(self, t: float) -> np.ndarray:
        if self.times.size == 0:
            return self.const.copy()
        return self.const + interp_columns(t, self.times, self.table)


def modal_load(body: ModalBody, key: str, forcing: Forcing) -> ModalLoad:
    """Constant point forces + gravity (eq. 14) + tabulated point and modal forces, in modal form."""
    n = body.n_modes
    const = np.zeros(n)
    if n == 0:
        return ModalLoad(const, np.zeros(0), np.zeros((0, 0)))
    const += body.modal_gravity(forcing.gravity)
    for p in forcing.constant:
        if p.body == key:
            const += body.phi[body.dof_index(p.label)] * p.value
    tables = [t for t in forcing.tables if t.body == key]
    modal = [m for m in forcing.modal if m.body == key]
    if not tables and not modal:
        return ModalLoad(const, np.zeros(0), np.zeros((0, n)))
    grid = np.unique(np.concatenate([t.time for t in tables] + [m.time for m in modal]))
    if grid.size * n > 5e8:
        raise InputError(f"body {body.name!r}: merged force tables need {grid.size} x {n} values; "
                         "resample the tables on a common, coarser grid")
    table = np.zeros((grid.size, n))
    for t in tables:  # exact: every table is linear between its own breakpoints, a subset of grid
        table += np.outer(np.interp(grid, t.time, t.value), body.phi[body.dof_index(t.label)])
    for m in modal:
        table += interp_columns(grid, m.time, m.values)
    return ModalLoad(const, grid, table)


def feedback_factors(n: int, key: str, forcing: Forcing, t0: float):
    """Feedback matrices of a body as rank-factored terms: (U (n, r), V (r, 2n), since (r,),
    until (r,)) acting on [q; v].

    Each [matrix, rate_matrix] is factored by SVD (singular values below 1e-14 of the
    largest dropped: exact to rounding); a feedback given with its ``factors`` (U, V, and W
    for a rate matrix) is used as it is (O(n r), no SVD of an n x n matrix). Then force = sum_k
    U[:, k] (V[k] . [q; v]) over the terms with since[k] <= t < until[k]."""
    Us, Vs, sinces, untils = [np.zeros((n, 0))], [np.zeros((0, 2 * n))], [np.zeros(0)], [np.zeros(0)]
    for fb in forcing.feedback:
        if fb.body != key or n == 0:
            continue
        if fb.factors is not None and (fb.rate_matrix is None or len(fb.factors) == 3):
            U, V, *W = fb.factors
            Us.append(U)
            Vs.append(np.hstack([V, W[0] if W else np.zeros_like(V)]))
            sinces.append(np.full(U.shape[1], fb.since))
            untils.append(np.full(U.shape[1], fb.until))
            continue
        rate = np.zeros_like(fb.matrix) if fb.rate_matrix is None else fb.rate_matrix
        U, s, Vt = np.linalg.svd(np.hstack([fb.matrix, rate]), full_matrices=False)
        r = int(np.sum(s > 1e-14 * max(s[0], 1e-300))) if s.size else 0
        Us.append(U[:, :r] * s[:r])
        Vs.append(Vt[:r])
        sinces.append(np.full(r, fb.since))
        untils.append(np.full(r, fb.until))
    return np.hstack(Us), np.vstack(Vs), np.concatenate(sinces), np.concatenate(untils)


def feedback_at(n: int, key: str, forcing: Forcing, t: float):
    """(U, V) of the feedback terms of a body active at time t (since <= t < until):
    force U (V [q; v]); statics uses the displacement part V[:, :n]."""
    U, V, since, until = feedback_factors(n, key, forcing, t)
    on = (since <= t) & (t < until)
    return U[:, on], V[on]


def feedback_matrix(n: int, key: str, forcing: Forcing, t: float, rate: bool = False) -> np.ndarray:
    """Sum of the feedback matrices (``rate``: rate matrices) active at time t (statics uses
    the displacement part)."""
    M = np.zeros((n, n))
    for fb in forcing.feedback:
        if fb.body == key and fb.active(t):
            disp, vel = fb.dense()
            if not rate:
                M += disp
            elif vel is not None:
                M += vel
    return M
