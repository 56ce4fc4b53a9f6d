"""Craig-Bampton reduction, assembly, system modes and data recovery (numpy/scipy only).

Section 3.0 and 4.2 of Prabhakar & Palermo; file formats in docs/reduction.md.
"""

from liftoff.core.lazy import lazy_exports

_EXPORTS = {
    "Assembly": ".assembly",
    "assemble": ".assembly",
    "CBCheck": ".checks",
    "cb_check": ".checks",
    "Component": ".component",
    "load_component": ".component",
    "save_component": ".component",
    "CBModel": ".craig_bampton",
    "craig_bampton": ".craig_bampton",
    "CBSolver": ".craig_bampton",
    "scipy_solver": ".craig_bampton",
    "load_cb": ".craig_bampton",
    "save_cb": ".craig_bampton",
    "acceleration_recovery": ".recovery",
    "cg_acceleration_recovery": ".recovery",
    "component_recovery": ".recovery",
    "CBRecovery": ".craig_bampton",
    "NastranRecovery": ".nastran",
    "UnitSystem": ".nastran",
    "unit_system": ".nastran",
    "from_extseout": ".nastran",
    "from_dmig": ".nastran",
    "from_nas2cam": ".nastran",
    "import_nastran": ".nastran",
    "write_dmig": ".nastran",
    "write_op4": ".nastran",
    "read_op4": ".nastran",
    "displacement_recovery": ".recovery",
    "field_recovery": ".recovery",
    "field_displacement": ".recovery",
    "interface_force_recovery": ".recovery",
    "label_transform": ".assembly",
    "ModalMassTable": ".modal_mass",
    "modal_mass_table": ".modal_mass",
    "SystemModes": ".system",
    "system_modes": ".system",
    "system_rb": ".system",
    "StaticFlexibility": ".truncation",
    "TruncationCheck": ".truncation",
    "keep_modes": ".truncation",
    "residual_vectors": ".truncation",
    "truncation_check": ".truncation",
}
__all__ = list(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
# the function shadows the module of the same name (a lazy export could not: importing the
# submodule sets the package attribute), so bind it now
from .craig_bampton import craig_bampton  # noqa: E402,F401
