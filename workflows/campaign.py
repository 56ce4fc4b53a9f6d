"""The case runner of a load campaign: generated cases run on any concurrent.futures.Executor.

A task (:class:`CaseTask`) is small: the scenario (its mapping and folder), the case
index (with ``--march-together K``, K indexes, marched together: :func:`solve_together`),
the stage cache's folder and the model's key. A worker rebuilds the case from
the scenario and its index (:meth:`liftoff.config.Scenario.generated_case`), loads the
reduced model from the stage cache by path (every model stage is a cache hit: the main
process built them first), solves the transient without any modal history and sends
back a :class:`CaseSummary` (max/min with times of every item, SRS of the selected
items, post events: a few kB) with the histories of only the items where the case
reaches the running envelope it was sent (:class:`Captured`: many for the first cases,
rarely any later; at most every item's, 0.1 GB for the default, per task in flight).
Workers keep the last scenario and model they loaded, so each is read once per worker.

The main process writes each summary to the campaign folder as one record
(``cases/<name>-<key>.npz``, the key a hash of the case's scenario mapping, model and
code), so a restarted campaign skips the cases already done, and then reads the records
back in case order to build envelopes and statistics (:mod:`.aggregate`), memory flat
in the number of cases.
"""
from __future__ import annotations

import hashlib
import itertools
import json
import time
from concurrent.futures import FIRST_COMPLETED, wait
from dataclasses import dataclass, field, replace
from functools import lru_cache
from pathlib import Path
from typing import Callable, Iterable, Iterator

import numpy as np

from liftoff.core.errors import ConvergenceError, InputError, ResourceError
from liftoff.core.records import read_record, write_record

#: bytes the main process keeps per generated case until the envelope is written: the
#: record's path, the index to run and the case's name (run_campaign, aggregate,
#: governing_case: ~560 B measured with a 40-character folder) and its share of the order
#: statistics (P99/90 keeps the largest ~1 % of every item's maxima and minima, 0.32 B per
#: item); rounded up
CASE_BYTES = 1000
RECORD_FORMAT = "liftoff-campaign-case"
RECORD_VERSION = 1
CODE = ("liftoff.transient", "liftoff.analysis", "liftoff.workflows", "liftoff.config", "liftoff.core")


@dataclass(frozen=True)
class ScenarioRef:
    """How a worker finds the scenario: its TOML mapping, name, folder (CSV and database
    files are read relative to it), the number of generated cases, and a digest."""

    data: dict
    source: str
    base: str
    n_cases: int
    digest: str

    @classmethod
    def of(cls, sc) -> ScenarioRef:
        data = sc.data
        digest = hashlib.sha256(json.dumps(data, sort_keys=True, default=repr).encode()).hexdigest()[:16]
        return cls(data, sc.path, str(sc.base), sc.n_generated, digest)

    def load(self):
        from liftoff.config.scenario import parse_scenario

        return parse_scenario(self.data, self.source, Path(self.base), n_cases=self.n_cases)


@dataclass(frozen=True)
class RunningEnvelope:
    """The envelope of the cases arrived so far, per item (in the summaries' order): its max
    and min, and the index of the case holding each (the first in case order on a tie, as
    analysis.aggregate.Aggregate)."""

    mx: np.ndarray
    mx_case: np.ndarray
    mn: np.ndarray
    mn_case: np.ndarray

    def taken(self, s: CaseSummary) -> tuple[np.ndarray, np.ndarray]:
        """Per item, whether case ``s`` takes the max, and whether it takes the min, from this
        envelope: beyond it, or equal and earlier in case order."""
        return ((s.mx > self.mx) | ((s.mx == self.mx) & (s.index < self.mx_case)),
                (s.mn < self.mn) | ((s.mn == self.mn) & (s.index < self.mn_case)))

    def reached(self, s: CaseSummary) -> np.ndarray:
        """Per item, whether case ``s`` would take its max or its min from this envelope."""
        mx, mn = self.taken(s)
        return mx | mn

    @staticmethod
    def joined(env: RunningEnvelope | None, s: CaseSummary) -> RunningEnvelope:
        """``env`` (None: no case yet) with case ``s`` arrived: each value it takes (:meth:`taken`)."""
        if env is None:                 # as Captured's: below and above every value, after every case
            n, last = len(s.mx), np.iinfo(np.int64).max
            env = RunningEnvelope(np.full(n, -np.inf), np.full(n, last), np.full(n, np.inf), np.full(n, last))
        mx, mn = env.taken(s)
        return RunningEnvelope(np.where(mx, s.mx, env.mx), np.where(mx, s.index, env.mx_case),
                               np.where(mn, s.mn, env.mn), np.where(mn, s.index, env.mn_case))


@dataclass(frozen=True)
class CaseTask:
    """One generated case for a worker; ``columns``: item names whose histories to send
    back (the envelope-setting cases), else a summary. With ``capture`` the summary also
    carries the histories of the items where the case reaches ``envelope`` (the campaign's
    running envelope when the task was sent; None: every item's, :class:`Captured`)."""

    scenario: ScenarioRef
    index: int
    cache: str
    model_key: str
    columns: tuple[str, ...] = ()
    capture: bool = False
    envelope: RunningEnvelope | None = None
    #: further generated cases marched together with ``index`` (liftoff.transient.solve_batch): the
    #: worker sends back a list of summaries, ``index``'s first
    together: tuple[int, ...] = ()
    #: the model's StackModel.key as the campaign saw it (its input files' contents too; "": not
    #: checked): a worker's kept stack of another key is built again (_worker_state)
    stack_key: str = ""


@dataclass
class CaseSummary:
    """What a case sends back: per item max/min and their times, SRS of the selected items
    (n_q, n_freq, n_srs_items), and per post the first separation, recontacts and peak
    compression."""

    name: str
    index: int
    items: tuple[str, ...]
    units: tuple[str, ...]
    categories: tuple[str, ...]
    mx: np.ndarray
    t_mx: np.ndarray
    mn: np.ndarray
    t_mn: np.ndarray
    srs_items: tuple[str, ...] = ()
    srs: np.ndarray | None = None
    posts: tuple[str, ...] = ()
    separation: np.ndarray = field(default_factory=lambda: np.zeros(0))
    recontacts: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    compression: np.ndarray = field(default_factory=lambda: np.zeros(0))
    n_steps: int = 0
    h: float = 0.0
    wall: float = 0.0
    err_mx: np.ndarray | None = None       # estimated error of each max/min (Richardson, a run at h/2)
    err_mn: np.ndarray | None = None
    support_items: tuple[str, ...] = ()   # "<interface>|<pair>" of the correlated loads (analysis.correlated)
    support: np.ndarray | None = None      # (n_support_items, N_DIRECTIONS) their support functions
    #: the time-consistent interface loads (analysis.interface_loads.to_arrays of time_consistent's rows)
    consistent: dict | None = None
    time: np.ndarray | None = None         # with histories: the case's time points (s); neither is recorded
    histories: dict | None = None          # {item: history} captured for the envelope (CaseTask.capture)
    note: str = ""                         # what the worker says of it (not recorded): solved one by one, why


# ------------------------------------------------------------------ one case
def summarize(result, cp, name: str, index: int, post, wall: float = 0.0, check=None, its=None) -> CaseSummary:
    """The compact summary of a solved case (the same for named and generated cases); with
    ``check`` (the same case at h/2) each max/min carries its estimated error; ``its``: the
    case's report.items when already made."""
    from liftoff.transient.accuracy import error_estimate

    from . import report

    band = post.acceleration_band_hz
    its = report.items(result, cp.attach, report.liquid_heads(cp), band) if its is None else its
    t = result.time
    # per item on its own history (first occurrence, as argmax over a stacked array), without
    # stacking them: 1 s a default case for the copy and the strided search
    imax = np.array([int(np.argmax(it.values)) for it in its], dtype=np.int64)
    imin = np.array([int(np.argmin(it.values)) for it in its], dtype=np.int64)
    vmax = np.array([it.values[i] for it, i in zip(its, imax)], dtype=float)
    vmin = np.array([it.values[i] for it, i in zip(its, imin)], dtype=float)
    srs_items, srs_arr = (), None
    if post.srs is not None:
        sel = [j for j, it in enumerate(its) if it.category in post.srs.categories]
        srs_items = tuple(its[j].name for j in sel)
        if sel:
            srs_arr = report.srs_of(np.column_stack([its[j].history for j in sel]), result.h, post.srs)[1]
    cs = result.contact_summary()
    from liftoff.analysis.correlated import case_support

    from liftoff.analysis import interface_loads as il

    interfaces = report.interface_histories(result, cp.attach)
    support_items, support = case_support(interfaces)
    consistent = il.time_consistent(t, interfaces, name)
    return CaseSummary(
        name, index, tuple(it.name for it in its), tuple(it.unit for it in its), tuple(it.category for it in its),
        vmax, t[imax].copy(), vmin, t[imin].copy(), srs_items, srs_arr,
        tuple(c["name"] for c in cs), np.array([np.nan if c["separation_time"] is None else c["separation_time"]
                                                 for c in cs]),
        np.array([c["recontacts"] for c in cs], dtype=np.int64), np.array([c["peak_compression"] for c in cs]),
        int(t.size - 1), float(result.h), float(wall), *_errors(its, report.items(check, cp.attach, report.liquid_heads(cp), band), error_estimate)
        if check is not None else (None, None), support_items=support_items, support=support if support_items else None,
        consistent=il.to_arrays(consistent) if consistent else None)


def _errors(its, its_half, estimate) -> tuple[np.ndarray, np.ndarray]:
    """Estimated errors of each item's max and min from its history at h/2."""
    mx = np.array([estimate(a.values.max(), b.values.max()) for a, b in zip(its, its_half)])
    mn = np.array([estimate(a.values.min(), b.values.min()) for a, b in zip(its, its_half)])
    return mx, mn


_MEMO: dict = {}


def _worker_state(task: CaseTask):
    """(scenario, stack) of a task, loaded once per worker process (the last one kept)."""
    from liftoff.config import Where

    from .cache import StageCache
    from .pipeline import build_stack

    key = _memo_key(task.scenario, task.cache, task.model_key)
    if _MEMO.get("key") != key or (task.stack_key and _MEMO["stack"].key != task.stack_key):
        # (a long-lived worker, a remote Dask one: the scenario's text and [model] are not all
        # that made its stack; its folder, whose files the scenario reads, and the contents of the
        # model's input files, in the stack's key, are checked too)
        _MEMO.clear()
        sc = task.scenario.load()
        case0 = sc.generated_case(task.index)
        stack = build_stack(case0.model, StageCache(Path(task.cache)), progress=False,
                            where=Where(case0.source, "model"), workers=1)     # (a pool's worker already)
        if task.stack_key and stack.key != task.stack_key:
            raise InputError(f"{sc.path}: case {case0.name}: the model's input files changed while the campaign ran "
                             "(its stack differs from the one the campaign started with); run it again")
        _MEMO.update(key=key, scenario=sc, stack=stack)
    return _MEMO["scenario"], _MEMO["stack"]


def _memo_key(ref: ScenarioRef, cache: str, model_key: str) -> tuple:
    """What a worker's kept (scenario, stack) was made from: the scenario's text, case count,
    name and folder, the contents of the files it names (:func:`referenced_files`: a profile's
    CSV edited between two campaigns on the same long-lived worker), the cache and the [model]
    parameters."""
    files = tuple(sorted(referenced_files(ref.data, Path(ref.base)).items()))
    return ref.digest, ref.n_cases, ref.source, ref.base, files, str(cache), model_key


def _generated_case(sc, index: int, model_key: str):
    """Generated case ``index`` of ``sc``; InputError if its [model] is not the campaign's."""
    from dataclasses import asdict

    from .cache import stage_key

    case = sc.generated_case(index)
    if stage_key("model", asdict(case.model)) != model_key:
        raise InputError(f"{sc.path}: case {case.name}: its [model] differs from the campaign's")
    return case


def solve_generated(task: CaseTask, keep_modal: bool | str = False, modal_scratch: Path | None = None):
    """(result, CaseProblem, Case, wall s) of generated case ``task.index``; ``modal_scratch``:
    the folder of the kept modal histories' scratch file (TransientProblem.modal_scratch)."""
    from liftoff.transient import solve

    from .loads import build_problem

    sc, stack = _worker_state(task)
    case = _generated_case(sc, task.index, task.model_key)
    t0 = time.perf_counter()
    try:
        cp = build_problem(case, stack, progress=False, keep_modal=keep_modal)
        problem = cp.problem if modal_scratch is None else replace(cp.problem, modal_scratch=str(modal_scratch))
        return solve(problem), cp, case, time.perf_counter() - t0
    except (InputError, ConvergenceError, ResourceError) as exc:
        msg = str(exc) if case.name in str(exc) else f"{sc.path}: case {case.name}: {exc}"
        raise type(exc)(msg) from None


def solve_together(task: CaseTask) -> tuple[Iterator, str]:
    """((index, result, CaseProblem, Case, wall s) of generated cases ``task.index`` and
    ``task.together``, in turn, marched together (liftoff.transient.solve_batch_iter: every
    case marched before this returns, each result made as it is taken, so a caller that
    lets each go holds one; each wall the batch's share); a note, "" unless they were solved
    one by one). Cases the batch cannot march (friction, dashpots, latches, soft release,
    rigid rows: its scope, which it names) or whose start fails are solved one by one, so
    that a case's error names that case as solve_generated names it, and the note says why."""
    from liftoff.transient import solve_batch_iter

    from .loads import build_problem

    sc, stack = _worker_state(task)
    indexes = (task.index, *task.together)
    cases = [_generated_case(sc, i, task.model_key) for i in indexes]
    t0 = time.perf_counter()
    try:
        cps = [build_problem(case, stack, progress=False) for case in cases]
        results = solve_batch_iter([cp.problem for cp in cps])
    except (InputError, ConvergenceError, ResourceError) as exc:     # (its memory: K cases' histories at once)
        note = (f"--march-together: cases {', '.join(c.name for c in cases)} solved one by one "
                f"({' '.join(str(exc).split())[:300]})"
                + ("; a smaller --march-together needs less memory" if isinstance(exc, ResourceError) else ""))
        if not _MEMO.get("warned"):      # once a worker: the cases are right, only not marched together
            _MEMO["warned"] = True
            import warnings

            warnings.warn(note + "; further such groups of this worker likewise", stacklevel=2)
        return ((i, *solve_generated(replace(task, index=i, together=()))) for i in indexes), note
    wall = (time.perf_counter() - t0) / len(cases)
    return _in_turn(list(indexes), results, cps, cases, wall), ""


def _in_turn(indexes: list, results: Iterator, cps: list, cases: list, wall: float) -> Iterator:
    """solve_together's (index, result, CaseProblem, Case, wall) tuples, each item taken off
    its list as it is handed over and nothing kept here between them, so that a case the
    caller lets go is freed before the next result is made."""
    while indexes:
        yield indexes.pop(0), next(results), cps.pop(0), cases.pop(0), wall


def run_case(task: CaseTask):
    """Worker entry point: the summary of one generated case (with ``task.capture`` the
    histories of the items reaching the envelope it was sent), or (time, {item: history})
    of the items in ``task.columns``; with ``task.together`` the list of the summaries of
    the cases marched together."""
    from .beside import trim_heap

    trim_heap()                          # the previous case's freed arrays back to the system
    if task.together and not task.columns:
        (solved, note), out = solve_together(task), []
        env = task.envelope
        for i, res, cp, case, wall in solved:   # each case's result made, summarised and let go in turn
            out.append(_summary(replace(task, index=i, envelope=env), res, cp, case, wall))
            del res, cp
            if task.capture and np.shape(env.mx if env is not None else out[-1].mx) == np.shape(out[-1].mx):
                # the next case of the task captures only where it reaches this one too: a case that
                # sets a final envelope value beats every case before it, these included (Captured)
                env = RunningEnvelope.joined(env, out[-1])
        if out and note:                 # said by the main process too (a remote worker's warning is not seen)
            out[0].note = note
        return out
    res, cp, case, wall = solve_generated(task)
    if task.columns:
        from . import report

        its = report.items(res, cp.attach, report.liquid_heads(cp), _MEMO["scenario"].post.acceleration_band_hz)
        by_name = {it.name: it.values for it in its}
        return task.index, res.time, {c: by_name[c] for c in task.columns}
    return _summary(task, res, cp, case, wall)


def _summary(task: CaseTask, res, cp, case, wall: float) -> CaseSummary:
    """run_case's summary of a solved generated case (module docstring)."""
    from . import report

    sc = _MEMO["scenario"]
    its = report.items(res, cp.attach, report.liquid_heads(cp), sc.post.acceleration_band_hz)
    s = summarize(res, cp, case.name, task.index, sc.post, wall, its=its)
    if task.capture:
        env = task.envelope
        reach = env.reached(s) if env is not None and np.shape(env.mx) == (len(its),) else np.ones(len(its), bool)
        if reach.any():                  # (most later cases reach nothing: no time points sent either)
            s.time = res.time
            s.histories = {its[j].name: np.ascontiguousarray(its[j].values) for j in np.flatnonzero(reach)}
    return s


def check_case_memory(source: str, n_cases: int, limit: float | None = None) -> None:
    """ResourceError, before any case is generated, when the run could not keep ``n_cases``
    generated cases (CASE_BYTES each) within ``limit`` bytes (None: MEMORY_FRACTION of the
    memory available)."""
    from liftoff.core import memory

    need = n_cases * CASE_BYTES
    limit = memory.MEMORY_FRACTION * memory.available_memory() if limit is None else limit
    if need > limit:
        raise ResourceError(f"{source}: {n_cases} generated cases: the run keeps about {CASE_BYTES / 1e3:g} kB per "
                            f"case ({need / 1e9:.3g} GB) but the limit is {limit / 1e9:.3g} GB; run fewer cases (split "
                            "the campaign into runs) or raise the limit (--max-memory GB)")


# ------------------------------------------------------------------ records
def case_key(sc, index: int, model_key: str, stack_key: str = "") -> str:
    """Hash of everything a generated case's summary depends on: its scenario mapping and the
    contents of the files it names (a force table's CSV: :func:`referenced_files`), the model
    (``model_key``: its parameters; ``stack_key``: StackModel.key, what its stages were built
    from: their code, libraries and input files, the modes kept), the post-processing settings
    and the code of the packages that compute it."""
    from .cache import _canonical, code_version

    raw, _ = sc.generated_raw(index)
    payload = json.dumps({"case": _canonical(raw), "files": referenced_files(raw, Path(sc.base)),
                          "model": model_key, "stack": stack_key, "post": repr(sc.post),
                          "code": code_version(*CODE)}, sort_keys=True, default=repr)
    return hashlib.sha256(payload.encode()).hexdigest()[:16]


def referenced_files(raw, base: Path) -> dict[str, str]:
    """{name: SHA-256} of every string in the scenario mapping ``raw`` that names a file
    (relative to ``base`` or absolute): a record made before such a file changed is not
    reused. Digests are kept per (path, size, times, inode) in this process (a large Nastran
    file a thousand cases name is read once)."""
    out: dict[str, str] = {}

    def walk(x):
        if isinstance(x, dict):
            for v in x.values():
                walk(v)
        elif isinstance(x, (list, tuple)):
            for v in x:
                walk(v)
        elif isinstance(x, str) and x and len(x) < 4096 and "\0" not in x:
            p = Path(x) if Path(x).is_absolute() else base / x
            try:
                st = p.stat()
            except (OSError, ValueError):
                return
            if p.is_file():
                out[x] = _digest(str(p.resolve()), st.st_size, st.st_mtime_ns, st.st_ctime_ns, st.st_ino)

    walk(raw)
    return out


@lru_cache(maxsize=256)
def _digest(path: str, size: int, mtime_ns: int, ctime_ns: int, inode: int) -> str:
    from liftoff.core.records import file_sha256

    return file_sha256(path)


def record_path(folder: Path, name: str, key: str) -> Path:
    return Path(folder) / "cases" / f"{name}-{key}.npz"


def record_key(path: Path) -> str:
    """The case key in a record's name (:func:`record_path`)."""
    return Path(path).stem.rsplit("-", 1)[1]


def save_summary(s: CaseSummary, path: Path, key: str) -> Path:
    data = {k: getattr(s, k) for k in ("mx", "t_mx", "mn", "t_mn", "separation", "recontacts", "compression")}
    data.update(items=np.array(s.items, dtype=str), units=np.array(s.units, dtype=str),
                categories=np.array(s.categories, dtype=str), posts=np.array(s.posts, dtype=str),
                srs_items=np.array(s.srs_items, dtype=str), scalars=np.array([s.index, s.n_steps, s.h, s.wall]))
    if s.srs is not None:
        data["srs"] = s.srs
    if s.support is not None:
        data.update(support_items=np.array(s.support_items, dtype=str), support=s.support)
    if s.consistent is not None:
        data.update({CONSISTENT + k: v for k, v in s.consistent.items()})
    return write_record(path, RECORD_FORMAT, RECORD_VERSION, data, units="SI per item (column units); s",
                        attrs={"name": s.name, "metadata": json.dumps({"key": key})}, suffixes=(".npz",))


#: a record's arrays of the time-consistent interface loads: this prefix, then to_arrays' keys
CONSISTENT = "consistent_"
_RECORD_ARRAYS = ("mx", "t_mx", "mn", "t_mn", "separation", "recontacts", "compression", "items", "units",
                  "categories", "posts", "srs_items", "scalars")


def load_summary(path: Path) -> CaseSummary:
    return _summary_of(read_record(path, RECORD_FORMAT, (RECORD_VERSION,), what="campaign record"), path)


def _summary_of(rec, path: Path) -> CaseSummary:
    """The CaseSummary of a campaign record read from ``path`` (InputError if incomplete)."""
    d = rec.data
    missing = [k for k in _RECORD_ARRAYS if k not in d]
    if missing or np.shape(d["scalars"]) != (4,) or "name" not in rec.attrs:
        raise InputError(f"campaign record {str(path)!r}: not a complete record "
                         f"({'missing ' + repr(missing[0]) if missing else 'scalars or name malformed'})")
    tup = lambda a: tuple(str(x) for x in np.atleast_1d(a))  # noqa: E731
    index, n_steps, h, wall = d["scalars"]
    return CaseSummary(str(rec.attrs["name"]), int(index), tup(d["items"]), tup(d["units"]), tup(d["categories"]),
                       d["mx"], d["t_mx"], d["mn"], d["t_mn"], tup(d["srs_items"]) if d["srs_items"].size else (),
                       d.get("srs"), tup(d["posts"]), d["separation"], d["recontacts"], d["compression"],
                       int(n_steps), float(h), float(wall),
                       **({"support_items": tup(d["support_items"]), "support": d["support"]}
                          if "support" in d and "support_items" in d else {}),
                       consistent={k[len(CONSISTENT):]: d[k] for k in d if k.startswith(CONSISTENT)} or None)


def record_problem(path: Path, name: str, index: int, key: str) -> str | None:
    """Why the record at ``path`` cannot stand for generated case ``name`` (``index``,
    ``key``), None if it can: unreadable or incomplete, another case's (a record copied
    over this one), another key, or values that are not finite (a damaged run)."""
    try:
        rec = read_record(path, RECORD_FORMAT, (RECORD_VERSION,), what="campaign record")
        s = _summary_of(rec, path)
        meta = json.loads(rec.attrs.get("metadata", "{}"))
    except (InputError, ResourceError, ValueError, TypeError, KeyError) as exc:   # (a damaged header may declare GBs)
        return " ".join(str(exc).split())[:200]
    if s.name != name or s.index != index:
        return f"it is the record of case {s.name!r} (index {s.index}), not of {name!r}"
    if not isinstance(meta, dict) or meta.get("key") != key:
        return "its key is not this case's"
    if not all(np.all(np.isfinite(np.asarray(a, dtype=float))) for a in (s.mx, s.mn, s.t_mx, s.t_mn)):
        return "it holds NaN or infinite peaks"
    if s.support is not None and (np.ndim(s.support) != 2 or np.shape(s.support)[0] != len(s.support_items)
                                  or not np.all(np.isfinite(s.support))):
        return "its correlated-load support functions are malformed or not finite"
    return None


# ------------------------------------------------------------------ the loop
def run_tasks(executor, tasks: Iterable[CaseTask], on_result: Callable, window: int) -> None:
    """Submit ``tasks`` to ``executor`` with at most ``window`` in flight, calling
    ``on_result`` on each result as it arrives (any order); the first failure cancels the
    rest and is raised."""
    it = iter(tasks)
    sent = {}
    for t in itertools.islice(it, window):
        sent[executor.submit(run_case, t)] = t
    pending = set(sent)
    try:
        while pending:
            done, pending = wait(pending, return_when=FIRST_COMPLETED)
            failed = None
            for fut in sorted(done, key=lambda f: sent[f].index):   # the finished ones kept before a failure
                try:
                    got = fut.result()
                except (InputError, ConvergenceError, ResourceError):
                    raise                   # (named by the worker: solve_generated; exit 2, 3, 4)
                except MemoryError:         # a worker out of memory: the run's resource error, the cases named
                    task = sent[fut]
                    names = ", ".join(case_name_of(i) for i in (task.index, *task.together))
                    raise ResourceError(f"campaign: generated case {names}: out of memory in its worker; use "
                                        "fewer workers, steps, outputs or modes") from None
                except Exception as exc:    # noqa: BLE001 - a lost worker, a library's error: name the cases
                    failed = failed or (sent.pop(fut), exc)
                    continue
                sent.pop(fut)
                for r in (got if isinstance(got, list) else [got]):     # (cases marched together: a list)
                    on_result(r)
                nxt = next(it, None)
                if nxt is not None:
                    f = executor.submit(run_case, nxt)
                    sent[f] = nxt
                    pending.add(f)
            if failed is not None:
                task, exc = failed
                names = ", ".join(case_name_of(i) for i in (task.index, *task.together))
                raise RuntimeError(f"campaign: generated case {names}: {type(exc).__name__}: "
                                   f"{' '.join(str(exc).split())[:500]}") from exc
    finally:
        for fut in pending:
            fut.cancel()


HISTORY_FORMAT = "liftoff-campaign-histories"
HISTORY_VERSION = 1


class Captured:
    """The envelope histories captured while a campaign runs, so that the cases setting an
    envelope value need not run again at the end (:func:`write_envelope_histories`).

    Each task is sent the running envelope of the cases arrived so far
    (:meth:`running`); the worker sends back the histories of the items where its case
    reaches it (:meth:`RunningEnvelope.reached`). A case that sets a final envelope value
    reaches every running envelope it can have been sent (those hold only cases it beats, or
    equals later in case order), so its histories always come back. On arrival only the items
    where the case now holds the running envelope are written, one file per case
    (``histories/<name>-<key>.npz``, items x time, beside its record); a file is deleted once
    every item it holds is taken by another case. A missing or unreadable file costs a
    re-run, as before, never a wrong history."""

    def __init__(self, folder: Path, records: dict):
        self.folder, self.records = Path(folder) / "histories", records
        self.items: tuple[str, ...] | None = None
        self.env: RunningEnvelope | None = None
        self.held: dict = {}             # case index -> {(item row, 'max' | 'min')} it holds

    def path(self, index: int) -> Path:
        return self.folder / self.records[index].name

    def running(self) -> RunningEnvelope | None:
        """A copy of the running envelope for the next task (None before any case)."""
        e = self.env
        return None if e is None else RunningEnvelope(e.mx.copy(), e.mx_case.copy(), e.mn.copy(), e.mn_case.copy())

    def arrive(self, s: CaseSummary) -> None:
        """Take a case's summary: update the running envelope, write the histories it holds
        and delete the files of cases that no longer hold any."""
        hist, t = s.histories, s.time
        s.histories = s.time = None
        if self.items is None:
            n, last = len(s.items), np.iinfo(np.int64).max
            self.items = s.items
            self.env = RunningEnvelope(np.full(n, -np.inf), np.full(n, last), np.full(n, np.inf), np.full(n, last))
        if s.items != self.items:       # (Aggregate says so at the end); nothing captured
            return
        e, lost = self.env, set()
        take_mx, take_mn = e.taken(s)
        for side, run, case, val, take in (("max", e.mx, e.mx_case, s.mx, take_mx),
                                           ("min", e.mn, e.mn_case, s.mn, take_mn)):
            for j in np.flatnonzero(take):
                before = int(case[j])
                if before in self.held:
                    self.held[before].discard((int(j), side))
                    lost.add(before)
                run[j], case[j] = val[j], s.index
                self.held.setdefault(s.index, set()).add((int(j), side))
        rows = sorted({j for j, _ in self.held.get(s.index, ())})
        if rows and hist is not None and all(self.items[j] in hist for j in rows):
            write_record(self.path(s.index), HISTORY_FORMAT, HISTORY_VERSION,
                         {"time": np.asarray(t), "items": np.array([self.items[j] for j in rows], dtype=str),
                          "value": np.stack([hist[self.items[j]] for j in rows])},
                         units="time s; value (items x time): SI, each row in its item's unit",
                         attrs={"name": s.name, "metadata": json.dumps({"key": record_key(self.records[s.index])})},
                         suffixes=(".npz",))
        for i in lost:
            if not self.held[i]:
                del self.held[i]
                self.path(i).unlink(missing_ok=True)

    def load(self, index: int, items: Iterable[str]) -> tuple[np.ndarray, dict] | None:
        """(time, {item: history}) of case ``index`` captured for ``items``; None when its
        file is missing, unreadable, another case's or lacks one of them."""
        p = self.path(index)
        if not p.is_file():
            return None
        try:
            rec = read_record(p, HISTORY_FORMAT, (HISTORY_VERSION,), what="campaign histories")
            meta = json.loads(rec.attrs.get("metadata", "{}"))
            t, names, value = rec.data["time"], [str(x) for x in np.atleast_1d(rec.data["items"])], rec.data["value"]
        except (InputError, ResourceError, ValueError, TypeError, KeyError):   # (a damaged header may declare GBs)
            return None
        if not isinstance(meta, dict) or meta.get("key") != record_key(self.records[index]) \
                or np.shape(value) != (len(names), t.size):
            return None
        col = {n: value[k] for k, n in enumerate(names)}
        return (t, {n: col[n] for n in items}) if all(n in col for n in items) else None

    def prune(self, keep: Iterable[int]) -> None:
        """Delete the captured files of every case not in ``keep``."""
        keep_names = {self.path(i).name for i in keep}
        for f in self.folder.glob("*.npz") if self.folder.is_dir() else ():
            if f.name not in keep_names:
                f.unlink(missing_ok=True)


@dataclass
class CampaignRun:
    """What :func:`run_campaign` did: records by index, how many ran and were reused, and
    the envelope histories captured on the way."""

    folder: Path
    records: dict            # index -> record path
    ran: int
    reused: int
    wall: float
    captured: Captured | None = None


def run_campaign(sc, ref: ScenarioRef, cache_root: Path, model_key: str, executor, folder: Path,
                 progress: bool = True, window: int = 0, echo=print, together: int = 1,
                 stack_key: str = "") -> CampaignRun:
    """Run every generated case of ``sc`` not already recorded in ``folder`` on ``executor``;
    ``together`` cases a task (marched together, :func:`solve_together`; 1: one by one; run()
    checks it, before the model stages); ``stack_key``: the model's StackModel.key (in each
    record's key: :func:`case_key`)."""
    t0 = time.perf_counter()
    folder = Path(folder)
    (folder / "cases").mkdir(parents=True, exist_ok=True)
    records, todo = {}, []
    for i in range(sc.n_generated):
        from liftoff.config.dispersion import case_name

        key = case_key(sc, i, model_key, stack_key)
        p = record_path(folder, case_name(i), key)
        records[i] = p
        if not p.is_file():
            todo.append(i)
            continue
        why = record_problem(p, case_name(i), i, key)
        if why is not None:          # damaged or foreign: the case runs again and its record is replaced
            echo(f"  campaign: record {p.name} is not usable ({why}); case {case_name(i)} runs again")
            todo.append(i)
    reused = sc.n_generated - len(todo)
    echo(f"  campaign: {sc.n_generated} generated cases, {reused} done before (records in {folder}), "
         f"{len(todo)} to run")
    bar = None
    if progress and todo:
        from tqdm import tqdm

        bar = tqdm(total=len(todo), unit="case", desc="cases", leave=False)

    captured = Captured(folder, records)

    said = []

    def store(s: CaseSummary) -> None:
        if s.note and not said:          # once a campaign: the first group the batch refused
            said.append(s.note)
            echo(f"  campaign: {s.note}; further such groups likewise")
        captured.arrive(s)
        save_summary(s, records[s.index], record_key(records[s.index]))
        if bar is not None:
            bar.update(1)

    # (a generator: each task takes the running envelope when it is sent)
    k = int(together)
    tasks = (CaseTask(ref, todo[j], str(cache_root), model_key, (), True, captured.running(), tuple(todo[j + 1:j + k]),
                      stack_key) for j in range(0, len(todo), k))
    try:                                 # (marched tasks: one running and one waiting a worker, as each holds k cases)
        workers = max(1, getattr(executor, "_max_workers", 2) or 2)
        run_tasks(executor, tasks, store, window or (4 if k == 1 else 2) * workers)
    finally:
        if bar is not None:
            bar.close()
    return CampaignRun(folder, records, len(todo), reused, time.perf_counter() - t0, captured)


# ------------------------------------------------------------------ after the cases
def prime(sc, cache_root: str, model_key: str, stack) -> None:
    """Give this process's worker state the scenario and the stack it already holds (the
    main process runs cases too: the governing case, an in-process executor)."""
    _MEMO.clear()
    _MEMO.update(key=_memo_key(ScenarioRef.of(sc), cache_root, model_key), scenario=sc, stack=stack)


def generated_index(sc, name: str) -> int | None:
    """The index of a generated case's name (d0017 -> 17), None for a named case."""
    if name in sc.overrides or not (name[:1] == "d" and name[1:].isdigit()):
        return None
    i = int(name[1:])
    return i if i < sc.n_generated else None


def feed_records(sc, camp: CampaignRun, agg, path: Path) -> Path:
    """Feed every generated case's record to ``agg`` in index order and write cases.csv:
    per case its draws, the database file, post events and wall time."""
    import csv as _csv

    from liftoff.core.records import atomic_path

    with atomic_path(path, suffix=".csv") as tmp, open(tmp, "w", newline="") as fh:
        fh.write(f"# liftoff generated cases of {sc.path}: seed {sc.dispersion.seed}; case i draws from "
                 "SeedSequence([seed, i, crc32(variable)]); times in s, forces in N\n")
        w = None
        for i in range(sc.n_generated):
            s = load_summary(camp.records[i])
            agg.add(s, generated=True)
            _, info = sc.generated_raw(i)
            row = {"index": i, "name": s.name, **info, "h": s.h, "n_steps": s.n_steps,      # (CASE_COLUMNS)
                   "first_separation": float(np.nanmin(s.separation)) if s.separation.size else float("nan"),
                   "last_separation": float(np.nanmax(s.separation)) if s.separation.size else float("nan"),
                   "max_recontacts": int(s.recontacts.max(initial=0)),
                   "peak_post_compression": float(s.compression.max(initial=0.0)), "wall_s": s.wall}
            if w is None:
                w = _csv.DictWriter(fh, fieldnames=list(row))
                w.writeheader()
            w.writerow({k: (f"{v:.9g}" if isinstance(v, float) else v) for k, v in row.items()})
    return path


def envelope_setters(sc, env: list[dict]) -> dict[int, list[tuple[int, str]]]:
    """{generated case index: [(item row, 'max' | 'min'), ...]} of the envelope values it sets."""
    out: dict[int, list] = {}
    for j, r in enumerate(env):
        for side in ("max", "min"):
            i = generated_index(sc, r[f"case_{side}"])
            if i is not None:
                out.setdefault(i, []).append((j, side))
    return out


def governing_case(sc, env: list[dict], named: bool = False):
    """The case that sets the most envelope values of the force items (posts, attach
    forces; N), the first in case order on a tie: a generated case's index (None if none
    sets one), or with ``named`` any case's name."""
    from .report import is_force

    count: dict[str, int] = {}
    for r in env:
        if is_force(r):
            for side in ("max", "min"):
                count[r[f"case_{side}"]] = count.get(r[f"case_{side}"], 0) + 1
    order = [c.name for c in sc.cases] + [case_name_of(i) for i in range(sc.n_generated)] if named else \
        [case_name_of(i) for i in range(sc.n_generated)]
    rank = {c: k for k, c in enumerate(order)}          # (one pass: a million cases' names, not a search each)
    best = max((c for c in count if c in rank), key=lambda c: (count[c], -rank[c]), default=None)
    if best is None:
        return None
    return best if named else generated_index(sc, best)


def case_name_of(i: int) -> str:
    from liftoff.config.dispersion import case_name

    return case_name(i)


def write_envelope_histories(env: list[dict], setters: dict, ref: ScenarioRef, cache_root: str, model_key: str,
                             executor, path: Path, captured: Captured | None = None) -> Path:
    """envelope_histories.h5: for each envelope value a generated case sets, that case's
    history of the item (captured while the campaign ran, ``captured``; else the case re-run
    on ``executor``, only those columns sent back); the other captured files are deleted.
    Layout (netCDF/xarray, every axis a dimension scale): root ``items`` (the envelope rows)
    with ``units``; per setting case a group ``cases/<case>`` with ``time`` (s), ``row`` (the
    values it sets: index into ``items``), ``side`` (max or min), ``item``, ``unit``,
    ``t_extreme`` (s) on ``row``, and ``value`` (time x row, each column in its row's unit)."""
    from liftoff.core.records import Dataset

    data: dict = {"items": np.array([r["item"] for r in env], dtype=str),
                  "units": Dataset(np.array([r["unit"] for r in env], dtype=str), "1", dims=("items",)),
                  "cases": {}}

    def store(res) -> None:
        index, t, cols = res
        name = case_name_of(index)
        rows = setters[index]
        data["cases"][name] = {
            "time": Dataset(t, "s"),
            "row": Dataset(np.array([j for j, _ in rows], dtype=np.int64), "1"),
            "side": Dataset(np.array([side for _, side in rows], dtype=str), "1", dims=("row",)),
            "item": Dataset(np.array([env[j]["item"] for j, _ in rows], dtype=str), "1", dims=("row",)),
            "unit": Dataset(np.array([env[j]["unit"] for j, _ in rows], dtype=str), "1", dims=("row",)),
            "t_extreme": Dataset(np.array([env[j][f"t_{side}"] for j, side in rows]), "s", dims=("row",)),
            "value": Dataset(np.column_stack([cols[env[j]["item"]] for j, _ in rows]), "SI: the row's unit",
                             dims=("time", "row"))}

    rerun = []
    for i in sorted(setters):
        cols = tuple(env[j]["item"] for j, _ in setters[i])
        got = captured.load(i, cols) if captured is not None else None
        if got is None:
            rerun.append(CaseTask(ref, i, cache_root, model_key, cols))
        else:
            store((i, *got))
    if captured is not None:
        captured.prune(setters)
    run_tasks(executor, rerun, store, 4 * max(1, getattr(executor, "_max_workers", 2) or 2))
    return write_record(path, "liftoff-envelope-histories", 2, data, units="SI per row (unit); s",
                        attrs={"layout": "cases/<case>/value (time x row): the history of envelope row "
                                         "items[row] in the case that sets its max or min (side), on that case's "
                                         "time; rows set by named cases are in their results_<case>.h5"})
