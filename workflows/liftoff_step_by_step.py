"""The lift-off pipeline step by step through the Python API (what `liftoff run` does).

    python -m liftoff.workflows.liftoff_step_by_step [--stick] [--out DIR]

Each step names the section of Prabhakar & Palermo it implements. SI units throughout.
`--stick` uses the beam stick model (seconds); without it the gmsh + dolfinx solids
(a few minutes). No caching here: every stage is computed in front of you.
"""
from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--stick", action="store_true", help="beam stick model instead of FE solids")
    ap.add_argument("--out", type=Path, default=Path("out/step_by_step"))
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    import pyvista  # noqa: F401  (before dolfinx, FENICSX-NOTES.md)
    from liftoff.reduction import assemble, craig_bampton, interface_force_recovery, system_modes
    from liftoff.transient import (
        ContactPoint,
        Forcing,
        ModalFeedback,
        PointForce,
        Recovery,
        TabulatedForce,
        TransientProblem,
        estimate_step,
        solve,
    )
    from liftoff.transient.effects import (
        center_of_gravity,
        cg_motion_matrix,
        cg_static_report,
        control_forces,
        cryo_point_loads,
        softening_matrix,
    )
    from liftoff.workflows.pipeline import boundary_points
    from liftoff.workflows.scenario import load_scenario

    # 1. The scenario: the embedded default (workflows/default_scenario.toml), first case.
    case = load_scenario(None).cases[0]
    t0 = time.perf_counter()

    # 2. Components: sparse K, M with labelled 6-DOF points (spiders), from FE or sticks.
    if args.stick:
        from liftoff.workflows.stick import stack_components, stack_thermal

        comps, thermal = stack_components(element_length=4.0), stack_thermal(element_length=4.0)
    else:
        from liftoff.workflows.fe_source import build_component

        comps, thermal = {}, {}
        with tempfile.TemporaryDirectory() as work:
            for name in ("core", "srb_left", "srb_right", "orbiter", "pad"):
                sel = case.model["component"].get(name, {}) if name != "pad" else case.model["pad"]
                comps[name], thermal[name] = build_component(
                    {"name": name, "mesh_size": sel.get("mesh_size"), "degree": 1, "stack": {}, "params": {},
                     "materials": {}}, Path(work))
    for name, c in comps.items():
        print(f"{name:10s} {c.n_dof:7d} DOFs, points: {', '.join(boundary_points(c))}")

    # 3. Craig-Bampton (section 3.0, eq. 13): every named point stays discrete.
    cbs = {}
    for name, c in comps.items():
        labels = [f"{p}:{d}" for p in boundary_points(c) for d in ("Tx", "Ty", "Tz", "Rx", "Ry", "Rz")]
        cbs[name] = craig_bampton(c, labels, n_modes=20, f_max=60.0)
        print(f"{name:10s} CB: {cbs[name].n_modes} fixed-interface modes up to {cbs[name].fixed_freq_hz[-1]:.1f} Hz")

    # 4. Vehicle: overlay the components on shared points, free-free system modes (eq. 4);
    #    pad: grounded, reduced to its posts. Modal bodies with gravity participation (eq. 14).
    vasm = assemble([cbs[n] for n in ("core", "srb_left", "srb_right", "orbiter")], "vehicle")
    vmodes = system_modes(vasm, n_rigid=6, f_max=60.0)
    _, cg = center_of_gravity(vmodes.to_body(name="vehicle"))
    vehicle = vmodes.to_body(ref_point=cg, zeta=0.01, name="vehicle")
    pasm = assemble([cbs["pad"]], "pad")
    pad = system_modes(pasm, n_rigid=0, f_max=100.0).to_body(zeta=0.01, name="pad")
    print(f"vehicle: {vehicle.n_modes} modes, {vehicle.mass / 1e3:.0f} t, c.g. {np.round(cg, 2)} m; "
          f"pad: {pad.n_modes} modes")

    # 5. Hold-down posts: penalty contacts, bolted until release, then compression-only (2.7).
    contacts = [ContactPoint(p.name, [f"{p.vehicle}:{d}" for d in ("Tx", "Ty", "Tz")],
                             [f"{p.pad}:{d}" for d in ("Tx", "Ty", "Tz")], p.stiffness, axial=2,
                             release_time=p.release_time) for p in case.posts]
    f_h, h = estimate_step(vehicle, pad, contacts)
    print(f"step: f_h = {f_h:.1f} Hz, h = 0.25/f_h = {h * 1e3:.3f} ms (eq. 12)")

    # 6. Loads (section 4): cryo preload at boundary DOFs only (4.3), thrust tables,
    #    control-system gimbal forces (4.4, eq. 15-21), gravity softening (4.5, eq. 22-27).
    cryo = cryo_point_loads([(cbs["core"].boundary_labels,
                              case.cryo["alpha"] * case.cryo["delta_T"] * cbs["core"].boundary_load(thermal["core"]["core_wall"]))])
    constant = [PointForce("a", lab, v) for lab, v in cryo.items()]
    tables = []
    for e in case.engines:
        t, v = e.table()
        tables += [TabulatedForce("a", f"{e.mount}:{d}", t, c * v) for d, c in zip(("Tx", "Ty", "Tz"), e.direction)
                   if c != 0.0]
    grid = np.unique(np.concatenate([tb.time for tb in tables] + [[case.time["t0"], case.time["t_end"]]]))
    labels = sorted({tb.label for tb in tables})
    P = np.zeros((grid.size, len(labels)))
    for tb in tables:
        P[:, labels.index(tb.label)] += np.interp(grid, tb.time, tb.value)
    gimbals = case.control["gimbals"]
    on = np.clip((grid - case.control["start"]) / max(case.control["ramp"], 1e-6), 0.0, 1.0)
    FSL = control_forces(vehicle, gimbals, labels, P) * on[:, None]
    tables += [TabulatedForce("a", lab, grid, FSL[:, j]) for j, lab in enumerate(gimbals)]
    soft = ModalFeedback("a", softening_matrix(vehicle, case.gravity), until=case.softening["until"])
    forcing = Forcing(constant=constant, tables=tables, feedback=[soft], gravity=case.gravity)

    # 7. Table 1: c.g. motion under static loads (section 4.5).
    print(cg_static_report(vehicle, pad, contacts, Forcing(gravity=case.gravity), constant, soft).table())

    # 8. The two-body transient from the static initial state (2.6), with recovery of the
    #    booster-to-core forward attach load and the c.g. motion (eq. 23).
    D, A = interface_force_recovery(vasm, vmodes, "srb_left", [f"att_srb_left_fwd:{d}" for d in ("Tx", "Ty", "Tz")])
    recs = [Recovery("attach_left_fwd", "a", ["Tx", "Ty", "Tz"], disp=D, acc=A),
            Recovery("cg_motion", "a", ["Tx", "Ty", "Tz", "Rx", "Ry", "Rz"], disp=cg_motion_matrix(vehicle))]
    problem = TransientProblem(vehicle, pad, contacts, forcing, t_end=case.time["t_end"], h=None,
                               initial="static", outputs={"a": ["stack_top:Tx", "stack_top:Ty"]},
                               recoveries=recs)
    result = solve(problem)
    path = result.save(args.out / "results.h5")
    for c in result.contact_summary():
        print(f"post {c['name']:8s} separates at {c['separation_time']:.4f} s, {c['recontacts']} recontacts, "
              f"peak compression {c['peak_compression'] / 1e6:.2f} MN")
    att = result.recovered["attach_left_fwd"]
    i = int(np.argmax(np.abs(att[:, 2])))
    print(f"left forward attach: peak |Fz| {abs(att[i, 2]) / 1e6:.2f} MN at t = {result.time[i]:.3f} s")
    print(f"results: {path}  ({time.perf_counter() - t0:.1f} s)")


if __name__ == "__main__":
    main()
