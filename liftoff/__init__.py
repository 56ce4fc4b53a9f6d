"""liftoff: gmsh geometry -> dolfinx FE -> Craig-Bampton -> two-body modal contact transient.

One import namespace over the repository's top-level folders (pyproject.toml maps
``liftoff.meshes`` to ``meshes/`` and so on). Nothing is imported here: each layer is
imported on demand, so the numpy-only layers never pull in gmsh, dolfinx or PETSc.
"""
__version__ = "0.2.0"
