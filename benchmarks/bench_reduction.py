"""Craig-Bampton reduction time: the sparse factorisation of K_ii, the constraint-mode
solves and the fixed-interface eigensolve separately, against the fixed-interface
eigensolve alone (scipy eigsh shift-invert at sigma = 0 with its own factorisation, as
one would do without sharing). Goal: constraint modes nearly free, because the factor
is shared.

Components: the default core stage built through meshes/ + fem/ (when gmsh and dolfinx
are available; boundary = its 8 spider reference points) and a synthetic solid, an
aluminium hex8 block with two rigid spiders (~41k DOFs); or one saved liftoff component
(``--component path.npz``, boundary = all its labelled DOFs). Wall times in one process,
best of ``--repeat``.

    .venv/bin/python benchmarks/bench_reduction.py [--cells 8 8 160] [--modes 40] [--no-fe]
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import liftoff  # noqa: F401 - before numpy: it picks the OpenBLAS kernels (liftoff/core/openblas.py)
import numpy as np
import scipy.sparse.linalg as spla

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from liftoff.reduction import craig_bampton, load_component  # noqa: E402
from liftoff.reduction.craig_bampton import ORDERING  # noqa: E402
from liftoff.reduction.models import hex_block, six_labels, spider_component  # noqa: E402


def synthetic(cells):
    nx, ny, nz = cells
    size = (0.4, 0.4, 0.4 * nz / nx)          # cubic cells
    K, M, nodes = hex_block(cells, size)
    z0, z1 = np.isclose(nodes[:, 2], 0.0), np.isclose(nodes[:, 2], size[2])
    c = (size[0] / 2, size[1] / 2)
    comp = spider_component("block", K, M, nodes, {"bottom": (np.flatnonzero(z0), (*c, 0.0)),
                                                   "top": (np.flatnonzero(z1), (*c, size[2]))})
    return comp, six_labels("bottom") + six_labels("top")


def fe_core():
    import os

    os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")
    import pyvista  # noqa: F401  (before dolfinx)

    from liftoff import fem
    from liftoff.meshes.vehicle import build_core_stage
    from liftoff.reduction import Component

    g = build_core_stage("out/bench_meshes")
    m = fem.build_model(g, degree=1)
    comp = Component(name="core", **m.component_fields())
    return comp, [lab for lab in comp.dof_labels]


def eigsh_alone(comp, boundary, n_modes):
    """Fixed-interface eigensolve alone: factor K_ii and run eigsh (what CB does anyway)."""
    b = comp.dofs_of(boundary)
    i = np.setdiff1d(np.arange(comp.n_dof), b)
    K, M = comp.K.tocsc(), comp.M.tocsc()
    Kii, Mii = K[i][:, i].tocsc(), M[i][:, i].tocsc()
    t0 = time.perf_counter()
    lu = spla.splu(Kii, permc_spec=ORDERING, diag_pivot_thresh=0.0, options={"SymmetricMode": True})
    op = spla.LinearOperator(Kii.shape, matvec=lu.solve, dtype=float)
    lam = spla.eigsh(Kii, k=n_modes, M=Mii, sigma=0.0, which="LM", OPinv=op, return_eigenvectors=True)[0]
    return time.perf_counter() - t0, np.sort(lam)


def bench(comp, boundary, n_modes, repeat, source):
    print(f"component: {source}: {comp.n_dof} DOFs, {len(boundary)} boundary DOFs, "
          f"nnz(K) {comp.K.nnz}, {n_modes} fixed-interface modes")
    best = {}
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        cb = craig_bampton(comp, boundary, n_modes=n_modes)
        total, total_cpu = time.perf_counter() - t0, time.process_time() - c0
        c0 = time.process_time()
        t_alone, lam = eigsh_alone(comp, boundary, n_modes)
        alone_cpu = time.process_time() - c0
        assert np.allclose(lam, cb.fixed_omega**2, rtol=1e-8), "eigsh alone and CB disagree"
        row = dict(cb.timings, total_s=total, eigsh_alone_s=t_alone, total_cpu_s=total_cpu,
                   eigsh_alone_cpu_s=alone_cpu)
        best = {k: min(v, best.get(k, np.inf)) for k, v in row.items()}
    f = best
    print(f"  partition K, M (b / i)      {f['partition_s']:8.3f} s")
    print(f"  factorisation of K_ii       {f['factor_s']:8.3f} s")
    print(f"  constraint modes (solves)   {f['constraint_solve_s']:8.3f} s   ({len(boundary)} right-hand sides)")
    print(f"  fixed-interface eigensolve  {f['eigensolve_s']:8.3f} s   (eigsh with the shared factor)")
    print(f"  CB matrices                 {f['matrices_s']:8.3f} s")
    print(f"  craig_bampton total         {f['total_s']:8.3f} s")
    print(f"  eigensolve alone            {f['eigsh_alone_s']:8.3f} s   (own factorisation + eigsh)")
    print(f"  ratio CB total / eigensolve alone      {f['total_s'] / f['eigsh_alone_s']:.2f} wall, "
          f"{f['total_cpu_s'] / f['eigsh_alone_cpu_s']:.2f} CPU time ({f['total_cpu_s']:.1f} / "
          f"{f['eigsh_alone_cpu_s']:.1f} s)")
    print(f"  constraint modes / eigensolve alone    {f['constraint_solve_s'] / f['eigsh_alone_s']:.3f}")
    print(f"  first fixed-interface frequencies (Hz): {np.round(cb.fixed_freq_hz[:4], 2).tolist()}", flush=True)
    return best


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cells", type=int, nargs=3, default=(8, 8, 160))
    ap.add_argument("--modes", type=int, default=40)
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--component", type=Path, default=None, help="a saved liftoff component (.npz)")
    ap.add_argument("--no-fe", action="store_true", help="skip the meshes/ + fem/ core stage")
    args = ap.parse_args(argv)
    if args.component is not None:
        comp = load_component(args.component)
        bench(comp, list(comp.dof_labels), args.modes, args.repeat, f"component file {args.component}")
        return
    if not args.no_fe:
        try:
            comp, boundary = fe_core()
        except ImportError as exc:
            print(f"core stage through meshes/ + fem/ skipped: {exc}")
        else:
            bench(comp, boundary, args.modes, args.repeat, "core stage, meshes/ + fem/ (P1)")
    comp, boundary = synthetic(args.cells)
    bench(comp, boundary, args.modes, args.repeat, f"synthetic hex8 block {tuple(args.cells)}, 2 spiders")


if __name__ == "__main__":
    main()
