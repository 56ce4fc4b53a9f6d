"""Default geometries built once per test session (meshes/ needs gmsh only), and a reader
that returns, per physical group of a .msh, its node coordinates and its mesh measure."""
from __future__ import annotations

import numpy as np
import pytest

gmsh = pytest.importorskip("gmsh")


def read_msh(path) -> dict:
    """{(dim, name): {"nodes": (n, 3) coords, "measure": mesh area/volume}} of a .msh."""
    gmsh.initialize([], False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.open(str(path))
        out = {}
        for dim, tag in gmsh.model.getPhysicalGroups():
            name = gmsh.model.getPhysicalName(dim, tag)
            coords, measure = {}, 0.0
            for ent in gmsh.model.getEntitiesForPhysicalGroup(dim, tag):
                tags, xyz, _ = gmsh.model.mesh.getNodes(dim, ent, includeBoundary=True)
                coords.update(zip(tags.tolist(), xyz.reshape(-1, 3)))
                etypes, _, enodes = gmsh.model.mesh.getElements(dim, ent)
                for et, en in zip(etypes, enodes):
                    nn = gmsh.model.mesh.getElementProperties(et)[3]
                    X = _node_lookup()[np.asarray(en, int).reshape(-1, nn)[:, : dim + 1]]
                    if dim == 2:
                        measure += 0.5 * np.linalg.norm(np.cross(X[:, 1] - X[:, 0], X[:, 2] - X[:, 0]), axis=1).sum()
                    elif dim == 3:
                        measure += np.abs(np.einsum("ij,ij->i", X[:, 1] - X[:, 0], np.cross(
                            X[:, 2] - X[:, 0], X[:, 3] - X[:, 0]))).sum() / 6.0
            out[(dim, name)] = {"nodes": np.array(list(coords.values())), "measure": measure}
        return out
    finally:
        _node_lookup.cache = None
        gmsh.finalize()


def _node_lookup() -> np.ndarray:
    """Dense node-tag -> coordinates array of the open model (cached while it is open)."""
    if getattr(_node_lookup, "cache", None) is None:
        tags, xyz, _ = gmsh.model.mesh.getNodes()
        table = np.full((int(tags.max()) + 1, 3), np.nan)
        table[tags.astype(int)] = xyz.reshape(-1, 3)
        _node_lookup.cache = table
    return _node_lookup.cache


@pytest.fixture(scope="session")
def stack(tmp_path_factory):
    from liftoff.meshes import default_stack
    return default_stack(out_dir=tmp_path_factory.mktemp("stack"))


@pytest.fixture(scope="session")
def pad(tmp_path_factory):
    from liftoff.meshes import default_pad
    return default_pad(out_dir=tmp_path_factory.mktemp("pad"))


@pytest.fixture(scope="session")
def msh_groups():
    cache = {}

    def get(geo):
        if geo.msh_path not in cache:
            cache[geo.msh_path] = read_msh(geo.msh_path)
        return cache[geo.msh_path]
    return get
