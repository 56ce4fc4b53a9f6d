"""Off-screen PNG pictures of deformed shapes (mode shapes, static or recovered fields).

Plain arrays in (one :class:`Part` per mesh: nodes (n, 3) m, cells, meshio cell type,
displacement (n, 3) m), so the workflow draws Craig-Bampton-recovered fields of a whole
stack with the same function. The undeformed outline (feature edges, or the lines of a
beam model) is drawn in grey, the deformed shape coloured by |u| on one colour scale, with
the title and the displacement scale factor written on the picture. Works without a display.

Import this module (it imports pyvista) before dolfinx: the other order aborts the
process when a scalar bar is drawn (FENICSX-NOTES.md). If dolfinx was imported first, the
picture is rendered in a fresh Python subprocess instead (slower, but no crash).
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

_RENDER_IN_PROCESS = "dolfinx" not in sys.modules     # pyvista must come first (see above)
os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")
import pyvista  # noqa: E402

pyvista.OFF_SCREEN = True
try:  # headless machines: VTK warns "bad X server connection" (in colour) and renders off-screen all the same
    from vtkmodules.vtkCommonCore import vtkLogger

    vtkLogger.SetStderrVerbosity(vtkLogger.VERBOSITY_ERROR)
except ImportError:  # pragma: no cover  (an older VTK without vtkLogger)
    pass

from liftoff.core.errors import InputError  # noqa: E402
from liftoff.core.records import atomic_path  # noqa: E402

_VTK_TYPES = {"tetra": 10, "tetra10": 24, "triangle": 5, "triangle6": 22, "hexahedron": 12,
              "quad": 9, "line": 3, "wedge": 13}


@dataclass
class Part:
    """One mesh in a picture: nodes (n, 3) m, cells (meshio ``cell_type``), displacement (n, 3) m."""

    nodes: np.ndarray
    cells: np.ndarray
    cell_type: str
    displacement: np.ndarray

    def __post_init__(self) -> None:
        self.nodes = np.asarray(self.nodes, float).reshape(-1, 3)
        self.cells = np.asarray(self.cells, np.int64)
        self.displacement = np.asarray(self.displacement, float).reshape(-1, 3)
        if self.cell_type not in _VTK_TYPES:
            raise InputError(f"snapshot: cell type {self.cell_type!r} not supported ({', '.join(_VTK_TYPES)})")
        if self.displacement.shape[0] != self.nodes.shape[0]:
            raise InputError(f"snapshot: displacement has {self.displacement.shape[0]} rows, "
                             f"mesh has {self.nodes.shape[0]} nodes")
        if not np.all(np.isfinite(self.displacement)):
            raise InputError("snapshot: displacement contains NaN or inf")

    def grid(self) -> "pyvista.UnstructuredGrid":
        k = self.cells.shape[1]
        conn = np.hstack([np.full((self.cells.shape[0], 1), k), self.cells]).ravel()
        types = np.full(self.cells.shape[0], _VTK_TYPES[self.cell_type], dtype=np.uint8)
        return pyvista.UnstructuredGrid(conn, types, self.nodes)


def mesh_parts(mesh, displacement) -> list[Part]:
    """The picture parts of a mesh-bearing object (an FEModel or a reduction.Component:
    ``nodes``, ``cells``, ``cell_type`` and ``line_cells``, the beams beside its cells, or
    None) deformed by ``displacement`` (n_nodes, 3)."""
    from .output import cell_blocks

    return [Part(mesh.nodes, cells, kind, displacement) for kind, cells in cell_blocks(mesh)]


#: quadratic cells drawn by their corners: (linear type, corner count); meshio's node order
#: puts the corners first
_CORNERS = {"tetra10": ("tetra", 4), "triangle6": ("triangle", 3)}


def picture_mesh(mesh) -> tuple[np.ndarray, list[tuple[str, np.ndarray]]]:
    """(the nodes a picture draws, [(cell type, cells over those nodes, numbered 0..)]) of a
    mesh-bearing object (as :func:`mesh_parts`): its quadratic cells by their corners
    (tetra10 -> tetra, triangle6 -> triangle), its linear cells and beams' lines as they are.
    A picture of a whole stack resolves its converged P2 meshes' corners as well as their
    edge nodes, and the field is then needed at a quarter to an eighth of the nodes only."""
    from .output import cell_blocks

    blocks = []
    for kind, cells in cell_blocks(mesh):
        cells = np.asarray(cells, np.int64)
        if kind in _CORNERS:
            kind, k = _CORNERS[kind]
            cells = cells[:, :k]
        blocks.append((kind, cells))
    used = np.unique(np.concatenate([c.ravel() for _, c in blocks]))
    number = np.full(len(mesh.nodes), -1, np.int64)
    number[used] = np.arange(used.size)
    return used, [(kind, number[cells]) for kind, cells in blocks]


def auto_scale(parts: list[Part], fraction: float = 0.1) -> float:
    """Scale factor that makes the largest displacement ``fraction`` of the largest extent."""
    size = max(float(np.ptp(np.vstack([p.nodes for p in parts]), axis=0).max()), 1e-9)
    umax = max(float(np.linalg.norm(p.displacement, axis=1).max()) for p in parts)
    return fraction * size / umax if umax > 0 else 1.0


def snapshot_png(path, parts: Part | list[Part], title: str = "", scale: float | None = None, *,
                 fraction: float = 0.1, note: str = "", window_size=(1024, 768), view: str = "iso",
                 azimuth: float = 0.0, elevation: float = 0.0, umax: float | None = None, zoom: float = 1.0) -> Path:
    """Write a PNG of the deformed parts; returns the path. ``scale=None``: the largest
    displacement drawn as ``fraction`` of the model size. ``view``: iso, xy, xz or yz, then
    turned by ``azimuth`` and ``elevation`` (degrees) and zoomed by ``zoom``. ``umax``: the
    top of the colour scale (m; default the picture's largest |u|), so that a series of
    pictures shares one scale. Line cells are drawn as thick lines."""
    path = Path(path)
    if path.suffix.lower() != ".png":
        raise InputError(f"snapshot: {str(path)!r} must end in .png")
    if view not in ("iso", "xy", "xz", "yz"):
        raise InputError(f"snapshot: view {view!r} must be iso, xy, xz or yz")
    parts = [parts] if isinstance(parts, Part) else list(parts)
    if scale is None:
        scale = auto_scale(parts, fraction)
    if not _RENDER_IN_PROCESS:
        return _render_in_subprocess(path, parts, dict(title=title, scale=scale, note=note, window_size=window_size,
                                                       view=view, azimuth=azimuth, elevation=elevation, umax=umax,
                                                       zoom=zoom))
    here = max(float(np.linalg.norm(p.displacement, axis=1).max()) for p in parts)
    umax = here if umax is None else float(umax)
    pl = pyvista.Plotter(off_screen=True, window_size=list(window_size))
    pl.set_background("white")
    bar = {"title": "|u| (m)", "color": "black"}
    for part in parts:
        base = part.grid()
        deformed = base.copy()
        deformed.points = part.nodes + scale * part.displacement
        deformed.point_data["|u| (m)"] = np.linalg.norm(part.displacement, axis=1)
        line = part.cell_type == "line"
        pl.add_mesh(base if line else base.extract_feature_edges(), color="lightgrey", line_width=2 if line else 1)
        pl.add_mesh(deformed, scalars="|u| (m)", cmap="viridis", clim=[0, umax or 1], scalar_bar_args=bar,
                    **({"line_width": 6} if line else {}))
    pl.add_text(title, position="upper_left", font_size=11, color="black")
    pl.add_text(f"displacement scale x {scale:.3g}, max |u| = {here:.3g} m" + (f" ({note})" if note else ""),
                position="lower_left", font_size=9, color="black")
    if view == "iso":
        pl.view_isometric()
    else:
        getattr(pl, f"view_{view}")()
    pl.camera.azimuth += azimuth
    pl.camera.elevation += elevation
    if zoom != 1.0:
        pl.camera.zoom(zoom)
    try:
        with atomic_path(path, suffix=".png") as tmp:
            pl.screenshot(str(tmp))
    finally:
        pl.close()
    return path


def _deformable_scene(parts: list[Part], scale: float, window_size, view: str, azimuth: float, elevation: float,
                      clim: float):
    """(plotter, deformed meshes, their actors): a white off-screen scene of ``parts``, each
    as its grey outline (feature edges, or its lines) and its mesh deformed by ``scale`` x
    its displacement, coloured by |u| on [0, clim] with one scalar bar, the camera set to
    ``view`` turned by ``azimuth`` and ``elevation`` (degrees); the caller updates the
    deformed meshes' points and ``|u| (m)`` for each picture or frame."""
    pl = pyvista.Plotter(off_screen=True, window_size=list(window_size))
    pl.set_background("white")
    bar = {"title": "|u| (m)", "color": "black"}
    meshes, actors = [], []
    for part in parts:
        base = part.grid()
        line = part.cell_type == "line"
        pl.add_mesh(base if line else base.extract_feature_edges(), color="lightgrey", line_width=2 if line else 1)
        deformed = base.copy()
        deformed.points = part.nodes + scale * part.displacement
        deformed.point_data["|u| (m)"] = np.linalg.norm(part.displacement, axis=1)
        actors.append(pl.add_mesh(deformed, scalars="|u| (m)", cmap="viridis", clim=[0, clim], scalar_bar_args=bar,
                                  **({"line_width": 6} if line else {})))
        meshes.append(deformed)
    getattr(pl, "view_isometric" if view == "iso" else f"view_{view}")()
    pl.camera.azimuth += azimuth
    pl.camera.elevation += elevation
    return pl, meshes, actors


def snapshot_pngs(shots: list[tuple], *, fraction: float = 0.1, note: str = "", window_size=(1024, 768),
                  view: str = "iso", azimuth: float = 0.0, elevation: float = 0.0) -> list[Path]:
    """Several pictures of the same meshes deformed differently, ``shots`` = [(path, parts,
    title)], each as :func:`snapshot_png` draws it (its own displacement scale, ``fraction``
    of the model size, and colour range), from one scene: the meshes, their outlines, the
    scalar bar and the camera (set for the first picture) are made once, the deformed
    points, colours and texts updated per picture (the three snapshots of a case: one
    outline extraction and scene instead of three). Parts that differ in their meshes
    between shots are drawn one by one."""
    shots = [(Path(p), [parts] if isinstance(parts, Part) else list(parts), title) for p, parts, title in shots]
    for path, _, _ in shots:
        if path.suffix.lower() != ".png":
            raise InputError(f"snapshot: {str(path)!r} must end in .png")
    if view not in ("iso", "xy", "xz", "yz"):
        raise InputError(f"snapshot: view {view!r} must be iso, xy, xz or yz")
    def same_mesh(p: Part, q: Part) -> bool:
        return p.cell_type == q.cell_type and np.array_equal(p.nodes, q.nodes) and np.array_equal(p.cells, q.cells)

    same = all(len(parts) == len(shots[0][1]) and all(same_mesh(p, q) for p, q in zip(parts, shots[0][1]))
               for _, parts, _ in shots)
    one = dict(fraction=fraction, note=note, window_size=window_size, view=view, azimuth=azimuth, elevation=elevation)
    if len(shots) < 2 or not same or not _RENDER_IN_PROCESS:
        return [snapshot_png(path, parts, title, **one) for path, parts, title in shots]
    pl, meshes, actors = _deformable_scene(shots[0][1], auto_scale(shots[0][1], fraction), window_size, view, azimuth,
                                           elevation, 1.0)
    label = pl.add_text("", position="upper_left", font_size=11, color="black")
    footer = pl.add_text("", position="lower_left", font_size=9, color="black")
    paths = []
    try:
        for path, parts, title in shots:
            scale = auto_scale(parts, fraction)
            here = max(float(np.linalg.norm(p.displacement, axis=1).max()) for p in parts)
            for mesh, actor, part in zip(meshes, actors, parts):
                mesh.points = part.nodes + scale * part.displacement
                mesh.point_data["|u| (m)"] = np.linalg.norm(part.displacement, axis=1)
                actor.mapper.scalar_range = (0.0, here or 1.0)
            label.SetText(2, title)
            footer.SetText(0, f"displacement scale x {scale:.3g}, max |u| = {here:.3g} m" + (f" ({note})" if note else ""))
            pl.render()                     # the updated scene (screenshot alone may return the last frame)
            with atomic_path(path, suffix=".png") as tmp:
                pl.screenshot(str(tmp))
            paths.append(path)
    finally:
        pl.close()
    return paths


def animation_gif(path, frames: list[list[Part]], titles: list[str], scale: float | None = None, *,
                  fraction: float = 0.1, note: str = "", fps: int = 8, window_size=(640, 800), view: str = "yz",
                  azimuth: float = 0.0, elevation: float = 0.0) -> Path:
    """An animated GIF of deformed parts, one picture per frame (same parts, meshes and
    camera in every frame; the colour scale and ``scale`` are those of the largest frame).
    Needs imageio (pyvista's GIF writer)."""
    path = Path(path)
    if path.suffix.lower() != ".gif":
        raise InputError(f"animation: {str(path)!r} must end in .gif")
    if not frames or len(titles) != len(frames):
        raise InputError(f"animation: {len(frames)} frames and {len(titles)} titles")
    if scale is None:       # the largest displacement of any frame drawn as ``fraction`` of the model size
        size = max(float(np.ptp(np.vstack([p.nodes for p in frames[0]]), axis=0).max()), 1e-9)
        big = max(float(np.linalg.norm(p.displacement, axis=1).max()) for f in frames for p in f)
        scale = fraction * size / big if big > 0 else 1.0
    if not _RENDER_IN_PROCESS:
        return _render_in_subprocess(path, [p for f in frames for p in f],
                                     dict(kind="gif", n_frames=len(frames), titles=titles, scale=scale, note=note,
                                          fps=fps, window_size=window_size, view=view, azimuth=azimuth,
                                          elevation=elevation))
    umax = max(float(np.linalg.norm(p.displacement, axis=1).max()) for f in frames for p in f) or 1.0
    pl, meshes, _ = _deformable_scene(frames[0], 0.0, window_size, view, azimuth, elevation, umax)
    pl.add_text(f"displacement scale x {scale:.3g}" + (f" ({note})" if note else ""), position="lower_left",
                font_size=9, color="black")
    label = pl.add_text("", position="upper_left", font_size=11, color="black")
    try:
        with atomic_path(path, suffix=".gif") as tmp:
            pl.open_gif(str(tmp), fps=fps)
            for parts, title in zip(frames, titles):
                for mesh, part in zip(meshes, parts):
                    mesh.points = part.nodes + scale * part.displacement
                    mesh.point_data["|u| (m)"] = np.linalg.norm(part.displacement, axis=1)
                label.SetText(2, title)
                pl.write_frame()
            pl.close()                      # finishes the GIF file before it is renamed into place
    finally:
        pl.close()
    return path


def snapshot_mode(path, model, modes, j: int, scale: float | None = None) -> Path | None:
    """Picture of mode ``j`` of an FE model (rank 0 draws; other ranks return None)."""
    u = model.nodal_displacement(modes.shapes[:, j])
    if model.comm.rank != 0:
        return None
    title = f"{model.name}: mode {j + 1}, {modes.freq_hz[j]:.4g} Hz"
    return snapshot_png(path, mesh_parts(model, u), title, scale)


def _render_in_subprocess(path: Path, parts: list[Part], options: dict) -> Path:
    """Render in a fresh interpreter (no dolfinx there); arrays passed through an .npz."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, npz = tempfile.mkstemp(dir=path.parent, suffix=".snapshot.npz")
    os.close(fd)
    try:
        arrays = {"path": np.array(str(path)), "options": np.array(json.dumps(options))}
        for k, p in enumerate(parts):
            arrays.update({f"nodes_{k}": p.nodes, f"cells_{k}": p.cells, f"cell_type_{k}": np.array(p.cell_type),
                           f"u_{k}": p.displacement})
        np.savez(npz, **arrays)
        res = subprocess.run([sys.executable, "-m", "liftoff.fem.snapshot", npz], capture_output=True, text=True)
        if res.returncode != 0 or not path.is_file():
            raise RuntimeError(f"snapshot subprocess failed ({res.returncode}): {res.stderr[-1000:]}")
    finally:
        os.unlink(npz)
    return path


def _main(npz: str) -> None:
    """Subprocess renderer: ``python -m liftoff.fem.snapshot args.npz``."""
    with np.load(npz, allow_pickle=False) as z:
        n = sum(1 for k in z.files if k.startswith("nodes_"))
        parts = [Part(z[f"nodes_{k}"], z[f"cells_{k}"], z[f"cell_type_{k}"].item(), z[f"u_{k}"]) for k in range(n)]
        options = json.loads(z["options"].item())
        options["window_size"] = tuple(options["window_size"])
        if options.pop("kind", "png") == "gif":
            k = options.pop("n_frames")
            per = len(parts) // k
            animation_gif(z["path"].item(), [parts[i * per:(i + 1) * per] for i in range(k)], **options)
        else:
            snapshot_png(z["path"].item(), parts, **options)


if __name__ == "__main__":
    _main(sys.argv[1])
