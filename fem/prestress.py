"""Pressure stiffening of shell tank walls: the ullage gas's gauge pressure on each
compartment's closed cavity wall (``spec.Liquid.ullage_pressure``) prestresses the wall; its
membrane resultants N0 add the geometric stiffness K_G, and the follower pressure adds
the load stiffness K_L = -p d^2V (fem.shell). With both, a pressurised closed vessel keeps
its rigid rotations free (tests/fem/test_shell_prestress.py: 4e-6 of K_G's rotation energy
is left).

The prestress is the linear static state of the pressures alone on the free shell part
(before spiders, clamps and solids are attached: the fittings' local stiffening of the
membrane state is left out, and rigid motions of the model stay rigid motions of the
part, so K_G + K_L stays free of rigid-body energy). Gauge pressures on closed cavities are
self-equilibrated (checked); the free part is solved with a small positive shift
(K + sigma M) u = f, sigma = SHIFT_RATIO x K's diagonal / M's diagonal: rigid motions carry
no strain, and the elastic response is off by sigma / omega_1^2 (below 1e-5 here). Left out:
the liquid's hydrostatic head, the weight and thrust (axial) loads, and bending and shear
prestress. Units SI (Pa, N/m).
"""
from __future__ import annotations

import numpy as np
from mpi4py import MPI

from liftoff.core.errors import InputError
from liftoff.core.rigid import dof_rb

from . import petsc_backend as pb

SHIFT_RATIO = 1e-10


def pressurised(geometry) -> dict:
    """{liquid group: Liquid} of the geometry's liquids with a gauge ullage pressure > 0."""
    return {g: liq for g, liq in geometry.liquids.items() if liq.ullage_pressure > 0}


def _cavity_measure(part, liq, group: str):
    import ufl

    tags = part.tagged.surface_tags.get(liq.cavity)
    # a mesh with solids and shells lists every surface name in each part, with no cells in the
    # part it does not touch: a cavity of solid faces is "present but empty" in the shell part,
    # and its pressure load came out zero (no prestress, no error)
    comm = part.tagged.mesh.comm
    if tags is None or not comm.allreduce(bool(np.any(tags.values == 1)), op=MPI.LOR):
        raise InputError(f"liquid {group!r}: ullage_pressure {liq.ullage_pressure:g} Pa needs a shell wall; "
                         f"its cavity {liq.cavity!r} is not a shell surface (solid walls take no pressure prestress)")
    return ufl.Measure("dx", domain=part.tagged.mesh, subdomain_data=tags)(1)


def _check_equilibrated(wall, b, name: str) -> None:
    """Gauge pressures on closed surfaces have no resultant: RB^T f ~ round-off."""
    comm = wall.tagged.mesh.comm
    own = slice(0, wall.n_own)
    f = b.getArray(readonly=True)
    c = comm.allreduce(np.asarray(wall.coords[own].sum(axis=0)), op=MPI.SUM) / max(comm.allreduce(wall.n_own), 1)
    rb = dof_rb(wall.coords[own] - c, wall.comp[own])
    res = comm.allreduce(rb.T @ f, op=MPI.SUM)
    size = comm.allreduce(float(np.abs(f).sum()), op=MPI.SUM)
    extent = comm.allreduce(float(np.abs(wall.coords[own] - c).max(initial=0.0)), op=MPI.MAX)
    scale = size * np.array([1, 1, 1, extent, extent, extent])
    if np.any(np.abs(res) > 1e-8 * scale):
        raise InputError(f"model {name!r}: the ullage pressures have a resultant (force {res[:3]} N, moment "
                         f"{res[3:]} N m): a cavity surface is not closed")


def prestress_stiffness(wall, geometry):
    """K_G + K_L (PETSc, on the shell part's space) of the geometry's ullage pressures
    (:func:`pressurised`: at least one). ``wall``: the model's shell part (fem.model.Part) with
    its assembled K and M."""
    import ufl
    from dolfinx import fem

    from . import shell as sh

    loads = pressurised(geometry)
    dx = {g: _cavity_measure(wall, liq, g) for g, liq in loads.items()}
    b = None
    for g, liq in loads.items():     # one form per cavity: UFL takes one subdomain_data per form
        bg = pb.assemble_vector(sh.pressure_load_form(wall.V, liq.ullage_pressure, liq.center, dx[g]))
        b = bg if b is None else b + bg
    _check_equilibrated(wall, b, geometry.name)
    A = wall.K.copy()
    d_k, d_m = (abs(A.getDiagonal().sum()), abs(wall.M.getDiagonal().sum()))
    A.axpy(SHIFT_RATIO * d_k / d_m, wall.M, structure=pb.PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN)
    u = fem.Function(wall.V)
    x = A.createVecRight()
    pb.direct_solve(A, b, x, what=f"pressure prestress of {geometry.name!r}")
    u.x.array[:wall.n_own] = x.getArray(readonly=True)
    u.x.scatter_forward()
    A.destroy()
    N0 = sh.membrane_resultants(ufl.split(u)[0], wall.fields, wall.tagged.mesh)
    KG = pb.assemble_matrix(sh.geometric_stiffness_form(wall.V, N0))
    for g, liq in loads.items():
        pb.add_subset(KG, pb.assemble_matrix(sh.volume_hessian_form(wall.V, liq.center, dx[g])), -liq.ullage_pressure)
    return KG


def relative_to_reference(K, rb: np.ndarray, ref_dofs: np.ndarray):
    """P^T K P, P = I - RB e^T: the stiffness of the motion relative to the rigid motion of one
    reference point (``ref_dofs``, its six DOFs; ``rb`` (n_dof, 6) the model's rigid-body
    shape about that point, so RB = I there). Returns the new matrix (K is destroyed).

    K_G + K_L leaves rigid rotations free only up to the bending prestress it omits (1e-4 of
    its rotation energy on the core stage at a 0.9 m mesh: a 0.06 Hz spurious rigid-body
    frequency); measured relative to the reference point's rigid motion, the pressure
    stiffness follows the tank's rotation as a follower load does, and the free model's six
    rigid-body modes are exactly free. An elastic K (K RB = 0) is unchanged. The update
    fills six rows and columns:  P^T K P = K - E e^T - e E^T + e (RB^T E) e^T, E = K RB."""
    import scipy.sparse as sp

    comm = K.getComm().tompi4py()
    r0, r1 = K.getOwnershipRange()
    n = rb.shape[0]
    E = np.zeros((n, 6))
    x, y = K.createVecs()
    for k in range(6):
        x.setArray(rb[r0:r1, k])
        K.mult(x, y)
        E[:, k] = pb.gather_vec(y)
    S = rb.T @ E
    e = sp.csr_matrix((np.ones(6), (np.asarray(ref_dofs), np.arange(6))), shape=(n, 6))
    C = sp.csr_matrix(-e @ sp.csr_matrix(E.T) - sp.csr_matrix(E) @ e.T + e @ sp.csr_matrix(0.5 * (S + S.T)) @ e.T)
    Cp = pb.csr_matrix(comm, r1 - r0, r1 - r0, n, C[r0:r1])
    return pb.add(K, Cp)
