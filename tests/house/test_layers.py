"""The building plan (README, Layout): one import name, imports pointing down only.

Walks every module's imports with ``ast`` (nothing is imported):

* layers, lowest first: core; meshes and transient; fem, reduction and analysis; config;
  workflows. A module may import its own layer's package and lower ones, except that meshes
  and fem never import transient, reduction imports transient only for ModalBody, and
  reduction and analysis never import meshes or fem (they run on matrices and histories
  from elsewhere; analysis takes only the step coefficients from transient);
* only meshes/ and fem/ import gmsh, dolfinx, ufl, PETSc, SLEPc or MPI (one exception: the
  case runner's MPI executor, mpi4py.futures in workflows/executors.py, which farms out load
  cases and touches no FE object);
* no import cycle between modules (module-level imports);
* a built wheel adds exactly one top-level import name, ``liftoff``.
"""
from __future__ import annotations

import ast
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PACKAGES = {"core": ROOT / "liftoff" / "core", "config": ROOT / "liftoff" / "config", "meshes": ROOT / "meshes",
            "fem": ROOT / "fem", "reduction": ROOT / "reduction", "transient": ROOT / "transient",
            "analysis": ROOT / "analysis", "workflows": ROOT / "workflows"}
PACKAGES_DIRS = ("liftoff", "meshes", "fem", "reduction", "transient", "analysis", "workflows")
FLOOR = {"core": 0, "meshes": 1, "transient": 1, "fem": 2, "reduction": 2, "analysis": 2, "config": 3, "workflows": 4}
FE_STACK = {"gmsh", "dolfinx", "ufl", "basix", "ffcx", "petsc4py", "slepc4py", "mpi4py"}


def _modules():
    """(package, dotted module name, path) of every module of every layer."""
    for pkg, folder in PACKAGES.items():
        if not folder.is_dir():
            continue
        for f in sorted(folder.rglob("*.py")):
            rel = f.relative_to(folder).with_suffix("")
            parts = [] if rel.name == "__init__" and rel.parent == Path(".") else list(rel.parts)
            if parts and parts[-1] == "__init__":
                parts = parts[:-1]
            yield pkg, ".".join(["liftoff", pkg, *parts]), f


def _imports(module: str, path: Path, top_level_only: bool = False):
    """Absolute dotted names imported by a module (relative imports resolved)."""
    tree = ast.parse(path.read_text())
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    nodes = tree.body if top_level_only else ast.walk(tree)
    for node in nodes:
        if isinstance(node, ast.Import):
            for a in node.names:
                yield node.lineno, a.name
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - node.level + 1]
                yield node.lineno, ".".join(base + ([node.module] if node.module else []))
            else:
                yield node.lineno, node.module or ""


def _names(path: Path, line: int) -> set[str]:
    """The names a ``from ... import`` statement at ``line`` takes."""
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.lineno == line:
            return {a.name for a in node.names}
    return {"*"}


def _layer(name: str) -> str | None:
    parts = name.split(".")
    if parts[0] == "liftoff" and len(parts) > 1 and parts[1] in FLOOR:
        return parts[1]
    return None


def test_imports_point_down():
    bad = []
    for pkg, module, path in _modules():
        for line, name in _imports(module, path):
            target = _layer(name)
            where = f"{path.relative_to(ROOT)}:{line} imports {name}"
            if name.split(".")[0] in (set(PACKAGES) - {"core", "config"}):
                bad.append(where + " (outside the liftoff namespace)")
            mpi_executor = name == "mpi4py.futures" and module == "liftoff.workflows.executors"
            if name.split(".")[0] in FE_STACK and pkg not in ("meshes", "fem") and not mpi_executor:
                bad.append(where + " (the FE stack belongs to meshes/ and fem/)")
            if target is None or target == pkg:
                continue
            ok = FLOOR[target] < FLOOR[pkg]
            if pkg in ("meshes", "fem") and target == "transient":
                ok = False
            if pkg == "reduction":
                ok = target == "core" or (name in ("liftoff.transient.body", "liftoff.transient")
                                          and _names(path, line) <= {"ModalBody"})
            if pkg == "analysis":
                ok = target == "core" or name == "liftoff.transient.coefficients"
            if not ok:
                bad.append(where)
    assert not bad, "imports against the layers:\n" + "\n".join(bad)


def test_no_import_cycles():
    graph = {}
    for _, module, path in _modules():
        graph[module] = {n for _, n in _imports(module, path, top_level_only=True) if n.startswith("liftoff.")}
    names = set(graph)
    for m in graph:  # 'from liftoff.x import y' may name a module liftoff.x.y: keep existing modules only
        graph[m] = {n for n in graph[m] if n in names and n != m}
    state, cycle = {}, []

    def visit(m, stack):
        state[m] = 1
        for n in sorted(graph[m]):
            if state.get(n) == 1:
                cycle.append(stack[stack.index(n):] + [n])
            elif n not in state:
                visit(n, stack + [n])
        state[m] = 2

    for m in sorted(graph):
        if m not in state:
            visit(m, [m])
    assert not cycle, "import cycles: " + "; ".join(" -> ".join(c) for c in cycle)


def test_wheel_adds_one_import_name(tmp_path):
    """`pip install` adds exactly one top-level import name: the wheel holds liftoff/ only.
    Built from a copy of the sources, so that setuptools' build/ folder stays out of the tree."""
    src = tmp_path / "src"
    src.mkdir()
    for name in ("pyproject.toml", "README.md", *PACKAGES_DIRS, "examples"):
        (shutil.copytree if (ROOT / name).is_dir() else shutil.copy)(ROOT / name, src / name)
    proc = subprocess.run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "--no-build-isolation",
                           "-w", str(tmp_path), str(src)], capture_output=True, text=True, cwd=tmp_path)
    if proc.returncode != 0:
        pytest.fail(f"pip wheel failed: {proc.stderr[-2000:]}")
    wheel = next(tmp_path.glob("*.whl"))
    names = zipfile.ZipFile(wheel).namelist()
    tops = {n.split("/")[0] for n in names if not n.split("/")[0].endswith(".dist-info")}
    assert tops == {"liftoff"}, tops
    for sub in ("meshes", "fem", "reduction", "transient", "analysis", "workflows", "core", "config"):
        assert f"liftoff/{sub}/__init__.py" in names
    assert "liftoff/config/default_scenario.toml" in names
    from liftoff.config.extends import EXAMPLES     # liftoff init --example single_stick writes these

    ex = EXAMPLES["single_stick"]
    assert {f"liftoff/examples/single_stick/{f}" for f in (*ex.files, "scenario.toml")} <= set(names)
    assert not [n for n in names if n.startswith("liftoff/examples/") and n.endswith((".npz", "make_files.py"))]


def test_functions_fit_on_a_screen():
    """No function over 100 lines, no signature over 16 positional arguments (kernels take
    a few named bundles, not dozens of arrays)."""
    long, wide = [], []
    for _, module, path in _modules():
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                where = f"{path.relative_to(ROOT)}:{node.lineno} {node.name}"
                if node.end_lineno - node.lineno + 1 > 100:
                    long.append(f"{where} ({node.end_lineno - node.lineno + 1} lines)")
                if len(node.args.args) + len(node.args.posonlyargs) > 16:
                    wide.append(where)
    assert not long and not wide, f"too long: {long}; too wide: {wide}"


def test_one_translation_of_a_scenario_into_a_transient_problem():
    """Lift-off cases, barge cases and two-body files become a TransientProblem in one place,
    liftoff.config.sections.TimeSpan.problem (issue 23: three copies of the [time] mapping had
    drifted: the step-by-step script dropped tol, max_iter and accuracy). Only the transient
    layer itself (and its tests and benchmarks, outside these folders) builds one directly."""
    direct = []
    for pkg, module, path in _modules():
        if pkg == "transient" or module == "liftoff.config.sections":
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Call) and getattr(node.func, "id", getattr(node.func, "attr", None)) \
                    == "TransientProblem":
                direct.append(f"{path.relative_to(ROOT)}:{node.lineno}")
    assert not direct, direct
