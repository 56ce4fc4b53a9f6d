"""dolfinx finite-element models of liftoff components (issue 3; DESIGN.md).

Public API (SI units throughout)::

    build_model(geometry, degree=1, comm=MPI.COMM_WORLD, lumped_smeared_mass=False) -> FEModel
    FEModel.component_fields() -> dict   # Component(name=..., **fields)
    eigenmodes(model, n_modes=None, band_hz=None, shift_hz=1.0, rigid_tol_hz=0.01) -> Modes
    beam_content(model, shape) -> float   # beam-bending share of a mode (shell models)
    static_solve(model, f, supports=()) -> x
    point_load(model, point, force, moment) -> f
    thermal_load(model, volumes, delta_T, alpha) -> f
    mass_properties(model, about=(0, 0, 0)) -> MassProperties
    write_vtu(path, nodes, cells, cell_type, point_data) / write_modes_vtu(model, modes, path)
    fem.snapshot.snapshot_png(path, nodes, cells, cell_type, displacement, title, scale=None)
    petsc_solver(comm=MPI.COMM_WORLD, tol=1e-10, eigensolver="block-lanczos") -> PetscSolver   # craig_bampton(solver=...)

Parts: solids (tetrahedra of the volume groups), Reissner-Mindlin shells (triangles of
the surface groups in ``Geometry.shells``, fem.shell) and 3-D Timoshenko beams (the line
elements of the curve groups in ``Geometry.beams``, fem.beam), tied by node position.
Import pyvista (fem.snapshot) before dolfinx when both are used (FENICSX-NOTES.md).
Only this package and meshes/ import gmsh or dolfinx; PETSc/SLEPc live in petsc_backend.
"""

from liftoff.core.lazy import lazy_exports

_EXPORTS = {
    "FEModel": ".model",
    "build_model": ".model",
    "Modes": ".modes",
    "eigenmodes": ".modes",
    "beam_content": ".modes",
    "LiquidOperator": ".liquid",
    "liquid_operator": ".liquid",
    "wet_eigensolve": ".liquid",
    "PetscSolver": ".petsc_cb",
    "petsc_solver": ".petsc_cb",
    "write_modes_vtu": ".output",
    "write_vtu": ".output",
    "MassProperties": ".static",
    "mass_properties": ".static",
    "point_load": ".static",
    "static_solve": ".static",
    "thermal_load": ".static",
}
__all__ = list(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
