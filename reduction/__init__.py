"""Craig-Bampton reduction, assembly, system modes and data recovery (numpy/scipy only).

Section 3.0 and 4.2 of Prabhakar & Palermo; file formats in docs/reduction.md.
"""
from .assembly import Assembly, assemble
from .checks import CBCheck, cb_check
from .component import Component, load_component, save_component
from .craig_bampton import CBModel, craig_bampton, load_cb, save_cb
from .recovery import (acceleration_recovery, displacement_recovery, field_recovery,
                       interface_force_recovery, label_transform)
from .rigid import mass_properties, nodal_rb, rb_rows
from .system import SystemModes, system_modes, system_rb

__all__ = ["Component", "load_component", "save_component", "CBModel", "craig_bampton", "load_cb",
           "save_cb", "CBCheck", "cb_check", "Assembly", "assemble", "SystemModes", "system_modes",
           "system_rb", "displacement_recovery", "acceleration_recovery", "interface_force_recovery",
           "field_recovery", "label_transform", "rb_rows", "nodal_rb", "mass_properties"]
