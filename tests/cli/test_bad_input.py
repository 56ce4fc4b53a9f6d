"""Bad scenario input: exit status 2, one line naming the culprit, no results file, no traceback.

Each case starts from the valid fixture scenario (conftest.base_scenario, which is shown to
run in test_cli_runs.py) and breaks exactly one thing.
"""
from __future__ import annotations

import copy
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from liftoff.workflows.cli import main

from .conftest import base_scenario, write_scenario

REPO = Path(__file__).resolve().parents[2]


def _set(path: str, value):
    """Mutation: set a key given as 'table.key' or 'array[i].key' (value None deletes it)."""
    def mutate(d: dict) -> None:
        node = d
        parts = path.split(".")
        for part in parts[:-1]:
            if "[" in part:
                name, idx = part[:-1].split("[")
                node = node[name][int(idx)]
            else:
                node = node.setdefault(part, {})
        last = parts[-1]
        if "[" in last:
            name, idx = last[:-1].split("[")
            node[name][int(idx)] = value
        elif value is None:
            node.pop(last)
        else:
            node[last] = value
    return mutate


def _both(first, second):
    def mutate(d: dict) -> None:
        first(d)
        second(d)
    return mutate


def _files(write: dict[str, str]):
    def mutate(d: dict, directory: Path) -> None:
        for name, content in write.items():
            if isinstance(content, bytes):
                (directory / name).write_bytes(content)
            else:
                (directory / name).write_text(content)
    return mutate


NAN = float("nan")

# (id, mutation of the scenario dict, extra files to write, substring the message must contain)

def _npz_bytes(**arrays) -> bytes:
    import io

    buf = io.BytesIO()
    np.savez(buf, **arrays)
    return buf.getvalue()


CASES = [
    ("unknown-top-key", _set("contacts", [1]), None, "unknown key 'contacts'"),
    ("unknown-contact-key", _set("contact[0].stifness", 1.0), None, "contact[0]: unknown key 'stifness'"),
    ("unknown-time-key", _set("time.dt", 1e-4), None, "time: unknown key 'dt'"),
    ("missing-t_end", _set("time.t_end", None), None, "missing required key 't_end'"),
    ("t_end-string", _set("time.t_end", "0.02"), None, "time.t_end: expected a number, got str"),
    ("t_end-negative", _set("time.t_end", -1.0), None, "time.t_end: must be greater than t0"),
    ("h-negative", _set("time.h", -1e-4), None, "time.h: must be positive"),
    ("h-nan", _set("time.h", NAN), None, "time.h: value is NaN"),
    ("method-unknown", _set("time.method", "newmark"), None, "time.method: must be one of"),
    ("body-file-missing", _set("bodies.a", "nowhere.npz"), None, "bodies.a: body file not found"),
    ("body-a-ground", _set("bodies.a", "ground"), None, "bodies.a: body a cannot be 'ground'"),
    ("body-file-corrupt", _set("bodies.b", "corrupt.npz"), {"corrupt.npz": "not a zip"}, "cannot be read"),
    ("unknown-label-contact", _set("contact[0].labels_a", ["base:Tx", "base:Ty"]), None,
     "contact[0] 'post'.labels_a[1]: unknown DOF label 'base:Ty' on body 'vehicle'"),
    ("unknown-label-pad", _set("contact[0].labels_b", ["post:Tx", "foot:Tz"]), None,
     "unknown DOF label 'foot:Tz' on body 'pad'"),
    ("malformed-label", _set("contact[0].labels_a", ["base:Tx", "base_Tz"]), None, "malformed DOF label 'base_Tz'"),
    ("unknown-label-force", _set("force[1].label", "tip:Tx"), None, "force[1].label: unknown DOF label 'tip:Tx'"),
    ("unknown-label-output", _set("output.a", ["top:Tz", "top:Rz"]), None, "output.a[1]: unknown DOF label 'top:Rz'"),
    ("labels-unequal", _set("contact[0].labels_b", ["post:Tz"]), None, "has 1 labels but labels_a has 2"),
    ("stiffness-negative", _set("contact[0].stiffness", [1e8, -1e8]), None, "stiffness: must be positive, got [100000000.0, -100000000.0]"),
    ("stiffness-scalar-negative", _set("contact[0].stiffness", -5.0), None, "stiffness: must be positive, got [-5.0, -5.0]"),
    ("stiffness-nan", _set("contact[0].stiffness", [1e8, NAN]), None, "stiffness[1]: value is NaN"),
    ("stiffness-shape", _set("contact[0].stiffness", [1e8, 1e8, 1e8]), None, "stiffness: has 3 entries, expected 2"),
    ("stiffness-missing", _set("contact[0].stiffness", None), None, "missing required key 'stiffness'"),
    ("stiffness-and-rigid", _set("contact[0].rigid", True), None, "a rigid contact takes no stiffness"),
    ("friction-negative", _set("contact[0].friction", -0.2), None, "contact[0] 'post'.friction: coefficient must be >= 0"),
    ("friction-rigid", _both(_set("contact[0].stiffness", None), _both(_set("contact[0].rigid", True),
                                                                      _set("contact[0].friction", 0.3))),
     None, "friction: needs a penalty (not rigid) contact"),
    ("damping-shape", _set("contact[0].damping", [1.0, 2.0, 3.0]), None, "damping: has 3 entries, expected 2"),
    ("damping-negative", _set("contact[0].damping", -1.0), None, "damping: must be one value or 2 values >= 0"),
    ("latch-negative", _set("contact[0].latch_force", -5.0), None, "latch_force: must be >= 0 N"),
    ("normal-zero", _both(_set("contact[0].axial", None), _set("contact[0].normal", [0.0, 0.0])), None,
     "contact[0] 'post'.normal: must be 2 finite numbers (one per label), not all zero"),
    ("normal-length", _both(_set("contact[0].axial", None), _set("contact[0].normal", [0.0, 0.0, 1.0])), None,
     "contact[0] 'post'.normal: has 3 entries, expected 2"),
    ("normal-and-axial", _set("contact[0].normal", [0.0, 1.0]), None, "give either axial"),
    ("gap-negative", _set("contact[0].gap", -0.001), None, "gap: negative value"),
    ("release-nan", _set("contact[0].release_time", NAN), None, "release_time: value is NaN"),
    ("axial-out-of-range", _set("contact[0].axial", 2), None, "axial: 2 out of range"),
    ("normal-sign", _set("contact[0].normal_sign", 0.5), None, "normal_sign: must be +1 or -1"),
    ("gravity-nan", _set("gravity.accel", [0.0, NAN, -9.81]), None, "gravity.accel[1]: value is NaN"),
    ("gravity-shape", _set("gravity.accel", [0.0, -9.81]), None, "gravity.accel: has 2 entries, expected 3"),
    ("softening-orphan", _set("gravity.softening_until", 0.3), None, "gravity.softening_until: given without softening"),
    ("softening-type", _set("gravity.softening", 1), None, "gravity.softening: expected true or false"),
    ("force-value-nan", _set("force[1].value", NAN), None, "force[1] 'top:Tx'.value: value is NaN"),
    ("force-body", _set("force[1].body", "c"), None, "force[1].body: must be 'a' or 'b'"),
    ("csv-missing", _set("force[0].csv", "nothrust.csv"), None, "CSV file not found"),
    ("csv-nan", None, {"thrust.csv": "time,force\n0,0\n0.01,nan\n"}, "thrust.csv line 3: NaN or inf"),
    ("csv-text", None, {"thrust.csv": "time,force\n0,0\n0.01,lots\n"}, "thrust.csv line 3: not a number"),
    ("csv-binary", None, {"thrust.csv": b"\xff\xfe\x00\x01,\x80\n"}, "thrust.csv is not a UTF-8 text file"),
    ("csv-header-only", None, {"thrust.csv": "time,force\n# nothing\n"}, "thrust.csv: no data rows"),
    ("csv-one-row", None, {"thrust.csv": "time,force\n0,5\n"}, "a table needs at least 2 time points"),
    ("csv-columns", None, {"thrust.csv": "0,0,1\n0.01,5,1\n"}, "thrust.csv: 3 columns, expected 2"),
    ("csv-ragged", None, {"thrust.csv": "0,0\n0.01,5,1\n"}, "thrust.csv line 2: 3 columns, expected 2"),
    ("csv-time-decreasing", None, {"thrust.csv": "0,0\n0.01,5\n0.005,7\n"}, "time is not strictly increasing at entry 2"),
    ("table-unequal", _set("force[1]", {"body": "a", "label": "top:Tx", "time": [0.0, 0.01, 0.02],
                                        "value": [0.0, 1.0]}), None, "unequal lengths"),
    ("table-time-repeated", _set("force[1]", {"body": "a", "label": "top:Tx", "time": [0.0, 0.01, 0.01],
                                              "value": [0.0, 1.0, 2.0]}), None, "not strictly increasing"),
    ("table-value-nan", _set("force[1]", {"body": "a", "label": "top:Tx", "time": [0.0, 0.01],
                                          "value": [0.0, NAN]}), None, "value[1]: value is NaN"),
    ("initial-mode", _set("initial.mode", "restart"), None, "initial.mode: must be one of"),
    ("initial-shape", _set("initial", {"mode": "given", "q_a": [0.0, 0.0]}), None,
     "initial.q_a: has 2 entries, expected 3"),
    ("initial-nan", _set("initial", {"mode": "given", "v_b": [0.0, NAN]}), None, "initial.v_b[1]: value is NaN"),
    ("modal-force-columns", _set("modal_force", [{"body": "a", "time": [0.0, 1.0], "values": [[0.0, 0.0], [1.0, 1.0]]}]),
     None, "modal_force[0].values[0]: has 2 entries, expected 3"),
    ("modal-force-body", _set("modal_force", [{"body": "c", "time": [0.0, 1.0], "values": [[0.0], [1.0]]}]),
     None, "modal_force[0].body: must be 'a' or 'b'"),
    ("recovery-missing", _set("recovery", [{"name": "r", "body": "a", "file": "none.npz"}]), None,
     "recovery[0].file: recovery file not found"),
    ("recovery-complex", _set("recovery", [{"name": "r", "body": "a", "file": "r.npz"}]),
     {"r.npz": _npz_bytes(labels=np.array(["x"]), disp=np.ones((1, 3)) * (1 + 2j))},
     "recovery[0].file: r.npz: disp is complex128 (a recovery matrix of a modal model is real numbers)"),
    ("ground-labels_b", _set("bodies.b", "ground"), None, "body b is ground: omit labels_b"),
    ("keep-modal-type", _set("output.keep_modal", "yes"), None, "output.keep_modal: expected true or false"),
    ("h-not-auto", _set("time.h", "automatic"), None, "time.h: expected a step in s or \"auto\""),
    ("axial-name", _set("contact[0].axial", "Ty"), None,
     "contact[0] 'post'.axial: 'Ty' is not one of the directions base:Tx, base:Tz"),
    ("softening-key", _set("softening", {"enabled": True, "untill": 0.1}), None, "softening: unknown key 'untill'"),
    ("softening-label", _set("softening", {"enabled": True, "labels": ["top:Ty"]}), None,
     "softening.labels[0]: unknown DOF label 'top:Ty'"),
    ("softening-no-gravity", _both(_set("gravity", None), _set("softening", {"enabled": True})), None,
     "softening: needs [gravity] accel"),
    ("softening-two-spellings", _both(_set("gravity.softening", True), _set("softening", {"enabled": True})), None,
     "gravity.softening: softening is given in [softening]: remove it from [gravity]"),
]


def _break(directory: Path, mutate, files) -> Path:
    data = copy.deepcopy(base_scenario())
    if mutate is not None:
        mutate(data)
    if files:
        _files(files)(data, directory)
    return write_scenario(directory, data)


def _assert_clean_failure(code: int, err: str, expect: str, out_dir: Path, status: int = 2) -> None:
    """Exit ``status`` (2: bad input), exactly one error line (warnings, one line each, may precede
    it), nothing in out_dir."""
    assert code == status, err
    lines = [ln for ln in err.strip().splitlines() if not ln.startswith("liftoff: warning: ")]
    assert len(lines) == 1, f"expected one line on stderr, got:\n{err}"
    assert lines[0].startswith("liftoff: error: "), lines[0]
    assert expect in lines[0], f"{expect!r} not in {lines[0]!r}"
    assert "Traceback" not in err
    assert not (out_dir / "results.h5").exists()
    assert not out_dir.exists() or not any(out_dir.iterdir()), list(out_dir.iterdir())


@pytest.mark.parametrize("mutate, files, expect", [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_bad_scenario(case_dir: Path, capsys, mutate, files, expect):
    scenario = _break(case_dir, mutate, files)
    out_dir = case_dir / "out"
    code = main(["transient", str(scenario), "--out", str(out_dir), "--no-progress"])
    _assert_clean_failure(code, capsys.readouterr().err, expect, out_dir)


def test_missing_scenario_file(tmp_path: Path, capsys):
    code = main(["transient", str(tmp_path / "none.toml"), "--out", str(tmp_path / "out")])
    _assert_clean_failure(code, capsys.readouterr().err, "scenario file not found", tmp_path / "out")


def test_toml_syntax_error(case_dir: Path, capsys):
    (case_dir / "bad.toml").write_text("[time]\nt_end = = 1\n")
    code = main(["transient", str(case_dir / "bad.toml"), "--out", str(case_dir / "out")])
    _assert_clean_failure(code, capsys.readouterr().err, "bad.toml: TOML syntax error", case_dir / "out")


def test_not_utf8(case_dir: Path, capsys):
    (case_dir / "bad.toml").write_bytes(b"title = '\xe9t\xe9'\n")
    code = main(["transient", str(case_dir / "bad.toml"), "--out", str(case_dir / "out")])
    _assert_clean_failure(code, capsys.readouterr().err, "bad.toml: not a UTF-8 text file", case_dir / "out")


def test_body_file_with_nan(case_dir: Path, capsys):
    """A body file written by another tool with a NaN frequency is refused when loaded."""
    with np.load(case_dir / "pad.npz") as z:
        data = {k: z[k] for k in z.files}
    data["omega"] = np.array([np.nan, 1000.0])
    np.savez(case_dir / "pad.npz", **data)
    code = main(["transient", str(_break(case_dir, None, None)), "--out", str(case_dir / "out")])
    _assert_clean_failure(code, capsys.readouterr().err, "omega contains NaN", case_dir / "out")


def test_body_file_wrong_shape(case_dir: Path, capsys):
    with np.load(case_dir / "vehicle.npz") as z:
        data = {k: z[k] for k in z.files}
    data["phi"] = data["phi"][:, :2]          # 3 modes but 2 mode-shape columns
    np.savez(case_dir / "vehicle.npz", **data)
    code = main(["transient", str(_break(case_dir, None, None)), "--out", str(case_dir / "out")])
    _assert_clean_failure(code, capsys.readouterr().err, "vehicle.npz", case_dir / "out")


def _edit_body(path: Path, **arrays) -> None:
    """Rewrite a body file with some arrays replaced (as another tool might write it)."""
    with np.load(path) as z:
        data = {k: z[k] for k in z.files}
    for key, fn in arrays.items():
        data[key] = fn(data[key])
    np.savez(path, **data)


@pytest.mark.parametrize("edit, expect", [
    (dict(phi=lambda a: a.T.copy()), "phi has shape (3, 4), expected (4, 3) (DOF labels x modes)"),
    (dict(phi=lambda a: a.ravel()), "phi has shape (12,), expected (4, 3)"),
    (dict(phi=lambda a: a[None]), "phi has shape (1, 4, 3), expected (4, 3)"),
    (dict(phi=lambda a: a + 0j), "phi is complex"),
    (dict(omega=lambda a: a[None]), "omega has shape (1, 3), expected 1 dimension(s)"),
    (dict(omega=lambda a: a.astype(str)), "omega is not numeric"),
    (dict(version=lambda a: np.array(999)), "version 999 is not supported"),
    (dict(omega=lambda a: a * 0 + 1e308), "omega has a value of magnitude 1e+308, beyond 1e+100"),
    (dict(phi=lambda a: a * 1e300), "phi has a value of magnitude"),
], ids=["phi-transposed", "phi-1d", "phi-3d", "phi-complex", "omega-2d", "omega-text", "version-999",
        "omega-1e308", "phi-1e300"])
def test_body_file_arrays_exactly_as_documented(case_dir: Path, capsys, edit, expect):
    """A body file's arrays must have the documented shapes and real dtype: a transposed phi
    (5 x 30 stored as 30 x 5) used to be reshaped silently and give another answer."""
    _edit_body(case_dir / "vehicle.npz", **edit)
    code = main(["transient", str(_break(case_dir, None, None)), "--out", str(case_dir / "out")])
    _assert_clean_failure(code, capsys.readouterr().err, expect, case_dir / "out")


@pytest.mark.parametrize("mutate, expect, status", [
    (_set("gravity.accel", [0.0, 0.0, -1e308]), "gravity.accel[2]: magnitude -1e+308 is beyond 1e+100", 2),
    (_set("force[1].value", 1e308), "force[1] 'top:Tx'.value: magnitude 1e+308", 2),
    (_set("time.t_end", 1e308), "time.t_end: magnitude 1e+308", 2),
    (_set("time.h", 0.002), "time: time step h = 0.002 s exceeds the stability limit of the penalty contact coupling", 2),
    (_both(_set("time.t0", 1e15), _set("time.t_end", 1e15 + 1.0)), "start the run near t0 = 0", 2),
    (_both(_set("contact[0].stiffness", [1e99, 1e99]), _set("time.h", "auto")), "the contact stiffnesses set f_h = ", 2),
    (_both(_set("time.t_end", 1e99), _set("time.h", "auto")), "give a shorter run", 2),
], ids=["gravity-1e308", "force-1e308", "t_end-1e308", "h-unstable", "t0-1e15", "stiffness-1e99", "t_end-1e99"])
def test_overflowing_or_unstable_input(case_dir: Path, capsys, mutate, expect, status):
    """Magnitudes that would overflow inside, a step beyond the stability limit (it used to
    run and save 1e22 N contact forces) and a time axis that cannot resolve the step are
    refused with one line naming file and key."""
    code = main(["transient", str(_break(case_dir, mutate, None)), "--out", str(case_dir / "out")])
    _assert_clean_failure(code, capsys.readouterr().err, expect, case_dir / "out", status)


def test_out_is_a_file(case_dir: Path, capsys):
    (case_dir / "taken").write_text("")
    code = main(["transient", str(_break(case_dir, None, None)), "--out", str(case_dir / "taken")])
    _assert_clean_failure(code, capsys.readouterr().err, "exists and is not a folder", case_dir / "nothing")


def _subprocess(args: list[str], cwd: Path) -> subprocess.CompletedProcess:
    exe = Path(sys.executable).with_name("liftoff")
    cmd = [str(exe)] if exe.exists() else [sys.executable, "-m", "liftoff.workflows.cli"]
    return subprocess.run(cmd + args, cwd=cwd, capture_output=True, text=True, timeout=300)


def test_console_script_bad_label(case_dir: Path):
    """The installed console script itself exits with status 2 and one line (no traceback)."""
    scenario = _break(case_dir, _set("output.b", ["post:Ty"]), None)
    proc = _subprocess(["transient", str(scenario), "--out", "out", "--no-progress"], case_dir)
    _assert_clean_failure(proc.returncode, proc.stderr, "output.b[0]: unknown DOF label 'post:Ty'",
                          case_dir / "out")


def test_fixed_point_divergence_is_an_error(case_dir: Path):
    """Fixed-point iteration with rho(K_C W) = 1.6 > 1 (K_C = 8e9 N/m, h = 1e-4 s) must stop with
    an error naming the time, not write a result. (The direct solve is stable at this step:
    stepping.coupling_margin = -0.8 > -1; a stiffer K_C would be refused before the run.)"""
    scenario = _break(case_dir, _set("contact[0].stiffness", [8e9, 8e9]), None)
    proc = _subprocess(["transient", str(scenario), "--out", "out", "--no-progress",
                        "--method", "fixed-point"], case_dir)
    _assert_clean_failure(proc.returncode, proc.stderr, "", case_dir / "out", status=3)   # no convergence
    assert "converge" in proc.stderr.lower(), proc.stderr


def test_no_command_is_one_line_with_usage(capsys):
    """`liftoff` alone: one line naming what is missing and where the usage is, exit 2 (no
    "liftoff: error: liftoff: ...")."""
    from liftoff.workflows.cli import main

    with pytest.raises(SystemExit) as exc:
        main([])
    err = capsys.readouterr().err
    assert exc.value.code == 2 and err.count("\n") == 1
    assert err.startswith("liftoff: error: the following arguments are required: COMMAND")
    assert "(usage: liftoff --help)" in err and "liftoff: error: liftoff:" not in err


def test_a_missing_optional_package_is_one_line_with_how_to_get_it(monkeypatch, capsys, tmp_path):
    """Issue 27: a missing optional package (pyvista, h5py ...) was an internal error."""
    from liftoff.workflows import cli

    def boom(args):
        raise ModuleNotFoundError("No module named 'pyvista'", name="pyvista")

    parser = cli.build_parser()
    monkeypatch.setattr(cli, "build_parser", lambda: parser)
    monkeypatch.setattr(parser, "parse_args", lambda argv: type("A", (), {"func": staticmethod(boom)})())
    assert cli.main(["run", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "needs the Python package 'pyvista'" in err and "--no-snapshots" in err

    def other(args):
        raise ModuleNotFoundError("No module named 'nonesuch'", name="nonesuch")
    monkeypatch.setattr(parser, "parse_args", lambda argv: type("A", (), {"func": staticmethod(other)})())
    assert cli.main(["run", "--out", str(tmp_path / "o")]) == 1            # not an optional package: a bug
