"""Static solves, loads and mass properties on an FE model's independent DOFs (SI units)."""
from __future__ import annotations

import numpy as np

from liftoff.core.errors import ConvergenceError, InputError
from liftoff.core.rigid import MassProperties, cg_mass

from . import petsc_backend as pb
from .elasticity import thermal_load_form
from .model import FEModel


def static_solve(model: FEModel, f: np.ndarray, supports=()) -> np.ndarray:
    """Displacements x (n_dof,) with K x = f and x[supports] = 0.

    ``supports``: DOF indices or ``point:Tx`` labels held at zero (e.g. a 3-2-1 set for a
    free-free body). A free-free model needs at least 6 supports; a singular system is
    reported (InputError), never returned as a result.
    """
    f = np.asarray(f, float).reshape(-1)
    if f.size != model.n_dof:
        raise InputError(f"static_solve: load has {f.size} entries, model {model.name!r} has {model.n_dof} DOFs")
    fixed = np.array([model.dof_index(s) if isinstance(s, str) else int(s) for s in supports], dtype=np.int64)
    if fixed.size and (fixed.min() < 0 or fixed.max() >= model.n_dof):
        raise InputError(f"static_solve: support DOF out of range 0..{model.n_dof - 1}")
    if not model.grounded and np.unique(fixed).size < 6:
        raise InputError(f"static_solve: model {model.name!r} is free-free (no clamped surface); "
                         f"give >= 6 supports that stop rigid-body motion (got {np.unique(fixed).size})")
    x = pb.solve(model.K, f, fixed, what=f"model {model.name!r}")
    K, _ = model.matrices()
    free = np.ones(model.n_dof, bool)
    free[fixed] = False
    r = (K @ x - f)[free]
    # a direct solve leaves a residual ~ eps * cond; 1e-6 of the load flags a singular K
    if not np.all(np.isfinite(x)) or np.linalg.norm(r) > 1e-6 * np.linalg.norm(f[free]):
        raise ConvergenceError(f"static_solve: model {model.name!r}: residual {np.linalg.norm(r):.3g} vs load "
                               f"{np.linalg.norm(f[free]):.3g}: K is singular for these supports (mechanism)")
    return x


def point_load(model: FEModel, point: str, force=(0.0, 0.0, 0.0), moment=(0.0, 0.0, 0.0)) -> np.ndarray:
    """Load vector (n_dof,) with a force (N) and moment (N m) at a reference point."""
    f = np.zeros(model.n_dof)
    i = model.dof_index(f"{point}:Tx")
    f[i:i + 3] = force
    f[i + 3:i + 6] = moment
    return f


def thermal_load(model: FEModel, volumes, delta_T: float, alpha) -> np.ndarray:
    """Equivalent nodal forces (n_dof,) of a uniform free thermal strain alpha * delta_T in
    the named volume groups, shell surfaces or beam groups (the cryogenic preload: delta_T <
    0 shrinks; on a shell the strain is in-plane and uniform through the thickness, on a
    beam axial). A shell wall's members (the beam groups whose BeamGroup.wall is it: its
    frames and stringers) take its strain with it: they are at its temperature, and a wall
    shrinking under members that do not held them back by the whole mismatch; a member
    named in ``volumes`` itself takes its own entry's alpha instead (whatever the order).

    ``alpha``: expansion coefficient (1/K), one number or {group: alpha}; ``delta_T`` in K.
    """
    from . import shell
    from .beam import thermal_forces

    volumes = [volumes] if isinstance(volumes, str) else list(volumes)
    groups = {g: p for p in model.parts if p.kind != "beam" for g in p.tagged.volume_ids}
    beams = {nm: (p, k) for p in model.parts if p.kind == "beam" for k, nm in enumerate(p.tagged.names)}
    strains: dict = {}
    members: dict = {}          # beam part -> {group index: strain}
    for v in volumes:
        if v not in groups and v not in beams:
            raise InputError(f"thermal_load: volume {v!r} is not in model {model.name!r} "
                             f"(has: {', '.join(sorted(groups) + sorted(beams))})")
        a = alpha[v] if isinstance(alpha, dict) else alpha
        if not np.isfinite(a) or not np.isfinite(delta_T):
            raise InputError(f"thermal_load: alpha {a!r} or delta_T {delta_T!r} of {v!r} is not finite")
        eps = float(a) * float(delta_T)
        if v in groups:
            part = groups[v]
            strains.setdefault(part.kind, (part, {}))[1][part.tagged.volume_ids[v]] = eps
        for nm, (bp, k) in beams.items():
            if nm == v or (bp.fields[k].wall == v and nm not in volumes):   # a member named itself: its own alpha
                members.setdefault(id(bp), (bp, {}))[1][k] = eps
    if not strains and not members:
        raise InputError("thermal_load: no volume given")
    f = np.zeros(model.n_dof)
    for kind, (part, by_id) in strains.items():
        if kind == "solid":
            E, nu, _ = part.fields
            form = thermal_load_form(part.V, E, nu, part.tagged.cell_tags, by_id)
        else:
            form = shell.thermal_load_form(part.V, part.fields, part.tagged.cell_tags, by_id)
        f += pb.gather_vec(pb.mult_transpose(part.T, pb.assemble_vector(form)))
    for part, by_group in members.values():
        fb = part.T.createVecLeft()
        if fb.getLocalSize():          # rank 0 holds every beam DOF (fem.beam)
            fb.setArray(thermal_forces(part, by_group))
        f += pb.gather_vec(pb.mult_transpose(part.T, fb))
    return f


def mass_properties(model: FEModel, about=(0.0, 0.0, 0.0)) -> MassProperties:
    """Mass properties (liftoff.core.cg_mass) of M6 = RB^T M RB about ``about`` (m)."""
    _, M = model.matrices()
    about = np.asarray(about, float)
    RB = model.rigid_body_shape(about)
    return cg_mass(RB.T @ (M @ RB), about)
