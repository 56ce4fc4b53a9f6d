"""One gmsh session per test mesh file: start, build (the caller's block), mesh, write, finalize."""
from __future__ import annotations

from contextlib import contextmanager

import gmsh


@contextmanager
def gmsh_file(name: str, path, dim: int = 3, h: float | None = None):
    """``with gmsh_file("box", path, h=0.1): <OCC geometry, physical groups>``: then meshes
    ``dim``-D with the characteristic length ``h`` (None: the caller's own sizing) and writes
    ``path``; gmsh is finalized even when the block raises."""
    gmsh.initialize(["-nopopup"])
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.add(name)
    try:
        yield gmsh.model
        if h is not None:
            gmsh.option.setNumber("Mesh.CharacteristicLengthMax", h)
        gmsh.model.mesh.generate(dim)
        gmsh.write(str(path))
    finally:
        gmsh.finalize()
