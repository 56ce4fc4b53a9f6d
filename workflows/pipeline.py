"""Model stages of the lift-off workflow: geometry -> FE (or stick) -> Craig-Bampton ->
system modes -> the two modal bodies (vehicle, pad) of the transient (sections 3.0, 4.2).

Each stage is cached under a hash of its inputs (workflows/cache.py), so a run that
changes only loads or cases loads the reduced models instead of meshing and solving.
The vehicle is the free-free assembly of the components ``core``, ``srb_left``,
``srb_right``, ``orbiter`` overlaid on their shared points; the pad is a grounded
component reduced to its hold-down posts. Every named point of a component (spider
reference point, stick node with a name) is a Craig-Bampton boundary point (section
3.0: interfaces, contact points and large-load points stay discrete).
"""
from __future__ import annotations

import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from liftoff.reduction import (
    Assembly,
    CBModel,
    Component,
    SystemModes,
    assemble,
    craig_bampton,
    load_cb,
    load_component,
    save_component,
    system_modes,
)
from liftoff.transient.body import ModalBody
from liftoff.transient.effects import center_of_gravity

from liftoff.core.errors import InputError
from liftoff.core.labels import named_points, points_labels

from .cache import StageCache, load_arrays, save_arrays, stage_key

VEHICLE = ("core", "srb_left", "srb_right", "orbiter")
DEFAULT_F_MAX = {"core": 60.0, "srb_left": 60.0, "srb_right": 60.0, "orbiter": 60.0, "pad": 60.0}


@dataclass
class StackModel:
    """The reduced stack: components, CB models, system modes and the two modal bodies."""

    components: dict[str, Component]
    cbs: dict[str, CBModel]
    vehicle_asm: Assembly
    vehicle_modes: SystemModes
    vehicle: ModalBody
    pad_asm: Assembly
    pad_modes: SystemModes
    pad: ModalBody
    unit_thermal: dict[str, dict[str, np.ndarray]]  # component -> volume -> boundary load per unit strain
    timings: dict = field(default_factory=dict)


def boundary_points(component: Component) -> list[str]:
    """Named points of a component (liftoff.core.labels.is_named_point): its CB boundary."""
    return named_points(component.points)


# ------------------------------------------------------------------ components
def _component_params(model: dict, name: str) -> dict:
    comp = model["component"].get(name, {}) if name != "pad" else model.get("pad", {})
    size = comp.get("mesh_size", model.get("vehicle", {}).get("mesh_size") if name != "pad" else None)
    size = size or model.get("mesh_size") or (4.0 if model["source"] == "stick" else None)  # fe: builder default
    return {"source": model["source"], "name": name, "mesh_size": size, "degree": model["degree"],
            "stack": model.get("vehicle", {}).get("params", {}),
            "params": comp.get("params", {}), "materials": model.get("materials", {})}


def _build_stick(params: dict) -> tuple[Component, dict]:
    from .stick import stack_components, stack_thermal

    stack = dict(params["stack"])
    stack.update(params["params"])
    name = params["name"]
    return stack_components(stack, params["mesh_size"])[name], stack_thermal(stack, params["mesh_size"])[name]


def _build_fe(params: dict, workdir: Path) -> tuple[Component, dict]:
    """gmsh geometry (meshes/) -> dolfinx FE model (fem/) -> Component; unit thermal loads
    (alpha * delta_T = 1) of every volume group for the cryo preload."""
    from . import fe_source

    return fe_source.build_component(params, workdir)


def component_stage(model: dict, name: str, cache: StageCache, workdir: Path) -> tuple[Component, dict, str]:
    params = _component_params(model, name)
    code = ("liftoff.workflows.stick", "liftoff.reduction", "liftoff.core") if model["source"] == "stick" else \
        ("liftoff.meshes", "liftoff.fem", "liftoff.reduction.component", "liftoff.workflows.fe_source", "liftoff.core")
    key = stage_key("component", params, code)
    thermal_path = cache.path("thermal", key, ".npz")

    def build():
        comp, thermal = (_build_stick(params) if model["source"] == "stick" else _build_fe(params, workdir))
        if thermal_path is not None:
            thermal_path.parent.mkdir(parents=True, exist_ok=True)
            save_arrays({f"vol_{k}": v for k, v in thermal.items()}, thermal_path)
        return comp, thermal

    def load(p):
        comp = load_component(p)
        if thermal_path is None or not thermal_path.is_file():
            raise FileNotFoundError(thermal_path)
        th = {k[4:]: v for k, v in load_arrays(thermal_path).items()}
        return comp, th

    comp, thermal = cache.get_or_build("fe" if model["source"] == "fe" else "stick", key, ".npz", build,
                                       lambda out, p: save_component(out[0], p), load, label=name)
    return comp, thermal, key


def cb_stage(model: dict, name: str, comp: Component, comp_key: str, cache: StageCache) -> tuple[CBModel, str]:
    sel = model["component"].get(name, {}) if name != "pad" else model.get("pad", {})
    params = {"boundary": points_labels(boundary_points(comp)), "n_modes": sel.get("n_modes"),
              "f_max": sel.get("f_max", None if sel.get("n_modes") is not None else DEFAULT_F_MAX[name])}
    key = stage_key("cb", params, ("liftoff.reduction", "liftoff.core"), (comp_key,))
    cb = cache.get_or_build("cb", key, ".npz",
                            lambda: craig_bampton(comp, params["boundary"], params["n_modes"], params["f_max"]),
                            lambda out, p: out.save(p, recovery=True), load_cb, label=name)
    return cb, key


def modes_stage(asm: Assembly, n_rigid: int, f_max, keys: list[str], cache: StageCache, label: str) -> SystemModes:
    key = stage_key("system", {"n_rigid": n_rigid, "f_max": f_max}, ("liftoff.reduction", "liftoff.core"), tuple(keys))

    def build():
        return system_modes(asm, n_rigid=n_rigid, f_max=f_max)

    def save(sm, p):
        save_arrays({"omega": sm.omega, "phi": sm.phi, "n_rigid": np.array(sm.n_rigid)}, p)

    def load(p):
        z = load_arrays(p)
        if z["phi"].shape[0] != asm.n_dof:
            raise ValueError("cached system modes do not match the assembly")
        return SystemModes(asm, z["omega"], z["phi"], int(z["n_rigid"]))

    return cache.get_or_build("system", key, ".npz", build, save, load, label=label)


# ------------------------------------------------------------------ the stack
def build_stack(model: dict, cache: StageCache, progress: bool = True) -> StackModel:
    """All model stages for a validated ``[model]`` table (workflows.scenario)."""
    from tqdm import tqdm

    t0 = time.perf_counter()
    comps, cbs, ckeys, thermal = {}, {}, {}, {}
    names = list(VEHICLE) + ["pad"]
    with tempfile.TemporaryDirectory(prefix="liftoff-geom-") as work:
        bar = tqdm(names, desc="model stages", unit="component", disable=not progress, leave=False)
        for name in bar:
            bar.set_postfix_str(name)
            comps[name], thermal[name], k = component_stage(model, name, cache, Path(work))
            cbs[name], ckeys[name] = cb_stage(model, name, comps[name], k, cache)
    t1 = time.perf_counter()
    sysp = model.get("system", {})
    vasm = assemble([cbs[n] for n in VEHICLE], "vehicle")
    vmodes = modes_stage(vasm, 6, sysp.get("f_max"), [ckeys[n] for n in VEHICLE], cache, "vehicle")
    if sysp.get("n_modes") and vmodes.n_modes > sysp["n_modes"]:
        vmodes = SystemModes(vasm, vmodes.omega[: sysp["n_modes"]], vmodes.phi[:, : sysp["n_modes"]], 6)
    body0 = vmodes.to_body(zeta=model["zeta"], name="vehicle")
    _, cg = center_of_gravity(body0)
    vehicle = vmodes.to_body(ref_point=cg, zeta=model["zeta"], name="vehicle")
    pasm = assemble([cbs["pad"]], "pad")
    pmodes = modes_stage(pasm, 0, sysp.get("pad_f_max"), [ckeys["pad"]], cache, "pad")
    if sysp.get("pad_n_modes") and pmodes.n_modes > sysp["pad_n_modes"]:
        pmodes = SystemModes(pasm, pmodes.omega[: sysp["pad_n_modes"]], pmodes.phi[:, : sysp["pad_n_modes"]], 0)
    pad = pmodes.to_body(zeta=model["zeta"], name="pad")
    unit = {}
    for name in names:
        cb = cbs[name]
        unit[name] = {vol: cb.boundary_load(f) for vol, f in thermal[name].items()}
    t2 = time.perf_counter()
    return StackModel(comps, cbs, vasm, vmodes, vehicle, pasm, pmodes, pad, unit,
                      timings={"components+CB (s)": t1 - t0, "system modes (s)": t2 - t1})


def cryo_loads(stack: StackModel, cryo: dict) -> dict[str, float]:
    """{vehicle label: force} of the cryo preload (section 4.3): the tank's free thermal
    strain alpha * delta_T reduced to the component's boundary DOFs only."""
    from liftoff.transient.effects import cryo_point_loads

    if not cryo.get("enabled"):
        return {}
    name = cryo["component"]
    if name not in stack.cbs or name == "pad":
        raise InputError(f"cryo.component: {name!r} is not a vehicle component ({', '.join(VEHICLE)})")
    avail = stack.unit_thermal[name]
    parts = []
    for vol in cryo["volumes"]:
        if vol not in avail:
            raise InputError(f"cryo.volumes: {vol!r} is not a volume of component {name!r} "
                             f"(has: {', '.join(sorted(avail)) or 'none'})")
        parts.append((stack.cbs[name].boundary_labels, cryo["alpha"] * cryo["delta_T"] * avail[vol]))
    return cryo_point_loads(parts)
