"""Full-field output of one case for ParaView: a .pvd time series of .vtu deformed shapes of
the stack and the pad, and an animated GIF of the lift-off. SI units (m).

Each frame is one .vtu holding every FE component (one cell block each, cell data ``part``
numbering them in the order of the .pvd's ``parts`` note), with the nodal fields

* ``displacement`` (m): the total motion, the vehicle's rigid-body motion included (the
  stack rises off the pad after release);
* ``elastic`` (m): the vehicle's elastic deformation (rigid-body modes removed), the pad's
  displacement: what the snapshots draw.

The fields are recovered through each component's Craig-Bampton model (reduction's
field_displacement: the component's rows of the system modes times the step's modal
coordinates, then its modes; no full recovery matrix is formed) from the modal displacements the
transient kept (``keep_modal = "q"``). Open ``fields_<case>.pvd`` in ParaView and warp by
either vector.
"""
from __future__ import annotations

from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from liftoff.core.records import write_text


class FieldFrames:
    """Recovered nodal displacements of every FE component of a stack at any step."""

    def __init__(self, stack, result):
        if "q_a" not in result.modal:
            raise ValueError("full-field output needs the modal displacements: solve with keep_modal = 'q'")
        self.result = result
        self.n_rigid = int(np.sum(stack.vehicle.omega == 0))
        self.parts = []          # (name, nodes, cells, cell_type, (assembly, system modes, component), on the pad?)
        for name, comp in fe_parts(stack):
            asm, modes = (stack.pad_asm, stack.pad_modes) if name == "pad" else (stack.vehicle_asm, stack.vehicle_modes)
            self.parts.append((name, comp.nodes, comp.cells, comp.cell_type, (asm, modes, comp), name == "pad"))

    def at(self, i: int, elastic: bool = True) -> list[np.ndarray]:
        """Per part the (n_nodes, 3) displacement at step i (``elastic``: vehicle rigid-body
        motion removed)."""
        from liftoff.reduction import field_displacement

        qa = self.result.modal["q_a"][i].copy()
        if elastic:
            qa[: self.n_rigid] = 0.0
        qb = self.result.modal["q_b"][i] if "q_b" in self.result.modal else np.zeros(0)
        return [field_displacement(asm, modes, name, comp, qb if pad else qa).reshape(-1, 3)
                for name, _, _, _, (asm, modes, comp), pad in self.parts]


def fe_parts(stack) -> list[tuple[str, object]]:
    """(name, component) of every FE component of ``stack`` (a field map and nodes), in the
    stack's order."""
    return [(name, comp) for name, comp in stack.components.items()
            if comp.field_map is not None and comp.nodes is not None]


def merged_mesh(comps) -> tuple[np.ndarray, list, list]:
    """One mesh of several components (each with ``nodes``, ``cells``, ``cell_type``): the
    nodes stacked, a cell block per component (indices shifted) and the cell data ``part``
    numbering the blocks in order."""
    offsets = np.cumsum([0] + [c.nodes.shape[0] for c in comps])
    nodes = np.vstack([c.nodes for c in comps])
    from liftoff.fem.output import cell_blocks

    blocks, part_ids = [], []
    for k, (c, off) in enumerate(zip(comps, offsets)):
        for kind, cells in cell_blocks(c):             # (its cells, then its beams' lines)
            blocks.append((kind, np.asarray(cells) + off))
            part_ids.append(np.full(len(cells), k, dtype=np.int32))
    return nodes, blocks, part_ids


#: the vehicle's elastic system modes written as FE fields (modes_vehicle.vtu)
MODE_SHAPE_FIELDS = 12


def mode_shapes_inputs(stack, cp, n_modes: int = MODE_SHAPE_FIELDS) -> dict:
    """What :func:`write_mode_shapes_vtu`'s file depends on besides the stack's key (its
    cache key, workflows/outputs.py): the number of modes and a SHA-256 of the vehicle's
    system modes (frequencies and shapes in the components' CB coordinates: a system
    stage rebuilt under the same key may flip a mode's sign or turn a degenerate pair)."""
    from .cache import content_sha256

    return {"n_modes": n_modes, "modes": content_sha256((stack.vehicle_modes.omega, stack.vehicle_modes.phi))}


def write_mode_shapes_vtu(stack, cp, out: Path, n_modes: int = MODE_SHAPE_FIELDS) -> list[Path]:
    """``modes_vehicle.vtu``: the vehicle's first ``n_modes`` elastic system modes as nodal
    vector fields ``mode_<k>_<f>Hz`` (m per unit modal coordinate, unit modal mass) over
    every FE component of the vehicle (cell data ``part``: 0, 1, ... in the order of the
    stack's FE components, :func:`fe_parts`, the default's core, srb_left, srb_right, orbiter;
    not the order of the summary's stage list), recovered through each
    component's CB model (reduction.field_displacement); nothing without FE components."""
    from liftoff.fem.output import write_vtu
    from liftoff.reduction import field_displacement

    parts = [(name, comp) for name, comp in fe_parts(stack) if name != "pad"]
    vm = stack.vehicle_modes
    modes = list(range(vm.n_rigid, min(vm.n_rigid + n_modes, vm.n_modes)))
    if not parts or not modes:
        return []
    nodes, blocks, part_ids = merged_mesh([c for _, c in parts])
    Q = np.zeros((vm.n_modes, len(modes)))          # every mode at once: each component's modes are read once
    Q[modes, np.arange(len(modes))] = 1.0
    per_part = [field_displacement(stack.vehicle_asm, vm, name, c, Q) for name, c in parts]   # (3 n_nodes, k)
    fields = {f"mode_{j + 1:03d}_{vm.freq_hz[j]:.4g}Hz": np.vstack([u[:, k].reshape(-1, 3) for u in per_part])
              for k, j in enumerate(modes)}
    return [write_vtu(out / "modes_vehicle.vtu", nodes, blocks, None, fields, cell_data={"part": part_ids})]


def frame_steps(n_t: int, n_frames: int) -> np.ndarray:
    """``n_frames`` step indices evenly spread over 0..n_t - 1 (first and last included)."""
    return np.unique(np.round(np.linspace(0, n_t - 1, min(n_frames, n_t))).astype(int))


def write_pvd(stack, result, out: Path, case: str, n_frames: int = 48) -> list[Path]:
    """fields_<case>.pvd and its frames fields_<case>_<k>.vtu; returns the paths."""
    from liftoff.fem.output import write_vtu

    ff = FieldFrames(stack, result)
    if not ff.parts:
        return []
    nodes, blocks, part_ids = merged_mesh([p[4][2] for p in ff.parts])
    paths, entries = [], []
    for k, i in enumerate(frame_steps(result.time.size, n_frames)):
        total, elastic = np.vstack(ff.at(i, elastic=False)), np.vstack(ff.at(i))
        name = f"fields_{case}_{k:04d}.vtu"
        paths.append(write_vtu(out / name, nodes, blocks, None, {"displacement": total, "elastic": elastic},
                               cell_data={"part": part_ids}))
        entries.append(f'    <DataSet timestep="{result.time[i]:.9g}" group="" part="0" file={quoteattr(name)}/>')
    parts = ", ".join(f"{k} {p[0]}" for k, p in enumerate(ff.parts))
    text = ('<?xml version="1.0"?>\n'
            f'<!-- liftoff: deformed stack and pad, case {case}; time in s, displacement in m; parts: {parts} -->\n'
            '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">\n  <Collection>\n'
            + "\n".join(entries) + "\n  </Collection>\n</VTKFile>\n")
    paths.insert(0, write_text(out / f"fields_{case}.pvd", text))
    return paths


def write_gif(stack, result, out: Path, case: str, n_frames: int = 48) -> Path | None:
    """animation_<case>.gif: the elastic deformation of stack and pad over the run (one
    frame per step of :func:`frame_steps`), one displacement scale for all frames."""
    from liftoff.fem.snapshot import animation_gif, mesh_parts

    ff = FieldFrames(stack, result)
    if not ff.parts:
        return None
    steps = frame_steps(result.time.size, n_frames)
    frames = [[q for p, u in zip(ff.parts, ff.at(i)) for q in mesh_parts(p[4][2], u)] for i in steps]
    titles = [f"{case}: t = {result.time[i]:.2f} s" for i in steps]
    return animation_gif(out / f"animation_{case}.gif", frames, titles, fraction=0.03, note="elastic part",
                         azimuth=35, elevation=12)
