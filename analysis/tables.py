"""Max/min tables of a run's histories (issue 24: moved from workflows/report.py): one
:class:`Item` per recovered history, the max/min rows of a case (:func:`maxmin`), their
envelope over cases (:func:`envelope`), the CSV file (:func:`write_csv`, SI units stated),
the fixed-width text the run prints, and the points a long history is drawn with
(:func:`display_points`). numpy only; no result type is imported (duck-typed).
"""
from __future__ import annotations

import csv
import io
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from liftoff.core.records import write_text


@dataclass
class Item:
    """One recovered time history (one column) of one case; ``category``: contact_force,
    displacement, acceleration, or the category of the recovery it comes from."""

    name: str
    unit: str
    values: np.ndarray
    category: str = ""
    raw: np.ndarray | None = None      # the unfiltered history where ``values`` is band-limited

    @property
    def history(self) -> np.ndarray:
        """The unfiltered history (spectra are taken of it)."""
        return self.values if self.raw is None else self.raw


def maxmin(time: np.ndarray, its: list[Item], case: str) -> list[dict]:
    rows = []
    for it in its:
        i, k = int(np.argmax(it.values)), int(np.argmin(it.values))
        rows.append({"item": it.name, "unit": it.unit, "max": float(it.values[i]), "t_max": float(time[i]),
                     "case_max": case, "min": float(it.values[k]), "t_min": float(time[k]), "case_min": case,
                     "category": it.category})
    return rows


def envelope(per_case: dict[str, list[dict]]) -> list[dict]:
    """Max of the maxima and min of the minima over cases, with the case (and the estimated
    error, :func:`with_errors`) of each."""
    env: dict[str, dict] = {}
    for rows in per_case.values():
        for r in rows:
            e = env.get(r["item"])
            if e is None:
                env[r["item"]] = dict(r)
                continue
            if r["max"] > e["max"]:
                e.update(max=r["max"], t_max=r["t_max"], case_max=r["case_max"], max_err=r.get("max_err", NAN))
            if r["min"] < e["min"]:
                e.update(min=r["min"], t_min=r["t_min"], case_min=r["case_min"], min_err=r.get("min_err", NAN))
    return list(env.values())


NAN = float("nan")


FIELDS = ("item", "unit", "max", "max_err_est", "t_max", "case_max", "min", "min_err_est", "t_min", "case_min")


_KEYS = {"max_err_est": "max_err", "min_err_est": "min_err"}


CSV_HEADER = ("# liftoff max/min table; SI units (column 'unit'); times in s; max_err_est, min_err_est: estimated "
              "error of the value (true - reported, Richardson from a second run at h/2; an estimate, not a bound; "
              "empty when not estimated); 'acc' rows (output-point accelerations) and rows recovered from the "
              "accelerations alone (liquid and tank pressures, liquid inertia forces): low-pass filtered to the "
              "scenario's [postprocess] acceleration_band_hz (summary.txt states it; 0: unfiltered)\n")


def _cell(value) -> str:
    if isinstance(value, float):
        return "" if value != value else f"{value:.6e}"
    return value


def write_csv(rows: list[dict], path: Path) -> Path:
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=FIELDS)
    w.writeheader()
    for r in rows:
        w.writerow({k: _cell(r.get(_KEYS.get(k, k), NAN)) for k in FIELDS})
    write_text(path, CSV_HEADER + buf.getvalue())
    return path


def is_force(row: dict) -> bool:
    """A max/min row of a post or attach force (N; moments, N m, excluded)."""
    return row.get("category") in ("contact_force", "interface_force") and row["unit"] == "N"


def format_table(rows: list[dict], select=None, limit: int = 60) -> str:
    """Fixed-width text of max/min rows; ``select(row)`` filters them."""
    sel = [r for r in rows if select is None or select(r)][:limit]
    w = max([len(r["item"]) for r in sel] + [10])
    lines = [f"{'item':<{w}} {'unit':>7} {'max':>12} {'est.err':>9} {'t (s)':>8} {'case':>12} "
             f"{'min':>12} {'est.err':>9} {'t (s)':>8} {'case':>12}"]
    for r in sel:
        lines.append(f"{r['item']:<{w}} {r['unit']:>7} {r['max']:12.4e} {_err(r.get('max_err')):>9} "
                     f"{r['t_max']:8.4f} {r['case_max']:>12} {r['min']:12.4e} {_err(r.get('min_err')):>9} "
                     f"{r['t_min']:8.4f} {r['case_min']:>12}")
    return "\n".join(lines)


def _err(value) -> str:
    """An estimated error as |value| (3 digits), '-' when not estimated."""
    return "-" if value is None or value != value else f"{abs(value):.2e}"


#: bins of a drawn time history: a longer history is drawn through the samples where each
#: bin has its minimum and maximum, in time order (a 10^5-step run draws 4,000 points a line,
#: fewer than the pixels of a panel: every peak is drawn where and as computed)
DISPLAY_BINS = 2000


def display_points(x: np.ndarray, y: np.ndarray, bins: int = DISPLAY_BINS) -> tuple[np.ndarray, np.ndarray]:
    """(x, y) to draw: every sample of a short history; of a long one the first and last
    samples and, in each of ``bins`` equal runs of samples, those at its minimum and
    maximum, in time order."""
    x, y = np.asarray(x), np.asarray(y)
    n = y.size
    if n <= 2 * bins:
        return x, y
    m = -(-n // bins)                        # samples a run (the last one padded with its own end)
    runs = -(-n // m)
    padded = np.concatenate([y, np.full(runs * m - n, y[-1])]).reshape(runs, m)
    finite = np.where(np.isfinite(padded), padded, 0.0)
    base = np.arange(runs) * m
    idx = np.concatenate([[0, n - 1], base + np.argmin(finite, axis=1), base + np.argmax(finite, axis=1)])
    idx = np.unique(np.minimum(idx, n - 1))
    return x[idx], y[idx]


def format_changes(rows: list[dict], limit: int = 12) -> str:
    """The force items with the largest percent changes against an earlier run."""
    sel = [r for r in rows if is_force(r) and r.get("status", "both") == "both"]
    only_old = sum(r.get("status") == "only in the earlier run" for r in rows)
    only_new = sum(r.get("status") == "only in this run" for r in rows)

    def change(r, side: str) -> float:     # a load from nothing (old 0: no percentage) ranks first, not last
        pct = r[f"{side}_change_pct"]
        if np.isfinite(pct):
            return abs(pct)
        return np.inf if np.isfinite(r[side]) and r[side] != 0 and r.get(f"{side}_old") == 0 else 0.0

    big = sorted(sel, key=lambda r: -max(change(r, "max"), change(r, "min")))
    w = max([len(r["item"]) for r in big[:limit]] + [10])
    alone = (f"; {only_old} only in the earlier run, {only_new} only in this one" if only_old or only_new else "")
    lines = [f"Largest changes against the earlier run ({len(rows) - only_old - only_new} items compared{alone}, "
             "compare.csv):",
             f"{'item':<{w}} {'max':>12} {'old':>12} {'%':>8} {'min':>12} {'old':>12} {'%':>8}"]
    for r in big[:limit]:
        lines.append(f"{r['item']:<{w}} {r['max']:12.4e} {r['max_old']:12.4e} {r['max_change_pct']:8.2f} "
                     f"{r['min']:12.4e} {r['min_old']:12.4e} {r['min_change_pct']:8.2f}")
    return "\n".join(lines)
