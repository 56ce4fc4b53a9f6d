"""Vehicle effects of section 4 of Prabhakar & Palermo, as plain numpy functions.

* the c.g. of a modal body from its rigid-body mass (eq. 14 quantities; the rigid-body
  kinematics themselves are liftoff.core.rigid);
* control system (eq. 15-21): lateral gimbal forces that cancel the moment of the
  applied forces about the vehicle c.g.; beyond the reference, an attitude hold (a PD
  law on the rigid-body attitude and rate through the same gimbals);
* gravity softening (eq. 22-27): the c.g. motion matrix ERV and the softening matrix
  KSOF, carried as a modal feedback force (held over a step) in the transient and as a
  stiffness correction in statics;
* cryogenic preload (section 4.3): boundary-DOF load vectors summed into point forces,
  with their resultant (a cryo load is self-equilibrated);
* c.g. motion under static loads in the form of the reference's Table 1.

Conventions: DOF labels ``point:Tx..Rz``; small rotations theta give the translation
u = t + theta x r of a point at offset r. SI units (N, m, kg, s, rad).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from liftoff.core.errors import InputError
from liftoff.core.labels import split_label
from liftoff.core.rigid import cg_mass, rb_rows, shift_rb, skew

from .body import ModalBody


# ---------------------------------------------------------------- rigid-body mass
def body_rb(body: ModalBody, labels, point) -> np.ndarray:
    """Geometric rigid-body shape RB (len(labels), 6) of the body's labelled DOFs about ``point``."""
    return rb_rows(labels, body.points, body.point_coords, point)


def rigid_mass(body: ModalBody) -> np.ndarray:
    """RB^T M RB about body.ref_point (6x6): the body's own value, else participation^T participation."""
    R = body.rigid_body_mass
    if not np.any(R):
        R = body.participation.T @ body.participation
    return R


def center_of_gravity(body: ModalBody) -> tuple[float, np.ndarray]:
    """(mass kg, c.g. m) of a body from its rigid-body mass (liftoff.core.cg_mass)."""
    mp = cg_mass(rigid_mass(body), body.ref_point)
    if not mp.mass > 0:
        raise InputError(f"body {body.name!r}: zero mass in its rigid-body mass matrix; no c.g.")
    return mp.mass, mp.cg


def participation_about(body: ModalBody, point) -> np.ndarray:
    """Phi^T M RB (n, 6) with RB taken about ``point`` instead of body.ref_point."""
    return body.participation @ shift_rb(np.asarray(point, float) - body.ref_point)


# ---------------------------------------------------------------- control system
def control_gimbal_matrix(body: ModalBody, gimbal_labels, cg=None) -> np.ndarray:
    """G (n_gimbal_dofs, 3) with FSL = -G @ M_R, the lateral gimbal forces that apply the
    moment -M_R about the c.g. (eq. 17-19).

    T1R = (RBL_R^T RBL_R)^-1 RBL_R^T is the least-squares fit of the c.g. rotation from the
    gimbal lateral motions (eq. 17-18; RBL_R = rotational columns of RB at the gimbal
    DOFs), and FSL = -T1R^T M_R (eq. 19). Its moment about the c.g. is RBL_R^T FSL = -M_R
    exactly when RBL_R has rank 3 (two gimbals at a height different from the c.g.).
    """
    if cg is None:
        cg = center_of_gravity(body)[1]
    RBL_R = body_rb(body, gimbal_labels, cg)[:, 3:]
    if np.linalg.matrix_rank(RBL_R, tol=1e-9 * max(1.0, np.abs(RBL_R).max())) < 3:
        raise InputError("control system: the gimbal DOFs " + ", ".join(gimbal_labels)
                         + " cannot produce a moment about every axis through the c.g.")
    T1R = np.linalg.solve(RBL_R.T @ RBL_R, RBL_R.T)
    return T1R.T


def resultant_about(body: ModalBody, labels, forces: np.ndarray, point) -> np.ndarray:
    """Resultant (..., 6: force, moment) about ``point`` of physical forces at labelled DOFs,
    P_R = RB^T P_A (eq. 15). ``forces`` has shape (..., len(labels))."""
    RB = body_rb(body, labels, point)
    return np.asarray(forces, float) @ RB


def modal_resultant_about(body: ModalBody, modal_force: np.ndarray, point) -> np.ndarray:
    """The same resultant from generalised forces F_A = Phi^T P_A: RB^T Phi^-T F_A with
    Phi^-1 = Phi^T M (eq. 20-21), i.e. (Phi^T M RB)^T F_A = participation^T F_A."""
    return np.asarray(modal_force, float) @ participation_about(body, point)


def control_forces(body: ModalBody, gimbal_labels, applied_labels, applied: np.ndarray,
                   cg=None) -> np.ndarray:
    """Lateral gimbal forces FSL (..., n_gimbal) that cancel the moment about the c.g. of the
    applied forces ``applied`` (..., n_applied) at ``applied_labels`` (eq. 15-19)."""
    if cg is None:
        cg = center_of_gravity(body)[1]
    M_R = resultant_about(body, applied_labels, applied, cg)[..., 3:]
    return -M_R @ control_gimbal_matrix(body, gimbal_labels, cg).T


def rigid_rotation_rows(body: ModalBody, cg=None) -> tuple[np.ndarray, np.ndarray]:
    """(R (3, n), I_cg (3, 3)): the rigid-body rotation of the body about its c.g.,
    theta = R q (from x_rb = (RB^T M RB)^-1 (Phi^T M RB)^T q about the c.g., eq. 14
    quantities), and its inertia tensor about the c.g. (kg m^2)."""
    if cg is None:
        cg = center_of_gravity(body)[1]
    T = shift_rb(np.asarray(cg, float) - body.ref_point)
    M_cg = T.T @ rigid_mass(body) @ T
    part = participation_about(body, cg)
    return np.linalg.solve(M_cg, part.T)[3:], M_cg[3:, 3:]


def attitude_hold(body: ModalBody, gimbal_labels, bandwidth_hz: float, damping: float, since: float = -np.inf,
                  cg=None):
    """Attitude hold beyond the reference: a PD law on the vehicle's rigid-body attitude and
    rate, through the same lateral gimbal forces as eq. 15-21. The commanded angular
    acceleration about the c.g. is alpha = -(w^2 theta + 2 zeta w theta_dot), w = 2 pi
    ``bandwidth_hz``, zeta = ``damping``; the moment I_cg alpha is applied by the gimbal
    forces F = G (I_cg alpha) (G of :func:`control_gimbal_matrix`: -G M cancels M, so G M
    applies it), i.e. the modal force Phi_g^T F. Returned as a ModalFeedback in rank-3
    factored form (U (-w^2 R) on q, U (-2 zeta w R) on v, held over each step, on from
    ``since``; no n x n matrix): the rigid vehicle's pitch,
    yaw and roll then follow theta'' + 2 zeta w theta' + w^2 theta = 0."""
    from .model import ModalFeedback

    if not (np.isfinite(bandwidth_hz) and bandwidth_hz > 0 and np.isfinite(damping) and damping >= 0):
        raise InputError(f"attitude hold: bandwidth {bandwidth_hz!r} Hz must be > 0 and damping {damping!r} >= 0")
    if cg is None:
        cg = center_of_gravity(body)[1]
    R, I_cg = rigid_rotation_rows(body, cg)
    G = control_gimbal_matrix(body, gimbal_labels, cg)
    U = body.rows(gimbal_labels).T @ G @ I_cg               # B = U R: modal force of alpha = theta (rad/s^2 per rad)
    w = 2 * np.pi * bandwidth_hz
    return ModalFeedback("a", since=since, factors=(U, -w * w * R, -2 * damping * w * R))  # rank 3: no n x n


# ---------------------------------------------------------------- gravity softening
def cg_motion_matrix(body: ModalBody, boundary_labels=None, cg=None) -> np.ndarray:
    """ERV (6, n): c.g. motion (3 translations, 3 rotations) from modal coordinates,
    x_g = (RB^T RB)^-1 RB^T Phi_b q (eq. 22-23), with RB about the c.g. of the boundary
    DOFs (default: every labelled DOF of the body)."""
    if cg is None:
        cg = center_of_gravity(body)[1]
    labels = list(body.dof_labels if boundary_labels is None else boundary_labels)
    RB = body_rb(body, labels, cg)
    if np.linalg.matrix_rank(RB) < 6:
        raise InputError(f"body {body.name!r}: boundary DOFs do not determine the c.g. motion "
                         "(their rigid-body shape has rank < 6)")
    T2 = np.linalg.solve(RB.T @ RB, RB.T)
    return T2 @ body.rows(labels)


def softening_factors(body: ModalBody, gravity, boundary_labels=None, cg=None) -> tuple[np.ndarray, np.ndarray]:
    """KSOF of eq. 27 in rank-3 factored form (U (n, 3), V (3, n)), KSOF = U V:
    U = ERVr^T FGM, V = ERVt (see :func:`softening_matrix`)."""
    m, cg0 = center_of_gravity(body)
    if cg is None:
        cg = cg0
    ERV = cg_motion_matrix(body, boundary_labels, cg)
    FG = m * np.asarray(gravity, dtype=float)[:3]
    FGM = -skew(FG)
    return ERV[3:].T @ FGM, ERV[:3]


def softening_matrix(body: ModalBody, gravity, boundary_labels=None, cg=None) -> np.ndarray:
    """KSOF (n, n) of eq. 27 as a feedback force: F_SOF = KSOF q (eq. 26).

    The weight F_G = m g acting at the displaced c.g. adds the moment
    M_G = x_gt x F_G = FGM x_gt with FGM = -skew(F_G) (eq. 25, sign written so that a
    lateral c.g. offset gives a moment that increases it); F_SOF = ERVr^T M_G. In statics
    the effective stiffness is diag(omega^2) - KSOF.
    """
    U, V = softening_factors(body, gravity, boundary_labels, cg)
    return U @ V


# ---------------------------------------------------------------- cryo preload
def cryo_point_loads(boundary_loads: list[tuple[tuple[str, ...], np.ndarray]]) -> dict[str, float]:
    """Sum boundary-DOF load vectors (labels, values) of several CB components into one
    {label: force} map on the assembled vehicle (overlay by label, section 4.3)."""
    out: dict[str, float] = {}
    for labels, values in boundary_loads:
        values = np.asarray(values, float).reshape(-1)
        if len(labels) != values.size:
            raise InputError(f"cryo load: {len(labels)} labels but {values.size} values")
        for lab, v in zip(labels, values):
            split_label(lab)
            out[lab] = out.get(lab, 0.0) + float(v)
    return out


def load_resultant(body: ModalBody, loads: dict[str, float], point=None) -> np.ndarray:
    """Resultant (6,) of a {label: force} map about ``point`` (default the c.g.)."""
    if point is None:
        point = center_of_gravity(body)[1]
    labels = list(loads)
    return resultant_about(body, labels, np.array([loads[k] for k in labels]), point)


# ---------------------------------------------------------------- Table 1
@dataclass
class CGReport:
    """C.g. motion (m, rad) under static loads, one row per load combination (Table 1)."""

    rows: list[str]
    motion: np.ndarray  # (n_rows, 6): Tx Ty Tz (m), Rx Ry Rz (rad)

    def table(self) -> str:
        head = f"{'static loads':<34}{'X (m)':>12}{'Y (m)':>12}{'Z (m)':>12}" \
               f"{'X (in)':>10}{'Y (in)':>10}{'Z (in)':>10}"
        lines = ["Vehicle c.g. motion under static loads (cf. Table 1 of the reference)", head]
        for name, x in zip(self.rows, self.motion):
            lines.append(f"{name:<34}" + "".join(f"{v:12.4e}" for v in x[:3])
                         + "".join(f"{v / 0.0254:10.3f}" for v in x[:3]))
        return "\n".join(lines)

    def csv(self) -> str:
        out = ["case,x_m,y_m,z_m,rx_rad,ry_rad,rz_rad"]
        out += [f"{n}," + ",".join(f"{v:.9e}" for v in x) for n, x in zip(self.rows, self.motion)]
        return "\n".join(out) + "\n"


TABLE1_ROWS = ("1) gravity only", "2) gravity + softening", "3) gravity + cryo",
               "4) gravity + softening + cryo")


def cg_static_report(body_a: ModalBody, body_b: ModalBody, contacts, gravity_forcing,
                     cryo_forces, softening, boundary_labels=None) -> CGReport:
    """Table 1: c.g. motion of body A on body B under static loads: gravity only;
    + softening; + cryo; + both. ``gravity_forcing`` is a transient.Forcing with gravity
    (and any other constant load), ``cryo_forces`` a list of PointForce, ``softening`` the
    ModalFeedback carrying KSOF."""
    from dataclasses import replace

    from .solver import static_equilibrium

    ERV = cg_motion_matrix(body_a, boundary_labels)
    motion = []
    for soft, cryo in ((False, False), (True, False), (False, True), (True, True)):
        f = replace(gravity_forcing,
                    constant=list(gravity_forcing.constant) + (list(cryo_forces) if cryo else []),
                    feedback=list(gravity_forcing.feedback) + ([softening] if soft else []))
        state = static_equilibrium(body_a, body_b, contacts, f, t=0.0)
        motion.append(ERV @ state.q_a)
    return CGReport(list(TABLE1_ROWS), np.array(motion))
