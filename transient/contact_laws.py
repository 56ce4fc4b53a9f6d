"""Contact laws beyond the reference's, in the compiled step (numba): Coulomb friction,
dashpots in parallel with K_C, capture latches. Used by ``kernel.march`` only when a
problem has one of them (``Contact.laws``); the reference's contact law keeps its own
path (kernel._solve_direct), unchanged.

Per step, as in the kernel: end-of-step relative displacement e = e_free + W f, velocity
e' = e'_free + W_v f (W_v: the velocity step flexibility, coefficients Bcd/Acd).

* **Dashpot** c per direction (tau = c / K_C): while coupled f = -K_C (c0 + e - a) - c e',
  i.e. (C + W + tau W_v)_SS f_S = -(c0 + e_free - a + tau e'_free)_S, the same active-set
  solve with a constant step matrix (folded into W by the solver). A closed normal row
  carries max(0, K_C d + c d'), and only while it penetrates: it opens when that force
  is tensile or when the position has separated, and closes only when both the position
  penetrates and the would-be force is compressive (Kelvin-Voigt with a unilateral clip,
  as Code_Aster's DIS_CHOC with its normal damping).
* **Coulomb friction** mu on the tangent rows T of a released, closed point (normal force
  N = normal_sign f_n > 0), with the tangent K_C as the stick spring anchored at a:
  stick: f_T = -K_T (e_T - a_T) (+ dashpot), kept while |f_T| <= mu N;
  slip:  f_T = mu N d, d the unit direction of the elastic trial force
  g_T = -K_T (e_T - a_T + tau e'_T) at the end of the step (the backward-Euler return
  map of the elastic-plastic analogy; exact for one tangent direction, iterated for
  two), then a_T moves so that the stick relation holds with the slip force. Slip rows
  leave the cached pattern; their forces mu N d, linear in the unknown normal force,
  enter by a rank-k update (k = slipping points) of the pattern's inverse, so N is
  implicit (no lag). Stick <-> slip with a 1e-9 hysteresis on |f_T| / mu N.
* **Latch**: a released point whose normal closes with compression >= latch_force is
  bolted from the next step on (all its directions, tension and compression), its
  tangent rows anchored where they are (no jump in force).

No Python objects, no I/O; status codes as in kernel.py.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from .kernel import _pattern_inverse

OK, NO_CONVERGENCE, CYCLING, SINGULAR, FRICTION_SINGULAR = 0, 1, 2, 3, 4
HYSTERESIS = 1e-9   # relative band on |f_T| / (mu N) between stick and slip
TURN_TOL = 1e-10    # slip direction converged when no component moves by more than this


@njit(cache=True)
def candidates(tb, e, ed, contact, state, rigid, bolted, cand, free, u):
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
def _follow_normals(free, active, opening, slip, mu, axrow):
    """Friction rows of released points are coupled while their normal row is closed."""
    for j in range(mu.size):
        if mu[j] > 0.0 and free[j]:
            a = axrow[j]
            active[j] = active[a] and not opening[a]
            if not active[j]:
                slip[j] = False


@njit(cache=True)
def _normal_flips(W, Wv, tau, nsign, u, ed, free, rigid, active, opening, mu, fn, g, single):
    """The active-set rules of kernel._solve_direct for normal and rigid rows, with the dashpot's
    position conditions; returns whether a row changed (one only when ``single``)."""
    nc = fn.size
    any_rigid = W.shape[0] > nc
    changed = False
    for j in range(nc):
        if not free[j] or mu[j] > 0.0:
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
        if N < 0.0:
            continue           # the normal row opens (kernel rules)
        lim *= N
        if not slipping:
            s = 0.0
            for j in range(nc):
                if axrow[j] == a and mu[j] > 0.0:
                    s += fn[j] * fn[j]
            s = np.sqrt(s)
            if s > lim * (1.0 + HYSTERESIS) and s > 0.0:
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
            if s <= lim * (1.0 - HYSTERESIS):
                for j in range(nc):
                    if axrow[j] == a and mu[j] > 0.0:
                        slip[j] = False
                changed = True
            else:
                for j in range(nc):
                    if axrow[j] == a and mu[j] > 0.0:
                        d = gT[j] / s
                        if abs(d - sdir[j]) > TURN_TOL:
                            turned = True
                        sdir[j] = d
        if changed and single:
            return True, turned
    return changed, turned


@njit(cache=True)
def solve(contact, state, cache, rigid, u, ed, free, opening, max_iter, fn, g, rows2, cols2):
    """Active-set solve with friction, dashpots and rigid rows (kernel._solve_direct's rules plus
    the stick/slip states); returns (status, iterations, info1, info2). ``contact``, ``state``,
    ``cache``: the kernel's bundles; the other arguments as in kernel._solve_direct."""
    W, C2, Wv, tau, nsign, axial, mu, axrow = contact.W, contact.C2, contact.Wv, contact.tau, contact.sign, \
        contact.axial, contact.mu, contact.axrow
    active, slip, sdir = state.active, state.slip, state.sdir
    keys, invs, used = cache
    nc = fn.size
    n2 = W.shape[0]
    any_rigid = n2 > nc
    it = 0
    turns = 0
    single = False
    while True:
        it += 1
        _follow_normals(free, active, opening, slip, mu, axrow)
        for j in range(nc):
            eq = active[j] and not slip[j]
            rows2[j] = eq
            cols2[j] = eq and not opening[j]
            if any_rigid:
                rows2[nc + j] = eq and rigid[j] and not opening[j]
                cols2[nc + j] = eq and rigid[j]
        slot, used[0], ok = _pattern_inverse(rows2, cols2, C2, W, keys, invs, used[0], used[1])
        if not ok:
            return SINGULAR, it, 0.0, 0.0
        used[1] = slot
        x2 = np.dot(invs[slot], u)
        if _slip_update(W, invs[slot], x2, nsign, active, slip, sdir, mu, axrow) != OK:
            return FRICTION_SINGULAR, it, 0.0, 0.0
        for j in range(nc):
            fn[j] = -x2[j]
            g[j] = -x2[nc + j] if any_rigid else 0.0
        for j in range(nc):  # slip rows: mu N d with the solved normal force
            if slip[j] and active[j]:
                fn[j] = mu[j] * nsign[axrow[j]] * fn[axrow[j]] * sdir[j]
        changed = _normal_flips(W, Wv, tau, nsign, u, ed, free, rigid, active, opening, mu, fn, g, single)
        turned = False
        if not (changed and single):
            ch, turned = _friction_checks(W, C2, nsign, u, free, axial, active, mu, axrow, slip, sdir, fn, g,
                                          single and not changed)
            changed = changed or ch
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
def after_step(contact, state, fn, bolted, opening):
    """Anchors and latches at the step end: a slipping tangent row's anchor moves so that the
    stick relation holds with the slip force; an open point's tangent anchors follow the
    relative position (a new contact starts unstressed); a point closed with compression
    >= latch force is latched (bolted from the next step), its frictionless laterals
    anchored at the current relative position."""
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
    for c in range(latch.size):
        if latched[c] or bolted[c] or not latch[c] < np.inf:
            continue
        a = axcol[c]
        if active[a] and not opening[a] and nsign[a] * fn[a] >= latch[c]:
            latched[c] = True
            for j in range(nc):
                if dcontact[j] == c and not axial[j]:
                    if mu[j] == 0.0:
                        anchor[j] = e[j]
                    elif slip[j]:
                        anchor[j] = e[j] + tau[j] * ev[j] + Cdiag[j] * fn[j]
                    slip[j] = False


# ------------------------------------------------------------------ initial state (numpy, not compiled)
def initial_friction(rows, f: np.ndarray, active: np.ndarray, ud: np.ndarray, bolted: np.ndarray) -> None:
    """At t0, a released point that is closed and sliding (tangent relative velocity ud_T != 0)
    already carries its slip force f_T = -mu N ud_T / |ud_T| (in place on f, active): the
    force history then starts right instead of ramping from zero over the first step."""
    for c, a in enumerate(rows.axial_column):
        T = np.flatnonzero((rows.contact == c) & (rows.mu > 0))
        if not T.size or bolted[c] or not active[a]:
            continue
        N = rows.sign[a] * f[a]
        speed = np.linalg.norm(ud[T])
        active[T] = True
        if N > 0 and speed > 0:
            f[T] = -rows.mu[T] * N * ud[T] / speed


def initial_slip(rows, f0: np.ndarray, e0: np.ndarray, active0: np.ndarray, bolted0: np.ndarray):
    """(anchor, slip, sdir) at t0 from the initial contact force: friction rows of released
    points are anchored so that the stick relation holds with their force (unstressed when
    it is zero); those carrying a force are slipping in its direction."""
    anchor = np.zeros(rows.n)
    slip = np.zeros(rows.n, dtype=np.bool_)
    sdir = np.zeros(rows.n)
    for c in range(len(rows.names)):
        T = np.flatnonzero((rows.contact == c) & (rows.mu > 0))
        if not T.size or bolted0[c]:
            continue
        anchor[T] = e0[T] + rows.compliance[T] * f0[T]
        s = np.linalg.norm(f0[T])
        if s > 0 and active0[T].all():
            slip[T] = True
            sdir[T] = f0[T] / s
    return anchor, slip, sdir
