"""Time-consistent interface loads: each peak of an interface's load with the other components
at the same instant (issue 24).

A stress analyst designs a joint to the whole load vector at the time of each peak, not to
six envelopes taken at six different times (envelopes of each component alone over-design).
For every interface (an attach point's six loads Tx..Rz, force on the named component, N
and N m) and every component j, the max and the min of j over the run are taken, and the
row holds the time and all of the interface's components at that time step:
``row = values[i_peak, :]``, exactly the histories' samples (no interpolation). Over several
cases (:func:`envelope`), each (interface, peak) keeps the case whose peak is the largest
(max) or the smallest (min), with that case's time and consistent components.

numpy only; tables as plain dicts (SI units, stated in :data:`CSV_HEADER`).
"""
from __future__ import annotations

import csv
import io
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable, Sequence

import numpy as np

from liftoff.core.errors import InputError
from liftoff.core.records import write_text


@dataclass
class InterfaceHistory:
    """One interface's load histories: ``values[:, j]`` is component ``labels[j]`` (unit
    ``units[j]``) at the run's time steps."""

    name: str
    labels: Sequence[str]
    units: Sequence[str]
    values: np.ndarray          # (n_t, n_components)

    def __post_init__(self) -> None:
        self.values = np.asarray(self.values, dtype=float)
        if self.values.ndim != 2 or self.values.shape[1] != len(self.labels) or len(self.units) != len(self.labels):
            raise InputError(f"interface {self.name!r}: values of shape {self.values.shape} for "
                             f"{len(self.labels)} labels and {len(self.units)} units")


def time_consistent(time: np.ndarray, interfaces: Iterable[InterfaceHistory], case: str) -> list[dict]:
    """Per interface and component: its max and its min over ``time``, each with the time and
    every component of the interface at that step (the first step where the extreme occurs).
    Row keys: interface, peak ('<label> max' / '<label> min'), component, extreme, case,
    time, labels, units, values (the consistent load vector)."""
    time = np.asarray(time, dtype=float)
    rows = []
    for itf in interfaces:
        if itf.values.shape[0] != time.size:
            raise InputError(f"interface {itf.name!r}: {itf.values.shape[0]} samples for {time.size} times")
        for j, lab in enumerate(itf.labels):
            col = itf.values[:, j]
            for extreme, i in (("max", int(np.argmax(col))), ("min", int(np.argmin(col)))):
                rows.append({"interface": itf.name, "peak": f"{lab} {extreme}", "component": j, "extreme": extreme,
                             "case": case, "time": float(time[i]), "labels": tuple(itf.labels),
                             "units": tuple(itf.units), "values": itf.values[i].copy()})
    return rows


def envelope(per_case: Iterable[list[dict]]) -> list[dict]:
    """Over cases: for each (interface, peak) the row of the case with the largest max (or the
    smallest min) of the peak's component, its consistent components kept together (the
    first case wins a tie)."""
    best: dict[tuple[str, str], dict] = {}
    for rows in per_case:
        for r in rows:
            key = (r["interface"], r["peak"])
            o = best.get(key)
            v = r["values"][r["component"]]
            if o is None or (v > o["values"][o["component"]] if r["extreme"] == "max" else
                             v < o["values"][o["component"]]):
                best[key] = r
    return list(best.values())


def to_arrays(rows: list[dict]) -> dict[str, np.ndarray]:
    """One case's :func:`time_consistent` rows as plain arrays (what a campaign record holds:
    a few hundred numbers a case; the case's name is kept beside them): interface, peak,
    extreme, labels and units (comma-joined) as strings, component, time, and the values
    (n_rows, widest interface), NaN-padded."""
    width = max((len(r["labels"]) for r in rows), default=0)
    values = np.full((len(rows), width), np.nan)
    for k, r in enumerate(rows):
        values[k, :len(r["values"])] = r["values"]
    return {"interface": np.array([r["interface"] for r in rows], dtype=str),
            "peak": np.array([r["peak"] for r in rows], dtype=str),
            "extreme": np.array([r["extreme"] for r in rows], dtype=str),
            "labels": np.array([",".join(r["labels"]) for r in rows], dtype=str),
            "units": np.array([",".join(r["units"]) for r in rows], dtype=str),
            "component": np.array([r["component"] for r in rows], dtype=np.int64),
            "time": np.array([r["time"] for r in rows], dtype=float), "values": values}


def from_arrays(arrays: dict, case: str) -> list[dict]:
    """The rows of :func:`to_arrays` again, from case ``case``."""
    rows = []
    for k in range(len(arrays["time"])):
        labels = tuple(str(arrays["labels"][k]).split(","))
        rows.append({"interface": str(arrays["interface"][k]), "peak": str(arrays["peak"][k]),
                     "component": int(arrays["component"][k]), "extreme": str(arrays["extreme"][k]), "case": case,
                     "time": float(arrays["time"][k]), "labels": labels,
                     "units": tuple(str(arrays["units"][k]).split(",")),
                     "values": np.asarray(arrays["values"][k, :len(labels)], dtype=float).copy()})
    return rows


CSV_HEADER = ("# liftoff time-consistent interface loads: for each interface (attach point, force on the named "
              "component) and each component's max and min over the run (column 'peak'), the time (s) and every "
              "component of the interface at that time step (N for T*, N m for R*; units in the column names); "
              "'case': the load case the peak comes from\n")


def write_csv(rows: list[dict], path: Path, note: str = "") -> Path:
    """The rows as CSV (one header over interfaces with the same labels; interfaces with other
    labels are refused: one table holds one kind of interface); ``note``: a second comment
    line (e.g. which cases the table covers)."""
    if not rows:
        raise InputError(f"{path.name}: no interface loads to write")
    labels, units = rows[0]["labels"], rows[0]["units"]
    for r in rows:
        if r["labels"] != labels or r["units"] != units:
            raise InputError(f"{path.name}: interface {r['interface']!r} has components {r['labels']} "
                             f"({r['units']}), the table {labels} ({units})")
    buf = io.StringIO()
    w = csv.writer(buf)
    w.writerow(["interface", "peak", "case", "t (s)"] + [f"{lab} ({u})" for lab, u in zip(labels, units)])
    for r in rows:
        w.writerow([r["interface"], r["peak"], r["case"], f"{r['time']:.6e}"] + [f"{x:.6e}" for x in r["values"]])
    write_text(path, CSV_HEADER + (f"# {note}\n" if note else "") + buf.getvalue())
    return path


def read_csv(path: Path) -> list[dict]:
    """Rows of a file written by :func:`write_csv` (labels and units from its header)."""
    lines = [ln for ln in Path(path).read_text().splitlines() if not ln.startswith("#")]
    reader = csv.reader(lines)
    head = next(reader)
    comps = [h.rpartition(" (")[0] for h in head[4:]]
    units = [h.rpartition(" (")[2].rstrip(")") for h in head[4:]]
    out = []
    for rec in reader:
        lab, _, extreme = rec[1].rpartition(" ")
        out.append({"interface": rec[0], "peak": rec[1], "component": comps.index(lab), "extreme": extreme,
                    "case": rec[2], "time": float(rec[3]), "labels": tuple(comps), "units": tuple(units),
                    "values": np.array([float(x) for x in rec[4:]])})
    return out
