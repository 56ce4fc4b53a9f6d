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
MAX_MAGNITUDE = 1e100  # no SI quantity of a body comes near it; squares and products of two stay finite


def _real(who: str, name: str, value, ndim: int | None = None, shape: tuple | None = None) -> np.ndarray:
    """``value`` as a float array: real numbers only (no complex, text or objects); with
    ``ndim`` or ``shape`` exactly that (no silent reshaping, e.g. of a transposed phi)."""
    arr = np.asarray(value)
    if arr.dtype.kind == "c":
        raise InputError(f"{who}: {name} is complex ({arr.dtype}); a modal body is real")
    if arr.dtype.kind not in "biuf" and arr.size:
        raise InputError(f"{who}: {name} is not numeric ({arr.dtype})")
    arr = arr.astype(float)
    if ndim is not None and arr.ndim != ndim:
        raise InputError(f"{who}: {name} has shape {arr.shape}, expected {ndim} dimension(s)")
    if shape is not None and arr.shape != shape and not (arr.size == 0 and 0 in shape):
        raise InputError(f"{who}: {name} has shape {arr.shape}, expected {shape}"
                         + (" (DOF labels x modes)" if name == "phi" else ""))
    return arr.reshape(shape) if shape is not None and arr.size == 0 else arr


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
        who = f"body {self.name!r}"
        self.omega = _real(who, "omega", self.omega, ndim=1)
        n = self.omega.size
        self.zeta = _real(who, "zeta", self.zeta)
        if self.zeta.ndim == 0:
            self.zeta = np.full(n, float(self.zeta))
        self.dof_labels = tuple(str(s) for s in self.dof_labels)
        self.phi = _real(who, "phi", self.phi, shape=(len(self.dof_labels), n))
        self.participation = _real(who, "participation", self.participation)
        if self.participation.size == 0:
            self.participation = np.zeros((n, 6))
        self.ref_point = _real(who, "ref_point", self.ref_point)
        self.points = tuple(str(s) for s in self.points)
        self.point_coords = _real(who, "point_coords", self.point_coords)
        if self.point_coords.size == 0:
            self.point_coords = np.zeros((0, 3))
        self.rigid_body_mass = _real(who, "rigid_body_mass", self.rigid_body_mass)
        self.validate()

    # ------------------------------------------------------------------ checks
    def validate(self) -> None:
        """Raise InputError (one line, naming the culprit) on any inconsistency."""
        who = f"body {self.name!r}"
        n = self.omega.size
        if self.zeta.shape != (n,):
            raise InputError(f"{who}: zeta has shape {self.zeta.shape}, expected ({n},) or one value")
        if self.phi.shape != (len(self.dof_labels), n):
            raise InputError(f"{who}: phi has shape {self.phi.shape}, expected ({len(self.dof_labels)}, {n}) "
                             "(DOF labels x modes)")
        if self.point_coords.ndim != 2 or self.point_coords.shape[1] != 3:
            raise InputError(f"{who}: point_coords has shape {self.point_coords.shape}, expected (n_points, 3)")
        if self.participation.shape != (n, 6):
            raise InputError(f"{who}: participation has shape {self.participation.shape}, expected ({n}, 6)")
        if self.ref_point.shape != (3,):
            raise InputError(f"{who}: ref_point has shape {self.ref_point.shape}, expected (3,)")
        if self.rigid_body_mass.shape != (6, 6):
            raise InputError(f"{who}: rigid_body_mass has shape {self.rigid_body_mass.shape}, expected (6, 6)")
        if len(self.points) != self.point_coords.shape[0]:
            raise InputError(f"{who}: {len(self.points)} points but {self.point_coords.shape[0]} point_coords rows")
        for name in ("omega", "zeta", "phi", "participation", "ref_point", "point_coords", "rigid_body_mass"):
            arr = getattr(self, name)
            if not np.all(np.isfinite(arr)):
                raise InputError(f"{who}: {name} contains NaN or inf")
            if arr.size and np.abs(arr).max() > MAX_MAGNITUDE:
                raise InputError(f"{who}: {name} has a value of magnitude {np.abs(arr).max():.3g}, beyond "
                                 f"{MAX_MAGNITUDE:g} (SI units): its products would overflow")
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


#: a body file's rigid-body modes are checked to this fraction of their own size (an FE
#: eigensolution's rigid modes are rigid to ~1e-8; a wrong file, e.g. a transposed phi, is O(1) off)
CONSISTENCY_TOL = 1e-3
#: modes below this (rad/s, 0.016 Hz) are taken as rigid-body modes by the file check
RIGID_OMEGA = 0.1


def consistency_problems(body: ModalBody) -> list[str]:
    """What a body file's arrays say about one another that cannot be true (empty: none
    found). ``rigid_body_mass`` = RB^T M RB is symmetric positive semidefinite (all zero:
    not given, with no ``participation`` either; rigid-body outputs are then undefined). On
    the rigid-body components it gives (nonzero diagonal, ``sel``), where ``participation`` (Phi^T M RB) is given, the modes
    satisfy what mass-normalised modes of a free body must: the rigid ones (omega <
    RIGID_OMEGA) are rigid motions, Phi_r = RB M_rb^-1 P_r^T at every labelled DOF of a point
    with coordinates, with unit modal mass, P_r M_rb^-1 P_r^T = I; the elastic ones are
    orthogonal to rigid motion, P_e = 0. A transposed square phi, a negated rigid-body mass
    or mode shapes of another body break these."""
    rigid = body.omega < RIGID_OMEGA
    if body.phi.size and not np.any(body.phi):
        return ["phi is all zero: the body's DOFs do not move in any mode"]
    if int(rigid.sum()) > 6:
        return [f"{int(rigid.sum())} modes below {RIGID_OMEGA:g} rad/s: a body has at most six rigid-body modes "
                "(omega in rad/s, not zero for elastic modes)"]
    M = body.rigid_body_mass
    scale = float(np.abs(M).max(initial=0.0))
    if scale == 0:
        # RB^T M RB = 0 means M RB = 0 (M >= 0), and then participation = Phi^T M RB = 0 too
        if np.abs(body.participation).max(initial=0.0) > 0:
            return ["rigid_body_mass is all zero while participation (Phi^T M RB) is not: a body with mass has "
                    "RB^T M RB > 0; give it, or leave out both"]
        return []
    if np.abs(M - M.T).max() > 1e-9 * scale:
        return ["rigid_body_mass is not symmetric"]
    if np.linalg.eigvalsh(0.5 * (M + M.T)).min() < -1e-9 * scale:
        return ["rigid_body_mass is not positive semidefinite (a negative mass or inertia)"]
    P = body.participation
    sel = np.flatnonzero(np.diag(M) > 0)
    if not rigid.any() or not np.abs(P).max(initial=0.0) > 0 or not sel.size:
        return []
    Msel = M[np.ix_(sel, sel)]
    if not np.linalg.cond(Msel) < 1e12:
        return []
    Minv = np.linalg.inv(Msel)
    Pr, Pe = P[rigid][:, sel], P[~rigid][:, sel]
    out = []
    G = Pr @ Minv @ Pr.T
    off = float(np.abs(G - np.eye(G.shape[0])).max())
    if off > CONSISTENCY_TOL:
        out.append(f"the rigid-body modes' participation and rigid_body_mass do not give unit modal masses "
                   f"(P_r M_rb^-1 P_r^T off I by {off:.2g})")
    size = float(np.sqrt(np.diag(Msel).max()))
    if Pe.size and np.abs(Pe).max() > CONSISTENCY_TOL * size:
        j = int(np.argmax(np.abs(Pe).max(axis=1)))
        out.append(f"elastic mode {int(np.flatnonzero(~rigid)[j])} has a rigid-body participation "
                   f"{np.abs(Pe[j]).max():.3g}: elastic modes of a free body are orthogonal to rigid motion")
    rows = [i for i, lab in enumerate(body.dof_labels) if split_label(lab)[0] in set(body.points)]
    if rows and not out:
        from liftoff.core.rigid import rb_rows

        RB = rb_rows([body.dof_labels[i] for i in rows], body.points, body.point_coords, body.ref_point)
        expect = RB[:, sel] @ Minv @ Pr.T
        got = body.phi[rows][:, rigid]
        err = np.abs(got - expect).max() / max(float(np.abs(expect).max()), 1e-300)
        if err > CONSISTENCY_TOL:
            out.append(f"phi's rigid-body modes are not rigid motions of the labelled points (off by {err:.2g} of "
                       "their size): are phi's rows the DOF labels and its columns the modes (not transposed)?")
    return out


def _declared(path: Path, shapes: dict) -> None:
    """The body file's declared shapes (before its arrays are read): the datasets a body
    needs are there, and phi is (dof_labels x modes)."""
    missing = [k for k in ("omega", "dof_labels", "phi") if k not in shapes]
    if missing:
        raise InputError(f"body file {str(path)!r}: missing dataset {missing[0]!r}")
    labels, omega, phi = shapes["dof_labels"][0], shapes["omega"][0], shapes["phi"][0]
    if len(labels) != 1 or len(omega) != 1 or len(phi) != 2:
        return                      # ModalBody's own checks word these
    n_dof, n = labels[0], omega[0]
    if phi != (n_dof, n):
        raise InputError(f"body file {str(path)!r}: phi has shape {shapes['phi'][0]}, expected ({n_dof}, {n}) "
                         "(DOF labels x modes)")


def load_body(path: str | os.PathLike) -> ModalBody:
    """Read a body written by :func:`save_body` (or by a user's tool in the same format).
    The file's ``units`` must be SI (the format's); :func:`consistency_problems` must find
    nothing."""
    path = Path(path)
    rec = read_record(path, FORMAT, (VERSION,), what="body file", check=lambda shapes: _declared(path, shapes))
    units = rec.attrs.get("units")
    if units is not None and not str(units).strip().upper().startswith("SI"):
        raise InputError(f"body file {str(path)!r}: units {str(units)!r}, but a body file holds SI (m, kg, s, rad): "
                         "convert it (the Nastran import converts: liftoff.reduction.nastran, units = ...)")
    data = {k: v for k, v in rec.data.items() if k in _ARRAYS or k in ("dof_labels", "points")}
    missing = [k for k in ("omega", "zeta", "dof_labels", "phi", "participation") if k not in data]
    if missing:
        raise InputError(f"body file {str(path)!r}: missing dataset {missing[0]!r}")
    try:
        body = ModalBody(name=str(rec.attrs.get("name", path.stem)),
                         dof_labels=tuple(str(s) for s in np.atleast_1d(data.pop("dof_labels"))),
                         points=tuple(str(s) for s in np.atleast_1d(data.pop("points", ()))), **data)
        problems = consistency_problems(body)
        if problems:
            raise InputError(problems[0])
        return body
    except InputError as exc:
        raise InputError(f"body file {str(path)!r}: {exc}") from None
    except (ValueError, TypeError) as exc:
        raise InputError(f"body file {str(path)!r}: wrong array shapes ({exc})") from None
