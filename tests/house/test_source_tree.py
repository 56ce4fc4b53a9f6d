"""Running from a source checkout (issue 27): with the repository root on sys.path (the
current folder, PYTHONPATH), ``import liftoff`` finds the root's ``liftoff/`` folder, which
holds only core/ and config/; the other subpackages are the root's fem/, transient/, ...
(pyproject.toml's [tool.setuptools.package-dir]). They must resolve there too, and an
installed package must not change."""
from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

# -I -S: no site-packages, so no installed or editable liftoff can answer; the only liftoff
# is the one under the folder put first on sys.path, as a checkout's root is
PROBE = """
import importlib.util, sys
sys.path.insert(0, sys.argv[1])
import liftoff
for name in ("liftoff.fem", "liftoff.transient", "liftoff.workflows", "liftoff.core"):
    spec = importlib.util.find_spec(name)
    print(name, spec.origin if spec else None)
"""


def _origins(folder: Path) -> dict[str, str]:
    out = subprocess.run([sys.executable, "-I", "-S", "-c", PROBE, str(folder)], capture_output=True, text=True,
                         timeout=60, check=True).stdout
    return dict(line.split(" ", 1) for line in out.splitlines())


def test_the_checkout_resolves_every_subpackage():
    got = _origins(ROOT)
    assert got == {"liftoff.fem": str(ROOT / "fem" / "__init__.py"),
                   "liftoff.transient": str(ROOT / "transient" / "__init__.py"),
                   "liftoff.workflows": str(ROOT / "workflows" / "__init__.py"),
                   "liftoff.core": str(ROOT / "liftoff" / "core" / "__init__.py")}, got


def test_an_installed_package_is_left_as_it_is(tmp_path):
    """The same liftoff/ folder without the checkout beside it (site-packages holds no
    pyproject.toml of liftoff-loads; here one of another project): nothing added."""
    site = tmp_path / "site"
    shutil.copytree(ROOT / "liftoff", site / "liftoff", ignore=shutil.ignore_patterns("__pycache__"))
    for d in ("fem", "transient", "workflows", "meshes", "reduction"):
        (site / d).mkdir()
        (site / d / "__init__.py").write_text("")
    (site / "pyproject.toml").write_text('[project]\nname = "another"\n')
    got = _origins(site)
    assert got["liftoff.fem"] == "None" and got["liftoff.transient"] == "None", got
    assert got["liftoff.core"] == str(site / "liftoff" / "core" / "__init__.py")
