"""Set-up cost of the transient at 3,000 modes: static start (section 2.6) and step estimate
(eq. 12) against a 20,000-step solve of the same problem (issue 14: <= 10 %).

Problem: the lift-off-sized two bodies of bench_transient.py with a 3,000-mode vehicle
(6 rigid) and a 300-mode pad, 8 hold-down posts x 3 penalty directions (one variant with
two rigid bolts, which takes the step estimate's Lanczos path), gravity softening as a
rank-3 factored feedback (eq. 27), gravity and thrust; h = 1e-4 s, 20,000 steps, bolts
released half-way.

Timed, best of --repeat in this process: ``static_equilibrium`` + ``estimate_step`` and the
whole ``solve`` (which runs them again inside, plus the time loop), and, for the record,
the former static solve (a dense SVD of the scaled (n + n_rigid_rows)^2 system as the
singularity test, then a dense solve), re-implemented here.

    .venv/bin/python benchmarks/bench_statics.py [--modes 3000] [--steps 20000] [--repeat 3]
"""
from __future__ import annotations

import argparse
import math
import os
import platform
import time
import warnings
from dataclasses import replace

import liftoff  # noqa: F401 - before numpy: it picks the OpenBLAS kernels (liftoff/core/openblas.py)
import numpy as np

import bench_transient as bt
from liftoff.transient import ContactPoint, Forcing, ModalFeedback, estimate_step, solve, static_equilibrium
from liftoff.transient.assembly import contact_rows, modal_load
from liftoff.transient.effects import softening_factors


def problem(n_modes: int, n_pad: int, n_steps: int, rigid: bool):
    bt.N_VEH, bt.N_PAD = n_modes, n_pad
    p = bt.problem(n_steps)
    U, V = softening_factors(p.body_a, p.forcing.gravity)
    fo = replace(p.forcing, feedback=[ModalFeedback("a", U @ V, until=0.5 * p.t_end, factors=(U, V))])
    contacts = list(p.contacts)
    if rigid:
        for k in (0, 4):
            c = contacts[k]
            contacts[k] = ContactPoint(c.name, c.labels_a, c.labels_b, rigid=True, axial=c.axial,
                                       release_time=c.release_time)
    return replace(p, forcing=fo, contacts=contacts)


def old_static(p) -> float:
    """The former _static_solve's cost: dense K, Jacobi scaling, full SVD, dense solve."""
    a, b, fo = p.body_a, p.body_b, p.forcing
    t0 = time.perf_counter()
    rows = contact_rows(a, b, p.contacts)
    na, nb = a.n_modes, b.n_modes
    n = na + nb
    K = np.zeros((n, n))
    K[:na, :na] = np.diag(a.omega ** 2) - fo.feedback[0].matrix
    K[na:, na:] = np.diag(b.omega ** 2)
    D = np.hstack([rows.Phi_a, -rows.Phi_b])
    pen = rows.compliance > 0
    K += D[pen].T @ ((1 / rows.compliance[pen])[:, None] * D[pen])
    Dr = D[~pen]
    S = np.block([[K, Dr.T], [Dr, np.zeros((Dr.shape[0],) * 2)]])
    d = np.abs(np.diag(S))
    sc = np.where(d > 0, 1 / np.sqrt(np.where(d > 0, d, 1)), 1.0)
    Ss = sc[:, None] * S * sc[None, :]
    np.linalg.svd(Ss, compute_uv=False)
    P = np.concatenate([modal_load(a, "a", fo).at(0.0), modal_load(b, "b", fo).at(0.0), np.zeros(Dr.shape[0])])
    np.linalg.solve(Ss, sc * P)
    return time.perf_counter() - t0


def best(fn, repeat: int) -> float:
    out = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t0)
    return min(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--modes", type=int, default=3000)
    ap.add_argument("--pad-modes", type=int, default=300)
    ap.add_argument("--steps", type=int, default=20000)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--old", action="store_true", help="also time the former dense-SVD static solve")
    args = ap.parse_args()
    from threadpoolctl import threadpool_limits

    warnings.filterwarnings("ignore", "time step h")   # the random 3,000-mode rows give f_h ~ 4 kHz; h fixed

    print(f"bench_statics: {platform.processor() or platform.machine()}, {os.cpu_count()} CPUs, load average "
          f"{' '.join(f'{x:.1f}' for x in os.getloadavg())}; {args.modes} + {args.pad_modes} modes, "
          f"{args.steps} steps, one BLAS thread (as solve runs)")
    solve(problem(60, 20, 200, False))                            # numba compilation
    for rigid in (False, True):
        p = problem(args.modes, args.pad_modes, args.steps, rigid)
        with threadpool_limits(limits=1, user_api="blas"):
            t_est = best(lambda: estimate_step(p.body_a, p.body_b, p.contacts), args.repeat)
            t_st = best(lambda: static_equilibrium(p.body_a, p.body_b, p.contacts, p.forcing, p.t0), args.repeat)
            t_old = best(lambda: old_static(p), 1) if args.old else math.nan
        t_solve = best(lambda: solve(p), max(1, args.repeat - 1))
        what = "2 rigid bolts + 6 penalty posts" if rigid else "8 penalty posts"
        print(f"  {what}: estimate_step {t_est * 1e3:.1f} ms, static_equilibrium {t_st * 1e3:.1f} ms, "
              f"together {(t_est + t_st) * 1e3:.1f} ms = {100 * (t_est + t_st) / t_solve:.2f} % of the "
              f"{args.steps}-step solve ({t_solve:.2f} s)"
              + (f"; former dense-SVD static solve {t_old:.2f} s" if args.old else ""))


if __name__ == "__main__":
    main()
