"""``type = "rigid_mass"``: a rigid body joined to the vehicle at one point (a payload or an
engine in an early loads cycle, a ballast): no mesh, no FE, no Craig-Bampton reduction;
its model is its 6 x 6 mass matrix at the point (reduction.models.RigidMass,
rigid_mass_cb). Params: ``point`` (the joint's name), ``at`` (m), ``mass`` (kg), ``cg`` (m,
default the point), ``inertia`` (kg m^2 about the c.g.: [Ixx, Iyy, Izz] or with products
[Ixx, Iyy, Izz, Ixy, Ixz, Iyz])."""
from __future__ import annotations

from ..params import builder
from ..values import Where
from . import ComponentType, Context


def read(ctx: Context, where: Where, params: dict):
    from liftoff.reduction.models import RigidMass

    if ctx.mesh_size is not None and ctx.mesh_size_given:     # (an inherited [model] mesh_size: nothing to mesh)
        raise where.error("a rigid mass has no mesh: remove the component's mesh_size")
    return builder(where, RigidMass, params)


TYPE = ComponentType("rigid_mass", read, "", "vehicle",
                     "a rigid body at one point: mass, c.g. and inertia (reduction.models.RigidMass)",
                     model="liftoff.reduction.models:rigid_mass_cb")
