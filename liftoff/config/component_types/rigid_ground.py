"""``type = "rigid_ground"`` (pad): immovable ground for the posts to hold the vehicle to,
when the pad's own flexibility is not wanted (a first cycle, a test stand on bedrock): no
mesh, no DOFs; its named points never move (reduction.models.RigidGround,
rigid_ground_cb). Params: ``points = {name = [x, y, z]}`` (m), the posts' pad points."""
from __future__ import annotations

from ..values import Where, named, table, xyz
from . import ComponentType, Context


def read(ctx: Context, where: Where, params: dict):
    from liftoff.reduction.models import RigidGround

    if ctx.mesh_size is not None and ctx.mesh_size_given:     # (an inherited [model] mesh_size: nothing to mesh)
        raise where.error("rigid ground has no mesh: remove the pad's mesh_size")
    p = table(where, params, {"points"}, ("points",))
    g = RigidGround(named(where / "points", p["points"], xyz))
    try:
        g.check()
    except Exception as exc:
        raise where.wrap(exc) from None
    return g


TYPE = ComponentType("rigid_ground", read, "", "pad",
                     "immovable ground: named points that never move (reduction.models.RigidGround)",
                     model="liftoff.reduction.models:rigid_ground_cb")
