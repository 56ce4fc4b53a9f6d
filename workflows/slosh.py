"""``liftoff slosh [SCENARIO]``: the gravity slosh modes of every hydroelastic liquid of the
scenario's FE components, each in its rigid tank, and their equivalent mechanical model
(fem.slosh; issue 25; docs/hydro.md, "Slosh").

For each component whose geometry has hydroelastic liquids (``[model] liquid =
"hydroelastic"``), the component is meshed by its builder and the liquid mesh alone gives
the modes: pressure P2 (reported) and P1 on the same mesh, whose difference in the first
mode says how converged the reported figures are. ``--csv FILE`` writes the spring-mass
and pendulum table (SI units, one row per mode and the impulsive mass per direction),
atomically. The modes are those of a rigid tank at ``--g-eff`` (default: the scenario's
``[model] slosh_gravity``, 1 g on the pad); ``[model] convective = "slosh"`` (the default)
puts the same modes, at ``slosh_gravity``, into the run's structural model as pendulums
(fem.slosh.SloshPendulums; docs/hydro.md).
"""
from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np

from liftoff.core.errors import InputError

COLUMNS = ("component", "liquid", "kind", "mode", "frequency_Hz", "mass_kg", "direction_x", "direction_y",
           "height_m", "stiffness_N_per_m", "pendulum_length_m", "g_eff_m_per_s2", "wave_height_per_force_m_per_N")


def check_args(g_eff: float | None, n_modes: int, csv: Path | None) -> None:
    """Everything the run needs, before any meshing (``g_eff`` None: the scenario's)."""
    if g_eff is not None and not (np.isfinite(g_eff) and g_eff > 0):
        raise InputError(f"--g-eff must be > 0 m/s^2 (got {g_eff!r})")
    if n_modes < 1:
        raise InputError(f"--modes must be >= 1 (got {n_modes!r})")
    if csv is not None:
        if csv.is_dir():
            raise InputError(f"--csv {str(csv)!r} is a folder; give a file name")
        if not csv.parent.is_dir():
            raise InputError(f"--csv {str(csv)!r}: folder {str(csv.parent)!r} does not exist")


def tank_slosh(scenario, g_eff: float, n_modes: int, progress=print) -> dict:
    """{component: {liquid: (LiquidSlosh at P2, LiquidSlosh at P1)}} of the FE components with
    hydroelastic liquids of ``scenario`` (a lift-off Scenario or a ModelConfig, as a barge
    scenario's model view); InputError when there is none."""
    from liftoff.config.model import ModelConfig
    from liftoff.fem.slosh import geometry_slosh

    from .fe_source import geometry
    from .pipeline import given_model

    # a lift-off Scenario: the model stages are shared by its cases (workflows.pipeline); or a ModelConfig
    model = scenario if isinstance(scenario, ModelConfig) else scenario.cases[0].model
    if model.source != "fe":
        raise InputError(f"liftoff slosh needs [model] source = \"fe\" (got {model.source!r}): the slosh modes "
                         "come from the tanks' liquid meshes")
    out = {}
    with tempfile.TemporaryDirectory(prefix="liftoff-slosh-") as work:
        for name, comp in model.components.items():
            if comp.nastran is not None or given_model(comp) is not None or comp.mirror is not None:
                continue                   # imported, given or a mirror (no liquids), not meshed: no liquid mesh
            progress(f"liftoff slosh: meshing {name} ...")
            geo = geometry(comp, Path(work) / name)
            if not geo.liquids:
                continue
            by_degree = geometry_slosh(geo, g_eff, n_modes, degrees=(2, 1))
            out[name] = {g: (s, by_degree[1].get(g)) for g, s in by_degree[2].items()}
    if not out:
        raise InputError("no FE component of the scenario has a hydroelastic liquid ([model] liquid = "
                         "\"hydroelastic\"): nothing sloshes")
    return out


def rows(result: dict) -> list[tuple]:
    """The table's rows (COLUMNS)."""
    out = []
    for comp, liquids in result.items():
        for g, (s, _) in liquids.items():
            for k, d in enumerate(((1.0, 0.0), (0.0, 1.0))):
                out.append((comp, g, "impulsive", 0, "", s.impulsive_mass[k], d[0], d[1], s.impulsive_height[k],
                            "", "", s.gravity, ""))
            for j, m in enumerate(s.modes, 1):
                out.append((comp, g, "slosh", j, m.frequency, m.mass, m.direction[0], m.direction[1], m.height,
                            m.stiffness, s.pendulum_length(m), s.gravity, m.wave_per_force))
    return out


def csv_text(result: dict) -> str:
    def cell(v):
        return v if isinstance(v, str) else f"{v:.9g}"

    lines = ["# liftoff slosh: equivalent mechanical model of each liquid in its rigid tank (fem.slosh); SI units. "
             "kind = impulsive: the mass m_0 that moves with the tank, its force at z = height_m; kind = slosh: a "
             "mass on a spring (stiffness) along (direction_x, direction_y), its force at z = height_m, or a "
             "pendulum of pendulum_length_m hinged at height_m; the mode's largest free-surface rise is "
             "wave_height_per_force_m_per_N times its force",
             ",".join(COLUMNS)]
    lines += [",".join(cell(v) if not isinstance(v, (int, np.integer)) or isinstance(v, bool) else str(v)
                       for v in r) for r in rows(result)]
    return "\n".join(lines) + "\n"


def summary(result: dict) -> str:
    lines = []
    for comp, liquids in result.items():
        for g, (s, s1) in liquids.items():
            lines.append(f"{comp} / {g}: liquid {s.mass / 1e3:.6g} t, c.g. z = {s.centroid[2]:.4g} m; impulsive "
                         f"{s.impulsive_mass[0] / 1e3:.6g} t (x) at z = {s.impulsive_height[0]:.4g} m; "
                         f"g_eff = {s.gravity:g} m/s^2")
            lines.append(f"  {'mode':>4} {'f [Hz]':>9} {'mass [t]':>10} {'direction (x, y)':>18} {'z [m]':>8} "
                         f"{'k [N/m]':>11} {'L [m]':>8}")
            for j, m in enumerate(s.modes, 1):
                lines.append(f"  {j:>4} {m.frequency:>9.4f} {m.mass / 1e3:>10.4g} "
                             f"{'(' + format(m.direction[0], '.3f') + ', ' + format(m.direction[1], '.3f') + ')':>18} "
                             f"{m.height:>8.4g} {m.stiffness:>11.4g} {s.pendulum_length(m):>8.4g}")
            lines.append(f"  modes + impulsive carry {100 * s.mass_kept:.2f} % of the liquid laterally (x)")
            if s1 is not None and s1.modes and s.modes:
                df = s.modes[0].frequency / s1.modes[0].frequency - 1
                dm = s.mass_kept - s1.mass_kept
                lines.append(f"  convergence: P2 against P1 pressure on the same mesh, first mode frequency "
                             f"{100 * df:+.2f} %, carried mass {100 * dm:+.2f} points (P2 reported)")
    return "\n".join(lines)


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Register ``liftoff slosh`` on the CLI's subparsers (workflows/cli.py)."""
    p = sub.add_parser(
        "slosh", help="gravity slosh modes of the scenario's tanks and their spring-mass / pendulum model",
        description="Slosh modes of every hydroelastic liquid of the scenario's FE components, each in its "
                    "rigid tank, from its liquid mesh (fem.slosh): frequency, slosh mass, direction, height, "
                    "spring stiffness and pendulum length per mode, and the impulsive mass. SI units.")
    p.add_argument("scenario", nargs="?", type=Path, default=None, metavar="SCENARIO",
                   help="scenario file (default: the embedded default)")
    p.add_argument("--g-eff", type=float, default=None, metavar="G",
                   help="apparent axial acceleration, m/s^2 [the scenario's [model] slosh_gravity: "
                        "9.80665, on the pad]")
    p.add_argument("--modes", type=int, default=4, metavar="N", help="lateral modes per liquid, rounded up to whole pairs of equal frequency [4]")
    p.add_argument("--csv", type=Path, default=None, metavar="FILE",
                   help="write the spring-mass / pendulum table here (SI units)")
    p.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    from liftoff.config.scenario import load_scenario
    from liftoff.core.records import write_text

    from liftoff.config.barge import load_barge, scenario_kind

    check_args(args.g_eff, args.modes, args.csv)
    if args.scenario is not None and scenario_kind(args.scenario) == "barge":    # kind = "barge": its model view
        scenario = load_barge(args.scenario).cases[0].model.model_config()
        model = scenario
    else:
        scenario = load_scenario(args.scenario)
        model = scenario.cases[0].model
    result = tank_slosh(scenario, model.slosh_gravity if args.g_eff is None else args.g_eff, args.modes)
    print(summary(result))
    if args.csv is not None:
        write_text(args.csv, csv_text(result))
        print(f"liftoff slosh: wrote {args.csv}")
    return 0
