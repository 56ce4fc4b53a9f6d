"""Whole scenarios end to end: stick model (always), FE on a coarse mesh (dolfinx), the
stage cache (a loads-only change skips the model stages; a model change does not), the
`liftoff run` command line (bad input: exit 2, one line, naming the key)."""
import csv
import importlib.util
import re
import tomllib
from dataclasses import replace

import numpy as np
import pytest

from liftoff.transient import load_result
from liftoff.workflows.cli import main
from liftoff.config import default_text

HAVE_FE = all(importlib.util.find_spec(m) is not None for m in ("dolfinx", "gmsh"))


def _toml(d: dict) -> str:
    """Minimal TOML writer for the scenario dictionaries used here."""
    def val(v):
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, float):
            return "inf" if v == float("inf") else repr(v)
        if isinstance(v, (int,)):
            return str(v)
        if isinstance(v, str):
            return '"' + v + '"'
        if isinstance(v, list):
            return "[" + ", ".join(val(x) for x in v) + "]"
        if isinstance(v, dict):
            return "{" + ", ".join(f'"{k}" = {val(x)}' for k, x in v.items()) + "}"
        raise TypeError(type(v))

    out = []
    for k, v in d.items():
        if not isinstance(v, (dict, list)) or (isinstance(v, list) and not (v and isinstance(v[0], dict))):
            out.append(f"{k} = {val(v)}")
    for k, v in d.items():
        if isinstance(v, dict):
            out.append(f"[{k}]")
            out += [f'"{kk}" = {val(x)}' for kk, x in v.items()]
        elif isinstance(v, list) and v and isinstance(v[0], dict):
            for item in v:
                out.append(f"[[{k}]]")
                out += [f'"{kk}" = {val(x)}' for kk, x in item.items()]
    return "\n".join(out) + "\n"


#: the default stack on coarse FE meshes with few modes (also test_mpi_run.py's); its system modes cut
#: without residual vectors on purpose (a small modal model, a large step: test_truncation* cover them)
COARSE_FE = {"source": "fe", "zeta": 0.01,
             "component": {"core": {"type": "shuttle_core", "mesh_size": 1.2, "n_modes": 8, "f_max": 40.0},
                           "srb_left": {"type": "shuttle_booster", "params": {"side": "left"}, "n_modes": 6,
                                        "f_max": 40.0},
                           "srb_right": {"type": "shuttle_booster", "params": {"side": "right"}, "n_modes": 6,
                                         "f_max": 40.0},
                           "orbiter": {"type": "shuttle_orbiter", "n_modes": 6, "f_max": 40.0}},
             "pad": {"type": "launch_table", "mesh_size": 2.4, "n_modes": 8, "f_max": 60.0},
             "joint": tomllib.loads(default_text())["model"]["joint"],         # the Shuttle's seven
             "system": {"f_max": 40.0, "pad_f_max": 60.0, "residual_vectors": False}}


def _scenario(tmp_path, model: dict, t_end=8.0, cases=None, name="s.toml", **over):
    d = tomllib.loads(default_text())
    d["model"] = model
    d["time"]["t_end"] = t_end
    if cases is not None:
        d["case"] = cases
    d.update(over)
    p = tmp_path / name
    p.write_text(_toml(d))
    assert tomllib.loads(p.read_text())["model"] == model
    return p


# (system modes cut without residual vectors on purpose: a small modal model with a large step;
# the modes kept and their convergence are tests/workflows/test_truncation_run.py's)
STICK = {"source": "stick", "mesh_size": 6.0, "zeta": 0.01,
         "system": {"f_max": 60.0, "pad_f_max": 100.0, "residual_vectors": False}, "pad": {"f_max": 100.0}}


def _check_outputs(out, cases, all_cases=None):
    for c in cases:
        res = load_result(out / f"results_{c}.h5")
        assert res.time[-1] > 7.9 and len(res.contact_names) == 8
        assert "cg_motion" in res.recovered and "attach_att_srb_left_fwd" in res.recovered
        # every post separates after the 6.6 s release; the vehicle rises
        assert np.all(np.isfinite(res.separation_time)) and np.all(res.separation_time >= 6.6)
        assert res.rigid_body_motion_a[-1, 2] > 0.5
        for stem in ("post_forces", "attach_forces", "motion", "payload_acc"):
            assert (out / f"{stem}_{c}.png").stat().st_size > 10_000
        rows = list(csv.DictReader(line for line in (out / f"maxmin_{c}.csv").read_text().splitlines()
                                   if not line.startswith("#")))
        assert {r["case_max"] for r in rows} == {c}
        assert any(r["item"] == "post left_1 Tz" for r in rows)
        _check_interface_loads(out, c, res, rows)
        _check_op4(out, res)
        # net c.g. load factors: at t0 the stack rests statically on its pad (exact static
        # start, section 2.6): no acceleration, so every component's load factor is +1 g in z
        names = [n for n in res.recovered if n.startswith("cg_accel_")]
        assert sorted(names) == ["cg_accel_core", "cg_accel_orbiter", "cg_accel_srb_left", "cg_accel_srb_right"]
        for n in names:
            assert np.abs(res.recovered[n][0]).max() < 1e-6 * 9.80665
        lf = {r["item"]: r for r in rows if r["item"].startswith("load factor ")}
        assert len(lf) == 12 and {r["unit"] for r in lf.values()} == {"g"}
        assert float(lf["load factor core Nz"]["max"]) > 1.0 > float(lf["load factor core Nz"]["min"]) > 0.0
    env = list(csv.DictReader(line for line in (out / "maxmin_envelope.csv").read_text().splitlines()
                              if not line.startswith("#")))
    assert {r["case_max"] for r in env} <= set(all_cases or cases)
    t1 = (out / "table1.txt").read_text()
    assert "gravity + softening + cryo" in t1
    _check_modal_tables(out)
    _check_workbook(out, env)
    assert "wall time per stage" in (out / "summary.txt").read_text()
    _check_twang(out, cases)


def _check_correlated(out):
    """correlated_loads.csv (analysis/correlated.py) against the envelope table: the hull of
    (Tz, Mb) over all cases reaches the envelope's Tz max and min of each attach point (the
    hull's extremes are the samples' extremes), and no vertex lies beyond them."""
    env = {r["item"]: r for r in csv.DictReader(ln for ln in (out / "maxmin_envelope.csv").read_text().splitlines()
                                                 if not ln.startswith("#"))}
    rows = list(csv.DictReader(ln for ln in (out / "correlated_loads.csv").read_text().splitlines()
                               if not ln.startswith("#")))
    by: dict = {}
    for r in rows:
        if r["pair"] == "axial-bending":
            by.setdefault(r["interface"], []).append(float(r["x"]))
    assert len(by) == 7
    for itf, xs in by.items():
        e = env[f"{itf} Tz"]
        assert max(xs) == pytest.approx(float(e["max"]), rel=1e-6) and min(xs) == pytest.approx(float(e["min"]), rel=1e-6)
    assert (out / "correlated_loads.png").stat().st_size > 10_000


def _check_workbook(out, env):
    """loads.xlsx (analysis/workbook.py) read back with openpyxl: every max/min envelope row is
    on its category's sheet with the CSV's numbers; the run's other tables have their sheets."""
    openpyxl = pytest.importorskip("openpyxl")
    book = openpyxl.load_workbook(out / "loads.xlsx", read_only=True)
    assert {"contents", "max-min posts", "max-min attach", "max-min load factors", "time-consistent loads",
            "table 1", "system modes", "modal mass vehicle held", "modal mass pad"} <= set(book.sheetnames)
    found = {}
    for name in book.sheetnames:
        if name.startswith("max-min"):
            for row in book[name].iter_rows(values_only=True):
                if row and row[1] in ("N", "N m", "g", "m", "m/s^2", "rad", "Pa", "m^3") and isinstance(row[2], (int, float)):   # openpyxl gives whole numbers as int
                    found[row[0]] = row
    assert len(found) == len(env)
    for r in env:
        assert found[r["item"]][2] == float(r["max"]) and found[r["item"]][6] == float(r["min"])


def _check_modal_tables(out):
    """modes_vehicle.csv and the effective mass tables (reduction/modal_mass.py): the vehicle
    held at its posts and the pad carry, with what sits on their supports, the rigid-body
    mass; the vehicle's is the same in x, y and z and equal to the summary's mass (cg_mass of the
    assembly: an independent computation, to its printed 0.1 t)."""
    modes = list(csv.DictReader(ln for ln in (out / "modes_vehicle.csv").read_text().splitlines()
                                if not ln.startswith("#")))
    assert [r["kind"] for r in modes[:6]] == ["rigid"] * 6 and modes[6]["kind"] == "elastic"
    summary_mass = float(re.search(r"vehicle +\d+ modes, mass ([0-9.]+) t", (out / "summary.txt").read_text())[1])
    for name in ("modal_mass_vehicle_held.csv", "modal_mass_pad.csv"):
        text = (out / name).read_text()
        head = text.splitlines()[0]
        total = np.array([float(x) for x in re.search(r"total mass \(kg\) x/y/z ([^,]+),", head)[1].split("/")])
        held = np.array([float(x) for x in re.search(r"on the supports \(no mode carries it\) (\S+)", head)[1]
                         .split("/")])
        rows = list(csv.DictReader(ln for ln in text.splitlines() if not ln.startswith("#")))
        m = np.array([[float(r[f"m_eff_{a}"]) for a in "xyz"] for r in rows])
        # the table's sum and what the supports hold make the total (the CSV's 7 digits)
        np.testing.assert_allclose(m.sum(axis=0) + held, total, rtol=1e-6)
        assert np.all(m >= 0) and float(rows[-1]["cum_pct_z"]) <= 100 + 1e-6
        if "vehicle" in name:          # the vehicle's translation mass is isotropic (the pad's: a stick
            np.testing.assert_allclose(total, total[0], rtol=1e-9)   # pad's scalar masses need not be)
            assert total[0] / 1e3 == pytest.approx(summary_mass, abs=0.051)
            assert 0 < m[:, 2].sum() < total[2]         # part moves on the posts, the rest sits on them


def _check_interface_loads(out, case, res, maxmin_rows):
    """interface_loads_<case>.csv (analysis/interface_loads.py) against the results file: each
    row is the attach history at its time (to the CSV's 7 digits), and its peak component is
    the max/min table's extreme of that row (the same history, the same step)."""
    from liftoff.analysis.interface_loads import read_csv

    rows = read_csv(out / f"interface_loads_{case}.csv")
    mm = {r["item"]: r for r in maxmin_rows}
    assert len(rows) == 12 * 7                     # 7 attach points x 6 components x (max, min)
    for r in rows:
        hist = res.recovered["attach_" + r["interface"].split()[1]]     # 'attach <point> on <component>'

        i = int(np.argmin(np.abs(res.time - r["time"])))
        np.testing.assert_allclose(r["values"], hist[i], rtol=5e-7, atol=1e-9 * np.abs(hist).max())
        table = mm[f"{r['interface']} {r['labels'][r['component']]}"]
        assert float(table[r["extreme"]]) == pytest.approx(r["values"][r["component"]], rel=1e-6)


TWANG = re.compile(r"twang at stack_top \(pad frame, from t0\): peak ([0-9.]+) m at t = ([0-9.]+) s .*"
                   r"at hold-down release \(t = ([0-9.]+) s\) ([0-9.]+) m.*relative to the c\.g\. \(eq\. 23, from the "
                   r"undeformed stack, ([0-9.]+) m at t0\): peak ([0-9.]+) m")


def _check_twang(out, cases):
    """The summary's twang (issue 15) against the results file: the tank tip's lateral
    displacement from t0 (pad frame) and less the c.g.'s, peaks before the first release."""
    found, case = {}, None
    for line in (out / "summary.txt").read_text().splitlines():
        head = re.match(r"  case '(.+)':", line)
        case = head.group(1) if head else case
        if TWANG.search(line):
            found[case] = TWANG.search(line)
    for c in cases:
        m = found[c]
        res = load_result(out / f"results_{c}.h5")
        lab = list(res.output_labels["a"])
        u = res.displacement["a"][:, [lab.index("stack_top:Tx"), lab.index("stack_top:Ty")]]
        u = u - u[0]
        t_rel = float(np.min(res.release_time))
        before = res.time <= t_rel
        mag = np.hypot(u[:, 0], u[:, 1])
        i = int(np.argmax(np.where(before, mag, -1.0)))
        assert float(m.group(1)) == pytest.approx(mag[i], abs=6e-4)         # printed to 1 mm
        assert float(m.group(2)) == pytest.approx(res.time[i], abs=6e-3)
        assert float(m.group(3)) == pytest.approx(t_rel, abs=6e-3)
        at = np.hypot(*[np.interp(t_rel, res.time, u[:, j]) for j in range(2)])
        assert float(m.group(4)) == pytest.approx(at, abs=6e-4)
        cg = res.recovered["cg_motion"][:, :2]
        rel = np.hypot(*(res.displacement["a"][:, [lab.index("stack_top:Tx"), lab.index("stack_top:Ty")]] - cg).T)
        assert float(m.group(6)) == pytest.approx(rel[before].max(), abs=6e-4)
        assert float(m.group(5)) == pytest.approx(rel[0], abs=6e-4)         # its reference said: t0's value


def test_stick_scenario_end_to_end_and_cache(tmp_path, capsys):
    cache = tmp_path / "cache"
    cases = [{"name": "nominal"},
             {"name": "late-release-wind", "post_defaults": {"release_time": 6.7},
              "force": [{"label": "stack_top:Tx", "time": [0.0, 5.0, 10.0], "value": [0.0, 2.0e5, 2.0e5]}]},
             {"name": "stud-hang", "post": [{"name": "left_1", "vehicle": "srb_left_hd_1",
                                              "pad": "pad_post_left_1", "release_time": float("inf")}]}]
    p = _scenario(tmp_path, STICK, cases=cases)
    assert main(["run", str(p), "--out", str(tmp_path / "a"), "--cache", str(cache), "--no-progress"]) == 0
    text = capsys.readouterr().out
    assert "separation (s)" in text and "Vehicle c.g. motion under static loads" in text
    _check_outputs(tmp_path / "a", ["nominal", "late-release-wind"], ["nominal", "late-release-wind", "stud-hang"])
    _check_correlated(tmp_path / "a")
    for png in ("srs.png", "psd_nominal.png", "attach_moments_nominal.png"):    # the spectra and moments, drawn
        assert (tmp_path / "a" / png).stat().st_size > 10_000
    # the wind leans the stack in +x (the symmetric nominal case has no x motion at all)
    wind, nom = (load_result(tmp_path / "a" / f"results_{c}.h5") for c in ("late-release-wind", "nominal"))
    assert wind.recovered["cg_motion"][-1, 0] > 1e-3 > abs(nom.recovered["cg_motion"][-1, 0]) * 1e3
    # a stud that never releases holds its post bolted (in tension) while the others separate
    hang = load_result(tmp_path / "a" / "results_stud-hang.h5")
    assert np.isnan(hang.separation_time[0]) and np.all(np.isfinite(hang.separation_time[1:]))
    assert hang.contact_force[-1, 2] < -1e6                    # left_1 Tz: tension on the vehicle
    assert (tmp_path / "a" / "snapshot_max_twang_nominal.png").stat().st_size > 10_000
    # loads-only change: every model stage comes from the cache
    p2 = _scenario(tmp_path, STICK, cases=[{"name": "nominal"}], name="s2.toml",
                   engine=tomllib.loads(default_text())["engine"][:3])
    assert main(["run", str(p2), "--out", str(tmp_path / "b"), "--cache", str(cache), "--no-progress",
                 "--no-snapshots"]) == 0
    text = capsys.readouterr().out
    assert "(built)" not in text and text.count("(hit)") == 12     # 5 components, 5 CB, 2 system
    # the model's outputs (recovery OP4, mode shapes, modal tables) copied from the cache, written
    # once per model
    assert len(list((cache / "outputs").glob("*.entry.json"))) == 3
    for f in ("recovery_vehicle.op4", "recovery_vehicle_op4.csv", "modes_vehicle.vtu", "modes_vehicle.csv",
              "modes_vehicle.h5", "modal_mass_vehicle_held.csv", "modal_mass_pad.csv"):
        assert (tmp_path / "b" / f).read_bytes() == (tmp_path / "a" / f).read_bytes()
    # a model change rebuilds (never a stale model)
    p3 = _scenario(tmp_path, {**STICK, "mesh_size": 7.0}, cases=[{"name": "nominal"}], name="s3.toml")
    assert main(["run", str(p3), "--out", str(tmp_path / "c"), "--cache", str(cache), "--no-progress",
                 "--no-snapshots"]) == 0
    assert capsys.readouterr().out.count("(built)") == 12
    assert len(list((cache / "outputs").glob("*.entry.json"))) == 6


def test_cli_bad_scenario_one_line(tmp_path, capsys):
    d = tomllib.loads(default_text())
    d["model"] = STICK
    d["post"][2]["vehicle"] = "srb_left_hd_9"
    p = tmp_path / "bad.toml"
    p.write_text(_toml(d))
    assert main(["run", str(p), "--out", str(tmp_path / "o"), "--no-cache", "--no-progress"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "bad.toml: case 'nominal': post[2] 'left_3'.vehicle: point 'srb_left_hd_9'" in err
    assert not list((tmp_path / "o").glob("results_*.h5"))
    p.write_text("[model]\nsource = 'nastran'\n")
    assert main(["run", str(p), "--out", str(tmp_path / "o")]) == 2
    assert "bad.toml: model.source" in capsys.readouterr().err


def test_cli_bad_liquid_one_line(tmp_path, capsys):
    """[model] liquid: an unknown model, or a liquid for the stick source, exits 2 with one line
    naming the file and the key, before any output."""
    d = tomllib.loads(default_text())
    d["model"]["liquid"] = "frozen"
    p = tmp_path / "bad.toml"
    p.write_text(_toml(d))
    assert main(["run", str(p), "--out", str(tmp_path / "o"), "--no-cache", "--no-progress"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "bad.toml: model.liquid: must be one of smeared, hydroelastic" in err
    d["model"] = dict(STICK, liquid="hydroelastic")
    p.write_text(_toml(d))
    assert main(["run", str(p), "--out", str(tmp_path / "o"), "--no-cache", "--no-progress"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "bad.toml: model.liquid: [model] liquid is for source = \"fe\"" in err
    assert not (tmp_path / "o").exists() or not list((tmp_path / "o").iterdir())


@pytest.mark.fem
@pytest.mark.skipif(not HAVE_FE, reason="needs dolfinx and gmsh")
def test_cb_stages_on_a_pool_give_the_sequential_stack(tmp_path, monkeypatch):
    """The FE and Craig-Bampton stages run by a pool of two processes, each component's two
    stages on one (pipeline.reduce_concurrently), give the stack of the sequential run: the
    same FE matrices, the same fixed-interface and system frequencies (the same block
    Lanczos, BLAS on one thread instead of two: round-off, far below the 1e-9 required);
    the run's cache log gives the workers' builds, and once in the cache a second build is
    all hits. A component whose FE stage is cached and CB stage is not goes to the pool for
    its CB stage alone."""
    import shutil

    from liftoff.config import load_scenario
    from liftoff.workflows import pipeline
    from liftoff.workflows.cache import StageCache
    from liftoff.workflows.pipeline import build_stack, component_stage, is_fe_component

    pool_logs, reduce = [], pipeline.reduce_concurrently     # each pool's logs, by component (a worker that
    monkeypatch.setattr(pipeline, "reduce_concurrently",     # fails is left to the sequential stages: not in them)
                        lambda *a, **k: pool_logs.append(reduce(*a, **k)) or pool_logs[-1])
    model = load_scenario(_scenario(tmp_path, COARSE_FE, cases=[{"name": "nominal"}])).cases[0].model
    seq = build_stack(model, StageCache(tmp_path / "a"), progress=False, workers=1)
    fe = [n for n in seq.cbs if is_fe_component(model, n)]
    assert len(fe) >= 2
    # a cold build through the pool (pipeline.reduce_concurrently): its log has each worker's two
    # builds, in place of the loads; the same FE matrices and frequencies as the sequential build
    cache = StageCache(tmp_path / "b")
    con = build_stack(model, cache, progress=False, workers=2)
    logs = pool_logs[-1]
    assert set(logs) == set(fe)                              # every component built by a worker, its two stages
    assert all([(e[0], e[2]) for e in logs[n]] == [("fe", "built"), ("cb", "built")] for n in fe), logs
    assert sorted((e[0], e[1]) for e in cache.log if e[0] in ("fe", "cb") and e[2] == "built") == sorted(
        (st, n) for n in fe for st in ("fe", "cb")), cache.log
    for name in fe:
        comp, _, _ = component_stage(model, name, cache, tmp_path)
        assert (comp.K != seq.components[name].K).nnz == 0 and (comp.M != seq.components[name].M).nnz == 0, name
    for name, cb in seq.cbs.items():
        assert np.allclose(con.cbs[name].fixed_omega, cb.fixed_omega, rtol=1e-9, atol=0), name
    # once in the cache, a second build is all hits
    cache.log.clear()
    again = build_stack(model, cache, progress=False, workers=2)
    assert all(how == "hit" for stage, _, how, _ in cache.log if stage in ("fe", "cb"))
    assert np.array_equal(again.vehicle_modes.freq_hz, con.vehicle_modes.freq_hz)
    # the FE stages cached, the CB stages not: the pool runs the CB stages (FE hits in the workers)
    shutil.copytree(tmp_path / "a" / "fe", tmp_path / "d" / "fe")
    part = StageCache(tmp_path / "d")
    build_stack(model, part, progress=False, workers=2)
    built = [(e[0], e[1]) for e in part.log if e[0] in ("fe", "cb") and e[2] == "built"]
    assert sorted(built) == sorted(("cb", n) for n in fe)
    logs = pool_logs[-1]
    assert set(logs) == set(fe) and all([(e[0], e[2]) for e in logs[n]] == [("fe", "hit"), ("cb", "built")]
                                        for n in fe), logs
    f_seq, f_con = seq.vehicle_modes.freq_hz[6:], con.vehicle_modes.freq_hz[6:]
    assert np.allclose(f_con, f_seq, rtol=1e-9), np.max(np.abs(f_con / f_seq - 1))


@pytest.mark.fem
@pytest.mark.slow
@pytest.mark.skipif(not HAVE_FE, reason="needs dolfinx and gmsh")
def _check_modal_deliverables(out, stack):
    """cb_checks.json: every vehicle component's CB model free-free (rigid-body residual OK)
    and their CB masses adding up to the vehicle's rigid-body mass (the assembly adds none:
    1e-9); modes_vehicle.vtu: the first elastic system modes as finite, distinct nodal fields
    over the vehicle's FE nodes, named with the frequencies of modes_vehicle.csv."""
    import json

    import meshio

    checks = {c["name"]: c for c in json.loads((out / "cb_checks.json").read_text())["components"]}
    assert set(checks) == set(stack.cbs)
    vehicle = [n for n in checks if n != "pad"]
    assert all(checks[n]["rb_ok"] for n in vehicle)
    mass = sum(checks[n]["mass_properties_cb"]["mass"] for n in vehicle)
    assert mass == pytest.approx(stack.vehicle.rigid_body_mass[0, 0], rel=1e-9)
    # the grounded pad: no rigid-body check (its boundary is no support), its own mass beside M_B's
    pad = checks["pad"]
    assert pad["grounded"] and pad["rb_ok"] is None
    assert pad["mass_properties_own"]["mass"] == pytest.approx(stack.pad.rigid_body_mass[2, 2], rel=1e-12)
    assert pad["mass_properties_own"]["mass"] > 1.2 * pad["mass_properties_cb"]["mass"]
    text = (out / "cb_checks.txt").read_text()
    assert "Craig-Bampton check: core" in text and "not applicable: grounded" in text and "FAIL" not in text
    mesh = meshio.read(out / "modes_vehicle.vtu")
    assert mesh.points.shape[0] == sum(stack.components[n].nodes.shape[0] for n in vehicle)
    names = sorted(mesh.point_data)
    assert len(names) == min(12, stack.vehicle_modes.n_modes - 6)
    freqs = [float(ln.split(",")[1]) for ln in (out / "modes_vehicle.csv").read_text().splitlines()
             if ln[:1].isdigit()]
    for k, name in enumerate(names):
        assert name == f"mode_{k + 7:03d}_{freqs[k + 6]:.4g}Hz"
        u = mesh.point_data[name]
        assert u.shape == (mesh.points.shape[0], 3) and np.all(np.isfinite(u)) and np.abs(u).max() > 0
    a, b = (mesh.point_data[n].ravel() for n in names[:2])
    assert abs(a @ b) < 0.999 * np.linalg.norm(a) * np.linalg.norm(b)     # two modes, two shapes


def test_fe_scenario_end_to_end_coarse(tmp_path, capsys, monolithic):
    """The default stack in 3-D solids on coarse meshes, few modes: geometry -> FE -> CB ->
    system modes -> transient -> reports, in one go (under a minute on 2 cores). Then,
    on the same (cached) FE models, the bolted phase (SSME build-up, 0-3 s) against the
    monolithic coupled model (vehicle + pad + K_C, scipy DOP853 rtol 1e-10): error below
    1e-5 of the peak post force at h0/8 and second order (ratio > 3 from h0/8 to h0/16).
    Measured with every attach joint released as the default's (boosters and the orbiter's
    bipods): 4.0e-6, 2.8e-6, 9.6e-7, 2.5e-7 at h0/2, h0/4, h0/8, h0/16 (ratios 1.4, 2.9,
    3.8: second order from h0/8 on); with the booster joints alone released, 5.8e-6,
    2.2e-6, 7.0e-7 at h0/2, h0/4, h0/8 (2.6, 3.2); all welded, 2.5e-6, 7.3e-7 at h0/2, h0/4
    (3.4)."""
    p = _scenario(tmp_path, COARSE_FE, cases=[{"name": "nominal"}])
    assert main(["run", str(p), "--out", str(tmp_path / "fe"), "--cache", str(tmp_path / "cache"),
                 "--no-progress"]) == 0
    text = capsys.readouterr().out
    print(text[-3000:])
    _check_outputs(tmp_path / "fe", ["nominal"])
    for what in ("max_twang", "release", "peak_load"):
        assert (tmp_path / "fe" / f"snapshot_{what}_nominal.png").stat().st_size > 20_000

    from liftoff.workflows.cache import StageCache
    from liftoff.workflows.loads import build_problem
    from liftoff.workflows.pipeline import build_stack
    from liftoff.config import load_scenario

    case = load_scenario(p).cases[0]
    cache = StageCache(tmp_path / "cache")
    stack = build_stack(case.model, cache, progress=False)
    assert all(how == "hit" for _, _, how, _ in cache.log)
    _check_modal_deliverables(tmp_path / "fe", stack)
    case = replace(case, time=replace(case.time, t_end=3.0), control=replace(case.control, enabled=False),
                   softening=replace(case.softening, enabled=False))
    errs = monolithic.errors(build_problem(case, stack, progress=False).problem, (8, 16))
    print(f"FE bolted phase vs monolithic: max error / peak post force at h0/8, h0/16: {errs}")
    assert errs[0] < 1e-5 and errs[0] / errs[1] > 3.0


def test_step_by_step_script_is_what_run_does(tmp_path, capsys):
    """workflows/liftoff_step_by_step.py (stick) calls the model and loads functions of `liftoff
    run`: its post forces equal those of build_stack + build_problem on the same case. Same
    functions on the same inputs, so equal up to BLAS summation order (1e-9 of the peak)."""
    from liftoff.transient import solve
    from liftoff.workflows import liftoff_step_by_step as sbs
    from liftoff.workflows.cache import StageCache
    from liftoff.workflows.loads import build_problem
    from liftoff.workflows.pipeline import build_stack

    sbs.main(["--stick", "--out", str(tmp_path)])
    text = capsys.readouterr().out
    assert "gravity + softening + cryo" in text and "left forward attach" in text
    res = load_result(tmp_path / "results.h5")
    case = sbs._scenario(True)
    stack = build_stack(case.model, StageCache(None), progress=False)
    ref = solve(replace(build_problem(case, stack, progress=False).problem, progress=False))
    assert res.contact_force.shape == ref.contact_force.shape
    np.testing.assert_allclose(res.contact_force, ref.contact_force, rtol=0,
                               atol=1e-9 * np.abs(ref.contact_force).max())


@pytest.mark.parametrize("over, code, expect", [
    ({"case": [{"name": "a"}, {"name": "b", "post": [{"name": "left_1", "vehicle": "nowhere",
                                                    "pad": "pad_post_left_1"}]}]},
     2, "s.toml: case 'b': post[0] 'left_1'.vehicle: point 'nowhere' is not on the vehicle model"),
    ({"case": [{"name": "a"}, {"name": "b", "time": {"h": 0.01}}]},
     2, "s.toml: case 'b': time step h = 0.01 s exceeds the stability limit"),
    ({"time": {"t_end": 8.0, "h": 1e-8}}, 4, "GB of histories but the limit is"),
    ({"model": {**STICK, "mesh_size": 0.001}}, 4, "stick component 'core': element length 0.001 m gives 4.69e+04 beams"),
    ({"recovery": {**tomllib.loads(default_text())["recovery"], "attach": []},
      "postprocess": {"srs": {"categories": ["interface_force"]}}},
     2, "s.toml: [postprocess.srs] categories = ['interface_force'] select no history of case 'nominal' "
        "(it has: acceleration, cg_motion, contact_force, displacement)"),
], ids=["case-2-point", "case-2-unstable-h", "memory", "stick-elements", "srs-selects-nothing"])
def test_run_refuses_before_any_output(tmp_path, capsys, over, code, expect):
    """A bad case 2, an unstable step, a run too large for memory or a model too fine for the
    element limit: one line naming file, case and key, the right exit status, and nothing in
    the output folder (checked before the first file is written)."""
    d = tomllib.loads(default_text())
    d["model"] = STICK
    d["time"]["t_end"] = 7.0
    d.update(over)
    p = tmp_path / "s.toml"
    p.write_text(_toml(d))
    out = tmp_path / "o"
    assert main(["run", str(p), "--out", str(out), "--cache", str(tmp_path / "c"), "--no-progress",
                 "--no-snapshots"]) == code
    err = [ln for ln in capsys.readouterr().err.strip().splitlines() if not ln.startswith("liftoff: warning: ")]
    assert len(err) == 1 and expect in err[0], err
    assert not out.exists() or not any(out.iterdir())


def test_item_categories_are_those_of_the_solved_items():
    """The categories a case's items will have, known from its problem before it is solved
    (analysis.histories.item_categories: what the up-front [postprocess.srs]/[postprocess.psd]
    check reads), are those of the items made of its result; with the attach recoveries left
    out, interface_force is not among them."""
    from liftoff.analysis.histories import item_categories, items
    from liftoff.config import parse_scenario
    from liftoff.transient import solve
    from liftoff.workflows.cache import StageCache
    from liftoff.workflows.loads import build_problem
    from liftoff.workflows.pipeline import build_stack

    d = tomllib.loads(default_text())
    d["model"] = STICK
    for attach in (d["recovery"]["attach"], []):
        d["recovery"]["attach"] = attach
        sc = parse_scenario(d, "s.toml")
        case = sc.cases[0]
        cp = build_problem(case, build_stack(case.model, StageCache(None), progress=False), progress=False)
        pr = replace(cp.problem, t_end=cp.problem.t0 + 0.05, progress=False)
        made = {it.category for it in items(solve(pr), cp.attach)}
        assert item_categories(pr) == made
        assert ("interface_force" in made) == bool(attach)


def test_ranks_pass_every_option_to_the_ranks():
    """`liftoff run --ranks N` relaunches itself under mpirun: the ranks' command line
    (workflows.run._child_args) parses back to the same options, less --ranks (it dropped
    --cases, --campaign, --compare, --march-together, --no-error-estimate, --max-memory and
    --workers: the ranks ran another campaign, with exit status 0)."""
    from liftoff.workflows.cli import build_parser
    from liftoff.workflows.run import _child_args

    argv = ["run", "s.toml", "--out", "o", "--ranks", "2", "--cases", "50", "--campaign", "c", "--compare", "old",
            "--march-together", "4", "--no-error-estimate", "--max-memory", "3", "--workers", "0", "--fields",
            "--keep-histories", "--no-plots", "--cache", "k", "--dask", "local"]
    parser = build_parser()
    args = parser.parse_args(argv)
    child = _child_args(args)
    assert "--ranks" not in child
    again = vars(parser.parse_args(child))
    assert {k: v for k, v in again.items() if k != "ranks"} == {k: v for k, v in vars(args).items() if k != "ranks"}
    plain = parser.parse_args(["run", "--out", "o", "--ranks", "2"])
    assert _child_args(plain) == ["run", "--out", "o"]


def test_a_database_column_on_no_dof_names_its_file(tmp_path, capsys):
    """Issue 27: a database file's column naming a DOF the vehicle lacks was blamed on a
    generated ``force[6]`` that is in no file, and the second file's only when case d0001 ran.
    Every file is checked against the model before any case runs: one line naming the file,
    the line and the column, exit 2, nothing written."""
    (tmp_path / "db").mkdir()
    (tmp_path / "db" / "g0.csv").write_text("time,stack_top:Tx\n0,0\n1,1e4\n")
    (tmp_path / "db" / "g1.csv").write_text("time,stack_top:Ty,nope:Tx\n0,0,0\n1,1e4,1e4\n")
    d = tomllib.loads(default_text())
    d["model"], d["time"]["t_end"] = STICK, 7.0
    d["dispersion"] = {"seed": 1, "database": {"files": ["db/g*.csv"]}}
    p = tmp_path / "s.toml"
    p.write_text(_toml(d))
    out = tmp_path / "o"
    assert main(["run", str(p), "--cases", "2", "--out", str(out), "--cache", str(tmp_path / "c"), "--no-progress",
                 "--no-snapshots"]) == 2
    err = [ln for ln in capsys.readouterr().err.strip().splitlines() if not ln.startswith("liftoff: warning: ")]
    assert err == ["liftoff: error: s.toml: dispersion.database: db/g1.csv line 1, column 3 'nope:Tx': unknown DOF "
                   "label 'nope:Tx' on body 'vehicle'"], err
    assert not out.exists() or not any(out.iterdir())


def test_a_case_count_beyond_memory_is_refused_before_any_stage(tmp_path, monkeypatch, capsys):
    """Issue 27: `--cases 1000000` generated and parsed every case before running any. The
    count times what the run keeps per case (campaign.CASE_BYTES) is compared with the memory
    limit before any model stage or case generation (both would fail the test here): one
    line, exit 4."""
    from liftoff.config.dispersion import Dispersion
    from liftoff.workflows import campaign, run

    def never(*a, **k):
        raise AssertionError("reached")

    monkeypatch.setattr(Dispersion, "generate", never)
    monkeypatch.setattr(run, "prepare_models", never)
    monkeypatch.setattr("liftoff.core.memory.available_memory", lambda: 1e6 * campaign.CASE_BYTES)
    p = tmp_path / "s.toml"
    p.write_text('extends = "shuttle"\n[model]\nsource = "stick"\n')
    assert main(["run", str(p), "--cases", "1000000", "--out", str(tmp_path / "o"), "--no-progress"]) == 4
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("liftoff: error: s.toml: 1000000 generated cases: the run keeps about "
                                               "1 kB per case (1 GB) but the limit is 0.8 GB"), err


def _check_op4(out, res):
    """recovery_vehicle.op4 read back with pyyeti (an independent OUTPUT4 reader): FREQ and each
    recovery matrix times the run's modal accelerations give the run's recovered history (the
    same matrices, bit for bit, through the file's double precision)."""
    pytest.importorskip("pyyeti")
    from pyyeti.nastran import op4

    mats = op4.read(str(out / "recovery_vehicle.op4"))
    index = list(csv.DictReader(ln for ln in (out / "recovery_vehicle_op4.csv").read_text().splitlines()
                                if not ln.startswith("#")))
    assert mats["freq"].shape[1] == 1 and np.all(np.diff(mats["freq"][:, 0]) >= 0)
    acc = {r["item"]: r for r in index if r["kind"] == "acc"}
    A = mats[acc["cg_accel_core"]["matrix"].lower()]
    assert A.shape == (3, mats["freq"].shape[0]) and acc["cg_accel_core"]["row_labels"] == "Tx;Ty;Tz"
    # the c.g. motion (eq. 23) is a DTM: the kept modal displacements through it give the history
    disp = {r["item"]: r for r in index if r["kind"] == "disp"}
    D = mats[disp["cg_motion"]["matrix"].lower()]
    q = res.modal["q_a"]
    y = res.recovered["cg_motion"]
    np.testing.assert_allclose(q @ D.T, y, rtol=0, atol=1e-12 * np.abs(y).max())
    # an interface force is an LTM plus a constant (less the component's weight share): at t0,
    # the static state (no acceleration), D q + C gives the history's first row
    const = {r["item"]: r for r in index if r["kind"] == "const"}
    name = next(k for k in const if k.startswith("attach_"))
    D, C = (mats[m[name]["matrix"].lower()] for m in (disp, const))
    y = res.recovered[name]
    assert C.shape == (6, 1) and np.abs(C).max() > 1e-3 * np.abs(y[0]).max()
    np.testing.assert_allclose(D @ q[0] + C[:, 0], y[0], rtol=0, atol=1e-9 * np.abs(y[0]).max())


def test_a_registered_output_is_written_with_the_run(tmp_path):
    """workflows/outputs.py: one registration adds a deliverable (DR_Def style); it is written
    per case into the published folder, and listed in its manifest."""
    from liftoff.workflows import outputs
    from liftoff.workflows.run import run

    seen = []

    @outputs.register_output("test_post_sum", "case", "sum of the posts' axial forces")
    def post_sum(res, cp, out, case):
        ax = [res.axial_column(c) for c in range(len(res.contact_names))]
        path = out / f"post_sum_{case}.csv"
        path.write_text("t,sum_N\n" + "".join(f"{t:.6e},{v:.6e}\n" for t, v in
                                               zip(res.time[::500], res.contact_force[::500][:, ax].sum(axis=1))))
        seen.append(case)
        return [path]

    try:
        post = dict(tomllib.loads(default_text()).get("postprocess", {}), units="in-lbf-s")   # the workbook's units
        p = _scenario(tmp_path, STICK, cases=[{"name": "nominal"}], t_end=7.0, postprocess=post)
        run(p, tmp_path / "o", cache_dir=tmp_path / "cache", progress=False, plots=False, snapshots=False,
            echo=lambda *a, **k: None, error_estimate=False)
    finally:
        outputs.OUTPUTS.pop("test_post_sum", None)
    # [postprocess] units reaches the workbook (analysis.units; tests/analysis/test_workbook.py checks the numbers)
    openpyxl = pytest.importorskip("openpyxl")
    book = openpyxl.load_workbook(tmp_path / "o" / "loads.xlsx", read_only=True)
    assert "in-lbf-s units" in next(book["contents"].iter_rows(min_row=2, max_row=2, values_only=True))[0]
    assert seen == ["nominal"]
    assert (tmp_path / "o" / "post_sum_nominal.csv").read_text().startswith("t,sum_N\n")
    assert "post_sum_nominal.csv" in (tmp_path / "o" / "MANIFEST.json").read_text()
    with pytest.raises(Exception, match="stage must be one of"):
        outputs.register_output("x", "later")


@pytest.mark.parametrize("mass", [1e30, 1.0])
def test_a_platform_mass_out_of_range_is_named(tmp_path, capsys, mass):
    """[model.pad.params] mlp_mass far outside a launch platform's span: one line naming the key
    and the range before any stage (1e30 kg used to end in 'static equilibrium singular')."""
    d = tomllib.loads(default_text())
    d["model"] = dict(STICK, pad={"params": {"mlp_mass": mass}})
    p = tmp_path / "bad.toml"
    p.write_text(_toml(d))
    assert main(["run", str(p), "--out", str(tmp_path / "o"), "--no-cache", "--no-progress"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "mlp_mass" in err and "outside [1000, 1e+09] kg" in err, err
    assert not (tmp_path / "o").exists() or not list((tmp_path / "o").iterdir())


def test_fe_stage_builds_on_one_blas_thread(monkeypatch, tmp_path):
    """The FE stage builds with BLAS on one thread whatever the calling process's limit, so
    a component built by the run's process, a pool worker or an MPI rank's worker is the
    same, bit for bit (the default core's stiffness differed in round-off between one
    thread and two)."""
    from threadpoolctl import threadpool_info, threadpool_limits

    from liftoff.config import load_scenario
    from liftoff.workflows import fe_source, pipeline

    model = load_scenario(_scenario(tmp_path, COARSE_FE, cases=[{"name": "nominal"}])).cases[0].model
    seen = []
    monkeypatch.setattr(fe_source, "build_component",
                        lambda comp, model, work: seen.append(
                            {p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas"}) or ("c", {}))
    with threadpool_limits(limits=2, user_api="blas"):
        assert pipeline.build_component(model, model.components["core"], tmp_path) == ("c", {})
    assert seen == [{1}]


def test_a_case_with_other_model_files_is_named(tmp_path):
    """The run's model files (modes, modal mass, recovery OP4, CB checks, Table 1) are written
    once, of the first named case. A named case whose gravity changes its recovery matrices'
    constant columns (or whose model or recoveries differ) does not share them: summary.txt
    and the console say so, naming it (a review: a user combining results_moon.h5 with the
    OP4 got the first case's gravity column, 6x too large). Cases that share them: no note."""
    from liftoff.config import load_scenario
    from liftoff.workflows.cache import StageCache
    from liftoff.workflows.run import _model_files_note, prepare

    def note_of(path):
        sc = load_scenario(path)
        return _model_files_note(sc, prepare(sc, StageCache(tmp_path / "cache"), False, lambda *a, **k: None,
                                             error_estimate=False))

    p = _scenario(tmp_path, STICK, t_end=1.0, cases=[{"name": "nominal"}, {"name": "no-control",
                                                                             "control": {"enabled": False}},
                                                     {"name": "moon", "gravity": {"accel": [0.0, 0.0, -1.62]}},
                                                     {"name": "stiff",
                                                      "post_defaults": {"stiffness": [2.0e10, 2.0e10, 5.0e10]}},
                                                     {"name": "late", "post_defaults": {"release_time": 6.7}}])
    note = note_of(p)        # (stiffer posts: another Table 1; a later release: the same files)
    assert "cases moon, stiff differ" in note and "no-control" not in note and "late" not in note
    assert "of case nominal's model" in note
    assert note_of(_scenario(tmp_path, STICK, t_end=1.0, name="s2.toml")) == ""


def test_python_runs_manifest_a_command_that_runs():
    """From Python, MANIFEST.json's command is `liftoff run` with the options given (the
    embedded default's `<default ...>` name is no path: left out)."""
    import shlex

    from liftoff.config import load_scenario
    from liftoff.workflows.run import Options, _api_command

    cmd = _api_command(load_scenario(None), 3, Options(march_together=8), False, True, 2e9, snapshots=False)
    assert cmd.endswith(" (called from Python)")
    assert shlex.split(cmd[:-len(" (called from Python)")]) == [
        "liftoff", "run", "--cases", "3", "--march-together", "8", "--no-error-estimate", "--no-snapshots",
        "--max-memory", "2"]
