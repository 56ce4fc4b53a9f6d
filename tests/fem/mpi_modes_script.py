"""Run by test_mpi.py under `mpirun -n 2`: modes, mass and a spider static solve of a
mesh given on the command line; rank 0 prints one JSON line."""
import json
import sys

import numpy as np
from mpi4py import MPI

from liftoff.fem import build_model, eigenmodes, mass_properties, point_load, static_solve
from liftoff.meshes.spec import Geometry, Material, Patch

path, degree = sys.argv[1], int(sys.argv[2])
steel = Material("steel", 2.0e11, 0.3, 7800.0)
free = build_model(Geometry("box", path, {"solid": steel}, patches=[Patch("x1", (1.1, 0.05, 0.05))]), degree)
modes = eigenmodes(free, n_modes=12)
clamped = build_model(Geometry("cant", path, {"solid": steel}, patches=[Patch("x1", (1.1, 0.05, 0.05))],
                               clamped=["x0"]), degree)
x = static_solve(clamped, point_load(clamped, "x1", force=(0, 0, 1000.0), moment=(50.0, 0, 0)))
# gathered mesh + field_map consistent: a rigid rotation about z gives u = (-y, x, 0) at
# every node; the cells (first 4 nodes = vertices) tile the box volume

rot = free.rigid_body_shape()[:, 5]
u = free.nodal_displacement(rot)
fields = free.component_fields()
v = fields["nodes"][fields["cells"][:, :4]]
vol = np.abs(np.einsum("ij,ij->i", v[:, 1] - v[:, 0], np.cross(v[:, 2] - v[:, 0], v[:, 3] - v[:, 0]))).sum() / 6
out = {"rot_err": float(np.abs(u - np.column_stack([-fields["nodes"][:, 1], fields["nodes"][:, 0],
                                                      0 * fields["nodes"][:, 0]])).max()),
       "volume": float(vol), "n_cells": int(fields["cells"].shape[0]),
"size": MPI.COMM_WORLD.size, "freq": modes.freq_hz.tolist(), "n_rigid": modes.n_rigid,
       "mass": mass_properties(free).mass, "n_dof": free.n_dof,
       "tip": [float(x[clamped.dof_index(f"x1:{c}")]) for c in ("Tx", "Ty", "Tz", "Rx", "Ry", "Rz")],
       "clamped_freq": eigenmodes(clamped, n_modes=4).freq_hz.tolist()}
if MPI.COMM_WORLD.rank == 0:
    print("RESULT " + json.dumps(out), flush=True)
