"""Modal bodies: the data a body brings to the two-body transient, and its file format.

A modal body is the uncoupled modal model of eq. 4-6 of Prabhakar & Palermo: natural
frequencies ``omega`` (rad/s, rigid-body modes have omega = 0), modal damping ratios
``zeta``, mass-normalised mode-shape rows ``phi`` at labelled DOFs (Phi^T M Phi = I),
and the rigid-body participation ``participation = Phi^T M RB`` (n_modes x 6, RB the
geometric rigid-body shape about ``ref_point``) that turns a uniform acceleration field
a (6-vector: 3 translations m/s^2, 3 rotations rad/s^2) into modal forces Phi^T M RB a
(eq. 14). A body with no modes is rigid ground.

DOF labels are ``point:component`` with component in Tx Ty Tz Rx Ry Rz.

File format (``.h5`` via h5py, or ``.npz``; same names in both; SI units; no pickle):

=================  ===============  =====================================================
name               shape / type     meaning (unit)
=================  ===============  =====================================================
format             str              "liftoff-modal-body"
version            int              1
name               str              body name
omega              (n,)             natural circular frequency (rad/s)
zeta               (n,)             modal damping ratio (-)
dof_labels         (n_dof,) str     labels of the rows of phi
phi                (n_dof, n)       mass-normalised mode shapes (m/sqrt(kg) or rad/sqrt(kg m^2))
participation      (n, 6)           Phi^T M RB about ref_point (sqrt(kg), sqrt(kg) m)
ref_point          (3,)             reference point of RB (m)
points             (n_p,) str       names of labelled points (may be empty)
point_coords       (n_p, 3)         their coordinates (m)
rigid_body_mass    (6, 6)           RB^T M RB about ref_point (kg, kg m, kg m^2)
=================  ===============  =====================================================
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from liftoff.core.errors import InputError
from liftoff.core.labels import split_label
from liftoff.core.records import read_record, write_record

FORMAT = "liftoff-modal-body"
VERSION = 1


@dataclass
class ModalBody:
    """Uncoupled modal model of one body (eq. 4-6). See the module docstring for units."""

    name: str
    omega: np.ndarray
    zeta: np.ndarray
    dof_labels: tuple[str, ...]
    phi: np.ndarray
    participation: np.ndarray
    ref_point: np.ndarray = field(default_factory=lambda: np.zeros(3))
    points: tuple[str, ...] = ()
    point_coords: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    rigid_body_mass: np.ndarray = field(default_factory=lambda: np.zeros((6, 6)))

    def __post_init__(self) -> None:
        self.omega = np.asarray(self.omega, dtype=float).reshape(-1)
        n = self.omega.size
        self.zeta = np.broadcast_to(np.asarray(self.zeta, dtype=float), (n,)).copy()
        self.dof_labels = tuple(str(s) for s in self.dof_labels)
        self.phi = np.asarray(self.phi, dtype=float).reshape(len(self.dof_labels), n)
        self.participation = np.asarray(self.participation, dtype=float)
        if self.participation.size == 0:
            self.participation = np.zeros((n, 6))
        self.ref_point = np.asarray(self.ref_point, dtype=float)
        self.points = tuple(str(s) for s in self.points)
        self.point_coords = np.asarray(self.point_coords, dtype=float).reshape(-1, 3)
        self.rigid_body_mass = np.asarray(self.rigid_body_mass, dtype=float)
        self.validate()

    # ------------------------------------------------------------------ checks
    def validate(self) -> None:
        """Raise InputError (one line, naming the culprit) on any inconsistency."""
        who = f"body {self.name!r}"
        n = self.omega.size
        if self.participation.shape != (n, 6):
            raise InputError(f"{who}: participation has shape {self.participation.shape}, expected ({n}, 6)")
        if self.ref_point.shape != (3,):
            raise InputError(f"{who}: ref_point has shape {self.ref_point.shape}, expected (3,)")
        if self.rigid_body_mass.shape != (6, 6):
            raise InputError(f"{who}: rigid_body_mass has shape {self.rigid_body_mass.shape}, expected (6, 6)")
        if len(self.points) != self.point_coords.shape[0]:
            raise InputError(f"{who}: {len(self.points)} points but {self.point_coords.shape[0]} point_coords rows")
        for name in ("omega", "zeta", "phi", "participation", "ref_point", "point_coords", "rigid_body_mass"):
            if not np.all(np.isfinite(getattr(self, name))):
                raise InputError(f"{who}: {name} contains NaN or inf")
        if np.any(self.omega < 0):
            raise InputError(f"{who}: negative natural frequency in omega (mode {int(np.argmax(self.omega < 0))})")
        if np.any(self.zeta < 0):
            raise InputError(f"{who}: negative damping ratio in zeta (mode {int(np.argmax(self.zeta < 0))})")
        seen = set()
        for lab in self.dof_labels:
            split_label(lab)
            if lab in seen:
                raise InputError(f"{who}: duplicate DOF label {lab!r}")
            seen.add(lab)
        if len(set(self.points)) != len(self.points):
            raise InputError(f"{who}: duplicate point names")

    # ------------------------------------------------------------- accessors
    @property
    def n_modes(self) -> int:
        return self.omega.size

    @property
    def is_ground(self) -> bool:
        """A body with no modes is rigid ground."""
        return self.omega.size == 0

    @property
    def mass(self) -> float:
        """Total mass (kg) from rigid_body_mass."""
        return float(self.rigid_body_mass[0, 0])

    def dof_index(self, label: str) -> int:
        """Row of ``phi`` for a DOF label; InputError naming the label if absent."""
        split_label(label)
        try:
            return self.dof_labels.index(label)
        except ValueError:
            raise InputError(f"unknown DOF label {label!r} on body {self.name!r}") from None

    def rows(self, labels) -> np.ndarray:
        """Mode-shape rows (len(labels), n_modes) for the given labels."""
        return self.phi[[self.dof_index(lab) for lab in labels], :]

    def point_coord(self, point: str) -> np.ndarray:
        try:
            return self.point_coords[self.points.index(point)]
        except ValueError:
            raise InputError(f"unknown point {point!r} on body {self.name!r}") from None

    def modal_gravity(self, accel) -> np.ndarray:
        """Modal force Phi^T M RB a of a uniform acceleration field a (eq. 14), a of length 3 or 6."""
        a = np.zeros(6)
        a[: len(accel)] = accel
        return self.participation @ a

    # ------------------------------------------------------------------- I/O
    def save(self, path: str | os.PathLike) -> Path:
        return save_body(self, path)

    @classmethod
    def load(cls, path: str | os.PathLike) -> "ModalBody":
        return load_body(path)


def ground(name: str = "ground") -> ModalBody:
    """Rigid ground: a body with no modes and no DOFs (every label is fixed at zero)."""
    return ModalBody(name=name, omega=np.zeros(0), zeta=np.zeros(0), dof_labels=(),
                     phi=np.zeros((0, 0)), participation=np.zeros((0, 6)))


_ARRAYS = ("omega", "zeta", "phi", "participation", "ref_point", "point_coords", "rigid_body_mass")
UNITS = "SI (m, kg, s, rad)"


def save_body(body: ModalBody, path: str | os.PathLike) -> Path:
    """Write a body atomically (temporary file + rename) as .h5 or .npz."""
    body.validate()
    data = {k: getattr(body, k) for k in _ARRAYS}
    data["dof_labels"] = np.array(body.dof_labels, dtype="U")
    data["points"] = np.array(body.points, dtype="U")
    return write_record(path, FORMAT, VERSION, data, units=UNITS, attrs={"name": body.name})


def load_body(path: str | os.PathLike) -> ModalBody:
    """Read a body written by :func:`save_body` (or by a user's tool in the same format)."""
    path = Path(path)
    rec = read_record(path, FORMAT, (VERSION,), what="body file")
    data = {k: v for k, v in rec.data.items() if k in _ARRAYS or k in ("dof_labels", "points")}
    missing = [k for k in ("omega", "zeta", "dof_labels", "phi", "participation") if k not in data]
    if missing:
        raise InputError(f"body file {str(path)!r}: missing dataset {missing[0]!r}")
    try:
        return ModalBody(name=str(rec.attrs.get("name", path.stem)),
                         dof_labels=tuple(str(s) for s in np.atleast_1d(data.pop("dof_labels"))),
                         points=tuple(str(s) for s in np.atleast_1d(data.pop("points", ()))), **data)
    except InputError as exc:
        raise InputError(f"body file {str(path)!r}: {exc}") from None
    except (ValueError, TypeError) as exc:
        raise InputError(f"body file {str(path)!r}: wrong array shapes ({exc})") from None
