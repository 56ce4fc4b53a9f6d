"""``[model] source = "fe"``: gmsh geometry (meshes/) -> dolfinx FE model (fem/) -> Component.

Scenario keys used here: ``[model.vehicle.params]`` are fields of
meshes.layout.StackLayout (shared by every component and the pad, so that interface
points coincide); ``[model.component.<name>.params]`` and ``[model.pad.params]`` are
fields of the component's builder dataclass (BoosterParams, OrbiterParams, PadParams;
the core stage takes only the layout and the mesh size); ``[model.materials.<volume>]``
replaces the material of a physical volume group. The unit thermal load (alpha * delta_T
= 1) of every volume group is returned for the cryo preload (section 4.3).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from liftoff.core.errors import InputError


def _dataclass(cls, kwargs: dict, where: str):
    try:
        return cls(**kwargs)
    except TypeError as exc:
        import dataclasses

        known = ", ".join(f.name for f in dataclasses.fields(cls))
        raise InputError(f"{where}: {exc} (known: {known})") from None


def geometry(params: dict, workdir: Path):
    """The meshed Geometry of one component (``params`` from pipeline._component_params)."""
    from liftoff.meshes import (
        BoosterParams,
        OrbiterParams,
        PadParams,
        StackLayout,
        build_booster,
        build_core_stage,
        build_orbiter,
        build_pad,
    )

    name = params["name"]
    lay = _dataclass(StackLayout, dict(params["stack"]), "model.vehicle.params")
    lay.check()
    given = dict(params["params"])
    size = params["mesh_size"]
    extra = dict(given)
    if size is not None:
        extra.setdefault("mesh_size", size)
    where = f"model.{'pad' if name == 'pad' else 'component.' + name}.params"
    if name == "core":
        if given:
            raise InputError(f"{where}: the core stage takes no builder parameters in the FE source "
                             f"(got {', '.join(given)}); change [model.vehicle.params] (StackLayout)")
        geo = build_core_stage(workdir, lay, **({} if size is None else {"mesh_size": size}))
    elif name in ("srb_left", "srb_right"):
        geo = build_booster(_dataclass(BoosterParams, {"side": name[4:], "layout": lay, **extra},
                                       where), workdir)
    elif name == "orbiter":
        geo = build_orbiter(_dataclass(OrbiterParams, {"layout": lay, **extra}, where), workdir)
    elif name == "pad":
        geo = build_pad(_dataclass(PadParams, {"layout": lay, **extra}, where), workdir)
    else:
        raise InputError(f"unknown component {name!r}")
    return geo


def build_component(params: dict, workdir: Path):
    """(Component, {volume: unit thermal load over the component's DOFs})."""
    try:  # pyvista must be imported before dolfinx (FENICSX-NOTES.md)
        import pyvista  # noqa: F401
    except ImportError:  # pragma: no cover
        pass
    try:
        from liftoff.fem import build_model, thermal_load
        from liftoff.meshes import Material
    except ImportError as exc:
        raise InputError(f"model.source = 'fe' needs gmsh and dolfinx ({exc}); install them with "
                         "`make setup` or use source = 'stick'") from None
    from liftoff.reduction import Component

    geo = geometry(params, Path(workdir))
    for vol, mat in params["materials"].items():
        if vol in geo.volumes:
            geo.volumes[vol] = Material(vol, mat["E"], mat["nu"], mat["rho"])
    model = build_model(geo, params["degree"])
    comp = Component(name=params["name"], **model.component_fields())
    thermal = {vol: np.asarray(thermal_load(model, [vol], 1.0, 1.0), float) for vol in geo.volumes}
    return comp, thermal
