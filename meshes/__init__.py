"""Parametric gmsh geometry (no dolfinx): propellant tank, twin-booster vehicle, launch pad;
barge with its cargo tank and a pile-supported dock (meshes/barge.py).

Every builder takes a parameter dataclass (SI, documented defaults, ``mesh_size`` in m),
writes ``<out_dir>/<name>.msh`` with named physical groups plus a ``<name>.json``
sidecar, and returns a :class:`Geometry` (see meshes/spec.py and docs/meshes.md).
All parts share the global frame of :mod:`meshes.layout` (z up, origin on the core axis
at the hold-down level, x along the booster-booster line, y towards the orbiter).
"""

from liftoff.core.lazy import lazy_exports

_EXPORTS = {
    "StackLayout": ".layout",
    "BargeParams": ".barge",
    "CargoParams": ".barge",
    "DockParams": ".barge",
    "build_barge": ".barge",
    "build_cargo": ".barge",
    "build_dock": ".barge",
    "PadParams": ".pad",
    "StickParams": ".stick",
    "build_pad": ".pad",
    "default_pad": ".pad",
    "Geometry": ".spec",
    "Material": ".spec",
    "Patch": ".spec",
    "PointMass": ".spec",
    "SmearedMass": ".spec",
    "AL2219": ".tank",
    "Compartment": ".tank",
    "TankParams": ".tank",
    "build_tank": ".tank",
    "BoosterParams": ".vehicle",
    "SolidMotorParams": ".solid_motor",
    "OrbiterParams": ".vehicle",
    "build_booster": ".vehicle",
    "build_core_stage": ".vehicle",
    "build_orbiter": ".vehicle",
    "core_stage_params": ".vehicle",
    "default_stack": ".vehicle",
}
__all__ = list(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
