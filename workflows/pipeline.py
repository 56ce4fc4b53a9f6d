"""Model stages of the lift-off workflow: geometry -> FE (or stick) -> Craig-Bampton ->
system modes -> the two modal bodies (vehicle, pad) of the transient (sections 3.0, 4.2).

Each stage is cached under a hash of its inputs (workflows/cache.py), so a run that
changes only loads or cases loads the reduced models instead of meshing and solving.
The vehicle is the free-free assembly of the scenario's components (``[model.component]``,
in the order given) overlaid on their joints (``[[model.joint]]``: shared points); the pad
is a grounded component reduced to its hold-down posts. Every named point of a component (spider
reference point, stick node with a name) is a Craig-Bampton boundary point (section
3.0: interfaces, contact points and large-load points stay discrete).
"""
from __future__ import annotations

import os
import tempfile
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np
from liftoff.reduction import (
    Assembly,
    CBModel,
    Component,
    SystemModes,
    TruncationCheck,
    assemble,
    craig_bampton,
    keep_modes,
    load_cb,
    load_component,
    save_component,
    system_modes,
    truncation_check,
)
from liftoff.reduction.checks import with_own_inertia
from liftoff.transient.body import ModalBody
from liftoff.transient.effects import center_of_gravity
from threadpoolctl import threadpool_limits

from liftoff.config.model import PAD, ComponentModel, ModelConfig
from liftoff.config.sections import Cryo
from liftoff.config.values import Where
from liftoff.core.labels import named_points, points_labels
from liftoff.core.records import file_sha256, sweep_stale, temp_prefix

from .cache import StageCache, load_arrays, save_arrays, stage_key
from .parallel import on_root


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
    vehicle_all: SystemModes | None = None         # every system mode (None: the kept ones are all)
    pad_all: SystemModes | None = None
    timings: dict = field(default_factory=dict)
    key: str = ""         # what made it (its stages' keys, the modes kept, zeta); "": unknown
    # the memo of this stack's own model (a stack made by dataclasses.replace starts without it)
    _products: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    def product(self, key: tuple, build: Callable[[], Any]) -> Any:
        """``build()``, computed once per ``key`` for this stack: what depends on the model
        alone (a recovery matrix of its modes), which every case on it would otherwise rebuild
        (a campaign's worker runs hundreds of cases on one stack). The product is shared: its
        users must not change it in place."""
        if key not in self._products:
            self._products[key] = build()
        return self._products[key]

    def truncation(self, contact_a, contact_b, attach) -> tuple[TruncationCheck, TruncationCheck]:
        """The truncation checks (reduction/truncation.py) of the vehicle at its contact
        labels ``contact_a`` and attach labels ``attach``, and of the pad at ``contact_b``;
        computed once per set of labels."""
        contact_b = [lab for lab in contact_b if lab is not None]     # None: a post on rigid ground
        return self.product(("truncation", tuple(contact_a), tuple(contact_b), tuple(attach)), lambda: (
            truncation_check(self.vehicle_all or self.vehicle_modes, self.vehicle_modes,
                             list(contact_a) + list(attach), contact_a, "vehicle"),
            truncation_check(self.pad_all or self.pad_modes, self.pad_modes, contact_b, contact_b, "pad")))


def boundary_points(component: Component) -> list[str]:
    """Named points of a component (liftoff.core.labels.is_named_point): its CB boundary."""
    return named_points(component.points)


def boundary_labels(component: Component) -> list[str]:
    """The DOF labels of a component's CB boundary, point-major: the six of each named
    point, less those it does not have (a pinned strut's end rotations)."""
    have = set(component.dof_labels)
    return [lab for lab in points_labels(boundary_points(component)) if lab in have]


# ------------------------------------------------------------------ components
def component_materials(model: ModelConfig, name: str) -> dict:
    """The [model.materials] entries that may apply to component ``name``: the builders name
    their volume groups after their component (``srb_left_case``, ``pad_deck``, ...), so a
    volume named after another component is not this one's; a volume named after none may be
    any component's and counts for all."""
    others = [n for n in model.components if n != name and not name.startswith(n + "_")]
    return {vol: m for vol, m in model.materials.items()
            if vol.startswith(name + "_") or not any(vol.startswith(n + "_") for n in others)}


def _component_key(model: ModelConfig, comp: ComponentModel) -> dict:
    """Everything a component stage depends on (its cache key's parameters); of the materials,
    those that may apply to it (:func:`component_materials`), so that changing one component's
    material rebuilds that component only; a mirror's: its plane and its source's."""
    if comp.mirror is not None:
        return {"name": comp.name, "mirror": asdict(comp.mirror),
                "source": _component_key(model, model.components[comp.mirror.of])}
    liquid = {}                         # what a hydroelastic liquid's model depends on (a tank's, or a user file's)
    if getattr(comp.builder, "liquid", "") == "hydroelastic" or getattr(comp.builder, "liquids", None):
        liquid = {"convective": model.convective,
                  **({"slosh_gravity": model.slosh_gravity} if model.convective == "slosh" else {})}
    return {"source": model.source, "name": comp.name, "type": comp.type, "mesh_size": comp.mesh_size,
            "degree": model.degree, "builder": {type(comp.builder).__name__: asdict(comp.builder)},
            "materials": {vol: asdict(m) for vol, m in component_materials(model, comp.name).items()}, **liquid}


@threadpool_limits.wrap(limits=1, user_api="blas")
def build_component(model: ModelConfig, comp: ComponentModel, workdir: Path) -> tuple[Component, dict]:
    """Component and {volume: unit thermal load} from the beam stick model (workflows/stick.py)
    or from gmsh geometry -> dolfinx FE model (workflows/fe_source.py). BLAS on one thread:
    the same products, bit for bit, in any process (the run's, a pool worker's, an MPI
    rank's; the default core's K differed in round-off and in 144 of its 6.6e6 entries
    between one thread and two), at no cost in time (13.5 s either way)."""
    if model.source == "stick":
        from .stick import build

        return build(comp.name, comp.builder, comp.mesh_size, model.max_elements)
    t = component_types_of(comp)
    if t is not None and t.matrices:           # a type that gives its matrices directly (beam)
        return t.matrices_builder()(comp.builder, comp.name)
    from . import fe_source

    return fe_source.build_component(comp, model, workdir)


def component_types_of(comp: ComponentModel):
    """The registered type of a component (None: a Nastran import, or no type)."""
    if not comp.type or comp.nastran is not None:
        return None
    from liftoff.config import component_types

    return component_types.types().get(comp.type)


def given_model(comp: ComponentModel):
    """The function giving the component's CB model directly (a registered type with
    ``model``, such as rigid_mass), or None (built, imported from Nastran, or a stick)."""
    t = component_types_of(comp)
    return None if t is None else t.model_builder()


def is_fe_component(model: ModelConfig, name: str) -> bool:
    """Whether component ``name`` is built by the model's FE (or stick) stages: neither a
    Nastran import, a type whose CB model is given, nor a mirror (its source's reflected)."""
    comp = model.components[name]
    return comp.mirror is None and comp.nastran is None and given_model(comp) is None


def component_key(model: ModelConfig, name: str) -> str:
    """The cache key of the component stage of ``name``."""
    code = (("liftoff.workflows.stick", "liftoff.meshes", "liftoff.reduction", "liftoff.core") if model.source == "stick"
            else ("liftoff.meshes", "liftoff.fem", "liftoff.reduction", "liftoff.workflows.fe_source", "liftoff.core"))
    t = component_types_of(model.components[name])
    if t is not None:       # a type's own builder, a plug-in's outside these packages too
        code += tuple(sorted({f.split(":")[0] for f in (t.build, t.matrices, t.model) if f}))
    return stage_key("component", _component_key(model, model.components[name]), code)


def _thermal_path(p: Path) -> Path:
    """The unit thermal loads' file beside a component stage's product."""
    return p.with_name(p.name.replace(".npz", ".thermal.npz"))


def _save_component_stage(out, p: Path) -> None:
    save_component(out[0], p)
    save_arrays({f"vol_{k}": v for k, v in out[1].items()}, _thermal_path(p))


def _load_component_stage(p: Path):
    return load_component(p, mmap=True), {k[4:]: v for k, v in load_arrays(_thermal_path(p)).items()}


def component_stage(model: ModelConfig, name: str, cache: StageCache, workdir: Path,
                    source: tuple | None = None) -> tuple[Component, dict, str]:
    """(Component, {volume: unit thermal load}, key) of component ``name``: built (or from
    the cache); a mirror's from its source's (``source``: that stage's product when the
    caller has it, else this function's own for the source)."""
    comp = model.components[name]
    if comp.mirror is not None:
        return _mirror_component_stage(model, name, cache, workdir, source)
    key = component_key(model, name)
    out, thermal = cache.get_or_build(model.source, key, ".npz", lambda: build_component(model, comp, workdir),
                                      _save_component_stage, _load_component_stage, label=name)
    return out, thermal, key


_MIRROR_CODE = ("liftoff.reduction.mirror", "liftoff.reduction.component", "liftoff.reduction.craig_bampton",
                "liftoff.core")


def _mirror_component_stage(model: ModelConfig, name: str, cache: StageCache, workdir: Path,
                            source: tuple | None) -> tuple[Component, dict, str]:
    """A mirror's Component: its source's reflected (liftoff.reduction.mirror), cached so that a
    process that never uses its matrices never reads them, as a built one's."""
    from liftoff.reduction.mirror import mirror_component, mirror_load, renamer

    mir = model.components[name].mirror
    src, src_thermal, src_key = source or component_stage(model, mir.of, cache, workdir)
    key = stage_key("mirror", {"name": name, "of": mir.of, "normal": mir.normal}, _MIRROR_CODE, (src_key,))
    rename = renamer(mir.of, name)

    def build():
        return (mirror_component(src, name, mir.normal, rename),
                {rename(vol): mirror_load(src, f, mir.normal) for vol, f in src_thermal.items()})

    out, thermal = cache.get_or_build(model.source, key, ".npz", build, _save_component_stage, _load_component_stage,
                                      label=name)
    return out, thermal, key


def cb_solver(model: ModelConfig):
    """(solver, its code modules, its name) of the Craig-Bampton stage: PETSc/MUMPS,
    distributed over the run's processes, for FE components (fem.petsc_solver); the
    default numpy/scipy solver for the stick model's small matrices."""
    if model.source == "stick":
        return None, (), "scipy"
    from liftoff.fem import petsc_solver
    from liftoff.fem.parallel import fe_comm

    from .parallel import world

    return petsc_solver(fe_comm(world())), *_cb_solver_id(model)


def _cb_solver_id(model: ModelConfig) -> tuple[tuple, str]:
    """(code modules, name) of the CB stage's solver (part of its cache key)."""
    if model.source == "stick":
        return (), "scipy"
    return ("liftoff.fem.petsc_cb", "liftoff.fem.block_lanczos", "liftoff.fem.petsc_backend"), "petsc"


def _cb_key(model: ModelConfig, name: str, comp: Component, comp_key: str) -> tuple[str, dict]:
    """(cache key, parameters) of the CB stage of component ``name``."""
    sel = model.components[name]
    solver_code, solver_name = _cb_solver_id(model)
    params = {"boundary": boundary_labels(comp), "n_modes": sel.n_modes, "f_max": sel.f_max,
              "solver": solver_name}
    if sel.residual_vectors:            # (only when asked: the keys of models without them unchanged)
        params["residual_vectors"] = True
    return stage_key("cb", params, ("liftoff.reduction", "liftoff.core", *solver_code), (comp_key,)), params


def _load_cached_cb(path) -> CBModel:
    """A cached CB product, its large arrays mapped (the entry's checksums were checked)."""
    return load_cb(path, mmap=True)


def cb_stage(model: ModelConfig, name: str, comp: Component, comp_key: str, cache: StageCache,
             source: tuple | None = None) -> tuple[CBModel, str]:
    """The CB model of a component (from the cache, or reduced with :func:`cb_solver`: a
    cached Component is enough, the PETSc matrices are built from it); a mirror's is its
    source's reflected, no eigensolve (``source``: the source's (Component, component key,
    CBModel, CB key) when the caller has them)."""
    if model.components[name].mirror is not None:
        return _mirror_cb_stage(model, name, comp_key, cache, source)
    key, params = _cb_key(model, name, comp, comp_key)
    sel = model.components[name]
    solver = cb_solver(model)[0]
    cb = cache.get_or_build("cb", key, ".npz",
                            lambda: craig_bampton(comp, params["boundary"], params["n_modes"], params["f_max"],
                                                  solver=solver, residual_vectors=sel.residual_vectors),
                            lambda out, p: out.save(p, recovery=True), _load_cached_cb, label=name)
    return cb, key


def _mirror_cb_stage(model: ModelConfig, name: str, comp_key: str, cache: StageCache,
                     source: tuple | None) -> tuple[CBModel, str]:
    from liftoff.reduction.mirror import mirror_cb, renamer

    mir = model.components[name].mirror
    if source is None:
        with tempfile.TemporaryDirectory() as work:
            src_comp, _, src_key = component_stage(model, mir.of, cache, Path(work))
        src_cb, src_ckey = cb_stage(model, mir.of, src_comp, src_key, cache)
    else:
        src_comp, src_key, src_cb, src_ckey = source
    key = stage_key("cb-mirror", {"name": name, "of": mir.of, "normal": mir.normal}, _MIRROR_CODE,
                    (src_ckey, comp_key))
    cb = cache.get_or_build("cb", key, ".npz",
                            lambda: mirror_cb(src_cb, name, mir.normal, renamer(mir.of, name), source_component=src_comp),
                            lambda out, p: out.save(p, recovery=True), _load_cached_cb, label=name)
    return cb, key


def nastran_stage(model: ModelConfig, name: str, cache: StageCache) -> tuple[CBModel, str]:
    """A component from a Nastran CB model (liftoff.reduction.nastran), its fixed-interface
    modes selected like an FE component's; cached under the SHA-256 of the files it reads."""
    from liftoff.reduction.nastran import NastranRecovery, import_nastran

    sel = model.components[name]
    src = sel.nastran
    params = {"name": name, "files": {f: file_sha256(f) for f in src.files()}, "units": src.units,
              "grids": src.grid_names,
              "options": src.options, "recovery": list(src.recovery), "n_modes": sel.n_modes, "f_max": sel.f_max}
    key = stage_key("nastran", params, ("liftoff.reduction", "liftoff.core"))

    def build():
        recovery = [NastranRecovery(**r) for r in src.recovery]
        cb = import_nastran(src.file, name=name, units=src.units, grid_names=src.grid_names, **src.options,
                            **({"recovery": recovery} if recovery else {}))
        return cb.select_modes(sel.n_modes, sel.f_max)

    cb = cache.get_or_build("nastran", key, ".npz", build, lambda out, p: out.save(p, recovery=True), _load_cached_cb,
                            label=name)
    return cb, key


def vehicle_assembly(model: ModelConfig, cbs: dict) -> Assembly:
    """The vehicle's CB components overlaid on their joints, in the model's order, the
    joints' released DOFs kept apart (reduction.assembly)."""
    return assemble([cbs[n] for n in model.vehicle], "vehicle", [r for j in model.joints for r in j.released()])


def system_key(n_rigid: int, keys: list[str], assembly_params: dict | None = None) -> str:
    """The cache key of :func:`modes_stage` (its arguments' meaning there)."""
    return stage_key("system", {"n_rigid": n_rigid, **(assembly_params or {})},
                     ("liftoff.reduction.system", "liftoff.reduction.assembly", "liftoff.core"), tuple(keys))


def modes_stage(asm: Assembly, n_rigid: int, keys: list[str], cache: StageCache, label: str,
                assembly_params: dict | None = None) -> SystemModes:
    """Every system mode of an assembly (cached); the cut, if any, is :func:`keep_modes`'.
    ``assembly_params``: what, besides the components' keys, made the assembly (a
    joint's released DOFs)."""
    key = system_key(n_rigid, keys, assembly_params)

    def build():
        return system_modes(asm, n_rigid=n_rigid)

    def save(sm, p):
        save_arrays({"omega": sm.omega, "phi": sm.phi, "n_rigid": np.array(sm.n_rigid)}, p)

    def load(p):
        z = load_arrays(p)
        if z["phi"].shape[0] != asm.n_dof:
            raise ValueError("cached system modes do not match the assembly")
        return SystemModes(asm, z["omega"], z["phi"], int(z["n_rigid"]))

    return cache.get_or_build("system", key, ".npz", build, save, load, label=label)


# ------------------------------------------------------------------ concurrent CB stages
#: environment variable: the most processes that reduce components at once (1: one after another)
WORKERS_ENV = "LIFTOFF_MODEL_WORKERS"


def model_workers(requested: int | None = None) -> int:
    """Processes for the Craig-Bampton stages of a run: ``requested``, else
    $LIFTOFF_MODEL_WORKERS, else the machine's cores (at least 1)."""
    if requested is None:
        env = os.environ.get(WORKERS_ENV, "").strip()
        if env:
            try:
                requested = int(env)
            except ValueError:
                from liftoff.core.errors import InputError

                raise InputError(f"${WORKERS_ENV} = {env!r}: not a whole number of processes") from None
        else:
            requested = os.cpu_count() or 1
    return max(1, int(requested))


def _stages_worker(model: ModelConfig, name: str, cache_root: str) -> list:
    """In a worker process (a serial run's pool, or an MPI rank's own worker): the FE stage
    (a hit when it is already in the cache) and the CB stage of component ``name`` into the
    cache at ``cache_root``, serially; returns the worker's cache log (plain tuples). BLAS
    on one thread: the workers share the cores."""
    with threadpool_limits(limits=1, user_api="blas"), tempfile.TemporaryDirectory() as work:
        cache = StageCache(Path(cache_root))
        comp, _, key = component_stage(model, name, cache, Path(work))
        cb_stage(model, name, comp, key, cache)
        return [tuple(e) for e in cache.log]


def _cb_cached(model: ModelConfig, name: str, comp: Component, comp_key: str, cache: StageCache) -> bool:
    """Whether the CB stage of ``name`` has a cache entry (its record file; the stage checks it)."""
    return cache.has("cb", _cb_key(model, name, comp, comp_key)[0], ".npz")


def reduce_concurrently(model: ModelConfig, todo: list[str], cache: StageCache, workers: int,
                        bar=None) -> dict[str, list]:
    """The FE and CB stages of the FE components ``todo`` (each with a stage not yet in the
    cache) on a pool of ``workers`` processes (spawned; each runs a component's two stages
    serially, :func:`_stages_worker`), written to the cache, from which :func:`component_stage`
    and :func:`cb_stage` then load them. The components with a hydroelastic liquid (the wet
    eigenproblem, the most modes) are started first. Serial runs with a cache only; a worker
    that fails leaves its component to the sequential stages, which give its error. Returns
    {component: the worker's cache log}."""
    if workers < 2 or len(todo) < 2 or cache.root is None or cache.comm.size > 1 or model.source != "fe":
        return {}
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor, as_completed

    from .executors import die_with_parent

    todo.sort(key=lambda n: getattr(model.components[n].builder, "liquid", "") != "hydroelastic")
    logs = {}
    with ProcessPoolExecutor(max_workers=min(workers, len(todo)), mp_context=multiprocessing.get_context("spawn"),
                             initializer=die_with_parent) as pool:
        futures = {pool.submit(_stages_worker, model, n, str(cache.root)): n for n in todo}
        for fut in as_completed(futures):
            name = futures[fut]
            try:
                logs[name] = fut.result()
            except Exception:  # noqa: BLE001 - the sequential stages redo it and say why it fails
                continue
            if bar is not None:
                bar.set_postfix_str(f"fe + cb {name}")
    return logs


def _built_entries(log: list, stage: str) -> list:
    """The entries of a worker's cache ``log`` where it built ``stage`` (its time, not the load's)."""
    return [e for e in log if e[0] == stage and e[2] != "hit"]


#: under mpirun: "concurrent" (components shared out over the ranks, each reduced by one
#: rank alone) or "distributed" (each component over all ranks, one after another)
MPI_COMPONENTS_ENV = "LIFTOFF_MPI_COMPONENTS"


def _claim(folder: Path, tag: str) -> bool:
    """Whether this process is the first to claim ``tag`` (a file created exclusively); a
    file that cannot be made (taken, or a full disk) is not claimed."""
    try:
        os.close(os.open(folder / tag, os.O_CREAT | os.O_EXCL | os.O_WRONLY))
        return True
    except OSError:
        return False


def _needs_stages(model: ModelConfig, name: str, cache: StageCache, comp: Component | None = None) -> bool:
    """Whether FE component ``name`` has a model stage not yet in the cache: its component
    stage, or its CB stage (whose key needs the component: ``comp`` when the caller has loaded
    it, else loaded here, never rebuilt; an entry that does not load is left to the worker,
    which rebuilds it)."""
    key = component_key(model, name)
    if comp is None:
        if not cache.has(model.source, key, ".npz"):
            return True
        try:
            comp = load_component(cache.path(model.source, key, ".npz"))
        except Exception:  # noqa: BLE001 - damaged: the worker's stage rebuilds it (with its warning)
            return True
    return not _cb_cached(model, name, comp, key, cache)


#: the environment of an MPI rank's process that would make a child process join the job
MPI_JOB_VARS = ("OMPI_", "PMIX_", "PMI_", "MPI_LOCALNRANKS", "MPI_LOCALRANKID")


def _rank_worker_init() -> None:
    """Initializer of a rank's worker process: a serial process, not a member of the MPI job
    (the job's variables dropped before anything imports mpi4py), that dies with the rank."""
    from .executors import die_with_parent

    die_with_parent()
    drop_job_vars(os.environ)


def drop_job_vars(environ) -> None:
    """Remove the MPI job's variables (:data:`MPI_JOB_VARS`) from ``environ`` in place."""
    for k in [k for k in environ if k.startswith(MPI_JOB_VARS)]:
        del environ[k]


def reduce_over_ranks(model: ModelConfig, names: list[str], cache: StageCache, bar=None) -> dict:
    """Under mpirun with a stage cache: the FE and CB stages of the components not yet in
    it, shared out over the ranks. Each rank claims the next unclaimed component (a file in
    the cache folder) and has a worker process of its own run both stages serially,
    writing the cache as a serial run does; the ranks then meet, and the run loads every
    product from the cache. The worker is a plain serial process, outside the MPI job, so
    the ranks' own processes hold the same PETSc objects (none of these builds'), as their
    collective finalisation needs. Only with at least as many such components as ranks
    (else they are distributed over all ranks, one after another) and unless
    $LIFTOFF_MPI_COMPONENTS is "distributed". A component that fails here is left to the
    collective stages, which give its error on every rank. Returns {component: the cache
    log of its two stages, "(rank r)" in the labels of other ranks than 0}."""
    comm = cache.comm
    mode = os.environ.get(MPI_COMPONENTS_ENV, "concurrent").strip() or "concurrent"
    if mode not in ("concurrent", "distributed"):
        from liftoff.core.errors import InputError

        raise InputError(f"${MPI_COMPONENTS_ENV} = {mode!r}: give 'concurrent' or 'distributed'")
    fe = [n for n in names if is_fe_component(model, n)]
    if comm.size < 2 or cache.root is None or model.source != "fe" or mode == "distributed" or not fe:
        return {}
    todo = on_root(comm, lambda: [n for n in fe if _needs_stages(model, n, cache)])
    if len(todo) < comm.size:
        return {}
    import multiprocessing
    import uuid
    from concurrent.futures import ProcessPoolExecutor

    from .parallel import all_or_none, wait_for_all

    folder = Path(cache.root) / "claims"
    run = comm.bcast(uuid.uuid4().hex if comm.rank == 0 else None)
    probe = folder / f"{run}-probe"
    made = on_root(comm, lambda: _claim_folder(folder, probe))
    # every rank must see rank 0's probe in a folder it can write: one shared cache (else, or
    # a cache that cannot be written, the components go over all ranks, distributed)
    if not all(comm.allgather(made and probe.is_file() and os.access(folder, os.W_OK))):
        on_root(comm, lambda: _remove_claims(folder, run), share=False)
        return {}
    logs, failed = {}, None
    try:
        with ProcessPoolExecutor(max_workers=1, mp_context=multiprocessing.get_context("spawn"),
                                 initializer=_rank_worker_init) as pool:
            for i, name in enumerate(todo):
                if not _claim(folder, f"{run}-{i}"):
                    continue
                if bar is not None:
                    bar.set_postfix_str(f"fe + cb {name} (rank {comm.rank})")
                try:
                    log = pool.submit(_stages_worker, model, name, str(cache.root)).result()
                except Exception:  # noqa: BLE001 - the collective stages redo it and say why it fails
                    continue
                tag = "" if comm.rank == 0 else f" (rank {comm.rank})"
                logs[name] = [(st, f"{lab}{tag}", how, t) for st, lab, how, t in log]
    except BaseException as exc:  # noqa: BLE001 - raised below on every rank, not on this one alone
        failed = exc
    wait_for_all(comm)                      # asleep, not spinning, while other ranks' workers build
    parts = comm.allgather(logs)
    on_root(comm, lambda: _remove_claims(folder, run), share=False)
    all_or_none(comm, failed)
    merged = {}
    for part in parts:
        merged.update(part)
    return merged


def _claim_folder(folder: Path, probe: Path) -> bool:
    """The claims folder with a probe file in it (False: it cannot be made)."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
        return _claim(folder, probe.name)
    except OSError:
        return False


def _remove_claims(folder: Path, run: str) -> None:
    """The claim files of run ``run`` removed (what cannot be removed is left)."""
    for p in folder.glob(f"{run}-*"):
        try:
            p.unlink()
        except OSError:
            pass


# ------------------------------------------------------------------ the stack
def build_stack(model: ModelConfig, cache: StageCache, progress: bool = True, where: Where | None = None,
                workers: int | None = None) -> StackModel:
    """All model stages of a checked ``[model]`` (liftoff.config.ModelConfig); ``where``
    names the scenario's ``model`` key in messages. The FE and Craig-Bampton stages not in
    the cache of a serial run run on :func:`model_workers` processes (``workers``; each
    component's two stages on one: :func:`reduce_concurrently`); under mpirun the
    components are shared out over the ranks (:func:`reduce_over_ranks`). The products are
    then loaded from the cache (mapped)."""
    from tqdm import tqdm

    t0 = time.perf_counter()
    comps, cbs, ckeys, thermal, comp_keys = {}, {}, {}, {}, {}
    names = list(model.vehicle) + [PAD]
    on_root(cache.comm, lambda: sweep_stale(tempfile.gettempdir()), share=False)   # geometry folders of killed runs
    with tempfile.TemporaryDirectory(prefix=temp_prefix("liftoff-geom")) as work:
        bar = tqdm(total=2 * len(names), desc="model stages", unit="stage", disable=not progress or cache.comm.rank != 0,
                   leave=False)
        fe = [n for n in names if is_fe_component(model, n)]

        def fe_stage(name: str) -> None:
            bar.set_postfix_str(f"fe {name}")
            comps[name], thermal[name], comp_keys[name] = component_stage(model, name, cache, Path(work))
            built = _built_entries(logs.get(name, []), model.source)
            if built and cache.log and cache.log[-1][2] == "hit":
                cache.log[-1:] = built              # the time its worker took, not the load
            bar.update()

        # the stages not in the cache: shared out over the ranks (under mpirun), else on a
        # process pool: the components whose FE stage is missing, or (FE stage loaded) its CB stage
        logs = reduce_over_ranks(model, names, cache, bar)
        if cache.comm.size == 1:
            for name in fe:
                if cache.has(model.source, component_key(model, name), ".npz"):
                    fe_stage(name)
            todo = [n for n in fe if _needs_stages(model, n, cache, comps.get(n))]
            logs = reduce_concurrently(model, todo, cache, model_workers(workers), bar)
        mirrors = [n for n in names if model.components[n].mirror is not None]
        for name in names:
            if name in fe and name not in comps:
                fe_stage(name)
            elif name not in fe and name not in mirrors:
                bar.update()
        for name in mirrors:                 # their sources' products reflected (liftoff.reduction.mirror)
            bar.set_postfix_str(f"mirror {name}")
            of = model.components[name].mirror.of
            comps[name], thermal[name], comp_keys[name] = component_stage(
                model, name, cache, Path(work), source=(comps[of], thermal[of], comp_keys[of]))
            bar.update()
        for name in [n for n in names if n not in mirrors] + mirrors:
            bar.set_postfix_str(f"cb {name}")
            given = given_model(model.components[name])
            of = model.components[name].mirror.of if name in mirrors else None
            if of is not None:
                cbs[name], ckeys[name] = cb_stage(model, name, comps[name], comp_keys[name], cache,
                                                  source=(comps[of], comp_keys[of], cbs[of], ckeys[of]))
            elif model.components[name].nastran is not None:
                cbs[name], ckeys[name] = nastran_stage(model, name, cache)
                thermal[name] = {}
            elif given is not None:          # a type whose CB model is given (rigid_mass): no stage to cache
                comp = model.components[name]
                cbs[name] = given(comp.builder, name)
                ckeys[name] = stage_key("given", {"name": name, "type": comp.type, "params": asdict(comp.builder)},
                                        ("liftoff.reduction", "liftoff.core"))
                thermal[name] = {}
            else:
                cbs[name], ckeys[name] = cb_stage(model, name, comps[name], comp_keys[name], cache)
                built = _built_entries(logs.get(name, []), "cb")
                if built and cache.log and cache.log[-1][2] == "hit":
                    cache.log[-1:] = built          # the time its worker took, not the load
            bar.update()
        bar.close()
    t1 = time.perf_counter()
    _check_materials(model, thermal, where or Where("scenario", "model"))
    _check_joints(model, cbs, where or Where("scenario", "model"))
    vasm, vmodes, vehicle, pasm, pmodes, pad, unit, vall, pall = _bodies(model, cbs, ckeys, thermal, cache,
                                                                         comps.get(PAD))
    t2 = time.perf_counter()
    comps = {n: comps[n] for n in names if n in comps}     # the model's order, whichever stages were cached
    cbs = {n: cbs[n] for n in names}                        # (and whichever came last: the mirrors)
    return StackModel(comps, cbs, vasm, vmodes, vehicle, pasm, pmodes, pad, unit, vall, pall,
                      timings={"components+CB (s)": t1 - t0, "system modes (s)": t2 - t1},
                      key=stack_key(model, vasm, ckeys))


def stack_key(model: ModelConfig, vasm: Assembly, ckeys: dict) -> str:
    """The key of what :func:`build_stack` makes of ``model``: the two bodies' system-mode
    keys (the components' stage keys, the joints' releases), the modes kept, the damping and
    the code that turns system modes into bodies (keys the stack's cached outputs,
    workflows/outputs.py)."""
    args = _system_args(model, vasm, ckeys)
    return stage_key("stack", {"system": asdict(model.system), "zeta": model.zeta},
                     ("liftoff.workflows.pipeline", "liftoff.reduction", "liftoff.transient.effects"),
                     (system_key(*args["vehicle"]), system_key(*args["pad"])))


def _system_args(model: ModelConfig, vasm: Assembly, ckeys: dict) -> dict[str, tuple[int, list[str], dict]]:
    """(rigid-body modes, component keys, assembly parameters) of the vehicle's and the pad's
    system-mode stages (:func:`modes_stage`, :func:`system_key`)."""
    released = sorted(vasm.released)
    return {"vehicle": (6, [ckeys[n] for n in model.vehicle], {"released": released} if released else {}),
            "pad": (0, [ckeys[PAD]], {})}


@threadpool_limits.wrap(limits=1, user_api="blas")   # the same arithmetic in any process (campaign workers)
def _bodies(model: ModelConfig, cbs: dict, ckeys: dict, thermal: dict, cache: StageCache, pad_fe=None):
    """Assemblies, system modes (all of them cached; those kept with their residual vectors,
    reduction/truncation.py) and the two modal bodies; the unit thermal loads reduced to
    each component's boundary. ``pad_fe``: the pad's FE component, whose own rigid-body field
    gives the grounded pad's gravity loads and mass (reduction.checks.with_own_inertia; None, a
    pad without one: the boundary's geometric RB)."""
    names = list(model.vehicle) + [PAD]
    sysp = model.system
    vasm = vehicle_assembly(model, cbs)
    args = _system_args(model, vasm, ckeys)
    n_rigid, keys, params = args["vehicle"]
    vall = modes_stage(vasm, n_rigid, keys, cache, "vehicle", params)
    vmodes = keep_modes(vall, sysp.f_max, sysp.n_modes, sysp.residual_vectors)
    body0 = vmodes.to_body(zeta=model.zeta, name="vehicle")
    _, cg = center_of_gravity(body0)
    vehicle = vmodes.to_body(ref_point=cg, zeta=model.zeta, name="vehicle")
    pasm = assemble([cbs[PAD]], "pad")
    pasm = with_own_inertia(pasm, PAD, pad_fe, cbs[PAD])      # grounded: its own rigid-body field's loads
    n_rigid, keys, params = args["pad"]
    pall = modes_stage(pasm, n_rigid, keys, cache, "pad", params)
    pmodes = keep_modes(pall, sysp.pad_f_max, sysp.pad_n_modes, sysp.residual_vectors)
    pad = pmodes.to_body(zeta=model.zeta, name="pad")
    unit = {}
    for name in names:
        cb = cbs[name]
        unit[name] = {vol: cb.boundary_load(f) for vol, f in thermal[name].items()}
    return vasm, vmodes, vehicle, pasm, pmodes, pad, unit, vall, pall


def _check_joints(model: ModelConfig, cbs: dict, where: Where) -> None:
    """Every joint's point is on each of its components (a Nastran component names it by
    ``grids``), and every point that two vehicle components share is a joint of both: a
    missing one (an unmapped grid, a misspelt group) would leave a component disconnected
    there, an undeclared one would weld two components where nobody said so."""
    points = {n: set(cbs[n].boundary_points) for n in model.vehicle}
    for j in model.joints:
        for c in j.components:
            if j.name in points[c]:
                continue
            src = model.components[c].nastran
            if src is not None:
                named = ", ".join(f"{g} = {p!r}" for g, p in (src.grid_names or {}).items()) or "none"
                raise (where / "component" / c / "nastran" / "grids").error(
                    f"no grid is named {j.name!r}, a joint of {c} with the stack: map its grid ID to it "
                    f"(joints of {c}: {', '.join(sorted(k.name for k in model.joints if c in k.components))}; "
                    f"named: {named})")
            raise (where / "joint").error(f"joint {j.name!r}: component {c!r} has no point {j.name!r} "
                                          f"(its points: {', '.join(sorted(points[c])) or 'none'})")
        for c in j.components[1:]:          # a release of a direction the component has not there
            lacking = [d for d in j.release if f"{j.name}:{d}" not in cbs[c].boundary_labels]
            if lacking:
                raise (where / "joint").error(
                    f"joint {j.name!r}: releases {' '.join(lacking)} of component {c!r}, which has no such DOF at "
                    f"{j.name!r} (a pinned strut's ends are translations only: it passes no moment there; "
                    "release nothing for it, or list it first)")
    joined = {(j.name, c) for j in model.joints for c in j.components}
    names = list(model.vehicle)
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            for p in sorted(points[a] & points[b]):
                if (p, a) not in joined or (p, b) not in joined:
                    ca, cb = model.components.get(a), model.components.get(b)
                    mirror = next(((m, s) for m, s, c in ((b, a, cb), (a, b, ca))
                                   if c is not None and c.mirror is not None and c.mirror.of == s), None)
                    if mirror is not None:       # (the joint hint would weld a mirror to its source)
                        m, s = mirror
                        raise (where / "joint").error(
                            f"component {m!r}, the mirror of {s!r}, kept {s!r}'s point name {p!r}: a mirror renames "
                            f"its source's points by putting its own name for the source's in them ({s}_x -> {m}_x), "
                            f"and {p!r} has no {s!r} in it; put {s!r} in the name of that point of {s!r}")
                    raise (where / "joint").error(
                        f"components {a!r} and {b!r} both have a point {p!r}, which is no joint of both: declare "
                        f"it ([[model.joint]] name = {p!r}, components = [{a!r}, {b!r}]) or rename one of them")


def _check_materials(model: ModelConfig, thermal: dict[str, dict], where: Where) -> None:
    """Every [model.materials] volume names a volume group of some component."""
    volumes = {vol for th in thermal.values() for vol in th}
    for vol in model.materials:
        if vol not in volumes:
            raise (where / "materials" / vol).error(f"no component has a volume {vol!r} "
                                                    f"(volumes: {', '.join(sorted(volumes))})")


def cryo_loads(stack: StackModel, cryo: Cryo, where: Where | None = None) -> dict[str, float]:
    """{vehicle label: force} of the cryo preload (section 4.3): the tank's free thermal
    strain alpha * delta_T reduced to the component's boundary DOFs only."""
    from liftoff.transient.effects import cryo_point_loads

    where = where or Where("scenario", "cryo")
    if not cryo.enabled:
        return {}
    name = cryo.component
    vehicle = [n for n in stack.cbs if n != PAD]
    if name not in vehicle:
        raise (where / "component").error(f"{name!r} is not a vehicle component ({', '.join(vehicle)})")
    avail = stack.unit_thermal[name]
    parts = []
    for vol in cryo.volumes:
        if vol not in avail:
            raise (where / "volumes").error(f"{vol!r} is not a volume of component {name!r} "
                                            f"(has: {', '.join(sorted(avail)) or 'none'})")
        labels = [stack.vehicle_asm.system_label(name, lab) for lab in stack.cbs[name].boundary_labels]
        parts.append((labels, cryo.alpha * cryo.delta_T * avail[vol]))
    return cryo_point_loads(parts)
