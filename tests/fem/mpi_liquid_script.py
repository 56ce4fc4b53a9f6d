"""Run under mpirun by test_liquid_cb.py: a hydroelastic tank model and its PETSc CB on N ranks;
prints invariants (independent of the DOF order) as one JSON line on rank 0."""
import json
import sys

import numpy as np
from liftoff.fem import build_model, petsc_solver
from liftoff.meshes.spec import Geometry
from liftoff.reduction import Component, craig_bampton
from liftoff.reduction.liquid import LiquidMass
from mpi4py import MPI

m = build_model(Geometry.load(sys.argv[1]))
comp = Component(name="tank", **m.component_fields(), liquid=LiquidMass(**m.liquid_fields()))
cb = craig_bampton(comp, comp.dof_labels, n_modes=6, solver=petsc_solver())
rz = m.rigid_body_shape()[:, 2]
x = np.zeros(m.n_dof)
tr = m.dof_comp < 3
x[tr] = 1e-3 * m.dof_coords[tr, m.dof_comp[tr]]
out = {"size": MPI.COMM_WORLD.size, "freq": cb.fixed_freq_hz.tolist(), "axial": float(comp.liquid.project(rz)[0, 0]),
       "head": comp.liquid.pressure_rows() @ (9.80665 * rz), "dv": comp.liquid.volume_rows @ x,
       "n_p": comp.liquid.H.shape[0]}
out = {k: np.asarray(v).tolist() for k, v in out.items()}
if MPI.COMM_WORLD.rank == 0:
    print("RESULT " + json.dumps(out), flush=True)
