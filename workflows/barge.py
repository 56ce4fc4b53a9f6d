"""``liftoff run`` of a barge scenario (``kind = "barge"``; ``liftoff run --example barge``):
the reference's barge impact on a dock (Prabhakar & Palermo, section 5, figures 7-9).

Stages: scenario -> barge hull + cradle, cargo tank and dock (gmsh + dolfinx, cached like
the stack's components, workflows/pipeline.py) -> Craig-Bampton -> the barge and cargo
assembled free-free on the cargo interfaces (six rigid modes) and the dock grounded ->
per case: fender contacts (the rubber fenders as contact springs, gap, optional friction
and dashpots), the barge's rigid-body velocity towards the dock (the wave's), optional
wave force tables -> two-body transient -> fender forces, cargo interface loads, deck
accelerations, deformed-shape frames of the impact wave; across the cases the peak
fender force against the dock's stiffness beside the series-spring estimate
F = v0 sqrt(m k_eff), 1/k_eff = 1/k_b + 1/k_d (docs/barge.md).
"""
from __future__ import annotations

import tempfile
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
from liftoff.reduction import Assembly, SystemModes, assemble, keep_modes, truncation_check
from liftoff.reduction.checks import with_own_inertia
from liftoff.transient import ContactPoint, Forcing, InitialState, ModalBody, Recovery, TransientProblem
from liftoff.transient.effects import center_of_gravity

from liftoff.config.barge import BargeCase, BargeModel
from liftoff.config.values import Where
from liftoff.core.errors import InputError
from liftoff.core.labels import COMPONENTS, TRANSLATIONS

from .pipeline import cb_stage, component_stage, modes_stage



@dataclass
class BargeModels:
    """The reduced barge (with its cargo) and dock: components, CB models, assemblies, modes, bodies."""

    components: dict
    cbs: dict
    barge_asm: Assembly
    barge_modes: SystemModes
    barge: ModalBody            # free-free, ref_point at its c.g.
    dock_asm: Assembly
    dock_modes: SystemModes
    dock: ModalBody             # grounded
    timings: dict = field(default_factory=dict)
    truncation: tuple = ()      # (barge, dock) TruncationCheck at the fenders and cargo interfaces

    @property
    def bow_points(self) -> list[str]:
        """Fender contact points on the bow, ``bow_1`` ..."""
        return _numbered(self.barge.points, "bow_")

    @property
    def fender_points(self) -> list[str]:
        """The dock's fender points facing them, ``fender_1`` ..."""
        return _numbered(self.dock.points, "fender_")

    @property
    def stations(self) -> list[str]:
        """Deck response stations, stern (``deck_1``) to bow."""
        return _numbered(self.barge.points, "deck_")

    @property
    def cargo_points(self) -> list[str]:
        """Cargo interfaces (saddle tops), ``cargo_1`` ..."""
        return _numbered(self.barge.points, "cargo_")


def _numbered(points, prefix: str) -> list[str]:
    """The points ``<prefix><k>`` in the order of k."""
    return sorted((p for p in points if p.startswith(prefix) and p[len(prefix):].isdigit()),
                  key=lambda p: int(p[len(prefix):]))


def build_models(model: BargeModel, cache, progress: bool = True) -> BargeModels:
    """All model stages (cached): components, CB, the barge + cargo assembly (free-free) and
    the dock (grounded), their system modes and modal bodies."""
    from tqdm import tqdm

    t0 = time.perf_counter()
    mc = model.model_config()
    comps, cbs, keys = {}, {}, {}
    with tempfile.TemporaryDirectory(prefix="liftoff-barge-") as work:
        for name in tqdm(("barge", "cargo", "dock"), desc="model stages", unit="component", disable=not progress,
                         leave=False):
            comps[name], _, k = component_stage(mc, name, cache, Path(work))
            cbs[name], keys[name] = cb_stage(mc, name, comps[name], k, cache)
    t1 = time.perf_counter()
    basm = assemble([cbs["barge"], cbs["cargo"]], "barge")
    ball = modes_stage(basm, 6, [keys["barge"], keys["cargo"]], cache, "barge+cargo")
    bmodes = keep_modes(ball, model.f_max, residual=model.residual_vectors)
    _, cg = center_of_gravity(bmodes.to_body(zeta=model.zeta, name="barge"))
    barge = bmodes.to_body(ref_point=cg, zeta=model.zeta, name="barge")
    dasm = with_own_inertia(assemble([cbs["dock"]], "dock"), "dock", comps["dock"], cbs["dock"])   # grounded
    dall = modes_stage(dasm, 0, [keys["dock"]], cache, "dock")
    dmodes = keep_modes(dall, model.dock_f_max, residual=model.residual_vectors)
    dock = dmodes.to_body(zeta=model.zeta, name="dock")
    out = BargeModels(comps, cbs, basm, bmodes, barge, dasm, dmodes, dock,
                      {"components+CB (s)": t1 - t0, "system modes (s)": time.perf_counter() - t1})
    bow = [f"{p}:{c}" for p in out.bow_points for c in TRANSLATIONS]
    fenders = [f"{p}:{c}" for p in out.fender_points for c in TRANSLATIONS]
    cargo = [f"{p}:{c}" for p in out.cargo_points for c in COMPONENTS]
    out.truncation = (truncation_check(ball, bmodes, bow + cargo, bow, "barge"),
                      truncation_check(dall, dmodes, fenders, fenders, "dock"))
    return out


# ------------------------------------------------------------------ the series-spring estimate
def flexibility(body: ModalBody, labels, elastic_only: bool) -> np.ndarray:
    """Static flexibility (m/N) at ``labels`` from the modes, Phi diag(1/omega^2) Phi^T over the
    elastic modes: the grounded dock's static flexibility, and for the free-free barge its
    flexibility relative to its rigid-body motion (inertia relief). Exact at CB boundary DOFs
    when every system mode is kept or the cut ones are replaced by residual vectors
    (reduction/truncation.py); a cut without them makes it low."""
    rows = body.rows(labels)
    el = body.omega > 0 if elastic_only else np.ones(body.n_modes, bool)
    return (rows[:, el] / body.omega[el] ** 2) @ rows[:, el].T


def series_spring(models: BargeModels, case: BargeCase) -> dict:
    """The reference's finding as a formula: barge (mass m behind a spring k_b at the bow)
    against a dock spring k_d = 1/(1/k_fenders + 1/k_quay), all fenders loaded alike:
    F_peak = v0 sqrt(m k_eff), 1/k_eff = 1/k_b + 1/k_d; limits v0 sqrt(m k_b) (stiff dock:
    barge-governed) and v0 sqrt(m k_d) (soft dock: dock-governed). Stiffnesses in N/m of the
    total x force over the mean x displacement of the contact points."""
    bow = [f"{p}:Tx" for p in models.bow_points]
    fen = [f"{p}:Tx" for p in models.fender_points]
    n = len(bow)
    k_b = n * n / flexibility(models.barge, bow, True).sum()
    k_q = n * n / flexibility(models.dock, fen, False).sum()
    k_f = n * case.fender.stiffness
    k_d = 1.0 / (1.0 / k_f + 1.0 / k_q)
    k_eff = 1.0 / (1.0 / k_b + 1.0 / k_d)
    m = models.barge.mass
    v0 = max(case.velocity, 0.0)        # towards the dock; moving away, the estimates are of no impact
    return {"mass": m, "k_barge": k_b, "k_quay": k_q, "k_fenders": k_f, "k_dock": k_d, "k_eff": k_eff,
            "F_series": v0 * np.sqrt(m * k_eff), "F_barge_limit": v0 * np.sqrt(m * k_b),
            "F_dock_limit": v0 * np.sqrt(m * k_d), "duration": np.pi * np.sqrt(m / k_eff)}


# ------------------------------------------------------------------ the transient problem
@dataclass
class BargeProblem:
    """One case's transient problem and what the reports need."""

    case: BargeCase
    problem: TransientProblem
    interface: dict           # recovery name -> cargo point
    estimate: dict            # series_spring()


def contacts(case: BargeCase, models: BargeModels) -> list[ContactPoint]:
    """One fender per bow point: the barge (body a) on the -x side of the dock (body b), normal
    x, laterals y and z; open at t0 with the case's gap; never bolted."""
    f = case.fender
    out = []
    for k, (bow, fen) in enumerate(zip(models.bow_points, models.fender_points)):
        out.append(ContactPoint(f"fender_{k + 1}", [f"{bow}:{c}" for c in TRANSLATIONS],
                                [f"{fen}:{c}" for c in TRANSLATIONS],
                                [f.stiffness, f.lateral_stiffness, f.lateral_stiffness], axial=0, normal_sign=-1.0,
                                gap=case.gap, release_time=-np.inf, friction=f.friction, damping=f.damping))
    return out


def recoveries(models: BargeModels) -> tuple[list[Recovery], dict]:
    """Cargo interface forces (force of the barge on the cargo at each saddle) and the modal
    coordinates of both bodies (deformed-shape frames)."""
    from liftoff.reduction import interface_force_recovery

    out, interface = [], {}
    for pt in models.cargo_points:
        D, A = interface_force_recovery(models.barge_asm, models.barge_modes, "cargo",
                                        [f"{pt}:{c}" for c in COMPONENTS])
        out.append(Recovery(f"interface_{pt}", "a", COMPONENTS, disp=D, acc=A, units=("N",) * 3 + ("N m",) * 3,
                            category="interface_force", description=f"force of the barge's cradle on the cargo at {pt}"))
        interface[f"interface_{pt}"] = pt
    na, nb = models.barge.n_modes, models.dock.n_modes
    out.append(Recovery("modal_q_a", "a", [f"q{j}" for j in range(na)], disp=np.eye(na), units="sqrt(kg) m",
                        category="modal", description="modal coordinates of the barge"))
    out.append(Recovery("modal_q_b", "b", [f"q{j}" for j in range(nb)], disp=np.eye(nb), units="sqrt(kg) m",
                        category="modal", description="modal coordinates of the dock"))
    return out, interface


def build_problem(case: BargeCase, models: BargeModels, progress: bool = True) -> BargeProblem:
    """Fenders, wave forces, the barge's initial velocity (rigid body, +x), outputs."""
    barge = models.barge
    constant, tables = [], []
    for i, f in enumerate(case.forces):
        try:
            barge.dof_index(f.label)
        except InputError as exc:
            raise ((Where(case.source, "force") / i).named(f.label) / "label").wrap(exc) from None
        (constant if f.time is None else tables).append(f.on("a"))
    v = np.array([case.velocity, 0, 0, 0, 0, 0])
    init = InitialState(np.zeros(barge.n_modes), barge.participation @ v, np.zeros(models.dock.n_modes),
                        np.zeros(models.dock.n_modes))
    recs, interface = recoveries(models)
    outputs = {"a": [f"{p}:{c}" for p in models.stations for c in ("Tx", "Tz")] + [f"{p}:Tx" for p in models.bow_points],
               "b": [f"{p}:Tx" for p in models.fender_points]}
    prob = case.time.problem(barge, models.dock, contacts(case, models), Forcing(constant=constant, tables=tables),
                             initial=init, outputs=outputs, recoveries=recs, progress=progress and case.output.progress)
    est = series_spring(models, case)
    est["F_wave"] = abs(case.velocity) * impedance(models, case)
    return BargeProblem(case, prob, interface, est)



# ------------------------------------------------------------------ the run
def impedance(models: BargeModels, case: BargeCase) -> float:
    """The hull's axial wave impedance sqrt(EA m') (N s/m), m' = the barge's mass per length:
    a long elastic hull striking a rigid wall at v0 carries v0 sqrt(EA m') until the wave
    returns from the stern (2L/c), whatever the dock (1-D wave theory)."""
    from liftoff.meshes.barge import hull_axial_stiffness

    p = case.model.components["barge"].builder
    return float(np.sqrt(hull_axial_stiffness(p) * models.barge.mass / p.length))


def sweep_row(case: BargeCase, result, bp: BargeProblem) -> dict:
    """One row of the impact sweep: the dock's stiffness, FE peak force and duration, the estimate."""
    from .barge_report import fender_force, first_contact_steps

    F = fender_force(result)
    on = result.time[first_contact_steps(F)]
    est = bp.estimate
    cargo = max(float(np.linalg.norm(result.recovered[r][:, :3], axis=1).max()) for r in bp.interface)
    lab = result.output_labels["a"]
    deck = [j for j, s in enumerate(lab) if s.startswith("deck_")]
    return {"case": case.name, **{k: float(v) for k, v in est.items()}, "F_fe": float(F.max()),
            "ratio": float(F.max() / est["F_series"]) if est["F_series"] > 0 else float("nan"), "duration_fe": float(on[-1] - on[0]) if on.size else 0.0,
            "duration_series": float(est["duration"]), "cargo_peak": cargo,
            "deck_acc_peak": float(np.abs(result.acceleration["a"][:, deck]).max())}


def run(scenario=None, out: Path | str = "out/barge", cache_dir=None, progress: bool = True, plots: bool = True,
        snapshots: bool = True, echo=print, command: str | None = None):
    """Run a barge scenario (path, parsed BargeScenario, or None for the embedded example);
    ``command``: the command line MANIFEST.json records (default ``liftoff run <scenario>``)."""
    from liftoff.config.barge import BargeScenario, load_barge

    from .cache import StageCache, default_cache_dir, stage_key
    from .outdir import check_target, staged_output

    t_start = time.perf_counter()
    out = Path(out)
    sc = scenario if isinstance(scenario, BargeScenario) else load_barge(scenario)
    check_target(out)
    pics = snapshots and any(c.output.snapshots and c.output.frames for c in sc.cases)
    if pics:  # pyvista before dolfinx (FENICSX-NOTES.md)
        import liftoff.fem.snapshot  # noqa: F401
    cache = StageCache(None if cache_dir is False else Path(cache_dir) if cache_dir else default_cache_dir(out))
    models, problems, stage_times = {}, {}, []
    for case in sc.cases:          # every case built and checked before the first file is written
        mkey = stage_key("barge-model", asdict(case.model))
        if mkey not in models:
            n0, t0 = len(cache.log), time.perf_counter()
            models[mkey] = build_models(case.model, cache, progress)
            stage_times += [(f"{s} {lab} ({how})", secs) for s, lab, how, secs in cache.log[n0:]]
            stage_times.append(("model stages total", time.perf_counter() - t0))
        problems[case.name] = (build_problem(case, models[mkey], progress), mkey)
    with staged_output(out, command=command or f"liftoff run {sc.path}") as stage:
        files, text = _write(sc, models, problems, stage, plots, pics, stage_times, echo, t_start)
    echo(f"  outputs in {out}/ ({len(files)} files); cache {cache.root}")
    return {"out": out, "files": [out / Path(f).relative_to(stage) for f in files], "summary": text}


def _write(sc, models: dict, problems: dict, out: Path, plots: bool, pics: bool, stage_times: list, echo,
           t_start: float):
    """Per case the transient, results file, max/min table and plots; then the sweep, frames, summary."""
    from liftoff.transient import solve

    from liftoff.core.records import write_text

    from . import barge_report as rep
    from .report import envelope, write_csv

    files, rows, per_case, results = [], [], {}, {}
    for case in sc.cases:
        bp, mkey = problems[case.name]
        t0 = time.perf_counter()
        res = solve(bp.problem)
        stage_times.append((f"transient [{case.name}]", time.perf_counter() - t0))
        results[case.name] = res
        files.append(Path(res.save(out / f"results_{case.name}.h5")))
        per_case[case.name] = rep.case_rows(res, bp, case.name)
        files.append(write_csv(per_case[case.name], out / f"maxmin_{case.name}.csv"))
        rows.append(sweep_row(case, res, bp))
        if plots and case.output.plots:
            c = impedance(models[mkey], case) / (models[mkey].barge.mass / case.model.components["barge"].builder.length)
            files += [rep.case_plot(res, bp, out, case.name), rep.deck_wave_plot(res, models[mkey], out, case.name, c)]
    files.append(write_csv(envelope(per_case), out / "maxmin_envelope.csv"))
    files.append(rep.sweep_csv(rows, out))
    first = sc.cases[0]
    imp = impedance(models[problems[first.name][1]], first)
    if plots:
        files.append(rep.sweep_plot(rows, imp, abs(first.velocity), out))
    if pics:
        top = max(rows, key=lambda r: r["F_fe"])["case"]       # the frames of the hardest impact
        case = next(c for c in sc.cases if c.name == top)
        if case.output.snapshots and case.output.frames:
            t0 = time.perf_counter()
            files += rep.wave_frames(models[problems[top][1]], results[top], out, top, case.output.frames)
            stage_times.append((f"frames [{top}]", time.perf_counter() - t0))
    text = rep.summary(sc, models[problems[first.name][1]], rows, stage_times, imp, time.perf_counter() - t_start)
    files.append(write_text(out / "summary.txt", text + "\n"))
    echo(text)
    return files, text
