"""The default run's figures, generated: README.md and docs/ quote them from here, never typed.

    python benchmarks/default_figures.py [--cache DIR] [--check]

Runs the embedded default scenario (both named cases, no pictures) and writes its figures
to ``docs/figures/default_run.json`` (SI units, full precision), then renders that file and
``docs/figures/convergence.json`` (benchmarks/convergence_study.py) into the blocks between
``<!-- generated:NAME -->`` and ``<!-- /generated:NAME -->`` in README.md and
docs/workflow.md. ``--check`` writes nothing and exits 1 when the checked-in figures differ
from the current code's (tests/workflows/test_default_figures.py does the same).
"""
from __future__ import annotations

import argparse
import json
import re
import shutil
import sys
import tempfile
import time
from pathlib import Path

import liftoff  # noqa: F401 - before numpy: it picks the OpenBLAS kernels (liftoff/core/openblas.py)
import numpy as np

ROOT = Path(__file__).resolve().parent.parent
FIGURES = ROOT / "docs" / "figures"
DEFAULT_JSON = FIGURES / "default_run.json"
CONVERGENCE_JSON = FIGURES / "convergence.json"
TWANG_JSON = FIGURES / "twang_study.json"
MESH_JSON = FIGURES / "mesh_study.json"
BENCH_JSON = FIGURES / "bench_workflow.json"       # benchmarks/bench_workflow.py --json (machine-dependent)
CB_BENCH_JSON = FIGURES / "bench_cb_default.json"  # benchmarks/bench_cb_default.py --json (machine-dependent)
SLOSH_JSON = FIGURES / "slosh_default.json"        # benchmarks/slosh_default.py
SLOSH_COMPARE_JSON = FIGURES / "slosh_compare.json"  # benchmarks/slosh_compare.py
BOOSTER_GRAIN_JSON = FIGURES / "booster_grain.json"  # benchmarks/booster_grain_compare.py
ATTACH_RELEASE_JSON = FIGURES / "attach_release.json"  # benchmarks/attach_release_compare.py
STEP_JSON = FIGURES / "step_study.json"            # benchmarks/step_study.py
KERNEL_FLOOR_JSON = FIGURES / "bench_kernel_floor.json"  # benchmarks/bench_kernel_floor.py --json (machine-dependent)
STATIC_MODES_JSON = FIGURES / "static_modes_study.json"  # benchmarks/static_modes_study.py
CAMPAIGN_BENCH_JSON = FIGURES / "bench_campaign.json"  # benchmarks/bench_campaign.py --json (machine-dependent)
BATCH_BENCH_JSON = FIGURES / "bench_batch.json"    # benchmarks/bench_batch.py --json (machine-dependent)
MPI_BENCH_JSON = FIGURES / "bench_mpi_components.json"  # benchmarks/bench_mpi_components.py --json (machine-dependent)
STIFFENERS_JSON = FIGURES / "stiffeners.json"  # benchmarks/stiffener_compare.py
STRUTS_JSON = FIGURES / "struts.json"          # benchmarks/strut_compare.py
EXAMPLE_JSONS = {n: FIGURES / f"{n}.json" for n in ("single_stick", "saturn_v")}   # benchmarks/example_figures.py
DOCS = (ROOT / "README.md", ROOT / "docs" / "workflow.md", ROOT / "docs" / "transient.md")
#: figures agree when within this relative difference (of the larger of the two or, inside a
#: list, of the list's largest magnitude): the same code on another machine differs by
#: round-off amplified through the contact events (separations and recontacts), far below
#: the 3-4 digits the documents print
RTOL = 2e-3
#: figures that are round-off themselves, compared absolutely: a truncation check's
#: flexibility shortfall with every mode kept (~1e-10; the documents print one digit)
ATOL = {"flexibility_shortfall": 1e-6}
BLOCK = re.compile(r"(<!-- generated:(?P<name>[\w-]+) -->\n)(?P<body>.*?)(<!-- /generated:(?P=name) -->)", re.S)


# ------------------------------------------------------------------ runs
def run_default_like(edit, out: Path, cache: Path | None, error_estimate: bool = True):
    """``liftoff run`` of the default scenario's TOML data changed by ``edit`` (a function of
    the parsed dictionary), both named cases, no plots or pictures: its RunOutput."""
    from liftoff.config import default_text, parse_scenario, parse_toml
    from liftoff.workflows.run import run

    data = edit(parse_toml(default_text(), "default_scenario.toml"))
    sc = parse_scenario(data, "default_scenario.toml")
    return run(sc, out=out, cache_dir=cache if cache is not None else False, progress=False, plots=False,
               snapshots=False, echo=lambda *a, **k: None, error_estimate=error_estimate)


def timed_variant(edit, cache: Path | None):
    """(RunOutput, wall time s) of :func:`run_default_like` without the error estimate, its
    files in a temporary folder (the returned object holds what the figures need)."""
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        out = run_default_like(edit, Path(tmp) / "run", cache, error_estimate=False)
    return out, time.perf_counter() - t0


def compare_main(argv, doc: str, variants: dict, figures_of, json_path: Path, tag: str) -> int:
    """The command line of a comparison of default-like runs (attach_release_compare.py,
    stiffener_compare.py): ``--variants`` (default all of ``variants``' keys) each run by
    ``figures_of(name, cache)`` and written to ``--json`` (default ``json_path``), in
    ``variants``' order, keeping the file's other variants."""
    ap = argparse.ArgumentParser(description=doc, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cache", type=Path, default=ROOT / "out" / ".liftoff-cache")
    ap.add_argument("--variants", nargs="*", default=list(variants), choices=list(variants))
    ap.add_argument("--json", type=Path, default=json_path)
    args = ap.parse_args(argv)
    import pyvista  # noqa: F401  (before dolfinx, FENICSX-NOTES.md)

    out = json.loads(args.json.read_text()) if args.json.is_file() else {}
    for name in args.variants:
        print(f"{tag}: {name} ...", flush=True)
        out[name] = figures_of(name, args.cache)
    out = {k: out[k] for k in variants if k in out}
    args.json.write_text(json.dumps(out, indent=1, default=float) + "\n")
    print(f"wrote {args.json}")
    return 0


def variant_summary(out, wall_s: float, component: str) -> dict:
    """The figures a comparison of default-like runs tabulates (booster_grain_compare.py,
    attach_release_compare.py): ``component``'s FE DOFs, CB modes and stage times, the
    vehicle's modes and mass, the nominal twang, the peak post compression, every attach
    load's peak, the steps and the wall time ``wall_s`` (s)."""
    stack = next(iter(out.stacks.values()))
    v = stack.vehicle
    m, _ = _mass_cg(v)
    rows = out.envelope
    attach = [r for r in rows if r["category"] == "interface_force" and r["unit"] == "N"]
    times = {label.split(" (")[0]: s for label, s in out.stage_times if " (built)" in label}
    return {
        "wall_s": wall_s,
        "booster_fe_dofs": _fe_dofs(stack.components.get(component)),
        "booster_cb_modes": stack.cbs[component].n_modes,
        "booster_fe_s": times.get(f"fe {component}"), "booster_cb_s": times.get(f"cb {component}"),
        "vehicle_modes": v.n_modes, "vehicle_mass_t": m / 1e3,
        "first_elastic_hz": [float(w / (2 * np.pi)) for w in v.omega[6:10]],
        "steps": int(out.results["nominal"][0].time.size - 1),
        "twang": twang_figures(out, "nominal"),
        "peak_post_compression_n": max(r["max"] for r in post_tz_rows(rows)),
        "attach_n": {r["item"]: _peak(r)[0] for r in attach},
        "truncation": [c.as_dict() for c in out.results["nominal"][1].truncation],
    }


def post_tz_rows(rows: list) -> list:
    """The envelope's rows of the posts' axial (Tz) forces."""
    return [r for r in rows if r["category"] == "contact_force" and r["item"].endswith("Tz")]


def twang_figures(out, case: str = "nominal") -> dict:
    """The twang of ``case``: pad-frame peak (m) and its time (s), the value at booster
    ignition (m) and its share of the peak, the peak relative to the c.g. (m)."""
    from liftoff.workflows.report import twang

    res, cp = out.results[case]
    tw = twang(res, cp)
    i, k = tw.i_peak, tw.i_peak_cg
    peak = float(np.hypot(*tw.pad[i]))
    ign = float(np.hypot(*tw.at_ign))
    return {"peak_m": peak, "t_peak_s": float(tw.time[i]), "at_ignition_m": ign, "at_ignition_ratio": ign / peak,
            "t_ignition_s": float(tw.t_ign), "rel_cg_peak_m": float(np.hypot(*tw.rel_cg[k]))}


def _peak(row: dict) -> tuple[float, float, str]:
    """(value, time, case) of a row's larger extreme."""
    if abs(row["max"]) >= abs(row["min"]):
        return row["max"], row["t_max"], row["case_max"]
    return row["min"], row["t_min"], row["case_min"]


#: cases whose own peak equals the envelope's to this relative difference all set it: the
#: default's attach peaks at the first steps, before the control system acts, are the same
#: in both cases but for round-off, which decides which one the envelope names (it changed
#: with the BLAS threads of the FE stage)
TIE = 1e-6


def _cases_reaching(out, row: dict) -> list[str]:
    """The cases (in the scenario's order) whose own peak of ``row``'s item equals the
    envelope's larger extreme to :data:`TIE`."""
    from liftoff.workflows import report

    value = _peak(row)[0]
    side = "max" if value == row["max"] else "min"
    cases = []
    for name, (res, cp) in out.results.items():
        own = next(r for r in report.case_maxmin(res, cp, name, out.scenario.post.acceleration_band_hz)
                   if r["item"] == row["item"])[side]
        if abs(own - value) <= TIE * abs(value):
            cases.append(name)
    return cases


#: the default run's plots README shows (analysis.plots: post and attach forces of the
#: nominal case, the whole run and the release window), copied to docs/figures/default_<name>
README_PLOTS = ("post_forces_nominal.png", "attach_forces_nominal.png")


def default_figures(cache: Path | None, plots_to: Path | None = None) -> dict:
    """Every figure of the default run that the documents quote (SI units); with
    ``plots_to``, the plots README shows (:data:`README_PLOTS`) drawn from the same run into
    that folder as ``default_<name>``."""
    with tempfile.TemporaryDirectory() as tmp:
        out = run_default_like(lambda d: d, Path(tmp) / "run", cache)
        if plots_to is not None:
            from liftoff.analysis.plots import plots

            res, cp = out.results["nominal"]
            drawn = Path(tmp) / "plots"
            drawn.mkdir()
            plots(res, cp, drawn, "nominal")
            for name in README_PLOTS:
                shutil.copyfile(drawn / name, Path(plots_to) / f"default_{name}")
    stack = next(iter(out.stacks.values()))
    v, p = stack.vehicle, stack.pad
    res, cp = out.results["nominal"]
    m, cg = _mass_cg(v)
    rows = out.envelope
    posts = post_tz_rows(rows)
    pressure = [r for r in rows if r["item"].startswith("tank pressure core_lox")]
    largest = sorted((r for r in rows if r["category"] in ("contact_force", "interface_force") and r["unit"] == "N"),
                     key=lambda r: -abs(_peak(r)[0]))[:5]
    heads = {}
    from liftoff.workflows.report import bulge_modes, liquid_heads

    for name, head in liquid_heads(cp).items():
        heads[name] = [float(x) for x in head]
    preload = {}
    for name, (point, comp) in cp.attach.items():
        preload[point] = float(res.recovered[name][0, 2])
    checks = [c.as_dict() for c in cp.truncation]
    return {
        "vehicle": {"modes": v.n_modes, "first_elastic_hz": float(v.omega[6] / (2 * np.pi)),
                    "highest_hz": float(v.omega.max() / (2 * np.pi)), "mass_t": m / 1e3, "cg_m": cg},
        "pad": {"modes": p.n_modes, "first_hz": float(p.omega[0] / (2 * np.pi)),
                "highest_hz": float(p.omega.max() / (2 * np.pi))},
        "components": {n: {"cb_modes": cb.n_modes, "boundary_dofs": len(cb.boundary_labels),
                           "fe_dofs": _fe_dofs(stack.components.get(n)),
                           "slosh_dofs": _slosh_dofs(stack.components.get(n))}
                       for n, cb in stack.cbs.items()},
        "truncation": checks,
        "steps": int(res.time.size - 1), "h_s": float(res.h),
        "step_rule": {**{k: float(res.metadata[k]) for k in ("f_h", "h_default", "f_s", "mode_samples")},
                      **{k: res.metadata[k] for k in ("step_governed_by", "stability_halvings")}},
        "error_estimate": {c: out.results[c][0].metadata.get("error_estimate", {}).get("worst_relative")
                           for c in out.results},
        "twang": {c: twang_figures(out, c) for c in out.results},
        "posts": {c: out.results[c][0].contact_summary() for c in out.results},
        "preload_t0_tz_n": preload,
        "peak_post_compression_n": max(r["max"] for r in posts),
        "largest_loads": [{"item": r["item"], "value": _peak(r)[0], "t_s": _peak(r)[1],
                           "cases": _cases_reaching(out, r)} for r in largest],
        "lox_bottom_pressure_pa": [min(r["min"] for r in pressure), max(r["max"] for r in pressure)]
        if pressure else None,
        "liquid_heads_pa": heads,
        # (the volume change's sign is the eigenvector's, which any eigensolver may flip)
        "bulge_modes": [{k: (abs(float(v)) if k == "dv_m3" else float(v) if isinstance(v, (float, np.floating))
                             else v) for k, v in b.items()} for b in bulge_modes(stack.cbs)],
        "table1": {"rows": list(out.table1.rows), "cg_motion_m": [[float(x) for x in r[:3]] for r in out.table1.motion]},
    }


def _step_rule(fig: dict) -> str:
    """The rule that set the default's step, as the run recorded it (transient/stepping.py:
    the results' step_governed_by and stability_halvings)."""
    r = fig["step_rule"]
    rule = {"mode samples": f"{r['mode_samples']:g} steps a period of the highest mode, {r['f_s']:.0f} Hz; eq. 12 "
                            f"alone: 0.25/f_h = {r['h_default'] * 1e6:.0f} us, f_h = {r['f_h']:.0f} Hz",
            "eq. 12": f"eq. 12: 0.25/f_h, f_h = {r['f_h']:.0f} Hz"}.get(r["step_governed_by"], r["step_governed_by"])
    if r["stability_halvings"]:
        rule += f"; halved {r['stability_halvings']} x for the stability of the penalty coupling"
    return rule


def _slosh_dofs(comp) -> int:
    """The slosh pendulums' DOFs of a component (convective = "slosh"), 0 without."""
    sl = getattr(comp, "slosh", None)
    return 0 if sl is None else sl.n


def _fe_dofs(comp) -> int | None:
    """The FE model's DOFs of a component, less its slosh pendulums' (None: no FE model)."""
    return None if comp is None else comp.n_dof - _slosh_dofs(comp)


def _mass_cg(body) -> tuple[float, list]:
    from liftoff.transient.effects import center_of_gravity

    m, cg = center_of_gravity(body)
    return float(m), [float(x) for x in cg]


# ------------------------------------------------------------------ rendering
def _mn(x: float) -> str:
    return f"{x / 1e6:.2f}"


def render_blocks(fig: dict, conv: dict | None, twang_rows: dict | None = None,
                  mesh: dict | None = None, bench: dict | None = None,
                  examples: dict | None = None, cb_bench: dict | None = None,
                  slosh: dict | None = None, slosh_compare: dict | None = None,
                  booster_grain: dict | None = None, campaign_bench: dict | None = None,
                  attach_release: dict | None = None, step: dict | None = None,
                  kernel_floor: dict | None = None, static_modes: dict | None = None,
                  batch_bench: dict | None = None, mpi_bench: dict | None = None,
                  stiffeners: dict | None = None, struts: dict | None = None) -> dict[str, str]:
    """{block name: markdown} from the figures (and the convergence, twang and mesh studies,
    the workflow benchmark and the launcher examples' figures {name: figures}, if any)."""
    tw, twn = fig["twang"]["nominal"], fig["twang"]
    v, p = fig["vehicle"], fig["pad"]
    lox = fig["lox_bottom_pressure_pa"]
    head = max((max(h) for k, h in fig["liquid_heads_pa"].items() if "lox" in k), default=None)
    pre = fig["preload_t0_tz_n"]
    lines = [
        "| figure of the default run (`make run`, nominal case unless noted) | value |",
        "|---|---|",
        f"| vehicle system modes kept (all) | {v['modes']} (first elastic {v['first_elastic_hz']:.2f} Hz, highest "
        f"{v['highest_hz']:.0f} Hz) |",
        f"| pad system modes kept (all) | {p['modes']} (first {p['first_hz']:.2f} Hz, highest {p['highest_hz']:.0f} Hz) |",
        f"| vehicle mass, c.g. | {v['mass_t']:.1f} t at z = {v['cg_m'][2]:.2f} m |",
        "| FE DOFs; fixed-interface modes kept | " + "; ".join(
            f"{n} {c['fe_dofs']} DOFs" + (f" + {c['slosh_dofs']} slosh pendulums" if c.get("slosh_dofs") else "")
            + f", {c['cb_modes']} modes" for n, c in fig["components"].items()) + " |",
        f"| step | {fig['steps']} steps of h = {fig['h_s'] * 1e6:.1f} us ({_step_rule(fig)}) |",
    ]
    for c in fig["truncation"]:
        mass = "/".join("-" if x is None else f"{100 * x:.1f}" for x in c["effective_mass_kept_xyz"])
        lines.append(f"| truncation check, {c['body']} | static flexibility at {c['n_checked']} contact/attach DOFs "
                     f"short by {c['flexibility_shortfall']:.1g}; effective mass kept {mass} % |")
    err = max(x for x in fig["error_estimate"].values() if x is not None)
    lines += [
        f"| largest estimated step error of a peak post force (Richardson) | {err:.1g} of the largest post force |",
        f"| tank-tip twang (pad frame, from t0) | {tw['peak_m']:.3f} m at {tw['t_peak_s']:.2f} s; relative to the "
        f"c.g. {tw['rel_cg_peak_m']:.3f} m |",
        f"| twang at booster ignition ({tw['t_ignition_s']:.1f} s) | {tw['at_ignition_m']:.3f} m = "
        f"{100 * tw['at_ignition_ratio']:.0f} % of the peak |",
        f"| static load at t0 (Tz; weight and cryo preload): SRB forward attach (left) / orbiter aft bipod (left) | "
        f"{_mn(pre['att_srb_left_fwd'])} / {_mn(pre['att_orb_aft_left'])} MN |",
        f"| peak post compression (envelope) | {_mn(fig['peak_post_compression_n'])} MN |",
    ]
    for r in fig["largest_loads"]:
        lines.append(f"| {r['item']} (envelope) | {_mn(r['value'])} MN at {r['t_s']:.3f} s ({', '.join(r['cases'])}) |")
    if lox:
        lines.append(f"| LOX tank-bottom pressure (dynamic + head), range | {lox[0] / 1e3:.0f} to {lox[1] / 1e3:.0f} kPa"
                     + (f" (head {head / 1e3:.0f} kPa)" if head is not None else "") + " |")
    for b in fig["bulge_modes"]:
        lines.append(f"| first bulge mode, {b['tank']} (fixed-interface) | {b['hz']:.2f} Hz, ullage {b['dv_m3']:.3g} m^3 "
                     f"per unit modal coordinate, axial effective liquid mass {b['m_eff_kg'] / 1e3:.0f} t of "
                     f"{b['m_liquid_kg'] / 1e3:.0f} t |")
    blocks = {"default-run": "\n".join(lines) + "\n"}
    posts = ["| post | separation (s) nominal / no-control | recontacts | peak compression (MN) | peak tension (MN) |",
             "|---|---|---|---|---|"]
    nom, noc = fig["posts"]["nominal"], fig["posts"].get("no-control", fig["posts"]["nominal"])
    for a, b in zip(nom, noc):
        sep = " / ".join("-" if x["separation_time"] is None else f"{x['separation_time']:.4f}" for x in (a, b))
        posts.append(f"| {a['name']} | {sep} | {a['recontacts']} / {b['recontacts']} | "
                     f"{_mn(a['peak_compression'])} / {_mn(b['peak_compression'])} | "
                     f"{_mn(a['peak_tension'])} / {_mn(b['peak_tension'])} |")
    blocks["default-posts"] = "\n".join(posts) + "\n"
    t1 = ["| Table 1: c.g. motion on the pad under static loads | X (mm) | Y (mm) | Z (mm) | X, Y, Z (in) |",
          "|---|---|---|---|---|"]
    for row, m in zip(fig["table1"]["rows"], fig["table1"]["cg_motion_m"]):
        t1.append(f"| {row} | " + " | ".join(f"{1e3 * x:.1f}" for x in m) + " | "
                  + ", ".join(f"{x / 0.0254:.2f}" for x in m) + " |")
    blocks["table1"] = "\n".join(t1) + "\n"
    if conv:
        blocks["convergence"] = render_convergence(conv)
    if twang_rows:
        blocks["twang-study"] = render_twang(twang_rows)
    if mesh:
        blocks["mesh-study"] = render_mesh(mesh)
    if bench:
        blocks.update(render_bench(bench))
    if cb_bench:
        blocks["bench-cb-default"] = render_cb_bench(cb_bench)
    if slosh:
        blocks["slosh-default"] = render_slosh(slosh)
    if slosh_compare:
        blocks["slosh-compare"] = render_slosh_compare(slosh_compare)
    if campaign_bench:
        blocks["bench-campaign"] = render_campaign_bench(campaign_bench)
    if booster_grain and booster_grain.get("solid") and booster_grain.get("grain"):
        blocks["booster-grain"] = render_booster_grain(booster_grain)
    if attach_release and "welded" in attach_release:
        blocks["attach-release"] = render_attach_release(attach_release)
    if step:
        blocks["step-study"] = render_step(step)
    if kernel_floor:
        blocks["bench-kernel-floor"] = render_kernel_floor(kernel_floor)
    if static_modes:
        blocks["static-modes-study"] = render_static_modes(static_modes)
    if batch_bench:
        blocks["bench-batch"] = render_batch_bench(batch_bench)
    if mpi_bench:
        blocks["bench-mpi"] = render_mpi_bench(mpi_bench)
    if stiffeners and "bare" in stiffeners:
        blocks["stiffeners"] = render_stiffeners(stiffeners)
    if struts and "joint" in struts:
        blocks["aft-struts"] = render_aft_struts(struts)
    if examples:
        import runpy

        mod = runpy.run_path(str(ROOT / "benchmarks" / "example_figures.py"), run_name="example_figures")
        for name, ex in examples.items():
            blocks[mod["EXAMPLES"][name].block] = mod["render"](name, ex)
    return blocks


#: issue 28's targets for a default `make run`: warm (cached model stages) and cold, wall seconds
WORKFLOW_TARGET_WARM_S, WORKFLOW_TARGET_COLD_S = 4.0, 20.0


def render_bench(b: dict) -> dict[str, str]:
    """The workflow benchmark (benchmarks/bench_workflow.py --json): a one-line summary and
    the per-stage table (the run's own stage times, cold cache and warm)."""
    m = b.get("model", {})
    on = (f"{m['steps']} steps, {m['vehicle_modes']} vehicle + {m['pad_modes']} pad modes"
          if {"steps", "vehicle_modes", "pad_modes"} <= set(m) else "")
    line = (f"On this {b['cpus']}-core machine ({b['date']}, `benchmarks/bench_workflow.py`, load average "
            f"{b['load_average_end']:.1f} at the end): {b['cold_wall_s']:.0f} s cold (empty stage cache: meshing, FE, "
            f"Craig-Bampton, system modes), {b['warm_wall_s']:.0f} s warm (cache hit"
            + (f"; the fastest of {len(b['warm_walls_s'])}: " + ", ".join(f"{w:.0f}" for w in b["warm_walls_s"]) + " s"
               if len(b.get("warm_walls_s", [])) > 1 else "") + f"){'; ' + on if on else ''}. "
            f"Issue 28's targets: warm <= {WORKFLOW_TARGET_WARM_S:g} s "
            f"{'met' if b['warm_wall_s'] <= WORKFLOW_TARGET_WARM_S else '**not met**'}, cold <= "
            f"{WORKFLOW_TARGET_COLD_S:g} s {'met' if b['cold_wall_s'] <= WORKFLOW_TARGET_COLD_S else '**not met**'}.\n")
    rows = ["| stage | cold (s) | warm (s) |", "|---|---|---|"]
    for name, cold in b["cold_s"].items():
        warm = b["warm_s"].get(name, b["warm_s"].get(name.replace("(built)", "(hit)")))
        rows.append(f"| {name} | {cold:.1f} | {'-' if warm is None else f'{warm:.1f}'} |")
    rows.append(f"| **process wall time** (incl. start-up) | **{b['cold_wall_s']:.1f}** | **{b['warm_wall_s']:.1f}** |")
    return {"bench-summary": line, "bench-workflow": "\n".join(rows) + "\n"}


def render_cb_bench(b: dict) -> str:
    """The fixed-interface eigensolves of the default components (benchmarks/bench_cb_default.py
    --json): block Lanczos against SLEPc's Krylov-Schur, same process, same factor."""
    import statistics

    rows = [f"On this {b['cpus']}-core machine ({b['date']}, `benchmarks/bench_cb_default.py --repeat {b['repeat']}`, "
            f"load average {b['load_average_end']:.1f} at the end), every fixed-interface mode below each default "
            "component's f_max, residual 1e-10:", "",
            "| component | interior DOFs | modes | block Lanczos (s) min / median | basis vectors | SLEPc Krylov-Schur (s) "
            "min / median | SLEPc / block Lanczos | largest eigenvalue difference | block Lanczos shifted to the band's "
            "middle, with its factor (s) min; basis vectors; eigenvalue difference from SLEPc (the CB stage's solve "
            "where given) |", "|---|---|---|---|---|---|---|---|---|"]
    for r in b["rows"]:
        bl, sl, sh = r["block_lanczos_s"], r["slepc_s"], r.get("shifted_s") or []
        rows.append(f"| {r['component']}{' (wet: M + M_a)' if r['wet'] else ''} | {r['interior_dofs']:,} | {r['modes']} | "
                    f"{min(bl):.1f} / {statistics.median(bl):.1f} | {r['block_dimension']} | "
                    f"{min(sl):.1f} / {statistics.median(sl):.1f} | {min(sl) / min(bl):.2f} | "
                    f"{r['max_rel_eig_diff']:.0e} | "
                    + (f"{min(sh):.1f}; {r['shifted_dimension']}; {r['shifted_max_rel_eig_diff']:.0e} |" if sh else "- |"))
    return "\n".join(rows) + "\n"


#: issue 28's target for the transient kernel: its time a step within this ratio of the floor's
KERNEL_TARGET_RATIO = 1.2


def _machine(runs: list[dict], k: int) -> tuple[str, str]:
    """(the opening of measurement ``k``'s heading, "On this 2-core machine (date, CPU ..., ",
    and the suffix naming it in a verdict) of a benchmark file's ``runs``: the first and each
    further machine's (``others``, --append), the CPU said where there are several."""
    r = runs[k]
    cpu = (f"CPU {r['cpu']} ({r['vector_bits']}-bit vectors), " if r.get("cpu") else
           ("CPU not recorded, " if len(runs) > 1 else ""))
    where = "" if len(runs) == 1 else (" on the first machine" if k == 0 else f" on {r.get('cpu', 'the next')}")
    return f"On {'this' if k == 0 else 'another'} {r['cpus']}-core machine ({r['date']}, {cpu}", where


def render_kernel_floor(b: dict) -> str:
    """The transient kernel against a hand-written loop of the same per-step arithmetic
    (benchmarks/bench_kernel_floor.py --json), judged against issue 28's target; a
    measurement on each further machine (``others``, --append) after the first."""
    runs = [b, *b.get("others", [])]
    rows, verdicts = [], []
    for k, r in enumerate(runs):
        ratios = [x["liftoff_us"] / x["floor_us"] for x in r["rows"]]
        machine, where = _machine(runs, k)
        rows += [f"{machine}`benchmarks/bench_kernel_floor.py --repeat {r['repeat']}`, "
                 f"BLAS kernels {r.get('blas_kernels') or 'unknown'}, load average "
                 f"{r['load_average_end'] or float('nan'):.1f} at the end; each time the best of the repeats, liftoff's "
                 "and the floor's taken in turns):", "",
                 "| modes (vehicle + pad) | contact rows | output rows | liftoff (us a step) | floor (us a step) | ratio |",
                 "|---|---|---|---|---|---|"]
        for x, q in zip(r["rows"], ratios):
            rows.append(f"| {x['vehicle_modes']:,} + {x['pad_modes']} | {x['contact_rows']} | {x['outputs']} | "
                        f"{x['liftoff_us']:.1f} | {x['floor_us']:.1f} | {q:.2f} |")
        rows.append("")
        verdicts.append(("met" if all(q <= KERNEL_TARGET_RATIO for q in ratios) else "**not met**")
                        + f" (largest ratio {max(ratios):.2f}{where})")
    rows.append(f"Issue 28's target, liftoff within {KERNEL_TARGET_RATIO}x of the floor: " + "; ".join(verdicts) + ".")
    return "\n".join(rows) + "\n"


#: issue 28's target for cases marched together: case-steps per second against one-by-one solves
BATCH_TARGET = 3.0


def render_batch_bench(b: dict) -> str:
    """Cases marched together against one-by-one solves (benchmarks/bench_batch.py --json),
    judged against issue 28's target; a measurement on each further machine (``others``,
    bench_batch.py --append) after the first, since the speed-up turns on the CPU's vector
    width (8 cases: one 512-bit register, two 256-bit ones)."""
    runs = [b, *b.get("others", [])]
    parts, verdicts = [], []
    for k, r in enumerate(runs):
        ratio = r["one_by_one_us"] / r["batched_us"]
        machine, where = _machine(runs, k)
        d = r.get("default")
        parts += [
            f"{machine}`benchmarks/bench_batch.py --repeat {r['repeat']}`, load average {r['load_average_end']:.1f} at the end; "
            "each time the least of the repeats, the slope of the wall time over 500 and 2,500 steps):", "",
            "| modes (vehicle + pad) | contact rows | cases (group) | batched (us a case-step) | one by one (us a step) "
            "| speed-up | contact forces, batched vs one by one; one by one, modes reordered (of the peak) |",
            "|---|---|---|---|---|---|---|",
            f"| {r['vehicle_modes']:,} + {r['pad_modes']} | {r['contact_rows']} | {r['cases']} ({r['group']}) | "
            f"{r['batched_us']:.1f} | {r['one_by_one_us']:.1f} | {ratio:.2f} | {r['contact_force_diff']:.1e}; "
            f"{r['reordered_contact_force_diff']:.1e} |"]
        if d:
            parts.append(
                f"| {d['vehicle_modes']:,} + {d['pad_modes']}: the default's first {d['cases']} generated cases, whole "
                f"solves of {d['steps']:,} steps (set-up included) | {d['contact_rows']} | {d['cases']} ({d['group']}) | "
                f"{d['batched_s'] / d['steps'] * 1e6:.1f} | {d['one_by_one_s'] / d['steps'] * 1e6:.1f} | "
                f"{d['one_by_one_s'] / d['batched_s']:.2f} | {d['contact_force_diff']:.1e}; - |")
        parts.append("")
        verdicts.append(("met" if ratio >= BATCH_TARGET else "**not met**") + f" ({ratio:.2f}x at the issue's size{where})")
        if d:
            best = min(d["batched_s"], d["one_by_one_s"])
            parts.append(f"The default's generated case takes {best:.2f} s of transient alone there (the faster of "
                         f"the two rows above, one core): 1,000 of them on two cores need at least "
                         f"{1000 * best / 2 / 60:.1f} min before anything else a case costs (issue 28 asks 5 min for "
                         "the whole campaign).")
            parts.append("")
    return "\n".join(parts + [f"Issue 28's target, {BATCH_TARGET:g}x the case-steps per second of one-by-one solves: "
                              + "; ".join(verdicts) + "."]) + "\n"


#: issue 28's target for concurrent components under mpirun: cold model stages against the
#: serial ones (its "serial": one after another)
MPI_TARGET = 1.6


def render_mpi_bench(b: dict) -> str:
    """Cold model stages four ways (benchmarks/bench_mpi_components.py --json)."""
    runs = b["runs"]
    what = {"one-by-one": "serial, one component after another (`LIFTOFF_MODEL_WORKERS=1`)",
            "serial": "serial, the components on a pool of processes (the default)",
            "concurrent": f"`--ranks {b['ranks']}`, the components shared out over the ranks",
            "distributed": f"`--ranks {b['ranks']}`, each component over all ranks, one after another"}
    rep = b.get("repeat", 1)
    rows = [f"On this {b['cpus']}-core machine ({b['date']}, `benchmarks/bench_mpi_components.py --repeat {rep}`, "
            + ("one cold run each" if rep == 1 else f"the least of {rep} cold runs each, taken in turns")
            + f", each with an empty stage cache, load average {b['load_average_end']:.1f} at the end):", "",
            "| cold run | model stages (s) | process (s) | one by one / this |", "|---|---|---|---|"]
    base = runs.get("one-by-one", {}).get("model_stages_s")
    for mode, r in runs.items():
        ratio = f"{base / r['model_stages_s']:.2f}" if base else "-"
        rows.append(f"| {what.get(mode, mode)} | {r['model_stages_s']:.1f} | {r['wall_s']:.1f} | {ratio} |")
    if base and "concurrent" in runs:
        c = base / runs["concurrent"]["model_stages_s"]
        rows += ["", f"Issue 28's target, concurrent components under mpirun {MPI_TARGET:g}x the serial model stages "
                 "one after another: " + ("met" if c >= MPI_TARGET else "**not met**") + f" ({c:.2f}x); against the "
                 "serial run's own pool of processes, which reduces components concurrently too: "
                 f"{runs['serial']['model_stages_s'] / runs['concurrent']['model_stages_s']:.2f}x."
                 if "serial" in runs else ""]
    return "\n".join(rows) + "\n"


#: issue 28's campaign targets: 1,000 dispersed cases on 2 workers within this wall time (s),
#: the process tree's peak memory within this (GB), a Dask LocalCluster within this ratio
CAMPAIGN_TARGET_CASES, CAMPAIGN_TARGET_S, CAMPAIGN_TARGET_GB, CAMPAIGN_TARGET_DASK = 1000, 300.0, 2.0, 1.2


def render_campaign_bench(b: dict) -> str:
    """The load-campaign benchmark (benchmarks/bench_campaign.py --json): each measured
    command, then the issue-28 targets against it. 1,000 cases are extrapolated (said as
    such) from the largest process-pool run when none was measured: its fixed cost (the
    command less its generated cases) plus 1,000 times its wall time per generated case: an
    estimate, as reading the cases' records back at the end also grows with the cases."""
    runs = b["runs"]

    def shown(command: str) -> str:      # less the machine's own paths (--cache DIR, --json FILE)
        words = command.split()
        return " ".join(w for k, w in enumerate(words) if w not in ("--cache", "--json")
                        and (k == 0 or words[k - 1] not in ("--cache", "--json")))

    commands = " and ".join(f"`{shown(c)}`" for c in b["commands"])
    rows = [f"On this {b['cpus']}-core machine ({b['date']}, {commands}; "
            f"{'named cases with' if b.get('snapshots', True) else 'named cases without'} snapshots; "
            "each row one `liftoff run --cases N` process, warm stage cache, fresh campaign folder):", "",
            "| run | default steps per case | wall (s) | generated cases (s) | per generated case (s) | peak memory, "
            "PSS of the process tree (GB) | peak RSS of the command (GB) | CPU (s), cores got | load average |",
            "|---|---|---|---|---|---|---|---|---|"]
    for r in runs:
        gen = r.get("generated_s")
        (a0, *_), (a1, *_) = r["load"]
        gen_s, per_s = ("-", "-") if gen is None else (f"{gen:.1f}", f"{gen / r['cases']:.2f}")
        executor = "Dask LocalCluster" if r["executor"] == "dask" else "process pool"
        k = r.get("march_together", 1)
        together = f", {k} cases marched together a task (`--march-together {k}`)" if k > 1 else ""
        rows.append(f"| {r['cases']:,} cases, {executor} of {r['workers']}{together} | {r.get('steps') or '-'} | "
                    f"{r['wall']:.1f} | {gen_s} | {per_s} | {r['peak_total']:.2f} | {r['peak_main']:.2f} | "
                    f"{r['cpu']:.0f}, {r['cpu'] / r['wall']:.2f} | {a0:.1f} -> {a1:.1f} |")
    pool = [r for r in runs if r["executor"] == "pool" and r.get("generated_s") and r.get("march_together", 1) == 1]
    marched = [r for r in runs if r["executor"] == "pool" and r.get("generated_s") and r.get("march_together", 1) > 1]
    lines = ["", "Against issue 28's targets (the cases one by one, the default):", ""]
    n = CAMPAIGN_TARGET_CASES

    def thousand(rs: list) -> tuple[dict, float, str]:
        """(the largest run, the wall time of n cases, how it was found)."""
        big = max(rs, key=lambda r: r["cases"])
        exact = next((r for r in rs if r["cases"] == n), None)
        if exact is not None:
            return exact, exact["wall"], "measured"
        per = big["generated_s"] / big["cases"]
        return big, big["wall"] - big["generated_s"] + n * per, (
            f"extrapolated from the {big['cases']:,}-case run: its {big['wall'] - big['generated_s']:.0f} s "
            f"besides the generated cases plus {n:,} x {per:.2f} s; an estimate: reading the cases' records "
            "back at the end also grows with the cases, a few ms each")

    if pool:
        big, t, how = thousand(pool)
        met = "met" if t <= CAMPAIGN_TARGET_S else "**not met**"
        lines.append(f"* {n:,} cases on {big['workers']} workers within {CAMPAIGN_TARGET_S / 60:.0f} min: {met}, "
                     f"{t / 60:.1f} min ({how}).")
        peak = max(r["peak_total"] for r in runs if r.get("march_together", 1) == 1)
        met = "met" if peak <= CAMPAIGN_TARGET_GB else "**not met**"
        by_n = sorted(pool, key=lambda r: r["cases"])
        flat = (f"; {by_n[0]['cases']:,} -> {by_n[-1]['cases']:,} cases: {by_n[0]['peak_total']:.2f} -> "
                f"{by_n[-1]['peak_total']:.2f} GB" if len(by_n) > 1 else "")
        lines.append(f"* peak memory within {CAMPAIGN_TARGET_GB:g} GB: {met}, {peak:.2f} GB at most{flat}.")
        dask = [r for r in runs if r["executor"] == "dask"]
        for d in dask:
            same = next((r for r in pool if r["cases"] == d["cases"] and r["workers"] == d["workers"]), None)
            if same is not None:
                ratio = d["wall"] / same["wall"]
                met = "met" if ratio <= CAMPAIGN_TARGET_DASK else "**not met**"
                lines.append(f"* Dask LocalCluster within {CAMPAIGN_TARGET_DASK:g}x of the process pool "
                             f"({d['cases']:,} cases): {met}, {ratio:.2f}x.")
    for r in marched:
        big, t, how = thousand([r])
        lines.append(f"* With {r['march_together']} cases marched together a task (`--march-together "
                     f"{r['march_together']}`, not the default): {n:,} cases {t / 60:.1f} min ({how}), within "
                     f"{CAMPAIGN_TARGET_S / 60:.0f} min: {'met' if t <= CAMPAIGN_TARGET_S else '**not met**'}; peak "
                     f"memory {r['peak_total']:.2f} GB, within {CAMPAIGN_TARGET_GB:g} GB: "
                     f"{'met' if r['peak_total'] <= CAMPAIGN_TARGET_GB else '**not met**'}.")
    return "\n".join(rows + lines) + "\n"


def render_slosh(fig: dict) -> str:
    """The default's slosh modes (benchmarks/slosh_default.py): each core liquid in its rigid
    tank at 1 g, its first lateral mode (P2 pressure; P1 on the same mesh beside it)."""
    rows = ["| liquid | mass (t) | impulsive mass (t) at z (m) | first slosh mode (Hz), P2 (P1) | its slosh mass (t) "
            "at z (m) | pendulum length (m) |", "|---|---|---|---|---|---|"]
    for name, r in fig.items():
        m = r["modes"][0]
        f1 = r["p1_first_hz"]
        rows.append(f"| {name.split('/')[-1]} | {r['mass_kg'] / 1e3:.1f} | {r['impulsive_kg'] / 1e3:.1f} at "
                    f"{r['impulsive_z_m']:.2f} | {m['frequency_hz']:.3f} ({'-' if f1 is None else format(f1, '.3f')}) | "
                    f"{m['mass_kg'] / 1e3:.1f} at {m['height_m']:.2f} | "
                    f"{r['g_eff'] / (2 * 3.141592653589793 * m['frequency_hz']) ** 2:.2f} |")
    return "\n".join(rows) + "\n"


def render_slosh_compare(fig: dict) -> str:
    """The default run with the liquids' sloshing part three ways (benchmarks/slosh_compare.py)."""
    names = {"wall": '"wall" (rigid on the wall)', "free": '"free" (left out)',
             "slosh": '"slosh" (default: pendulums)'}
    keys = [k for k in ("slosh", "wall", "free") if k in fig]
    rows = ["| `convective` | " + " | ".join(names[k] for k in keys) + " |", "|---" * (len(keys) + 1) + "|"]

    def row(label, fn):
        rows.append(f"| {label} | " + " | ".join(fn(fig[k]) for k in keys) + " |")

    row("vehicle modes kept, lateral mass (t)", lambda r: f"{r['vehicle_modes']}, {r['vehicle_mass_t']:.1f}")
    row("twang, nominal (m)", lambda r: f"{r['twang_m']:.3f}")
    row("peak post compression (MN)", lambda r: f"{r['peak_post_compression_n'] / 1e6:.2f}")
    for j in range(3):
        row(f"attach load {j + 1} (MN): " + fig[keys[0]]["largest_attach"][j]["item"],
            lambda r, j=j: next((f"{a['value'] / 1e6:.2f}" for a in r["largest_attach"]
                                 if a["item"] == fig[keys[0]]["largest_attach"][j]["item"]), "-"))
    row("LOX tank-bottom pressure, min .. max (kPa)",
        lambda r: f"{r['lox_bottom_pressure_pa'][0] / 1e3:.0f} .. {r['lox_bottom_pressure_pa'][1] / 1e3:.0f}")
    row("vehicle c.g. at the end, x, y (m); attitude rx, ry (mrad)",
        lambda r: (f"{r['cg_motion_end'][0]:.3f}, {r['cg_motion_end'][1]:.3f}; "
                   f"{1e3 * r['cg_motion_end'][3]:.2f}, {1e3 * r['cg_motion_end'][4]:.2f}"))
    row("first slosh mode (Hz): " + ", ".join(s["liquid"] for s in fig.get("slosh", {}).get("slosh", [])),
        lambda r: ", ".join(f"{s['hz']:.3f}" for s in r["slosh"]) or "-")
    row("peak slosh force (kN)", lambda r: "-" if r["peak_slosh_force_n"] is None else f"{r['peak_slosh_force_n'] / 1e3:.1f}")
    return "\n".join(rows) + "\n"


def _variant_table(head: str, cols: list, lead: list, attach_items) -> str:
    """A comparison of default-like runs (columns ``cols``: (title, variant_summary)): the
    ``lead`` rows (label, function of a column), then the first modes, the twang, the peak
    post compression, the ``attach_items``' peaks, the steps and the wall time."""
    rows = [f"| {head} | " + " | ".join(c for c, _ in cols) + " |", "|---" * (len(cols) + 1) + "|"]
    common = [
        ("first four elastic vehicle modes (Hz)", lambda v: ", ".join(f"{f:.3f}" for f in v["first_elastic_hz"])),
        ("twang, pad frame: peak (m) at t (s); relative to the c.g. (m)",
         lambda v: f"{v['twang']['peak_m']:.3f} at {v['twang']['t_peak_s']:.2f}; {v['twang']['rel_cg_peak_m']:.3f}"),
        ("twang at hold-down release (m)", lambda v: f"{v['twang']['at_ignition_m']:.3f}"),
        ("peak post compression (MN)", lambda v: f"{v['peak_post_compression_n'] / 1e6:.2f}"),
    ] + [(f"{item} (MN)", lambda v, item=item: f"{v['attach_n'][item] / 1e6:.2f}" if item in v["attach_n"] else "-")
         for item in attach_items] + [("steps; run wall time (s)", lambda v: f"{v['steps']}; {v['wall_s']:.0f}")]
    for label, fn in lead + common:
        rows.append(f"| {label} | " + " | ".join(fn(v) for _, v in cols) + " |")
    return "\n".join(rows) + "\n"


def _seconds(x) -> str:
    """A stage time (s) as the comparison tables print it; "-" where not built (a cache hit)."""
    return "-" if x is None else f"{x:.0f}"


def _largest_change(v: dict, base: dict, items) -> str:
    """The largest change of an attach force's peak magnitude among ``items`` in variant
    ``v`` from ``base`` (the default's attach_n; the peaks are signed: a small load's may
    change sign between runs)."""
    k = max(items, key=lambda k: abs(abs(v["attach_n"].get(k, 0.0)) - abs(base[k])))
    d = abs(v["attach_n"].get(k, 0.0)) - abs(base[k])
    return f"{d / 1e6:+.2f} MN ({100 * d / abs(base[k]):+.0f} % of the default's), {k}"


def render_booster_grain(fig: dict) -> str:
    """The default run with thickened solid boosters against case + grain boosters at each
    Craig-Bampton cut (benchmarks/booster_grain_compare.py)."""
    cols = [("thickened solid (default)", fig["solid"])] + [
        (f"case + grain, CB to {k} Hz", v) for k, v in fig["grain"].items()] + [
        (f"case + grain, CB to {k} Hz + residual vectors", v) for k, v in fig.get("grain_rv", {}).items()]

    def modes(v):
        r = v.get("booster_residual_vectors", 0)
        return (f"{v['booster_fe_dofs']}; {v['booster_cb_modes'] - r} ({v['booster_f_max_hz']:g})"
                + (f" + {r} residual" if r else ""))

    lead = [("booster FE DOFs; fixed-interface modes (below f_max Hz)", modes),
            ("booster FE, CB stage times, cold (s, this machine)",
             lambda v: f"{_seconds(v['booster_fe_s'])}, {_seconds(v['booster_cb_s'])}"),
            ("vehicle system modes; mass (t)", lambda v: f"{v['vehicle_modes']}; {v['vehicle_mass_t']:.1f}"),
            ("peak resident memory of the run's processes (GB; - : not recorded)",
             lambda v: "-" if v.get("peak_rss_gb") is None else f"{v['peak_rss_gb']:.1f}")]
    base = fig["solid"]["attach_n"]
    return _variant_table("boosters", cols, lead, sorted(base, key=lambda k: -abs(base[k]))[:5])


#: attach_release_compare.py's variants, as the table heads them
RELEASE_TITLES = {"welded": "all six DOFs joined (before)", "aft_axial": "booster aft attach: Tz released",
                  "boosters": "boosters: forward ball (Rx Ry Rz), aft Tz Rx Ry released; orbiter welded",
                  "bipods": "boosters as before; orbiter bipods: forward Tz Rx Ry Rz, aft Tx Rx Ry Rz released (default)"}


def render_attach_release(fig: dict) -> str:
    """The default run with the attach joints welded and released
    (benchmarks/attach_release_compare.py)."""
    base = fig["welded"]["attach_n"]
    items = [k for k in sorted(base, key=lambda k: (k.split(" on ")[0], k)) if k.endswith(("Tx", "Ty", "Tz"))]
    return _variant_table("attach joints", [(RELEASE_TITLES[k], v) for k, v in fig.items()], [], items)


#: stiffener_compare.py's variants, as the table heads them
STIFFENER_TITLES = {"bare": "bare skins, solid deck (default)", "tank": "external tank: ring frames and stringers",
                    "tank_orbiter": "and the orbiter's", "tank_orbiter_girders": "and the launch table's girder deck"}


def render_stiffeners(fig: dict) -> str:
    """The default run with its walls bare and stiffened by ring frames, stringers and
    girders as beams (benchmarks/stiffener_compare.py); the largest change of an attach
    force's peak magnitude from the bare run's (the peaks are signed: a small load's may
    change sign between runs)."""
    base = fig["bare"]["attach_n"]
    items = [k for k in sorted(base, key=lambda k: (k.split(" on ")[0], k)) if k.endswith(("Tx", "Ty", "Tz"))]

    def built(v):                      # the components this variant built (the others: cache hits)
        parts = [(c, v["components"][c]) for c in ("core", "orbiter", "pad")]
        return "; ".join(f"{c} {p['fe_s']:.0f}, {p['cb_s']:.0f}" for c, p in parts
                         if p["fe_s"] is not None and p["cb_s"] is not None) or "-"

    lead = [("FE DOFs; fixed-interface modes: core, orbiter, pad",
             lambda v: "; ".join(f"{v['components'][c]['fe_dofs']}, {v['components'][c]['cb_modes']}"
                                 for c in ("core", "orbiter", "pad"))),
            ("FE, CB stage times of the components this run built, cold (s, this machine)", built),
            ("vehicle system modes; mass (t)", lambda v: f"{v['vehicle_modes']}; {v['vehicle_mass_t']:.1f}"),
            ("largest change of an attach force's peak magnitude from the default's",
             lambda v: "-" if v is fig["bare"] else _largest_change(v, base, items))]
    return _variant_table("walls and deck", [(STIFFENER_TITLES[k], v) for k, v in fig.items()], lead, items)



#: strut_compare.py's variants, as the table heads them
AFT_STRUT_TITLES = {"joint": "aft: one point, Tz Rx Ry released; forward: ball on the wall (default)",
                    "struts": "aft: three pin-ended struts, tube 0.2 m x 20 mm",
                    "struts_fine": "aft: the 20 mm struts, the boosters meshed 0.7 x as fine (0.42 m)",
                    "struts_thin": "aft: three pin-ended struts, tube 0.2 m x 10 mm",
                    "struts_beam": "aft: the 20 mm struts; forward: ball on the intertank's thrust beam "
                                   "(aluminium box 0.6 m x 1.0 m x 30 mm)",
                    "all": "those, and the orbiter's bipods as six pin-ended struts (tubes as the aft struts)"}


def render_aft_struts(fig: dict) -> str:
    """The default run with each booster's attach hardware as the released joints and as
    beams: the three pin-ended aft struts, and the intertank's thrust beam under the forward
    balls (benchmarks/strut_compare.py): the aft attach's force on the booster (the joint's,
    or the struts' resultant about the joint's point), each strut's peak axial force, and
    the other attach loads (the left booster's side and the orbiter's)."""
    base = fig["joint"]["attach_n"]
    items = [k for k in sorted(base, key=lambda k: (k.split(" on ")[0], k))
             if "right" not in k and "_aft on srb" not in k and k.endswith(("Tx", "Ty", "Tz"))]

    def aft(v):
        a, t0 = v["aft_attach"], v["aft_attach"].get("t0")
        return f"{a['Tx'] / 1e6:.2f}, {a['Ty'] / 1e6:.2f}; {a['Rz'] / 1e6:.2f}" + (
            f" (at t0: {t0['Tx'] / 1e6:.2f}, {t0['Ty'] / 1e6:.2f}; {t0['Rz'] / 1e6:.2f})" if t0 else "")

    def struts(v):
        s = v["aft_attach"].get("struts")
        if not s:
            return "-"
        return "; ".join(f"{k.rsplit('_', 1)[-1]} {p['tension_n'] / 1e6:.2f} / {p['compression_n'] / 1e6:.2f}"
                         for k, p in s.items())

    def bipods(v):
        b = v.get("bipods")
        if not b:
            return "-"
        return "; ".join(f"{b[k]['tension_n'] / 1e6:.2f} / {b[k]['compression_n'] / 1e6:.2f}" for k in
                         ("orbiter_fwd_bipod_left", "orbiter_aft_left_vertical", "orbiter_aft_left_diagonal"))

    def beam(v):
        b = v.get("thrust_beam")
        return "-" if not b else f"{b['Tx'] / 1e6:.2f}, {b['Tz'] / 1e6:.2f}; {b['Ry'] / 1e6:.2f}"

    lead = [("FE DOFs; fixed-interface modes: core, booster",
             lambda v: f"{v['core']['fe_dofs']}, {v['core']['cb_modes']}; {v['booster_fe_dofs']}, "
                       f"{v['booster_cb_modes']}"),
            ("FE, CB stage times, cold (s, this machine): core; booster",
             lambda v: f"{_seconds(v['core']['fe_s'])}, {_seconds(v['core']['cb_s'])}; "
                       f"{_seconds(v['booster_fe_s'])}, {_seconds(v['booster_cb_s'])}"),
            ("vehicle system modes; mass (t)", lambda v: f"{v['vehicle_modes']}; {v['vehicle_mass_t']:.1f}"),
            ("left booster's aft attach, peak (static at t0): Tx, Ty (MN); Rz (MN m) (the joint's, or the struts' "
             "resultant on the booster about the joint's point)", aft),
            ("left booster's aft struts: peak axial force, tension / compression (MN)", struts),
            ("orbiter's bipod struts (forward left, aft left vertical and diagonal): peak axial force, tension / "
             "compression (MN)", bipods),
            ("thrust beam's span at the left wall: peak axial Tx, shear Tz (MN); bending Ry (MN m)", beam),
            ("largest change of another attach force's peak magnitude from the default's",
             lambda v: "-" if v is fig["joint"] else _largest_change(v, base, items))]
    return _variant_table("attach hardware", [(AFT_STRUT_TITLES[k], v) for k, v in fig.items()], lead,
                          items)


def render_mesh(study: dict) -> str:
    """The static mesh study: each level's DOFs, post axial loads at t0 and its largest
    changes from the finest level."""
    posts = list(study["levels"][0]["posts_tz_n"])
    lines = [f"| level (solids' degree, mesh x the sizes before issue 22) | DOFs | post Tz at t0 (MN): {', '.join(posts)} | "
             f"change from {study['finest']}: posts; attach forces; attach moments |", "|---|---|---|---|"]
    for r in study["levels"]:
        ch = r.get("change_from_finest")
        pct = (lambda d: f"{100 * d['change']:.1f} % ({d['item']})")  # noqa: E731
        lines.append(f"| {r['level']} | {sum(r['dofs'].values())} | "
                     + ", ".join(f"{r['posts_tz_n'][p] / 1e6:.2f}" for p in posts) + " | "
                     + (f"{pct(ch['posts'])}; {pct(ch['attach_forces'])}; {pct(ch['attach_moments'])}" if ch else "-")
                     + " |")
    return "\n".join(lines) + "\n"


def render_twang(study: dict) -> str:
    lines = ["| variant (change from the default) | T1 (s) | static (m) | c = static / T1^2 (m/s^2) | peak (m) | "
             "t_peak (s) | at 6.6 s (m) | at 6.6 s / peak |", "|---|---|---|---|---|---|---|---|"]
    for r in study["variants"]:
        bold = "**" if r["variant"] == "default" else ""
        lines.append(f"| {bold}{r['what']}{bold} | {r['T1']:.2f} | {abs(r['static']):.3f} | "
                     f"{abs(r['static']) / r['T1'] ** 2:.4f} | {abs(r['peak']):.3f} | "
                     f"{r['t_peak']:.2f} | {abs(r['at_ign']):.3f} | {r['ratio']:.2f} |")
    return "\n".join(lines) + "\n"


def render_step(study: dict) -> str:
    """The step study (benchmarks/step_study.py): each run's step, twang and the largest
    change of an envelope peak from the finest run's, and the default's largest rows."""
    pct = lambda d: f"{100 * d:.3f} %"  # noqa: E731
    ref = f"h0/{1 / study['reference_factor']:g}"
    lines = [f"| step | steps | h (us) | twang peak (m) at (s); at ignition (m) | "
             f"largest change of a peak from {ref}: any row; posts; attaches |",
             "|---|---|---|---|---|"]
    for r in study["variants"]:
        tw = r["twang"]
        name = "h0 (the default's automatic step)" if r["factor"] == 1.0 else f"h0/{1 / r['factor']:g}"
        lines.append(f"| {name} | {r['steps']} | {r['h_s'] * 1e6:.1f} | {tw['peak_m']:.4f} at {tw['t_peak_s']:.2f}; "
                     f"{tw['at_ignition_m']:.4f} | {pct(r['all']['deviation'])} ({r['all']['item']}); "
                     f"{pct(r['posts']['deviation'])}; {pct(r['attach']['deviation'])} ({r['attach']['item']}) |")
    default = next(r for r in study["variants"] if r["factor"] == 1.0)
    lines.append("")
    lines.append(f"The default's largest changes from {ref} (against the row's own peak; against "
                 f"the largest peak of the point's vector): " + "; ".join(
                     f"{x['item']} {pct(x['deviation'])}, {pct(x['point_deviation'])}" for x in default["largest_rows"])
                 + f". The highest dynamic mode: {default['f_s_hz']:.0f} Hz; the contact frequency of eq. 12: "
                 f"{default['f_h_hz']:.0f} Hz (0.25/f_h = {0.25e6 / default['f_h_hz']:.0f} us).")
    return "\n".join(lines) + "\n"


def render_static_modes(study: dict) -> str:
    """The residual-flexibility study (benchmarks/static_modes_study.py): per cut, the
    static modes, the step, the transients' time and the largest change of an envelope
    peak from the default with every mode dynamic (against the row's own peak and the
    point's vector); the default's own cut marked."""
    pct = lambda d: f"{100 * d:.3g} %"  # noqa: E731
    default = study.get("default_static_above_hz")
    lines = ["| `[time] static_above_hz` | static modes, vehicle / pad | steps | h (us) | transients, both cases (s) | "
             "twang peak (m) | largest change of a peak from every mode dynamic: any row (of its point's vector); "
             "posts; attaches (the row) | rows over 1 % (of the point's vector) |",
             "|---|---|---|---|---|---|---|---|"]
    for r in study["variants"]:
        cut = "none (every mode dynamic)" if r["static_above_hz"] is None else (
            f"{r['static_above_hz']:g} Hz" + (", every mode dynamic's step" if r["same_step"] else "")
            + (" (the default)" if r["static_above_hz"] == default and not r["same_step"] else ""))
        worst = max(r["largest_rows"], key=lambda x: x["deviation"])
        att = r["attach"]
        lines.append(f"| {cut} | {r['static_modes'][0]} / {r['static_modes'][1]} | {r['steps']} | "
                     f"{r['h_s'] * 1e6:.1f} | {r['transients_s']:.1f} | {r['twang']['peak_m']:.4f} | "
                     f"{pct(worst['deviation'])} ({pct(worst['point_deviation'])}, {worst['item']}); "
                     f"{pct(r['posts']['deviation'])}; {pct(att['deviation'])} ({att['item']}) | "
                     f"{r['over_1pct']} ({r['over_1pct_of_point']}) of {r['n_rows']} |")
    return "\n".join(lines) + "\n"


def render_convergence(conv: dict) -> str:
    """The convergence study: each variant's twang and the largest change of an envelope
    peak from the reference (and, for the cuts, from the default)."""
    pct = lambda d: f"{100 * d['deviation']:.2f} %"  # noqa: E731
    lines = [f"| variant | vehicle / pad modes | steps | twang peak (m) at (s); at ignition (m) | largest change of a "
             f"peak from the {conv['reference']}: any row; posts; attaches | rows over 1 % (of the row; of the "
             "point's vector) | from the default: posts; attaches |", "|---|---|---|---|---|---|---|"]
    for r in conv["variants"]:
        tw, vd = r["twang"], r.get("vs_default")
        lines.append(f"| {r['variant']}: {r['what']} | {r['vehicle_modes']} / {r['pad_modes']} | {r['steps']} | "
                     f"{tw['peak_m']:.3f} at {tw['t_peak_s']:.2f}; {tw['at_ignition_m']:.3f} | "
                     f"{pct(r['all'])} ({r['all']['item']}); {pct(r['posts'])}; {pct(r['attach'])} | "
                     f"{r['over_1pct']}; {r.get('over_1pct_of_point', '-')} of {r['n_rows']} | "
                     + (f"{pct(vd['posts'])}; {pct(vd['attach'])} ({vd['attach']['item']})" if vd else "-") + " |")
    default = next((r for r in conv["variants"] if r["variant"] == "default"), None)
    if default and default.get("rows_over_1pct"):
        lines.append("")
        lines.append("The default's rows over 1 % of the reference (change against the row's own peak; against "
                     "the largest peak of the point's vector): " + "; ".join(
                         f"{x['item']} {100 * x['deviation']:.2f} %, {100 * x['point_deviation']:.2f} %"
                         for x in default["rows_over_1pct"]) + ".")
    mixed = [r for r in conv["variants"] if r.get("default_rows") and r["variant"] not in ("default", conv["reference"])
             and (r["variant"].endswith("f_max") or r["variant"].startswith("mesh"))]
    if default and default.get("rows_over_1pct") and mixed:
        lines.append("")
        lines.append("Those rows in the variants that take more modes (one component at a time, the boosters "
                     "together) or a finer mesh, change from the reference against the row's own peak:")
        lines.append("")
        lines.append("| row | default | " + " | ".join(r["variant"] for r in mixed) + " |")
        lines.append("|---|---|" + "---|" * len(mixed))
        for x in default["rows_over_1pct"]:
            lines.append(f"| {x['item']} | {100 * x['deviation']:.2f} % | " + " | ".join(
                f"{100 * r['default_rows'][x['item']]:.2f} %" if x["item"] in r["default_rows"] else "-"
                for r in mixed) + " |")
    if default and default.get("system_modes"):
        sm = default["system_modes"]
        lines.append("")
        lines.append("The default's vehicle system modes against the reference's (mode k against mode k), largest "
                     "frequency error below: " + "; ".join(
                         f"{b:g} Hz ({n} modes) {100 * e:.2f} %" for b, n, e in
                         zip(sm["bands_hz"], sm["modes_below"], sm["largest_error"])) + ".")
    return "\n".join(lines) + "\n"


def apply_blocks(text: str, blocks: dict[str, str]) -> str:
    """``text`` with every generated block whose name is in ``blocks`` replaced."""
    return BLOCK.sub(lambda m: m.group(1) + blocks[m.group("name")] + m.group(4)
                     if m.group("name") in blocks else m.group(0), text)


def block_names(text: str) -> list[str]:
    return [m.group("name") for m in BLOCK.finditer(text)]


def studies() -> tuple[dict | None, ...]:
    """The checked-in convergence, twang and mesh studies, the workflow benchmark and the
    single-stick example's figures (None where not run)."""
    out = tuple(json.loads(p.read_text()) if p.is_file() else None
                for p in (CONVERGENCE_JSON, TWANG_JSON, MESH_JSON, BENCH_JSON))
    return out + ({n: json.loads(p.read_text()) for n, p in EXAMPLE_JSONS.items() if p.is_file()},
                  json.loads(CB_BENCH_JSON.read_text()) if CB_BENCH_JSON.is_file() else None,
                  json.loads(SLOSH_JSON.read_text()) if SLOSH_JSON.is_file() else None,
                  json.loads(SLOSH_COMPARE_JSON.read_text()) if SLOSH_COMPARE_JSON.is_file() else None,
                  json.loads(BOOSTER_GRAIN_JSON.read_text()) if BOOSTER_GRAIN_JSON.is_file() else None,
                  json.loads(CAMPAIGN_BENCH_JSON.read_text()) if CAMPAIGN_BENCH_JSON.is_file() else None,
                  json.loads(ATTACH_RELEASE_JSON.read_text()) if ATTACH_RELEASE_JSON.is_file() else None,
                  json.loads(STEP_JSON.read_text()) if STEP_JSON.is_file() else None,
                  json.loads(KERNEL_FLOOR_JSON.read_text()) if KERNEL_FLOOR_JSON.is_file() else None,
                  json.loads(STATIC_MODES_JSON.read_text()) if STATIC_MODES_JSON.is_file() else None,
                  json.loads(BATCH_BENCH_JSON.read_text()) if BATCH_BENCH_JSON.is_file() else None,
                  json.loads(MPI_BENCH_JSON.read_text()) if MPI_BENCH_JSON.is_file() else None,
                  json.loads(STIFFENERS_JSON.read_text()) if STIFFENERS_JSON.is_file() else None,
                  json.loads(STRUTS_JSON.read_text()) if STRUTS_JSON.is_file() else None)


# ------------------------------------------------------------------ comparing
def differences(a, b, path: str = "") -> list[str]:
    """Where two figure trees differ: numbers beyond RTOL (relative to the larger of the two
    or, inside a list, to the list's largest magnitude), anything else not equal."""
    out = []
    if isinstance(a, dict) and isinstance(b, dict):
        for k in sorted(set(a) | set(b)):
            if k == "flexibility_dof" and _round_off_shortfall(a) and _round_off_shortfall(b):
                continue       # the DOF where a round-off-sized shortfall peaks is round-off itself
            if k not in a or k not in b:
                out.append(f"{path}/{k}: only in one")
            else:
                out += differences(a[k], b[k], f"{path}/{k}")
    elif isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            return [f"{path}: {len(a)} vs {len(b)} entries"]
        nums = [abs(x) for x in a + b if isinstance(x, (int, float)) and not isinstance(x, bool) and x == x]
        scale = max(nums, default=0.0)
        for i, (x, y) in enumerate(zip(a, b)):
            out += differences(x, y, f"{path}[{i}]") if not _is_num(x) else _num_diff(x, y, f"{path}[{i}]", scale)
    elif _is_num(a) and _is_num(b):
        out += _num_diff(a, b, path, 0.0)
    elif a != b:
        out.append(f"{path}: {a!r} vs {b!r}")
    return out


def _round_off_shortfall(check: dict) -> bool:
    x = check.get("flexibility_shortfall")
    return _is_num(x) and abs(x) <= ATOL["flexibility_shortfall"]


def _is_num(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool)


def _num_diff(x, y, path: str, scale: float) -> list[str]:
    if not (_is_num(x) and _is_num(y)):
        return [] if x == y else [f"{path}: {x!r} vs {y!r}"]
    if x != x and y != y:
        return []
    tol = ATOL.get(path.rsplit("/", 1)[-1], RTOL * max(abs(x), abs(y), scale))
    return [] if abs(x - y) <= tol else [f"{path}: {x!r} vs {y!r}"]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cache", type=Path, default=ROOT / "out" / ".liftoff-cache")
    ap.add_argument("--check", action="store_true", help="compare with the checked-in figures; write nothing")
    ap.add_argument("--render-only", action="store_true", help="only render the checked-in JSON into the documents")
    args = ap.parse_args(argv)
    import pyvista  # noqa: F401  (before dolfinx, FENICSX-NOTES.md)

    if args.render_only:
        fig = json.loads(DEFAULT_JSON.read_text())
    else:                                                             # as the JSON file holds it
        fig = json.loads(json.dumps(default_figures(args.cache, None if args.check else FIGURES)))
    if args.check:
        diff = differences(fig, json.loads(DEFAULT_JSON.read_text()))
        print("\n".join(diff) if diff else "the checked-in figures are the current code's")
        return 1 if diff else 0
    FIGURES.mkdir(parents=True, exist_ok=True)
    DEFAULT_JSON.write_text(json.dumps(fig, indent=1) + "\n")
    blocks = render_blocks(fig, *studies())
    for doc in DOCS:
        doc.write_text(apply_blocks(doc.read_text(), blocks))
    print(f"wrote {DEFAULT_JSON.relative_to(ROOT)} and the generated blocks of "
          f"{', '.join(str(d.relative_to(ROOT)) for d in DOCS)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
