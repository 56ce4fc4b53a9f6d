"""The Excel workbook (analysis/workbook.py) holds the CSV tables it was made from, cell for
cell; read back with openpyxl (an independent reader of the format)."""
import numpy as np
import pytest

from liftoff.analysis import workbook
from liftoff.core.errors import InputError

openpyxl = pytest.importorskip("openpyxl")

MAXMIN = """# liftoff max/min table; SI units (column 'unit')
item,unit,max,max_err_est,t_max,case_max,min,min_err_est,t_min,case_min
post left_1 Tz,N,1.250000e+06,,6.600000e+00,nominal,-3.000000e+05,,6.700000e+00,no-control
attach att_a on core Tx,N,2.000000e+03,1.0e-01,7.000000e+00,nominal,-1.000000e+03,,7.100000e+00,nominal
load factor core Nz,g,1.997548e+00,,7.05e+00,nominal,6.214628e-01,,6.79e+00,nominal
acc stack_top:Tx,m/s^2,4.897000e-01,,7.304000e+00,nominal,-5.172000e-01,,6.929000e+00,nominal
cg_motion Tx,m,1.764000e-03,,9.600000e+00,nominal,-7.409000e-04,,9.596000e+00,no-control
"""
TABLE = """# liftoff time-consistent interface loads
# cases: nominal, no-control
interface,peak,case,t (s),Tx (N),Ty (N)
attach a on core,Tx max,nominal,6.700000e+00,1.000000e+03,-2.500000e+02
"""


def _values(ws):
    return [[c.value for c in row] for row in ws.iter_rows()]


def test_workbook_holds_the_csv_tables_cell_for_cell(tmp_path):
    (tmp_path / "maxmin_envelope.csv").write_text(MAXMIN)
    (tmp_path / "tcl.csv").write_text(TABLE)
    sheets = workbook.from_csv([("time-consistent loads", tmp_path / "tcl.csv")], tmp_path / "maxmin_envelope.csv",
                               "test run")
    path = workbook.write_workbook(sheets, tmp_path / "loads.xlsx")
    book = openpyxl.load_workbook(path, read_only=True)
    assert book.sheetnames == ["contents", "max-min posts", "max-min attach", "max-min load factors",
                               "max-min accelerations", "max-min other", "time-consistent loads"]
    # each category sheet: its notes, the header, then the CSV's rows of that category
    rows = _values(book["max-min load factors"])
    assert rows[0][0].startswith("liftoff max/min table") and rows[2][:3] == ["item", "unit", "max"]
    assert rows[3][0] == "load factor core Nz" and rows[3][2] == 1.997548 and rows[3][5] == "nominal"
    assert rows[3][3] is None                  # an empty estimate stays empty
    rows = _values(book["max-min attach"])
    assert rows[3][3] == 0.1
    rows = _values(book["time-consistent loads"])
    assert rows[1][0] == "cases: nominal, no-control"
    assert rows[3][:3] == ["interface", "peak", "case"] and rows[4][4:6] == [1000.0, -250.0]
    contents = _values(book["contents"])
    assert contents[0][0] == "test run"
    assert contents[3][:2] == ["sheet", "rows"]
    assert [r[:2] for r in contents[4:]] == [["max-min posts", 1], ["max-min attach", 1], ["max-min load factors", 1],
                                           ["max-min accelerations", 1], ["max-min other", 1],
                                           ["time-consistent loads", 1]]
    assert contents[-1][2].endswith("; cases: nominal, no-control")     # the cases a table covers, said there too


def test_bad_sheets_are_refused(tmp_path):
    with pytest.raises(InputError, match="sheet name"):
        workbook.Sheet("a/b", ["x"])
    with pytest.raises(InputError, match="two sheets"):
        workbook.write_workbook([workbook.Sheet("s", ["x"]), workbook.Sheet("s", ["y"])], tmp_path / "w.xlsx")
    assert not (tmp_path / "w.xlsx").exists()
    (tmp_path / "empty.csv").write_text("# only a note\n")
    with pytest.raises(InputError, match="no table"):
        workbook.read_csv_table(tmp_path / "empty.csv")


def test_workbook_in_inch_pound_units(tmp_path):
    """[postprocess] units = "in-lbf-s": every number with an SI unit divided by the exact
    definition of its US unit (1 in = 0.0254 m, 1 lbf = 0.45359237 kg x 9.80665 m/s^2: N ->
    lbf, N m -> lbf in, m -> in, m/s^2 -> in/s^2), the unit cells and headers renamed; load
    factors (g), times and case names unchanged; the notes say so. Read back with openpyxl."""
    lbf, inch = 0.45359237 * 9.80665, 0.0254
    (tmp_path / "maxmin_envelope.csv").write_text(MAXMIN)
    (tmp_path / "tcl.csv").write_text(TABLE)
    (tmp_path / "cl.csv").write_text("# correlated\ninterface,pair,vertex,x_name,x,x_unit,y_name,y,y_unit,time,case\n"
                                     "a,axial-bending,1,Tz,4.448222e+00,N,Mb,1.129848e-01,N m,1.0,nominal\n")
    (tmp_path / "t1.csv").write_text("case,x_m,rx_rad\n1) gravity only,2.54e-02,1.0e-03\n")
    sheets = workbook.from_csv([("time-consistent loads", tmp_path / "tcl.csv"), ("correlated loads", tmp_path / "cl.csv"),
                                ("table 1", tmp_path / "t1.csv")], tmp_path / "maxmin_envelope.csv", "test run",
                               units="in-lbf-s")
    book = openpyxl.load_workbook(workbook.write_workbook(sheets, tmp_path / "loads.xlsx"), read_only=True)
    rows = _values(book["max-min posts"])
    assert rows[0][0].startswith("numbers in in-lbf-s units") and rows[1][0].startswith("liftoff max/min table")
    post = rows[4]
    assert post[1] == "lbf" and post[2] == pytest.approx(1.25e6 / lbf, rel=1e-15)
    assert post[6] == pytest.approx(-3e5 / lbf, rel=1e-15) and post[4] == 6.6       # the time stays in s
    att = _values(book["max-min attach"])[4]
    assert att[3] == pytest.approx(0.1 / lbf, rel=1e-15)                           # the error estimate too
    lf = _values(book["max-min load factors"])[4]
    assert lf[1] == "g" and lf[2] == 1.997548
    acc = _values(book["max-min accelerations"])[4]
    assert acc[1] == "in/s^2" and acc[2] == pytest.approx(0.4897 / inch, rel=1e-15)
    other = _values(book["max-min other"])[4]
    assert other[1] == "in" and other[2] == pytest.approx(1.764e-3 / inch, rel=1e-15)
    tcl = _values(book["time-consistent loads"])
    assert tcl[4][:6] == ["interface", "peak", "case", "t (s)", "Tx (lbf)", "Ty (lbf)"]
    assert tcl[5][4] == pytest.approx(1000.0 / lbf, rel=1e-15) and tcl[5][3] == 6.7
    cl = _values(book["correlated loads"])[4]
    assert cl[4] == pytest.approx(1.0, rel=1e-6) and cl[5] == "lbf"               # 1 lbf, 1 lbf in, to 7 digits
    assert cl[7] == pytest.approx(1.0, rel=1e-6) and cl[8] == "lbf in"
    t1 = _values(book["table 1"])[2:]
    assert t1[0][:3] == ["case", "x_in", "rx_rad"] and t1[1][1] == pytest.approx(1.0, rel=1e-15) and t1[1][2] == 1e-3
    assert "in-lbf-s units" in _values(book["contents"])[1][0]
    with pytest.raises(InputError, match="unit system 'mks' is not one of SI, in-lbf-s"):
        workbook.from_csv([], tmp_path / "maxmin_envelope.csv", units="mks")


def test_values_not_computed_are_empty_and_case_names_stay_names(tmp_path):
    """A value the run did not compute ("nan" in the CSV: an order statistic for too few cases)
    is an empty cell, not Excel's #NUM! error that breaks sums and filters; a case named like
    a number ("1", "inf") stays its name in the case columns; other numbers stay numbers."""
    (tmp_path / "stats.csv").write_text("item,unit,order_max,case_max,mean\n"
                                        "post left_1 Tz,N,nan,1,2.5\n"
                                        "post left_2 Tz,N,-nan,inf,3.0\n")
    sheets = workbook.from_csv([("statistics", tmp_path / "stats.csv")])
    path = workbook.write_workbook(sheets, tmp_path / "loads.xlsx")
    rows = _values(openpyxl.load_workbook(path, read_only=True)["statistics"])
    assert rows[1] == ["post left_1 Tz", "N", None, "1", 2.5]
    assert rows[2] == ["post left_2 Tz", "N", None, "inf", 3.0]


def test_fft_amplitude_of_a_cosine_at_nyquist_is_its_amplitude():
    """fft_amplitude: a unit cosine at the Nyquist frequency (an even record) reads 1, as one
    at any other bin (its bin, like the mean's, has no mirror image: it read 2)."""
    from liftoff.analysis.spectra import fft_amplitude

    n, h = 64, 1e-3
    t = np.arange(n) * h
    for k in (5, n // 2):
        f, a = fft_amplitude(np.cos(2 * np.pi * k / (n * h) * t), h)
        assert a[k, 0] == pytest.approx(1.0, rel=1e-12) and f[k] == pytest.approx(k / (n * h))


def test_a_load_from_nothing_leads_the_largest_changes():
    """format_changes: an item whose earlier peak was 0 (no percentage: NaN) and is now a
    load ranks first, not last; one 0 before and after stays at the bottom."""
    from liftoff.analysis.tables import format_changes

    def row(item, mx, old, pct):
        return {"item": item, "category": "contact_force", "unit": "N", "max": mx, "max_old": old,
                "max_change_pct": pct, "min": 0.0, "min_old": 0.0, "min_change_pct": float("nan")}

    rows = [row("post a Tz", 1.1e6, 1.0e6, 10.0), row("post b Tz", 5.0e5, 0.0, float("nan")),
            row("post c Tz", 0.0, 0.0, float("nan"))]
    text = format_changes(rows)
    lines = [ln for ln in text.splitlines() if ln.startswith("post ")]
    assert [ln.split()[1] for ln in lines] == ["b", "a", "c"]
