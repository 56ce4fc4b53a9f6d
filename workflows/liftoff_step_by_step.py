"""The lift-off pipeline step by step through the Python API (what `liftoff run` does).

    python -m liftoff.workflows.liftoff_step_by_step [--stick] [--out DIR]

Each step names the section of Prabhakar & Palermo it implements and calls the functions
`liftoff run` calls (workflows/pipeline.py, workflows/loads.py). SI units throughout.
`--stick` uses the beam stick model (seconds); without it the gmsh + dolfinx solids (a few
minutes). No caching here: every stage is computed in front of you.
"""
from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np


def _scenario(stick: bool):
    """The embedded default scenario's first case; ``stick``: its [model] on beams (4 m elements)."""
    from liftoff.config import default_text, parse_scenario, parse_toml

    data = parse_toml(default_text(), "default_scenario.toml")
    if stick:
        m = data["model"]
        no_size = lambda t: {k: v for k, v in t.items() if k not in ("mesh_size", "params", "type", "mirror")}  # noqa: E731
        data["model"] = {"source": "stick", "mesh_size": 4.0, "zeta": m["zeta"], "system": m.get("system", {}),
                         "pad": no_size(m["pad"]), "component": {n: no_size(c) for n, c in m["component"].items()}}
    return parse_scenario(data, "default_scenario.toml").cases[0]


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--stick", action="store_true", help="beam stick model instead of FE solids")
    ap.add_argument("--out", type=Path, default=Path("out/step_by_step"))
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    if not args.stick:
        import pyvista  # noqa: F401  (before dolfinx, FENICSX-NOTES.md)
    from liftoff.reduction import assemble, craig_bampton, keep_modes, system_modes
    from liftoff.reduction.checks import with_own_inertia
    from liftoff.transient import Forcing, PointForce, TabulatedForce, estimate_step, solve
    from liftoff.transient.effects import center_of_gravity, cg_static_report
    from liftoff.workflows.loads import applied_forces, attitude_feedback, contacts, control_table
    from liftoff.workflows.loads import recoveries, softening
    from liftoff.workflows.pipeline import (StackModel, boundary_labels, boundary_points, build_component, cb_solver,
                                            vehicle_assembly)
    from liftoff.workflows.pipeline import cryo_loads

    # 1. The scenario: typed and checked (liftoff.config), builder parameters included.
    case = _scenario(args.stick)
    model = case.model
    t0 = time.perf_counter()

    # 2. Components: sparse K, M with labelled 6-DOF points (spiders), from FE or sticks;
    #    and the nodal load of a unit free thermal strain of each volume (for the cryo preload).
    comps, thermal = {}, {}
    with tempfile.TemporaryDirectory() as work:
        for name, cm in model.components.items():
            comps[name], thermal[name] = build_component(model, cm, Path(work))
    for name, c in comps.items():
        print(f"{name:10s} {c.n_dof:7d} DOFs, points: {', '.join(boundary_points(c))}")

    # 3. Craig-Bampton (section 3.0, eq. 13): every named point stays discrete. FE
    #    components use the PETSc/SLEPc solver (fem.petsc_solver), the stick model scipy's.
    cbs = {}
    solver = cb_solver(model)[0]
    for name, c in comps.items():
        cm = model.components[name]
        cbs[name] = craig_bampton(c, boundary_labels(c), cm.n_modes, cm.f_max, solver=solver,
                                  residual_vectors=cm.residual_vectors)
        cb = cbs[name]
        top = cb.fixed_freq_hz[cb.n_eigenmodes - 1] if cb.n_eigenmodes else 0.0
        print(f"{name:10s} CB: {cb.n_eigenmodes} fixed-interface modes up to {top:.1f} Hz"
              + (f" and {cb.n_residual} residual vectors" if cb.n_residual else ""))

    # 4. Vehicle: overlay the components on shared points, free-free system modes (eq. 4);
    #    pad: grounded, reduced to its posts. Modal bodies with gravity participation (eq. 14).
    #    Every system mode is kept (section 3.0) unless [model.system] cuts them; then residual
    #    vectors keep the static flexibility at the boundary DOFs exact (reduction/truncation.py).
    sysp = model.system
    vasm = vehicle_assembly(model, cbs)           # a joint's released DOFs kept apart
    vall = system_modes(vasm, n_rigid=6)
    vmodes = keep_modes(vall, sysp.f_max, sysp.n_modes, sysp.residual_vectors)
    _, cg = center_of_gravity(vmodes.to_body(name="vehicle"))
    vehicle = vmodes.to_body(ref_point=cg, zeta=model.zeta, name="vehicle")
    pasm = with_own_inertia(assemble([cbs["pad"]], "pad"), "pad", comps.get("pad"), cbs["pad"])   # (its gravity)
    pall = system_modes(pasm, n_rigid=0)
    pmodes = keep_modes(pall, sysp.pad_f_max, sysp.pad_n_modes, sysp.residual_vectors)
    pad = pmodes.to_body(zeta=model.zeta, name="pad")
    print(f"vehicle: {vehicle.n_modes} modes, {vehicle.mass / 1e3:.0f} t, c.g. {np.round(cg, 2)} m; "
          f"pad: {pad.n_modes} modes")
    unit = {n: {vol: cbs[n].boundary_load(f) for vol, f in thermal[n].items()} for n in comps}
    stack = StackModel(comps, cbs, vasm, vmodes, vehicle, pasm, pmodes, pad, unit, vall, pall)

    # 5. Hold-down posts: penalty contacts, bolted until release, then compression-only on
    #    their axial direction (2.7). The step from the contact model (eq. 12).
    posts = contacts(case, stack)
    f_h, h = estimate_step(vehicle, pad, posts, case.time.static_above_hz)
    print(f"step: f_h = {f_h:.1f} Hz, h = 0.25/f_h = {h * 1e3:.3f} ms (eq. 12)")

    # 6. Loads (section 4): cryo preload at boundary DOFs only (4.3), thrust tables and forces,
    #    control-system gimbal forces (4.4, eq. 15-21) and the attitude hold after release
    #    (beyond the reference), gravity softening (4.5, eq. 22-27).
    cryo = [PointForce("a", lab, v) for lab, v in cryo_loads(stack, case.cryo).items()]
    constant, tables = applied_forces(case, stack)
    constant = cryo + constant
    grid, FSL, gimbals = control_table(case, stack, tables, constant)
    tables += [TabulatedForce("a", lab, grid, FSL[:, j]) for j, lab in enumerate(gimbals)]
    soft = softening(case, stack)
    hold = attitude_feedback(case, stack)
    forcing = Forcing(constant=constant, tables=tables, feedback=[soft, hold], gravity=case.gravity)

    # 7. Table 1: c.g. motion under static loads (section 4.5).
    print(cg_static_report(vehicle, pad, posts, Forcing(gravity=case.gravity), cryo, soft).table())

    # 8. The two-body transient from the static initial state (2.6), with recovery of the
    #    interface forces at the attach points and the c.g. motion (eq. 23).
    recs, attach, outputs = recoveries(case, stack)
    problem = case.time.problem(vehicle, pad, posts, forcing, initial="static", outputs=outputs, recoveries=recs)
    result = solve(problem)
    path = result.save(args.out / "results.h5")
    for c in result.contact_summary():
        sep = "never" if c["separation_time"] is None else f"{c['separation_time']:.4f} s"
        print(f"post {c['name']:8s} separates at {sep}, {c['recontacts']} recontacts, "
              f"peak compression {c['peak_compression'] / 1e6:.2f} MN")
    att = result.recovered["attach_att_srb_left_fwd"]
    i = int(np.argmax(np.abs(att[:, 2])))
    print(f"left forward attach: peak |Fz| {abs(att[i, 2]) / 1e6:.2f} MN at t = {result.time[i]:.3f} s")
    print(f"results: {path}  ({time.perf_counter() - t0:.1f} s)")


if __name__ == "__main__":
    main()
