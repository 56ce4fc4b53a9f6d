"""Parametric gmsh geometry (no dolfinx): propellant tank, twin-booster vehicle, launch pad.

Every builder takes a parameter dataclass (SI, documented defaults, ``mesh_size`` in m),
writes ``<out_dir>/<name>.msh`` with named physical groups plus a ``<name>.json``
sidecar, and returns a :class:`Geometry` (see meshes/spec.py and docs/meshes.md).
All parts share the global frame of :mod:`meshes.layout` (z up, origin on the core axis
at the hold-down level, x along the booster-booster line, y towards the orbiter).
"""
from .layout import StackLayout
from .pad import PadParams, build_pad, default_pad
from .spec import Geometry, Material, Patch, PointMass, SmearedMass
from .tank import AL2219, Compartment, TankParams, build_tank
from .vehicle import (BoosterParams, OrbiterParams, build_booster, build_core_stage, build_orbiter,
                      core_stage_params, default_stack)

__all__ = ["Geometry", "Material", "Patch", "PointMass", "SmearedMass", "StackLayout",
           "AL2219", "Compartment", "TankParams", "build_tank",
           "BoosterParams", "OrbiterParams", "build_booster", "build_core_stage", "build_orbiter",
           "core_stage_params", "default_stack", "PadParams", "build_pad", "default_pad"]
