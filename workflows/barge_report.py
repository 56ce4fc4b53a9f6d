"""Reports of a barge-impact run (workflows/barge.py): max/min items, per-case time histories,
the impact sweep against the series-spring estimate, the deck's response to the impact
wave (the reference's figure 9), deformed-shape frames and an animation. SI units.

Sign conventions: the fender force is the compression of the fenders (N, > 0 pushing the
barge back, -x); cargo interface forces are the forces of the barge's cradle on the cargo
at each saddle (reduction.recovery), in the barge frame (x towards the dock, z up).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .report import Item, maxmin, stage_time_lines, truncation_lines

PLATE_WAVE = float(np.sqrt(210e9 / (7850.0 * (1 - 0.3 ** 2))))   # m/s, membrane waves in the steel plates


def fender_force(result) -> np.ndarray:
    """(n_t,) total fender compression (N): sum over the fenders of normal_sign * axial force."""
    cols = [result.axial_column(c) for c in range(len(result.contact_names))]
    return sum(result.contact_directions[j].normal_sign * result.contact_force[:, j] for j in cols)


def impact_window(result, margin: float = 0.25) -> slice:
    """Steps from a little before the first contact to a little after the last one."""
    F = fender_force(result)
    on = np.flatnonzero(F > 0)
    if not on.size:
        return slice(0, result.time.size)
    i0, i1 = on[0], on[-1]
    pad = max(int(margin * (i1 - i0)), 2)
    return slice(max(i0 - pad, 0), min(i1 + pad, result.time.size - 1) + 1)


def items(result, bp) -> list[Item]:
    """Reported histories: fender forces (per fender and total), cargo interface forces, deck accelerations."""
    out = [Item("fender total compression", "N", fender_force(result), "contact_force")]
    for c, name in enumerate(result.contact_names):
        for j in result.directions_of(c):
            d = result.contact_directions[j]
            out.append(Item(f"{name} {d.component} (force on barge)", d.unit, result.contact_force[:, j],
                            "contact_force"))
    for rec, pt in bp.interface.items():
        it = result.recovery_items[rec]
        for j, (lab, unit) in enumerate(zip(it.labels, it.units)):
            out.append(Item(f"cargo interface {pt} {lab}", unit, result.recovered[rec][:, j], "interface_force"))
    units = result.output_units("a", "acc")
    for j, lab in enumerate(result.output_labels["a"]):
        out.append(Item(f"acc {lab}", units[j], result.acceleration["a"][:, j], "acceleration"))
    return out


def case_rows(result, bp, name: str) -> list[dict]:
    return maxmin(result.time, items(result, bp), name)


# ------------------------------------------------------------------ plots
def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def case_plot(result, bp, out: Path, name: str) -> Path:
    """Fender force, cargo interface forces and deck accelerations of one case over the impact."""
    plt = _pyplot()
    w = impact_window(result)
    t = result.time[w] * 1e3
    fig, axs = plt.subplots(3, 1, figsize=(10, 10), sharex=True)
    axs[0].plot(t, fender_force(result)[w] / 1e6, "k", lw=1.2, label="total")
    for c, cname in enumerate(result.contact_names):
        j = result.axial_column(c)
        axs[0].plot(t, result.contact_directions[j].normal_sign * result.contact_force[w, j] / 1e6, lw=0.8, label=cname)
    est = bp.estimate
    axs[0].axhline(est["F_series"] / 1e6, color="r", ls="--", lw=1, label="series spring v0 sqrt(m k_eff)")
    axs[0].axhline(est["F_wave"] / 1e6, color="m", ls="-.", lw=1, label="hull wave impedance v0 sqrt(EA m')")
    axs[0].set_ylabel("fender compression (MN)")
    for rec, pt in bp.interface.items():
        it = result.recovery_items[rec]
        for comp, ls in (("Tx", "-"), ("Tz", "--")):
            axs[1].plot(t, result.recovered[rec][w, it.labels.index(comp)] / 1e3, ls, lw=0.9, label=f"{pt} {comp}")
    axs[1].set_ylabel("cargo interface force (kN)\n(cradle on cargo)")
    labels = result.output_labels["a"]
    for j, lab in enumerate(labels):
        if lab.startswith("deck_") and lab.endswith(":Tx"):
            axs[2].plot(t, result.acceleration["a"][w, j], lw=0.7, label=lab)
    axs[2].set_ylabel("deck acceleration x (m/s^2)")
    axs[2].set_xlabel("time (ms)")
    for ax in axs:
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, ncol=3)
    fig.suptitle(f"Barge impact, case {name}: k_dock = {est['k_dock']:.3g} N/m, v0 = {abs(bp.case.velocity):g} m/s")
    fig.tight_layout()
    path = out / f"impact_{name}.png"
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def deck_wave_plot(result, models, out: Path, name: str, c: float | None = None) -> Path:
    """The reference's figure 9: deck response along the barge (stations stern -> bow), each
    station's x velocity relative to the barge's rigid-body velocity, stacked by position;
    ``c`` (m/s): the hull's bar-wave speed, drawn as the front leaving the bow at first contact."""
    plt = _pyplot()
    w = impact_window(result, margin=0.1)
    t = result.time[w] * 1e3
    labels = result.output_labels["a"]
    rb = result.rigid_body_motion_a
    vrb = np.gradient(rb[:, 0], result.time) if rb is not None else np.zeros(result.time.size)
    xs = {p: models.barge.point_coord(p)[0] for p in models.stations}
    rel = {p: result.velocity["a"][w, labels.index(f"{p}:Tx")] - vrb[w] for p in models.stations}
    span = max(float(np.abs(np.concatenate(list(rel.values()))).max()), 1e-12)
    fig, ax = plt.subplots(figsize=(10, 7))
    spacing = max(np.diff(sorted(xs.values())).min(), 1.0)
    for p in models.stations:
        ax.plot(t, xs[p] + 0.45 * spacing * rel[p] / span, lw=0.9)
        ax.text(t[0], xs[p], f" {p}", fontsize=7, va="bottom")
    on = np.flatnonzero(fender_force(result) > 0)
    if c and on.size:
        x_bow = models.barge.point_coord(models.bow_points[0])[0]
        x = np.array(sorted(xs.values()))
        for speed, ls, what in ((PLATE_WAVE, ":", "steel plate, sqrt(E / rho (1 - nu^2))"),
                                (c, "--", "loaded hull girder, sqrt(EA / m')")):
            ax.plot(1e3 * (result.time[on[0]] + (x_bow - x) / speed), x, "k" + ls, lw=0.8,
                    label=f"front from the bow at {speed:.0f} m/s: {what}")
        ax.legend(fontsize=8, loc="lower right")
    ax.set_xlabel("time (ms)")
    ax.set_ylabel("station position x (m)   [traces: x velocity relative to the rigid-body motion]")
    ax.set_title(f"Deck response to the impact wave, case {name} (bow at the top; each trace scaled to "
                 f"{span * 1e3:.3g} mm/s = 0.45 station spacing)")
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    path = out / f"deck_wave_{name}.png"
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def sweep_plot(rows: list[dict], impedance: float, v0: float, out: Path) -> Path:
    """Peak fender force against the dock's stiffness: FE, series spring and its two limits."""
    plt = _pyplot()
    kd = np.array([r["k_dock"] for r in rows])
    order = np.argsort(kd)
    kd = kd[order]
    F = np.array([r["F_fe"] for r in rows])[order]
    m, kb = rows[0]["mass"], rows[0]["k_barge"]
    grid = np.geomspace(kd.min() / 3, kd.max() * 3, 200)
    fig, ax = plt.subplots(figsize=(9, 6))
    ax.loglog(grid, v0 * np.sqrt(m * grid * kb / (grid + kb)) / 1e6, "r-", label="series spring v0 sqrt(m k_eff)")
    ax.loglog(grid, v0 * np.sqrt(m * grid) / 1e6, "b:", label="dock-governed limit v0 sqrt(m k_d)")
    ax.axhline(v0 * np.sqrt(m * kb) / 1e6, color="g", ls=":", label="barge-governed limit v0 sqrt(m k_b)")
    ax.axhline(v0 * impedance / 1e6, color="m", ls="-.", label="hull wave impedance v0 sqrt(EA m')")
    ax.loglog(kd, F / 1e6, "ko", label="FE barge + dock (transient)")
    for r in rows:
        ax.annotate(r["case"], (r["k_dock"], r["F_fe"] / 1e6), fontsize=7, textcoords="offset points", xytext=(4, -10))
    ax.set_xlabel("dock stiffness at the fenders k_d (N/m)")
    ax.set_ylabel("peak fender force (MN)")
    ax.set_title(f"Barge impact at {v0:g} m/s: m = {m / 1e3:.0f} t, k_b = {kb:.3g} N/m")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    path = out / "impact_sweep.png"
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def sweep_csv(rows: list[dict], out: Path) -> Path:
    from liftoff.core.records import write_text

    keys = ("case", "k_fenders", "k_quay", "k_dock", "k_barge", "k_eff", "mass", "F_fe", "F_series", "ratio",
            "F_dock_limit", "F_barge_limit", "F_wave", "duration_fe", "duration_series")
    lines = ["# barge impact sweep: peak fender force vs dock stiffness; N/m, kg, N, s", ",".join(keys)]
    for r in rows:
        lines.append(",".join(r[k] if isinstance(r[k], str) else f"{r[k]:.6e}" for k in keys))
    return write_text(out / "impact_sweep.csv", "\n".join(lines) + "\n")


# ------------------------------------------------------------------ deformed-shape frames
def first_contact_steps(F: np.ndarray) -> np.ndarray:
    """The steps of the first contact of fender force history ``F``: from the first F > 0 to
    the last before F is 0 again (a barge pushed back on, or rebounding, touches again later:
    the series-spring duration and the frames are one contact's, not first to last)."""
    idx = np.flatnonzero(F > 0)
    gaps = np.flatnonzero(np.diff(idx) > 1)
    return idx[: gaps[0] + 1] if gaps.size else idx


def frame_steps(result, n: int) -> np.ndarray:
    """``n`` step indices spread over the first contact (first contact to its separation; a
    barge pushed back on touches again later, which the frames leave out)."""
    on = first_contact_steps(fender_force(result))
    if not on.size or n < 1:
        return np.zeros(0, dtype=int)
    return np.unique(np.linspace(on[0], on[-1], n).round().astype(int))


def _fields(models, result, i: int) -> list:
    """fem.snapshot.Part of the barge and the cargo at step i, elastic part (rigid-body motion removed)."""
    from liftoff.fem.snapshot import mesh_parts
    from liftoff.reduction import field_displacement

    q = result.recovered["modal_q_a"][i].copy()
    q[: models.barge_modes.n_rigid] = 0.0
    out = []
    for name in ("barge", "cargo"):
        comp = models.components[name]
        if comp.field_map is None or comp.nodes is None:
            continue
        u = field_displacement(models.barge_asm, models.barge_modes, name, comp, q)
        out += mesh_parts(comp, u.reshape(-1, 3))
    return out


def wave_frames(models, result, out: Path, name: str, n: int) -> list[Path]:
    """PNG frames of the deformed barge and cargo during the impact, one displacement scale for all,
    a montage of them (``wave_frames_<case>.png``) and an animated GIF (``wave_<case>.gif``)."""
    from liftoff.fem.snapshot import auto_scale, snapshot_png

    steps = frame_steps(result, n)
    if not steps.size:
        return []
    fields = [_fields(models, result, i) for i in steps]
    if not fields[0]:
        return []
    scale = min(auto_scale(parts, 0.04) for parts in fields)     # the largest frame sets the scale
    umax = max(float(np.linalg.norm(p.displacement, axis=1).max()) for parts in fields for p in parts)
    t0 = result.time[steps[0]]
    frames = []
    for k, (i, parts) in enumerate(zip(steps, fields)):
        frames.append(snapshot_png(out / f"wave_frame_{k + 1}_{name}.png", parts,
                                   f"{name}: t = {1e3 * (result.time[i] - t0):.1f} ms after first contact",
                                   scale, note="elastic part", window_size=(1100, 520), view="xz", elevation=25,
                                   azimuth=-20, umax=umax, zoom=1.7))
    return frames + _montage(frames, out, name)


def _montage(frames: list[Path], out: Path, name: str) -> list[Path]:
    """One PNG with the frames in a column pair, and a GIF of them (Pillow)."""
    from PIL import Image

    from liftoff.core.records import atomic_path

    imgs = [Image.open(f).convert("RGB") for f in frames]
    w, h = imgs[0].size
    cols = 2 if len(imgs) > 3 else 1
    rows = -(-len(imgs) // cols)
    sheet = Image.new("RGB", (cols * w, rows * h), "white")
    for k, im in enumerate(imgs):
        sheet.paste(im, ((k % cols) * w, (k // cols) * h))
    paths = [out / f"wave_frames_{name}.png", out / f"wave_{name}.gif"]
    with atomic_path(paths[0], suffix=".png") as tmp:
        sheet.save(tmp)
    with atomic_path(paths[1], suffix=".gif") as tmp:
        imgs[0].save(tmp, save_all=True, append_images=imgs[1:], duration=400, loop=0)
    return paths


# ------------------------------------------------------------------ summary
def summary(scenario, models, rows: list[dict], stage_times: list, impedance: float, wall: float) -> str:
    """Printed and written summary: models, the sweep table with the series-spring estimate, times."""
    b = models.barge
    lines = [f"liftoff run (barge): {scenario.title}",
             f"  barge + cargo {b.n_modes} modes ({np.sum(b.omega > 0)} elastic, first "
             f"{b.omega[6] / 2 / np.pi:.2f} Hz), mass {b.mass / 1e3:.1f} t; dock {models.dock.n_modes} modes "
             f"(first {models.dock.omega[0] / 2 / np.pi:.2f} Hz)",
             f"  barge stiffness at the bow k_b = {rows[0]['k_barge']:.4g} N/m, quay at the fenders "
             f"k_quay = {rows[0]['k_quay']:.4g} N/m, hull wave impedance sqrt(EA m') = {impedance:.4g} N s/m",
             f"  {'case':<12}{'k_dock (N/m)':>14}{'k_d/k_b':>9}{'F FE (MN)':>11}{'F series':>10}{'FE/series':>10}"
             f"{'cargo |F| (kN)':>15}{'deck acc (m/s2)':>16}  governed by"]
    for r in rows:
        gov = "dock" if r["k_dock"] < 0.3 * r["k_barge"] else ("barge" if r["k_dock"] > 3 * r["k_barge"] else "both")
        lines.append(f"  {r['case']:<12}{r['k_dock']:>14.4g}{r['k_dock'] / r['k_barge']:>9.3g}{r['F_fe'] / 1e6:>11.4g}"
                     f"{r['F_series'] / 1e6:>10.4g}{r['ratio']:>10.4f}{r['cargo_peak'] / 1e3:>15.4g}"
                     f"{r['deck_acc_peak']:>16.4g}  {gov}")
    lines += truncation_lines(models.truncation)
    lines += stage_time_lines(stage_times, wall)
    return "\n".join(lines)
