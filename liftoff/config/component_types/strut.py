"""``type = "strut"``: one straight member between two named points, joining two other
components (an attach strut, a thrust beam; reduction.strut.Strut): ``ends = {name = [x, y,
z], other = [x, y, z]}`` (m; name the ends as the joints they share), ``section = {shape =
"tube", r_out = ..., t = ...}`` (liftoff.core.beam.SHAPES), ``E``, ``nu``, ``rho``,
``elements`` [4], ``vref``, ``pinned`` [false] (pin-ended: no moment at either end, its end
points translations only). No gmsh: its matrices are reduced by the CB stage."""
from __future__ import annotations

from ..params import beam_section, builder
from ..values import Where, named, string, xyz
from . import ComponentType, Context


def read(ctx: Context, where: Where, params: dict):
    from liftoff.reduction.strut import Strut

    if not isinstance(params, dict):
        raise where.error("expected a table of Strut fields")
    if "section" not in params:
        raise (where / "section").error("missing: the strut's section, e.g. {shape = \"tube\", r_out = 0.2, t = 0.01}")
    ends = params.get("ends", {})
    if isinstance(ends, list):          # the layout's named points (meshes.layout.StackLayout.named_points)
        known = ctx.layout.named_points() if ctx.layout is not None else {}
        for i, n in enumerate(ends):
            if string(where / "ends" / i, n) not in known:
                raise (where / "ends" / i).error(f"{n!r} is not a point of the layout ([model.vehicle.params]): "
                                                 f"give the ends as {{name = [x, y, z]}} (m), or one of "
                                                 f"{', '.join(sorted(known)) or 'none'}")
        ends = {n: [float(c) for c in known[n]] for n in ends}
    fixed = {"name": ctx.name, "ends": named(where / "ends", ends, xyz),
             "section": beam_section(where / "section", params["section"])}
    return builder(where, Strut, {k: v for k, v in params.items() if k not in ("ends", "section")}, fixed)


TYPE = ComponentType("strut", read, "", "vehicle", "one straight member between two named points (reduction.strut.Strut)",
                     matrices="liftoff.reduction.strut:strut_component")
