"""Cases marched together: K problems that share both bodies, their contact rows, step and
outputs, and differ in their forcing, feedback, release times and initial state (a
campaign's dispersed cases), solved by one time loop (issue 28).

Per step the one-by-one kernel (kernel.py) streams every mode's eight step coefficients,
the contact rows Phi (n_c x n) twice, and a case's own load table, free state and
contact load; the arithmetic per mode is a few multiply-adds. Here a group of cases
(:data:`GROUP`, states as n x K_s arrays, the cases contiguous) reads each shared array
once for all of them and keeps as per-case data only what must be (3 n a case):

* the free state X = (q_free, v_free) of the last step and the contact load Pc = Phi^T f
  at its end. The state is q = X_q + Bc Pc, v = X_v + Bcd Pc (kernel.py's end-of-step
  update, eq. 9-10), so the next free state is one pass over the modes (the "sweep"):

      X_q <- F X_q + G X_v + (F Bc + G Bcd + Ac) Pc + L_q,   X_v likewise,

  with L_q = Ac (P_ext(ta) + fb) + Bc (P_ext(tb) + fb) the applied loads and feedback;
* the applied loads in a basis shared by the group: every case's constant and tabulated
  modal loads (transient/assembly.py ModalLoad) lie in the span of a few modal vectors (the
  loaded DOFs' mode-shape rows, gravity), found by one SVD of them all (singular values
  below 1e-14 of the largest dropped, as feedback_factors does); a case carries their
  coefficients (its own time grid kept). The feedback terms (eq. 26) likewise: U and V of
  every case in shared bases (a dispersed gain changes the coefficients, not the bases);
* the outputs at the step end from X, the contact force, the load coefficients and the
  feedback coordinates through matrices formed once (acceleration = P1 + Pc - 2 zeta omega
  v - omega^2 q substituted).

The work over all modes is then one pass a step over the group (``_modes``): per mode its
Pc = Phi^T F, its load terms, the sweep and its shares of e_free = Phi X_q and of the
outputs' state terms (its body's output rows on X_q and X_v), each shared row read once,
four modes at a time for a full group (``_modes8``); the contact solve stays per
case: kernel.py's candidate rows and active-set solve (``_candidates``, ``_solve_direct``),
the pattern inverses shared (one W) with each case's last pattern tried first. Before the
group's first release every row of every case is bolted: one pattern, no iteration, and the
group's forces are one product with its inverse.

Measured: benchmarks/bench_batch.py at 3,000 + 300 modes, 24 rows, 64 cases, its figures
rendered into README "Benchmarks"; the speed-up depends on the machine's cache (the pass
streams Phi and the output rows from the core's L2 where they fit: 0.6 MB at 3,300 modes
and 24 rows).

Scope: the reference's contact law with penalty rows and the direct solve (no rigid rows,
friction, dashpots, latches or soft release: solve those one by one); one step for all
(``accuracy`` None: the h/2 estimate is a second batch); no modal histories. A problem
outside it is refused with the field that differs.

Results are the one-by-one solve's to round-off, not bit for bit: the sums run in another
order (the fused pass and the substituted state). How far apart two orders of the same sums may land
is a property of the problem, not of this module: a bolted stack's contact forces are K_C
times small differences of large modal displacements (tests/transient/test_batch.py
measures it against a one-by-one solve of the same case with its modes reordered).
"""
from __future__ import annotations

import time as _time
from dataclasses import dataclass
from typing import Iterator, NamedTuple, Sequence

import numpy as np
from numba import njit

from liftoff.core.errors import ConvergenceError, InputError

from .assembly import contact_rows, modal_load
from .coefficients import step_coefficients
from .guard import GrowthGuard
from .kernel import BOLTED, OK, SINGULAR, History, _candidates, _pattern_inverse, _record_contact, _solve_direct
from .model import TransientProblem
from .result import TransientResult
from .solver import (CHUNK, _contact_inputs, _failure, _modal_inputs, _new_cache, _result,
                     _spectral_radius, _start, initial_contact_force, initial_state, output_plan)
from .stepping import check_memory, choose_step

#: cases marched together in one compiled loop: their states (X_q, X_v, Pc: 3 x n x 8
#: doubles, 0.6 MB at 3,300 modes) and the shared arrays (coefficients, Phi) stay in a
#: core's L2 cache; more gain nothing per case-step (benchmarks/bench_batch.py)
GROUP = 8
#: singular values below this fraction of the largest are dropped from the shared load and
#: feedback bases (round-off of the stacked tables: feedback_factors' threshold)
BASIS_RTOL = 1e-14


# ------------------------------------------------------------------ kernel inputs
class Shared(NamedTuple):
    """What every case of a batch shares (n modes of both bodies, n_c contact rows)."""

    ST: np.ndarray       # (n, 6) sweep coefficients F G Dq Fd Gd Dv of each mode, Dq = F Bc + G Bcd + Ac (Dv alike)
    Mq: np.ndarray       # (n, m) X_q's load columns: [Ac B^T | Bc B^T | (Ac + Bc) Ub]
    Mv: np.ndarray       # (n, m) X_v's: [Acd B^T | Bcd B^T | (Acd + Bcd) Ub]
    PhiT: np.ndarray     # (n, n_c) contact rows [Phi_a, -Phi_b] transposed (a mode's row contiguous)
    Vq: np.ndarray       # (r_v, n) feedback basis on q
    Vv: np.ndarray       # (r_v, n) on v
    Vf: np.ndarray       # (r_v, n_c) on the contact force (the state's Bc Pc, Bcd Pc parts)
    W: np.ndarray        # (n_c, n_c) step flexibility
    C2: np.ndarray       # (n_c,) compliance 1/K_C
    offset: np.ndarray   # (n_c,) c
    dcontact: np.ndarray  # (n_c,) contact point of each row
    axial: np.ndarray    # (n_c,) bool
    nsign: np.ndarray    # (n_c,) normal sign
    na: int              # modes of body a (then body b's)
    R: tuple             # (RqT_a, RvT_a, RqT_b, RvT_b): each body's output rows on its X_q, X_v that are
    #                      not zero, transposed ((na, k) and (n - na, k)) ...
    iR: tuple            # ... and the targets each adds to (int64; body b's after body a's ntarg_a)
    Ax: np.ndarray       # (ntarg_a + ntarg_b, n_c + n_b + r_u) the outputs from [f; g(tb); z]
    ntarg_a: int         # body a's targets (then body b's)


class Cases(NamedTuple):
    """Per case (index k first) of a group: load coefficients, feedback, release times."""

    c: np.ndarray        # (K, n_b) constant load's coefficients in the basis
    tk: np.ndarray       # (K, n_k) load breakpoints (padded with +inf past a case's own n_tk)
    n_tk: np.ndarray     # (K,) int64: breakpoints of each case
    gk: np.ndarray       # (K, n_k, n_b) tabulated load's coefficients at its breakpoints
    Cv: np.ndarray       # (K, r, r_v) feedback term rows in the V basis (zero rows: no term)
    Du: np.ndarray       # (K, r_u, r) feedback columns in the U basis
    since: np.ndarray    # (K, r) s
    until: np.ndarray    # (K, r) s
    release: np.ndarray  # (K, n_contacts) s


class GroupState(NamedTuple):
    """The group's state between chunks (mutated), cases contiguous in the last axis."""

    Xq: np.ndarray       # (n, K) free modal displacement of the last step
    Xv: np.ndarray       # (n, K)
    Pc: np.ndarray       # (n, K) modal contact load at its end, Phi^T f
    F: np.ndarray        # (n_c, K) contact force on A at its end
    active: np.ndarray   # (K, n_c) bool
    g: np.ndarray        # (K, n_b) load coefficients at its end
    ptr: np.ndarray      # (K,) int64 position in each case's breakpoints
    last: np.ndarray     # (K,) int64 pattern slot each case used last


class GroupHistory(NamedTuple):
    """Histories of the group (case k first; row r = step r; mutated)."""

    Y_a: np.ndarray      # (K, n_t, ntarg_a)
    Y_b: np.ndarray      # (K, n_t, ntarg_b)
    Fc: np.ndarray       # (K, n_t, n_c)
    state: np.ndarray    # (K, n_t, n_contacts) int8
    iters: np.ndarray    # (K, n_t) int32


# ------------------------------------------------------------------ kernel
@njit(cache=True, fastmath=False)
def _modes(ST, Xq, Xv, Pc, F, PhiT, Mq, Mv, Y, E, na, R, O, from_f):
    """One pass over the modes of the group's step (module docstring), the cases of a mode
    contiguous: per mode its contact load Pc = Phi^T f of the last step's force (taken from F
    when ``from_f``, else the state's Pc as it stands), its load terms Mq Y and Mv Y, the free
    state X <- F X_q + G X_v + D Pc + L (eq. 9-10 in sweep form), and its shares of the contact
    rows' free displacement E = Phi X_q and of its body's output terms O = (Rq_a X_q_a, Rv_a X_v_a,
    Rq_b X_q_b, Rv_b X_v_b) (R: the rows transposed, as Shared.R). Each row of PhiT, Mq, Mv and
    R read once a step instead of once a product (with 8 columns a BLAS product spent more time
    packing the state than multiplying). Body a's modes (the first ``na``), then body b's, each
    with its own output rows; E sums the modes in order. A full group (K = :data:`GROUP` = 8)
    takes :func:`_modes8`: the same arithmetic in the same order, bit for bit."""
    n, K = Xq.shape
    E[:] = 0.0
    for o in O:
        o[:] = 0.0
    for lo, hi, RqT, RvT, Oq, Ov in ((0, na, R[0], R[1], O[0], O[1]), (na, n, R[2], R[3], O[2], O[3])):
        if K == 8:
            _modes8(ST[lo:hi], Xq[lo:hi], Xv[lo:hi], Pc[lo:hi], F, PhiT[lo:hi], Mq[lo:hi], Mv[lo:hi], Y, E, RqT, RvT,
                    Oq, Ov, from_f)
        else:
            _modes_rolled(ST[lo:hi], Xq[lo:hi], Xv[lo:hi], Pc[lo:hi], F, PhiT[lo:hi], Mq[lo:hi], Mv[lo:hi], Y, E,
                          RqT, RvT, Oq, Ov, from_f)


@njit(cache=True, fastmath=False)
def _modes_rolled(ST, Xq, Xv, Pc, F, PhiT, Mq, Mv, Y, E, RqT, RvT, Oq, Ov, from_f):
    """:func:`_modes` over one body's modes (the arrays its rows), any number of cases; adds to
    E, Oq and Ov."""
    n, K = Xq.shape
    nc, m, kq, kv = PhiT.shape[1], Mq.shape[1], RqT.shape[1], RvT.shape[1]
    for i in range(n):
        Fq = ST[i, 0]; G = ST[i, 1]; Dq = ST[i, 2]; Fd = ST[i, 3]; Gd = ST[i, 4]; Dv = ST[i, 5]
        phi = PhiT[i]; mq = Mq[i]; mv = Mv[i]; xq = Xq[i]; xv = Xv[i]; p = Pc[i]; rq = RqT[i]; rv = RvT[i]
        for k in range(K):
            if from_f:
                pc = 0.0
                for j in range(nc):
                    pc = pc + phi[j] * F[j, k]
                p[k] = pc
            else:
                pc = p[k]
            a = 0.0
            b = 0.0
            for j in range(m):
                a = a + mq[j] * Y[j, k]
                b = b + mv[j] * Y[j, k]
            q = xq[k]; v = xv[k]
            u = Fq * q + G * v + Dq * pc + a
            w = Fd * q + Gd * v + Dv * pc + b
            xv[k] = w
            xq[k] = u
            for j in range(nc):
                E[j, k] = E[j, k] + phi[j] * u
            for j in range(kq):
                Oq[j, k] = Oq[j, k] + rq[j] * u
            for j in range(kv):
                Ov[j, k] = Ov[j, k] + rv[j] * w


@njit(cache=True, fastmath=False)
def _modes8(ST, Xq, Xv, Pc, F, PhiT, Mq, Mv, Y, E, RqT, RvT, Oq, Ov, from_f):
    """:func:`_modes_rolled` for eight cases, four modes at a time: their contact loads (each F
    row loaded once for the four), then each mode's load terms and sweep, then their shares of
    E, Oq and Ov (each row of those loaded and stored once for the four); the last n % 4 modes
    through the rolled loop. Every line is unrolled over the cases with its loads before its
    stores: LLVM cannot prove the rows apart, so a rolled loop stays scalar (one multiply-add
    at a time); written so, the SLP vectorizer packs each line into vector instructions. Per mode and case the same arithmetic in the same order as the rolled
    loop, so the same bits (tests/transient/test_batch.py); the four-mode blocks took the pass
    at 3,300 modes and 24 rows from 97-103 to 62-64 us on this machine (2026-12-07: the products
    with F and E had been bound by their loads and stores). The sweep is inlined into this
    loop (numba's ``inline="always"``, one copy in a loop over the four modes): called four
    times a block, each call passing its arrays' structures and saving the vector registers,
    it cost a quarter of the pass on an AMD EPYC (znver3, 256-bit vectors): at 3,300 modes,
    24 rows, 4 load columns and 2 output rows 257 us called against 191 us inlined (2026-12-08).
    Inlining the other two blocks as well took it to 173 us, but numba then compiled this
    function in 127 s instead of 16 s (4 s with no block inlined): ``make setup`` compiles it."""
    n = PhiT.shape[0]
    kq, kv = RqT.shape[1], RvT.shape[1]
    n4 = n - n % 4
    for i in range(0, n4, 4):
        if from_f:
            _contact_load8x4(PhiT, F, Pc, i)
        for d in range(4):
            _sweep8(ST, Xq, Xv, Pc, Mq, Mv, Y, i + d)
        _add_rows8x4(PhiT, Xq, E, i)
        if kq:
            _add_rows8x4(RqT, Xq, Oq, i)
        if kv:
            _add_rows8x4(RvT, Xv, Ov, i)
    if n4 < n:                           # the last modes one at a time: the rolled loop, the same sums
        _modes_rolled(ST[n4:], Xq[n4:], Xv[n4:], Pc[n4:], F, PhiT[n4:], Mq[n4:], Mv[n4:], Y, E, RqT[n4:], RvT[n4:],
                      Oq, Ov, from_f)


@njit(cache=True)
def _contact_load8x4(PhiT, F, Pc, i):
    """Pc[i:i + 4] = PhiT[i:i + 4] F for eight cases: each F row loaded once for four modes;
    per mode the sum over the rows in the order of :func:`_modes_rolled`."""
    r0 = PhiT[i]; r1 = PhiT[i + 1]; r2 = PhiT[i + 2]; r3 = PhiT[i + 3]
    a0 = 0.0; a1 = 0.0; a2 = 0.0; a3 = 0.0; a4 = 0.0; a5 = 0.0; a6 = 0.0; a7 = 0.0
    b0 = 0.0; b1 = 0.0; b2 = 0.0; b3 = 0.0; b4 = 0.0; b5 = 0.0; b6 = 0.0; b7 = 0.0
    c0 = 0.0; c1 = 0.0; c2 = 0.0; c3 = 0.0; c4 = 0.0; c5 = 0.0; c6 = 0.0; c7 = 0.0
    d0 = 0.0; d1 = 0.0; d2 = 0.0; d3 = 0.0; d4 = 0.0; d5 = 0.0; d6 = 0.0; d7 = 0.0
    for j in range(F.shape[0]):
        f = F[j]
        f0 = f[0]; f1 = f[1]; f2 = f[2]; f3 = f[3]; f4 = f[4]; f5 = f[5]; f6 = f[6]; f7 = f[7]
        t = r0[j]
        a0 = a0 + t * f0; a1 = a1 + t * f1; a2 = a2 + t * f2; a3 = a3 + t * f3
        a4 = a4 + t * f4; a5 = a5 + t * f5; a6 = a6 + t * f6; a7 = a7 + t * f7
        t = r1[j]
        b0 = b0 + t * f0; b1 = b1 + t * f1; b2 = b2 + t * f2; b3 = b3 + t * f3
        b4 = b4 + t * f4; b5 = b5 + t * f5; b6 = b6 + t * f6; b7 = b7 + t * f7
        t = r2[j]
        c0 = c0 + t * f0; c1 = c1 + t * f1; c2 = c2 + t * f2; c3 = c3 + t * f3
        c4 = c4 + t * f4; c5 = c5 + t * f5; c6 = c6 + t * f6; c7 = c7 + t * f7
        t = r3[j]
        d0 = d0 + t * f0; d1 = d1 + t * f1; d2 = d2 + t * f2; d3 = d3 + t * f3
        d4 = d4 + t * f4; d5 = d5 + t * f5; d6 = d6 + t * f6; d7 = d7 + t * f7
    p = Pc[i + 0]
    p[0] = a0; p[1] = a1; p[2] = a2; p[3] = a3; p[4] = a4; p[5] = a5; p[6] = a6; p[7] = a7
    p = Pc[i + 1]
    p[0] = b0; p[1] = b1; p[2] = b2; p[3] = b3; p[4] = b4; p[5] = b5; p[6] = b6; p[7] = b7
    p = Pc[i + 2]
    p[0] = c0; p[1] = c1; p[2] = c2; p[3] = c3; p[4] = c4; p[5] = c5; p[6] = c6; p[7] = c7
    p = Pc[i + 3]
    p[0] = d0; p[1] = d1; p[2] = d2; p[3] = d3; p[4] = d4; p[5] = d5; p[6] = d6; p[7] = d7


@njit(cache=True)
def _add_rows8x4(RT, X, E, i):
    """E += RT[i:i + 4]^T X[i:i + 4] for eight cases (rows RT transposed: the contact rows on X_q,
    or a body's output rows on X_q or X_v): each E row loaded and stored once for four modes,
    the four added one after another as :func:`_modes_rolled` adds them."""
    r0 = RT[i]; r1 = RT[i + 1]; r2 = RT[i + 2]; r3 = RT[i + 3]
    x = X[i + 0]
    ua0 = x[0]; ua1 = x[1]; ua2 = x[2]; ua3 = x[3]; ua4 = x[4]; ua5 = x[5]; ua6 = x[6]; ua7 = x[7]
    x = X[i + 1]
    ub0 = x[0]; ub1 = x[1]; ub2 = x[2]; ub3 = x[3]; ub4 = x[4]; ub5 = x[5]; ub6 = x[6]; ub7 = x[7]
    x = X[i + 2]
    uc0 = x[0]; uc1 = x[1]; uc2 = x[2]; uc3 = x[3]; uc4 = x[4]; uc5 = x[5]; uc6 = x[6]; uc7 = x[7]
    x = X[i + 3]
    ud0 = x[0]; ud1 = x[1]; ud2 = x[2]; ud3 = x[3]; ud4 = x[4]; ud5 = x[5]; ud6 = x[6]; ud7 = x[7]
    for j in range(E.shape[0]):
        e = E[j]
        e0 = e[0]; e1 = e[1]; e2 = e[2]; e3 = e[3]; e4 = e[4]; e5 = e[5]; e6 = e[6]; e7 = e[7]
        t = r0[j]
        e0 = e0 + t * ua0; e1 = e1 + t * ua1; e2 = e2 + t * ua2; e3 = e3 + t * ua3
        e4 = e4 + t * ua4; e5 = e5 + t * ua5; e6 = e6 + t * ua6; e7 = e7 + t * ua7
        t = r1[j]
        e0 = e0 + t * ub0; e1 = e1 + t * ub1; e2 = e2 + t * ub2; e3 = e3 + t * ub3
        e4 = e4 + t * ub4; e5 = e5 + t * ub5; e6 = e6 + t * ub6; e7 = e7 + t * ub7
        t = r2[j]
        e0 = e0 + t * uc0; e1 = e1 + t * uc1; e2 = e2 + t * uc2; e3 = e3 + t * uc3
        e4 = e4 + t * uc4; e5 = e5 + t * uc5; e6 = e6 + t * uc6; e7 = e7 + t * uc7
        t = r3[j]
        e0 = e0 + t * ud0; e1 = e1 + t * ud1; e2 = e2 + t * ud2; e3 = e3 + t * ud3
        e4 = e4 + t * ud4; e5 = e5 + t * ud5; e6 = e6 + t * ud6; e7 = e7 + t * ud7
        e[0] = e0; e[1] = e1; e[2] = e2; e[3] = e3; e[4] = e4; e[5] = e5; e[6] = e6; e[7] = e7


@njit(cache=True, inline="always")
def _sweep8(ST, Xq, Xv, Pc, Mq, Mv, Y, i):
    """Mode i's load terms a = Mq[i] Y, b = Mv[i] Y and its free state X <- F X_q + G X_v + D Pc
    + L (eq. 9-10 in sweep form) for eight cases, Pc[i] as it stands (a mode of :func:`_modes8`)."""
    c = ST[i]
    Fq = c[0]; G = c[1]; Dq = c[2]; Fd = c[3]; Gd = c[4]; Dv = c[5]
    mq = Mq[i]; mv = Mv[i]; xq = Xq[i]; xv = Xv[i]; p = Pc[i]
    p0 = p[0]; p1 = p[1]; p2 = p[2]; p3 = p[3]; p4 = p[4]; p5 = p[5]; p6 = p[6]; p7 = p[7]
    a0 = 0.0; a1 = 0.0; a2 = 0.0; a3 = 0.0; a4 = 0.0; a5 = 0.0; a6 = 0.0; a7 = 0.0
    b0 = 0.0; b1 = 0.0; b2 = 0.0; b3 = 0.0; b4 = 0.0; b5 = 0.0; b6 = 0.0; b7 = 0.0
    for j in range(Mq.shape[1]):
        tq = mq[j]; tv = mv[j]; y = Y[j]
        y0 = y[0]; y1 = y[1]; y2 = y[2]; y3 = y[3]; y4 = y[4]; y5 = y[5]; y6 = y[6]; y7 = y[7]
        a0 = a0 + tq * y0; a1 = a1 + tq * y1; a2 = a2 + tq * y2; a3 = a3 + tq * y3
        a4 = a4 + tq * y4; a5 = a5 + tq * y5; a6 = a6 + tq * y6; a7 = a7 + tq * y7
        b0 = b0 + tv * y0; b1 = b1 + tv * y1; b2 = b2 + tv * y2; b3 = b3 + tv * y3
        b4 = b4 + tv * y4; b5 = b5 + tv * y5; b6 = b6 + tv * y6; b7 = b7 + tv * y7
    q0 = xq[0]; q1 = xq[1]; q2 = xq[2]; q3 = xq[3]; q4 = xq[4]; q5 = xq[5]; q6 = xq[6]; q7 = xq[7]
    v0 = xv[0]; v1 = xv[1]; v2 = xv[2]; v3 = xv[3]; v4 = xv[4]; v5 = xv[5]; v6 = xv[6]; v7 = xv[7]
    u0 = Fq * q0 + G * v0 + Dq * p0 + a0
    u1 = Fq * q1 + G * v1 + Dq * p1 + a1
    u2 = Fq * q2 + G * v2 + Dq * p2 + a2
    u3 = Fq * q3 + G * v3 + Dq * p3 + a3
    u4 = Fq * q4 + G * v4 + Dq * p4 + a4
    u5 = Fq * q5 + G * v5 + Dq * p5 + a5
    u6 = Fq * q6 + G * v6 + Dq * p6 + a6
    u7 = Fq * q7 + G * v7 + Dq * p7 + a7
    xv[0] = Fd * q0 + Gd * v0 + Dv * p0 + b0
    xv[1] = Fd * q1 + Gd * v1 + Dv * p1 + b1
    xv[2] = Fd * q2 + Gd * v2 + Dv * p2 + b2
    xv[3] = Fd * q3 + Gd * v3 + Dv * p3 + b3
    xv[4] = Fd * q4 + Gd * v4 + Dv * p4 + b4
    xv[5] = Fd * q5 + Gd * v5 + Dv * p5 + b5
    xv[6] = Fd * q6 + Gd * v6 + Dv * p6 + b6
    xv[7] = Fd * q7 + Gd * v7 + Dv * p7 + b7
    xq[0] = u0; xq[1] = u1; xq[2] = u2; xq[3] = u3; xq[4] = u4; xq[5] = u5; xq[6] = u6; xq[7] = u7


@njit(cache=True)
def _load_at(c, tk, n_tk, gk, ptr, tb, out):
    """out = the case's load coefficients at tb (constant + table interpolated from position
    ``ptr``, as kernel._pre_step walks it); returns the new position."""
    nb = c.size
    nk = n_tk
    for j in range(nb):
        out[j] = c[j]
    if nk == 0:
        return ptr
    if tb <= tk[0]:
        for j in range(nb):
            out[j] += gk[0, j]
        return 0
    if tb >= tk[nk - 1]:
        for j in range(nb):
            out[j] += gk[nk - 1, j]
        return nk - 1
    while ptr + 1 < nk and tk[ptr + 1] <= tb:
        ptr += 1
    while ptr > 0 and tk[ptr] > tb:
        ptr -= 1
    w = (tb - tk[ptr]) / (tk[ptr + 1] - tk[ptr])
    a = 1.0 - w
    for j in range(nb):
        out[j] += a * gk[ptr, j] + w * gk[ptr + 1, j]
    return ptr


@njit(cache=True)
def _outputs(sh, O, Xo, y, Y_a, Y_b, row):
    """Row ``row`` of every case's output histories Y_a, Y_b (K, n_t, ntarg): Ax [f; g; z]
    plus the state terms O that :func:`_modes` summed (module docstring)."""
    np.dot(sh.Ax, Xo, y)
    K = y.shape[1]
    for o, targets in zip(O, sh.iR):
        for i in range(targets.size):
            for k in range(K):
                y[targets[i], k] += o[i, k]
    na = sh.ntarg_a
    for k in range(K):
        for j in range(na):
            Y_a[k, row, j] = y[j, k]
        for j in range(na, y.shape[0]):
            Y_b[k, row, j - na] = y[j, k]


@njit(cache=True)
def _load_columns(ta, tb, cs, g, ptr, Sfb, has_fb, Y):
    """Y (m, K): per case the load coefficients at ta (``g`` on entry) and at tb (``g`` on
    exit, from its table, position ``ptr``), then the feedback coordinates z = Du (on-mask
    * Cv Sfb) held over the step (eq. 26)."""
    c, tk, n_tk, gk, Cv, Du, since, until = cs[:8]
    K, nb = g.shape
    r, ru = since.shape[1], Du.shape[1]
    s = np.empty(r)
    g1 = np.empty(nb)
    for k in range(K):
        for j in range(2 * nb, Y.shape[0]):
            Y[j, k] = 0.0
        for j in range(nb):
            Y[j, k] = g[k, j]
        ptr[k] = _load_at(c[k], tk[k], n_tk[k], gk[k], ptr[k], tb, g1)
        for j in range(nb):
            Y[nb + j, k] = g1[j]
            g[k, j] = g1[j]
        if has_fb:
            for a in range(r):
                acc = 0.0
                if since[k, a] <= ta < until[k, a]:
                    for b in range(Cv.shape[2]):
                        acc += Cv[k, a, b] * Sfb[b, k]
                s[a] = acc
            for j in range(ru):
                acc = 0.0
                for a in range(r):
                    acc += Du[k, j, a] * s[a]
                Y[2 * nb + j, k] = acc


@njit(cache=True)
def _solve_bolted(row, sh, E, keys, invs, used, last, F, active, Fc, states, iters):
    """Every row of every case bolted: kernel.py's solve on the full active set (one pattern,
    no iteration), the group's forces F = -(C + W)^-1 (c + e_free) in one product. Returns
    False when the pattern is singular."""
    nc, K = E.shape
    all_rows = np.ones(nc, dtype=np.bool_)
    slot, used[0], ok = _pattern_inverse(all_rows, all_rows, sh.C2, sh.W, keys, invs, used[0], last[0])
    if not ok:
        return False
    for k in range(K):
        last[k] = slot
        for j in range(nc):
            E[j, k] += sh.offset[j]
    np.dot(invs[slot], E, F)
    for k in range(K):
        for j in range(nc):
            F[j, k] = -F[j, k]
            Fc[k, row, j] = F[j, k]
            active[k, j] = True
        for ci in range(states.shape[2]):
            states[k, row, ci] = BOLTED
        iters[k, row] = 1
    return True


@njit(cache=True)
def _solve_cases(row, tb, max_iter, sh, release, E, keys, invs, used, last, F, active, Fc, states, iters):
    """kernel.py's candidate rows and active-set solve, case by case (the pattern cache shared,
    each case's last pattern tried first). Returns (status, info1, info2, case)."""
    nc, K = E.shape
    e = np.empty(nc); u = np.zeros(nc); fn = np.empty(nc); gg = np.zeros(nc)
    rows2 = np.zeros(nc, dtype=np.bool_); cols2 = np.zeros(nc, dtype=np.bool_)
    opening = np.zeros(nc, dtype=np.bool_); rigid = np.zeros(nc, dtype=np.bool_)
    cand = np.empty(nc, dtype=np.bool_); free = np.empty(nc, dtype=np.bool_)
    bolted = np.empty(release.shape[1], dtype=np.bool_)
    u2 = np.zeros(2, dtype=np.int64)
    for k in range(K):
        for j in range(nc):
            e[j] = E[j, k]
        act = active[k]
        _candidates(tb, release[k], sh.dcontact, sh.axial, sh.offset, rigid, False, e, e, bolted, cand, free, act, u)
        u2[0] = used[0]
        u2[1] = last[k]
        st, it, info1, info2 = _solve_direct(sh.W, sh.C2, sh.nsign, keys, invs, u2, u, free, rigid, act, opening,
                                             max_iter, fn, gg, rows2, cols2)
        used[0] = u2[0]
        last[k] = u2[1]
        if st != OK:
            return st, info1, info2, k
        for j in range(nc):
            F[j, k] = fn[j]
        _record_contact(row, it, fn, bolted, act, opening, sh.dcontact, sh.axial, Fc[k], states[k], iters[k])
    return OK, 0.0, 0.0, -1


@njit(cache=True, nogil=True)
def march_group(i0, i1, t0, h, max_iter, sh, cs, st, keys, invs, used, hist):
    """March the group's cases through steps i0 -> i1 (time t0 + i h). Returns (status,
    step, info1, info2, case): the first case that failed, else -1. ``keys``, ``invs``,
    ``used``: the shared pattern cache (kernel.Cache's arrays)."""
    release = cs.release
    Xq, Xv, Pc, F, active, g, ptr, last = st
    Y_a, Y_b, Fc, states, iters = hist
    K = Xq.shape[1]
    nc, nb, ru, m = sh.PhiT.shape[1], g.shape[1], cs.Du.shape[1], sh.Mq.shape[1]
    Y = np.zeros((m, K))               # [g(ta); g(tb); z] per case: the load columns' coefficients
    Xo = np.zeros((nc + nb + ru, K))   # [f; g(tb); z]: the outputs' small columns
    E = np.empty((nc, K))
    O = (np.empty((sh.R[0].shape[1], K)), np.empty((sh.R[1].shape[1], K)),
         np.empty((sh.R[2].shape[1], K)), np.empty((sh.R[3].shape[1], K)))
    Sfb = np.zeros((sh.Vq.shape[0], K))
    y = np.empty((sh.Ax.shape[0], K))
    first_release = np.inf
    for k in range(K):
        for ci in range(release.shape[1]):
            first_release = min(first_release, release[k, ci])
    has_fb = cs.since.shape[1] > 0 and sh.Vq.shape[0] > 0 and ru > 0
    for i in range(i0, i1):
        ta = t0 + i * h
        tb = t0 + (i + 1) * h
        row = i + 1
        # ---------------- feedback from the state at ta (eq. 26), loads; the free step: one sweep
        if has_fb:
            np.dot(sh.Vq, Xq, Sfb)
            Sfb += np.dot(sh.Vv, Xv)
            Sfb += np.dot(sh.Vf, F)
        _load_columns(ta, tb, cs, g, ptr, Sfb, has_fb, Y)
        _modes(sh.ST, Xq, Xv, Pc, F, sh.PhiT, sh.Mq, sh.Mv, Y, E, sh.na, sh.R, O, i > i0)
        # ---------------- the contact solve
        if tb < first_release:
            if not _solve_bolted(row, sh, E, keys, invs, used, last, F, active, Fc, states, iters):
                return SINGULAR, i + 1, 0.0, 0.0, 0
        else:
            status, info1, info2, k = _solve_cases(row, tb, max_iter, sh, release, E, keys, invs, used, last, F,
                                                   active, Fc, states, iters)
            if status != OK:
                return status, i + 1, info1, info2, k
        # ---------------- the outputs at tb (the contact load Phi^T f: the next step's _modes)
        for k in range(K):
            for j in range(nc):
                Xo[j, k] = F[j, k]
            for j in range(nb + ru):
                Xo[nc + j, k] = Y[nb + j, k]
        if y.shape[0] > 0:
            _outputs(sh, O, Xo, y, Y_a, Y_b, row)
    if i1 > i0:                        # the state's Pc of the last force, as the chunk's caller reads it
        np.dot(sh.PhiT, F, Pc)
    return OK, i1, 0.0, 0.0, -1


# ------------------------------------------------------------------ set-up
def _basis(blocks: list[np.ndarray], what: str) -> np.ndarray:
    """An orthonormal basis (r, n) of the row space of the stacked ``blocks`` (each (k_i, n)),
    singular values below BASIS_RTOL of the largest dropped."""
    n = blocks[0].shape[1]
    A = np.vstack([b for b in blocks if b.size] or [np.zeros((0, n))])
    if not A.size:
        return np.zeros((0, n))
    _, sv, Vt = np.linalg.svd(A, full_matrices=False)
    keep = sv > BASIS_RTOL * sv[0] if sv.size and sv[0] > 0 else np.zeros(0, bool)
    if keep.sum() > min(n, 256):
        import warnings

        warnings.warn(f"batch: the cases' {what} span {int(keep.sum())} modal vectors; the batch marches them all "
                      "each step (a full-rank table is slower batched than one by one)", stacklevel=3)
    return np.ascontiguousarray(Vt[keep])


def _same(a, b) -> bool:
    if a is b:
        return True
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return np.shape(a) == np.shape(b) and np.array_equal(np.asarray(a), np.asarray(b))
    return a == b


def _check_shared(problems: Sequence[TransientProblem], rows_k) -> None:
    """InputError naming the first problem and field that a batch cannot share."""
    p0, r0 = problems[0], rows_k[0]
    if r0.laws:
        raise InputError("batch: friction, dashpots, latches and soft release are not marched batched; solve these "
                         "problems one by one (liftoff.transient.solve)")
    if np.any(r0.compliance == 0):
        raise InputError("batch: rigid contact rows are not marched batched (penalty contacts only); solve these "
                         "problems one by one (liftoff.transient.solve)")
    for k, (p, rows) in enumerate(zip(problems, rows_k)):
        who = f"batch problem {k}"
        if rows.laws:                        # (each problem's: the kernel is built from problem 0's rows)
            raise InputError(f"{who}: friction, dashpots, latches or soft release are not marched batched; solve "
                             "these problems one by one (liftoff.transient.solve)")
        if p.method != "direct":
            raise InputError(f"{who}: method {p.method!r}; a batch uses the direct active-set solve")
        if p.accuracy is not None:
            raise InputError(f"{who}: accuracy = {p.accuracy!r}; a batch marches one step (solve the h/2 run as "
                             "a second batch)")
        if p.keep_modal:
            raise InputError(f"{who}: keep_modal; a batch keeps no modal histories")
        for key in ("body_a", "body_b"):
            a, b = getattr(p0, key), getattr(p, key)
            if a is not b and not (a.dof_labels == b.dof_labels and all(
                    _same(getattr(a, f), getattr(b, f)) for f in ("omega", "zeta", "phi", "ref_point",
                                                                  "rigid_body_mass", "participation"))):
                raise InputError(f"{who}: its {key} differs from problem 0's; a batch shares both bodies")
        for f in ("t0", "t_end", "h", "mode_samples", "static_above_hz", "max_iter"):
            if not _same(getattr(p, f), getattr(p0, f)):
                raise InputError(f"{who}: {f} = {getattr(p, f)!r}, problem 0 has {getattr(p0, f)!r}; a batch "
                                 "marches one step")
        for f in ("names", "Phi_a", "Phi_b", "compliance", "offset", "contact", "axial", "sign"):
            if not _same(getattr(rows, f), getattr(r0, f)):
                raise InputError(f"{who}: its contacts differ from problem 0's ({f}); a batch shares the contact rows "
                                 "(only the release times may differ)")
        if p.outputs != p0.outputs:
            raise InputError(f"{who}: its outputs differ from problem 0's")
        if len(p.recoveries) != len(p0.recoveries) or any(
                ra is not rb and not (ra.name == rb.name and ra.body == rb.body and ra.labels == rb.labels
                                      and all(_same(getattr(ra, f), getattr(rb, f)) for f in ("disp", "vel", "acc",
                                                                                           "const")))
                for ra, rb in zip(p.recoveries, p0.recoveries)):
            raise InputError(f"{who}: its recoveries differ from problem 0's")


@dataclass
class _Case:
    """One case's own set-up: its kernel modal bundle, start state and histories (views of
    its group's)."""

    problem: TransientProblem
    rows: object
    modal: object
    state: object
    hist: History
    guard: GrowthGuard


def _output_matrices(plan, coef, w2, zw2, Phi_body, B_body, Ub_body, nc) -> tuple[np.ndarray, ...]:
    """(Aq, Av, Ax) of one body: its output targets from X_q, X_v and from [f; g(tb); z]
    (module docstring); ``coef`` (8, n_body), ``Phi_body`` (n_c, n_body): the body's part of
    [Phi_a, -Phi_b]; ``B_body`` (n_b, n_body), ``Ub_body`` (n_body, r_u) its part of the bases."""
    nbody = coef.shape[1]
    nb, ru = B_body.shape[0], Ub_body.shape[1]
    Aq, Av = np.zeros((plan.ntarg, nbody)), np.zeros((plan.ntarg, nbody))
    Ax = np.zeros((plan.ntarg, nc + nb + ru))
    Bc, Bcd = coef[3], coef[7]
    for L, kind, t in zip(plan.L, plan.kind, plan.targ):
        if kind == 0:           # q = X_q + Bc Phi^T f
            Aq[t] += L
            Ax[t, :nc] += Phi_body @ (L * Bc)
        elif kind == 1:         # v = X_v + Bcd Phi^T f
            Av[t] += L
            Ax[t, :nc] += Phi_body @ (L * Bcd)
        else:                   # acc = P1 + Phi^T f - zw2 v - w2 q, P1 = B^T g(tb) + Ub z
            Lw, Lz = L * w2, L * zw2
            Aq[t] -= Lw
            Av[t] -= Lz
            Ax[t, :nc] += Phi_body @ (L - Lw * Bc - Lz * Bcd)
            Ax[t, nc:nc + nb] += B_body @ L
            Ax[t, nc + nb:] += L @ Ub_body
    return Aq, Av, Ax


def _case(k: int, p: TransientProblem, rows_p, step, coefs, plans, contact, hist: History) -> _Case:
    """Case k's start (static solve, initial contact force, row 0 of its histories ``hist``,
    views of its group's), kernel modal bundle and growth guard."""
    pa, pb = p.body_a, p.body_b
    try:
        init = initial_state(p)
        f0, active0 = initial_contact_force(pa, pb, rows_p, p.forcing, init, p.t0)
    except (InputError, ConvergenceError) as exc:
        raise type(exc)(f"batch problem {k}: {exc}") from None
    loads = (modal_load(pa, "a", p.forcing), modal_load(pb, "b", p.forcing))
    state = _start(p, rows_p, contact, init, f0, active0, loads, plans, hist)
    modal = _modal_inputs(p, coefs, loads)
    guard = GrowthGuard(rows_p, modal, state, step.h, step.margin)
    guard.start(step.t0, step.t_end)
    return _Case(p, rows_p, modal, state, hist, guard)


def _group_history(K: int, n_t: int, plans, rows) -> GroupHistory:
    return GroupHistory(np.zeros((K, n_t, plans[0].ntarg)), np.zeros((K, n_t, plans[1].ntarg)),
                        np.zeros((K, n_t, rows.n)), np.zeros((K, n_t, len(rows.names)), dtype=np.int8),
                        np.zeros((K, n_t), dtype=np.int32))


def _case_history(hist: GroupHistory, k: int, na: int, nb: int) -> History:
    """Case k's History: views of its group's arrays (no modal histories, no output block)."""
    e = np.zeros((0, 0))
    return History(hist.Y_a[k], hist.Y_b[k], hist.Fc[k], hist.state[k], hist.iters[k], False, e, e, e, e, e, e,
                   np.zeros((3, 0, na)), np.zeros((3, 0, nb)), np.zeros(1, dtype=np.int64))


def _shared(cases: list[_Case], plans, contact) -> tuple[Shared, np.ndarray, np.ndarray, np.ndarray]:
    """A group's Shared bundle and its bases: (shared, B (n_b, n) loads, Vb (r_v, 2n)
    feedback rows, Ub (n, r_u) feedback columns)."""
    m0 = cases[0].modal
    na, n = m0.na, m0.w2.size
    coef = m0.coef
    F, G, Ac, Bc, Fd, Gd, Acd, Bcd = coef
    B = _basis([np.vstack([c.modal.const[None, :], c.modal.Pk]) for c in cases], "applied loads")
    Vb = _basis([c.modal.V for c in cases], "feedback rows")
    Ub = _basis([c.modal.U.T for c in cases], "feedback columns").T
    Phi = contact.Phi
    Mq = np.hstack([(Ac[:, None] * B.T), (Bc[:, None] * B.T), ((Ac + Bc)[:, None] * Ub)])
    Mv = np.hstack([(Acd[:, None] * B.T), (Bcd[:, None] * B.T), ((Acd + Bcd)[:, None] * Ub)])
    S = np.vstack([F, G, F * Bc + G * Bcd + Ac, Fd, Gd, Fd * Bc + Gd * Bcd + Acd])
    Vq, Vv = Vb[:, :n], Vb[:, n:]
    Vf = (Vq * Bc + Vv * Bcd) @ Phi.T
    nc = Phi.shape[0]
    C = np.ascontiguousarray
    R, iR, Ax = [], [], []
    for plan, sl, t0 in ((plans[0], slice(0, na), 0),                       # Phi's b part is -Phi_b: as the
                         (plans[1], slice(na, n), plans[0].ntarg)):         # force acts
        Aq, Av, ax = _output_matrices(plan, coef[:, sl], m0.w2[sl], m0.zw2[sl], Phi[:, sl], B[:, sl], Ub[sl], nc)
        for A in (Aq, Av):
            rows = np.flatnonzero(np.any(A != 0, axis=1))
            R.append(C(A[rows].T))
            iR.append((rows + t0).astype(np.int64))
        Ax.append(ax)
    sh = Shared(C(S.T), C(Mq), C(Mv), C(Phi.T), C(Vq), C(Vv), C(Vf), C(contact.W), C(contact.C2),
                C(contact.offset), C(contact.contact), C(contact.axial), C(contact.sign), int(na), tuple(R), tuple(iR),
                C(np.vstack(Ax)), int(plans[0].ntarg))
    return sh, B, Vb, Ub


def _group_inputs(group: list[_Case], B, Vb, Ub, sh: Shared) -> tuple[Cases, GroupState]:
    """The group's per-case bundle and its state at t0 (each case's own start state, _start)."""
    K = len(group)
    n = B.shape[1]
    nb, rv, ru = B.shape[0], Vb.shape[0], Ub.shape[1]
    nk = max(c.modal.tk.size for c in group)
    r = max(c.modal.V.shape[0] for c in group)
    cc, gk = np.zeros((K, nb)), np.zeros((K, nk, nb))
    tk, n_tk = np.full((K, nk), np.inf), np.zeros(K, dtype=np.int64)
    Cv, Du = np.zeros((K, r, rv)), np.zeros((K, ru, r))
    since, until = np.zeros((K, r)), np.zeros((K, r))       # since = until: a padded term, never on
    release = np.zeros((K, group[0].rows.release.size))
    Xq, Xv, Pc = np.zeros((n, K)), np.zeros((n, K)), np.zeros((n, K))
    F = np.zeros((sh.PhiT.shape[1], K))
    active = np.zeros((K, sh.PhiT.shape[1]), dtype=np.bool_)
    g = np.zeros((K, nb))
    Bc, Bcd = group[0].modal.coef[3], group[0].modal.coef[7]
    for k, case in enumerate(group):
        md, stt = case.modal, case.state
        cc[k] = B @ md.const
        if md.tk.size:
            tk[k, :md.tk.size], n_tk[k] = md.tk, md.tk.size
            gk[k, :md.tk.size] = md.Pk @ B.T
        rk = md.V.shape[0]
        if rk:
            Cv[k, :rk] = md.V @ Vb.T
            Du[k, :, :rk] = Ub.T @ md.U
            since[k, :rk], until[k, :rk] = md.since, md.until
        release[k] = case.rows.release
        Pc[:, k] = stt.Pc
        Xq[:, k] = stt.q - Bc * stt.Pc          # q = X_q + Bc Pc (module docstring)
        Xv[:, k] = stt.v - Bcd * stt.Pc
        F[:, k] = stt.f
        active[k] = stt.active
        g[k] = B @ stt.Pext
    cs = Cases(cc, tk, n_tk, gk, Cv, Du, since, until, release)
    st = GroupState(Xq, Xv, Pc, F, active, g, np.zeros(K, dtype=np.int64), np.zeros(K, dtype=np.int64))
    return cs, st


def solve_batch(problems: Sequence[TransientProblem], group: int = GROUP) -> list[TransientResult]:
    """Solve problems that share both bodies, their contact rows, step and outputs (module
    docstring) by marching them together, ``group`` cases at a time; the results in order,
    each as :func:`transient.solve` gives it (to round-off). One BLAS thread."""
    return list(solve_batch_iter(problems, group))


def solve_batch_iter(problems: Sequence[TransientProblem], group: int = GROUP) -> Iterator[TransientResult]:
    """:func:`solve_batch`, its results made one at a time as they are taken: every case is
    marched before this returns (a failure is raised here, as solve_batch raises it), and
    each result (its histories split per body and item: copies) is made when asked for, so
    that a caller who lets each go before taking the next holds one result beside the
    marched histories instead of all of them (a campaign worker: workflows/campaign.py)."""
    from threadpoolctl import threadpool_limits

    problems = list(problems)
    if not problems:
        return iter(())
    if int(group) < 1:
        raise InputError(f"batch: group = {group!r} must be at least 1")
    with threadpool_limits(limits=1, user_api="blas"):
        return _solve_batch(problems, int(group))


def _check_schedules(problems: list[TransientProblem], rows_k: list, step) -> None:
    """A given step above 0.25/f_h is checked through the contact-coupled step map in the
    active sets of each case's release schedule (stepping.check_step_map), not problem 0's
    alone: release times may differ between the cases, and with them the sets a run passes
    through and its steps in each. Once per distinct schedule; InputError naming the case."""
    from .stepping import _modes, above_eq12, check_step_map

    if step.h_requested is None or not above_eq12(step.h, step.h_default, rows_k[0]):
        return

    seen = {tuple(float(c.release_time) for c in problems[0].contacts)}
    for k, (p, rows) in enumerate(zip(problems, rows_k)):
        key = tuple(float(c.release_time) for c in p.contacts)
        if key in seen:
            continue
        seen.add(key)
        omega, zeta, static = _modes(p)
        try:
            check_step_map(p, rows, omega, zeta, step.h, static, step.f_h, step.h_default)
        except InputError as exc:
            raise InputError(f"batch problem {k}: {exc}") from None


def _solve_batch(problems: list[TransientProblem], group: int) -> Iterator[TransientResult]:
    started = _time.perf_counter()
    p0 = problems[0]
    pa, pb = p0.body_a, p0.body_b
    rows_k = [contact_rows(pa, pb, p.contacts) for p in problems]
    _check_shared(problems, rows_k)
    rows = rows_k[0]
    step = choose_step(p0, rows)
    _check_schedules(problems, rows_k, step)
    check_memory(p0, step.n_steps, len(problems), f" for {len(problems)} cases marched together")
    coefs = (step_coefficients(pa.omega, pa.zeta, step.h, p0.static_modes("a")),
             step_coefficients(pb.omega, pb.zeta, step.h, p0.static_modes("b")))
    plans = (output_plan(p0, "a"), output_plan(p0, "b"))
    contact, W = _contact_inputs(rows, coefs)
    cache = _new_cache(contact.W.shape[0], cap=256)
    bar = None
    if any(p.progress for p in problems) and step.n_steps > 4 * CHUNK:
        from tqdm import tqdm

        bar = tqdm(total=step.n_steps * len(problems), unit="case-step", desc=f"transient, {len(problems)} cases",
                   leave=False)
    cases = []
    try:
        for g0 in range(0, len(problems), group):
            ks = range(g0, min(g0 + group, len(problems)))
            hist = _group_history(len(ks), step.n_steps + 1, plans, rows)
            members = [_case(k, problems[k], rows_k[k], step, coefs, plans, contact,
                             _case_history(hist, k - g0, pa.n_modes, pb.n_modes)) for k in ks]
            sh, B, Vb, Ub = _shared(members, plans, contact)
            cs, st = _group_inputs(members, B, Vb, Ub, sh)
            _march(members, g0, step, sh, cs, st, cache, hist, W, bar)
            cases += members
            del hist, members, sh, cs, st
    finally:
        if bar is not None:
            bar.close()
    return _results(cases, step, plans, int(cache.used[0]), started)


def _results(cases: list[_Case], step, plans, n_patterns: int, started: float) -> Iterator[TransientResult]:
    """Each marched case's TransientResult in turn; a case is let go once its result is
    made, so a group's output histories are freed with its last case's (the contact
    forces, states and iterations stay views of the group's: small). A result's wall time
    leaves out the time the caller spent between results, as if they were made at once."""
    away = 0.0
    while cases:
        c = cases.pop(0)
        res = _result(c.problem, c.rows, step, plans, c.hist, n_patterns, started + away, c.state)
        del c
        t = _time.perf_counter()
        yield res
        away += _time.perf_counter() - t
        del res


def _march(members: list[_Case], g0: int, step, sh: Shared, cs: Cases, st: GroupState, cache, hist: GroupHistory,
           W, bar) -> None:
    """Every step of one group in compiled chunks; each case's finiteness and growth guard
    checked after each chunk (solver._drive's checks)."""
    Bc, Bcd = members[0].modal.coef[3], members[0].modal.coef[7]
    i = 0
    while i < step.n_steps:
        i1 = min(i + CHUNK, step.n_steps)
        status, at, info1, info2, k = march_group(i, i1, float(step.t0), float(step.h), int(members[0].problem.max_iter),
                                                  sh, cs, st, cache.keys, cache.invs, cache.used, hist)
        if status != OK:
            try:
                _failure(status, step.t0 + at * step.h, info1, info2,
                         lambda: _spectral_radius(W, members[k].rows, st.active[k]))
            except (InputError, ConvergenceError) as exc:
                raise type(exc)(f"batch problem {g0 + k}: {exc}") from None
        times = step.t0 + step.h * np.arange(i + 1, i1 + 1)
        for k, c in enumerate(members):
            q = st.Xq[:, k] + Bc * st.Pc[:, k]
            v = st.Xv[:, k] + Bcd * st.Pc[:, k]
            if not (np.all(np.isfinite(q)) and np.all(np.isfinite(v))):
                raise ConvergenceError(f"batch problem {g0 + k}: the solution diverged (non-finite values) by "
                                       f"t = {step.t0 + step.h * i1:.6g} s with h = {step.h:.4g} s; reduce h")
            view = c.state._replace(q=q, v=v, active=st.active[k], f=np.ascontiguousarray(st.F[:, k]))
            try:
                c.guard.check(step.t0 + step.h * i1, view, hist.Fc[k, i + 1:i1 + 1], times)
            except ConvergenceError as exc:
                raise ConvergenceError(f"batch problem {g0 + k}: {exc}") from None
        if bar is not None:
            bar.update((i1 - i) * len(members))
        i = i1
