"""Envelopes and statistics over the cases of a run, fed one case summary at a time.

* the envelope (max of the maxima, min of the minima, each with its time and case) over
  every case, named and generated (the first case fed wins a tie, and cases are fed in a
  fixed order: named cases, then generated ones by index);
* over the generated (dispersed) cases: mean and std of each item's maxima and minima,
  the P99/90 normal tolerance bounds mean + k std and mean - k std (k :func:`.stats.k_factor`),
  and the distribution-free P99/90 order statistic (:func:`.stats.order_rank`), as pyyeti's
  cla computes them;
* the SRS of the selected items: envelope over cases with the case of each point, and
  the same statistics per Q and frequency.

Memory is O(items x r + SRS points), whatever the number of cases. Files: CSV for people,
HDF5 (format ``liftoff-statistics``) for programs; SI units per item.
"""
from __future__ import annotations

import csv
import io
from pathlib import Path

import numpy as np

from liftoff.core.errors import InputError
from liftoff.core.records import Dataset, write_record, write_text

from . import interface_loads
from .stats import P99_90, Largest, Running, k_factor, order_rank


class Aggregate:
    """Streaming envelope and statistics; ``n_stat``: the number of generated cases that
    will be fed (it fixes the order statistic's rank)."""

    def __init__(self, n_stat: int, p: float = P99_90[0], c: float = P99_90[1]):
        self.p, self.c, self.n_stat = p, c, n_stat
        self.k = k_factor(p, c, n_stat)
        self.r = order_rank(p, c, n_stat)
        self.items: tuple | None = None
        self.case_names: list[str] = []                 # generated cases fed, in order (index -> name)
        #: time-consistent interface loads (analysis.interface_loads): the envelope over every case
        #: fed that carries them (each summary's rows), and the names of the cases that did not
        self.consistent: list[dict] = []
        self.consistent_missing: list[str] = []

    def _init(self, s) -> None:
        self.items, self.units, self.categories = s.items, s.units, s.categories
        n = len(s.items)
        self.mx, self.mn = np.full(n, -np.inf), np.full(n, np.inf)
        self.t_mx, self.t_mn = np.zeros(n), np.zeros(n)
        self.c_mx, self.c_mn = [""] * n, [""] * n
        self.e_mx, self.e_mn = np.full(n, np.nan), np.full(n, np.nan)     # estimated errors of the envelope
        # the envelope of the named (not generated) cases alone, and its cases: a design basis
        # below a named case's load would leave out a load the run computed (write_design)
        self.named_mx, self.named_mn = np.full(n, -np.inf), np.full(n, np.inf)
        self.named_c_mx, self.named_c_mn = [""] * n, [""] * n
        self.run_mx, self.run_mn = Running(n), Running(n)
        self.top_mx, self.top_mn = Largest(n, self.r), Largest(n, self.r)
        self.srs_items = s.srs_items
        # correlated loads (analysis.correlated): the support functions' envelope over every
        # case and, over the generated ones, their statistics per direction
        self.support_items = s.support_items
        if s.support is not None:
            self.support_env = np.full(np.shape(s.support), -np.inf)
            self.support_run = Running(np.shape(s.support))
            self.support_top = Largest(int(np.size(s.support)), self.r)
        else:
            self.support_env = None
        if s.srs is not None:
            self.srs_env = np.full(s.srs.shape, -np.inf)
            self.srs_case = np.full(s.srs.shape, "", dtype=object)
            self.srs_run = Running(s.srs.shape)
        else:
            self.srs_env = None

    def add(self, s, generated: bool) -> None:
        """Feed one :class:`~.campaign.CaseSummary`."""
        if self.items is None:
            self._init(s)
        if s.items != self.items or s.srs_items != self.srs_items or s.support_items != self.support_items \
                or np.shape(s.support) != np.shape(self.support_env):        # np.shape(None): ()
            raise InputError(f"case {s.name}: its recovery items differ from those of the first case")
        if getattr(s, "consistent", None) is not None:
            self.consistent = interface_loads.envelope([self.consistent, interface_loads.from_arrays(s.consistent,
                                                                                                      s.name)])
        else:
            self.consistent_missing.append(s.name)
        up = s.mx > self.mx
        self.mx[up], self.t_mx[up] = s.mx[up], s.t_mx[up]
        self.e_mx[up] = s.err_mx[up] if s.err_mx is not None else np.nan
        for j in np.flatnonzero(up):
            self.c_mx[j] = s.name
        dn = s.mn < self.mn
        self.mn[dn], self.t_mn[dn] = s.mn[dn], s.t_mn[dn]
        self.e_mn[dn] = s.err_mn[dn] if s.err_mn is not None else np.nan
        for j in np.flatnonzero(dn):
            self.c_mn[j] = s.name
        if self.srs_env is not None and s.srs is not None:
            better = s.srs > self.srs_env
            self.srs_env[better] = s.srs[better]
            self.srs_case[better] = s.name
        if self.support_env is not None:
            np.maximum(self.support_env, s.support, out=self.support_env)
        if not generated:
            for mine, cases, vals, up in ((self.named_mx, self.named_c_mx, s.mx, s.mx > self.named_mx),
                                          (self.named_mn, self.named_c_mn, s.mn, s.mn < self.named_mn)):
                mine[up] = vals[up]
                for j in np.flatnonzero(up):
                    cases[j] = s.name
        else:
            k = len(self.case_names)
            self.case_names.append(s.name)
            self.run_mx.add(s.mx)
            self.run_mn.add(s.mn)
            self.top_mx.add(s.mx, k)
            self.top_mn.add(-s.mn, k)
            if self.srs_env is not None and s.srs is not None:
                self.srs_run.add(s.srs)
            if self.support_env is not None:
                self.support_run.add(s.support)
                self.support_top.add(np.ravel(s.support), k)

    # ------------------------------------------------------------ tables
    def envelope_rows(self) -> list[dict]:
        """Rows of the max/min envelope (report.write_csv layout)."""
        return [{"item": it, "unit": u, "max": float(self.mx[j]), "t_max": float(self.t_mx[j]),
                 "case_max": self.c_mx[j], "min": float(self.mn[j]), "t_min": float(self.t_mn[j]),
                 "case_min": self.c_mn[j], "category": cat, "max_err": float(self.e_mx[j]),
                 "min_err": float(self.e_mn[j])}
                for j, (it, u, cat) in enumerate(zip(self.items, self.units, self.categories))]

    @property
    def n(self) -> int:
        return self.run_mx.n if self.items is not None else 0

    def statistics(self) -> dict:
        """Arrays per item over the generated cases: mean/std of maxima and minima, P99/90
        normal bounds, order-statistic bounds and their cases."""
        omx, cmx = self.top_mx.rth()
        omn, cmn = self.top_mn.rth()
        name = lambda c: self.case_names[c] if c >= 0 else ""  # noqa: E731
        return {"mean_max": self.run_mx.mean, "std_max": self.run_mx.std, "normal_max": self.run_mx.bound(self.k),
                "order_max": omx, "order_case_max": [name(c) for c in cmx],
                "mean_min": self.run_mn.mean, "std_min": self.run_mn.std, "normal_min": self.run_mn.bound(-self.k),
                "order_min": -omn, "order_case_min": [name(c) for c in cmn]}


    def support_statistics(self) -> dict:
        """Per correlated-load pair and direction (analysis.correlated): the support
        functions' envelope over every case, and over the generated cases the P/C normal
        bound mean + k std and the order-statistic bound (the r-th largest; NaN if too few
        cases), each (n_support_items, n_directions)."""
        order = self.support_top.rth()[0].reshape(self.support_env.shape)
        return {"envelope": self.support_env.copy(), "normal": self.support_run.bound(self.k), "order": order}


STAT_FIELDS = ("item", "unit", "category", "mean_max", "std_max", "normal_max", "order_max", "order_case_max",
               "mean_min", "std_min", "normal_min", "order_min", "order_case_min")


def write_rows_csv(rows: list[dict], fields, head: str, path: Path, digits: int = 7) -> Path:
    """Dict rows as a CSV table under the comment ``head`` (floats to ``digits`` significant
    digits, %.6e by default), atomically."""
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=list(fields), extrasaction="ignore")
    w.writeheader()
    fmt = f".{digits - 1}e"
    for r in rows:
        w.writerow({k: (format(v, fmt) if isinstance(v, float) else v) for k, v in r.items()})
    return write_text(path, head + buf.getvalue())


def write_statistics(agg: Aggregate, out: Path, freq=None, q=None) -> list[Path]:
    """statistics.csv and statistics.h5 over the generated cases."""
    st = agg.statistics()
    rows = [{"item": it, "unit": u, "category": cat, **{k: (v[j] if isinstance(v, list) else float(v[j]))
                                                      for k, v in st.items()}}
            for j, (it, u, cat) in enumerate(zip(agg.items, agg.units, agg.categories))]
    head = (f"# liftoff statistics over {agg.n} dispersed cases; SI units (column 'unit'); "
            f"P{agg.p * 100:g}/{agg.c * 100:g}: normal bound mean +- k std with k = {agg.k:.6g} (one-sided "
            "tolerance factor), order statistic = " + (
                f"the {agg.r}-th largest maximum / smallest minimum (distribution-free)" if agg.r else
                f"none (too few cases for a distribution-free P{agg.p * 100:g}/{agg.c * 100:g} bound; its columns NaN)")
            + "\n")
    paths = [write_rows_csv(rows, STAT_FIELDS, head, out / "statistics.csv")]
    data = {"items": np.array(agg.items, dtype=str),
            "units": Dataset(np.array(agg.units, dtype=str), "1", dims=("items",)),
            "categories": Dataset(np.array(agg.categories, dtype=str), "1", dims=("items",))}
    for key, v in st.items():
        data[key] = Dataset(np.array(v, dtype=str) if isinstance(v, list) else v, "per item (see units)",
                            dims=("items",))
    if agg.srs_env is not None and agg.srs_run.n:
        # its own dimensions (Q x frequency x SRS item), each a labelled scale with units, so that
        # xarray opens the group beside the root's 'items' (issue 24: the group reused 'items')
        units = [agg.units[agg.items.index(it)] for it in agg.srs_items]
        unit = units[0] if len(set(units)) == 1 else "per item (srs_units)"
        dims = ("q", "freq_Hz", "srs_items")
        nq, nf, _ = np.shape(agg.srs_env)
        qv = np.asarray(q if q is not None else np.arange(nq), float)
        fv = np.asarray(freq if freq is not None else np.arange(nf), float)
        data["srs"] = {"srs_items": np.array(agg.srs_items, dtype=str),          # the scales themselves
                       "srs_units": Dataset(np.array(units, dtype=str), "1", dims=("srs_items",)),
                       "q": Dataset(qv, "1 (quality factor Q)" if q is not None else "index"),
                       "freq_Hz": Dataset(fv, "Hz" if freq is not None else "index"),
                       **{k: Dataset(v, unit, dims=dims, description=d) for k, v, d in (
                           ("envelope", agg.srs_env, "SRS envelope over every case (absolute-acceleration SRS in each item's units: its history the oscillators' base input)"),
                           ("mean", agg.srs_run.mean, "mean over the dispersed cases"),
                           ("std", agg.srs_run.std, "standard deviation over the dispersed cases"),
                           ("normal", agg.srs_run.bound(agg.k), "normal P/C bound, mean + k std"))}}
    paths.append(write_record(out / "statistics.h5", "liftoff-statistics", 1, data, units="SI per item",
                              attrs={"n_cases": agg.n, "p": agg.p, "c": agg.c, "k": agg.k, "r": agg.r}))
    return paths


CONTOUR_FIELDS = ("interface", "pair", "contour", "vertex", "x_name", "x", "x_unit", "y_name", "y", "y_unit")


def contour_rows(agg: Aggregate) -> list[dict]:
    """The rows of correlated_statistics.csv: per interface and pair (analysis.correlated) the
    polygons of the support functions' envelope over every case and of their P/C normal and
    order-statistic bounds over the generated cases, vertices counter-clockwise."""
    from .correlated import PAIRS, contour

    if agg.support_env is None or agg.n < 2:
        return []
    names = {pair: (xn, yn) for pair, xn, yn in PAIRS}
    rows = []
    for kind, h in agg.support_statistics().items():
        for j, item in enumerate(agg.support_items):
            interface, _, pair = item.rpartition("|")
            if not np.all(np.isfinite(h[j])):
                continue                       # too few cases for the order statistic
            x, y = contour(h[j])
            xn, yn = names.get(pair, ("x", "y"))
            rows += [{"interface": interface, "pair": pair, "contour": kind, "vertex": v + 1, "x_name": xn,
                      "x": float(x[v]), "x_unit": "N", "y_name": yn, "y": float(y[v]), "y_unit": "N m"}
                     for v in range(x.size)]
    return rows


def write_contours(agg: Aggregate, out: Path) -> Path | None:
    """correlated_statistics.csv (:func:`contour_rows`); None without correlated loads or
    with fewer than two generated cases."""
    from .correlated import MOMENT_ARM, N_DIRECTIONS

    rows = contour_rows(agg)
    if not rows:
        return None
    head = (f"# liftoff correlated-load contours over {agg.n} dispersed cases (and the envelope over every case): "
            "per attach point (force on the named component) and pair, the polygon {p : n_k . p <= h_k} of the "
            f"support functions h_k = max over time of n_k . (x, y / {MOMENT_ARM:g} m) in {N_DIRECTIONS} directions; "
            f"contour = envelope (max over every case), normal (P{agg.p * 100:g}/{agg.c * 100:g} bound mean + k std, "
            f"k = {agg.k:.6g}) or order (" + (f"the {agg.r}-th largest over the dispersed cases" if agg.r else
                                              "none: too few cases for a distribution-free bound")
            + "); each direction's bound "
            "holds alone, not jointly; vertices counter-clockwise; units in x_unit, y_unit\n")
    return write_rows_csv(rows, CONTOUR_FIELDS, head, out / "correlated_statistics.csv")


def write_srs(agg: Aggregate, freq: np.ndarray, q: tuple, out: Path) -> Path | None:
    """srs.csv: per item, Q and frequency the envelope over every case (and its case) and,
    over the generated cases, mean, std and P99/90 normal bound."""
    if agg.srs_env is None:
        return None
    stats = agg.srs_run.n >= 2
    rows = []
    for iq, qv in enumerate(q):
        for j, it in enumerate(agg.srs_items):
            unit = agg.units[agg.items.index(it)]
            for k, f in enumerate(freq):
                r = {"item": it, "unit": unit, "Q": float(qv), "freq_Hz": float(f), "envelope": float(agg.srs_env[iq, k, j]),
                     "case": agg.srs_case[iq, k, j]}
                if stats:
                    r.update(mean=float(agg.srs_run.mean[iq, k, j]), std=float(agg.srs_run.std[iq, k, j]),
                             normal_P9990=float(agg.srs_run.bound(agg.k)[iq, k, j]))
                rows.append(r)
    fields = ["item", "unit", "Q", "freq_Hz", "envelope", "case"] + (["mean", "std", "normal_P9990"] if stats else [])
    head = ("# liftoff shock response spectra (absolute acceleration, peak; oscillators initially steady under each "
            "history's first value) of the items' histories; units of the "
            f"item; envelope over all cases{'; statistics over the dispersed cases' if stats else ''}\n")
    return write_rows_csv(rows, fields, head, out / "srs.csv")


def design_basis(agg: Aggregate) -> tuple[np.ndarray, np.ndarray, list[str], list[str]]:
    """(max, min, basis of each max, basis of each min) per item: over >= 2 dispersed cases
    the P99/90 normal bound, or the named cases' envelope where it lies beyond it (a named
    case, e.g. an off-nominal one, is not of the dispersed population, and a design load below
    a named case's load would be wrong without a word; a dispersed case may lie beyond the
    bound, about 1 % of them by its definition); else the envelope over every case."""
    if agg.n < 2:
        return agg.mx.copy(), agg.mn.copy(), ["envelope"] * len(agg.items), ["envelope"] * len(agg.items)
    st = agg.statistics()
    mx, mn = np.array(st["normal_max"], dtype=float), np.array(st["normal_min"], dtype=float)
    b_mx, b_mn = ["P99/90 normal"] * mx.size, ["P99/90 normal"] * mn.size
    for j in np.flatnonzero(agg.named_mx > mx):
        mx[j], b_mx[j] = agg.named_mx[j], f"case {agg.named_c_mx[j]}"
    for j in np.flatnonzero(agg.named_mn < mn):
        mn[j], b_mn[j] = agg.named_mn[j], f"case {agg.named_c_mn[j]}"
    return mx, mn, b_mx, b_mn


def factored_outward(mx: float, mn: float, f: float) -> tuple[float, float]:
    """The range [mn, mx] widened by the uncertainty factor f >= 1: max + (f - 1)|max| and
    min - (f - 1)|min|. Where max > 0 and min < 0 it is f x each; a bound on the other side of
    zero (a compression-only item's max < 0, a shear that never reverses: its min > 0) moves
    toward zero, not away: f x max would then move it inside the computed range."""
    return float(mx + (f - 1.0) * abs(mx)), float(mn - (f - 1.0) * abs(mn))


def write_design(agg: Aggregate, factors: dict, out: Path) -> Path | None:
    """design_loads.csv: per item of a category with an uncertainty factor, the basis
    (:func:`design_basis`: P99/90 normal bound over >= 2 dispersed cases or a named case's load
    beyond it, else the envelope) times the factor; which basis each side took."""
    if not factors:
        return None
    mx, mn, b_mx, b_mn = design_basis(agg)
    rows = []
    for j, (it, u, cat) in enumerate(zip(agg.items, agg.units, agg.categories)):
        if cat not in factors:
            continue
        f = factors[cat]
        d_mx, d_mn = factored_outward(mx[j], mn[j], f)
        rows.append({"item": it, "unit": u, "category": cat, "basis_max": b_mx[j], "basis_min": b_mn[j],
                     "max": float(mx[j]), "min": float(mn[j]), "factor": float(f), "design_max": d_mx,
                     "design_min": d_mn})
    head = ("# liftoff design loads: the basis widened outward by the uncertainty factor f of the item's category "
            "(design_max = max + (f - 1) |max|, design_min = min - (f - 1) |min|: f x the bound where it lies on its "
            "own side of zero, so the design range always holds the basis); basis: the P99/90 normal bound "
            "over the dispersed cases, or a named case's load where it lies beyond it (basis_max, basis_min name it), "
            "or the envelope over every case with fewer than 2 dispersed cases; SI units (column 'unit')\n")
    return write_rows_csv(rows, ("item", "unit", "category", "basis_max", "basis_min", "max", "min", "factor",
                                 "design_max", "design_min"), head, out / "design_loads.csv")


def read_maxmin(path: Path) -> dict[str, dict]:
    """Rows of a max/min CSV written by liftoff (or a run folder's maxmin_envelope.csv) by item."""
    path = Path(path)
    if path.is_dir():
        path = path / "maxmin_envelope.csv"
    if not path.is_file():
        raise InputError(f"--compare {str(path)!r}: no such max/min table")
    try:
        lines = [ln for ln in path.read_text(encoding="utf-8").splitlines() if ln and not ln.startswith("#")]
        rows = {r["item"]: {"max": float(r["max"]), "min": float(r["min"]), "unit": r.get("unit", ""),
                            "case_max": r.get("case_max") or "", "case_min": r.get("case_min") or ""}
                for r in csv.DictReader(lines)}
    except UnicodeDecodeError:
        raise InputError(f"--compare {str(path)!r}: not a text file (a liftoff max/min CSV is)") from None
    except OSError as exc:
        raise InputError(f"--compare {str(path)!r}: cannot be read ({exc.strerror or exc})") from None
    except (KeyError, ValueError, TypeError) as exc:
        raise InputError(f"--compare {str(path)!r}: not a liftoff max/min table ({exc})") from None
    if not rows:
        raise InputError(f"--compare {str(path)!r}: holds no max/min rows")
    return rows


def pct_change(new: float, old: float) -> float:
    """(new - old) / |old| in percent (pyyeti rptpct's 'percent difference'); NaN when old is 0."""
    return (new - old) / abs(old) * 100.0 if old != 0 else (0.0 if new == 0 else float("nan"))


def cases_of(rows) -> list[str]:
    """The cases named in max/min rows' case_max and case_min columns, in order of appearance
    (the cases that set an envelope's values)."""
    return list(dict.fromkeys(c for r in rows for c in (r.get("case_max"), r.get("case_min")) if c))


def write_compare(rows_new: list[dict], old: dict, out: Path) -> tuple[Path, list[dict]]:
    """compare.csv: max and min of every item against an earlier run's, with % change and the
    case of each side; an item in one run only has a row too (its other side empty, status
    'only in this run' or 'only in the earlier run': a load path removed or added is not a
    missing row). The header names the cases that set each side's values."""
    nan = float("nan")
    absent = {"max": nan, "min": nan}                 # the side of an item in one run only
    new = {r["item"]: r for r in rows_new}
    rows = []
    for item in [*new, *(i for i in old if i not in new)]:
        n, o = new.get(item), old.get(item)
        status = "both" if n is not None and o is not None else "only in this run" if o is None else \
            "only in the earlier run"
        unit = (n if n is not None else o).get("unit", "")
        n, o = n or absent, o or absent
        rows.append({"item": item, "unit": unit, "max": n["max"], "max_old": o["max"],
                     "max_change_pct": pct_change(n["max"], o["max"]), "min": n["min"], "min_old": o["min"],
                     "min_change_pct": pct_change(n["min"], o["min"]), "case_max": n.get("case_max", ""),
                     "case_max_old": o.get("case_max", ""), "case_min": n.get("case_min", ""),
                     "case_min_old": o.get("case_min", ""), "status": status, "category": n.get("category", "")})
    fields = ("item", "unit", "max", "max_old", "max_change_pct", "min", "min_old", "min_change_pct", "case_max",
              "case_max_old", "case_min", "case_min_old", "status")
    new_cases, old_cases = cases_of(rows_new), cases_of(old.values())
    head = ("# liftoff comparison with an earlier run's max/min; change = (new - old) / |old| x 100 %; status: both, "
            "only in this run, only in the earlier run (its other side empty)\n"
            f"# cases setting this run's values: {', '.join(new_cases) or 'not recorded'}; the earlier run's: "
            f"{', '.join(old_cases) or 'not recorded'} (an envelope over other cases differs by them too)\n")
    return write_rows_csv(rows, fields, head, out / "compare.csv"), rows
