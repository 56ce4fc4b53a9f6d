"""The run's deliverables, registered by name (pyyeti's ``cla.DR_Def`` registers recovery
categories the same way): a new output is one function and one registration, not an edit
of the run.

Three stages, each output a function of that stage's objects returning the paths it wrote
(into the run's staging folder, which is published atomically with everything else):

* ``"model"``: once per run, ``fn(stack, cp, out)`` (the stack model and the first named
  case's problem): modal tables, mode shapes, recovery matrices;
* ``"case"``: per case with full outputs, ``fn(result, cp, out, case)``;
* ``"run"``: after every case, ``fn(ctx)`` with a :class:`RunContext` (the cases' results,
  the folder, whether plots are wanted, the scenario's title, what the tables cover).

Outputs run in registration order within a stage; liftoff's workbook is the last of its own
"run" outputs, so it reads their tables (an output registered later runs after it and is not
in the workbook). An output registered with ``beside=True`` writes only files nothing of the
run reads again (pictures, ParaView and OP4 files): a serial run writes it in a forked child
beside the run (workflows/beside.py), as one job per stage. A ``"model"`` output registered
with ``cache_on`` (a function of ``(stack, cp)`` giving what, besides the stack model, its
files depend on) keeps its files in the stage cache, keyed by that, the stack's key and the
source of its module and ``code``: a run on a cached model copies them instead of writing
them again (the mode shapes' VTU and the recovery OP4 take seconds, the modal tables half of one). From Python, before
``liftoff.workflows.run.run``::

    from liftoff.workflows.outputs import register_output

    @register_output("peak_post_sum", "case", "sum of the posts' axial forces")
    def peak_post_sum(result, cp, out, case):
        ...
        return [path]
"""
from __future__ import annotations

import hashlib
import importlib.util
import inspect
import shutil
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

from liftoff.core.errors import InputError

from .cache import entry_files

STAGES = ("model", "case", "run")


@dataclass(frozen=True)
class Output:
    name: str
    stage: str
    fn: Callable
    description: str = ""
    beside: bool = False
    cache_on: Callable | None = None     # "model" outputs: (stack, cp) -> dict, what else the files depend on
    code: tuple[str, ...] = ()           # modules besides fn's own whose source the files depend on


@dataclass
class RunContext:
    """What a ``"run"``-stage output gets: ``results`` {case: (TransientResult, CaseProblem)}
    of the named cases and the governing generated case, the staging folder ``out``,
    ``plots`` (pictures wanted), the scenario ``title`` and ``partial`` (non-empty when the
    cases' histories do not cover a campaign's generated cases: a note for the tables) and
    ``units``, the report unit system of the workbook ([postprocess] units, analysis.units);
    ``beside``: where an output may hand work that writes files nothing reads again
    (:class:`workflows.beside.Beside`; None: inline)."""

    results: dict
    out: Path
    plots: bool
    title: str
    partial: str = ""
    units: str = "SI"
    beside: Any = None
    #: a campaign's time-consistent interface loads over every case (rows, the cases they cover
    #: in words), from the cases' summaries: the envelope table is written from them, not from
    #: ``results`` (which hold the named cases and the governing one); None: from ``results``
    consistent: tuple | None = None


OUTPUTS: dict[str, Output] = {}


def register_output(name: str, stage: str, description: str = "", beside: bool = False,
                    cache_on: Callable | None = None, code: tuple[str, ...] = ()):
    """Decorator: register ``fn`` as output ``name`` of ``stage`` (replacing one of that name);
    ``beside``: its files are read by nothing later in the run; ``cache_on`` and ``code``
    (``"model"`` outputs only): its files kept in the stage cache (module docstring)."""
    if stage not in STAGES:
        raise InputError(f"output {name!r}: stage must be one of {', '.join(STAGES)}, got {stage!r}")
    if cache_on is not None and stage != "model":
        raise InputError(f"output {name!r}: only \"model\" outputs can be cached (cache_on), not {stage!r} ones")

    def deco(fn):
        OUTPUTS.pop(name, None)
        OUTPUTS[name] = Output(name, stage, fn, description, beside, cache_on, tuple(code))
        return fn
    return deco


def write(stage: str, *args, beside=None, cache=None) -> list[Path]:
    """Every registered output of ``stage`` (in registration order); the paths they wrote.
    With ``beside`` (:class:`workflows.beside.Beside`), the outputs registered ``beside=True``
    go to it as one job, their files returned by its ``wait``; with ``cache``
    (:class:`workflows.cache.StageCache`), cached ``"model"`` outputs are copied from it when
    there (then in this process, being copies) and stored in it when not."""
    files: list[Path] = []
    later = []
    for o in list(OUTPUTS.values()):
        if o.stage != stage:
            continue
        fn, hit = o.fn, False
        if o.cache_on is not None:
            fn, hit = _through_cache(o, cache, *args)
        if o.beside and beside is not None and not hit:
            later.append((o.name, fn))
        else:
            files += list(fn(*args) or [])
    if later:
        beside.submit(", ".join(name for name, _ in later),
                      lambda: [p for _, fn in later for p in list(fn(*args) or [])])
    return files


def model_identity(stack, cp) -> str:
    """What the ``"model"`` outputs of a run and its Table 1 are made from, as a digest: the
    stack's key, for each such output with ``cache_on`` what else its files depend on (a case's
    recoveries, with their gravity constant column; its contact labels), and Table 1's inputs
    (loads.table1_inputs: post stiffness, cryo, gravity, softening). Two named cases of one digest share the
    run's model files; they are written once, of the first case (workflows/run.py says which
    cases differ)."""
    from .cache import content_sha256

    from .loads import table1_inputs

    inputs = {o.name: o.cache_on(stack, cp) for o in OUTPUTS.values() if o.stage == "model" and o.cache_on}
    inputs["table1"] = table1_inputs(cp)          # (written beside them, workflows/run.py _table1)
    return content_sha256([repr(getattr(stack, "key", id(stack))), repr(sorted(inputs.items()))])


CACHE_STAGE = "outputs"


def _through_cache(o: Output, cache, stack, cp, out: Path) -> tuple[Callable, bool]:
    """(the function that writes ``o``'s files through the stage cache, whether they are
    cached); ``o.fn`` itself where there is no cache (or only the run's temporary one) or the
    stack has no key."""
    from .cache import StageCache, stage_key

    if cache is None or cache.root is None or cache.temporary or not getattr(stack, "key", ""):
        return o.fn, False
    code = _code_of(o)
    if code is None:
        warnings.warn(f"output {o.name!r}: neither its module nor its source can be read: written, not cached",
                      stacklevel=3)
        return o.fn, False
    modules, source = code
    serial = StageCache(cache.root)     # written by one process (rank 0, or the child beside the run)
    key = stage_key(f"output {o.name}", {"inputs": o.cache_on(stack, cp), "source": source}, modules, (stack.key,))

    def write_through(stack, cp, out: Path) -> list[Path]:
        def build() -> tuple[str, list[Path]]:
            paths = [Path(f) for f in list(o.fn(stack, cp, out) or [])]
            for f in paths:
                if f.parent != Path(out):
                    raise InputError(f"output {o.name!r}: a cached output writes into the run's folder itself, "
                                     f"not {f}")
            return "built", paths

        def save(got, p: Path) -> None:
            for f in entry_files(p.parent, key):     # a killed writer's leftovers are not this entry's
                f.unlink(missing_ok=True)
            for f in got[1]:
                shutil.copyfile(f, p.with_name(f"{key}.{f.name}"))

        def load(p: Path) -> tuple[str, list[Path]]:
            return "cached", entry_files(p.parent, key)

        how, paths = serial.get_or_build(CACHE_STAGE, key, "", build, save, load, label=o.name)
        if how == "built":
            return paths
        got = [Path(out) / f.name[len(key) + 1:] for f in paths]      # copied here: an error on the run's disk
        for src, dst in zip(paths, got):                                # is the run's, not the entry's
            shutil.copyfile(src, dst)
        return got

    return write_through, serial.has(CACHE_STAGE, key, "")


def _code_of(o: Output) -> tuple[tuple[str, ...], str] | None:
    """(modules whose source keys ``o``'s cached files, a SHA-256 of its function's own source
    where its module is not importable: a script's or a notebook's), or None when neither can
    be read."""
    modules = tuple(o.code)
    try:
        if importlib.util.find_spec(o.fn.__module__) is not None:
            return modules + (o.fn.__module__,), ""
    except (ValueError, ImportError):      # __main__ (no spec), or a module gone since
        pass
    try:
        source = inspect.getsource(o.fn)
    except (OSError, TypeError):
        return None
    return modules, hashlib.sha256(source.encode()).hexdigest()


# ------------------------------------------------------------------ liftoff's own deliverables
def _register_builtin() -> None:
    from . import fields, report

    register_output("modal_tables", "model", "modes_vehicle.csv/.h5, modal_mass_vehicle_held.csv, "
                    "modal_mass_pad.csv", cache_on=report.modal_tables_inputs,
                    code=("liftoff.reduction", "liftoff.analysis", "liftoff.core"))(report.write_modal_tables)
    register_output("recovery_op4", "model", "recovery_vehicle.op4 and its index", beside=True,
                    cache_on=report.recovery_op4_inputs, code=("liftoff.reduction",))(report.write_recovery_op4)
    register_output("cb_checks", "model", "cb_checks.txt/.json")(report.write_cb_checks)
    register_output("mode_shapes_vtu", "model", "modes_vehicle.vtu", beside=True,
                    cache_on=fields.mode_shapes_inputs,
                    code=("liftoff.fem.output", "liftoff.reduction"))(fields.write_mode_shapes_vtu)
    register_output("interface_loads", "case", "interface_loads_<case>.csv")(
        lambda res, cp, out, case: report.write_interface_loads({case: (res, cp)}, out, case))
    register_output("interface_loads_envelope", "run", "interface_loads_envelope.csv")(
        lambda ctx: report.write_interface_loads(ctx.results, ctx.out, "envelope",
                                                 "" if ctx.consistent is not None else ctx.partial, ctx.consistent))
    register_output("correlated_loads", "run", "correlated_loads.csv/.png")(
        lambda ctx: report.write_correlated(ctx.results, ctx.out, ctx.plots, ctx.partial, ctx.beside))
    register_output("spectra_plots", "run", "srs.png, psd_<case>.png", beside=True)(report.plot_spectra)
    register_output("workbook", "run", "loads.xlsx")(lambda ctx: report.write_workbook(ctx.out, ctx.title, ctx.units))


_register_builtin()
