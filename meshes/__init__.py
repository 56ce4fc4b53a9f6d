"""Parametric gmsh geometry (no dolfinx): propellant tank, twin-booster vehicle, launch pad.

Every builder takes a parameter dataclass (SI, documented defaults, ``mesh_size`` in m),
writes ``<out_dir>/<name>.msh`` with named physical groups plus a JSON sidecar, and
returns a :class:`Geometry` (see meshes/spec.py and docs/meshes.md).
"""
from .spec import Geometry, Material, Patch, PointMass, SmearedMass
from .tank import AL2219, Compartment, TankParams, build_tank

__all__ = ["Geometry", "Material", "Patch", "PointMass", "SmearedMass",
           "AL2219", "Compartment", "TankParams", "build_tank"]
