"""An Excel workbook of a run's tables (issue 24; pyyeti's ``rpttab`` style): one sheet per
table, the max/min envelope split by category, each sheet headed by the table's own comment
lines (what it is, SI units), then the table with frozen header and filters.

The workbook is made **from the CSV tables the run wrote** (:func:`from_csv`), so it holds
the same numbers as the CSV files, cell for cell (numbers as numbers, to the CSVs' digits);
xlsxwriter writes it, to a temporary name renamed into place (all or nothing).
"""
from __future__ import annotations

import csv
import math
from dataclasses import dataclass, field
from pathlib import Path

from liftoff.core.errors import InputError
from liftoff.core.records import atomic_path

#: the max/min rows' categories by item name (prefix -> sheet), in sheet order
MAXMIN_SHEETS = (("post ", "max-min posts"), ("attach ", "max-min attach"), ("load factor ", "max-min load factors"),
                 ("acc ", "max-min accelerations"), ("disp ", "max-min displacements"))
OTHER_SHEET = "max-min other"
SHEET_NAME_MAX = 31          # Excel's limit


@dataclass
class Sheet:
    """One table: ``notes`` (lines above it), ``columns`` and ``rows`` (cells: str or float)."""

    name: str
    columns: list[str]
    rows: list[list] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)

    def __post_init__(self) -> None:
        if not 0 < len(self.name) <= SHEET_NAME_MAX or any(ch in self.name for ch in "[]:*?/\\"):
            raise InputError(f"sheet name {self.name!r}: 1 to {SHEET_NAME_MAX} characters, none of []:*?/\\")


def _cell(text: str):
    """A CSV cell as Excel takes it: a number where it reads as a finite one (a value not
    computed, "nan" in the CSV, is an empty cell: Excel showed #NUM! and its sums and filters
    broke), else the text: a name that reads as a number ("1", "inf") stays the name."""
    try:
        x = float(text)
    except ValueError:
        return text
    if math.isfinite(x):
        return x
    return None if text.strip().lower() in ("nan", "-nan", "+nan") else text


def read_csv_table(path: Path) -> tuple[list[str], list[str], list[list]]:
    """(comment lines without '# ', columns, rows) of one of liftoff's CSV tables."""
    notes, lines = [], []
    for ln in Path(path).read_text().splitlines():
        (notes.append(ln[1:].strip()) if ln.startswith("#") else lines.append(ln))
    reader = csv.reader(lines)
    try:
        columns = next(reader)
    except StopIteration:
        raise InputError(f"{Path(path).name}: no table in the file") from None
    text = [_text_column(c) for c in columns]
    return notes, columns, [[c if j < len(text) and text[j] else _cell(c) for j, c in enumerate(rec)]
                            for rec in reader]


def _text_column(name: str) -> bool:
    """Whether a table's column holds names, not numbers (a case named "1" stays "1")."""
    n = name.strip().lower()
    return n.startswith("case") or n in ("item", "unit", "units", "category", "name", "post", "pair", "contour",
                                         "interface", "direction", "component", "point", "label")


def maxmin_sheets(path: Path) -> list[Sheet]:
    """The max/min table split by category (:data:`MAXMIN_SHEETS`), empty sheets left out."""
    notes, columns, rows = read_csv_table(path)
    sheets = {name: Sheet(name, columns, [], notes) for _, name in MAXMIN_SHEETS + (("", OTHER_SHEET),)}
    for r in rows:
        item = str(r[0])
        name = next((n for prefix, n in MAXMIN_SHEETS if item.startswith(prefix)), OTHER_SHEET)
        sheets[name].rows.append(r)
    return [s for s in sheets.values() if s.rows]


def from_csv(tables: list[tuple[str, Path]], maxmin: Path | None = None, title: str = "",
             units: str = "SI") -> list[Sheet]:
    """The sheets of a run: a 'contents' sheet, the max/min envelope by category (``maxmin``),
    then one sheet per (name, CSV path) in ``tables``; numbers in the unit system ``units``
    (analysis.units: the CSV files' SI, or converted for the reader)."""
    from .units import SYSTEMS, check_system, convert_table

    check_system(units)
    sheets = maxmin_sheets(maxmin) if maxmin is not None else []
    for name, path in tables:
        notes, columns, rows = read_csv_table(path)
        sheets.append(Sheet(name, columns, rows, notes))
    # each table's first note, and the cases it covers where a later note says ("cases: ...": the
    # time-consistent interface loads of a campaign cover other cases than the max/min envelope)
    what = ["; ".join([s.notes[0], *(n for n in s.notes[1:] if n.startswith("cases:"))]) if s.notes else ""
            for s in sheets]
    if units == "SI":
        say = "SI units throughout (each sheet says which)"
    else:
        names = ", ".join(f"{si} -> {new}" for si, (new, _) in SYSTEMS[units].items())
        say = (f"{units} units ({names}; g, s, rad, Hz unchanged): converted from the run's SI CSV files, whose "
               "notes above each sheet still say SI; each unit column and header gives the unit")
        for s in sheets:
            s.columns, s.rows = convert_table(s.columns, s.rows, units)
            s.notes = [f"numbers in {units} units (converted from the SI CSV file described below)"] + s.notes
    contents = Sheet("contents", ["sheet", "rows", "what"], [[s.name, float(len(s.rows)), w]
                                                            for s, w in zip(sheets, what)],
                     [title or "liftoff run", say])
    return [contents] + sheets


def write_workbook(sheets: list[Sheet], path: Path) -> Path:
    """Write ``sheets`` to an .xlsx file, atomically."""
    import xlsxwriter

    names = [s.name for s in sheets]
    if len(set(names)) != len(names):
        raise InputError(f"{Path(path).name}: two sheets with one name in {names}")
    with atomic_path(path) as tmp:
        book = xlsxwriter.Workbook(str(tmp), {"nan_inf_to_errors": True})
        bold = book.add_format({"bold": True})
        note = book.add_format({"italic": True, "font_color": "#555555"})
        num = book.add_format({"num_format": "0.000000E+00"})
        for s in sheets:
            ws = book.add_worksheet(s.name)
            for i, line in enumerate(s.notes):
                ws.write_string(i, 0, line, note)
            top = len(s.notes) + (1 if s.notes else 0)
            ws.write_row(top, 0, s.columns, bold)
            for i, row in enumerate(s.rows):
                for j, v in enumerate(row):
                    if isinstance(v, float):
                        ws.write_number(top + 1 + i, j, v, num)
                    elif v is None or v == "":
                        continue                           # an empty CSV cell (or a value not computed) stays empty
                    else:
                        ws.write_string(top + 1 + i, j, str(v))
            ws.freeze_panes(top + 1, 1)
            if s.rows:
                ws.autofilter(top, 0, top + len(s.rows), len(s.columns) - 1)
            widths = [max([len(str(c))] + [len(str(r[j])) if j < len(r) and not isinstance(r[j], float) else 13
                                          for r in s.rows[:200]]) for j, c in enumerate(s.columns)]
            for j, w in enumerate(widths):
                ws.set_column(j, j, min(max(w + 2, 10), 60))
        book.close()
    return Path(path)
