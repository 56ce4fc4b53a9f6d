"""liftoff: gmsh geometry -> dolfinx FE -> Craig-Bampton -> two-body modal contact transient.

One import namespace over the repository's top-level folders (pyproject.toml maps
``liftoff.meshes`` to ``meshes/`` and so on). Nothing is imported here (but the
standard-library choice of OpenBLAS kernels, liftoff/core/openblas.py): each layer is
imported on demand, so the numpy-only layers never pull in gmsh, dolfinx or PETSc.
"""
__version__ = "0.2.0"


def _source_tree() -> None:
    """Run from a source checkout (its root on sys.path: the current folder, PYTHONPATH),
    ``import liftoff`` finds this folder, which holds only core/ and config/ (issue 27: it
    shadowed the installed package and ``liftoff.fem`` failed). There the checkout's root
    joins ``__path__``, so ``liftoff.fem`` is ../fem as pyproject.toml's package-dir maps it.
    A checkout is told by its pyproject.toml (project liftoff-loads) and every folder its
    [tool.setuptools.package-dir] names; an installed package changes nothing."""
    import os
    import tomllib

    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    try:
        with open(os.path.join(root, "pyproject.toml"), "rb") as fh:
            project = tomllib.load(fh)
    except (OSError, tomllib.TOMLDecodeError):
        return
    dirs = project.get("tool", {}).get("setuptools", {}).get("package-dir", {})
    if (project.get("project", {}).get("name") == "liftoff-loads" and dirs
            and all(os.path.isdir(os.path.join(root, d)) for d in dirs.values()) and root not in __path__):
        __path__.append(root)


def _blas_kernels() -> None:
    """OPENBLAS_CORETYPE before anything loads OpenBLAS (liftoff/core/openblas.py: the
    installed OpenBLAS falls back to generic kernels on CPUs it does not recognise). That
    file is run alone, standard library only: importing liftoff.core would load numpy first."""
    import importlib.util
    import os

    spec = importlib.util.spec_from_file_location("liftoff_core_openblas",
                                                  os.path.join(os.path.dirname(__file__), "core", "openblas.py"))
    if spec is None or spec.loader is None:     # not a plain file (a zip): OpenBLAS picks its own kernels
        return
    module = importlib.util.module_from_spec(spec)
    try:
        spec.loader.exec_module(module)
    except OSError:
        return
    module.choose_coretype()


_source_tree()
_blas_kernels()
