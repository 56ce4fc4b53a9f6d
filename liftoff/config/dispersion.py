"""Generated load cases (``[dispersion]``): random variables on scenario values and database
cases read from files. Units are those of the values they disperse (SI).

A generated case is the base scenario (or the named case ``from``) with

* every ``[dispersion.variables.<name>]`` drawn and applied to its ``targets``: scenario
  values addressed by a path such as ``engine[srb_left].start``, ``post[*].release_time``,
  ``engine[srb_left].direction[0]``, ``force[wind_*].scale`` or ``control.ramp``
  (``[name]`` selects an entry of an array of tables by name, ``[3]`` by position, ``*``
  and ``?`` match names); ``op`` adds the draw to the value, scales it, or sets it;
* with ``[dispersion.database]``, the forcing time histories of one file (CSV or HDF5,
  one per case) added as tabulated vehicle forces: case i takes file ``i mod n_files``.

Case ``i`` is reproducible from the scenario and its index alone: every draw takes one
uniform number from its own stream, ``numpy.random.SeedSequence([seed, i, crc32(key)])``
with ``key`` the variable's name (one shared draw) or ``name|target`` (one draw per
target, ``independent = true``), turned into the variable's distribution by its inverse
CDF. Adding a variable or a case therefore never changes the draws of the others.
"""
from __future__ import annotations

import copy
import csv
import io
import math
import operator
import re
import zlib
from dataclasses import dataclass
from fnmatch import fnmatchcase
from pathlib import Path
from typing import Any, Callable, NamedTuple

import numpy as np

from liftoff.core.errors import InputError
from liftoff.core.labels import split_label

from .files import file_path
from .values import Where, boolean, choice, integer, number, string, strings, table

KEYS = {"seed", "n_cases", "from", "variables", "database"}
VARIABLE_KEYS = {"targets", "op", "distribution", "mean", "std", "low", "high", "independent", "description"}
DATABASE_KEYS = {"files"}
DISTRIBUTIONS = ("normal", "uniform", "truncnormal")
OPS = ("add", "scale", "set")
NOT_DISPERSED = ("model", "title", "description", "case", "dispersion", "postprocess", "recovery", "output")
# values the scenario layer defaults when a table omits them (what "add"/"scale" start from)
DEFAULTS = {"engine": {"start": 0.0, "scale": 1.0, "direction": [0.0, 0.0, 1.0]}, "force": {"scale": 1.0}}
_SEGMENT = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*)((?:\[[^\[\]]+\])*)$")


#: the most generated cases of one run ([dispersion] n_cases and --cases): every case is
#: checked before the first runs (a few ms each), and the run keeps a record path and name
#: per case until its envelope is written (workflows/campaign.py)
MAX_CASES = 10 ** 7


def check_case_count(source: str, n_cases: Any) -> int:
    """``n_cases`` of the command line (--cases) as an int in [0, MAX_CASES], or a one-line
    InputError, before any case is generated."""
    try:
        n = None if isinstance(n_cases, bool) else operator.index(n_cases)
    except TypeError:
        n = None
    if n is None or not 0 <= n <= MAX_CASES:
        raise InputError(f"{source}: --cases {n_cases}: out of range [0, {MAX_CASES}] (the most generated cases of "
                         "one run; split a larger campaign into runs)")
    return n


def case_name(index: int) -> str:
    """The name of generated case ``index`` (0-based): d0000, d0001, ..."""
    return f"d{index:04d}"


# --------------------------------------------------------------------- paths
def parse_path(where: Where, text: str) -> list[tuple[str, list[str]]]:
    """``engine[srb_left].direction[0]`` -> [("engine", ["srb_left"]), ("direction", ["0"])]."""
    out = []
    for seg in string(where, text).split("."):
        m = _SEGMENT.match(seg)
        if not m:
            raise where.error(f"{text!r} is not a value path like engine[srb_left].start or post[*].release_time")
        out.append((m.group(1), re.findall(r"\[([^\[\]]+)\]", m.group(2))))
    if out[0][0] in NOT_DISPERSED:
        raise where.error(f"[{out[0][0]}] values cannot be dispersed" + (
            " (every case shares the model stages)" if out[0][0] == "model" else ""))
    return out


def _select(where: Where, container: Any, sel: str, path: str) -> list[tuple[str, int, Any]]:
    """(name, position, entry) of the entries of a list picked by ``[sel]``: a position, a
    name, or a name pattern (``*``, ``?``)."""
    if not isinstance(container, list):
        raise where.error(f"{path}: [{sel}] applied to a value that is not an array")
    if re.fullmatch(r"-?\d+", sel):
        k = int(sel)
        if not -len(container) <= k < len(container):
            raise where.error(f"{path}: index [{k}] out of range (the array has {len(container)} entries)")
        k %= len(container)
        return [(str(k), k, container[k])]
    named = [(str(x["name"]), k, x) for k, x in enumerate(container) if isinstance(x, dict) and "name" in x]
    hits = [h for h in named if fnmatchcase(h[0], sel)]
    if not hits:
        raise where.error(f"{path}: no entry named {sel!r} (names: {', '.join(n for n, _, _ in named) or 'none'})")
    return hits


def expand(where: Where, raw: dict, text: str) -> list[tuple[str, tuple, Any]]:
    """Concrete targets of a path in the scenario mapping ``raw``: (label, steps, value),
    the steps being table keys and array positions; patterns give one target per matching
    entry; the value is the one in force (a table's own, or the default it takes), None
    if there is none."""
    found = [("", (), raw)]
    for key, sels in parse_path(where, text):
        nxt = []
        for label, steps, node in found:
            label = f"{label}.{key}" if label else key
            if not isinstance(node, dict):
                raise where.error(f"{text}: {label} is inside a value that is not a table")
            value = node.get(key)
            cur = [(label, steps + (key,), _default(raw, steps, key) if value is None else value)]
            for sel in sels:
                new = []
                for lab, st, v in cur:
                    if v is None:
                        raise where.error(f"{text}: the scenario has no {lab!r}")
                    new += [(f"{lab}[{name}]", st + (pos,), x) for name, pos, x in _select(where, v, sel, text)]
                cur = new
            nxt += cur
        found = nxt
    return found


def _default(raw: dict, steps: tuple, key: str):
    """The value a table omits and the scenario layer supplies (post_defaults, engine and
    force defaults); None if there is none."""
    if len(steps) == 2 and steps[0] == "post" and key in raw.get("post_defaults", {}):
        return copy.deepcopy(raw["post_defaults"][key])
    if len(steps) == 2 and steps[0] in DEFAULTS:
        return copy.deepcopy(DEFAULTS[steps[0]].get(key))
    return None


def _locate(raw: dict, steps: tuple) -> tuple[Any, Any]:
    """(container, key or position) of the last step; a defaulted table value on the way
    is copied into its table first."""
    node = raw
    for i, st in enumerate(steps[:-1]):
        nxt = node[st] if isinstance(node, list) else node.get(st)
        if nxt is None:
            nxt = node[st] = _default(raw, steps[:i], st)
        node = nxt
    return node, steps[-1]


def apply(where: Where, raw: dict, steps: tuple, label: str, op: str, value: float) -> None:
    """Apply one draw to the value at ``steps`` of ``raw`` (in place): add, scale or set; a
    vector is changed entry by entry."""
    node, key = _locate(raw, steps)
    old = node[key] if isinstance(node, list) else node.get(key)
    if old is None:
        old = _default(raw, steps[:-1], key)
    if old is None:
        if op != "set":
            raise where.error(f"{label}: the scenario gives no value to {op} (give one, or use op = \"set\")")
        node[key] = value
        return

    def one(x):
        if isinstance(x, bool) or not isinstance(x, (int, float)):
            raise where.error(f"{label}: {x!r} is not a number")
        return {"add": x + value, "scale": x * value, "set": value}[op]

    node[key] = [one(x) for x in old] if isinstance(old, list) else one(old)


# --------------------------------------------------------------------- variables
@dataclass(frozen=True)
class Variable:
    """One named random variable (``[dispersion.variables.<name>]``): distribution
    ``normal`` (mean, std), ``uniform`` (low, high) or ``truncnormal`` (mean, std, low,
    high), applied with ``op`` to each of its ``targets``; one draw per target when
    ``independent``, else one shared draw."""

    name: str
    targets: tuple[str, ...]
    op: str
    distribution: str
    mean: float = 0.0
    std: float = 0.0
    low: float = -math.inf
    high: float = math.inf
    independent: bool = True
    description: str = ""

    def draw(self, seed: int, index: int, target: str = "") -> float:
        """The value of case ``index`` (for ``target`` when independent): inverse CDF of one
        uniform from SeedSequence([seed, index, crc32(key)])."""
        from scipy.special import ndtr, ndtri

        key = f"{self.name}|{target}" if self.independent else self.name
        u = np.random.default_rng(np.random.SeedSequence([seed, index, zlib.crc32(key.encode())])).random()
        u = min(max(u, 1e-300), 1.0 - 2.0 ** -53)
        if self.distribution == "uniform":
            return float(self.low + (self.high - self.low) * u)
        if self.distribution == "normal":
            return float(self.mean + self.std * ndtri(u))
        a, b = ndtr((self.low - self.mean) / self.std), ndtr((self.high - self.mean) / self.std)
        return float(np.clip(self.mean + self.std * ndtri(a + u * (b - a)), self.low, self.high))


#: the columns of a campaign's cases.csv beside the draws (workflows.campaign.feed_records): a
#: shared variable's column is its name, so none may take one of these
CASE_COLUMNS = ("index", "name", "database", "h", "n_steps", "first_separation", "last_separation",
                "max_recontacts", "peak_post_compression", "wall_s")


def variable(where: Where, name: str, spec: Any) -> Variable:
    if name in CASE_COLUMNS:
        raise where.error(f"the name {name!r} is a column of cases.csv (the case's {name}); name the variable "
                          "otherwise")
    v = table(where, spec, VARIABLE_KEYS, required=("targets", "distribution"))
    dist = choice(where / "distribution", v["distribution"], DISTRIBUTIONS)
    targets = v["targets"] if isinstance(v["targets"], list) else [v["targets"]]
    targets = strings(where / "targets", targets, nonempty=True)
    need = {"normal": ("mean", "std"), "uniform": ("low", "high"), "truncnormal": ("mean", "std", "low", "high")}[dist]
    for key in need:
        if key not in v:
            raise where.error(f"missing {key!r} for a {dist} distribution (needs {', '.join(need)})")
    extra = sorted(set(v) & {"mean", "std", "low", "high"} - set(need))
    if extra:
        raise (where / extra[0]).error(f"not a parameter of a {dist} distribution (give {', '.join(need)})")
    par = {k: number(where / k, v[k]) for k in need}
    if "std" in par and not par["std"] > 0:
        raise (where / "std").error(f"must be positive, got {par['std']:g}")
    if "low" in par and not par["high"] > par["low"]:
        raise (where / "high").error(f"must be greater than low = {par['low']:g}, got {par['high']:g}")
    if dist == "truncnormal" and not par["low"] <= par["mean"] <= par["high"]:
        raise (where / "mean").error(f"must lie within [low, high] = [{par['low']:g}, {par['high']:g}]")
    return Variable(name, targets, choice(where / "op", v.get("op", "add"), OPS), dist, **par,
                    independent=boolean(where / "independent", v.get("independent", True)),
                    description=string(where / "description", v.get("description", ""), nonempty=False))


# --------------------------------------------------------------------- database
class Forcing(NamedTuple):
    """One database file: ``labels`` (k DOF labels), ``time`` (n_t,) s, ``values`` (n_t, k)
    N or N m, and ``columns``: where each label stands in the file (``line 1, column 2``
    of a CSV, ``labels[0]`` of an HDF5 file), for messages."""

    labels: list[str]
    time: np.ndarray
    values: np.ndarray
    columns: list[str]


@dataclass(frozen=True)
class Database:
    """``[dispersion.database] files``: one forcing file per case, CSV (header ``time``,
    then one DOF label per column; values in N or N m) or HDF5 (datasets ``time`` (s),
    ``force`` (n_t, k) in N / N m, ``labels`` (k,)); each column becomes a tabulated force
    on the vehicle. ``base``: the scenario's folder (messages name a file relative to it)."""

    files: tuple[Path, ...]
    base: Path = Path(".")

    def shown(self, path: Path) -> str:
        """``path`` as the scenario's folder sees it (``db/gust_0.csv``)."""
        try:
            return str(path.relative_to(self.base))
        except ValueError:
            return str(path)

    def forces(self, where: Where, index: int) -> tuple[str, list[dict]]:
        path = self.files[index % len(self.files)]
        f = read_forcing(where, path, self.shown(path))
        return path.name, [{"label": lab, "time": f.time.tolist(), "value": f.values[:, j].tolist()}
                           for j, lab in enumerate(f.labels)]

    def check(self, where: Where, known: Callable[[str], Any]) -> None:
        """Every file read once, and each column's DOF given to ``known`` (say the vehicle's
        ``dof_index``, raising InputError for a DOF it lacks): before any case runs, a bad
        file is named with its line and column, not as the generated force it would become."""
        for path in dict.fromkeys(self.files):
            f = read_forcing(where, path, self.shown(path))
            for lab, col in zip(f.labels, f.columns):
                try:
                    known(lab)
                except InputError as exc:
                    raise where.error(f"{self.shown(path)} {col} {lab!r}: {' '.join(str(exc).split())}") from None


def database(where: Where, spec: Any, base: Path) -> Database:
    d = table(where, spec, DATABASE_KEYS, required=("files",))
    pats = strings(where / "files", d["files"] if isinstance(d["files"], list) else [d["files"]], nonempty=True)
    files = []
    for i, pat in enumerate(pats):
        try:
            hits = sorted(base.glob(pat)) if any(c in pat for c in "*?[") else [file_path(where / "files" / i, pat, base)]
            hits = [h for h in hits if h.is_file()]
        except (ValueError, NotImplementedError, OSError) as exc:      # (an absolute or malformed pattern)
            raise (where / "files" / i).error(f"not a usable file pattern {pat[:200]!r}: "
                                              f"{' '.join(str(exc).split())} (give one relative to the scenario)") from None
        if not hits:
            raise (where / "files" / i).error(f"no file matches {pat!r} (relative to {str(base)!r})")
        files += hits
    return Database(tuple(files), base)


def _csv_forcing(where: Where, shown: str, path: Path) -> Forcing:
    """A CSV forcing file: header ``time,<label>,...``, then rows of numbers ('#' comments)."""
    text = path.read_bytes().decode("utf-8-sig", errors="replace")
    reader = csv.reader(io.StringIO(text))
    rows = [(reader.line_num, r) for r in reader if r and not r[0].lstrip().startswith("#")]
    if len(rows) < 3:
        raise where.error(f"{shown}: expected a header (time, DOF labels) and at least 2 rows")
    head_line, head = rows[0]
    labels = [c.strip() for c in head[1:]]
    data = np.empty((len(rows) - 1, len(head)))
    for i, (line, r) in enumerate(rows[1:]):
        if len(r) != len(head):
            raise where.error(f"{shown} line {line}: {len(r)} columns, expected {len(head)} (time and one per label)")
        for c, cell in enumerate(r):
            try:
                data[i, c] = x = float(cell)
            except ValueError:
                x = None
            if x is None or not math.isfinite(x):
                what = "not a number" if x is None else "NaN or inf"
                raise where.error(f"{shown} line {line}, column {c + 1} {head[c].strip()!r}: {what}: {cell.strip()!r}")
    for (line, _), dt in zip(rows[2:], np.diff(data[:, 0])):
        if not dt > 0:
            raise where.error(f"{shown} line {line}: time is not strictly increasing")
    return Forcing(labels, data[:, 0], data[:, 1:], [f"line {head_line}, column {j + 2}" for j in range(len(labels))])


def read_forcing(where: Where, path: Path, shown: str | None = None) -> Forcing:
    """One database forcing file, checked; every error names ``shown`` (the file as the
    scenario's folder sees it; default its name) and the line and column (CSV) or the
    dataset (HDF5)."""
    shown = shown or path.name
    if path.suffix.lower() in (".h5", ".hdf5"):
        import h5py

        try:
            with h5py.File(path, "r") as f:
                labels = [s.decode() if isinstance(s, bytes) else str(s) for s in f["labels"][()]]
                time, values = np.asarray(f["time"][()], float), np.asarray(f["force"][()], float)
        except (OSError, KeyError, TypeError, ValueError) as exc:     # (a missing, grouped or text dataset)
            raise where.error(f"{shown}: not a forcing file with datasets time, force, labels "
                              f"({' '.join(str(exc).split())})") from None
        out = Forcing(labels, time, values, [f"labels[{j}]" for j in range(len(labels))])
        if time.ndim != 1:
            raise where.error(f"{shown}: time has shape {time.shape}, expected one row of times")
        if values.ndim != 2 or values.shape != (time.size, len(labels)) or time.size < 2:
            raise where.error(f"{shown}: force has shape {values.shape}, expected ({time.size}, {len(labels)}) "
                              "with >= 2 times")
        if not (np.all(np.isfinite(time)) and np.all(np.isfinite(values))):
            raise where.error(f"{shown}: NaN or inf in the forcing")
        if np.any(np.diff(time) <= 0):
            raise where.error(f"{shown}: time is not strictly increasing")
    else:
        out = _csv_forcing(where, shown, path)
    first: dict[str, str] = {}
    for lab, col in zip(out.labels, out.columns):
        try:
            split_label(lab)
        except InputError as exc:
            raise where.error(f"{shown} {col} {lab!r}: {exc}") from None
        if lab in first:
            raise where.error(f"{shown} {col} {lab!r}: the same DOF as {first[lab].split(', ')[-1]} (one column "
                              "per DOF)")
        first[lab] = col
    return out


# --------------------------------------------------------------------- the section
@dataclass(frozen=True)
class Dispersion:
    """``[dispersion]``: ``n_cases`` generated cases from the base (or the named case
    ``source``) with the ``variables`` drawn under ``seed`` and the ``database`` forcing."""

    seed: int
    n_cases: int
    source: str | None
    variables: tuple[Variable, ...]
    database: Database | None = None

    def columns(self, raw: dict, where: Where) -> list[tuple[Variable, str, tuple]]:
        """(variable, target label, steps) of every concrete draw, in a fixed order."""
        return [(v, lab, steps) for v in self.variables for t in v.targets
                for lab, steps, _ in expand(where / "variables" / v.name / "targets", raw, t)]

    def check(self, raw: dict, where: Where) -> None:
        """Every target names a value of ``raw`` that its variable can change."""
        for v in self.variables:
            for i, t in enumerate(v.targets):
                wt = where / "variables" / v.name / "targets" / i
                for lab, _, value in expand(wt, raw, t):
                    vals = value if isinstance(value, list) else [value]
                    if value is None and v.op != "set":
                        raise wt.error(f"{lab}: the scenario gives no value to {v.op} (give one, or op = \"set\")")
                    if value is not None and not all(isinstance(x, (int, float)) and not isinstance(x, bool)
                                                     for x in vals):
                        raise wt.error(f"{lab}: {value!r} is not a number or an array of numbers")

    def generate(self, raw: dict, index: int, where: Where, columns=None) -> tuple[dict, dict]:
        """(scenario mapping of case ``index``, {column: value drawn, 'database': file});
        ``columns``: :meth:`columns` of ``raw`` if already expanded."""
        out = copy.deepcopy(raw)
        info: dict[str, Any] = {}
        shared: dict[str, float] = {}
        for v, lab, steps in columns if columns is not None else self.columns(raw, where):
            if v.independent:
                x = v.draw(self.seed, index, lab)
            else:
                x = shared.setdefault(v.name, v.draw(self.seed, index))
            info[f"{v.name}[{lab}]" if v.independent else v.name] = x
            apply(where / "variables" / v.name, out, steps, lab, v.op, x)
        if self.database is not None:
            name, forces = self.database.forces(where / "database", index)
            out["force"] = list(out.get("force", [])) + forces
            info["database"] = name
        return out, info


def dispersion(where: Where, spec: Any, base: Path, n_cases: int | None = None) -> Dispersion:
    """Parse ``[dispersion]``; ``n_cases`` (the command line's --cases) overrides the file's."""
    d = table(where, spec, KEYS)
    seed = integer(where / "seed", d.get("seed", 0), 0, 2 ** 63 - 1)
    wv = where / "variables"
    variables = d.get("variables", {})
    if not isinstance(variables, dict):
        raise wv.error("expected a table of named variables [dispersion.variables.<name>]")
    from .values import unique_name

    names: set[str] = set()
    out = tuple(variable(wv / name, unique_name(wv / name, name, names, "variable"), v) for name, v in variables.items())
    db = database(where / "database", d["database"], base) if "database" in d else None
    n = integer(where / "n_cases", d.get("n_cases", len(db.files) if db else 0), 0, MAX_CASES)
    source = string(where / "from", d["from"]) if "from" in d else None
    return Dispersion(seed, n if n_cases is None else check_case_count(where.source, n_cases), source, out, db)
