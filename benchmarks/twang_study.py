"""What sets the twang of the default stack: sensitivity of the tank-tip twang and of the
on-pad rocking period to the stack, skirt, post, pad and engine parameters (issue 15).

    python benchmarks/twang_study.py [--cache DIR] [--only NAME ...] [--list] [--resume]

Each variant is the embedded default scenario (its first case) with a few keys changed
(deep-merged as a ``[[case]]`` override would be). For each it reports, from the FE stack
on its pad with the posts bolted (SI units):

* ``T1`` (s): period of the first coupled vehicle + pad + posts mode (modal stiffness
  diag(omega^2) + D^T K_C D less the gravity softening KSOF, eq. 2 and 27; unit modal
  masses), the on-pad rocking mode;
* ``static`` (m): lateral (y) tank-tip deflection under the full main-engine thrust,
  in the pad frame (the pad's foundation is the ground);
* ``peak``, ``t_peak`` (m, s): largest tank-tip twang (pad frame, relative to its
  position at t0) before booster ignition, from the two-body transient (the scenario's
  transient core, posts bolted until t_ign);
* ``at_ign`` (m): the tank-tip twang at booster ignition and its ratio to ``peak``.

Model stages use the stage cache (default out/.liftoff-cache, shared with `make run`), so
only the components a variant changes are rebuilt. The rows go to
docs/figures/twang_study.json, which benchmarks/default_figures.py renders into
docs/workflow.md, "What sets the twang".
"""
from __future__ import annotations

import argparse
import json
import time
from dataclasses import replace
from pathlib import Path

import liftoff  # noqa: F401 - before numpy: it picks the OpenBLAS kernels (liftoff/core/openblas.py)
import numpy as np

ROOT = Path(__file__).resolve().parent.parent
T_IGN = 6.6

#: Materials of the default: the core wall and orbiter skin are Al 2219 shells (6.8 mm and
#: the skin's share of the structure mass), the boosters the builders' thickened-solid
#: equivalents (meshes/: E_eff, nu, rho_eff; docs/meshes.md) with the default scenario's
#: booster case (12.7 mm D6AC membrane).
MATERIALS = {"core_wall": (73.8e9, 0.33, 2840.0), "srb_case": (17.357e9, 0.29, 1024.447),
             "srb_skirt": (8.905302e9, 0.33, 342.6973), "orbiter_structure": (73.8e9, 0.33, 2840.0),
             "pad_deck": (7.894737e9, 0.30, 240.5370), "pad_pedestals": (19.5e9, 0.29, 765.375),
             "pad_posts": (200e9, 0.29, 7850.0)}
#: the builder's booster case modulus: the whole 75 t case_mass as a 19.6 mm D6AC wall (before issue 15)
E_CASE_BUILDER = 26.75306e9
K_POST = (2.0e9, 2.0e9, 5.0e9)
SSME_SCALE, SSME_DIR = 1.668e6, [0.0, -7.38, 24.03]


def scaled(group: str, factor: float) -> dict:
    """[model.materials] override scaling the default modulus of a volume group (both
    boosters' for srb_*), density and so mass unchanged."""
    E, nu, rho = MATERIALS[group]
    vols = [group.replace("srb_", f"srb_{s}_") for s in ("left", "right")] if group.startswith("srb_") else [group]
    return {"model": {"materials": {v: {"E": E * factor, "nu": nu, "rho": rho} for v in vols}}}


#: the thickened-solid walls everywhere: the default before issue 11 made core and orbiter shells
SOLID = {"model": {"walls": "solid"}}
#: every wall a shell, framed to the thickened solids' wall bending (12 I/t^3 = (t_solid/t_shell)^2:
#: like for like), the rigid attach patches of the solids, and the default's case membrane
#: (12.7 mm of D6AC on the 19.5 mm shell that weighs case_mass)
SHELL_B = {"model": {"walls": "shell", "component": {
    "core": {"params": {"shell_bending_ratio": 490.0, "attach": "patch"}},
    "srb_left": {"params": {"walls": "shell", "case_shell_bending_ratio": 58.6, "attach": "patch"}},
    "orbiter": {"params": {"skin_shell_bending_ratio": 46.5, "attach": "patch"}}},
    "materials": {f"srb_{s}_case": {"E": 205e9 * 0.0127 / 0.0195, "nu": 0.29, "rho": 7850.0} for s in ("left", "right")}}}


def merge_all(*overs: dict) -> dict:
    from liftoff.config import merge

    out: dict = {}
    for o in overs:
        out = merge(out, o)
    return out


def engines(**kw) -> dict:
    return {"engine": [dict(name=f"ssme_{k}", **kw) for k in (1, 2, 3)]}


#: name -> (what it changes, scenario override of the default)
VARIANTS: dict[str, tuple[str, dict]] = {
    "default": ("the default scenario", {}),
    "solid walls": ("walls = solid: thickened tetrahedra everywhere (the default before issue 11)", SOLID),
    "before": ("main before issue 15: SSME 1.80 MN canted 16.6 deg, case of the builder (19.6 mm)",
               merge_all(engines(scale=1.80e6, direction=[0.0, -7.36, 24.67]), scaled("srb_case", E_CASE_BUILDER / 17.357e9))),
    "posts x0.25": ("hold-down stiffness K_C / 4", {"post_defaults": {"stiffness": [k / 4 for k in K_POST]}}),
    "posts x4": ("K_C x 4", {"post_defaults": {"stiffness": [k * 4 for k in K_POST]}}),
    "posts rigid": ("K_C x 100", {"post_defaults": {"stiffness": [k * 100 for k in K_POST]}}),
    "skirt E x0.25": ("booster aft-skirt modulus / 4", scaled("srb_skirt", 0.25)),
    "case E x0.5": ("booster case modulus / 2", scaled("srb_case", 0.5)),
    "case E x2": ("booster case modulus x 2", scaled("srb_case", 2.0)),
    "case 19.6 mm": ("booster case of the builder (75 t as a 19.6 mm wall)", scaled("srb_case", E_CASE_BUILDER / 17.357e9)),
    "core E x0.5": ("core tank wall modulus / 2", scaled("core_wall", 0.5)),
    "orbiter E x0.5": ("orbiter structure modulus / 2", scaled("orbiter_structure", 0.5)),
    "deck E x0.25": ("MLP deck modulus / 4", scaled("pad_deck", 0.25)),
    "deck E x4": ("MLP deck modulus x 4", scaled("pad_deck", 4.0)),
    "pedestals E x0.25": ("pedestal modulus / 4", scaled("pad_pedestals", 0.25)),
    "SSME 1.80 MN": ("main-engine thrust 1.80 MN (before)", engines(scale=1.80e6)),
    "SSME vertical": ("main-engine thrust vertical (no cant)", engines(direction=[0.0, 0.0, 1.0])),
    "SSME cant 8.5 deg": ("half the cant", engines(direction=[0.0, -3.69, 24.64])),
    "no stagger": ("three engines started together", {"engine": [{"name": "ssme_2", "start": 0.0},
                                                                 {"name": "ssme_1", "start": 0.0}]}),
    "build-up x0.7": ("thrust build-up 30 % faster", {"profiles": {"ssme": {
        "time": [0.0, 0.35, 0.7, 1.05, 1.4, 1.75, 2.1, 2.45]}}}),
    "build-up x1.3": ("thrust build-up 30 % slower", {"profiles": {"ssme": {
        "time": [0.0, 0.65, 1.3, 1.95, 2.6, 3.25, 3.9, 4.55]}}}),
    "case E x0.49": ("case modulus x 0.49 (a 6.3 mm wall): the period that brings the tip back at 6.6 s",
                     scaled("srb_case", 0.49)),
    "shell-b": ("walls = shell everywhere with the solids' wall bending and rigid attach patches, the same "
                "case membrane", SHELL_B),
}


def scenario_case(over: dict):
    """The default scenario's first case with ``over`` deep-merged into its common tables."""
    from liftoff.config import default_text, merge, parse_scenario, parse_toml

    data = parse_toml(default_text(), "default_scenario.toml")
    data = merge(data, over)
    data["case"] = [data["case"][0]]
    return parse_scenario(data, "default_scenario.toml").cases[0]


def coupled(problem) -> tuple[np.ndarray, np.ndarray]:
    """Modal stiffness of vehicle + pad + bolted posts less KSOF (unit modal masses), and
    the row matrix D of the post DOFs (relative displacement = D q), from the transient's
    own contact rows (transient.assembly.contact_rows)."""
    from liftoff.transient.assembly import contact_rows

    a, b = problem.body_a, problem.body_b
    na = a.n_modes
    rows = contact_rows(a, b, problem.contacts)
    if np.any(rows.compliance <= 0):
        raise ValueError("twang_study: rigid posts have no stiffness to assemble (use penalty posts)")
    D = np.hstack([rows.Phi_a, -rows.Phi_b])
    K = np.diag(np.concatenate([a.omega ** 2, b.omega ** 2])) + D.T @ (D / rows.compliance[:, None])
    for fb in problem.forcing.feedback:   # the gravity softening (eq. 27), on before ignition
        matrix, rate = fb.dense()         # (a control law has a rate part: not a stiffness)
        if fb.active(0.0) and rate is None:
            K[:na, :na] -= matrix
    return K, D


def ssme_modal_load(problem, t: float) -> np.ndarray:
    """Modal load of the engine tables (mount forces) at time t, vehicle block."""
    a = problem.body_a
    P = np.zeros(a.n_modes)
    for tb in problem.forcing.tables:
        if tb.body == "a" and tb.label.startswith("ssme_mount:"):
            P += a.rows([tb.label])[0] * np.interp(t, tb.time, tb.value)
    return P


def analyse(case, cache, top: str = "stack_top") -> dict:
    from liftoff.transient import solve
    from liftoff.workflows.loads import build_problem
    from liftoff.workflows.pipeline import build_stack

    stack = build_stack(case.model, cache, progress=False)
    cp = build_problem(case, stack, progress=False)
    pr = cp.problem
    K, _ = coupled(pr)
    na = pr.body_a.n_modes
    w2, V = np.linalg.eigh(K)
    f = np.sqrt(np.clip(w2, 0, None)) / (2 * np.pi)
    tip = pr.body_a.rows([f"{top}:Ty"])[0]
    # the lowest mode that moves the tip in y (the rocking mode, not an x-mode)
    ty = np.array([abs(tip @ V[:na, j]) for j in range(len(w2))])
    j1 = int(np.argmax(ty[:6] > 0.1 * ty[:6].max()))
    P = np.zeros(K.shape[0])
    P[:na] = ssme_modal_load(pr, 1e3)
    static = float(tip @ np.linalg.solve(K, P)[:na])
    res = solve(replace(pr, t_end=T_IGN, progress=False))
    lab = res.output_labels["a"]
    y = res.displacement["a"][:, lab.index(f"{top}:Ty")]
    y = y - y[0]
    i = int(np.argmax(np.abs(y)))
    return {"T1": float(1 / f[j1]), "f1": float(f[j1]), "static": static, "peak": float(y[i]),
            "t_peak": float(res.time[i]), "at_ign": float(y[-1]), "ratio": float(y[-1] / y[i]),
            "mass_t": float(pr.body_a.mass / 1e3)}


def variant_key(over: dict) -> str:
    """What a row was computed from: the default scenario's text and the variant's override
    (a row whose key differs was computed on another model and is never reused)."""
    import hashlib

    from liftoff.config import default_text

    return hashlib.sha256((default_text() + json.dumps(over, sort_keys=True)).encode()).hexdigest()[:16]


def write_rows(path: Path, rows: list[dict]) -> None:
    """Write the rows atomically (a killed study leaves the previous file or the new one)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".json.tmp")
    tmp.write_text(json.dumps({"variants": rows}, indent=1) + "\n")
    tmp.replace(path)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cache", type=Path, default=ROOT / "out" / ".liftoff-cache")
    ap.add_argument("--only", nargs="*", default=None)
    ap.add_argument("--list", action="store_true")
    ap.add_argument("--resume", action="store_true",
                    help="keep the rows of --json computed on the same default and override (their key), "
                         "compute the others")
    ap.add_argument("--json", type=Path, default=ROOT / "docs" / "figures" / "twang_study.json",
                    help="write the rows here (benchmarks/default_figures.py renders them into docs/workflow.md)")
    args = ap.parse_args(argv)
    if args.list:
        for k, (what, over) in VARIANTS.items():
            print(f"{k:24s} {what}: {json.dumps(over)}")
        return
    names = args.only or list(VARIANTS)
    unknown = [n for n in names if n not in VARIANTS]
    if unknown:
        raise SystemExit(f"twang_study: unknown variant(s) {unknown} (--list shows them)")
    old = {}
    if args.resume and args.json.exists():
        old = {r["variant"]: r for r in json.loads(args.json.read_text())["variants"]}
    import pyvista  # noqa: F401  (before dolfinx, FENICSX-NOTES.md)

    from liftoff.workflows.cache import StageCache

    cache = StageCache(args.cache)
    rows = []
    print(f"{'variant':24s}{'T1 (s)':>8}{'static (m)':>12}{'peak (m)':>10}{'t_peak':>8}{'at 6.6 s':>10}{'ratio':>7}"
          f"{'wall (s)':>9}")
    for name in names:
        what, over = VARIANTS[name]
        key = variant_key(over)
        if name in old and old[name].get("key") == key:
            r = old[name]
        else:
            t0 = time.perf_counter()
            r = analyse(scenario_case(over), cache)
            r.update(variant=name, what=what, key=key, wall=time.perf_counter() - t0)
        print(f"{name:24s}{r['T1']:8.2f}{r['static']:12.3f}{r['peak']:10.3f}{r['t_peak']:8.2f}{r['at_ign']:10.3f}"
              f"{r['ratio']:7.2f}{r['wall']:9.1f}", flush=True)
        rows.append(r)
        # each row as it comes (and the old rows not yet reached), so a killed study resumes
        write_rows(args.json, rows + [old[n] for n in names[len(rows):] if n in old])
    print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
