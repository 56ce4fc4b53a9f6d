"""Run by test_petsc_cb.py under `mpirun -n N`: the PETSc/SLEPc Craig-Bampton solver
against the scipy one on the same FE component (a box with spiders on both ends, built
over the N processes and gathered); rank 0 prints one JSON line."""
import json
import sys

import numpy as np
from mpi4py import MPI

from liftoff.fem import build_model, petsc_cb, petsc_solver
from liftoff.meshes.spec import Geometry, Material, Patch
from liftoff.reduction import Component, craig_bampton
from liftoff.reduction.models import six_labels

path, L, W, H = sys.argv[1], *map(float, sys.argv[2:5])
steel = Material("steel", 2.0e11, 0.3, 7800.0)
model = build_model(Geometry("box", path, {"solid": steel},
                             patches=[Patch("x0", (0.0, W / 2, H / 2)), Patch("x1", (L, W / 2, H / 2))]), 1)
comp = Component(name="box", **model.component_fields())
bl = six_labels("x0") + six_labels("x1")
out = {"size": MPI.COMM_WORLD.size, "n_dof": comp.n_dof}
SHIFT_MIN_MODES = petsc_cb.SHIFT_MIN_MODES
for key, kw in (("count", dict(n_modes=10)), ("band", dict(f_max=float(sys.argv[5]))),
                ("band_shifted", dict(f_max=float(sys.argv[5])))):
    # band_shifted: the band shift-inverted at its middle, as bands of SHIFT_MIN_MODES or more are
    petsc_cb.SHIFT_MIN_MODES = 1 if key == "band_shifted" else SHIFT_MIN_MODES
    ref = craig_bampton(comp, bl, **kw)                          # scipy, on every rank
    cb = craig_bampton(comp, bl, solver=petsc_solver(), **kw)    # distributed
    # eigenvectors are defined up to sign: align by Phi_petsc^T M Phi_scipy (no degenerate
    # pairs in this box: W != H)
    s = np.sign(np.einsum("ij,ij->j", cb.fixed_interface_modes, comp.M @ ref.fixed_interface_modes))
    S = np.diag(np.r_[s, np.ones(cb.n_boundary)])
    out[key] = {"n": [ref.n_modes, cb.n_modes], "freq": cb.fixed_freq_hz.tolist(),
                "freq_err": float(np.abs(cb.fixed_omega / ref.fixed_omega - 1).max()),
                "K_err": float(np.abs(cb.K - ref.K).max() / np.abs(ref.K).max()),
                "M_err": float(np.abs(S @ cb.M @ S - ref.M).max() / np.abs(ref.M).max()),
                "T_err": float(np.abs(cb.constraint_modes - ref.constraint_modes).max()
                               / np.abs(ref.constraint_modes).max()),
                "K_B": cb.K_B.tolist(), "M_B": cb.M_B.tolist(), "shifted": "eigen_shift" in cb.timings}
if MPI.COMM_WORLD.rank == 0:
    print("RESULT " + json.dumps(out), flush=True)
