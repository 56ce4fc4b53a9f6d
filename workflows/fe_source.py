"""``[model] source = "fe"``: gmsh geometry (meshes/) -> dolfinx FE model (fem/) -> Component.

The builder parameters arrive checked, as the builders' own dataclasses
(liftoff.config.model: TankParams of the core stage, BoosterParams, OrbiterParams,
PadParams, all on the scenario's StackLayout, so that interface points coincide);
``[model.materials.<volume>]`` replaces the material of a physical volume group. The unit
thermal load (alpha * delta_T = 1) of every volume group is returned for the cryo preload
(section 4.3). Under mpirun, rank 0 meshes with gmsh and the dolfinx model is built over
all ranks (fem.build_model on MPI.COMM_WORLD); the Component is gathered on every rank.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from liftoff.config.model import ComponentModel, ModelConfig
from liftoff.core.errors import InputError


def geometry(comp: ComponentModel, workdir: Path):
    """The meshed Geometry of one component, built by its registered type's gmsh builder
    (liftoff.config.component_types) from its parameter dataclass."""
    from liftoff.config import component_types

    try:
        t = component_types.types()[comp.type]
    except KeyError:
        raise InputError(f"component {comp.name!r}: no FE builder for type {comp.type!r}") from None
    return t.builder()(comp.builder, workdir)


def build_component(comp: ComponentModel, model: ModelConfig, workdir: Path):
    """(Component, {volume: unit thermal load over the component's DOFs})."""
    try:  # pyvista must be imported before dolfinx (FENICSX-NOTES.md)
        import pyvista  # noqa: F401
    except ImportError:  # pragma: no cover
        pass
    try:
        from liftoff.fem import build_model, thermal_load
    except ImportError as exc:
        raise InputError(f"model.source = 'fe' needs gmsh and dolfinx ({exc}); install them with "
                         "`make setup` or use source = 'stick'") from None
    from liftoff.meshes._occ import element_limit
    from liftoff.reduction import Component

    from .parallel import on_root, world

    def mesh():
        with element_limit(model.max_elements, f"component {comp.name!r}"):
            return geometry(comp, Path(workdir))

    from .pipeline import component_materials

    geo = on_root(world(), mesh)   # gmsh on rank 0; its .msh is read there
    for vol, mat in component_materials(model, comp.name).items():   # those in the stage's cache key
        if vol in geo.volumes:
            geo.volumes[vol] = mat
    for liq in geo.liquids.values():      # the slosh modes' g_eff is the model's, [model] slosh_gravity
        liq.gravity = model.slosh_gravity
    from liftoff.fem.parallel import fe_comm

    fe = build_model(geo, model.degree, comm=fe_comm(world()), convective=model.convective)
    liquid = fe.liquid_fields()
    if liquid is not None:
        from liftoff.reduction.liquid import LiquidMass

        liquid = LiquidMass(**liquid)
    slosh = fe.slosh_fields()
    if slosh is not None:
        from liftoff.reduction.slosh import SloshDOFs

        slosh = SloshDOFs(**slosh)
    component = Component(name=comp.name, **fe.component_fields(), liquid=liquid, slosh=slosh)
    thermal = {vol: fe.pad_dofs(np.asarray(thermal_load(fe, [vol], 1.0, 1.0), float)) for vol in geo.volumes}
    return component, thermal
