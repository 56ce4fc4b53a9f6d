"""Result of a two-body transient and its HDF5 file (layout documented in docs/transient.md)."""
from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from liftoff.core.errors import InputError
from liftoff.core.records import atomic_path

FORMAT = "liftoff-transient-result"
VERSION = 1
STATE_NAMES = ("bolted", "closed", "open")


def _dof_units(labels, kind: str) -> str:
    """Units string for a list of DOF labels ('m' or 'rad' per label, in order)."""
    base = {"disp": ("m", "rad"), "vel": ("m/s", "rad/s"), "acc": ("m/s^2", "rad/s^2")}[kind]
    units = [base[1] if lab.split(":")[-1].startswith("R") else base[0] for lab in labels]
    if units and all(u == units[0] for u in units):
        return units[0]
    return "per column: " + ", ".join(units) if units else base[0]


@dataclass
class TransientResult:
    """Time histories (time-major) of one run. Forces are on body A (N or N m)."""

    time: np.ndarray
    contact_names: tuple
    contact_labels: tuple
    contact_force: np.ndarray
    contact_state: np.ndarray
    separation_time: np.ndarray
    recontact_count: np.ndarray
    release_time: np.ndarray
    output_labels: dict
    displacement: dict
    velocity: dict
    acceleration: dict
    recovered: dict
    recovered_units: dict
    rigid_body_motion_a: np.ndarray | None
    rigid_body_motion_b: np.ndarray | None
    iterations: np.ndarray
    modal: dict = field(default_factory=dict)
    metadata: dict = field(default_factory=dict)

    @property
    def h(self) -> float:
        return float(self.metadata["h"])

    @property
    def method(self) -> str:
        return str(self.metadata["method"])

    def contact_summary(self) -> list[dict]:
        """Per contact point: release time, first separation (None if never), peak axial forces."""
        out = []
        for c, name in enumerate(self.contact_names):
            cols = [j for j, lab in enumerate(self.contact_labels) if lab.split("/")[0] == name]
            ax = self.metadata["axial_columns"][c]
            sign = self.metadata["normal_signs"][c]
            normal = sign * self.contact_force[:, ax]  # > 0 compression
            sep = self.separation_time[c]
            out.append({"name": name, "release_time": float(self.release_time[c]),
                        "separation_time": None if np.isnan(sep) else float(sep),
                        "recontacts": int(self.recontact_count[c]),
                        "peak_compression": float(max(normal.max(), 0.0)),
                        "peak_tension": float(max(-normal.min(), 0.0)),
                        "columns": cols})
        return out

    # ------------------------------------------------------------------ file
    def save(self, path: str | os.PathLike) -> Path:
        """Write one HDF5 file atomically (temporary file + os.replace)."""
        import h5py

        path = Path(path)
        sdt = h5py.string_dtype()

        def put(group, name, data, units, **attrs):
            data = np.asarray(data)
            if data.dtype.kind == "U":
                d = group.create_dataset(name, data=data.astype(object), dtype=sdt)
            else:
                d = group.create_dataset(name, data=data)
            d.attrs["units"] = units
            for k, v in attrs.items():
                d.attrs[k] = v

        with atomic_path(path) as tmp, h5py.File(tmp, "w") as f:
            f.attrs["format"] = FORMAT
            f.attrs["version"] = VERSION
            f.attrs["units"] = "SI (m, kg, s, N, rad)"
            f.attrs["metadata"] = json.dumps(self.metadata)
            put(f, "time", self.time, "s")
            put(f, "iterations", self.iterations, "1")
            c = f.create_group("contact")
            put(c, "names", np.array(self.contact_names, dtype="U"), "1")
            put(c, "labels", np.array(self.contact_labels, dtype="U"), "1")
            put(c, "force", self.contact_force, "N (N m for rotations)", on="body a")
            put(c, "state", self.contact_state, "1", meaning="0 bolted, 1 closed, 2 open")
            put(c, "separation_time", self.separation_time, "s", meaning="first opening, NaN if never")
            put(c, "recontact_count", self.recontact_count, "1")
            put(c, "release_time", self.release_time, "s")
            for key in ("a", "b"):
                g = f.create_group(f"body_{key}")
                labels = list(self.output_labels[key])
                put(g, "output_labels", np.array(labels, dtype="U"), "1")
                put(g, "displacement", self.displacement[key], _dof_units(labels, "disp"))
                put(g, "velocity", self.velocity[key], _dof_units(labels, "vel"))
                put(g, "acceleration", self.acceleration[key], _dof_units(labels, "acc"))
                rb = self.rigid_body_motion_a if key == "a" else self.rigid_body_motion_b
                if rb is not None:
                    put(g, "rigid_body_motion", rb, "m (Tx Ty Tz), rad (Rx Ry Rz)",
                        columns="Tx Ty Tz Rx Ry Rz about ref_point")
                for mk, unit in (("q", "sqrt(kg) m"), ("v", "sqrt(kg) m/s"), ("acc", "sqrt(kg) m/s^2")):
                    if f"{mk}_{key}" in self.modal:
                        put(g, f"modal_{mk}", self.modal[f"{mk}_{key}"], unit)
            r = f.create_group("recovered")
            for name, arr in self.recovered.items():
                put(r, name, arr, self.recovered_units.get(name, "SI"))
        return path


def load_result(path: str | os.PathLike) -> TransientResult:
    """Read a file written by :meth:`TransientResult.save`."""
    import h5py

    path = Path(path)
    if not path.is_file():
        raise InputError(f"result file not found: {str(path)!r}")

    def strings(ds):
        return tuple(s.decode() if isinstance(s, bytes) else str(s) for s in ds[()])

    try:
        with h5py.File(path, "r") as f:
            if f.attrs.get("format") != FORMAT:
                raise InputError(f"result file {str(path)!r}: format is {f.attrs.get('format')!r}, expected {FORMAT!r}")
            meta = json.loads(f.attrs["metadata"])
            c = f["contact"]
            labels, disp, vel, acc, modal, rb = {}, {}, {}, {}, {}, {}
            for key in ("a", "b"):
                g = f[f"body_{key}"]
                labels[key] = strings(g["output_labels"])
                disp[key], vel[key], acc[key] = g["displacement"][()], g["velocity"][()], g["acceleration"][()]
                rb[key] = g["rigid_body_motion"][()] if "rigid_body_motion" in g else None
                for mk in ("q", "v", "acc"):
                    if f"modal_{mk}" in g:
                        modal[f"{mk}_{key}"] = g[f"modal_{mk}"][()]
            rec = {k: f["recovered"][k][()] for k in f["recovered"]}
            rec_units = {k: str(f["recovered"][k].attrs["units"]) for k in f["recovered"]}
            return TransientResult(
                time=f["time"][()], contact_names=strings(c["names"]), contact_labels=strings(c["labels"]),
                contact_force=c["force"][()], contact_state=c["state"][()],
                separation_time=c["separation_time"][()], recontact_count=c["recontact_count"][()],
                release_time=c["release_time"][()], output_labels=labels, displacement=disp, velocity=vel,
                acceleration=acc, recovered=rec, recovered_units=rec_units, rigid_body_motion_a=rb["a"],
                rigid_body_motion_b=rb["b"], iterations=f["iterations"][()], modal=modal, metadata=meta)
    except InputError:
        raise
    except Exception as exc:
        raise InputError(f"result file {str(path)!r} cannot be read: {exc}") from None
