"""Full-field output readable by ParaView: VTU (VTK XML unstructured grid) via meshio.

Takes plain arrays (nodes, cells, nodal fields), so it also writes fields recovered from a
Craig-Bampton model (reduction's field_map). Atomic: temporary file + os.replace.
Coordinates in m, displacements in m (mass-normalised mode shapes in m/sqrt(kg)).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from liftoff.core.errors import InputError
from liftoff.core.records import atomic_path


def write_vtu(path, nodes: np.ndarray, cells, cell_type: str | None,
              point_data: dict[str, np.ndarray], field_data: dict | None = None,
              cell_data: dict[str, list] | None = None) -> Path:
    """Write a .vtu with nodal fields ``point_data`` (each (n_nodes,) or (n_nodes, k)).
    ``cell_type=None``: ``cells`` is a list of (cell_type, cells) blocks (several meshes
    in one file); ``cell_data``: name -> one array per block."""
    import meshio

    path = Path(path)
    if path.suffix != ".vtu":
        raise InputError(f"write_vtu: {str(path)!r} must end in .vtu")
    nodes = np.asarray(nodes, float)
    for k, v in point_data.items():
        if np.asarray(v).shape[0] != nodes.shape[0]:
            raise InputError(f"write_vtu: field {k!r} has {np.asarray(v).shape[0]} rows, mesh has {nodes.shape[0]} nodes")
    blocks = [(cell_type, cells)] if cell_type is not None else list(cells)
    mesh = meshio.Mesh(nodes, [(ct, np.asarray(c, np.int64)) for ct, c in blocks],
                       point_data={k: np.asarray(v, float) for k, v in point_data.items()},
                       cell_data={k: [np.asarray(a) for a in v] for k, v in (cell_data or {}).items()},
                       field_data=field_data or {})
    with atomic_path(path, suffix=".vtu") as tmp:
        meshio.write(str(tmp), mesh, file_format="vtu")
    return path


def write_modes_vtu(model, modes, path) -> Path | None:
    """All mode shapes of ``modes`` as vector fields ``mode_001_<f>Hz`` (written by rank 0)."""
    T = model.field_map()            # collective (gathers T on every rank)
    if model.comm.rank != 0:
        return None
    fields = {}
    for j, f in enumerate(modes.freq_hz):
        fields[f"mode_{j + 1:03d}_{f:.4g}Hz"] = (T @ modes.shapes[:, j]).reshape(-1, 3)
    return write_vtu(path, model.nodes, cell_blocks(model), None, fields)


def cell_blocks(mesh) -> list:
    """[(meshio cell type, cells)] of an FEModel or reduction.Component: its cells, then its
    beams' lines where it has both (``line_cells``)."""
    blocks = [(mesh.cell_type, mesh.cells)]
    lines = getattr(mesh, "line_cells", None)
    if lines is not None and len(lines):
        blocks.append(("line", lines))
    return blocks
