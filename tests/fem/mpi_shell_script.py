"""Run by test_mpi.py under `mpirun -n 2`: a free and a clamped shell tube (also loaded
through two interpolation patches sharing its tip edge, and with a beam ring frame on its
tip edge) and a shell glued on a solid (meshes on the command line); rank 0 prints one
JSON line."""
import json
import sys

import numpy as np
from mpi4py import MPI

from liftoff.fem import build_model, eigenmodes, mass_properties, point_load, static_solve
from liftoff.core.beam import rectangle
from liftoff.meshes.spec import BeamGroup, Geometry, Material, Patch

tube, glued, degree = sys.argv[1], sys.argv[2], int(sys.argv[3])
al = Material("al", 70e9, 0.3, 2700.0)
out = {"size": MPI.COMM_WORLD.size}
free = build_model(Geometry("tube", tube, {"tube": al}, shells={"tube": 0.005}, patches=[Patch("tip", (0, 0, 1.0))]))
modes = eigenmodes(free, n_modes=12)
cant = build_model(Geometry("tube", tube, {"tube": al}, shells={"tube": 0.005}, patches=[Patch("tip", (0, 0, 1.0))],
                            clamped=["root"]))
x = static_solve(cant, point_load(cant, "tip", force=(100.0, 0, 0), moment=(0, 0, 10.0)))
ring = build_model(Geometry("tube", tube, {"tube": al}, shells={"tube": 0.005}, clamped=["root"],
                            patches=[Patch("east", (0.1, 0, 1.0), nodes="tip", reach=0.142),
                                     Patch("west", (-0.1, 0, 1.0), nodes="tip", reach=0.142)]))
xr = static_solve(ring, point_load(ring, "east", force=(0, 50.0, 20.0), moment=(1.0, 0, 0)))
framed = build_model(Geometry("tube", tube, {"tube": al}, shells={"tube": 0.005}, clamped=["root"],
                              beams={"tip": BeamGroup(al, rectangle(0.005, 0.02), radial_offset=-0.01)}))
hyb = build_model(Geometry("g", glued, {"plate": al, "block": al}, shells={"plate": 0.01}), degree)
u = hyb.nodal_displacement(hyb.rigid_body_shape()[:, 5])
out.update(freq=modes.freq_hz.tolist(), n_rigid=modes.n_rigid, mass=mass_properties(free).mass, n_dof=free.n_dof,
           tip=[float(x[cant.dof_index(f"tip:{c}")]) for c in ("Tx", "Ty", "Tz", "Rx", "Ry", "Rz")],
           hybrid_freq=eigenmodes(hyb, n_modes=10).freq_hz.tolist(), hybrid_mass=mass_properties(hyb).mass,
           rot_err=float(np.abs(u - np.column_stack([-hyb.nodes[:, 1], hyb.nodes[:, 0], 0 * hyb.nodes[:, 0]])).max()),
           n_cells=int(hyb.cells.shape[0]), ring_n_dof=ring.n_dof,
           framed_freq=eigenmodes(framed, n_modes=6).freq_hz.tolist(), framed_n_dof=framed.n_dof,
           ring=[float(xr[ring.dof_index(f"{p}:{c}")]) for p in ("east", "west") for c in ("Tx", "Ty", "Tz", "Rx")])
if MPI.COMM_WORLD.rank == 0:
    print("RESULT " + json.dumps(out), flush=True)
