"""Benchmark: a lift-off-sized two-body contact transient against pyyeti's linear modal solve.

Problem (issue 2): vehicle 200 modes (6 rigid), pad 100 modes (grounded), 8 hold-down
points x 3 directions (24 contact DOF pairs, penalty coupling), h = 1e-4 s, 100,000
steps, static initial conditions, gravity + thrust, bolts released half-way (t = 5 s),
the vehicle lifting off under thrust > weight.

Reference, in the same process: ``pyyeti.ode.SolveUnc(m, b, k, h).tsolve(force)`` on the
same 300 uncoupled modes (unit modal mass, b = 2 zeta omega, k = omega^2) with the same
applied modal forces and no contact: the linear modal integration that every loads
engineer runs, with pyyeti's own exact (matrix-exponential) coefficients.

Timed: liftoff's ``solve(problem)`` (set-up, static solve, time loop, output recovery)
after a short warm-up run that triggers the numba compilation (compile time reported on
its own line), and pyyeti's ``tsolve``; each the best of ``--repeat`` interleaved runs,
wall time and the CPU time of this process (less sensitive to other load on the machine).
``--profile`` adds the per-step cost of the phases (numba code is opaque to cProfile, so
the phases are timed as variants of the problem).

    .venv/bin/python benchmarks/bench_transient.py [--steps 100000] [--repeat 1] [--profile]
"""
from __future__ import annotations

import argparse
import dataclasses
import math
import os
import platform
import time

import liftoff  # noqa: F401 - before numpy: it picks the OpenBLAS kernels (liftoff/core/openblas.py)
import numpy as np

from liftoff.transient import (ContactPoint, Forcing, InitialState, ModalBody, PointForce, TabulatedForce,
                               TransientProblem, solve, static_equilibrium)
from liftoff.transient.stepping import estimate_step

N_VEH, N_RIGID, N_PAD, N_POINTS = 200, 6, 100, 8
H = 1.0e-4
MASS_VEH, MASS_PAD = 5.0e5, 2.0e6          # kg
RADIUS, HEIGHT_CG = 5.0, 20.0              # m: hold-down circle, c.g. above it
K_CONTACT = 5.0e9                          # N/m per direction
THRUST = 1.3 * MASS_VEH * 9.81             # N, total, reached at t = 4 s (T/W = 1.3)


def _points() -> tuple[list[str], np.ndarray]:
    ang = 2 * np.pi * np.arange(N_POINTS) / N_POINTS
    coords = np.c_[RADIUS * np.cos(ang), RADIUS * np.sin(ang), np.zeros(N_POINTS)]
    return [f"hd{i + 1}" for i in range(N_POINTS)], coords


def _labels(points: list[str], extra: tuple[str, ...] = ()) -> tuple[str, ...]:
    return tuple(f"{p}:{c}" for p in points for c in ("Tx", "Ty", "Tz")) + extra


def vehicle(rng: np.random.Generator, n_modes: int = N_VEH) -> ModalBody:
    """Free-free vehicle: 6 exact rigid-body modes about its c.g. plus 194 elastic modes
    (1-150 Hz, 1 % damping) whose rows at the hold-down points are random but mass-normalised
    in scale (|phi| ~ 1/sqrt(modal mass share)); an engine point at the c.g. axis carries thrust."""
    points, coords = _points()
    cg = np.array([0.0, 0.0, HEIGHT_CG])
    inertia = MASS_VEH * np.array([HEIGHT_CG**2 / 3 + RADIUS**2 / 4] * 2 + [RADIUS**2 / 2])
    mrb = np.diag(np.r_[[MASS_VEH] * 3, inertia])               # about the c.g.
    allc = np.vstack([coords, [[0.0, 0.0, 0.0]]])
    labels = _labels(points, ("engine:Tx", "engine:Ty", "engine:Tz"))
    rb = np.zeros((len(labels), 6))
    for i, r in enumerate(np.repeat(allc - cg, 3, axis=0)):
        comp = i % 3
        rb[i, comp] = 1.0
        skew = np.array([[0, -r[2], r[1]], [r[2], 0, -r[0]], [-r[1], r[0], 0]])
        rb[i, 3:] = -skew[comp]
    phi = np.zeros((len(labels), n_modes))
    phi[:, :N_RIGID] = rb @ np.diag(1 / np.sqrt(np.diag(mrb)))
    phi[:, N_RIGID:] = rng.standard_normal((len(labels), n_modes - N_RIGID)) / math.sqrt(MASS_VEH / 20)
    omega = np.r_[np.zeros(N_RIGID), 2 * np.pi * np.geomspace(1.0, 150.0, n_modes - N_RIGID)]
    part = np.zeros((n_modes, 6))
    part[:N_RIGID] = np.diag(np.sqrt(np.diag(mrb)))             # Phi^T M RB for the rigid modes
    return ModalBody("vehicle", omega=omega, zeta=np.r_[np.zeros(N_RIGID), np.full(n_modes - N_RIGID, 0.01)],
                     dof_labels=labels, phi=phi, participation=part, ref_point=cg,
                     points=tuple(points) + ("engine",), point_coords=allc, rigid_body_mass=mrb)


def pad(rng: np.random.Generator, n_modes: int = N_PAD) -> ModalBody:
    """Grounded pad: 100 elastic modes (5-400 Hz, 2 % damping), random rows of mass-normalised scale."""
    points, coords = _points()
    labels = _labels(points)
    omega = 2 * np.pi * np.geomspace(5.0, 400.0, n_modes)
    phi = rng.standard_normal((len(labels), n_modes)) / math.sqrt(MASS_PAD / 10)
    part = np.zeros((n_modes, 6))
    part[:, 2] = phi[2::3].mean(axis=0) * MASS_PAD / 10       # some vertical participation
    return ModalBody("pad", omega=omega, zeta=0.02, dof_labels=labels, phi=phi, participation=part,
                     points=tuple(points), point_coords=coords)


def host_cpu() -> dict:
    """The CPU the kernels were compiled for (numba's target, LLVM's name for it) and the width
    of its widest double-precision vectors: a group of 8 cases fills one 512-bit register, two
    256-bit ones, which the speed of the batch and of the kernel depend on (bench_batch.py, bench_kernel_floor.py)."""
    import llvmlite.binding as ll

    ll.initialize(); ll.initialize_native_target()
    features = ll.get_host_cpu_features()
    bits = 512 if features.get("avx512f") else 256 if features.get("avx") else 128
    return {"cpu": ll.get_host_cpu_name(), "vector_bits": bits}


def problem(n_steps: int, progress: bool = False, n_veh: int = N_VEH, n_pad: int = N_PAD,
            release: float | None = 0.5) -> TransientProblem:
    """The benchmark's problem; ``n_veh``, ``n_pad`` modes; the bolts released at ``release``
    of the run (None: bolted throughout)."""
    rng = np.random.default_rng(20260521)
    veh, pd = vehicle(rng, n_veh), pad(rng, n_pad)
    points, _ = _points()
    contacts = [ContactPoint(p, [f"{p}:Tx", f"{p}:Ty", f"{p}:Tz"], [f"{p}:Tx", f"{p}:Ty", f"{p}:Tz"],
                             K_CONTACT, axial=2) for p in points]
    # H, or eq. 12's step where that is shorter (3,000 vehicle modes: 5.9e-5 s; a given step above
    # it is refused where its step map is too large to check, transient/stepping.py)
    h = min(H, estimate_step(veh, pd, contacts)[1])
    t_end = n_steps * h
    release_time = math.inf if release is None else release * t_end
    contacts = [dataclasses.replace(c, release_time=release_time) for c in contacts]
    ramp = np.array([0.0, 0.4 * t_end, t_end])
    forcing = Forcing(constant=[PointForce("a", "engine:Tx", 1.0e4)],
                      tables=[TabulatedForce("a", "engine:Tz", ramp, np.array([0.0, THRUST, THRUST]))],
                      gravity=(0.0, 0.0, -9.81))
    return TransientProblem(veh, pd, contacts, forcing, t_end, h=h, initial="static",
                            outputs={"a": ["engine:Tz", "hd1:Tz"], "b": ["hd1:Tz"]}, progress=progress)


def modal_forces(prob: TransientProblem, n_steps: int) -> tuple[np.ndarray, ...]:
    """Uncoupled (m, b, k) and the applied modal force history (300, n_steps + 1) for pyyeti."""
    t = np.arange(n_steps + 1) * prob.h
    bodies = (prob.body_a, prob.body_b)
    blocks = []
    for key, body in zip("ab", bodies):
        f = np.zeros((body.n_modes, t.size))
        f += body.modal_gravity(prob.forcing.gravity)[:, None]
        for pf in prob.forcing.constant:
            if pf.body == key:
                f += body.rows([pf.label])[0][:, None] * pf.value
        for tf in prob.forcing.tables:
            if tf.body == key:
                f += np.outer(body.rows([tf.label])[0], np.interp(t, tf.time, tf.value))
        blocks.append(f)
    omega = np.r_[bodies[0].omega, bodies[1].omega]
    zeta = np.r_[bodies[0].zeta, bodies[1].zeta]
    return np.ones(omega.size), 2 * zeta * omega, omega**2, np.vstack(blocks)


def timed(fn) -> tuple[float, float, object]:
    """(wall s, CPU s of this process, result) of one call."""
    w0, c0 = time.perf_counter(), time.process_time()
    out = fn()
    return time.perf_counter() - w0, time.process_time() - c0, out


def breakdown(n_steps: int, repeat: int) -> None:
    """Where the time goes: per-step cost of the phases of the liftoff run (best of ``repeat``)."""
    variants = {}
    p = problem(n_steps)
    variants["as benchmarked (bolted half, free half)"] = p
    p = problem(n_steps)
    for c in p.contacts:
        c.release_time = math.inf
    variants["bolted throughout (24 coupled rows)"] = p
    p = problem(n_steps)
    for c in p.contacts:
        c.release_time = -math.inf
    p.initial = "zero"
    variants["released from t0 (free flight, 8 open rows)"] = p
    p = problem(n_steps)
    p.outputs = {"a": [], "b": []}
    variants["as benchmarked, no labelled outputs"] = p
    best = {k: math.inf for k in variants}
    for _ in range(repeat):
        for k, p in variants.items():
            best[k] = min(best[k], timed(lambda: solve(p))[1])
    print(f"  breakdown ({n_steps} steps, CPU time per step):")
    for k, v in best.items():
        print(f"    {k:<46}{1e6 * v / n_steps:>8.1f} us")


def resting(n_steps: int, mu: float, lateral: float) -> TransientProblem:
    """The benchmark's bodies with the vehicle released at t0 and resting on its 8 points (static
    state of the bolted stack), no thrust, a lateral force ``lateral`` (N) at the engine and
    Coulomb friction ``mu`` on the posts (0: the reference's contact law)."""
    p = problem(n_steps)
    init = static_equilibrium(p.body_a, p.body_b, p.contacts, p.forcing)
    p.initial = InitialState(init.q_a, init.v_a, init.q_b, init.v_b)
    for c in p.contacts:
        c.release_time = -math.inf
        c.friction = mu
    p.forcing = Forcing(constant=[PointForce("a", "engine:Tx", lateral)], gravity=(0.0, 0.0, -9.81))
    return p


def friction_breakdown(n_steps: int, repeat: int) -> None:
    """Per-step cost of friction contacts (transient/contact_laws.py) against the reference's
    contact law on the same bodies: all 8 points closed, sticking or slipping."""
    weight = MASS_VEH * 9.81
    bolted = problem(n_steps)
    for c in bolted.contacts:
        c.release_time = math.inf
    lifting = problem(n_steps)
    for c in lifting.contacts:
        c.friction = 0.3
    variants = {"bolted throughout (reference path, 24 rows)": (bolted, 0.0),
                "resting, frictionless (reference path, 8 rows)": (resting(n_steps, 0.0, 1.0e4), 0.0),
                "resting, mu = 0.5, sticking (24 rows)": (resting(n_steps, 0.5, 1.0e4), 0.5),
                "resting, mu = 0.01, slipping (8 + 16 slip rows)": (resting(n_steps, 0.01, 0.05 * weight), 0.01),
                "as benchmarked, mu = 0.3 (bolted, then lift-off)": (lifting, 0.3)}
    best, res = {k: math.inf for k in variants}, {}
    for _ in range(repeat):
        for k, (pr, _mu) in variants.items():
            w, c, res[k] = timed(lambda: solve(pr))
            best[k] = min(best[k], c)
    print(f"  friction ({n_steps} steps, CPU time per step, set-up included):")
    for k, v in best.items():
        mu, F = variants[k][1], res[k].contact_force.reshape(res[k].time.size, N_POINTS, 3)
        N = F[:, :, 2]
        slipping = (mu > 0) & (N > 0) & (np.hypot(F[:, :, 0], F[:, :, 1]) >= mu * N * (1 - 1e-6))
        print(f"    {k:<50}{1e6 * v / n_steps:>8.1f} us   solves/step {res[k].iterations[1:].mean():.2f}   "
              f"slipping point-steps {slipping.mean():.0%}")


def products(nc: int = 3 * N_POINTS, n: int = N_VEH + N_PAD, steps: int = 20_000) -> None:
    """The two contact products of a coupled step, u = Phi_c q and P = Phi_c^T f (nc x n), timed
    as scalar numba loops (the kernel's style) and as BLAS calls inside numba."""
    from numba import njit

    @njit(cache=False)
    def loops(Phi, q, f, N):
        nc, n = Phi.shape
        u, P, acc = np.empty(nc), np.empty(n), 0.0
        for _ in range(N):
            for j in range(nc):
                s = 0.0
                for m in range(n):
                    s += Phi[j, m] * q[m]
                u[j] = s
            P[:] = 0.0
            for j in range(nc):
                for m in range(n):
                    P[m] += Phi[j, m] * f[j]
            acc += u[0] + P[0]
        return acc

    @njit(cache=False)
    def blas(Phi, q, f, N):
        acc = 0.0
        for _ in range(N):
            u = Phi @ q
            P = f @ Phi
            acc += u[0] + P[0]
        return acc

    rng = np.random.default_rng(1)
    Phi, q, f = rng.standard_normal((nc, n)), rng.standard_normal(n), rng.standard_normal(nc)
    print(f"  contact products u = Phi_c q, P = Phi_c^T f ({nc} x {n}), CPU time per step:")
    for name, fn in (("scalar numba loops", loops), ("BLAS (Phi @ q, f @ Phi) in numba", blas)):
        fn(Phi, q, f, 10)
        best = min(timed(lambda: fn(Phi, q, f, steps))[1] for _ in range(3))
        print(f"    {name:<46}{1e6 * best / steps:>8.1f} us")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--steps", type=int, default=100_000)
    ap.add_argument("--repeat", type=int, default=3, help="runs of each (interleaved); best is reported")
    ap.add_argument("--profile", action="store_true", help="also time the phases of the liftoff run")
    ap.add_argument("--friction", action="store_true",
                    help="also time friction contacts against the reference's contact law (per step)")
    args = ap.parse_args()
    from pyyeti import ode

    compile_s = timed(lambda: solve(problem(200)))[0]            # numba compilation (or cache load)

    prob = problem(args.steps)
    m, b, k, force = modal_forces(prob, args.steps)
    lift, yeti, res = [math.inf, math.inf], [math.inf, math.inf], None
    for _ in range(args.repeat):  # interleaved, so that a busy machine affects both alike
        w, c, res = timed(lambda: solve(prob))
        lift = [min(lift[0], w), min(lift[1], c)]
        w, c, _ = timed(lambda: ode.SolveUnc(m, b, k, prob.h).tsolve(force))
        yeti = [min(yeti[0], w), min(yeti[1], c)]

    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(f"bench_transient: {platform.machine()}, {os.cpu_count()} cores, load average {load:.1f}, "
          f"numpy {np.__version__}, best of {args.repeat}")
    print(f"  problem: vehicle {N_VEH} modes ({N_RIGID} rigid), pad {N_PAD} modes, {N_POINTS} points x 3 "
          f"directions, h = {prob.h:g} s, {args.steps} steps, release at t = {0.5 * args.steps * prob.h:g} s")
    print(f"  {'run':<48}{'wall (s)':>10}{'CPU (s)':>10}")
    print(f"  {'liftoff first call (numba compile/cache, 200 steps)':<48}{compile_s:>10.2f}")
    print(f"  {'liftoff solve, contact transient':<48}{lift[0]:>10.2f}{lift[1]:>10.2f}")
    print(f"  {'pyyeti SolveUnc.tsolve, 300 modes, no contact':<48}{yeti[0]:>10.2f}{yeti[1]:>10.2f}")
    rw, rc = lift[0] / yeti[0], lift[1] / yeti[1]
    verdict = lambda r: "met" if r <= 0.5 else "NOT met"  # noqa: E731
    print(f"  {'ratio liftoff / pyyeti (target <= 0.5)':<48}{rw:>10.3f}{rc:>10.3f}  "
          f"target {verdict(rw)} (wall), {verdict(rc)} (CPU)")
    seps = [c["separation_time"] for c in res.contact_summary() if c["separation_time"] is not None]
    if seps:
        print(f"  separation: {len(seps)}/{N_POINTS} points, first at {min(seps):.4f} s, last at {max(seps):.4f} s")
    if args.profile:
        breakdown(min(args.steps, 20_000), args.repeat)
        products()
    if args.friction:
        friction_breakdown(min(args.steps, 20_000), args.repeat)


if __name__ == "__main__":
    main()
