"""The plots' fixed layout (analysis/plots._fixed_layout, issue 28): margins and gaps from what
the panels show, without matplotlib's measuring pass. Checked on the layouts the run draws
(a grid of panels each with its own labels and title, as srs.png and correlated_loads.png;
shared axes with two-line y labels and a release-window title, as the history plots; one
log-log panel with a legend right of it, as psd_<case>.png), by drawing them and measuring
what tight_layout would have measured: no panel's decorations (tick labels, labels, title)
overlap another panel's or the figure title, and all lie inside the figure."""
from __future__ import annotations

import numpy as np
import pytest

from liftoff.analysis.plots import _fixed_layout, _pyplot


def _boxes(fig):
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    axes = [ax for ax in fig.axes if ax.get_visible()]
    return r, axes, [ax.get_tightbbox(r) for ax in axes]


def _check(fig):
    r, axes, boxes = _boxes(fig)
    W, H = fig.bbox.width, fig.bbox.height
    for b in boxes:                                   # inside the figure (1 px of rounding)
        assert b.x0 >= -1 and b.y0 >= -1 and b.x1 <= W + 1 and b.y1 <= H + 1, b
    for i in range(len(boxes)):
        for j in range(i + 1, len(boxes)):
            assert not boxes[i].overlaps(boxes[j]), (i, j, boxes[i], boxes[j])
    if fig._suptitle is not None:
        st = fig._suptitle.get_window_extent(r)
        for b in boxes:
            assert not st.overlaps(b)


def test_a_grid_of_labelled_log_panels():
    plt = _pyplot()
    fig, axs = plt.subplots(3, 2, figsize=(11, 2.8 * 3 + 1), squeeze=False)
    f = np.logspace(0, 1.7, 60)
    for k, ax in enumerate(axs.flat):
        ax.loglog(f, 1e-3 * f ** (k % 3), label="Q = 10")
        ax.set_title(f"acc stack_top:T{'xyz'[k % 3]}", fontsize=8)
        ax.set_xlabel("frequency (Hz)", fontsize=8)
        ax.set_ylabel("SRS (m/s^2)", fontsize=8)
    fig.suptitle("Shock response spectra, absolute acceleration, envelope over the cases")
    _fixed_layout(fig, 0.97)
    _check(fig)
    plt.close(fig)


def test_shared_panels_with_two_line_labels():
    plt = _pyplot()
    fig, axs = plt.subplots(3, 2, figsize=(14, 2.6 * 3 + 1), squeeze=False, sharex="col", sharey="row",
                            gridspec_kw={"width_ratios": [2, 1]})
    t = np.linspace(0, 9.6, 500)
    for r in range(3):
        for ax in axs[r]:
            ax.plot(t, -18.2e6 * np.sin(t) / 1e6)
        axs[r][0].set_ylabel("axial force on vehicle (MN)\n(+ compression)")
    axs[0][1].set_title("release window (6.55 to 7.05 s)", fontsize=8)
    for ax in axs[-1]:
        ax.set_xlabel("time (s)")
    fig.suptitle("Hold-down post forces — case nominal")
    _fixed_layout(fig, 0.97)
    _check(fig)
    plt.close(fig)


def test_too_small_a_figure_keeps_matplotlibs_defaults():
    plt = _pyplot()
    fig, axs = plt.subplots(6, 1, figsize=(3, 2))
    before = fig.subplotpars.top, fig.subplotpars.hspace
    _fixed_layout(fig, 0.97)
    assert (fig.subplotpars.top, fig.subplotpars.hspace) == pytest.approx(before)
    plt.close(fig)


def test_a_grid_with_a_legend_right_of_it():
    """correlated_loads.png's layout: labelled panels ending at ``right``, the legend beside
    them (analysis/plots._save_figure): the gaps are measured with the panels' final width."""
    plt = _pyplot()
    fig, axs = plt.subplots(4, 2, figsize=(10, 2.6 * 4 + 1), squeeze=False)
    for ax in axs.flat:
        ax.plot([-18.2, 11.5], [0.0, 150.0], label="nominal")
        ax.set_xlabel("Tz (MN)", fontsize=8)
        ax.set_ylabel("Mb (MN m)", fontsize=8)
        ax.set_title("att_srb_left_fwd", fontsize=8)
    fig.suptitle("Correlated loads")
    _fixed_layout(fig, 0.98, 0.84)
    assert fig.subplotpars.right == pytest.approx(0.84)
    _check(fig)
    plt.close(fig)
