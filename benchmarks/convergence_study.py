"""Is the default run converged in the modes it keeps? The default scenario against a
reference with every component mode below 180 Hz (pad 300 Hz: 3 x the default's 60 Hz and
100 Hz cuts, 1.5 x its boosters' 120 Hz; no n_modes caps) and every system mode, and the
system-mode cuts a user may choose, with and without residual vectors (issue 22;
reduction/truncation.py).

    python benchmarks/convergence_study.py [--cache DIR] [--only NAME ...] [--json PATH]

Each variant is the embedded default scenario with a few [model] keys changed; both named
cases run (nominal, no-control) and the envelope over them is compared, row by row, with
the reference's: the deviation of a row is the larger change of its max and of its min,
relative to the row's largest magnitude in the reference (a peak near zero is judged
against the row's scale, not against itself). The step is each run's own automatic one;
its error is the run's Richardson estimate (shown by ``make run``), not studied here.

Writes ``docs/figures/convergence.json`` (default ``--json``), which
``benchmarks/default_figures.py`` renders into README.md and docs/workflow.md; the test
tests/workflows/test_default_figures.py checks that its default row is what the current
code gives. Model stages use the stage cache (default out/.liftoff-cache).

Memory: the "mesh x0.7" variant built its Craig-Bampton stages two at a time (the default
$LIFTOFF_MODEL_WORKERS on 2 cores) past the 24 GB of this machine (killed at 17 GB resident,
2026-11-26); with ``LIFTOFF_MODEL_WORKERS=1`` it ran. Variants can be run a few at a time
with ``--only NAME ... --reuse`` (the others taken from the JSON file), so that a killed run
loses only its own variants.
"""
from __future__ import annotations

import argparse
import copy
import json
import sys
import tempfile
import time
from pathlib import Path

import liftoff  # noqa: F401 - before numpy: it picks the OpenBLAS kernels (liftoff/core/openblas.py)
import numpy as np
from liftoff.core.labels import COMPONENTS

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks"))
from default_figures import run_default_like, twang_figures  # noqa: E402

REFERENCE = "reference"
#: the reference's cuts (Hz): 3 x the default's 60 Hz (pad 100 Hz), 1.5 x its boosters' 120 Hz
REFERENCE_F_MAX, REFERENCE_PAD_F_MAX = 180.0, 300.0
#: fixed-interface modes a component may have below its f_max here (the library refuses more
#: than reduction.craig_bampton.BAND_MODE_LIMIT: the default core has 1490 below 180 Hz)
STUDY_BAND_LIMIT = 4000


def components_below(f_max: float, pad_f_max: float | None = None, only: tuple[str, ...] | None = None):
    """Every vehicle component's mode below ``f_max`` Hz and the pad's below ``pad_f_max``
    (None: the pad as given), no n_modes caps, every system mode; ``only``: those components
    (names, "pad"), the others as given."""
    def edit(data: dict) -> dict:
        m = data["model"]
        for name, sel in list(m.get("component", {}).items()) + [("pad", m.get("pad", {}))]:
            if (only is not None and name not in only) or (name == "pad" and pad_f_max is None) or "mirror" in sel:
                continue                      # (a mirror keeps its source's modes)
            sel.pop("n_modes", None)
            sel["f_max"] = pad_f_max if name == "pad" else f_max
        m.pop("system", None)
        return data
    return edit


def system_cut(f_max: float, residual: bool, pad_f_max: float | None = None):
    def edit(data: dict) -> dict:
        data["model"]["system"] = {"f_max": f_max, "pad_f_max": pad_f_max or f_max, "residual_vectors": residual}
        return data
    return edit


#: the fixed-interface modes the default capped before issue 22 (srb_right, the mirror of
#: srb_left, keeps its source's)
CAPS = {"core": 30, "srb_left": 20, "orbiter": 20}
PAD_CAP = 30


def capped(data: dict) -> dict:
    m = data["model"]
    for name, n in CAPS.items():
        m["component"][name]["n_modes"] = n
    m["pad"]["n_modes"] = PAD_CAP
    return data


#: mesh sizes (m) of the refined variant: 0.7 x the default's (core 0.85 and orbiter 0.5 from the
#: scenario, boosters 0.6 from their builder, pad 2.4; srb_right mirrors srb_left's mesh)
REFINED = {"core": 0.6, "srb_left": 0.42, "orbiter": 0.35, "pad": 1.7}


def refined(data: dict) -> dict:
    m = data["model"]
    for name, h in REFINED.items():
        (m["pad"] if name == "pad" else m["component"][name])["mesh_size"] = h
    return data


def before_issue_22(data: dict) -> dict:
    """The default before issue 22: P1 solids, the core at 1.2 m and the orbiter at its
    builder's 0.7 m, the caps, the system modes below 60 Hz (pad 100 Hz), no residual vectors."""
    m = data["model"]
    m["degree"] = 1
    m["component"]["core"]["mesh_size"] = 1.2
    m["component"]["orbiter"].pop("mesh_size", None)
    return system_cut(60.0, False, 100.0)(capped(data))


#: (label, what, components, cut Hz) of the variants that take one component (the boosters
#: together) to the reference's modes: which component's truncation moves which row
ONE_AT_A_TIME = (("core", "the core's modes", ("core",), REFERENCE_F_MAX),
                 ("boosters", "the boosters' modes", ("srb_left", "srb_right"), REFERENCE_F_MAX),
                 ("orbiter", "the orbiter's modes", ("orbiter",), REFERENCE_F_MAX),
                 ("pad", "the pad's modes", ("pad",), REFERENCE_PAD_F_MAX))


#: name -> (what it is, edit of the default scenario's TOML data)
VARIANTS = {
    "default": ("every fixed-interface mode below each component's f_max (boosters 120 Hz, core and orbiter "
                "60 Hz, pad 100 Hz), every system mode", lambda d: d),
    REFERENCE: (f"every fixed-interface mode below {REFERENCE_F_MAX:g} Hz (pad {REFERENCE_PAD_F_MAX:g} Hz), "
                "every system mode", components_below(REFERENCE_F_MAX, REFERENCE_PAD_F_MAX)),
    "boosters at 60 Hz": ("the default with the boosters' modes below 60 Hz, as the core's and the orbiter's "
                          "(the default before 2026-11-28)", components_below(60.0, only=("srb_left", "srb_right"))),
    "components to 120 Hz": ("every fixed-interface mode below 120 Hz (pad 200 Hz), every system mode",
                             components_below(120.0, 200.0)),
    "mesh x0.7": ("the default on meshes 0.7 x as fine (core 0.6 m, boosters 0.42 m, orbiter 0.35 m, pad 1.7 m)",
                  refined),
    "component caps": ("the default with the fixed-interface modes capped as before issue 22 (core 30, boosters and "
                       "orbiter 20, pad 30)", capped),
    "before issue 22": ("P1 solids, core 1.2 m, orbiter 0.7 m, those caps, the system modes below 60 Hz (pad "
                        "100 Hz), no residual vectors: the default before issue 22", before_issue_22),
    "system 30 Hz + RV": ("the default with the system modes below 30 Hz and residual vectors", system_cut(30.0, True)),
    "system 30 Hz": ("the default with the system modes below 30 Hz, no residual vectors", system_cut(30.0, False)),
    **{f"{label} to {cut:g} Hz": (
        f"the default with {what} below the reference's {cut:g} Hz, the other components at their f_max",
        components_below(cut, cut, names)) for label, what, names, cut in ONE_AT_A_TIME},
}


LOAD_FACTORS = ("Nx", "Ny", "Nz")      # a component's net c.g. load factor rows (workflows/report.load_factor_items)


def point_of(row: dict) -> str:
    """The vector a row is one component of: its name less the component (``attach X on
    core Ty`` -> ``attach X on core``, ``acc stack_top:Tz`` -> ``acc stack_top``) and its
    unit (forces apart from moments; a component's load factors Nx Ny Nz form one vector); a
    scalar row (a pressure) is its own."""
    item = row["item"]
    for sep in (" ", ":"):
        head, _, last = item.rpartition(sep)
        if head and (last in COMPONENTS or last in LOAD_FACTORS):
            return f"{head} [{row['unit']}]"
    return f"{item} [{row['unit']}]"


def deviations(rows: list[dict], ref: list[dict]) -> list[dict]:
    """Per envelope row: its deviation from the reference's row (module docstring), and
    ``point_deviation``, the same change against the largest peak of the vector the row is
    a component of (the point's forces, moments, accelerations: :func:`point_of`), which is
    how a small component of a large load is judged (an out-of-plane 9 kN at a 12 MN joint)."""
    by = {r["item"]: r for r in ref}
    point_scale: dict[str, float] = {}
    for o in ref:
        k = point_of(o)
        point_scale[k] = max(point_scale.get(k, 0.0), abs(o["max"]), abs(o["min"]))
    out = []
    for r in rows:
        o = by[r["item"]]
        scale = max(abs(o["max"]), abs(o["min"]))
        change = max(abs(r["max"] - o["max"]), abs(r["min"] - o["min"]))
        ps = point_scale[point_of(o)]
        out.append({"item": r["item"], "category": r["category"], "unit": r["unit"],
                    "deviation": change / scale if scale > 0 else 0.0,
                    "point_deviation": change / ps if ps > 0 else 0.0})
    return out


def mode_errors(omega: list[float], omega_ref: list[float], bands=(10, 20, 30, 40, 50, 60)) -> dict:
    """The largest relative frequency error of a variant's system modes below each band (Hz)
    against the reference's, mode k against mode k: the variant's Craig-Bampton space is a
    subspace of the reference's (the same constraint modes, fewer fixed-interface modes), so
    its k-th frequency is an upper bound of the reference's k-th (Rayleigh-Ritz)."""
    f = np.sort(np.asarray(omega)) / (2 * np.pi)
    fr = np.sort(np.asarray(omega_ref)) / (2 * np.pi)
    n = min(f.size, fr.size)
    elastic = fr[:n] > 0.05             # rigid modes (~0 Hz) carry no relative error
    err = np.zeros(n)
    err[elastic] = f[:n][elastic] / fr[:n][elastic] - 1.0
    return {"bands_hz": list(bands),
            "largest_error": [float(np.abs(err[f[:n] < b]).max(initial=0.0)) for b in bands],
            "modes_below": [int((f < b).sum()) for b in bands]}


def summarize(devs: list[dict]) -> dict:
    """Largest deviation over all rows, over posts and attaches, and the worst rows."""
    def worst(sel):
        d = [x for x in devs if sel(x)]
        return max(d, key=lambda x: x["deviation"]) if d else None
    out = {"n_rows": len(devs)}
    for key, sel in (("all", lambda x: True), ("posts", lambda x: x["category"] == "contact_force"),
                     ("attach", lambda x: x["category"] == "interface_force")):
        w = worst(sel)
        out[key] = {"deviation": w["deviation"], "item": w["item"]} if w else None
    out["over_1pct"] = sum(x["deviation"] > 0.01 for x in devs)
    out["over_1pct_of_point"] = sum(x["point_deviation"] > 0.01 for x in devs)
    out["rows_over_1pct"] = [{"item": x["item"], "deviation": x["deviation"], "point_deviation": x["point_deviation"]}
                             for x in sorted(devs, key=lambda x: -x["deviation"]) if x["deviation"] > 0.01]
    return out


def against(runs: list[dict], ref: list[dict]) -> list[dict]:
    """Each run (a dict with its envelope ``rows``) with its rows' deviations from ``ref``
    summarized (:func:`summarize`), its five largest rows and every row's peak (max, min),
    in place of its rows: the table a study script writes (step_study.py, static_modes_study.py)."""
    table = []
    for r in runs:
        devs = deviations(r["rows"], ref)
        s = summarize(devs)
        s["largest_rows"] = [{"item": x["item"], "deviation": x["deviation"], "point_deviation": x["point_deviation"]}
                             for x in sorted(devs, key=lambda x: -x["deviation"])[:5]]
        # every row's peak (max, min): what ties the study to the current default's figures
        s["peaks"] = {x["item"]: [x["max"], x["min"]] for x in r["rows"]}
        table.append({**{k: v for k, v in r.items() if k != "rows"}, **s})
    return table


def run_variant(name: str, cache: Path, tmp: Path) -> dict:
    """One variant's run: what it is, its envelope rows (item, category, unit, max, min), mode
    counts, steps, twang and wall time."""
    t0 = time.perf_counter()
    what, edit = VARIANTS[name]
    out = run_default_like(lambda d: edit(copy.deepcopy(d)), tmp / name.replace(" ", "_"), cache,
                           error_estimate=False)
    stack = next(iter(out.stacks.values()))
    rows = [{k: r[k] for k in ("item", "category", "unit", "max", "min")} for r in out.envelope]
    return {"variant": name, "what": what, "rows": rows, "vehicle_modes": stack.vehicle.n_modes,
            "pad_modes": stack.pad.n_modes, "component_modes": {n: cb.n_modes for n, cb in stack.cbs.items()},
            "steps": next(iter(out.results.values()))[0].time.size - 1, "twang": twang_figures(out),
            "wall_s": time.perf_counter() - t0,
            **({"omega": [float(w) for w in stack.vehicle.omega]} if name in ("default", REFERENCE) else {})}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cache", type=Path, default=ROOT / "out" / ".liftoff-cache")
    ap.add_argument("--only", nargs="*", default=None,
                    help="variants to run (default: all; none with --reuse: only recompute the tables)")
    ap.add_argument("--reuse", action="store_true",
                    help="take the variants not named by --only from the existing --json file instead of running them")
    ap.add_argument("--json", type=Path, default=ROOT / "docs" / "figures" / "convergence.json")
    ap.add_argument("--reference", default=REFERENCE, help="the variant the others are compared with")
    args = ap.parse_args(argv)
    import pyvista  # noqa: F401  (before dolfinx, FENICSX-NOTES.md)
    import importlib

    importlib.import_module("liftoff.reduction.craig_bampton").BAND_MODE_LIMIT = STUDY_BAND_LIMIT

    old = {r["variant"]: r for r in json.loads(args.json.read_text())["variants"]} \
        if args.reuse and args.json.is_file() else {}
    todo = list(VARIANTS if args.only is None else args.only)
    runs = {n: {**old[n], "what": VARIANTS[n][0]} for n in VARIANTS if n in old and n not in todo}
    with tempfile.TemporaryDirectory() as tmp:
        for name in todo:
            runs[name] = r = run_variant(name, args.cache, Path(tmp))
            print(f"{name:20s} vehicle {r['vehicle_modes']:4d} modes, pad {r['pad_modes']:3d}, {r['steps']} steps, "
                  f"{r['wall_s']:.0f} s", flush=True)
    if args.reference not in runs:
        raise SystemExit(f"no run of the reference {args.reference!r} (run it, or --reuse a file that has it)")
    ref = runs[args.reference]["rows"]
    table = []
    watch = ([x["item"] for x in summarize(deviations(runs["default"]["rows"], ref))["rows_over_1pct"]]
             if "default" in runs else [])
    for name in [n for n in VARIANTS if n in runs]:
        r = runs[name]
        devs = deviations(r["rows"], ref)
        s = summarize(devs)
        s["default_rows"] = {x["item"]: x["deviation"] for x in devs if x["item"] in watch}
        if "default" in runs and name not in ("default", args.reference):
            s["vs_default"] = summarize(deviations(r["rows"], runs["default"]["rows"]))
        if "omega" in r and name != args.reference and "omega" in runs[args.reference]:
            s["system_modes"] = mode_errors(r["omega"], runs[args.reference]["omega"])
        table.append({**{k: v for k, v in r.items() if k not in ("vs_default", "omega")}, **s})
        tw = r["twang"]
        print(f"{name:20s} twang {tw['peak_m']:.3f} m at {tw['t_peak_s']:.2f} s, at ignition {tw['at_ignition_m']:.3f} m; "
              f"largest deviation {s['all']['deviation']:.2%} ({s['all']['item']}), posts "
              f"{s['posts']['deviation']:.2%}, attach {s['attach']['deviation']:.2%}, rows over 1 %: {s['over_1pct']}")
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps({"reference": args.reference, "reference_f_max_hz": REFERENCE_F_MAX,
                                     "reference_pad_f_max_hz": REFERENCE_PAD_F_MAX, "variants": table},
                                    indent=1) + "\n")
    print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
