"""Reports of a lift-off run: its histories as max/min items (the tables themselves:
analysis/tables.py), time-history plots, deformed-shape snapshots of stack and pad, and the
printed summary. SI units.

Sign conventions: post forces are the forces the pad applies to the vehicle at the
hold-down points (Tz > 0: compression); attach forces are the forces the rest of the
vehicle applies to the named component at the attach point (reduction.recovery).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from liftoff.transient.effects import center_of_gravity

from liftoff.analysis.tables import (CSV_HEADER, DISPLAY_BINS, FIELDS, NAN, Item, display_points,  # noqa: F401
                                     envelope, format_changes, format_table, is_force, maxmin, write_csv)
from liftoff.core.errors import InputError
from liftoff.core.labels import TRANSLATIONS, point_labels
from liftoff.core.records import write_text


def items(result, attach: dict, heads: dict | None = None, band_hz: float = 0.0) -> list[Item]:
    """Every reported history: post forces, recovered items (attach forces, c.g. motion; not
    the modal coordinates), output points, and with ``heads`` (:func:`liquid_heads`) the
    total tank pressures and ullage volumes. Names, units and kinds come from the result's
    contact directions and recovery items; ``attach``: recovery name -> (point, component).
    ``band_hz`` > 0: the acceleration-type histories low-pass filtered to that band
    (analysis/spectra.lowpass; ``[postprocess] acceleration_band_hz``), the unfiltered
    history kept as ``raw``: the output-point accelerations and every recovery made from
    the modal accelerations alone (``RecoveryItem.from_acceleration``: liquid pressures,
    liquid inertia forces, a Nastran ATM), whose peaks are set by the highest modes."""
    from liftoff.analysis.spectra import lowpass

    out = []
    for j, d in enumerate(result.contact_directions):
        out.append(Item(f"post {d.contact} {d.component}", d.unit, result.contact_force[:, j], "contact_force"))
    for it in result.recovery_items.values():
        if it.category == CG_ACCELERATION:
            out += load_factor_items(result, it, band_hz)
            continue
        if it.category == "modal":
            continue
        arr = result.recovered[it.name]
        head = it.name
        if it.category == "interface_force" and it.name in attach:
            point, comp = attach[it.name]
            head = f"attach {point} on {comp}"
        band = band_hz if it.from_acceleration else 0.0
        filtered = lowpass(arr, result.h, band)
        for j, (lab, unit) in enumerate(zip(it.labels, it.units)):
            out.append(Item(f"{head} {lab}", unit, filtered[:, j], it.category, raw=arr[:, j] if band > 0 else None))
    dunits, aunits = result.output_units("a", "disp"), result.output_units("a", "acc")
    for j, lab in enumerate(result.output_labels["a"]):
        out.append(Item(f"disp {lab}", dunits[j], result.displacement["a"][:, j], "displacement"))
        acc = result.acceleration["a"][:, j]
        out.append(Item(f"acc {lab}", aunits[j], lowpass(acc, result.h, band_hz), "acceleration",
                        raw=acc if band_hz > 0 else None))
    if heads is not None:
        out += tank_items(result, heads, band_hz)
    return out


G0 = 9.80665          # m/s^2, standard gravity: load factors are in units of it
#: recovery category of a vehicle component's net c.g. acceleration (reduction.cg_acceleration_recovery,
#: workflows/loads.recoveries): the reports turn it into the net c.g. load factor (:func:`load_factor_items`)
CG_ACCELERATION = "cg_acceleration"


def load_factor_items(result, it, band_hz: float = 0.0) -> list[Item]:
    """A component's net c.g. load factor (g) from its c.g. acceleration item (category
    ``cg_acceleration``, m/s^2; reduction.cg_acceleration_recovery): n = (a - g) / g0 with g the
    run's gravity field (result metadata), the specific force of the component's c.g.: the net
    non-gravity force on it over its weight, +1 g upward (z) at rest on the pad. An
    acceleration-type history: band-limited like the other accelerations (``band_hz``)."""
    from liftoff.analysis.spectra import lowpass

    comp = it.name.removeprefix("cg_accel_")
    gvec = np.asarray(result.metadata.get("gravity", (0.0, 0.0, 0.0)), dtype=float)
    a = result.recovered[it.name]
    n = (a - gvec[None, :]) / G0
    filtered = lowpass(n, result.h, band_hz)
    return [Item(f"load factor {comp} N{lab[-1].lower()}", "g", filtered[:, j], "cg_load_factor",
                 raw=n[:, j] if band_hz > 0 else None) for j, lab in enumerate(it.labels)]


def interface_histories(result, attach: dict) -> list:
    """The attach points' load histories as analysis.interface_loads.InterfaceHistory, named as
    the max/min rows name them (``attach <point> on <component>``); ``attach``: recovery name
    -> (point, component)."""
    from liftoff.analysis.interface_loads import InterfaceHistory

    out = []
    for it in result.recovery_items.values():
        if it.category == "interface_force" and it.name in attach:
            point, comp = attach[it.name]
            out.append(InterfaceHistory(f"attach {point} on {comp}", tuple(it.labels), tuple(it.units),
                                        result.recovered[it.name]))
    return out


def write_interface_loads(results: dict, out: Path, name: str, note: str = "") -> list[Path]:
    """``interface_loads_<name>.csv``: the time-consistent interface loads (analysis/
    interface_loads.py) of one case (``results`` {case: (result, case problem)} with one
    entry) or, over several, their envelope; nothing when the model has no attach points.
    The file's second comment line names the cases it covers (and ``note``)."""
    from liftoff.analysis import interface_loads as il

    per_case = [il.time_consistent(res.time, interface_histories(res, cp.attach), case)
                for case, (res, cp) in results.items()]
    rows = il.envelope(per_case) if len(per_case) > 1 else (per_case[0] if per_case else [])
    cover = f"cases: {', '.join(results)}" + (f"; {note}" if note else "")
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


def write_recovery_op4(stack, cp, out: Path) -> list[Path]:
    """``recovery_vehicle.op4`` and its index ``recovery_vehicle_op4.csv``: the vehicle's
    recovery matrices in its system modal coordinates (y = D q + V qdot + A qddot: DTM, the
    velocity matrix, ATM; interface forces are LTMs in D and A), with the modal model they act
    on (FREQ, Hz; ZETA; unit modal masses) for another team's tools (Nastran OUTPUT4, binary,
    double; pyyeti.nastran.op4 reads it). Needs pyyeti (the ``nastran`` extra): without it
    nothing is written and the summary says so."""
    from liftoff.reduction import write_op4

    body = stack.vehicle
    mats = {"FREQ": stack.vehicle_modes.freq_hz[:, None], "ZETA": np.asarray(body.zeta, float)[:, None]}
    index = ["# liftoff recovery matrices of the vehicle in recovery_vehicle.op4 (binary OUTPUT4, double); "
             "y = D q + V qdot + A qddot over the vehicle's system modes (unit modal mass; FREQ Hz, ZETA); "
             "row_labels, row_units: one per row, ';'-separated; SI", "matrix,item,kind,rows,category,row_labels,row_units"]
    k = 0
    for r in cp.problem.recoveries:
        if r.body != "a":
            continue
        k += 1
        for kind, m in (("D", r.disp), ("V", r.vel), ("A", r.acc)):
            if m is None:
                continue
            name = f"R{k:04d}{kind}"
            mats[name] = m
            index.append(f"{name},{r.name},{ {'D': 'disp', 'V': 'vel', 'A': 'acc'}[kind]},{m.shape[0]},{r.category},"
                         f"{';'.join(r.labels)},{';'.join(r.units)}")
    try:
        files = [write_op4(out / "recovery_vehicle.op4", mats)]
    except ImportError:
        files = []
        index.insert(1, "# recovery_vehicle.op4 NOT written: pyyeti is not installed (pip install 'liftoff-loads[nastran]')")
    return files + [write_text(out / "recovery_vehicle_op4.csv", "\n".join(index) + "\n")]


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


def write_correlated(results: dict, out: Path, plots: bool = True, note: str = "") -> list[Path]:
    """``correlated_loads.csv`` (and ``correlated_loads.png``): per attach point the correlated
    envelopes of axial force with bending moment and of shear with torque over the cases in
    ``results`` (analysis/correlated.py: the convex hull of the pair's samples over time and
    cases, each vertex a sample with its time and case); nothing without attach points."""
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
    if plots:
        files.append(_plot_correlated(hulls, per_case, out))
    return files


def _plot_correlated(hulls, per_case: dict, out: Path) -> Path:
    """correlated_loads.png: a row per attach point, a column per pair; every case's
    trajectory (thin) and the hull (black)."""
    from liftoff.analysis import correlated as cl

    plt = _pyplot()
    names = list(dict.fromkeys(h.interface for h in hulls))
    pairs = [p for p, _, _ in cl.PAIRS]
    fig, axs = plt.subplots(len(names), len(pairs), figsize=(10, 2.6 * len(names) + 1), squeeze=False)
    for h in hulls:
        ax = axs[names.index(h.interface)][pairs.index(h.pair)]
        for case, (_, itfs) in per_case.items():
            itf = next(i for i in itfs if i.name == h.interface)
            ax.plot(cl.pair_values(itf.labels, itf.values, h.x_name) / 1e6,
                    cl.pair_values(itf.labels, itf.values, h.y_name) / 1e6, lw=0.5, alpha=0.7, label=case)
        ax.fill(h.x / 1e6, h.y / 1e6, fill=False, ec="k", lw=1.2)
        ax.set_xlabel(f"{h.x_name} (M{h.x_unit})", fontsize=8)
        ax.set_ylabel(f"{h.y_name} (M{h.y_unit})", fontsize=8)
        ax.set_title(h.interface, fontsize=8)
        ax.grid(True, alpha=0.3)
    fig.suptitle("Correlated loads: axial force with bending moment, shear with torque (hull over time and cases)")
    return _save_figure(plt, fig, out / "correlated_loads.png", axs[0][0], top=0.98, dpi=100)


def plot_contours(csv_path: Path, out: Path) -> Path:
    """correlated_statistics.png from correlated_statistics.csv: a row per attach point, a
    column per pair; the envelope polygon over every case and the P99/90 normal and
    order-statistic contours over the dispersed cases."""
    from liftoff.analysis import correlated as cl
    from liftoff.analysis.workbook import read_csv_table

    plt = _pyplot()
    _, cols, table = read_csv_table(csv_path)
    ci = {c: k for k, c in enumerate(cols)}
    poly: dict = {}
    for r in table:
        key = (r[ci["interface"]], r[ci["pair"]], r[ci["contour"]])
        poly.setdefault(key, ([], [], r[ci["x_name"]], r[ci["y_name"]]))
        poly[key][0].append(float(r[ci["x"]]))
        poly[key][1].append(float(r[ci["y"]]))
    names = list(dict.fromkeys(k[0] for k in poly))
    pairs = [p for p, _, _ in cl.PAIRS]
    style = {"envelope": ("k", "-", "envelope, every case"), "normal": ("C3", "--", "P99/90 normal"),
             "order": ("C0", ":", "P99/90 order statistic")}
    fig, axs = plt.subplots(len(names), len(pairs), figsize=(10, 2.6 * len(names) + 1), squeeze=False)
    for (itf, pair, kind), (x, y, xn, yn) in poly.items():
        ax = axs[names.index(itf)][pairs.index(pair)]
        c, ls, label = style.get(kind, ("C2", "-", kind))
        ax.fill(np.array(x) / 1e6, np.array(y) / 1e6, fill=False, ec=c, ls=ls, lw=1.2, label=label)
        ax.set_xlabel(f"{xn} (MN)", fontsize=8)
        ax.set_ylabel(f"{yn} (MN m)", fontsize=8)
        ax.set_title(itf, fontsize=8)
        ax.grid(True, alpha=0.3)
    fig.suptitle("Correlated loads over the dispersed cases: support-function contours")
    return _save_figure(plt, fig, out / "correlated_statistics.png", axs[0][0], top=0.98, dpi=100)


def plot_spectra(ctx) -> list[Path]:
    """``srs.png`` (the SRS envelope over the cases of every selected item, one panel per
    item, a line per Q, log-log; from srs.csv) and ``psd_<case>.png`` (each case's PSD of the
    selected items, log-log; from psd_<case>.csv): the spectra the tables hold, drawn."""
    if not ctx.plots:
        return []
    from liftoff.analysis.workbook import read_csv_table

    plt = _pyplot()

    files = []
    if (ctx.out / "srs.csv").is_file():
        _, cols, rows = read_csv_table(ctx.out / "srs.csv")
        ci = {c: k for k, c in enumerate(cols)}
        items = list(dict.fromkeys(r[ci["item"]] for r in rows))
        n = len(items)
        fig, axs = plt.subplots((n + 1) // 2, 2, figsize=(11, 2.8 * ((n + 1) // 2) + 1), squeeze=False)
        for ax, item in zip(axs.flat, items):
            sel = [r for r in rows if r[ci["item"]] == item]
            for q in dict.fromkeys(r[ci["Q"]] for r in sel):
                rq = [r for r in sel if r[ci["Q"]] == q]
                ax.loglog([r[ci["freq_Hz"]] for r in rq], [r[ci["envelope"]] for r in rq], lw=1, label=f"Q = {q:g}")
            ax.set_title(item, fontsize=8)
            ax.set_xlabel("frequency (Hz)", fontsize=8)
            ax.set_ylabel(f"SRS ({sel[0][ci['unit']]})", fontsize=8)
            ax.grid(True, which="both", alpha=0.3)
            ax.legend(fontsize=7)
        for ax in list(axs.flat)[n:]:
            ax.set_visible(False)
        fig.suptitle("Shock response spectra, absolute acceleration, envelope over the cases")
        files.append(_save_figure(plt, fig, ctx.out / "srs.png", dpi=100))
    for case in ctx.results:
        src = ctx.out / f"psd_{case}.csv"
        if not src.is_file():
            continue
        _, cols, rows = read_csv_table(src)
        data = np.array(rows, dtype=float)
        fig, ax = plt.subplots(figsize=(10, 5))
        for k, col in enumerate(cols[1:], start=1):
            y = np.where(data[:, k] > 0, data[:, k], np.nan)
            ax.loglog(data[1:, 0], y[1:], lw=0.8, label=col)
        ax.set_xlabel("frequency (Hz)")
        ax.set_ylabel("PSD (unit^2/Hz of each item)")
        ax.grid(True, which="both", alpha=0.3)
        fig.suptitle(f"Power spectral density (Welch) — case {case}")
        files.append(_save_figure(plt, fig, ctx.out / f"psd_{case}.png", ax, dpi=100, right=0.7))   # long labels
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
LIQUID_PRESSURE, ULLAGE = "_liquid_pressure", "_ullage_volume"     # component recovery names end so


def liquid_heads(cp) -> dict[str, np.ndarray]:
    """{recovery name: head (Pa) per column} of the liquids' pressure items: the pressure
    rows (over the vehicle's modes) times the modal acceleration of a uniform acceleration
    -g, Phi^T M RB (-g) (eq. 14; exact for the rigid-body part, which is all a uniform field
    has): the hydrostatic head under gravity, which the total tank pressure adds to the
    dynamic pressure from the accelerations (reduction.liquid)."""
    pr = cp.problem
    g = np.asarray(pr.forcing.gravity, float).reshape(-1)[:3]
    out = {}
    for r in pr.recoveries:
        if r.name.endswith(LIQUID_PRESSURE) and r.acc is not None and r.body == "a":
            out[r.name] = r.acc @ pr.body_a.modal_gravity(-g)
    return out


def tank_items(result, heads: dict, band_hz: float = 0.0) -> list[Item]:
    """Total tank pressure (dynamic + head) and ullage volume change histories; ``band_hz``
    > 0: the dynamic pressure (from the accelerations) in that band, as in :func:`items`."""
    from liftoff.analysis.spectra import lowpass

    out = []
    for it in result.recovery_items.values():
        if it.name in heads:
            dynamic, head = result.recovered[it.name], heads[it.name]
            band = band_hz if it.from_acceleration else 0.0
            arr = lowpass(dynamic, result.h, band) + head
            raw = dynamic + head if band > 0 else None
            out += [Item(f"tank pressure {lab}", "Pa", arr[:, j], "tank_pressure", raw=None if raw is None else raw[:, j])
                    for j, lab in enumerate(it.labels)]
        elif it.name.endswith(ULLAGE):
            arr = result.recovered[it.name]
            out += [Item(f"ullage volume change {lab}", "m^3", arr[:, j], "ullage_volume")
                    for j, lab in enumerate(it.labels)]
    return out


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


def tank_plots(result, cp, out: Path, case: str, finish) -> None:
    """ullage_volume_<case>.png and tank_pressure_<case>.png (the reference's figures 5, 6)."""
    import matplotlib.pyplot as plt

    its = tank_items(result, liquid_heads(cp))
    for cat, name, title, scale, unit in (("ullage_volume", "ullage_volume", "Ullage volume change", 1e3, "litre"),
                                          ("tank_pressure", "tank_pressure", "Tank-bottom pressure", 1e-3, "kPa")):
        sel = [it for it in its if it.category == cat]
        if not sel:
            continue
        fig, axs = plt.subplots(len(sel), 1, figsize=(10, 3 + 2.5 * len(sel)), sharex=True, squeeze=False)
        for ax, it in zip(axs[:, 0], sel):
            ax.plot(*display_points(result.time, it.values * scale), lw=0.8, label=it.name)
            ax.set_ylabel(f"{it.name.split()[-1]} ({unit})")
        finish(fig, list(axs[:, 0]), name, title)


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
def release_time(cp) -> float | None:
    """The first hold-down release (booster ignition in the lift-off scenario), None if none."""
    rel = [p.release_time for p in cp.case.posts if np.isfinite(p.release_time)]
    return min(rel) if rel else None


@dataclass
class Twang:
    """Lateral (x, y) motion of the recovery's ``top`` point (the tank tip), m.

    ``pad``: in the pad frame (the pad's foundation is the ground), from its position at t0
    (the static state on the pad before main-engine start): the twang as engineers quote
    it. ``rel_cg``: the top's lateral displacement less the c.g.'s (eq. 23), as before.
    Peaks are taken before the first hold-down release ``t_ign`` (the whole run without
    one); ``at_ign``: the pad-frame twang at ``t_ign``, interpolated in time."""

    point: str
    time: np.ndarray
    pad: np.ndarray
    rel_cg: np.ndarray
    t_ign: float | None

    def _peak(self, xy: np.ndarray) -> int:
        n = self.time.size if self.t_ign is None else max(int(np.searchsorted(self.time, self.t_ign, "right")), 1)
        return int(np.argmax(np.hypot(xy[:n, 0], xy[:n, 1])))

    @property
    def i_peak(self) -> int:
        return self._peak(self.pad)

    @property
    def i_peak_cg(self) -> int:
        return self._peak(self.rel_cg)

    @property
    def at_ign(self) -> np.ndarray | None:
        if self.t_ign is None or not self.time[0] <= self.t_ign <= self.time[-1]:
            return None
        return np.array([np.interp(self.t_ign, self.time, self.pad[:, j]) for j in range(2)])

    def line(self) -> str:
        """One summary line: pad-frame peak and value at the first hold-down release (the
        Shuttle's booster ignition), relative-to-c.g. peak."""
        i, k = self.i_peak, self.i_peak_cg
        peak = float(np.hypot(*self.pad[i]))
        out = (f"twang at {self.point} (pad frame, from t0): peak {peak:.3f} m at t = {self.time[i]:.2f} s "
               f"(x {self.pad[i, 0]:+.3f}, y {self.pad[i, 1]:+.3f} m)")
        ign = self.at_ign
        if ign is not None:
            v = float(np.hypot(*ign))
            out += (f"; at hold-down release (t = {self.t_ign:.2f} s) {v:.3f} m"
                    + (f" = {100 * v / peak:.0f} % of the peak" if peak > 0 else ""))
        return out + f"; relative to the c.g.: peak {float(np.hypot(*self.rel_cg[k])):.3f} m at t = {self.time[k]:.2f} s"


def twang(result, cp) -> Twang | None:
    """The twang of a lift-off case (None without a ``[recovery] top`` point)."""
    top = cp.case.recovery.top
    if not top:
        return None
    labels = result.output_labels["a"]
    cg_item = result.items("cg_motion")[0]
    cg = result.recovered[cg_item.name][:, _translations(cg_item)[:2]]
    u = result.displacement["a"][:, [labels.index(lab) for lab in point_labels(top, TRANSLATIONS[:2])]]
    return Twang(top, result.time, u - u[0], u - cg, release_time(cp))


# ------------------------------------------------------------------ plots
RELEASE_WINDOW = (-0.05, 0.45)   # s about the first release: the zoom panel of the plots


def _pyplot():
    """matplotlib.pyplot on the Agg backend (files only, no display)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _save_figure(plt, fig, path: Path, legend_from=None, top: float = 0.97, dpi: int = 110,
                 right: float = 0.84) -> Path:
    """Lay out, save and close a figure: tight layout below the title (a fixed layout where
    matplotlib cannot fit one, instead of its warning on stderr) and, with ``legend_from`` (an
    axes), that axes' legend right of the panels (which end at ``right``), outside the data."""
    import warnings

    with warnings.catch_warnings(record=True) as caught:    # matplotlib's "tight layout not applied"
        warnings.simplefilter("always")
        fig.tight_layout(rect=(0, 0, 1, top))
    if any("tight" in str(w.message).lower() for w in caught):
        fig.subplots_adjust(left=0.09, bottom=0.08, top=0.9, hspace=0.4, wspace=0.2)
    handles, labs = legend_from.get_legend_handles_labels() if legend_from is not None else ([], [])
    if handles:
        fig.subplots_adjust(right=right)
        fig.legend(handles, labs, fontsize=7, loc="center left", bbox_to_anchor=(right + 0.015, 0.5), frameon=False)
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path


class _Figures:
    """The history plots' common frame: the whole run | the release window (:data:`RELEASE_WINDOW`
    about the first release), engine starts (grey, dotted, named) and the release (red,
    dashed) marked, the legend right of the panels; ``paths`` collects the PNGs written."""

    def __init__(self, plt, result, cp, out: Path, case: str):
        self.plt, self.out, self.case, self.paths = plt, out, case, []
        t = result.time
        rel = [p.release_time for p in cp.case.posts if np.isfinite(p.release_time)]
        self.t_rel = min(rel) if rel else None
        self.starts: dict[float, list[str]] = {}
        for e in cp.case.engines:
            if t[0] <= e.start <= t[-1]:
                self.starts.setdefault(round(float(e.start), 6), []).append(e.name)

    def panels(self, nrows: int, height: float):
        """(fig, axes (nrows, 2)): the whole run | the release window, each row sharing y."""
        ncol = 2 if self.t_rel is not None else 1
        return self.plt.subplots(nrows, ncol, figsize=(14 if ncol == 2 else 11, height), squeeze=False,
                                 sharex="col", sharey="row", gridspec_kw={"width_ratios": [2, 1][:ncol]})

    def draw(self, axs, row: int, x, y, **kw):
        """A history in the whole-run panel and, restricted to the window, in the release one
        (each through :func:`display_points`)."""
        for k, ax in enumerate(axs[row]):
            xs, ys = x, y
            if k == 1 and self.t_rel is not None:
                lo, hi = np.searchsorted(x, [self.t_rel + RELEASE_WINDOW[0], self.t_rel + RELEASE_WINDOW[1]])
                xs, ys = x[max(lo - 1, 0):hi + 1], y[max(lo - 1, 0):hi + 1]
            ax.plot(*display_points(xs, ys), **{**kw, "label": kw.get("label") if k == 0 else None})

    def finish(self, fig, ax_list, name, title):
        ax_arr = np.atleast_2d(np.asarray(ax_list, dtype=object))
        if ax_arr.shape[0] == 1 and ax_arr.shape[1] > 1 and not isinstance(ax_list[0], np.ndarray):
            ax_arr = ax_arr.T                      # a plain list of axes: one column
        t_rel, lo, hi = self.t_rel, *RELEASE_WINDOW
        for r, row in enumerate(ax_arr):
            for k, ax in enumerate(row):
                for ts, names in self.starts.items():
                    ax.axvline(ts, color="0.45", ls=":", lw=0.9)
                    if r == 0:
                        ax.annotate(", ".join(names), (ts, 1.0), xycoords=("data", "axes fraction"), rotation=90,
                                    fontsize=6, va="top", ha="right", color="0.3")
                if t_rel is not None:
                    ax.axvline(t_rel, color="red", ls="--", lw=1, label="release" if (r == 0 and k == 0) else None)
                ax.grid(True, alpha=0.3)
                if k == 1:
                    ax.set_xlim(t_rel + lo, t_rel + hi)
                    if r == 0:
                        ax.set_title(f"release window ({t_rel + lo:g} to {t_rel + hi:g} s)", fontsize=8)
        for ax in ax_arr[-1]:
            ax.set_xlabel("time (s)")
        fig.suptitle(f"{title} — case {self.case}")
        self.paths.append(_save_figure(self.plt, fig, self.out / f"{name}_{self.case}.png", ax_arr[0][0]))


def plots(result, cp, out: Path, case: str) -> list[Path]:
    """PNG time histories: post forces, attach forces and moments, c.g./top motion, payload
    acceleration, tank pressures (:class:`_Figures`: the whole run beside the release window,
    engine starts and release marked, legends outside the data)."""
    plt = _pyplot()
    t = result.time
    kit = _Figures(plt, result, cp, out, case)
    panels, draw, finish, paths = kit.panels, kit.draw, kit.finish, kit.paths

    # post forces: axial (normal, + compression) and the magnitude of the lateral translations
    fig, axs = panels(2, 7)
    dirs, F = result.contact_directions, result.contact_force
    for c, name in enumerate(result.contact_names):
        ax = result.axial_column(c)
        lat = [j for j in result.directions_of(c) if not dirs[j].axial and dirs[j].component in TRANSLATIONS]
        draw(axs, 0, t, dirs[ax].normal_sign * F[:, ax] / 1e6, lw=0.8, label=name)
        draw(axs, 1, t, np.sqrt(np.sum(F[:, lat] ** 2, axis=1)) / 1e6, lw=0.8)
    axs[0][0].set_ylabel("axial force on vehicle (MN)\n(+ compression)")
    axs[1][0].set_ylabel("lateral force magnitude (MN)")
    finish(fig, axs, "post_forces", "Hold-down post forces")

    att = [it for it in result.items("interface_force") if it.name in cp.attach]
    for kind, title, unit_scale in (("T", "Attach forces (on the named component)", "MN"),
                                    ("R", "Attach moments (on the named component)", "MN m")):
        cols = [k for k, lab in enumerate(att[0].labels) if lab.startswith(kind)] if att else []
        if not cols:
            continue
        fig, axs = panels(len(cols), 2.6 * len(cols) + 1)
        for it in att:
            point, comp = cp.attach[it.name]
            for r, j in enumerate(cols):
                draw(axs, r, t, result.recovered[it.name][:, j] / 1e6, lw=0.8, label=f"{point} ({comp})")
        for r, j in enumerate(cols):
            axs[r][0].set_ylabel(f"{att[0].labels[j]} ({unit_scale})")
        finish(fig, axs, "attach_forces" if kind == "T" else "attach_moments", title)

    fig, axs = plt.subplots(3, 1, figsize=(10, 9), sharex=True)
    cg_item = result.items("cg_motion")[0]
    cg, cgc = result.recovered[cg_item.name], _translations(cg_item)
    for j in cgc:
        axs[0].plot(*display_points(t, cg[:, j]), lw=0.9, label=f"c.g. {cg_item.labels[j]} ({cg_item.units[j]})")
    labels = result.output_labels["a"]
    tw = twang(result, cp)
    if tw is not None:
        on = slice(None) if tw.t_ign is None else t <= tw.t_ign   # on the pad (then it flies)
        for j, c in enumerate("xy"):
            axs[1].plot(*display_points(t[on], tw.pad[on, j]), lw=1.2, label=f"{tw.point} {c}, pad frame (from t0; to release)")
        for j, c in enumerate("xy"):
            axs[1].plot(*display_points(t, tw.rel_cg[:, j]), lw=0.8, ls=":", label=f"{tw.point} {c} rel. to c.g.")
        i = tw.i_peak
        axs[1].plot(t[i], tw.pad[i, 1], "kv", ms=6, label=f"peak {np.hypot(*tw.pad[i]):.2f} m")
        if tw.at_ign is not None:
            axs[1].plot(tw.t_ign, tw.at_ign[1], "ko", mfc="none", ms=6,
                        label=f"at ignition {np.hypot(*tw.at_ign):.2f} m")
    if result.rigid_body_motion_a is not None:
        for j in range(3):
            axs[2].plot(*display_points(t, np.degrees(result.rigid_body_motion_a[:, 3 + j])), lw=0.9, label=f"R{'xyz'[j]}")
        axs[2].legend(fontsize=7)
    axs[0].set_ylabel("c.g. motion (m)")
    axs[1].set_ylabel("tank-tip lateral (m)")
    axs[2].set_ylabel("attitude, rigid-body\nrotation (deg)")
    axs[1].legend(fontsize=7, loc="upper left")
    finish(fig, list(axs), "motion", "C.g. motion, tank-tip twang, attitude")

    pay = cp.case.recovery.payload
    if pay:
        fig, axs = panels(1, 4.5)
        for lab in point_labels(pay, TRANSLATIONS):
            draw(axs, 0, t, result.acceleration["a"][:, labels.index(lab)] / G0, lw=0.8, label=lab)
        axs[0][0].set_ylabel(f"{pay} acceleration\n(g = {G0} m/s^2, unfiltered)")
        finish(fig, axs, "payload_acc", "Payload-station acceleration")
    tank_plots(result, cp, out, case, finish)
    return paths


def _translations(item) -> list[int]:
    """Columns of a recovery item labelled with a translation component (Tx Ty Tz), in order."""
    return [item.labels.index(c) for c in TRANSLATIONS if c in item.labels]


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


def deformed_fields(stack, result, i: int) -> list:
    """One fem.snapshot.Part per component at step i, elastic part of the vehicle only (its
    rigid-body motion removed, so the picture stays on the pad)."""
    from liftoff.fem.snapshot import Part
    from liftoff.reduction import field_displacement

    out = []
    if "q_a" not in result.modal:
        raise ValueError("deformed_fields needs the modal displacements: solve with keep_modal = 'q'")
    qa = result.modal["q_a"][i].copy()
    qa[: np.sum(stack.vehicle.omega == 0)] = 0.0            # elastic deformation only
    qb = result.modal["q_b"][i] if "q_b" in result.modal else np.zeros(0)
    for name, comp in stack.components.items():
        if comp.field_map is None or comp.nodes is None:
            continue
        if name == "pad":
            u = field_displacement(stack.pad_asm, stack.pad_modes, name, comp, qb)
        else:
            u = field_displacement(stack.vehicle_asm, stack.vehicle_modes, name, comp, qa)
        out.append(Part(comp.nodes, comp.cells, comp.cell_type, u.reshape(-1, 3)))
    return out


TITLES = {"max_twang": "maximum twang", "release": "hold-down release",
          "peak_load": "peak post/attach load change"}


def snapshots(stack, result, cp, out: Path, case: str) -> list[Path]:
    from liftoff.fem.snapshot import snapshot_png

    paths = []
    for what, i in snapshot_times(result, cp).items():
        parts = deformed_fields(stack, result, i)
        if not parts:
            break
        # looking along -x: the orbiter (+y) and the twang plane in view
        paths.append(snapshot_png(out / f"snapshot_{what}_{case}.png", parts,
                                  f"{case}: {TITLES.get(what, what)} at t = {result.time[i]:.3f} s",
                                  fraction=0.03, note="elastic part", window_size=(900, 1100), view="yz",
                                  azimuth=35, elevation=12))
    return paths


# ------------------------------------------------------------------ summary
#: the share of a mode at the lowest component cut that the acceleration band may pass
BAND_LEAK_WARNING = 0.01


def band_lines(band: float, cbs: dict, f_max: dict | None = None) -> list[str]:
    """The acceleration band of the max/min tables and what its filter passes at the lowest
    frequency a component's reduction cuts at: its highest kept fixed-interface mode, or its
    ``f_max[name]`` Hz when it was selected by band alone; a component that keeps all its
    interior modes cuts nothing. The modes above a cut are left out, so whatever the band
    passes there is not converged; a warning above BAND_LEAK_WARNING. ``cbs``: the vehicle's
    CB models (n_modes, fixed_freq_hz, n_dof, boundary_labels)."""
    from liftoff.analysis.spectra import lowpass_gain

    head = "  accelerations and liquid pressures in the max/min tables: "
    tail = " ([postprocess] acceleration_band_hz; SRS and PSD unfiltered)"
    f_max = f_max or {}
    cuts = {name: max(float(cb.fixed_freq_hz.max()), f_max.get(name) or 0.0) for name, cb in cbs.items()
            if 0 < cb.n_modes < cb.n_dof - len(cb.boundary_labels)}
    if not band > 0:
        return [head + "unfiltered" + tail]
    if not cuts:
        return [head + f"low-pass filtered to {band:g} Hz" + tail]
    name = min(cuts, key=cuts.get)
    leak = lowpass_gain(cuts[name], band)
    lines = [head + f"low-pass filtered to {band:g} Hz, which passes {100 * leak:.2g} % at {cuts[name]:.1f} Hz, the "
             f"lowest component cut ({name!r})" + tail]
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
        est = res.metadata.get("error_estimate")
        if est:
            lines.append(f"    peak post forces: estimated error (Richardson, second run at h/2) at most "
                         f"{est['worst_relative']:.2g} of the largest post force")
        else:
            lines.append("    step: not checked (no second run at h/2: --no-error-estimate); the peaks carry no error "
                         "estimate")
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
    peaks = sorted((r for r in rows_env if r.get("category") in ("contact_force", "interface_force")
                    and r["unit"] == "N"),
                   key=lambda r: -max(abs(r["max"]), abs(r["min"])))[:5]
    if peaks:
        estimated = any(r.get(k) is not None and r.get(k) == r.get(k) for r in peaks for k in ("max_err", "min_err"))
        lines.append("  largest loads (envelope over cases" + ("; est. error: Richardson from a run at h/2, an estimate):"
                                                            if estimated else "; no step-error estimate):"))
        for r in peaks:
            big, t, c, e = (r["max"], r["t_max"], r["case_max"], r.get("max_err")) if abs(r["max"]) >= abs(r["min"]) \
                else (r["min"], r["t_min"], r["case_min"], r.get("min_err"))
            est = "" if e is None or e != e else f" (est. error {abs(e) / 1e6:.3g} MN)"
            lines.append(f"    {r['item']:<40} {big / 1e6:10.3f} MN at t = {t:.4f} s ({c}){est}")
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
def spectra(result, cp, post, out: Path, case: str) -> list[Path]:
    """spectra_<case>.h5 (PSD, FFT amplitude and SRS of the selected items) and
    psd_<case>.csv, per [postprocess.psd] / [postprocess.srs]; nothing when neither is set."""
    from liftoff.core.records import Dataset, write_record

    from liftoff.analysis.spectra import fft_amplitude, psd, srs, srs_frequencies

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
                       "item_units": Dataset(np.array([it.unit for it in sel], dtype=str), "1", dims=("items",))}
        data["fft"] = {"items": np.array([it.name for it in sel], dtype=str), "freq": Dataset(fa, "Hz"),
                       "amplitude": Dataset(A, "units of each item", dims=("freq", "items"))}
        head = f"# liftoff PSD (Welch, {post.psd.segment:g} s segments, Hann) of case {case}; units^2/Hz of each item\n"
        lines = [",".join(["freq_Hz"] + [f"{it.name} [{it.unit}^2/Hz]" for it in sel])]
        lines += [",".join([f"{x:.6e}" for x in row]) for row in np.column_stack([f, P])]
        paths.append(write_text(out / f"psd_{case}.csv", head + "\n".join(lines) + "\n"))
    if post.srs is not None:
        sel = [it for it in its if it.category in post.srs.categories]
        freq = srs_frequencies(post.srs.f_min, post.srs.f_max, post.srs.n_freq)
        V = np.column_stack([it.history for it in sel])
        data["srs"] = {"items": np.array([it.name for it in sel], dtype=str), "freq": Dataset(freq, "Hz"),
                       "q": Dataset(np.array(post.srs.q), "1"),
                       "value": Dataset(np.stack([srs(V, h, freq, q) for q in post.srs.q]),
                                        "units of each item (absolute acceleration)", dims=("q", "freq", "items"))}
    paths.insert(0, write_record(out / f"spectra_{case}.h5", "liftoff-spectra", 1, data, units="SI per item",
                                 attrs={"case": case, "h": h}))
    return paths


