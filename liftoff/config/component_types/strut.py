"""``type = "strut"``: one straight member between two named points, joining two other
components (an attach strut, a thrust beam; reduction.strut.Strut): ``ends = {name = [x, y,
z], other = [x, y, z]}`` (m; name the ends as the joints they share), ``section = {shape =
"tube", r_out = ..., t = ...}`` (liftoff.core.beam.SHAPES), ``E``, ``nu``, ``rho``,
``elements`` [4], ``vref``, ``pins`` (the pin flags of its two ends, Nastran's PA and PB:
``["456", "56"]`` for a pin-ended strut). No gmsh: its matrices are reduced by the CB stage."""
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
    fixed = {"name": ctx.name, "ends": named(where / "ends", params.get("ends", {}), xyz),
             "section": beam_section(where / "section", params["section"])}
    if "pins" in params:
        pins = params["pins"]
        if not isinstance(pins, list) or len(pins) != 2:
            raise (where / "pins").error(f"expected the two ends' pin flags, e.g. [\"456\", \"56\"], got {pins!r}")
        fixed["pins"] = tuple(string(where / "pins" / i, f, nonempty=False) for i, f in enumerate(pins))
    return builder(where, Strut, {k: v for k, v in params.items() if k not in ("ends", "section", "pins")}, fixed)


TYPE = ComponentType("strut", read, "", "vehicle", "one straight member between two named points (reduction.strut.Strut)",
                     matrices="liftoff.reduction.strut:strut_component")
