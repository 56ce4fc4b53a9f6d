"""Reports of a lift-off run that need its model: the modal deliverables (mode shapes, OP4
recovery matrices, modal tables), the files made from several cases (interface and
correlated loads, workbook), deformed-shape snapshots of stack and pad, spectra files and
the printed summary. The histories as items, the max/min tables and the plots are
analysis/'s (histories.py, tables.py, plots.py), re-exported here. SI units.

Sign conventions: post forces are the forces the pad applies to the vehicle at the
hold-down points (Tz > 0: compression); attach forces are the forces the rest of the
vehicle applies to the named component at the attach point (reduction.recovery).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
from liftoff.transient.effects import center_of_gravity

# the histories, tables and plots live in analysis/ (issue 24); the run's callers find them here too
from liftoff.analysis.histories import (CG_ACCELERATION, EDGE_PERIODS, _translations, edge_extremes,  # noqa: F401
                                        interface_histories, items, liquid_heads, load_factor_items, twang)
from liftoff.analysis.plots import _plot_correlated, plot_contours, plot_spectra, plots  # noqa: F401
from liftoff.analysis.tables import (Item, display_points, envelope, format_changes, format_table,  # noqa: F401
                                     is_force, maxmin, write_csv)
from liftoff.core.errors import InputError
from liftoff.core.labels import TRANSLATIONS
from liftoff.core.records import write_text


def case_maxmin(result, cp, case: str, band_hz: float) -> list[dict]:
    """The max/min rows of one case's result (the items of its case problem ``cp``: attach
    points and the liquids' heads; acceleration-type histories filtered to ``band_hz``)."""
    return maxmin(result.time, items(result, cp.attach, liquid_heads(cp), band_hz), case)


def write_interface_loads(results: dict, out: Path, name: str, note: str = "", consistent=None) -> list[Path]:
    """``interface_loads_<name>.csv``: the time-consistent interface loads (analysis/
    interface_loads.py) of one case (``results`` {case: (result, case problem)} with one
    entry) or, over several, their envelope; nothing when the model has no attach points.
    ``consistent``: (rows, cases) of an envelope already made (a campaign's over every case,
    from their summaries: analysis.aggregate.Aggregate.consistent), written instead. The
    file's second comment line names the cases it covers (and ``note``)."""
    from liftoff.analysis import interface_loads as il

    if consistent is not None:
        rows, cases = consistent
    else:
        per_case = [il.time_consistent(res.time, interface_histories(res, cp.attach), case)
                    for case, (res, cp) in results.items()]
        rows = il.envelope(per_case) if len(per_case) > 1 else (per_case[0] if per_case else [])
        cases = ", ".join(results)
    cover = f"cases: {cases}" + (f"; {note}" if note else "")
    return [il.write_csv(rows, out / f"interface_loads_{name}.csv", cover)] if rows else []


MODE_SHAPES = "liftoff-mode-shapes"


def write_mode_shapes(stack, path: Path) -> Path:
    """``modes_vehicle.h5``: the vehicle's system modes (Hz) and their shapes at the
    translations of its named points (the assembly's boundary DOFs: posts, attach points,
    engine mounts, output stations), m per unit modal coordinate (unit modal mass): what a
    later run pairs its modes with by MAC (``--compare``, analysis/modes_compare.py)."""
    from liftoff.core.records import Dataset, write_record
    from liftoff.reduction import label_transform

    asm, vm = stack.vehicle_asm, stack.vehicle_modes
    labels = [lab for lab in asm.boundary_labels if lab.rpartition(":")[2] in TRANSLATIONS]
    shapes = label_transform(asm, labels) @ vm.phi
    data = {"mode": Dataset(np.arange(1, vm.n_modes + 1), "1"), "dof": np.array(labels, dtype=str),
            "freq": Dataset(vm.freq_hz, "Hz", dims=("mode",)),
            "shape": Dataset(shapes, "m per unit modal coordinate (unit modal mass)", dims=("dof", "mode"))}
    return write_record(path, MODE_SHAPES, 1, data, units="SI", attrs={"n_rigid": int(vm.n_rigid)})


def read_mode_shapes(path: Path) -> tuple[np.ndarray, list[str], np.ndarray]:
    """(freq Hz, DOF labels, shapes) of a ``modes_vehicle.h5``."""
    from liftoff.core.records import read_record

    rec = read_record(path, MODE_SHAPES, (1,))
    d = rec.data
    return np.asarray(d["freq"], float), [str(x) for x in d["dof"]], np.asarray(d["shape"], float)


def compare_modes(new: Path, old: Path, out: Path) -> tuple[Path, list]:
    """compare_modes.csv: each elastic vehicle mode of this run (``new``, a modes_vehicle.h5)
    paired by MAC with one of an earlier run's (``old``) at the DOFs both have
    (analysis/modes_compare.py), with the frequency change."""
    from liftoff.analysis.modes_compare import MAC_PAIRED, pair_modes

    f_new, dof_new, s_new = read_mode_shapes(new)
    f_old, dof_old, s_old = read_mode_shapes(old)
    common = [d for d in dof_new if d in set(dof_old)]
    if not common:
        raise InputError(f"{old}: no DOF in common with this run's modes; cannot pair them")
    i_new = [dof_new.index(d) for d in common]
    i_old = [dof_old.index(d) for d in common]
    pairs = pair_modes(f_new, s_new[i_new], f_old, s_old[i_old])
    head = (f"# liftoff modes of this run paired by MAC with an earlier run's ({old}), at the {len(common)} "
            f"translation DOFs both have; mode numbers 1-based; MAC below {MAC_PAIRED}: unmatched (empty old "
            "mode); change = (f - f_old) / f_old x 100 %\n")
    lines = ["mode,f_hz,old_mode,f_old_hz,mac,change_pct"]
    for p in pairs:
        lines.append(f"{p.new + 1},{p.f_new:.6e}," + (f"{p.old + 1},{p.f_old:.6e}" if p.old is not None else ",")
                     + f",{p.mac:.6f}," + ("" if p.old is None else f"{p.change_pct:.6e}"))
    return write_text(out / "compare_modes.csv", head + "\n".join(lines) + "\n"), pairs


def earlier_modes(compare) -> Path:
    """The modes_vehicle.h5 beside a ``--compare`` table (or in a ``--compare`` folder)."""
    p = Path(compare)
    return (p if p.is_dir() else p.parent) / "modes_vehicle.h5"


def format_mode_changes(pairs: list, limit: int = 10) -> str:
    """The vehicle modes that moved most against the earlier run, and the unmatched ones."""
    matched = [p for p in pairs if p.old is not None]
    lost = [p for p in pairs if p.old is None]
    lines = [f"Vehicle modes against the earlier run (compare_modes.csv): {len(matched)} of {len(pairs)} elastic modes "
             f"paired by MAC, {len(lost)} unmatched; largest frequency changes:"]
    for p in sorted(matched, key=lambda p: -abs(p.change_pct))[:limit]:
        lines.append(f"  mode {p.new + 1:5d} {p.f_new:9.3f} Hz <- old {p.old + 1:5d} {p.f_old:9.3f} Hz "
                     f"{p.change_pct:+8.3f} %  MAC {p.mac:.3f}")
    return "\n".join(lines)


def recovery_op4_inputs(stack, cp) -> dict:
    """What :func:`write_recovery_op4`'s files depend on besides the stack model (its cache
    key, workflows/outputs.py): a SHA-256 of the vehicle's recoveries (names, labels, units
    and matrices) and the versions of pyyeti (its OP4 writer) and pandas (which
    pyyeti.nastran imports): without either the OP4 is not written, and installing it
    changes the key."""
    from importlib import metadata

    from .cache import content_sha256

    digest = content_sha256(x for r in cp.problem.recoveries if r.body == "a"
                            for x in (repr((r.name, r.category, list(r.labels), list(r.units))),
                                      r.disp, r.vel, r.acc, r.const))
    versions = {}
    for dist in ("pyyeti", "pandas"):
        try:
            versions[dist] = metadata.version(dist)
        except metadata.PackageNotFoundError:
            versions[dist] = "absent"
    return {"recoveries": digest, **versions}


def write_recovery_op4(stack, cp, out: Path) -> list[Path]:
    """``recovery_vehicle.op4`` and its index ``recovery_vehicle_op4.csv``: the vehicle's
    recovery matrices in its system modal coordinates (y = D q + V qdot + A qddot + C: DTM,
    the velocity matrix, ATM, and a constant column; interface forces are LTMs in D and A,
    less the component's own weight share in C), with the modal model they act
    on (FREQ, Hz; ZETA; unit modal masses) for another team's tools (Nastran OUTPUT4, binary,
    double; pyyeti.nastran.op4 reads it). Needs pyyeti (the ``nastran`` extra): without it
    nothing is written and the summary says so."""
    from liftoff.reduction import write_op4

    body = stack.vehicle
    mats = {"FREQ": stack.vehicle_modes.freq_hz[:, None], "ZETA": np.asarray(body.zeta, float)[:, None]}
    index = ["# liftoff recovery matrices of the vehicle in recovery_vehicle.op4 (binary OUTPUT4, double); "
             "y = D q + V qdot + A qddot + C over the vehicle's system modes (unit modal mass; FREQ Hz, ZETA; "
             "C a constant column, where an item has one); "
             "row_labels, row_units: one per row, ';'-separated; SI", "matrix,item,kind,rows,category,row_labels,row_units"]
    k = 0
    for r in cp.problem.recoveries:
        if r.body != "a":
            continue
        k += 1
        const = None if r.const is None else r.const[:, None]
        for kind, m in (("D", r.disp), ("V", r.vel), ("A", r.acc), ("C", const)):
            if m is None:
                continue
            name = f"R{k:04d}{kind}"
            mats[name] = m
            index.append(f"{name},{r.name},{ {'D': 'disp', 'V': 'vel', 'A': 'acc', 'C': 'const'}[kind]},{m.shape[0]},"
                         f"{r.category},"
                         f"{';'.join(r.labels)},{';'.join(r.units)}")
    try:
        files = [write_op4(out / "recovery_vehicle.op4", mats)]
    except ImportError:
        files = []
        index.insert(1, "# recovery_vehicle.op4 NOT written: pyyeti is not installed (pip install 'liftoff-loads[nastran]')")
    return files + [write_text(out / "recovery_vehicle_op4.csv", "\n".join(index) + "\n")]


def write_cb_checks(stack, cp, out: Path) -> list[Path]:
    """``cb_checks.txt`` and ``cb_checks.json``: reduction.cb_check of every component's
    Craig-Bampton model (symmetry, definiteness, rigid-body residual about its first boundary
    point, mass properties, fixed-interface effective masses, free-free frequencies of the CB
    model; SI units), the checks a Nastran user runs on a delivered CB model (pyyeti's
    cbcheck). The FE comparison is not run here (a free-free eigensolve of each FE model:
    ``cb_check(cb, component)`` from Python)."""
    import json

    from liftoff.reduction import cb_check

    checks, skipped = [], []
    for name, cb in stack.cbs.items():
        if cb.n_boundary == 0:           # rigid ground (type = "rigid_ground"): nothing moves, nothing to check
            skipped.append(f"Craig-Bampton check: {name}: no boundary DOFs ({cb.n_modes} modes), not checked")
            continue
        own = None
        if name not in {c.name for c in stack.vehicle_asm.components} and stack.pad_asm.rigid_mass is not None:
            from liftoff.reduction.system import rigid_inertia      # the grounded pad: its own mass

            own = rigid_inertia(stack.pad_asm, cb.point_coord(cb.boundary_points[0]))[1]
        checks.append(cb_check(cb, own_mass=own))
    text = "\n\n".join([c.text for c in checks] + skipped)
    return [write_text(out / "cb_checks.txt", text + "\n"),
            write_text(out / "cb_checks.json", json.dumps({"units": "SI (kg, m, kg m^2, Hz)",
                                                           "components": [c.summary for c in checks]},
                                                          indent=1, default=float) + "\n")]


def modal_tables_inputs(stack, cp) -> dict:
    """What :func:`write_modal_tables`'s files depend on besides the stack's key (their cache
    key, workflows/outputs.py): the vehicle's contact DOFs (the held condition) and a SHA-256 of
    both bodies' system modes (a system stage rebuilt under the same key may flip a sign)."""
    from .cache import content_sha256

    pm = None if stack.pad.is_ground else stack.pad_modes
    return {"contact": [lab for c in cp.problem.contacts for lab in c.labels_a],
            "modes": content_sha256((stack.vehicle_modes.omega, stack.vehicle_modes.phi)
                                    + (() if pm is None else (pm.omega, pm.phi)))}


def write_modal_tables(stack, cp, out: Path) -> list[Path]:
    """The modal deliverables of the stack (reduction/modal_mass.py): ``modes_vehicle.csv``
    (the vehicle's free-free system modes the transient uses: rigid, elastic, residual
    vectors), ``modal_mass_vehicle_held.csv`` (the vehicle held at its contact DOFs: modes
    and effective mass under the posts' rigid translation) and ``modal_mass_pad.csv`` (the
    grounded pad's modes and their effective mass; none for rigid ground)."""
    from liftoff.analysis.aggregate import write_rows_csv
    from liftoff.reduction.modal_mass import modal_mass_table

    vm = stack.vehicle_modes
    kind = ["rigid"] * vm.n_rigid + ["elastic"] * (vm.n_modes - vm.n_rigid - vm.n_residual) + \
        ["residual vector"] * vm.n_residual
    lines = ["# liftoff vehicle system modes (free-free; the modes the transient keeps): frequency in Hz; kind: "
             "rigid, elastic or residual vector (its Rayleigh frequency)", "mode,f_hz,kind"]
    lines += [f"{k + 1},{f:.6e},{kd}" for k, (f, kd) in enumerate(zip(vm.freq_hz, kind))]
    files = [write_text(out / "modes_vehicle.csv", "\n".join(lines) + "\n")]
    files.append(write_mode_shapes(stack, out / "modes_vehicle.h5"))
    contact_a = [lab for c in cp.problem.contacts for lab in c.labels_a]
    tables = [(modal_mass_table(vm, contact_a, "vehicle"), "modal_mass_vehicle_held.csv")]
    if not stack.pad.is_ground:          # rigid ground (type = "rigid_ground") has no modes to tabulate
        tables.append((modal_mass_table(stack.pad_modes, [], "pad"), "modal_mass_pad.csv"))
    for table, name in tables:
        head = (f"# liftoff modal effective mass, {table.body} {table.condition} (reduction/modal_mass.py): per mode "
                "the frequency (Hz) and the effective mass (kg) under a rigid translation x, y, z of the supports, "
                "its percent and cumulative percent of the total; total mass (kg) x/y/z "
                + "/".join(f"{m:.6e}" for m in table.total_mass) + ", on the supports (no mode carries it) "
                + "/".join(f"{m:.6e}" for m in table.on_supports) + "\n")
        rows = table.rows()
        files.append(write_rows_csv(rows, list(rows[0]), head, out / name) if rows else write_text(out / name, head))
    return files


#: correlated_loads.csv's hulls simplified to this fraction of each axis's range
#: (analysis.correlated.simplify): a thousandth, ten times below the 1 % to which the
#: default's loads are converged (README, "Convergence"), so it changes no design margin
CORRELATED_TOLERANCE = 1e-3


def write_correlated(results: dict, out: Path, plots: bool = True, note: str = "", beside=None) -> list[Path]:
    """``correlated_loads.csv`` (and ``correlated_loads.png``): per attach point the correlated
    envelopes of axial force with bending moment and of shear with torque over the cases in
    ``results`` (analysis/correlated.py: the convex hull of the pair's samples over time and
    cases, each vertex a sample with its time and case); nothing without attach points.
    ``beside`` (workflows/beside.py): draws the picture beside the run."""
    from liftoff.analysis import correlated as cl
    from liftoff.analysis.aggregate import write_rows_csv

    per_case = {case: (res.time, interface_histories(res, cp.attach)) for case, (res, cp) in results.items()}
    full = cl.envelope(cl.correlated(t, itfs, case) for case, (t, itfs) in per_case.items())
    if not full:
        return []
    hulls = [cl.simplify(h, CORRELATED_TOLERANCE) for h in full]
    rows = cl.rows(hulls)
    worst = max(h.shortfall for h in hulls)
    head = ("# liftoff correlated loads: per attach point (force on the named component) the convex hull of "
            "(Tz, Mb = |(Rx, Ry)|) and of (V = |(Tx, Ty)|, Rz) over time and the cases " + ", ".join(results)
            + (f" ({note})" if note else "") + "; vertices counter-clockwise, each a sample (time s, case); "
            f"units in x_unit, y_unit; simplified from {sum(h.x.size for h in full)} to {len(rows)} vertices, every "
            f"dropped vertex within {CORRELATED_TOLERANCE:g} of its axis's range outside the polygon (at most "
            f"{worst:.2g})\n")
    files = [write_rows_csv(rows, list(rows[0]), head, out / "correlated_loads.csv")]
    if plots and beside is not None:
        beside.submit("correlated_loads.png", lambda: [_plot_correlated(hulls, per_case, out)])
    elif plots:
        files.append(_plot_correlated(hulls, per_case, out))
    return files


#: (sheet, CSV file) of the run's tables the workbook holds, in order (those present)
WORKBOOK_TABLES = (("time-consistent loads", "interface_loads_envelope.csv"), ("correlated loads", "correlated_loads.csv"),
                   ("design loads", "design_loads.csv"),
                   ("comparison", "compare.csv"), ("statistics", "statistics.csv"), ("SRS", "srs.csv"),
                   ("table 1", "table1.csv"), ("system modes", "modes_vehicle.csv"),
                   ("modal mass vehicle held", "modal_mass_vehicle_held.csv"), ("modal mass pad", "modal_mass_pad.csv"))


def write_workbook(out: Path, title: str, units: str = "SI") -> list[Path]:
    """``loads.xlsx`` (analysis/workbook.py): the max/min envelope by category and the run's
    other tables, made from the CSV files in ``out`` (the same numbers, cell for cell, in SI;
    or in the report unit system ``units``, analysis.units)."""
    from liftoff.analysis import workbook

    if not (out / "maxmin_envelope.csv").is_file():
        return []
    tables = [(name, out / f) for name, f in WORKBOOK_TABLES if (out / f).is_file()]
    return [workbook.write_workbook(workbook.from_csv(tables, out / "maxmin_envelope.csv", title, units),
                                    out / "loads.xlsx")]


# ------------------------------------------------------------------ hydroelastic tanks


def bulge_modes(cbs: dict, threshold: float = 0.25) -> list[dict]:
    """Each hydroelastic tank's first bulge mode from its component's CB model: the lowest
    fixed-interface mode whose ullage volume change (per unit modal coordinate) is at least
    ``threshold`` of the largest among the kept modes; its frequency (Hz), that volume
    change (m^3), and the axial effective mass of the liquid in it, (Phi_j^T M_a,c r)^2 (kg,
    r the unit axial translation; modes normalised with M + M_a), beside the liquid's mass."""
    rows = []
    for name, cb in cbs.items():
        rec = {it.name: it for it in getattr(cb, "recovery", ())}
        if "ullage_volume" not in rec or "liquid_axial_inertia" not in rec or not cb.n_modes:
            continue
        nq = cb.n_modes
        dv, f = rec["ullage_volume"].disp[:, :nq], rec["liquid_axial_inertia"].acc
        x = np.concatenate([np.zeros(nq), [1.0 if lab.endswith(":Tz") else 0.0 for lab in cb.boundary_labels]])
        labels = list(rec["liquid_axial_inertia"].labels)
        for k, tank in enumerate(rec["ullage_volume"].labels):
            if not np.abs(dv[k]).max() > 0 or tank not in labels:
                continue
            j = int(np.flatnonzero(np.abs(dv[k]) >= threshold * np.abs(dv[k]).max())[0])
            c = labels.index(tank)
            rows.append({"component": name, "tank": tank, "mode": j + 1, "hz": float(cb.fixed_freq_hz[j]),
                         "dv_m3": float(dv[k, j]), "m_eff_kg": float(f[c, j] ** 2),
                         "m_liquid_kg": float(f[c] @ x)})
    return rows


def slosh_summary(cbs: dict, rows_env: list, components: dict | None = None) -> list[dict]:
    """Each liquid's slosh pendulums (``convective = "slosh"``) from its component's CB model:
    the lowest fixed-interface mode in which the liquid's pendulums carry a quarter of their
    largest force per unit modal coordinate (the first slosh mode), the peak force of its
    pendulums and the largest crest of one of its modes over the cases (``rows_env``: the
    envelope rows); with ``components`` (reduction.Component by name), the g_eff (m/s^2) of
    the liquid's slosh modes."""
    out = []
    for name, cb in cbs.items():
        rec = {it.name: it for it in getattr(cb, "recovery", ())}
        it = rec.get("slosh_force")
        if it is None or not cb.n_modes:
            continue
        F = np.abs(it.disp[:, :cb.n_modes])
        for liquid in dict.fromkeys(lab.rpartition(":")[0] for lab in it.labels):
            on = np.array([lab.rpartition(":")[0] == liquid for lab in it.labels])
            per_mode = F[on].max(axis=0)
            j = int(np.flatnonzero(per_mode >= 0.25 * per_mode.max())[0])
            peak = [r for r in rows_env if r["item"].startswith(f"{name}_slosh_force {liquid}:")]
            big = max(peak, key=lambda r: max(abs(r["max"]), abs(r["min"])), default=None)
            waves = [max(abs(r["max"]), abs(r["min"])) for r in rows_env
                     if r["item"].startswith(f"{name}_slosh_wave_height {liquid}:")]
            out.append({"component": name, "liquid": liquid, "mode": j + 1, "hz": float(cb.fixed_freq_hz[j]),
                        "peak_n": None if big is None else max(abs(big["max"]), abs(big["min"])),
                        "peak_item": None if big is None else big["item"],
                        "peak_wave_m": max(waves) if waves else None})
            sd = getattr((components or {}).get(name), "slosh", None)
            if sd is not None and liquid in sd.liquid:
                out[-1]["g_eff"] = float(sd.gravity[sd.liquid.index(liquid)])
    return out


def with_errors(rows: list[dict], rows_half: list[dict] | None) -> list[dict]:
    """The max/min ``rows`` of a run at step h with ``max_err`` and ``min_err``: the estimated
    error (value - reported, signed) of each extreme from the same rows of the run at h/2
    (transient/accuracy.py: 4/3 (y_h/2 - y_h), Richardson, an estimate, not a bound); NaN
    without ``rows_half``."""
    from liftoff.transient.accuracy import error_estimate

    half = {r["item"]: r for r in rows_half or []}
    for r in rows:
        o = half.get(r["item"])
        r["max_err"] = error_estimate(r["max"], o["max"]) if o else float("nan")
        r["min_err"] = error_estimate(r["min"], o["min"]) if o else float("nan")
    return rows


# ------------------------------------------------------------------ twang


# ------------------------------------------------------------------ plots


# ------------------------------------------------------------------ snapshots
def snapshot_times(result, cp) -> dict[str, int]:
    """Step indices: maximum twang (largest top lateral deflection relative to the c.g.
    before release), release, and the peak of the largest post or attach load change
    (from its static preload at t0)."""
    t = result.time
    rel = [p.release_time for p in cp.case.posts if np.isfinite(p.release_time)]
    t_rel = min(rel) if rel else t[-1]
    i_rel = int(np.searchsorted(t, t_rel))
    i_rel = min(i_rel, t.size - 1)
    out = {"release": i_rel}
    tw = twang(result, cp)
    if tw is not None:
        out["max_twang"] = int(np.argmax(np.hypot(*tw.rel_cg[: max(i_rel, 1)].T)))
    # the largest load event: the biggest change of a post axial force or of an attach force
    # magnitude from its static preload at t0 (the preloads themselves peak at t0)
    best, idx = -1.0, 0
    for j, d in enumerate(result.contact_directions):
        if d.axial:
            v = np.abs(result.contact_force[:, j] - result.contact_force[0, j])
            if v.max() > best:
                best, idx = float(v.max()), int(np.argmax(v))
    for it in result.items("interface_force"):
        F = result.recovered[it.name][:, _translations(it)]
        v = np.linalg.norm(F - F[0], axis=1)
        if v.max() > best:
            best, idx = float(v.max()), int(np.argmax(v))
    out["peak_load"] = idx
    return out


def deformed_fields_at(stack, result, steps) -> list[list]:
    """Per step of ``steps``, the fem.snapshot.Parts of each component (its cells by their
    corners, fem.snapshot.picture_mesh; its beams as lines), the elastic part of the vehicle
    only (its rigid-body motion removed, so the picture stays on the pad); the fields of all
    steps in one product per component (its modes read once, not once per step, and only
    their rows of the corner nodes)."""
    from liftoff.fem.snapshot import Part, picture_mesh
    from liftoff.reduction import field_displacement

    if "q_a" not in result.modal:
        raise ValueError("deformed_fields_at needs the modal displacements: solve with keep_modal = 'q'")
    steps = list(steps)
    qa = np.array([result.modal["q_a"][i] for i in steps]).T          # (n_modes, k)
    qa[: np.sum(stack.vehicle.omega == 0)] = 0.0                        # elastic deformation only
    qb = (np.array([result.modal["q_b"][i] for i in steps]).T if "q_b" in result.modal
          else np.zeros((0, len(steps))))
    out = [[] for _ in steps]
    for name, comp in stack.components.items():
        if comp.field_map is None or comp.nodes is None:
            continue
        nodes, blocks = picture_mesh(comp)
        if name == "pad":
            u = field_displacement(stack.pad_asm, stack.pad_modes, name, comp, qb, nodes)
        else:
            u = field_displacement(stack.vehicle_asm, stack.vehicle_modes, name, comp, qa, nodes)
        xyz = comp.nodes[nodes]                     # one copy of the drawn nodes, shared by every part
        for k in range(len(steps)):
            uk = u[:, k].reshape(-1, 3)
            out[k] += [Part(xyz, cells, kind, uk) for kind, cells in blocks]
    return out


TITLES = {"max_twang": "maximum twang", "release": "hold-down release",
          "peak_load": "peak post/attach load change"}


def snapshots(stack, result, cp, out: Path, case: str) -> list[Path]:
    """snapshot_<what>_<case>.png at the steps of :func:`snapshot_times`, from one scene
    (fem.snapshot.snapshot_pngs)."""
    from liftoff.fem.snapshot import snapshot_pngs

    times = snapshot_times(result, cp)
    shots = [(out / f"snapshot_{what}_{case}.png", parts, f"{case}: {TITLES.get(what, what)} at t = {result.time[i]:.3f} s")
             for (what, i), parts in zip(times.items(), deformed_fields_at(stack, result, times.values()))]
    if not shots or not shots[0][1]:
        return []
    # looking along -x: the orbiter (+y) and the twang plane in view
    return snapshot_pngs(shots, fraction=0.03, note="elastic part", window_size=(900, 1100), view="yz", azimuth=35,
                         elevation=12)


# ------------------------------------------------------------------ summary
#: the share of a mode at the lowest component cut that the acceleration band may pass
BAND_LEAK_WARNING = 0.01


def band_lines(band: float, cbs: dict, f_max: dict | None = None) -> list[str]:
    """The acceleration band of the max/min tables and what its filter passes at the lowest
    frequency a component's reduction cuts at: its highest kept fixed-interface mode, or its
    ``f_max[name]`` Hz when it was selected by band alone; a component that keeps all its
    interior modes cuts nothing. The modes above a cut are left out, so whatever the band
    passes there is not converged; a warning above BAND_LEAK_WARNING. ``cbs``: the vehicle's
    CB models (n_modes, n_eigenmodes, fixed_freq_hz, n_dof, boundary_labels)."""
    from liftoff.analysis.spectra import lowpass_gain

    head = "  accelerations and liquid pressures in the max/min tables: "
    tail = " ([postprocess] acceleration_band_hz; SRS and PSD unfiltered)"
    f_max = f_max or {}
    # (the highest kept eigenmode: residual vectors, above it, are not the modes the cut keeps)
    cuts = {name: max(float(cb.fixed_freq_hz[:cb.n_eigenmodes].max()), f_max.get(name) or 0.0)
            for name, cb in cbs.items() if 0 < cb.n_eigenmodes < cb.n_dof - len(cb.boundary_labels)}
    if not band > 0:
        return [head + "unfiltered" + tail]
    # (the band is the filter's -6 dB point, not the edge of what it passes whole)
    filtered = (f"low-pass filtered to {band:g} Hz (zero phase, -6 dB there: {100 * lowpass_gain(0.8 * band, band):.0f} % "
                f"passed at {0.8 * band:g} Hz, 50 % at {band:g} Hz)")
    if not cuts:
        return [head + filtered + tail]
    name = min(cuts, key=cuts.get)
    leak = lowpass_gain(cuts[name], band)
    lines = [head + filtered + f", which passes {100 * leak:.2g} % at {cuts[name]:.1f} Hz, the lowest component cut "
             f"({name!r})" + tail]
    if leak > BAND_LEAK_WARNING:
        lines.append(f"  WARNING: the acceleration band passes {100 * leak:.2g} % at {cuts[name]:.1f} Hz, where "
                     f"component {name!r} is cut: modes the reduction left out would enter those peaks; lower "
                     f"[postprocess] acceleration_band_hz (to {cuts[name] / 1.5:.0f} Hz or less) or raise the "
                     "component's f_max")
    return lines


def summary(scenario, stack, results: dict, stage_times: list, rows_env: list[dict], wall: float) -> str:
    m, cg = center_of_gravity(stack.vehicle)
    lines = [f"liftoff run: {scenario.title}",
             f"  vehicle  {stack.vehicle.n_modes} modes, mass {m / 1e3:.1f} t, c.g. {np.round(cg, 2).tolist()} m; "
             f"pad {stack.pad.n_modes} modes"]
    lines += truncation_lines(c for _, cp in results.values() for c in cp.truncation)
    comps = scenario.cases[0].model.components        # the stack shown is the first case's model
    lines += band_lines(scenario.post.acceleration_band_hz, stack.cbs,
                        {n: c.f_max for n, c in comps.items() if c.n_modes is None})
    lines.append("  mesh: not checked by a run (refine the [model] mesh sizes and compare the envelopes; the default's "
                 "study: docs/workflow.md, Convergence)")
    for case, (res, cp) in results.items():
        lines.append(f"  case {case!r}: {res.time.size - 1} steps of h = {res.h:.3g} s "
                     f"({res.time[0]:g} .. {res.time[-1]:g} s)")
        cut = res.metadata.get("static_above_hz")
        if cut is not None:
            n_a, n_b = res.metadata["static_modes"]
            lines.append(f"    residual-flexibility modes: {n_a} of the vehicle's and {n_b} of the pad's, above {cut:g} "
                         "Hz, solved quasi-statically (their static flexibility kept; [time] static_above_hz; what "
                         "it changes on the default: docs/transient.md, Residual-flexibility modes)")
        est = res.metadata.get("error_estimate")
        if est:
            lines.append(f"    peak post forces: estimated error (Richardson, second run at h/2) at most "
                         f"{est['worst_relative']:.2g} of the largest post force")
        elif case not in {c.name for c in scenario.cases}:      # a campaign's governing generated case
            lines.append("    step: not checked for this case (a generated case is solved without a second run at "
                         "h/2, at the step rule the named cases' estimates check); its peaks carry no error estimate")
        else:
            lines.append("    step: not checked (no second run at h/2: --no-error-estimate); the peaks carry no error "
                         "estimate")
        band = scenario.post.acceleration_band_hz
        edge = res.metadata.get("band_edge_extremes", [])      # (workflows.run._full_case: edge_extremes)
        if edge:
            name, side, t = edge[0]
            lines.append(f"    WARNING: {len(edge)} band-limited max/min values lie within {EDGE_PERIODS / band:.3g} s of "
                         f"an end of the record (first: {name} {side} at t = {t:.4g} s), where the zero-phase {band:g} "
                         "Hz filter's end transient may have made or raised them (by up to tens of percent); run the "
                         "case longer ([time] t_end), or read its unfiltered histories")
        tw = twang(res, cp)
        if tw is not None:
            lines.append(f"    {tw.line()}")
        lines.append(f"    {'post':<10}{'release (s)':>12}{'separation (s)':>16}{'recontacts':>12}"
                     f"{'peak compr. (MN)':>18}{'peak tension (MN)':>19}")
        for c in res.contact_summary():
            sep = "-" if c["separation_time"] is None else f"{c['separation_time']:.4f}"
            rel = "never" if not np.isfinite(c["release_time"]) else f"{c['release_time']:.3f}"
            lines.append(f"    {c['name']:<10}{rel:>12}{sep:>16}{c['recontacts']:>12}"
                         f"{c['peak_compression'] / 1e6:>18.3f}{c['peak_tension'] / 1e6:>19.3f}")
    lines += largest_load_lines(rows_env)
    bulges = bulge_modes(getattr(stack, "cbs", {}))
    if bulges:
        lines.append("  hydroelastic tanks, first bulge mode (fixed-interface; volume change per unit modal coordinate):")
        for b in bulges:
            lines.append(f"    {b['tank']:<24} {b['hz']:7.2f} Hz (mode {b['mode']}), dV {b['dv_m3']:.3g} m^3, axial "
                         f"effective liquid mass {b['m_eff_kg'] / 1e3:.0f} t of {b['m_liquid_kg'] / 1e3:.0f} t")
    slosh = slosh_summary(getattr(stack, "cbs", {}), rows_env, getattr(stack, "components", {}))
    if slosh:
        lines.append("  slosh pendulums (convective = 'slosh'; first slosh mode fixed-interface, peak force over cases):")
        for r in slosh:
            g = "" if r.get("g_eff") is None else f" at g_eff {r['g_eff']:.4g} m/s^2"
            pk = "" if r["peak_n"] is None else f", peak slosh force {r['peak_n'] / 1e3:.4g} kN ({r['peak_item']})"
            pk += "" if r.get("peak_wave_m") is None else f", largest crest of one mode {r['peak_wave_m']:.3g} m"
            lines.append(f"    {r['liquid']:<24} {r['hz']:7.3f} Hz (mode {r['mode']}){g}{pk}")
    lines += stage_time_lines(stage_times, wall)
    return "\n".join(lines)


def largest_load_lines(rows_env: list[dict], n: int = 5) -> list[str]:
    """The summary's "largest loads" block: the ``n`` largest force peaks of the envelope rows
    (posts, attach forces; N), each on the side of its larger magnitude, with its estimated
    error where that side's case had a run at h/2; the heading promises estimates only as far
    as the lines carry them."""
    lines: list[str] = []
    peaks = sorted((r for r in rows_env if r.get("category") in ("contact_force", "interface_force")
                    and r["unit"] == "N"),
                   key=lambda r: -max(abs(r["max"]), abs(r["min"])))[:n]
    if peaks:
        shown = [(r["max"], r["t_max"], r["case_max"], r.get("max_err")) if abs(r["max"]) >= abs(r["min"])
                 else (r["min"], r["t_min"], r["case_min"], r.get("min_err")) for r in peaks]
        # (the side each line shows: an estimate on the other side, a post's tension of a named case
        # beside the compression of a generated one, promised estimates no line carried)
        estimated = [e is not None and e == e for _, _, _, e in shown]
        lines.append("  largest loads (envelope over cases" + (
            "; est. error: Richardson from a run at h/2, an estimate):" if all(estimated) else
            "; est. error where the case had a run at h/2, an estimate):" if any(estimated) else
            "; no step-error estimate):"))
        for r, (big, t, c, e), has in zip(peaks, shown, estimated):
            est = f" (est. error {abs(e) / 1e6:.3g} MN)" if has else ""
            lines.append(f"    {r['item']:<40} {big / 1e6:10.3f} MN at t = {t:.4f} s ({c}){est}")
    return lines


def truncation_lines(checks) -> list[str]:
    """The summary's truncation block (reduction/truncation.py): each distinct check of the
    bodies once, then a warning for each that misses more than 1 %."""
    checks = list(dict.fromkeys(checks))
    if not checks:
        return []
    lines = ["  modes kept (truncation check against the whole CB space; warning above 1 %):"]
    lines += [f"    {c.line()}" for c in checks]
    lines += [f"  {c.warning()}" for c in checks if c.warning()]
    return lines


def stage_time_lines(stage_times: list, wall: float) -> list[str]:
    """The summary's "wall time per stage" block: (stage, seconds) pairs and the total (s)."""
    return ["  wall time per stage:", *(f"    {name:<38}{secs:8.2f} s" for name, secs in stage_times),
            f"    {'total':<38}{wall:8.2f} s"]


# ------------------------------------------------------------------ spectra, comparisons
def srs_freq(settings) -> np.ndarray:
    """The SRS frequencies (Hz) of [postprocess.srs] ``settings``."""
    from liftoff.analysis.spectra import srs_frequencies

    return srs_frequencies(settings.f_min, settings.f_max, settings.n_freq)


def srs_of(values: np.ndarray, h: float, settings) -> tuple[np.ndarray, np.ndarray]:
    """(frequencies (Hz), SRS (n_q, n_freq, k)) of the columns of ``values`` (sampled every
    ``h`` s) per [postprocess.srs] ``settings``: absolute acceleration, each oscillator steady
    under its history's first value (analysis.spectra.srs, ic="steady"); what a case's
    spectra file and the campaign's envelope (its summaries) hold."""
    from liftoff.analysis.spectra import srs

    freq = srs_freq(settings)
    return freq, np.stack([srs(values, h, freq, q, ic="steady") for q in settings.q])


def _item_units(sel) -> "Dataset":
    """The units of the items ``sel`` on a spectra group's ``items`` axis."""
    from liftoff.core.records import Dataset

    return Dataset(np.array([it.unit for it in sel], dtype=str), "1", dims=("items",))


def spectra(result, cp, post, out: Path, case: str, srs: tuple | None = None) -> list[Path]:
    """spectra_<case>.h5 (PSD, FFT amplitude and SRS of the selected items) and
    psd_<case>.csv, per [postprocess.psd] / [postprocess.srs]; nothing when neither is set.
    ``srs``: (item names, SRS) of the case already computed by :func:`srs_of` (its summary's,
    workflows.campaign.summarize), used where its items are the selection's."""
    from liftoff.core.records import Dataset, write_record

    from liftoff.analysis.spectra import fft_amplitude, psd

    if post.psd is None and post.srs is None:
        return []
    its = items(result, cp.attach)
    h, data, paths = result.h, {}, []
    if post.psd is not None:
        sel = [it for it in its if it.category in post.psd.categories]
        V = np.column_stack([it.history for it in sel])
        f, P = psd(V, h, post.psd.segment)
        fa, A = fft_amplitude(V, h)
        data["psd"] = {"items": np.array([it.name for it in sel], dtype=str), "freq": Dataset(f, "Hz"),
                       "value": Dataset(P, "units^2/Hz of each item", dims=("freq", "items")),
                       "item_units": _item_units(sel)}
        data["fft"] = {"items": np.array([it.name for it in sel], dtype=str), "freq": Dataset(fa, "Hz"),
                       "amplitude": Dataset(A, "units of each item", dims=("freq", "items")),
                       "item_units": _item_units(sel)}
        head = f"# liftoff PSD (Welch, {post.psd.segment:g} s segments, Hann) of case {case}; units^2/Hz of each item\n"
        lines = [",".join(["freq_Hz"] + [f"{it.name} [({it.unit})^2/Hz]" for it in sel])]   # ((m/s^2)^2/Hz, not m/s^2^2/Hz)
        lines += [",".join([f"{x:.6e}" for x in row]) for row in np.column_stack([f, P])]
        paths.append(write_text(out / f"psd_{case}.csv", head + "\n".join(lines) + "\n"))
    if post.srs is not None:
        sel = [it for it in its if it.category in post.srs.categories]
        if srs is not None and srs[1] is not None and list(srs[0]) == [it.name for it in sel]:
            freq, S = srs_freq(post.srs), srs[1]
        else:
            freq, S = srs_of(np.column_stack([it.history for it in sel]), h, post.srs)
        data["srs"] = {"items": np.array([it.name for it in sel], dtype=str), "freq": Dataset(freq, "Hz"),
                       "q": Dataset(np.array(post.srs.q), "1"),
                       "value": Dataset(S, "units of each item (the absolute-acceleration SRS: each history the oscillators' base input)", dims=("q", "freq", "items"),
                                        initial_conditions="steady under each history's first value (pyyeti.srs "
                                                           "ic='steady')"),
                       "item_units": _item_units(sel)}
    paths.insert(0, write_record(out / f"spectra_{case}.h5", "liftoff-spectra", 1, data, units="SI per item",
                                 attrs={"case": case, "h": h}))
    return paths


