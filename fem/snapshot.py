"""Off-screen PNG pictures of deformed shapes (mode shapes, static or recovered fields).

Plain arrays in (nodes (n, 3) m, cells, meshio cell type, displacement (n, 3)), so the
workflow can draw Craig-Bampton-recovered fields too. The undeformed outline (feature
edges) is drawn in grey, the deformed surface coloured by |u|, with the title and the
displacement scale factor written on the picture. Works without a display.

Import this module (it imports pyvista) before dolfinx: the other order aborts the
process when a scalar bar is drawn (FENICSX-NOTES.md). If dolfinx was imported first, the
picture is rendered in a fresh Python subprocess instead (slower, but no crash).
"""
from __future__ import annotations

import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

_RENDER_IN_PROCESS = "dolfinx" not in sys.modules     # pyvista must come first (see above)
os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")
import pyvista  # noqa: E402

pyvista.OFF_SCREEN = True

from liftoff.core.errors import InputError  # noqa: E402
from liftoff.core.records import atomic_path  # noqa: E402

_VTK_TYPES = {"tetra": 10, "tetra10": 24, "triangle": 5, "triangle6": 22, "hexahedron": 12,
              "quad": 9, "line": 3, "wedge": 13}


def auto_scale(nodes: np.ndarray, displacement: np.ndarray, fraction: float = 0.1) -> float:
    """Scale factor that makes the largest displacement ``fraction`` of the model size."""
    size = float(np.linalg.norm(nodes.max(axis=0) - nodes.min(axis=0)))
    umax = float(np.linalg.norm(displacement, axis=1).max())
    return fraction * size / umax if umax > 0 else 1.0


def grid(nodes: np.ndarray, cells: np.ndarray, cell_type: str) -> "pyvista.UnstructuredGrid":
    if cell_type not in _VTK_TYPES:
        raise InputError(f"snapshot: cell type {cell_type!r} not supported ({', '.join(_VTK_TYPES)})")
    cells = np.asarray(cells, np.int64)
    k = cells.shape[1]
    conn = np.hstack([np.full((cells.shape[0], 1), k), cells]).ravel()
    types = np.full(cells.shape[0], _VTK_TYPES[cell_type], dtype=np.uint8)
    return pyvista.UnstructuredGrid(conn, types, np.asarray(nodes, float))


def snapshot_png(path, nodes: np.ndarray, cells: np.ndarray, cell_type: str, displacement: np.ndarray,
                 title: str = "", scale: float | None = None, window_size=(1024, 768),
                 view: str = "iso") -> Path:
    """Write a PNG of the deformed shape; returns the path. ``scale=None``: auto (10 % of size)."""
    path = Path(path)
    if path.suffix.lower() != ".png":
        raise InputError(f"snapshot: {str(path)!r} must end in .png")
    nodes = np.asarray(nodes, float)
    u = np.asarray(displacement, float).reshape(-1, 3)
    if u.shape[0] != nodes.shape[0]:
        raise InputError(f"snapshot: displacement has {u.shape[0]} rows, mesh has {nodes.shape[0]} nodes")
    if not np.all(np.isfinite(u)):
        raise InputError("snapshot: displacement contains NaN or inf")
    if scale is None:
        scale = auto_scale(nodes, u)
    if not _RENDER_IN_PROCESS:
        return _render_in_subprocess(path, nodes, cells, cell_type, u, title, scale, window_size, view)
    base = grid(nodes, cells, cell_type)
    deformed = base.copy()
    deformed.points = nodes + scale * u
    deformed.point_data["|u| (m)"] = np.linalg.norm(u, axis=1)
    pl = pyvista.Plotter(off_screen=True, window_size=list(window_size))
    pl.set_background("white")
    pl.add_mesh(base.extract_feature_edges(), color="grey", line_width=1)
    pl.add_mesh(deformed, scalars="|u| (m)", cmap="viridis", show_edges=False,
                scalar_bar_args={"title": "|u| (m)", "color": "black"})
    pl.add_text(title, position="upper_left", font_size=12, color="black")
    pl.add_text(f"displacement scale x {scale:.3g}", position="lower_left", font_size=10, color="black")
    if view == "iso":
        pl.view_isometric()
    elif view in ("xy", "xz", "yz"):
        getattr(pl, f"view_{view}")()
    else:
        raise InputError(f"snapshot: view {view!r} must be iso, xy, xz or yz")
    try:
        with atomic_path(path, suffix=".png") as tmp:
            pl.screenshot(str(tmp))
    finally:
        pl.close()
    return path


def snapshot_mode(path, model, modes, j: int, scale: float | None = None) -> Path | None:
    """Picture of mode ``j`` of an FE model (rank 0 draws; other ranks return None)."""
    u = model.nodal_displacement(modes.shapes[:, j])
    if model.comm.rank != 0:
        return None
    title = f"{model.name}: mode {j + 1}, {modes.freq_hz[j]:.4g} Hz"
    return snapshot_png(path, model.nodes, model.cells, model.cell_type, u, title, scale)


def _render_in_subprocess(path, nodes, cells, cell_type, u, title, scale, window_size, view) -> Path:
    """Render in a fresh interpreter (no dolfinx there); arrays passed through an .npz."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, npz = tempfile.mkstemp(dir=path.parent, suffix=".snapshot.npz")
    os.close(fd)
    try:
        np.savez(npz, nodes=nodes, cells=np.asarray(cells, np.int64), cell_type=np.array(cell_type),
                 u=u, title=np.array(title), scale=np.array(float(scale)),
                 window_size=np.asarray(window_size, np.int64), view=np.array(view), path=np.array(str(path)))
        res = subprocess.run([sys.executable, "-m", "liftoff.fem.snapshot", npz], capture_output=True, text=True)
        if res.returncode != 0 or not path.is_file():
            raise RuntimeError(f"snapshot subprocess failed ({res.returncode}): {res.stderr[-1000:]}")
    finally:
        os.unlink(npz)
    return path


if __name__ == "__main__":      # subprocess renderer: python -m liftoff.fem.snapshot args.npz
    with np.load(sys.argv[1], allow_pickle=False) as z:
        snapshot_png(z["path"].item(), z["nodes"], z["cells"], z["cell_type"].item(), z["u"],
                     z["title"].item(), float(z["scale"]), tuple(z["window_size"]), z["view"].item())
