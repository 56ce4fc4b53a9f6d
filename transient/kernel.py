"""Compiled time-marching kernel (numba): exact modal steps + contact solve, one chunk of steps.

Per step (section 2.3, DESIGN.md): both bodies are advanced with the contact force at
the end of the step set to zero (x_free), the end-of-step relative contact displacement
is affine in the contact force, e = e_free + W f (W the step flexibility), and

* ``direct``: (C + W_SS) f_S = -(c + e_free)_S on the active set S (C = diag(1/K_C)),
  the active set iterated until consistent (released axial rows in tension open, open
  rows that penetrate close); the inverse per active-set pattern is cached. Cycling
  switches to one flip per iteration (least-index rule), then fails.
  Rigid (Lagrange) rows: a force linear from the previous end value and closing the gap
  at the step end is unstable (amplification -2 - sqrt(3) for a rigid mass), so a rigid
  row carries its own start value g over the step, f(tau) = g + (f1 - g) tau / h, with
  two conditions: relative displacement and velocity both zero at the step end. The
  unknowns are x = [f1; g] and the step matrix is [[C + W_B, W_A], [Wd_B, Wd_A]] with
  W_* = Phi diag(coefficient) Phi^T (B: end value, A: start value, d: velocity).
  A released rigid row found in tension at the step end is 'opening': f1 = 0 and g
  chosen so that the gap just closes at the step end (the force ramps down to zero over
  the step); it is open from the next step on (or at once if g itself is tensile).
* ``fixed-point``: the reference's iteration f <- -K_C (c + e_free + W f) with its
  convergence test |f_j - f_i| < tol (eq. 11).
* contact laws beyond the reference's (friction, dashpots, latches, soft release: ``Contact.laws``; the
  method in transient/contact_laws.py): ``_laws_candidates``, ``_solve_laws`` and
  ``_laws_after_step`` at the end of this file, called from the same loop in place of the
  candidate rows and ``_solve_direct``; problems without them never enter that branch.

No Python objects, no I/O: named bundles of arrays in (:class:`Modal`, :class:`Contact`, ...),
arrays out; status codes report failures.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

OK, NO_CONVERGENCE, CYCLING, SINGULAR, FRICTION_SINGULAR = 0, 1, 2, 3, 4
#: steps whose outputs are recovered together, one matrix-matrix product per kind (march)
OUT_BLOCK = 64
BOLTED, CLOSED, OPEN = 0, 1, 2


# ------------------------------------------------------------------ inputs, as named bundles
# numba passes a NamedTuple of arrays by value (a struct of array views): no copies, no
# Python objects in the loop. State, Cache and History are mutated in place. march unpacks
# each bundle once per call and the per-step helpers take plain arrays: unpacking bundles
# inside them (reference counting of every array, every step) cost 15 % on
# benchmarks/bench_transient.py.
class Stepping(NamedTuple):
    """Time stepping and contact-solve settings."""

    t0: float       # s, time of step 0
    h: float        # s, step
    method: int     # 0 direct active-set solve, 1 fixed-point iteration (eq. 11)
    tol: float      # N, fixed-point convergence test
    max_iter: int


class Modal(NamedTuple):
    """Both bodies as one modal set: modes 0..na-1 of body a, then those of body b."""

    na: int
    coef: np.ndarray    # (8, n) exact step coefficients F G Ac Bc Fd Gd Acd Bcd (eq. 9-10)
    w2: np.ndarray      # (n,) omega^2
    zw2: np.ndarray     # (n,) 2 zeta omega
    const: np.ndarray   # (n,) constant modal load
    tk: np.ndarray      # (n_k,) breakpoints of the tabulated modal load
    Pk: np.ndarray      # (n_k, n) tabulated modal load
    U: np.ndarray       # (n, r) feedback factors: force = sum_k U[:, k] (V[k] . [q; v]) (eq. 26)
    V: np.ndarray       # (r, 2 n)
    since: np.ndarray   # (r,) s, each term on while since <= t < until
    until: np.ndarray   # (r,) s


class Contact(NamedTuple):
    """Contact rows: Phi = [Phi_ca, -Phi_cb], so e = Phi q = x_a - x_b and Phi^T f acts on A and B."""

    Phi: np.ndarray         # (nc, n)
    compliance: np.ndarray  # (nc,) 1/K_C, 0 for rigid rows
    offset: np.ndarray      # (nc,) c
    contact: np.ndarray     # (nc,) index of the contact point of each row
    axial: np.ndarray       # (nc,) bool
    sign: np.ndarray        # (nc,) normal sign
    release: np.ndarray     # (ncon,) s
    W: np.ndarray           # (n2, n2) step matrix (n2 = nc, or 2 nc with rigid rows: unknowns [f1; g])
    C2: np.ndarray          # (n2,) its compliance diagonal
    laws: bool              # friction, dashpots or latches present: the _solve_laws path
    tau: np.ndarray         # (nc,) s, dashpot / K_C (W already holds + diag(tau) W_v)
    Wv: np.ndarray          # (nc, n2) velocity step flexibility [W_Bcd, W_Acd] (0 rows: no dashpot)
    mu: np.ndarray          # (nc,) friction coefficient on tangent rows of friction points, else 0
    axrow: np.ndarray       # (nc,) the normal row of each row's contact point
    axcol: np.ndarray       # (ncon,) the normal row of each contact point
    latch: np.ndarray       # (ncon,) N, latch force (inf: none)
    rtravel: np.ndarray     # (k,) m, soft-release travel tables of all contacts, concatenated (0: none)
    rforce: np.ndarray      # (k,) N, their forces F(s)
    rptr: np.ndarray        # (ncon + 1,) int64, contact c's table is [rptr[c], rptr[c + 1]) (empty: no soft release)


class OutputRows(NamedTuple):
    """Output rows per body: Y[targ] += L_row . x_kind (kind 0 q, 1 qdot, 2 qddot), rows sorted by kind."""

    L_a: np.ndarray
    kind_a: np.ndarray
    targ_a: np.ndarray
    L_b: np.ndarray
    kind_b: np.ndarray
    targ_b: np.ndarray


class State(NamedTuple):
    """State carried from one chunk to the next (mutated)."""

    q: np.ndarray       # (n,) modal displacement
    v: np.ndarray       # (n,) modal velocity
    f: np.ndarray       # (nc,) contact force on A at the end of the last step
    active: np.ndarray  # (nc,) bool, coupled rows
    Pc: np.ndarray      # (n,) modal contact force at the step start (penalty rows)
    Pext: np.ndarray    # (n,) applied modal load at the step start
    ptr: np.ndarray     # (1,) int64, position in tk
    anchor: np.ndarray  # (nc,) stick anchor of friction rows / latched laterals (contact_laws.py)
    latched: np.ndarray  # (ncon,) bool, captured by a latch
    slip: np.ndarray    # (nc,) bool, friction row slipping
    sdir: np.ndarray    # (nc,) slip direction (unit per contact point)
    pin: np.ndarray     # (nc,) bool, soft release: the pin carries the normal row (elastic or yielding)
    yld: np.ndarray     # (nc,) bool, soft release: the pin yields (known force F(s))
    panchor: np.ndarray  # (nc,) soft release: the pin's anchor (drawn travel) in row units (u' = u - panchor)
    fsoft: np.ndarray   # (nc,) N, soft release: F(s) at the step start
    drawn: np.ndarray   # (ncon,) bool, soft release: pins drawn out
    sep: np.ndarray     # (ncon,) m, separation of the normal row at the last step end
    tyield: np.ndarray  # (ncon,) s, first yield (NaN: never)
    tdrawn: np.ndarray  # (ncon,) s, drawn out (NaN: never)
    opened: np.ndarray  # (ncon,) bool, released and open at a step end since: a latch may capture it


class Cache(NamedTuple):
    """Inverses of the step matrix per active-set pattern (mutated)."""

    keys: np.ndarray    # (cap, 2 n2) bool: rows and columns of each pattern
    invs: np.ndarray    # (cap, n2, n2)
    used: np.ndarray    # (2,) int64: patterns stored, slot used last


class History(NamedTuple):
    """Time histories, row r = step r (mutated)."""

    Y_a: np.ndarray     # (n_t, n_out_a)
    Y_b: np.ndarray     # (n_t, n_out_b)
    Fc: np.ndarray      # (n_t, nc) contact force on A
    state: np.ndarray   # (n_t, ncon) int8 BOLTED / CLOSED / OPEN
    iters: np.ndarray   # (n_t,) int32
    keep: bool          # keep the modal histories below
    Qa: np.ndarray      # (n_t or 0, na) modal displacement, velocity, acceleration of body a
    Va: np.ndarray
    Aa: np.ndarray
    Qb: np.ndarray      # (n_t or 0, nb) the same for body b
    Vb: np.ndarray
    Ab: np.ndarray
    X_a: np.ndarray     # (3, OUT_BLOCK, na) q, v, acc of body a at the steps whose outputs are not yet recovered
    X_b: np.ndarray     # (3, OUT_BLOCK, nb) the same for body b
    kept: np.ndarray    # (1,) int64: how many steps X_a, X_b hold (the last ones marched)


@njit(cache=True)
def _feedback(q, v, U, Vq, Vv, since, until, ta, s, out):
    """out = sum_k U[:, k] (V[k] . [q; v]) over the rank-one terms on at ta
    (since[k] <= ta < until[k]) (eq. 26); Vq, Vv the q and v halves of V, s (r,) work.
    Three BLAS matrix-vector products: V's halves read once each, not one loop per term."""
    r = since.size
    if r == 0:
        out[:] = 0.0
        return
    np.dot(Vq, q, s)
    s += np.dot(Vv, v)
    for k in range(r):
        if not (since[k] <= ta < until[k]):
            s[k] = 0.0
    np.dot(U, s, out)


@njit(cache=True)
def _pattern_inverse(rows, cols, Cdiag, W, keys, invs, nkeys, last):
    """Cached inverse of (diag(C) + W)[rows, cols] embedded at [cols, rows] of an (n, n) matrix,
    so that x[cols] = -inv @ u[rows]. Returns (slot, nkeys, ok)."""
    n = rows.size
    cap = keys.shape[0]
    for trial in range(nkeys + 1):  # most recently used first, then the others
        if trial == 0:
            k = last
        else:
            k = trial - 1
            if k == last:
                continue
        if k < 0 or k >= nkeys:
            continue
        same = True
        for j in range(n):
            if keys[k, j] != rows[j] or keys[k, n + j] != cols[j]:
                same = False
                break
        if same:
            return k, nkeys, True
    ir = np.empty(n, dtype=np.int64)
    ic = np.empty(n, dtype=np.int64)
    nr = 0
    ncol = 0
    for j in range(n):
        if rows[j]:
            ir[nr] = j
            nr += 1
        if cols[j]:
            ic[ncol] = j
            ncol += 1
    slot = nkeys if nkeys < cap else (last + 1) % cap
    if nkeys < cap:
        nkeys += 1
    for j in range(n):
        keys[slot, j] = rows[j]
        keys[slot, n + j] = cols[j]
        for l in range(n):
            invs[slot, j, l] = 0.0
    if nr != ncol:
        return slot, nkeys, False
    if nr > 0:
        A = np.empty((nr, nr))
        for a in range(nr):
            for b in range(nr):
                A[a, b] = W[ir[a], ic[b]]
                if ir[a] == ic[b]:
                    A[a, b] += Cdiag[ir[a]]
        ok = True
        try:
            Ainv = np.linalg.inv(A)
        except Exception:  # noqa: BLE001 - numba: singular matrix
            ok = False
            Ainv = np.zeros((nr, nr))
        if not ok or not np.all(np.isfinite(Ainv)):
            for j in range(2 * n):
                keys[slot, j] = False
            return slot, nkeys, False
        for a in range(nr):
            for b in range(nr):
                invs[slot, ic[a], ir[b]] = Ainv[a, b]
    return slot, nkeys, True


@njit(cache=True)
def _pre_step(coef, const, tk, Pk, ptr, tb, has_fb, fb, q, v, Pext, Pc, P1, qf, vf):
    """One pass over all modes of both bodies: load at tb (table interpolation from position
    ptr of tk; returns the new position), feedback fb held over the step (eq. 26),
    P0 = load(ta) + feedback + contact(ta), P1 = load(tb) + feedback, and the free step
    (end-of-step contact force 0). Pext holds load(ta) on entry, load(tb) on exit."""
    n = q.size
    nk = tk.size
    k0 = 0
    w = 0.0
    if nk > 0:
        if tb <= tk[0]:
            ptr = 0
        elif tb >= tk[nk - 1]:
            k0 = nk - 1
            ptr = nk - 1
        else:
            while ptr + 1 < nk and tk[ptr + 1] <= tb:
                ptr += 1
            while ptr > 0 and tk[ptr] > tb:
                ptr -= 1
            k0 = ptr
            w = (tb - tk[ptr]) / (tk[ptr + 1] - tk[ptr])
    k1 = k0 + 1 if (nk > 0 and w > 0.0) else k0
    a = 1.0 - w
    if nk > 0 and not has_fb:  # the common case in one pass
        for m in range(n):
            p1 = const[m] + a * Pk[k0, m] + w * Pk[k1, m]
            p0 = Pext[m] + Pc[m]
            Pext[m] = p1
            P1[m] = p1
            qf[m] = coef[0, m] * q[m] + coef[1, m] * v[m] + coef[2, m] * p0 + coef[3, m] * p1
            vf[m] = coef[4, m] * q[m] + coef[5, m] * v[m] + coef[6, m] * p0 + coef[7, m] * p1
        return ptr
    for m in range(n):
        p1 = const[m]
        if nk > 0:
            p1 += a * Pk[k0, m] + w * Pk[k1, m]
        fbm = fb[m] if has_fb else 0.0
        p0 = Pext[m] + fbm + Pc[m]
        Pext[m] = p1
        p1 += fbm
        P1[m] = p1
        qf[m] = coef[0, m] * q[m] + coef[1, m] * v[m] + coef[2, m] * p0 + coef[3, m] * p1
        vf[m] = coef[4, m] * q[m] + coef[5, m] * v[m] + coef[6, m] * p0 + coef[7, m] * p1
    return ptr


@njit(cache=True)
def _post_step(coef, qf, vf, P1, Pf, Pg, anyf, anyg, zw2, w2, q, v, acc):
    """End-of-step state with the contact force (f1 end values Pf, rigid start values Pg)."""
    n = q.size
    if anyg:
        for m in range(n):
            q[m] = qf[m] + coef[3, m] * Pf[m] + coef[2, m] * Pg[m]
            v[m] = vf[m] + coef[7, m] * Pf[m] + coef[6, m] * Pg[m]
            acc[m] = P1[m] + Pf[m] - zw2[m] * v[m] - w2[m] * q[m]
    elif anyf:
        for m in range(n):
            q[m] = qf[m] + coef[3, m] * Pf[m]
            v[m] = vf[m] + coef[7, m] * Pf[m]
            acc[m] = P1[m] + Pf[m] - zw2[m] * v[m] - w2[m] * q[m]
    else:
        for m in range(n):
            q[m] = qf[m]
            v[m] = vf[m]
            acc[m] = P1[m] - zw2[m] * v[m] - w2[m] * q[m]


@njit(cache=True, nogil=True)   # releases the GIL: two runs march together on two threads (accuracy.py)
def march(i0, i1, steps, modal, contact, rows_out, state, cache, hist, laws=None):
    """March steps i0 -> i1 (time t0 + i h). Returns (status, step, info1, info2).

    ``steps`` :class:`Stepping`, ``modal`` :class:`Modal`, ``contact`` :class:`Contact`,
    ``rows_out`` :class:`OutputRows`; ``state`` :class:`State`, ``cache`` :class:`Cache`
    and ``hist`` :class:`History` are updated in place. The bundles are unpacked once here:
    the helpers take plain arrays (no reference counting per step).

    ``laws``: None for the reference's contacts, True with the contact laws beyond them
    (``contact.laws``). numba prunes the ``laws is not None`` branches before typing, so a
    run without the laws compiles the reference's path alone (24 s against 43-46 s for the
    whole the first time on this machine, 2026-11-27; a separate specialisation in numba's
    cache; ``make setup`` compiles both: transient/warm.py)."""
    t0, h, method, tol, max_iter = steps
    na, coef, w2, zw2, const, tk, Pk, U, V, since, until = modal
    Phi_c, Cdiag, coff, dcontact, axial, nsign, release, W, C2 = contact[:9]  # the rest: _solve_laws
    L_a, kind_a, targ_a, L_b, kind_b, targ_b = rows_out
    q, v, f, active, Pc, Pext, ptr = state[:7]
    keys, invs, used = cache
    Y_a, Y_b, Fc, states, iters, keep, Qa, Va, Aa, Qb, Vb, Ab, Xa, Xb, kept = hist
    n, nc = q.size, f.size
    P1 = np.empty(n); fb = np.zeros(n); qf = np.empty(n); vf = np.empty(n)
    Vq = np.ascontiguousarray(V[:, :n]); Vv = np.ascontiguousarray(V[:, n:]); sfb = np.empty(V.shape[0])
    acc = np.empty(n); Pf = np.zeros(n); Pg = np.zeros(n)
    n2 = W.shape[0]  # nc, or 2 nc when there are rigid rows (unknowns [f1; g])
    u = np.zeros(n2); fn = np.empty(nc); g = np.zeros(nc)
    rows2 = np.zeros(n2, dtype=np.bool_)
    cols2 = np.zeros(n2, dtype=np.bool_)
    opening = np.zeros(nc, dtype=np.bool_)
    rigid = Cdiag == 0.0
    any_rigid = n2 > nc
    cand = np.empty(nc, dtype=np.bool_)
    free = np.empty(nc, dtype=np.bool_)
    bolted = np.empty(release.size, dtype=np.bool_)
    # outputs: the states of OUT_BLOCK steps kept (in hist, across chunks: the blocks start at
    # the same steps whatever the chunks, so the results do not depend on them), then
    # recovered together (_outputs_block); the last block when the run's last step is marched
    need_a = _kinds(kind_a); need_b = _kinds(kind_b)
    nbuf = kept[0]
    last = Y_a.shape[0] - 1
    for i in range(i0, i1):
        ta = t0 + i * h
        tb = t0 + (i + 1) * h
        # ---------------- free step of both bodies (contact force at t1 = 0)
        if V.shape[0] > 0:
            _feedback(q, v, U, Vq, Vv, since, until, ta, sfb, fb)
        ptr[0] = _pre_step(coef, const, tk, Pk, ptr[0], tb, V.shape[0] > 0, fb, q, v, Pext, Pc, P1, qf, vf)
        # ---------------- candidate rows and free relative displacement
        e = np.dot(Phi_c, qf)  # one BLAS product
        if laws is not None:  # friction, dashpots, latches (transient/contact_laws.py)
            ed = np.dot(Phi_c, vf)
            _laws_candidates(tb, e, ed, contact, state, rigid, bolted, cand, free, u)
            st, it, info1, info2 = _solve_laws(contact, state, cache, rigid, u, ed, free, opening, max_iter,
                                                      fn, g, rows2, cols2)
        else:
            ed = np.dot(Phi_c, vf) if any_rigid else e
            _candidates(tb, release, dcontact, axial, coff, rigid, any_rigid, e, ed, bolted, cand, free, active, u)
            # ---------------- contact solve
            if method == 0:
                st, it, info1, info2 = _solve_direct(W, C2, nsign, keys, invs, used, u, free, rigid, active,
                                                     opening, max_iter, fn, g, rows2, cols2)
            else:
                st, it, info1, info2 = _solve_fixed_point(W, Cdiag, nsign, u, free, active, f, tol, max_iter, fn)
        if st != OK:
            _flush(L_a, kind_a, targ_a, Xa, L_b, kind_b, targ_b, Xb, nbuf, Y_a, Y_b, i + 1 - nbuf)
            kept[0] = 0
            return st, i + 1, info1, info2
        # ---------------- end-of-step state with the contact force
        anyf, anyg = _contact_load(Phi_c, rigid, any_rigid, fn, g, f, Pf, Pg, Pc)
        _post_step(coef, qf, vf, P1, Pf, Pg, anyf, anyg, zw2, w2, q, v, acc)
        if laws is not None:
            _laws_after_step(contact, state, fn, bolted, opening, tb)
        # ---------------- outputs at t1
        r = i + 1
        _record_contact(r, it, fn, bolted, active, opening, dcontact, axial, Fc, states, iters)
        _keep_state(Xa, nbuf, need_a, q, v, acc, 0)
        _keep_state(Xb, nbuf, need_b, q, v, acc, na)
        nbuf += 1
        if nbuf == OUT_BLOCK:
            _flush(L_a, kind_a, targ_a, Xa, L_b, kind_b, targ_b, Xb, nbuf, Y_a, Y_b, r + 1 - nbuf)
            nbuf = 0
        if keep:
            _record_modal(r, na, q, v, acc, Qa, Va, Aa, Qb, Vb, Ab)
    if i1 >= last:
        _flush(L_a, kind_a, targ_a, Xa, L_b, kind_b, targ_b, Xb, nbuf, Y_a, Y_b, i1 + 1 - nbuf)
        nbuf = 0
    kept[0] = nbuf
    return OK, i1, 0.0, 0.0


@njit(cache=True)
def _candidates(tb, release, dcontact, axial, coff, rigid, any_rigid, e, ed, bolted, cand, free, active, u):
    """The reference's rows of a step ending at tb: bolted contacts (every row, coupled) and
    the axial rows of released ones (``free``: may open or close in this step); released
    lateral rows uncoupled; u = c + e_free on the candidate rows (and e'_free on rigid ones)."""
    nc = e.size
    for c in range(release.size):
        bolted[c] = tb < release[c]
    for j in range(nc):
        cand[j] = bolted[dcontact[j]] or axial[j]
        free[j] = cand[j] and not bolted[dcontact[j]]  # may open or close in this step
        if not bolted[dcontact[j]] and not axial[j]:
            active[j] = False
        elif bolted[dcontact[j]]:
            active[j] = True
        u[j] = coff[j] + e[j] if cand[j] else 0.0
        if any_rigid:
            u[nc + j] = ed[j] if (cand[j] and rigid[j]) else 0.0


@njit(cache=True)
def _solve_direct(W, C2, nsign, keys, invs, used, u, free, rigid, active, opening, max_iter, fn, g, rows2, cols2):
    """Active-set solve (C + W_SS) x_S = -u_S with the inverses cached per pattern (``keys``,
    ``invs``, ``used``: see :class:`Cache`); returns (status, iterations, info1, info2) with
    info1 the iterations when cycling. ``free``: rows
    whose state may change (released, candidate); fn: end-of-step force f1, g: start value
    of rigid rows (module docstring); rows2, cols2: work arrays (n2,), equations and unknowns.
    Cycling switches to one change per iteration (least-index rule), then fails."""
    nc = fn.size
    any_rigid = W.shape[0] > nc
    it = 0
    single = False
    while True:
        it += 1
        # equations (rows2) and unknowns (cols2): penalty row j: eq j, unknown f1_j;
        # rigid closed: eqs j (gap) and nc+j (velocity), unknowns f1_j and g_j;
        # rigid opening: eq j (gap closes at the step end), unknown g_j (f1_j = 0)
        for j in range(nc):
            rows2[j] = active[j]
            cols2[j] = active[j] and not opening[j]
            if any_rigid:
                rows2[nc + j] = active[j] and rigid[j] and not opening[j]
                cols2[nc + j] = active[j] and rigid[j]
        slot, used[0], ok = _pattern_inverse(rows2, cols2, C2, W, keys, invs, used[0], used[1])
        if not ok:
            return SINGULAR, it, 0.0, 0.0
        used[1] = slot
        # the cached inverse is zero outside [cols, rows]: one BLAS product does the masking
        x2 = np.dot(invs[slot], u)
        for j in range(nc):
            fn[j] = -x2[j]
            g[j] = -x2[nc + j] if any_rigid else 0.0
        changed = False
        for j in range(nc):
            if not free[j]:
                continue
            flip = False
            if active[j] and rigid[j]:
                if not opening[j] and nsign[j] * fn[j] < 0.0:  # closed -> opening
                    opening[j] = True
                    changed = True
                    if single:
                        break
                elif opening[j] and nsign[j] * g[j] < 0.0:  # opening -> open
                    opening[j] = False
                    active[j] = False
                    changed = True
                    if single:
                        break
                continue
            if active[j]:
                flip = nsign[j] * fn[j] < 0.0
            else:
                s = u[j]
                for l in range(nc):
                    s += W[j, l] * fn[l]
                    if any_rigid:
                        s += W[j, nc + l] * g[l]
                flip = nsign[j] * s < 0.0
            if flip:
                active[j] = not active[j]
                changed = True
                if single:
                    break
        if not changed:
            return OK, it, 0.0, 0.0
        if it > nc + 2:
            single = True
        if it > max_iter + 4 * nc:
            return CYCLING, it, float(it), 0.0


@njit(cache=True)
def _solve_fixed_point(W, Cdiag, nsign, u, free, active, f, tol, max_iter, fn):
    """The reference's iteration f <- -K_C (c + e_free + W f), |f_j - f_i| < tol (eq. 11);
    returns (status, iterations, last |dF|, iterations)."""
    nc = fn.size
    Wf = np.empty(nc)
    Kc = np.empty(nc)
    for j in range(nc):
        Kc[j] = 1.0 / Cdiag[j] if Cdiag[j] > 0 else 0.0
    for j in range(nc):
        fn[j] = f[j] if active[j] else 0.0
    it = 0
    while True:
        it += 1
        for j in range(nc):
            s = u[j]
            for l in range(nc):
                s += W[j, l] * fn[l]
            Wf[j] = s  # constraint residual with the current estimate
        changed = False
        dmax = 0.0
        for j in range(nc):
            if free[j]:
                if active[j] and nsign[j] * fn[j] < 0.0:
                    active[j] = False
                    changed = True
                elif not active[j] and nsign[j] * Wf[j] < 0.0:
                    active[j] = True
                    changed = True
            new = -Kc[j] * Wf[j] if active[j] else 0.0
            d = abs(new - fn[j])
            if d > dmax:
                dmax = d
            fn[j] = new
        if not changed and dmax < tol:
            return OK, it, dmax, float(it)
        if it >= max_iter or not np.isfinite(dmax):
            return NO_CONVERGENCE, it, dmax, float(it)


@njit(cache=True)
def _contact_load(Phi_c, rigid, any_rigid, fn, g, f, Pf, Pg, Pc):
    """f = fn; modal contact loads Pf = Phi^T fn (end values), Pg = Phi^T g (rigid start values)
    and Pc, the load the next step starts from (penalty rows only). Returns (any fn, any g)."""
    nc = fn.size
    anyf = False
    anyg = False
    for j in range(nc):
        f[j] = fn[j]
        anyf = anyf or fn[j] != 0.0
        anyg = anyg or g[j] != 0.0
    if anyf:
        Pf[:] = np.dot(fn, Phi_c)
    else:
        Pf[:] = 0.0
    if anyg:
        Pg[:] = np.dot(g, Phi_c)
    if any_rigid:
        fpen = np.empty(nc)
        for j in range(nc):
            fpen[j] = 0.0 if rigid[j] else fn[j]
        Pc[:] = np.dot(fpen, Phi_c)
    else:
        Pc[:] = Pf
    return anyf, anyg


@njit(cache=True)
def _record_contact(r, it, fn, bolted, active, opening, dcontact, axial, Fc, states, iters):
    """Row r of the contact histories: force, state per contact point, iterations; then rigid
    rows that opened during the step start the next one open."""
    nc = fn.size
    for j in range(nc):
        Fc[r, j] = fn[j]
    for c in range(bolted.size):
        states[r, c] = BOLTED if bolted[c] else OPEN
    for j in range(nc):
        if axial[j] and not bolted[dcontact[j]] and active[j] and not opening[j]:
            states[r, dcontact[j]] = CLOSED
    iters[r] = it
    for j in range(nc):
        if opening[j]:
            active[j] = False
            opening[j] = False


@njit(cache=True)
def _record_modal(r, na, q, v, acc, Qa, Va, Aa, Qb, Vb, Ab):
    """Row r of the modal histories of both bodies (velocity and acceleration only where
    their arrays have rows: keep_modal = "q" keeps the displacements alone)."""
    full = Va.shape[0] > r
    for m in range(na):
        Qa[r, m] = q[m]
        if full:
            Va[r, m] = v[m]; Aa[r, m] = acc[m]
    for m in range(q.size - na):
        Qb[r, m] = q[na + m]
        if full:
            Vb[r, m] = v[na + m]; Ab[r, m] = acc[na + m]


@njit(cache=True)
def _kinds(kind):
    """(3,) bool: which of q, qdot, qddot the output rows read."""
    need = np.zeros(3, dtype=np.bool_)
    for row in range(kind.size):
        need[kind[row]] = True
    return need


@njit(cache=True)
def _keep_state(X, t, need, q, v, acc, m0):
    """Row t of the kept states X (3, OUT_BLOCK, nm): modes m0 .. m0 + nm of q, v, acc (the
    kinds the outputs read)."""
    nm = X.shape[2]
    if need[0]:
        for m in range(nm):
            X[0, t, m] = q[m0 + m]
    if need[1]:
        for m in range(nm):
            X[1, t, m] = v[m0 + m]
    if need[2]:
        for m in range(nm):
            X[2, t, m] = acc[m0 + m]


@njit(cache=True)
def _flush(L_a, kind_a, targ_a, Xa, L_b, kind_b, targ_b, Xb, nt, Y_a, Y_b, r0):
    """The outputs of both bodies at the nt kept steps, rows r0 .. r0 + nt of Y_a, Y_b."""
    if nt == 0:
        return
    _outputs_block(L_a, kind_a, targ_a, Xa, nt, Y_a, r0)
    if Xb.shape[2] > 0:
        _outputs_block(L_b, kind_b, targ_b, Xb, nt, Y_b, r0)


@njit(cache=True)
def _outputs_block(L, kind, targ, X, nt, Y, r0):
    """Y[r0 + t, targ] = sum over rows of L_row . x_kind(t) for the nt kept steps t (X: their
    q, v, acc); rows sorted by kind, one matrix-matrix product per kind (BLAS-3: L is read
    once for OUT_BLOCK steps, not once a step)."""
    if Y.shape[1] == 0:
        return
    for t in range(nt):
        for k in range(Y.shape[1]):
            Y[r0 + t, k] = 0.0
    nrow = L.shape[0]
    s0 = 0
    while s0 < nrow:
        kd = kind[s0]
        s1 = s0
        while s1 < nrow and kind[s1] == kd:
            s1 += 1
        y = np.empty((nt, s1 - s0))
        if nt == X.shape[1]:
            np.dot(X[kd], L[s0:s1].T, y)
        else:                                   # a partly filled block (a chunk's end)
            np.dot(np.ascontiguousarray(X[kd, :nt]), L[s0:s1].T, y)
        for t in range(nt):
            for row in range(s0, s1):
                Y[r0 + t, targ[row]] += y[t, row - s0]
        s0 = s1


# ------------------------------------------------------------------ contact laws beyond the reference's
# Friction, dashpots and latches (the method: transient/contact_laws.py). Compiled here, beside
# march, because numba's on-disk cache of march is keyed on this file only: a callee in another
# file could change without march being recompiled.
FRICTION_HYSTERESIS = 1e-9   # relative band on |f_T| / (mu N) between stick and slip
SOFT_HYSTERESIS = 1e-9       # relative band on the pin tension / F(s) between elastic and yielding
SLIP_TURN_TOL = 1e-8         # slip direction converged when no component moves by more than this


@njit(cache=True)
def _laws_candidates(tb, e, ed, contact, state, rigid, bolted, cand, free, u):
    """Rows that take part in the step's solve and their right-hand side u = c0 + e - a + tau e'
    (and the rigid velocity rows); ``bolted`` includes latched points. ``contact``, ``state``:
    the kernel's bundles (kernel.Contact, kernel.State), unpacked once here."""
    coff, dcontact, axial, release, tau, mu = contact.offset, contact.contact, contact.axial, contact.release, \
        contact.tau, contact.mu
    active, anchor, latched = state.active, state.anchor, state.latched
    nc = e.size
    any_rigid = u.size > nc
    for c in range(release.size):
        bolted[c] = tb < release[c] or latched[c]
    for j in range(nc):
        c = dcontact[j]
        if bolted[c]:
            cand[j] = True
            free[j] = False
            active[j] = True
        elif axial[j] or mu[j] > 0.0:
            cand[j] = True     # normal rows may open or close; friction rows follow their normal
            free[j] = True
        else:
            cand[j] = False
            free[j] = False
            active[j] = False
        u[j] = coff[j] + e[j] - anchor[j] + tau[j] * ed[j] if cand[j] else 0.0
        if any_rigid:
            u[nc + j] = ed[j] if (cand[j] and rigid[j]) else 0.0
    rtravel, rforce, rptr, axcol = contact.rtravel, contact.rforce, contact.rptr, contact.axcol
    if rtravel.size > 0:  # soft release: F(s) with the separation at the step start (explicit)
        for c in range(release.size):
            k0, k1 = rptr[c], rptr[c + 1]
            if k1 > k0:
                a = axcol[c]
                state.fsoft[a] = 0.0 if (bolted[c] or state.drawn[c]) else \
                    _table_force(rtravel, rforce, k0, k1, state.sep[c])


@njit(cache=True)
def _table_force(rtravel, rforce, k0, k1, s):
    """F(s) of the table [k0, k1): linear between its points, held at the end values outside."""
    if s <= rtravel[k0]:
        return rforce[k0]
    for k in range(k0, k1 - 1):
        if s < rtravel[k + 1]:
            w = (s - rtravel[k]) / (rtravel[k + 1] - rtravel[k])
            return rforce[k] + w * (rforce[k + 1] - rforce[k])
    return rforce[k1 - 1]


@njit(cache=True)
def _row_residual(W, u, fn, g, j, any_rigid):
    """u_j + (W [f; g])_j: what the row's equation leaves over (its would-be compliance term)."""
    nc = fn.size
    s = u[j]
    for l in range(nc):
        s += W[j, l] * fn[l]
        if any_rigid:
            s += W[j, nc + l] * g[l]
    return s


@njit(cache=True)
def _position(W, Wv, u, ed, tau, fn, g, j, any_rigid):
    """Relative position along row j at the step end (c0 + e - a), i.e. the residual less its dashpot part."""
    nc = fn.size
    s = _row_residual(W, u, fn, g, j, any_rigid)
    if tau[j] > 0.0:
        v = ed[j]
        for l in range(nc):
            v += Wv[j, l] * fn[l]
            if any_rigid:
                v += Wv[j, nc + l] * g[l]
        s -= tau[j] * v
    return s


@njit(cache=True)
def _slip_update(W, Ainv, x2, nsign, active, slip, sdir, mu, axrow):
    """Add the slip forces mu N d (linear in the unknown normal forces) to x2 = Ainv u by a
    rank-k update: x2 += Z y, (I + Z[a, :]) y = -x2[a] over the k slipping points (normal rows a)."""
    nc = mu.size
    n2 = x2.size
    ks = np.empty(nc, dtype=np.int64)
    nk = 0
    for a in range(nc):
        for j in range(nc):
            if axrow[j] == a and mu[j] > 0.0 and slip[j] and active[j]:
                ks[nk] = a
                nk += 1
                break
    if nk == 0:
        return OK
    Z = np.empty((n2, nk))
    w = np.empty(n2)
    for k in range(nk):
        a = ks[k]
        w[:] = 0.0
        for j in range(nc):
            if axrow[j] == a and mu[j] > 0.0 and slip[j] and active[j]:
                alpha = mu[j] * nsign[a] * sdir[j]
                for r in range(n2):
                    w[r] += W[r, j] * alpha
        Z[:, k] = np.dot(Ainv, w)
    G = np.eye(nk)
    rhs = np.empty(nk)
    for k in range(nk):
        rhs[k] = -x2[ks[k]]
        for l in range(nk):
            G[k, l] += Z[ks[k], l]
    ok = True
    try:
        y = np.linalg.solve(G, rhs)
    except Exception:  # noqa: BLE001 - numba: singular matrix
        ok = False
        y = np.zeros(nk)
    if not ok or not np.all(np.isfinite(y)):
        return FRICTION_SINGULAR
    x2 += np.dot(Z, y)
    return OK


@njit(cache=True)
def _follow_normals(free, active, opening, mu, axrow):
    """Friction rows of released points are coupled while their normal row is closed (their
    stick/slip state is kept while the normal changes within a step: a point that closes
    while sliding keeps sliding, and is reset to stick only once it has been open at a step
    end, _laws_after_step)."""
    for j in range(mu.size):
        if mu[j] > 0.0 and free[j]:
            a = axrow[j]
            active[j] = active[a] and not opening[a]


@njit(cache=True)
def _normal_flips(W, Wv, tau, nsign, u, ed, free, rigid, active, opening, mu, pin, fn, g, single):
    """The active-set rules of kernel._solve_direct for normal and rigid rows, with the dashpot's
    position conditions; returns whether a row changed (one only when ``single``). Rows carried
    by a soft-release pin follow _soft_checks instead."""
    nc = fn.size
    any_rigid = W.shape[0] > nc
    changed = False
    for j in range(nc):
        if not free[j] or mu[j] > 0.0 or pin[j]:
            continue
        if active[j] and rigid[j]:
            if not opening[j] and nsign[j] * fn[j] < 0.0:  # closed -> opening
                opening[j] = True
                changed = True
            elif opening[j] and nsign[j] * g[j] < 0.0:  # opening -> open
                opening[j] = False
                active[j] = False
                changed = True
            if changed and single:
                return True
            continue
        if active[j]:
            flip = nsign[j] * fn[j] < 0.0
            if not flip and tau[j] > 0.0:
                flip = nsign[j] * _position(W, Wv, u, ed, tau, fn, g, j, any_rigid) > 0.0
        else:
            flip = nsign[j] * _row_residual(W, u, fn, g, j, any_rigid) < 0.0
            if flip and tau[j] > 0.0:
                flip = nsign[j] * _position(W, Wv, u, ed, tau, fn, g, j, any_rigid) < 0.0
        if flip:
            active[j] = not active[j]
            changed = True
            if single:
                return True
    return changed


@njit(cache=True)
def _friction_checks(W, C2, nsign, u, free, axial, active, mu, axrow, slip, sdir, fn, g, single):
    """Stick -> slip when |f_T| > mu N, slip -> stick when the elastic trial |g_T| < mu N, and
    the slip direction d = g_T / |g_T|. Returns (changed state, turned direction)."""
    nc = fn.size
    any_rigid = W.shape[0] > nc
    changed = False
    turned = False
    gT = np.empty(nc)
    for a in range(nc):
        if not (axial[a] and active[a] and free[a]):
            continue
        n_t = 0
        slipping = False
        lim = 0.0
        for j in range(nc):
            if axrow[j] == a and mu[j] > 0.0:
                n_t += 1
                slipping = slipping or slip[j]
                lim = mu[j]
        if n_t == 0:
            continue
        N = nsign[a] * fn[a]
        if N < 0.0 and slipping:
            continue           # the normal row opens (kernel rules)
        lim *= max(N, 0.0)
        if not slipping:
            s = 0.0
            for j in range(nc):
                if axrow[j] == a and mu[j] > 0.0:
                    s += fn[j] * fn[j]
            s = np.sqrt(s)
            if s > lim * (1.0 + FRICTION_HYSTERESIS) and s > 0.0:
                for j in range(nc):
                    if axrow[j] == a and mu[j] > 0.0:
                        slip[j] = True
                        sdir[j] = fn[j] / s
                changed = True
        else:
            s = 0.0
            for j in range(nc):
                if axrow[j] == a and mu[j] > 0.0:
                    gT[j] = -_row_residual(W, u, fn, g, j, any_rigid) / C2[j]
                    s += gT[j] * gT[j]
            s = np.sqrt(s)
            if s <= lim * (1.0 - FRICTION_HYSTERESIS):
                for j in range(nc):
                    if axrow[j] == a and mu[j] > 0.0:
                        slip[j] = False
                changed = True
            else:
                for j in range(nc):
                    if axrow[j] == a and mu[j] > 0.0:
                        d = gT[j] / s
                        if abs(d - sdir[j]) > SLIP_TURN_TOL:
                            turned = True
                        sdir[j] = d
        if changed and single:
            return True, turned
    return changed, turned


@njit(cache=True)
def _soft_checks(W, C2, nsign, u, free, active, pin, yld, panchor, fsoft, drawn, axcol, rptr, fn, g, single):
    """Soft-release states of the normal rows of points not drawn out (transient/contact_laws.py):
    elastic pin -> yielding when its tension exceeds F(s), -> slack when it is compressed after
    having been drawn (panchor on the open side); yielding -> elastic when the elastic trial
    (end position less the anchor, with the solved forces) gives a tension below F(s); slack
    and open -> elastic pin when the position passes the anchor. Returns whether a row changed."""
    nc = fn.size
    any_rigid = W.shape[0] > nc
    changed = False
    for c in range(drawn.size):
        if rptr[c + 1] == rptr[c] or drawn[c]:
            continue
        j = axcol[c]
        if not free[j]:
            continue
        if pin[j] and not yld[j]:
            tension = -nsign[j] * fn[j]
            if tension > fsoft[j] * (1.0 + SOFT_HYSTERESIS):
                yld[j] = True
                changed = True
            elif tension < 0.0 and nsign[j] * panchor[j] > 0.0:
                pin[j] = False
                active[j] = False
                changed = True
        elif pin[j]:
            trial = nsign[j] * (_row_residual(W, u, fn, g, j, any_rigid) - panchor[j]) / C2[j]
            if trial < fsoft[j] * (1.0 - SOFT_HYSTERESIS):
                yld[j] = False
                changed = True
        elif not active[j]:
            if nsign[j] * (_row_residual(W, u, fn, g, j, any_rigid) - panchor[j]) > 0.0:
                pin[j] = True
                active[j] = True
                changed = True
        if changed and single:
            return True
    return changed


@njit(cache=True)
def _solve_laws(contact, state, cache, rigid, u, ed, free, opening, max_iter, fn, g, rows2, cols2):
    """Active-set solve with friction, dashpots and rigid rows (kernel._solve_direct's rules plus
    the stick/slip states); returns (status, iterations, info1, info2). ``contact``, ``state``,
    ``cache``: the kernel's bundles; the other arguments as in kernel._solve_direct."""
    W, C2, Wv, tau, nsign, axial, mu, axrow = contact.W, contact.C2, contact.Wv, contact.tau, contact.sign, \
        contact.axial, contact.mu, contact.axrow
    active, slip, sdir = state.active, state.slip, state.sdir
    pin, yld, panchor, fsoft = state.pin, state.yld, state.panchor, state.fsoft
    soft = contact.rtravel.size > 0
    keys, invs, used = cache
    nc = fn.size
    n2 = W.shape[0]
    any_rigid = n2 > nc
    u2 = np.empty(n2) if soft else u
    it = 0
    turns = 0
    single = False
    while True:
        it += 1
        _follow_normals(free, active, opening, mu, axrow)
        if soft:  # the pins' anchors and the yielding rows' known forces, u' = u + W[:, P] f_P
            for r in range(n2):
                u2[r] = u[r]
            for j in range(nc):
                if pin[j] and free[j]:
                    if yld[j]:
                        fy = -nsign[j] * fsoft[j]
                        for r in range(n2):
                            u2[r] += W[r, j] * fy
                    else:
                        u2[j] -= panchor[j]
        for j in range(nc):
            eq = active[j] and not slip[j]
            if soft and yld[j] and free[j]:
                eq = False
            rows2[j] = eq
            cols2[j] = eq and not opening[j]
            if any_rigid:
                rows2[nc + j] = eq and rigid[j] and not opening[j]
                cols2[nc + j] = eq and rigid[j]
        slot, used[0], ok = _pattern_inverse(rows2, cols2, C2, W, keys, invs, used[0], used[1])
        if not ok:
            return SINGULAR, it, 0.0, 0.0
        used[1] = slot
        x2 = np.dot(invs[slot], u2)
        if _slip_update(W, invs[slot], x2, nsign, active, slip, sdir, mu, axrow) != OK:
            return FRICTION_SINGULAR, it, 0.0, 0.0
        for j in range(nc):
            fn[j] = -x2[j]
            g[j] = -x2[nc + j] if any_rigid else 0.0
        for j in range(nc):  # slip rows: mu N d with the solved normal force
            if slip[j] and active[j]:
                fn[j] = mu[j] * nsign[axrow[j]] * fn[axrow[j]] * sdir[j]
        if soft:
            for j in range(nc):  # yielding pins: the known tension F(s)
                if yld[j] and free[j]:
                    fn[j] = -nsign[j] * fsoft[j]
        # friction first, on the pattern that was solved (a point closing in stick with a large
        # trial tangent force must slip before its normal is judged), then the normal rows
        changed, turned = _friction_checks(W, C2, nsign, u, free, axial, active, mu, axrow, slip, sdir, fn, g,
                                           single)
        if not (changed and single):
            changed = _normal_flips(W, Wv, tau, nsign, u, ed, free, rigid, active, opening, mu, pin, fn, g,
                                    single) or changed
        if soft and not (changed and single):
            changed = _soft_checks(W, C2, nsign, u, free, active, pin, yld, panchor, fsoft, state.drawn,
                                   contact.axcol, contact.rptr, fn, g, single) or changed
        if not changed and not turned:
            return OK, it, 0.0, 0.0
        if turned and not changed:
            turns += 1
            if turns > max_iter:
                return CYCLING, it, float(it), 0.0
        elif it > nc + 2:
            single = True
        if it > max_iter + 4 * nc + turns:
            return CYCLING, it, float(it), 0.0


@njit(cache=True)
def _laws_after_step(contact, state, fn, bolted, opening, tb):
    """Anchors and latches at the step end (time tb): a slipping tangent row's anchor moves so
    that the stick relation holds with the slip force; an open point's tangent anchors follow
    the relative position (a new contact starts unstressed); a point closed with compression
    >= latch force is latched (bolted from the next step), its frictionless laterals
    anchored at the current relative position. Soft release: a yielding pin's anchor moves
    so that K_C times its stretch is the yield force; a point whose separation reached the
    table's end is drawn out (an ordinary released point from the next step on)."""
    Phi_c, Cdiag, tau, mu, axial, nsign = contact.Phi, contact.compliance, contact.tau, contact.mu, contact.axial, \
        contact.sign
    dcontact, axcol, latch = contact.contact, contact.axcol, contact.latch
    active, latched, anchor, slip = state.active, state.latched, state.anchor, state.slip
    e = np.dot(Phi_c, state.q)
    ev = np.dot(Phi_c, state.v) if contact.Wv.shape[0] > 0 else e
    nc = fn.size
    for j in range(nc):
        if mu[j] > 0.0 and not bolted[dcontact[j]]:
            if active[j]:
                if slip[j]:
                    anchor[j] = e[j] + tau[j] * ev[j] + Cdiag[j] * fn[j]
            else:
                anchor[j] = e[j]
                slip[j] = False
    rtravel, rptr = contact.rtravel, contact.rptr
    if rtravel.size > 0:
        coff = contact.offset
        pin, yld, panchor, drawn = state.pin, state.yld, state.panchor, state.drawn
        for c in range(latch.size):
            if rptr[c + 1] == rptr[c]:
                continue
            a = axcol[c]
            s = nsign[a] * (coff[a] + e[a])
            state.sep[c] = s
            if bolted[c] or drawn[c]:
                continue
            if yld[a]:
                panchor[a] = coff[a] + e[a] + Cdiag[a] * fn[a]
                if np.isnan(state.tyield[c]):
                    state.tyield[c] = tb
            if s >= rtravel[rptr[c + 1] - 1]:
                drawn[c] = True
                state.tdrawn[c] = tb
                pin[a] = False
                yld[a] = False
                active[a] = s < 0.0
    opened = state.opened
    for c in range(latch.size):
        if latched[c] or bolted[c] or not latch[c] < np.inf:
            continue
        a = axcol[c]
        if not active[a]:
            opened[c] = True    # capture is an event: the point closes again after it has been open
            continue
        if opened[c] and not opening[a] and nsign[a] * fn[a] >= latch[c]:
            latched[c] = True
            for j in range(nc):
                if dcontact[j] == c and not axial[j]:
                    if mu[j] == 0.0:
                        anchor[j] = e[j]
                    elif slip[j]:
                        anchor[j] = e[j] + tau[j] * ev[j] + Cdiag[j] * fn[j]
                    slip[j] = False
