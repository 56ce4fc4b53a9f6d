"""Fuzzed bad input (issue 16): a few hundred generated cases through the command line.

Each case breaks one thing of a valid scenario (a value of every key replaced by values of
the wrong type, non-finite, huge, tiny, negative or malformed; a key removed; a body file
rewritten with wrong shapes, dtypes or magnitudes; the file's bytes damaged). Every case
must end in one of two ways:

* refused: exactly one line ``liftoff: error: ...`` on stderr (warnings, one line each,
  may precede it), no traceback, exit status 2 for bad input (the line naming the file),
  4 for a resource limit (the line naming the limit), 3 for a solution that does not
  converge, and the output folder exactly as it was (a previous run's files, unchanged);
* accepted (some mutations are valid input, e.g. a key removed that has a default):
  exit 0 and a complete, manifest-checked output folder.

The generator is seeded, so a failure names a reproducible case.
"""
from __future__ import annotations

import contextlib
import copy
import io
import math
import random
import tomllib
from pathlib import Path

import numpy as np
import pytest

from liftoff.config import default_text
from liftoff.workflows.cli import main
from liftoff.workflows.outdir import MANIFEST, verify

from .conftest import base_scenario, case_dir, write_scenario  # noqa: F401 (fixture)

BAD_VALUES = [float("nan"), float("inf"), -float("inf"), 1e308, -1e308, 1e200, 0, 0.0, -1, -1e-300, 5e-324,
              10 ** 400, True, "", ".", "x/../../y", "a\x00b", "é" * 3, "x" * 300, [], [1, "a"], [[1.0]],
              {"k": 1}, None]


def _paths(node, prefix=()):
    """Every key path of a scenario (tables by key, arrays by index)."""
    if isinstance(node, dict):
        for k, v in node.items():
            yield prefix + (k,)
            yield from _paths(v, prefix + (k,))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield prefix + (i,)
            yield from _paths(v, prefix + (i,))


def _mutated(base: dict, path: tuple, value) -> dict:
    d = copy.deepcopy(base)
    node = d
    for p in path[:-1]:
        node = node[p]
    if value is None:
        if isinstance(node, list):
            node.pop(path[-1])
        else:
            node.pop(path[-1])
    else:
        node[path[-1]] = value
    return d


def _cases(base: dict, n: int, seed: int) -> list[tuple[str, dict]]:
    rng = random.Random(seed)
    paths = list(_paths(base))
    out = []
    for _ in range(n):
        path, value = rng.choice(paths), rng.choice(BAD_VALUES)
        out.append((f"{'.'.join(map(str, path))}={value!r:.30}", _mutated(base, path, value)))
    return out


# ------------------------------------------------------------------ TOML
def _val(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return "nan" if math.isnan(v) else ("inf" if v == math.inf else "-inf" if v == -math.inf else repr(v))
    if isinstance(v, int):
        return str(v)
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"').replace("\x00", "\\u0000") + '"'
    if isinstance(v, list):
        return "[" + ", ".join(_val(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f'"{k}" = {_val(x)}' for k, x in v.items()) + "}"
    raise TypeError(type(v))


def _toml(d: dict) -> str:
    """TOML of a scenario dict: scalars and inline tables for nested tables (any depth)."""
    lines = []
    for k, v in d.items():
        if isinstance(v, list) and v and all(isinstance(x, dict) for x in v):
            continue
        if not isinstance(v, dict):
            lines.append(f'"{k}" = {_val(v)}')
    for k, v in d.items():
        if isinstance(v, dict):
            lines.append(f'["{k}"]')
            lines += [f'"{kk}" = {_val(x)}' for kk, x in v.items()]
        elif isinstance(v, list) and v and all(isinstance(x, dict) for x in v):
            for item in v:
                lines.append(f'[["{k}"]]')
                lines += [f'"{kk}" = {_val(x)}' for kk, x in item.items()]
    return "\n".join(lines) + "\n"


# ------------------------------------------------------------------ running and judging
def _state(out: Path):
    """What a later failed run must not change: the files and the manifest of the output folder."""
    if not out.exists():
        return None
    return sorted((p.name, p.stat().st_size, p.stat().st_mtime_ns) for p in out.iterdir())


def _run(args: list[str]) -> tuple[int, str]:
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        try:
            code = main(args)
        except SystemExit as exc:        # argparse (usage errors)
            code = exc.code
    return code, err.getvalue()


def _judge(name: str, code: int, err: str, out: Path, before, source: str) -> str:
    """'ok' or 'refused' for a case that ended as documented (module docstring); AssertionError else."""
    assert "Traceback" not in err, f"{name}: traceback\n{err}"
    lines = [ln for ln in err.strip().splitlines() if not ln.startswith("liftoff: warning: ")]
    if code == 0:
        assert not lines, f"{name}: exit 0 with errors\n{err}"
        assert verify(out) == [] and (out / MANIFEST).is_file(), f"{name}: exit 0 without a complete output"
        return "ok"
    assert len(lines) == 1 and lines[0].startswith("liftoff: error: "), f"{name}: not one error line\n{err}"
    assert code in (2, 3, 4), f"{name}: exit {code} (1 is an internal error)\n{err}"
    if code == 2:
        assert f"{source}" in lines[0] or "body" in lines[0], f"{name}: the file is not named\n{err}"
    if code == 4:
        assert "limit" in lines[0], f"{name}: a resource error without its limit\n{err}"
    if code == 3:
        assert "converge" in lines[0] or "diverged" in lines[0], f"{name}: {err}"
    assert _state(out) == before, f"{name}: the output folder changed"
    return "refused"


def _fuzz(directory: Path, cases, command: list[str], source: str) -> dict:
    out = directory / "out"
    tally = {"ok": 0, "refused": 0}
    for i, (name, data) in enumerate(cases):
        scenario = directory / source
        if isinstance(data, bytes):
            scenario.write_bytes(data)
        else:
            scenario.write_text(_toml(data))
        before = _state(out)
        code, err = _run([command[0], str(scenario), "--out", str(out), *command[1:]])
        tally[_judge(f"case {i} {name}", code, err, out, before, source)] += 1
    return tally


def _damaged_bytes(text: str, rng: random.Random, n: int) -> list[tuple[str, bytes]]:
    raw = text.encode()
    out = [("empty", b""), ("random", bytes(rng.randrange(256) for _ in range(200))),
           ("latin-1", "title = 'été'\n".encode("latin-1")), ("nul", raw[:50] + b"\x00" + raw[50:])]
    for k in range(n):
        cut = rng.randrange(1, len(raw))
        out.append((f"truncated at {cut}", raw[:cut]))
        pos = rng.randrange(len(raw))
        out.append((f"byte {pos} flipped", raw[:pos] + bytes([raw[pos] ^ 0x5A]) + raw[pos + 1:]))
    return out


# ------------------------------------------------------------------ liftoff transient
def _body_cases(directory: Path, rng: random.Random):
    """(name, {file: arrays}) body files damaged one array at a time."""
    edits = [("transposed", lambda a: a.T.copy() if a.ndim == 2 else a[::-1].copy()),
             ("flattened", lambda a: a.ravel()), ("3-D", lambda a: a[None]), ("complex", lambda a: a + 1j),
             ("NaN", lambda a: np.full_like(a, np.nan, dtype=float)), ("1e308", lambda a: np.full(a.shape, 1e308)),
             ("text", lambda a: a.astype(str)), ("empty", lambda a: np.zeros((0,))),
             ("one more row", lambda a: np.concatenate([a, a[:1]]) if a.ndim else a)]
    out = []
    for body in ("vehicle.npz", "pad.npz"):
        with np.load(directory / body) as z:
            data = {k: z[k] for k in z.files}
        for key in ("omega", "zeta", "phi", "participation", "rigid_body_mass", "dof_labels", "version", "format"):
            for label, fn in rng.sample(edits, 3):
                try:
                    arr = fn(data[key])
                except Exception:  # noqa: BLE001 - an edit that does not apply to this array
                    continue
                out.append((f"{body}:{key} {label}", body, {**data, key: arr}))
        out.append((f"{body}: no phi", body, {k: v for k, v in data.items() if k != "phi"}))
    return out


def test_fuzz_transient(case_dir: Path):  # noqa: F811 (fixture)
    rng = random.Random(16)
    base = base_scenario()
    base["time"] = {"t_end": 0.004, "h": 1.0e-4}   # 40 steps: accepted mutations stay cheap
    write_scenario(case_dir, base)
    out = case_dir / "out"
    code, err = _run(["transient", str(case_dir / "scenario.toml"), "--out", str(out), "--no-progress"])
    assert code == 0, err
    cases = _cases(base, 260, seed=16) + _damaged_bytes(_toml(base), rng, 15)
    tally = _fuzz(case_dir, cases, ["transient", "--no-progress"], "scenario.toml")
    # body files: a valid scenario over damaged bodies
    (case_dir / "scenario.toml").write_text(_toml(base))
    originals = {b: (case_dir / b).read_bytes() for b in ("vehicle.npz", "pad.npz")}
    for name, body, data in _body_cases(case_dir, rng):
        np.savez(case_dir / body, **data)
        before = _state(out)
        code, err = _run(["transient", str(case_dir / "scenario.toml"), "--out", str(out), "--no-progress"])
        tally[_judge(name, code, err, out, before, "scenario.toml")] += 1
        (case_dir / body).write_bytes(originals[body])
    print(f"\nliftoff transient fuzz: {tally}")
    assert tally["refused"] >= 250 and sum(tally.values()) >= 320


# ------------------------------------------------------------------ liftoff run (stick model)
# (system modes cut without residual vectors on purpose: a small modal model with a large step;
# the modes kept and their convergence are tests/workflows/test_truncation_run.py's)
STICK = {"source": "stick", "mesh_size": 6.0, "zeta": 0.01,
         "system": {"f_max": 60.0, "pad_f_max": 100.0, "residual_vectors": False}, "pad": {"f_max": 100.0}}


def test_fuzz_run_stick(tmp_path: Path):
    base = tomllib.loads(default_text())
    base["model"] = STICK
    base["time"]["t_end"] = 0.05       # the bolted stack under the first engine start: a cheap transient
    base["output"] = {"plots": False}
    base["case"] = [{"name": "nominal"}, {"name": "no-control", "control": {"enabled": False}}]
    cache = tmp_path / "cache"
    (tmp_path / "s.toml").write_text(_toml(base))
    common = ["--cache", str(cache), "--no-progress", "--no-snapshots"]
    code, err = _run(["run", str(tmp_path / "s.toml"), "--out", str(tmp_path / "out"), *common])
    assert code == 0, err
    rng = random.Random(61)
    cases = _cases(base, 110, seed=61) + _damaged_bytes(_toml(base), rng, 5)
    tally = _fuzz(tmp_path, cases, ["run", *common], "s.toml")
    print(f"\nliftoff run fuzz: {tally}")
    assert tally["refused"] >= 80 and sum(tally.values()) >= 120


@pytest.mark.parametrize("args", [["--max-memory", "-1"], ["--max-memory", "nan"], ["--method", "rk4"], ["--bogus"]])
def test_fuzz_options(case_dir: Path, args):  # noqa: F811 (fixture)
    """Bad options: a one-line usage error, exit 2, no output."""
    scenario = write_scenario(case_dir, base_scenario())
    code, err = _run(["transient", str(scenario), "--out", str(case_dir / "out"), *args])
    assert code == 2 and err.count("\n") == 1 and err.startswith("liftoff: error: ")
    assert not (case_dir / "out").exists()
