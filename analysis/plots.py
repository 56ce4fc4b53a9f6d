"""Plots of a run (issue 24: moved from workflows/report.py): the time histories of each
case (the whole run and the release window, engine starts and the release marked, legends
outside the data), tank pressures and ullage volumes, correlated loads and their campaign
contours, SRS and PSD. matplotlib on the Agg backend (files only); SI units on every axis.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from liftoff.core.labels import TRANSLATIONS, point_labels

from .histories import G0, _translations, items, liquid_heads, tank_items, twang
from .tables import display_points


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


RELEASE_WINDOW = (-0.05, 0.45)   # s about the first release: the zoom panel of the plots


def _pyplot():
    """matplotlib.pyplot on the Agg backend (files only, no display)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _save_figure(plt, fig, path: Path, legend_from=None, top: float = 0.97, dpi: int = 110,
                 right: float = 0.84) -> Path:
    """Lay out (:func:`_fixed_layout`, below the title in the top ``1 - top`` of the figure),
    save and close a figure; with ``legend_from`` (an axes), that axes' legend right of the
    panels (which then end at ``right``), outside the data."""
    handles, labs = legend_from.get_legend_handles_labels() if legend_from is not None else ([], [])
    _fixed_layout(fig, top, right if handles else None)
    if handles:
        fig.legend(handles, labs, fontsize=7, loc="center left", bbox_to_anchor=(right + 0.015, 0.5), frameon=False)
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path


_PT = 1.0 / 72.0         # inch
_TICK_LABEL_WIDTH = 0.55  # inch: a y tick label of up to 7 characters at 10 pt ("-0.0025", "10^-5")


def _fixed_layout(fig, top: float, right: float | None = None) -> None:
    """Margins and gaps in inches from what the panels show (labels, their lines and font
    sizes, tick labels, titles), on a regular grid of panels: the layout matplotlib's
    ``tight_layout`` finds, without its measuring pass over every tick label. That pass
    drew each figure once more before saving it: 7.3 s for the four log-log and grid
    figures of a warm default run (2026-11-27). ``right``: the panels end there (a fraction
    of the width; a legend goes right of them), else 0.2 inch from the edge. Panels off a
    regular grid (a twin or colour-bar axes) are not measured."""
    from matplotlib import rcParams

    axes = [ax for ax in fig.axes if ax.get_visible() and ax.get_subplotspec() is not None]
    if not axes:
        return
    W, H = fig.get_size_inches()
    nrows, ncols = axes[0].get_subplotspec().get_gridspec().get_geometry()
    fs = rcParams["font.size"]

    def text_h(text) -> float:          # a label's or title's height with its pad, inch
        s = text.get_text()
        return (s.count("\n") + 1) * 1.25 * text.get_fontsize() * _PT + 4 * _PT if s else 0.0

    def x_band(ax) -> float:            # below a panel: tick labels and x label
        return (1.4 * fs * _PT if ax.xaxis.get_tick_params().get("labelbottom", True) else 0.0) + text_h(ax.xaxis.label)

    def y_band(ax) -> float:            # left of a panel: tick labels and y label
        return (_TICK_LABEL_WIDTH if ax.yaxis.get_tick_params().get("labelleft", True) else 0.0) + text_h(ax.yaxis.label)

    def rows(ax):
        return ax.get_subplotspec().rowspan

    def cols(ax):
        return ax.get_subplotspec().colspan

    title = [max((text_h(ax.title) for ax in axes if rows(ax).start == r), default=0.0) for r in range(nrows)]
    left = 0.12 + max((y_band(ax) for ax in axes if cols(ax).start == 0), default=0.0)
    bottom = 0.1 + max((x_band(ax) for ax in axes if rows(ax).stop == nrows), default=0.0)
    top_in = max((1.0 - top) * H, 0.5 if fig._suptitle is not None else 0.1) + title[0]
    h_gap = 0.2 + max((x_band(ax) for ax in axes if rows(ax).stop < nrows), default=0.0) + max(title[1:], default=0.0)
    w_gap = 0.2 + max((y_band(ax) for ax in axes if cols(ax).start > 0), default=0.0)
    right_in = 0.2 if right is None else (1.0 - right) * W
    ax_h = (H - top_in - bottom - (nrows - 1) * h_gap) / nrows
    ax_w = (W - left - right_in - (ncols - 1) * w_gap) / ncols
    if ax_h <= 0.2 or ax_w <= 0.2:      # too small a figure for its labels: matplotlib's defaults
        if right is not None:
            fig.subplots_adjust(right=right)
        return
    fig.subplots_adjust(left=left / W, right=1.0 - right_in / W, bottom=bottom / H, top=1.0 - top_in / H,
                        hspace=h_gap / ax_h, wspace=w_gap / ax_w)


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
