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

No Python objects, no I/O: named bundles of arrays in (:class:`Modal`, :class:`Contact`, ...),
arrays out; status codes report failures.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

OK, NO_CONVERGENCE, CYCLING, SINGULAR = 0, 1, 2, 3
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
    U: np.ndarray       # (n, r) feedback factors: force = sum_k U[:, k] (V[k] . q) (eq. 26)
    V: np.ndarray       # (r, n)
    until: np.ndarray   # (r,) s, each term on while t < until


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


@njit(cache=True)
def _feedback(q, U, V, until, ta, out):
    """out = sum_k U[:, k] (V[k] . q) over the rank-one terms still on (ta < until[k]) (eq. 26)."""
    for m in range(q.size):
        out[m] = 0.0
    for k in range(V.shape[0]):
        if not ta < until[k]:
            continue
        s = 0.0
        for m in range(q.size):
            s += V[k, m] * q[m]
        for m in range(q.size):
            out[m] += U[m, k] * s


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


@njit(cache=True)
def march(i0, i1, steps, modal, contact, rows_out, state, cache, hist):
    """March steps i0 -> i1 (time t0 + i h). Returns (status, step, info1, info2).

    ``steps`` :class:`Stepping`, ``modal`` :class:`Modal`, ``contact`` :class:`Contact`,
    ``rows_out`` :class:`OutputRows`; ``state`` :class:`State`, ``cache`` :class:`Cache`
    and ``hist`` :class:`History` are updated in place. The bundles are unpacked once here:
    the helpers take plain arrays (no reference counting per step)."""
    t0, h, method, tol, max_iter = steps
    na, coef, w2, zw2, const, tk, Pk, U, V, until = modal
    Phi_c, Cdiag, coff, dcontact, axial, nsign, release, W, C2 = contact
    L_a, kind_a, targ_a, L_b, kind_b, targ_b = rows_out
    q, v, f, active, Pc, Pext, ptr = state
    keys, invs, used = cache
    Y_a, Y_b, Fc, states, iters, keep, Qa, Va, Aa, Qb, Vb, Ab = hist
    n, nc = q.size, f.size
    P1 = np.empty(n); fb = np.zeros(n); qf = np.empty(n); vf = np.empty(n)
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
    for i in range(i0, i1):
        ta = t0 + i * h
        tb = t0 + (i + 1) * h
        # ---------------- free step of both bodies (contact force at t1 = 0)
        if V.shape[0] > 0:
            _feedback(q, U, V, until, ta, fb)
        ptr[0] = _pre_step(coef, const, tk, Pk, ptr[0], tb, V.shape[0] > 0, fb, q, v, Pext, Pc, P1, qf, vf)
        # ---------------- candidate rows and free relative displacement
        e = np.dot(Phi_c, qf)  # one BLAS product
        ed = np.dot(Phi_c, vf) if any_rigid else e
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
        # ---------------- contact solve
        if method == 0:
            st, it, info1, info2 = _solve_direct(W, C2, nsign, keys, invs, used, u, free, rigid, active, opening,
                                                 max_iter, fn, g, rows2, cols2)
        else:
            st, it, info1, info2 = _solve_fixed_point(W, Cdiag, nsign, u, free, active, f, tol, max_iter, fn)
        if st != OK:
            return st, i + 1, info1, info2
        # ---------------- end-of-step state with the contact force
        anyf, anyg = _contact_load(Phi_c, rigid, any_rigid, fn, g, f, Pf, Pg, Pc)
        _post_step(coef, qf, vf, P1, Pf, Pg, anyf, anyg, zw2, w2, q, v, acc)
        # ---------------- outputs at t1
        r = i + 1
        _record_contact(r, it, fn, bolted, active, opening, dcontact, axial, Fc, states, iters)
        _outputs(L_a, kind_a, targ_a, q[:na], v[:na], acc[:na], Y_a, r)
        if n > na:
            _outputs(L_b, kind_b, targ_b, q[na:], v[na:], acc[na:], Y_b, r)
        if keep:
            _record_modal(r, na, q, v, acc, Qa, Va, Aa, Qb, Vb, Ab)
    return OK, i1, 0.0, 0.0


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
def _outputs(L, kind, targ, q, v, acc, Y, r):
    """Y[r, targ] = sum over rows of L_row . x_kind (x = q, v or acc); rows sorted by kind,
    one BLAS product per kind."""
    if Y.shape[1] == 0:
        return
    for k in range(Y.shape[1]):
        Y[r, k] = 0.0
    nrow = L.shape[0]
    s0 = 0
    while s0 < nrow:
        kd = kind[s0]
        s1 = s0
        while s1 < nrow and kind[s1] == kd:
            s1 += 1
        x = q if kd == 0 else (v if kd == 1 else acc)
        y = np.dot(L[s0:s1], x)
        for row in range(s0, s1):
            Y[r, targ[row]] += y[row - s0]
        s0 = s1
