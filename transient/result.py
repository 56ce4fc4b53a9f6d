"""Result of a two-body transient and its HDF5 file (layout documented in docs/transient.md).

The result describes itself: each column of the contact force is a :class:`ContactDirection`
(contact, DOF labels, component, axial or not, normal sign) and each recovered history a
:class:`RecoveryItem` (category, per-column labels and units), in memory and in the file,
so that readers select and name histories without parsing names. In the file every
time-major dataset has HDF5 dimension scales on its axes (``/time`` and the label
datasets), which netCDF-style readers take as its dimensions.
"""
from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from liftoff.core.labels import COMPONENTS, split_label
from liftoff.core.records import Dataset, read_record, write_record

FORMAT = "liftoff-transient-result"
VERSION = 3  # 2: contact directions and recovery items as data, dimension scales; 3: body_?/mode from 1
#: the versions load_result reads (a version 2 file reads the same; only its mode numbers start at 0)
READS = (2, 3)
STATE_NAMES = ("bolted", "closed", "open")
COLUMNS = "_columns"  # recovered/<name>_columns: the column labels of recovered/<name>
_KINDS = {"disp": ("m", "rad"), "vel": ("m/s", "rad/s"), "acc": ("m/s^2", "rad/s^2"), "force": ("N", "N m")}


def dof_units(labels, kind: str) -> tuple[str, ...]:
    """Per DOF label the unit of a ``kind`` (disp, vel, acc, force): translation or rotation."""
    base = _KINDS[kind]
    return tuple(base[1] if split_label(lab)[1] >= 3 else base[0] for lab in labels)


def units_text(units, default: str = "1") -> str:
    """One units string for a dataset: the common unit, or ``per column: u1, u2, ...``."""
    units = list(units)
    if not units:
        return default
    if all(u == units[0] for u in units):
        return units[0]
    return "per column: " + ", ".join(units)


@dataclass(frozen=True)
class ContactDirection:
    """One coupled direction of a contact point: one column of ``contact_force``."""

    contact: str            # name of the contact point
    index: int              # its index in contact_names
    label_a: str            # DOF label on body a
    label_b: str | None     # DOF label on body b, None where b is ground
    component: str          # component of label_a: Tx Ty Tz Rx Ry Rz
    axial: bool             # the contact's normal direction (compression-only once released)
    normal_sign: float      # +1: A on the + side of B; normal_sign * force > 0 is compression
    vector: tuple = ()      # oriented direction (ContactPoint.normal): its coefficients over the
                            # contact's labels; component is then n, t1, t2 ... and label_a point:n ...

    @property
    def label(self) -> str:
        """``contact/label_a``, the column label in the file."""
        return f"{self.contact}/{self.label_a}"

    @property
    def unit(self) -> str:
        """Unit of the contact force in this direction: N, or N m for a rotation."""
        return "N m" if self.component in COMPONENTS[3:] else "N"


@dataclass(frozen=True)
class RecoveryItem:
    """What a recovered history is: its :class:`~liftoff.transient.model.Recovery` less the matrices."""

    name: str
    body: str                   # 'a' or 'b'
    category: str               # interface_force, cg_motion, modal, displacement, user, ...
    labels: tuple[str, ...]     # per column
    units: tuple[str, ...]      # per column
    description: str = ""
    from_acceleration: bool = False     # recovered from the modal accelerations alone (an ATM: y = A qddot)


@dataclass
class TransientResult:
    """Time histories (time-major) of one run. Forces are on body A (N or N m)."""

    time: np.ndarray
    contact_names: tuple
    contact_directions: tuple       # ContactDirection per column of contact_force
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
    recovery_items: dict            # name -> RecoveryItem, same keys and order as recovered
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

    @property
    def contact_labels(self) -> tuple[str, ...]:
        """``contact/label_a`` per column of contact_force."""
        return tuple(d.label for d in self.contact_directions)

    @property
    def recovered_units(self) -> dict[str, str]:
        """One units string per recovered history (see :func:`units_text`)."""
        return {k: units_text(it.units, "SI") for k, it in self.recovery_items.items()}

    def directions_of(self, contact: int) -> list[int]:
        """Columns of contact_force that belong to contact point number ``contact``."""
        return [j for j, d in enumerate(self.contact_directions) if d.index == contact]

    def axial_column(self, contact: int) -> int:
        """The column of the normal (axial) direction of contact point number ``contact``."""
        return next(j for j in self.directions_of(contact) if self.contact_directions[j].axial)

    def output_units(self, key: str, kind: str) -> tuple[str, ...]:
        """Per labelled output of body ``key`` the unit of its ``kind`` (disp, vel, acc)."""
        return dof_units(self.output_labels[key], kind)

    def items(self, category: str | None = None) -> list[RecoveryItem]:
        """The recovery items, optionally only those of one category."""
        return [it for it in self.recovery_items.values() if category is None or it.category == category]

    def contact_summary(self) -> list[dict]:
        """Per contact point: release time, first separation (None if never), peak axial forces."""
        out = []
        for c, name in enumerate(self.contact_names):
            ax = self.axial_column(c)
            normal = self.contact_directions[ax].normal_sign * self.contact_force[:, ax]  # > 0 compression
            sep = self.separation_time[c]
            out.append({"name": name, "release_time": float(self.release_time[c]),
                        "separation_time": None if np.isnan(sep) else float(sep),
                        "recontacts": int(self.recontact_count[c]),
                        "peak_compression": float(max(normal.max(), 0.0)),
                        "peak_tension": float(max(-normal.min(), 0.0)),
                        "columns": self.directions_of(c), "axial_column": ax})
        return out

    # ------------------------------------------------------------------ file
    def save(self, path: str | os.PathLike) -> Path:
        """Write one HDF5 file (.h5 or .hdf5) atomically (temporary file + os.replace)."""
        data = {"time": Dataset(self.time, "s"),
                "iterations": Dataset(self.iterations, "1", dims=("/time",)),
                "contact": self._contact_data()}
        for key in ("a", "b"):
            data[f"body_{key}"] = self._body_data(key)
        rec = {}
        for name, arr in self.recovered.items():
            it = self.recovery_items[name]
            rec[name + COLUMNS] = Dataset(np.array(it.labels, dtype=object), "1")
            rec[name] = Dataset(arr, units_text(it.units, "SI"), dims=("/time", name + COLUMNS),
                                column_units=list(it.units), category=it.category, body=it.body,
                                description=it.description, from_acceleration=int(it.from_acceleration))
        data["recovered"] = rec
        return write_record(path, FORMAT, VERSION, data, units="SI (m, kg, s, N, rad)",
                            attrs={"metadata": json.dumps(_json_safe(self.metadata), allow_nan=False)},
                            suffixes=(".h5", ".hdf5"))

    def _contact_data(self) -> dict:
        dirs = self.contact_directions
        by_contact = ("names",)
        return {
            "names": Dataset(np.array(self.contact_names, dtype=object), "1"),
            "labels": Dataset(np.array(self.contact_labels, dtype=object), "1", meaning="contact/label_a"),
            "force": Dataset(self.contact_force, units_text([d.unit for d in dirs]), dims=("/time", "labels"),
                             on="body a", column_units=[d.unit for d in dirs]),
            "state": Dataset(self.contact_state, "1", dims=("/time", "names"), meaning="0 bolted, 1 closed, 2 open"),
            "separation_time": Dataset(self.separation_time, "s", dims=by_contact, meaning="first opening, NaN if never"),
            "recontact_count": Dataset(self.recontact_count, "1", dims=by_contact),
            "release_time": Dataset(self.release_time, "s", dims=by_contact),
            "direction": {
                "contact_index": Dataset([d.index for d in dirs], "1", dims=("/contact/labels",), meaning="row of names"),
                "label_a": Dataset(np.array([d.label_a for d in dirs], dtype=object), "1", dims=("/contact/labels",)),
                "label_b": Dataset(np.array([d.label_b or "" for d in dirs], dtype=object), "1",
                                   dims=("/contact/labels",), meaning="empty where body b is ground"),
                "component": Dataset(np.array([d.component for d in dirs], dtype=object), "1", dims=("/contact/labels",)),
                "axial": Dataset(np.array([d.axial for d in dirs], dtype=np.int8), "1", dims=("/contact/labels",),
                                 meaning="1 normal (axial) direction, 0 lateral"),
                "normal_sign": Dataset([d.normal_sign for d in dirs], "1", dims=("/contact/labels",),
                                       meaning="normal_sign * force > 0: compression"),
                **self._vectors()},
        }

    def _vectors(self) -> dict:
        """``direction/vector`` (n_dirs, max labels), only when a contact has a normal: the
        coefficients of each oriented direction over its contact's labels (NaN padding, and
        NaN rows for directions that are plain labels)."""
        dirs = self.contact_directions
        if not any(d.vector for d in dirs):
            return {}
        width = max(len(d.vector) for d in dirs)
        V = np.full((len(dirs), width), np.nan)
        for j, d in enumerate(dirs):
            V[j, :len(d.vector)] = d.vector
        return {"vector": Dataset(V, "1", meaning="oriented direction over the contact's labels_a; NaN: none")}

    def _body_data(self, key: str) -> dict:
        labels = list(self.output_labels[key])
        g = {"output_labels": Dataset(np.array(labels, dtype=object), "1")}
        for name, kind, hist in (("displacement", "disp", self.displacement), ("velocity", "vel", self.velocity),
                                 ("acceleration", "acc", self.acceleration)):
            units = self.output_units(key, kind)
            g[name] = Dataset(hist[key], units_text(units, _KINDS[kind][0]), dims=("/time", "output_labels"),
                              column_units=list(units))
        rb = self.rigid_body_motion_a if key == "a" else self.rigid_body_motion_b
        if rb is not None:
            g["rigid_body_components"] = Dataset(np.array(COMPONENTS, dtype=object), "1")
            g["rigid_body_motion"] = Dataset(rb, "m (Tx Ty Tz), rad (Rx Ry Rz)",
                                             dims=("/time", "rigid_body_components"),
                                             columns="Tx Ty Tz Rx Ry Rz about ref_point")
        modal = [(mk, unit) for mk, unit in (("q", "sqrt(kg) m"), ("v", "sqrt(kg) m/s"), ("acc", "sqrt(kg) m/s^2"))
                 if f"{mk}_{key}" in self.modal]
        if modal:
            # numbered from 1, as modes_vehicle.h5/.csv and the mode-shape VTU number them (a review: 0 here
            # put xarray's .sel(mode=6) on the first elastic mode, the modes file's mode 6 a rigid one)
            g["mode"] = Dataset(np.arange(1, self.modal[f"{modal[0][0]}_{key}"].shape[1] + 1), "1")
            for mk, unit in modal:
                g[f"modal_{mk}"] = Dataset(self.modal[f"{mk}_{key}"], unit, dims=("/time", "mode"))
        return g


def load_result(path: str | os.PathLike) -> TransientResult:
    """Read a file written by :meth:`TransientResult.save` (format version 3, or 2: its modes numbered from 0)."""
    rec = read_record(path, FORMAT, READS, what="result file")
    d, attrs = rec.data, rec.dataset_attrs
    c = d["contact"]
    cd = c["direction"]
    strings = lambda a: tuple(str(s) for s in a)  # noqa: E731
    vec = cd.get("vector", np.full((len(cd["axial"]), 0), np.nan))
    dirs = tuple(ContactDirection(str(c["names"][i]), int(i), str(la), str(lb) or None, str(comp), bool(ax), float(s),
                                  tuple(float(x) for x in v if np.isfinite(x)))
                 for i, la, lb, comp, ax, s, v in zip(cd["contact_index"], cd["label_a"], cd["label_b"],
                                                      cd["component"], cd["axial"], cd["normal_sign"], vec))
    labels, disp, vel, acc, modal, rb = {}, {}, {}, {}, {}, {}
    for key in ("a", "b"):
        g = d[f"body_{key}"]
        labels[key] = strings(g["output_labels"])
        disp[key], vel[key], acc[key] = g["displacement"], g["velocity"], g["acceleration"]
        rb[key] = g.get("rigid_body_motion")
        for mk in ("q", "v", "acc"):
            if f"modal_{mk}" in g:
                modal[f"{mk}_{key}"] = g[f"modal_{mk}"]
    recovered, items = {}, {}
    for name, arr in d["recovered"].items():
        if name.endswith(COLUMNS):
            continue
        a = attrs[f"recovered/{name}"]
        recovered[name] = arr
        items[name] = RecoveryItem(name, str(a["body"]), str(a["category"]), strings(d["recovered"][name + COLUMNS]),
                                   strings(np.atleast_1d(a["column_units"])) if arr.shape[1] else (),
                                   str(a.get("description", "")), bool(a.get("from_acceleration", 0)))
    return TransientResult(
        time=d["time"], contact_names=strings(c["names"]), contact_directions=dirs, contact_force=c["force"],
        contact_state=c["state"], separation_time=c["separation_time"], recontact_count=c["recontact_count"],
        release_time=c["release_time"], output_labels=labels, displacement=disp, velocity=vel, acceleration=acc,
        recovered=recovered, recovery_items=items, rigid_body_motion_a=rb["a"], rigid_body_motion_b=rb["b"],
        iterations=d["iterations"], modal=modal, metadata=json.loads(rec.attrs["metadata"]))


def _json_safe(x):
    """``x`` with every non-finite float as null (standard JSON: a stability margin of inf,
    written as Infinity, broke strict readers of the results file's metadata)."""
    if isinstance(x, dict):
        return {k: _json_safe(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_json_safe(v) for v in x]
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x
