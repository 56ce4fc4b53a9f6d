"""Loads and vehicle effects of one case -> the transient problem (section 4, 2.6).

* gravity through the rigid-body participation (eq. 14, in the transient core);
* cryo preload of the core tank at boundary DOFs only (section 4.3), constant;
* engine thrust tables at the engine mounts; other tabulated forces (winds);
* control system (eq. 15-21): lateral forces at the booster gimbals that cancel the
  moment of the applied forces about the c.g.; the applied forces are known tables,
  so the corrective forces are tables too, on the union of their time points (exact for
  piecewise-linear forcing: the correction is linear in the applied forces);
* gravity softening (eq. 22-27): KSOF as a modal feedback held over each step, until
  booster ignition; in the static initial conditions as -KSOF in the stiffness.
"""
from __future__ import annotations

import dataclasses

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from liftoff.transient import (
    ContactPoint,
    Forcing,
    ModalFeedback,
    PointForce,
    Recovery,
    TabulatedForce,
    TransientProblem,
)
from liftoff.transient.effects import center_of_gravity, cg_motion_matrix, control_forces
from threadpoolctl import threadpool_limits

from liftoff.config.scenario import Case
from liftoff.config.sections import Softening
from liftoff.config.values import Where
from liftoff.core.errors import InputError
from liftoff.core.labels import COMPONENTS, TRANSLATIONS, named_points

from .pipeline import StackModel, cryo_loads
from .report import CG_ACCELERATION



@dataclass
class CaseProblem:
    """The transient problem of one case plus what the reports need to read it back."""

    case: Case
    problem: TransientProblem
    cryo: dict[str, float]
    control_table: tuple[np.ndarray, np.ndarray, list[str]] | None
    softening: ModalFeedback | None
    attach: dict[str, tuple[str, str]] = field(default_factory=dict)  # recovery name -> (point, component)
    gravity_only: Forcing | None = None
    truncation: tuple = ()   # (vehicle, pad) TruncationCheck at the posts and attach points (reduction/truncation.py)


def _check_point(body, point: str, where: Where) -> None:
    if point not in body.points:
        raise where.error(f"point {point!r} is not on the {body.name} model "
                          f"(named points: {', '.join(named_points(body.points))[:300]})")


def _check_labels(body, labels, where: Where) -> None:
    for j, lab in enumerate(labels):
        try:
            body.dof_index(lab)
        except InputError as exc:
            raise (where / j).wrap(exc) from None


def _check_post_place(stack: StackModel, post, where: Where) -> None:
    """A post joins one place of both bodies: its vehicle point and its pad point must be
    where each other is (within reduction.assembly's tolerance for shared points); apart,
    the contact would couple two places as if they were one (a mirrored booster numbered
    otherwise than the pad's posts, a pad built on another layout)."""
    from liftoff.reduction.assembly import COORD_TOL

    a, b = stack.vehicle.point_coord(post.vehicle), stack.pad.point_coord(post.pad)
    size = max(1.0, float(np.ptp(stack.vehicle.point_coords, axis=0).max(initial=0.0)))
    if np.linalg.norm(a - b) > COORD_TOL * size:
        raise where.error(f"its vehicle point {post.vehicle!r} at {np.round(a, 4).tolist()} m and pad point "
                          f"{post.pad!r} at {np.round(b, 4).tolist()} m are {np.linalg.norm(a - b):.4g} m apart: a post "
                          "joins one place of both bodies")


def contacts(case: Case, stack: StackModel) -> list[ContactPoint]:
    """The hold-down posts (section 2.7) as contact points, vehicle = body a, pad = body b."""
    out = []
    for i, p in enumerate(case.posts):
        w = (case.at("post") / i).named(p.name)
        _check_point(stack.vehicle, p.vehicle, w / "vehicle")
        _check_point(stack.pad, p.pad, w / "pad")
        _check_post_place(stack, p, w)
        c = p.contact()
        if stack.pad.is_ground:             # rigid ground (type = "rigid_ground"): the post holds to a fixed point
            c = dataclasses.replace(c, labels_b=(None,) * len(c.labels_b))
        out.append(c)
    return out


def applied_forces(case: Case, stack: StackModel) -> tuple[list[PointForce], list[TabulatedForce]]:
    """Engine thrust (per direction component, tables) and the [[force]] entries (constant
    or tables; a force that is zero at every time is left out), all on the vehicle."""
    constant, tables = [], []
    for i, e in enumerate(case.engines):
        _check_point(stack.vehicle, e.mount, (case.at("engine") / i).named(e.name) / "mount")
        t, v = e.table()
        for c, d in zip(TRANSLATIONS, e.direction):
            if d != 0.0:
                tables.append(TabulatedForce("a", f"{e.mount}:{c}", t, d * v))
    for i, f in enumerate(case.forces):
        try:
            stack.vehicle.dof_index(f.label)
        except InputError as exc:
            raise ((case.at("force") / i).named(f.label) / "label").wrap(exc) from None
        if (f.value if f.time is None else np.abs(f.table).max()) == 0.0:
            continue                       # zero everywhere (e.g. a wind at scale 0): nothing to apply
        (constant if f.time is None else tables).append(f.on("a"))
    return constant, tables


def control_table(case: Case, stack: StackModel, tables: list[TabulatedForce],
                  constant: list[PointForce]) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """(time, FSL (n_t, n_gimbal), gimbal labels): eq. 19 on the union time grid of all
    applied tables, switched on at ``control.start`` over ``control.ramp`` seconds."""
    ctl = case.control
    body = stack.vehicle
    _check_labels(body, ctl.gimbals, case.at("control.gimbals"))
    t0, t1 = case.time.t0, case.time.t_end
    pts = [np.array([t0, t1])] + [tb.time for tb in tables]
    start, ramp = ctl.start, ctl.ramp
    if np.isfinite(start):
        pts.append(np.array([start, start + max(ramp, 1e-6)]))
    grid = np.unique(np.concatenate(pts))
    grid = grid[(grid >= t0) & (grid <= t1)]
    labels = sorted({tb.label for tb in tables} | {pf.label for pf in constant})
    P = np.zeros((grid.size, len(labels)))
    for tb in tables:
        P[:, labels.index(tb.label)] += np.interp(grid, tb.time, tb.value)
    for pf in constant:
        P[:, labels.index(pf.label)] += pf.value
    gimbals = list(ctl.gimbals)
    try:
        F = control_forces(body, gimbals, labels, P) if labels else np.zeros((grid.size, len(gimbals)))
    except InputError as exc:
        raise case.at("control.gimbals").wrap(exc) from None
    if np.isfinite(start):
        on = np.clip((grid - start) / max(ramp, 1e-6), 0.0, 1.0)
        F = F * on[:, None]
    return grid, F, gimbals


def softening(case: Case, stack: StackModel, soft: Softening | None = None) -> ModalFeedback:
    """Gravity softening KSOF (eq. 22-27) of the vehicle under the case's gravity, held over
    each step until ``softening.until`` (``soft``: another softening spec than the case's)."""
    soft = soft or case.softening
    if soft.labels is not None:
        _check_labels(stack.vehicle, soft.labels, case.at("softening.labels"))
    try:
        return soft.feedback(stack.vehicle, case.gravity)
    except InputError as exc:
        raise case.at("softening").wrap(exc) from None


def _attach_component(stack: StackModel, joints, point: str, where: Where) -> str:
    """The component whose interface force an attach recovery gives (``point@component``
    names it): at a joint, the last of the joint's components (the Shuttle's joints list the
    core first: the force on the booster or the orbiter), else the one component there."""
    owners = [n for n, cb in stack.cbs.items()
              if n != "pad" and any(f"{point}:{c}" in cb.boundary_labels for c in COMPONENTS)]
    if not owners:
        raise where.error(f"point {point!r} is not a boundary point of any vehicle component")
    for j in joints:
        if j.name == point and j.components[-1] in owners:
            return j.components[-1]
    return owners[0]


def _held_labels(stack: StackModel, comp: str, point: str, labels: list[str], spec: str, where: Where) -> list[str]:
    """The labels of ``point`` through which the rest of the vehicle pushes on ``comp`` (an
    attach recovery's rows; the others are zero): those ``comp`` has, less a direction a
    release leaves to ``comp`` alone and, where the point is shared, a direction no other
    component has there (a pinned strut's end brings no rotations: a pin passes no moment).
    One-line InputError naming ``spec`` when ``comp`` is no vehicle component or has no such
    point."""
    asm = stack.vehicle_asm
    names = [cb.name for cb in asm.components]
    if comp not in names:
        raise where.error(f"{spec!r}: no vehicle component {comp!r} (the vehicle's: {', '.join(names)})")
    own = set(stack.cbs[comp].boundary_labels).intersection(labels)
    if not own:
        raise where.error(f"{spec!r}: component {comp!r} has no point {point!r}")
    held = [lab for lab in labels if lab in own and not asm.released_apart(comp, lab)]
    others = [set(cb.boundary_labels) for cb in asm.components if cb.name != comp]
    if not any(lab in o for o in others for lab in labels):       # a point of this component alone
        return held
    return [lab for lab in held if any(lab in o for o in others)]


def recoveries(case: Case, stack: StackModel, cryo: dict | None = None) -> tuple[list[Recovery], dict, dict]:
    """Interface forces at attach points, c.g. motion (eq. 23), top/payload/stations motion.
    (The modal coordinates the full-field pictures need are kept by the transient's
    ``keep_modal = "q"`` storage, O(n) per step, not by identity-matrix recoveries.)
    ``cryo``: the case's cryo preload {vehicle label: N} (None: :func:`cryo_loads`').

    An interface force is the component's boundary rows of M xddot + K x less the loads
    applied to the component itself there (Craig-Bampton lumps part of its distributed
    loads on its boundary DOFs): its weight, A Phi^T M RB (-g) (eq. 14: the acceleration
    recovery of a uniform field -g, exact for the rigid-body part, which is all a uniform
    field has), and, on the cryo component, its cryo preload at those rows (section 4.3).
    Point forces applied at the recovery's own point (a joint's shared DOF belongs to no
    one component) and the gravity-softening feedback stay in it. A direction the joint
    releases (``[[model.joint]] release``) passes no force: its rows are zero (the boundary
    rows there would hold only the modal damping's and the feedback's residual); so are the
    rows of a DOF the component does not have there, and, at a shared point, of a DOF no other
    component has there (a pinned strut's end rotations: :func:`_held_labels`)."""
    from liftoff.reduction import cg_acceleration_recovery, interface_force_recovery

    body = stack.vehicle
    cryo = cryo_loads(stack, case.cryo, case.at("cryo")) if cryo is None else cryo
    g = np.asarray(case.gravity, dtype=float)
    out, attach = [], {}
    for spec in case.recovery.attach:
        point, _, comp = spec.partition("@")
        comp = comp or _attach_component(stack, case.model.joints, point, case.at("recovery.attach"))
        labels = [f"{point}:{c}" for c in COMPONENTS]
        held = _held_labels(stack, comp, point, labels, spec, case.at("recovery.attach"))
        rows = [labels.index(lab) for lab in held]
        D, A = (np.zeros((len(labels), body.n_modes)) for _ in range(2))   # a released direction: no force
        D[rows], A[rows] = stack.product(("interface_force", comp, tuple(held)), lambda: interface_force_recovery(
            stack.vehicle_asm, stack.vehicle_modes, comp, held))
        const = A @ body.modal_gravity(-g)                    # less the component's weight lumped here
        if case.cryo.enabled and comp == case.cryo.component:   # and its cryo preload
            const[rows] -= [cryo.get(stack.vehicle_asm.system_label(comp, lab), 0.0) for lab in held]
        name = f"attach_{point}"
        out.append(Recovery(name, "a", COMPONENTS, disp=D, acc=A, units=("N",) * 3 + ("N m",) * 3,
                            category="interface_force", const=const,
                            description=f"force of the rest of the vehicle on {comp} at {point}"))
        attach[name] = (point, comp)
    out.append(Recovery("cg_motion", "a", COMPONENTS, disp=stack.product(("cg_motion",), lambda: cg_motion_matrix(body)),
                        units=("m",) * 3 + ("rad",) * 3, category="cg_motion", description="vehicle c.g. motion (eq. 23)"))
    for comp in (cb.name for cb in stack.vehicle_asm.components):
        A, mass = stack.product(("cg_acceleration", comp), lambda: cg_acceleration_recovery(
            stack.vehicle_asm, stack.vehicle_modes, comp))
        out.append(Recovery(f"cg_accel_{comp}", "a", TRANSLATIONS, acc=A, units="m/s^2", category=CG_ACCELERATION,
                            description=f"net acceleration of {comp}'s c.g. (rigid-body mass x/y/z "
                                        f"{'/'.join(f'{m:.6g}' for m in mass)} kg)"))
    out += component_recoveries(stack)
    w = case.at("recovery")
    out += otm_recoveries(case.recovery.otm, body, w / "otm")
    outputs = []
    for key in ("top", "payload"):
        pt = getattr(case.recovery, key)
        if pt:
            _check_point(body, pt, w / key)
            outputs += [f"{pt}:{c}" for c in TRANSLATIONS]
    for i, pt in enumerate(case.recovery.stations):
        _check_point(body, pt, w / "stations" / i)
        outputs += [f"{pt}:{c}" for c in TRANSLATIONS if f"{pt}:{c}" not in outputs]
    return out, attach, {"a": outputs, "b": []}


def otm_recoveries(otms, body, where: Where) -> list[Recovery]:
    """``[[recovery.otm]]``: each payload OTM (reduction.nastran.interface_otm, SI) composed
    with the vehicle's modes at its point, y = OTM (Phi_p q) per part: an item
    ``otm_<name>`` of category "otm" on body a."""
    from liftoff.reduction.nastran import interface_otm

    out = []
    for i, o in enumerate(otms):
        _check_point(body, o.point, where / i / "point")
        labels = [f"{o.point}:{c}" for c in COMPONENTS]
        try:
            rows = np.array([body.dof_index(lab) for lab in labels])
        except InputError as exc:
            raise (where / i / "point").error(f"an OTM needs the point's six DOFs T1..R3 on the vehicle model "
                                              f"({exc})") from None
        try:
            names, units, parts = interface_otm(o.file, name=o.name, units=o.units, disp=o.disp, vel=o.vel, acc=o.acc,
                                                rows=o.rows, quantity=o.quantity)
        except InputError as exc:
            raise (where / i).wrap(exc) from None
        phi = body.phi[rows]
        out.append(Recovery(f"otm_{o.name}", "a", names, units=units, category="otm",
                            description=f"payload OTM {o.name!r} ({Path(o.file).name}) at {o.point}",
                            **{k: Y @ phi for k, Y in parts.items()}))
    return out


def component_recoveries(stack: StackModel) -> list[Recovery]:
    """The recovery items that came with the components (Nastran DTM/ATM/LTM: CBModel.recovery),
    carried through the system modes (reduction.component_recovery): vehicle ones on body a,
    the pad's on body b."""
    from liftoff.reduction import component_recovery

    out = []
    for name, cb in stack.cbs.items():
        if not cb.recovery:
            continue
        asm, modes, key = (stack.pad_asm, stack.pad_modes, "b") if name == "pad" else \
            (stack.vehicle_asm, stack.vehicle_modes, "a")
        for it in component_recovery(asm, modes, name):
            out.append(Recovery(it.name, key, it.labels, disp=it.disp, vel=it.vel, acc=it.acc, units=it.units,
                                category="component", description=f"recovery item of component {name}"))
    return out


def attitude_feedback(case: Case, stack: StackModel) -> ModalFeedback:
    """The attitude hold of ``[control] law = "attitude-hold"`` (transient.effects.attitude_hold),
    on from ``hold_start`` (default: the control start)."""
    from liftoff.transient.effects import attitude_hold

    ctl = case.control
    since = ctl.hold_start if ctl.hold_start is not None else ctl.start
    try:
        return attitude_hold(stack.vehicle, ctl.gimbals, ctl.bandwidth_hz, ctl.damping, since=since)
    except InputError as exc:
        raise Where(case.source, "control").wrap(exc) from None


@threadpool_limits.wrap(limits=1, user_api="blas")   # the same arithmetic in any process (campaign workers)
def build_problem(case: Case, stack: StackModel, progress: bool = True, keep_modal: bool | str = False) -> CaseProblem:
    """The two-body transient of one case: posts, cryo preload, thrust and forces, control
    forces, gravity softening, recoveries; static initial state (section 2.6).
    ``keep_modal``: the transient's modal storage ("q": modal displacements, for full-field
    pictures and ParaView output)."""
    body = stack.vehicle
    cps = contacts(case, stack)
    cryo = cryo_loads(stack, case.cryo, case.at("cryo"))
    constant, tables = applied_forces(case, stack)
    constant = [PointForce("a", lab, val) for lab, val in cryo.items()] + constant
    ctab = None
    if case.control.enabled:
        ctab = control_table(case, stack, tables, constant)
        grid, F, labels = ctab
        tables = tables + [TabulatedForce("a", lab, grid, F[:, j]) for j, lab in enumerate(labels)]
    soft = softening(case, stack) if case.softening.enabled else None
    feedback = [soft] if soft else []
    if case.control.enabled and case.control.law == "attitude-hold":
        feedback.append(attitude_feedback(case, stack))
    forcing = Forcing(constant=constant, tables=tables, feedback=feedback, gravity=case.gravity)
    recs, attach, outputs = recoveries(case, stack, cryo)
    problem = case.time.problem(body, stack.pad, cps, forcing, initial="static", outputs=outputs, recoveries=recs,
                                keep_modal=keep_modal, progress=progress and case.output.progress)
    checks = stack.truncation([lab for c in cps for lab in c.labels_a], [lab for c in cps for lab in c.labels_b],
                              [f"{point}:{c}" for point, _ in attach.values() for c in COMPONENTS])
    return CaseProblem(case, problem, cryo, ctab, soft, attach, gravity_only=Forcing(gravity=case.gravity),
                       truncation=checks)


def table1(stack: StackModel, cp: CaseProblem, case: Case):
    """Table 1 of the reference for this stack on its pad: c.g. motion under static loads
    (gravity only; + softening; + cryo; + both). Softening is always evaluated (KSOF of
    this stack and gravity); the cryo rows use the case's cryo preload and are marked
    when the case has cryo switched off (they then repeat rows 1-2)."""
    from liftoff.transient.effects import cg_static_report

    soft = cp.softening or softening(case, stack, Softening(True, labels=case.softening.labels))
    cryo = [PointForce("a", k, v) for k, v in cp.cryo.items()]
    cps = [c for c in cp.problem.contacts]
    rep = cg_static_report(stack.vehicle, stack.pad, cps, cp.gravity_only, cryo, soft)
    if not cryo:
        rep.rows[2:] = [r + " (cryo off)" for r in rep.rows[2:]]
    return rep


def table1_inputs(cp: CaseProblem) -> list:
    """What :func:`table1` takes from a case besides its stack: the contacts as the static
    (bolted) state sees them (not their release times or laws), the cryo preload, gravity and
    the softening (its factors or matrix, else the labels its default is built from)."""
    from .cache import content_sha256

    soft = cp.softening
    arrays = () if soft is None else tuple(a for a in (*(soft.factors or ()), soft.matrix) if a is not None)
    return [[repr((c.name, list(c.labels_a), list(c.labels_b), c.stiffness, c.axial, c.normal_sign, c.gap, c.rigid,
                   c.normal)) for c in cp.problem.contacts],
            sorted(cp.cryo.items()), repr(tuple(cp.gravity_only.gravity) if cp.gravity_only is not None else None),
            content_sha256(arrays) if arrays else repr(cp.case.softening.labels)]


def stack_mass_summary(stack: StackModel) -> str:
    from liftoff.transient.effects import rigid_mass

    m, cg = center_of_gravity(stack.vehicle)
    m_z = float(rigid_mass(stack.vehicle)[2, 2])
    axial = "" if abs(m_z - m) <= 1e-6 * m else \
        f" (axial {m_z / 1e3:.1f} t: a hydroelastic liquid's sloshing part is not carried laterally, docs/hydro.md)"
    return (f"vehicle: {stack.vehicle.n_modes} modes ({np.sum(stack.vehicle.omega > 0)} elastic, first "
            f"{stack.vehicle.omega[6] / 2 / np.pi if stack.vehicle.n_modes > 6 else float('nan'):.2f} Hz), "
            f"mass {m / 1e3:.1f} t{axial}, c.g. {np.round(cg, 2).tolist()} m; pad: "
            + (f"{stack.pad.n_modes} modes (first {stack.pad.omega[0] / 2 / np.pi:.2f} Hz)" if stack.pad.n_modes
               else "rigid ground (no modes)"))
