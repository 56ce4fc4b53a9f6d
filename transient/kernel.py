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

No Python objects, no I/O: arrays in, arrays out; status codes report failures.
"""
from __future__ import annotations

import numpy as np
from numba import njit

OK, NO_CONVERGENCE, CYCLING, SINGULAR = 0, 1, 2, 3
BOLTED, CLOSED, OPEN = 0, 1, 2


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
def _pre_step(coef, q, v, Pext, Pc, U, V, until, ta, const, tk, Pk, ptr, tb, fb, P1, qf, vf):
    """One pass over all modes of both bodies: load at tb (table interpolation), feedback held
    over the step (eq. 26), P0 = load(ta) + feedback + contact(ta), P1 = load(tb) + feedback,
    and the free step (end-of-step contact force 0). Pext holds load(ta) on entry, load(tb)
    on exit."""
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
    has_fb = V.shape[0] > 0
    if has_fb:
        _feedback(q, U, V, until, ta, fb)
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
def march(i0, i1, t0, h, method, tol, max_iter,
          # both bodies as one modal set: modes 0..na-1 of body a, then those of body b
          na, coef, w2, zw2, const, tk, Pk, U, V, fb_until,
          L_a, kind_a, targ_a, L_b, kind_b, targ_b,
          # contact rows: Phi_c = [Phi_ca, -Phi_cb], so e = Phi_c q = x_a - x_b, Phi_c^T f on A and B
          Phi_c, Cdiag, coff, dcontact, axial, nsign, release, W, C2,
          # state (mutated)
          q, v, f, active, Pc, Pext, ptr, keys, invs, ncache, last,
          # outputs (mutated)
          Y_a, Y_b, Fc, state, iters, keep, Qa, Va, Aa, Qb, Vb, Ab):
    """March steps i0 -> i1 (time t0 + i h). Returns (status, step, info1, info2)."""
    n, nc, ncon = q.size, f.size, release.size
    nb = n - na
    P1 = np.empty(n); fb = np.zeros(n); qf = np.empty(n); vf = np.empty(n)
    acc = np.empty(n); Pf = np.zeros(n); Pg = np.zeros(n)
    n2 = W.shape[0]  # nc, or 2 nc when there are rigid rows (unknowns [f1; g])
    u = np.zeros(n2); fn = np.empty(nc); Wf = np.empty(nc); g = np.zeros(nc); x2 = np.zeros(n2)
    rows2 = np.zeros(n2, dtype=np.bool_)
    cols2 = np.zeros(n2, dtype=np.bool_)
    opening = np.zeros(nc, dtype=np.bool_)
    fpen = np.zeros(nc)
    rigid = np.empty(nc, dtype=np.bool_)
    any_rigid = False
    for j in range(nc):
        rigid[j] = Cdiag[j] == 0.0
        any_rigid = any_rigid or rigid[j]
    cand = np.empty(nc, dtype=np.bool_)
    bolted = np.empty(ncon, dtype=np.bool_)
    Kc = np.empty(nc)
    for j in range(nc):
        Kc[j] = 1.0 / Cdiag[j] if Cdiag[j] > 0 else 0.0
    for i in range(i0, i1):
        ta = t0 + i * h
        tb = t0 + (i + 1) * h
        # ---------------- free step of both bodies (contact force at t1 = 0)
        ptr[0] = _pre_step(coef, q, v, Pext, Pc, U, V, fb_until, ta, const, tk, Pk, ptr[0], tb, fb, P1, qf, vf)
        # ---------------- candidate rows and free relative displacement (one BLAS product)
        e = np.dot(Phi_c, qf)
        ed = np.dot(Phi_c, vf) if any_rigid else e
        for c in range(ncon):
            bolted[c] = tb < release[c]
        for j in range(nc):
            cand[j] = bolted[dcontact[j]] or axial[j]
            if not bolted[dcontact[j]] and not axial[j]:
                active[j] = False
            elif bolted[dcontact[j]]:
                active[j] = True
            u[j] = coff[j] + e[j] if cand[j] else 0.0
            if any_rigid:
                u[nc + j] = ed[j] if (cand[j] and rigid[j]) else 0.0
        # ---------------- contact solve
        it = 0
        if method == 0:
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
                slot, ncache[0], ok = _pattern_inverse(rows2, cols2, C2, W, keys, invs, ncache[0], last[0])
                if not ok:
                    return SINGULAR, i + 1, 0.0, 0.0
                last[0] = slot
                # the cached inverse is zero outside [cols, rows]: one BLAS product does the masking
                x2[:] = np.dot(invs[slot], u)
                for j in range(nc):
                    fn[j] = -x2[j]
                    g[j] = -x2[nc + j] if any_rigid else 0.0
                changed = False
                for j in range(nc):
                    if not cand[j] or bolted[dcontact[j]]:
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
                    break
                if it > nc + 2:
                    single = True
                if it > max_iter + 4 * nc:
                    return CYCLING, i + 1, float(it), 0.0
        else:
            for j in range(nc):
                fn[j] = f[j] if active[j] else 0.0
            dmax = 0.0
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
                    if cand[j] and not bolted[dcontact[j]]:
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
                    break
                if it >= max_iter or not np.isfinite(dmax):
                    return NO_CONVERGENCE, i + 1, dmax, float(it)
        # ---------------- end-of-step state with the contact force
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
        if any_rigid:  # the next step starts from the end values of the penalty rows only
            for j in range(nc):
                fpen[j] = 0.0 if rigid[j] else fn[j]
            Pc[:] = np.dot(fpen, Phi_c)
        else:
            Pc[:] = Pf
        _post_step(coef, qf, vf, P1, Pf, Pg, anyf, anyg, zw2, w2, q, v, acc)
        # ---------------- outputs at t1
        r = i + 1
        for j in range(nc):
            Fc[r, j] = fn[j]
        for c in range(ncon):
            state[r, c] = BOLTED if bolted[c] else OPEN
        for j in range(nc):
            if axial[j] and not bolted[dcontact[j]] and active[j] and not opening[j]:
                state[r, dcontact[j]] = CLOSED
        iters[r] = it
        for j in range(nc):
            if opening[j]:  # a rigid row that opened during this step starts the next one open
                active[j] = False
                opening[j] = False
        _outputs(L_a, kind_a, targ_a, q[:na], v[:na], acc[:na], Y_a, r)
        if nb > 0:
            _outputs(L_b, kind_b, targ_b, q[na:], v[na:], acc[na:], Y_b, r)
        if keep:
            for m in range(na):
                Qa[r, m] = q[m]; Va[r, m] = v[m]; Aa[r, m] = acc[m]
            for m in range(nb):
                Qb[r, m] = q[na + m]; Vb[r, m] = v[na + m]; Ab[r, m] = acc[na + m]
    return OK, i1, 0.0, 0.0


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
