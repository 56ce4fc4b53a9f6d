"""Report units (issue 24): a run's tables converted from SI to another unit system for the
people who read them (the workbook), while the CSV and HDF5 files stay SI for programs.

Systems (:data:`SYSTEMS`): ``"SI"`` (as computed: N, N m, m, m/s^2, Pa, m^3, kg) and
``"in-lbf-s"`` (lbf, lbf in, in, in/s^2, psi, in^3, lbf s^2/in), the US customary system of
Nastran's in-lbf-s models (the factors are the exact definitions: 1 in = 0.0254 m, 1 lbf =
0.45359237 kg x 9.80665 m/s^2). Load factors (g), angles (rad), times (s), frequencies (Hz)
and ratios are the same in both.

A table's numbers are found by their unit, as liftoff's tables state it: a row's ``unit``
column (max/min, statistics and design tables: its value columns), ``x_unit``/``y_unit``
(correlated loads: ``x``/``y``), a column header ``name (unit)`` (time-consistent loads),
``name_<unit>`` suffixes (``x_m``, Table 1) and the modal tables' effective masses
(``m_eff_*``, kg). numpy only.
"""
from __future__ import annotations

import re

from liftoff.core.errors import InputError
from liftoff.core.units import INCH as _IN
from liftoff.core.units import LBF as _LBF

#: unit system -> {SI unit: (its unit, SI value of one of it)}; units absent stay as they are
SYSTEMS: dict[str, dict[str, tuple[str, float]]] = {
    "SI": {},
    "in-lbf-s": {"N": ("lbf", _LBF), "N m": ("lbf in", _LBF * _IN), "m": ("in", _IN),
                 "m/s": ("in/s", _IN), "m/s^2": ("in/s^2", _IN), "Pa": ("psi", _LBF / _IN ** 2),
                 "m^3": ("in^3", _IN ** 3), "kg": ("lbf s^2/in", _LBF / _IN)},
}

#: the value columns a row's ``unit`` column governs (max/min, statistics, design loads,
#: comparison and SRS tables; analysis.aggregate's column names)
UNIT_COLUMNS = ("max", "min", "max_err_est", "min_err_est", "mean_max", "std_max", "normal_max", "order_max",
                "mean_min", "std_min", "normal_min", "order_min", "design_max", "design_min", "max_old", "min_old",
                "envelope", "mean", "std", "normal_P9990")
_HEADER = re.compile(r"^(?P<name>.*) \((?P<unit>[^()]+)\)$")
_SUFFIX = {"_m": "m", "_pa": "Pa", "_n": "N", "_kg": "kg"}


def check_system(system: str) -> str:
    """``system`` if it is one of :data:`SYSTEMS`, else a one-line InputError."""
    if system not in SYSTEMS:
        raise InputError(f"unit system {system!r} is not one of {', '.join(SYSTEMS)}")
    return system


def factor(unit: str, system: str) -> tuple[str, float]:
    """(the unit in ``system``, the number to divide an SI value by) for an SI ``unit``."""
    return SYSTEMS[check_system(system)].get(str(unit).strip(), (unit, 1.0))


def convert_table(columns: list[str], rows: list[list], system: str) -> tuple[list[str], list[list]]:
    """``columns`` and ``rows`` (cells: str or float, as analysis.workbook reads them) with
    every number that has an SI unit expressed in ``system`` and every stated unit renamed;
    the other cells unchanged. "SI" returns them as they are."""
    check_system(system)
    if system == "SI":
        return list(columns), [list(r) for r in rows]
    cols = list(columns)
    col_factor: dict[int, float] = {}
    for j, c in enumerate(columns):                 # units stated by the header
        m = _HEADER.match(c)
        if m:
            new, f = factor(m["unit"], system)
            cols[j], col_factor[j] = f"{m['name']} ({new})", f
            continue
        low = c.lower()
        if low.startswith("m_eff_"):
            new, f = factor("kg", system)
            col_factor[j] = f
            cols[j] = f"{c} ({new})"
            continue
        for suffix, unit in _SUFFIX.items():
            if low.endswith(suffix):
                new, f = factor(unit, system)
                if f != 1.0:
                    cols[j], col_factor[j] = c[: -len(suffix)] + "_" + new.replace(" ", "_").replace("/", "_per_"), f
                break
    row_units = [(columns.index(u), [columns.index(v) for v in vals if v in columns])
                 for u, vals in (("unit", UNIT_COLUMNS), ("x_unit", ("x",)), ("y_unit", ("y",))) if u in columns]
    out = []
    for r in rows:
        r = list(r)
        for j, f in col_factor.items():
            if j < len(r) and isinstance(r[j], float):
                r[j] = r[j] / f
        for ju, targets in row_units:
            if ju < len(r) and isinstance(r[ju], str):
                new, f = factor(r[ju], system)
                r[ju] = new
                for j in targets:
                    if j < len(r) and isinstance(r[j], float):
                        r[j] = r[j] / f
        out.append(r)
    return cols, out
