"""``liftoff run NEW --compare OLD_RUN --contributions OLD_SCENARIO``: each compared peak
split into what changed it, the forcing, the modes and the damping (issue 24;
analysis/contributions.py for the states and the arithmetic).

The earlier scenario is read before the first stage; its named cases must be the new
run's (by name), and the run has no generated cases (the split is of the named cases'
envelope, which is then the compared one). After the new run's cases, each named case is
solved three more times: the earlier case on the earlier model (its stages from the stage
cache, or built), the new case on the earlier model, and the new case on the new model
with the earlier damping (every elastic mode's ratio scaled by old zeta / new zeta). The
rows go to ``contributions.csv`` (SI units, column ``unit``). Where the swapped problems
cannot be built (a new case that names points the earlier model lacks), the run's other
outputs are written and a warning says that no split was.
"""
from __future__ import annotations

import dataclasses
import time
import warnings
from pathlib import Path

import numpy as np

from liftoff.core.errors import InputError

from . import report


def check(sc, opt, n_generated: int):
    """The earlier Scenario of ``opt.contributions``, read and matched to ``sc`` before any
    stage: ``--compare`` given, no generated cases, every named case of ``sc`` in it."""
    from liftoff.config import load_scenario

    path = Path(opt.contributions)
    if opt.compare is None:
        raise InputError(f"--contributions {path}: needs --compare (the earlier run's folder or max/min CSV)")
    if n_generated:
        raise InputError(f"--contributions {path}: splits the named cases' envelope; run it without --cases "
                         "(or [dispersion] n_cases = 0)")
    if not path.is_file():
        raise InputError(f"--contributions {path}: no such scenario file")
    old = load_scenario(path, n_cases=0)
    have = {c.name for c in old.cases}
    missing = [c.name for c in sc.cases if c.name not in have]
    if missing:
        raise InputError(f"--contributions {path}: it has no case {missing[0]!r} (its cases: "
                         f"{', '.join(sorted(have))}); the split pairs the cases by name")
    # the split rebuilds the earlier run from its named cases: an envelope some of whose values other
    # cases set (an earlier campaign's generated cases) would put their whole excess into 'other' as if
    # code or files had changed (a review: 100 % of a peak, nothing changed)
    from liftoff.analysis.aggregate import cases_of, read_maxmin

    beyond = [c for c in cases_of(read_maxmin(Path(opt.compare)).values()) if c not in have]
    if beyond:
        raise InputError(f"--contributions {path}: the earlier envelope ({opt.compare}) has values set by case"
                         f"{'s' if len(beyond) > 1 else ''} {', '.join(beyond[:5])}{' ...' if len(beyond) > 5 else ''}"
                         ", not a named case of that scenario (a campaign's generated cases?); the split rebuilds "
                         "the named cases only: compare against a run of them alone")
    return old


def with_damping(stack, old_zeta: float, new_zeta: float):
    """``stack`` with its two bodies' modal damping as the earlier model's: each ratio times
    old_zeta / new_zeta (the elastic modes at old_zeta where new_zeta is 0)."""
    def body(b):
        z = np.asarray(b.zeta, float)
        z = z * (old_zeta / new_zeta) if new_zeta > 0 else np.where(np.asarray(b.omega) > 0, old_zeta, 0.0)
        return dataclasses.replace(b, zeta=z)

    return dataclasses.replace(stack, vehicle=body(stack.vehicle), pad=body(stack.pad), key="")   # not the keyed model


def _peaks(cp, name: str, band: float) -> list[dict]:
    from liftoff.transient import solve

    return report.case_maxmin(solve(cp.problem), cp, name, band)


def states(sc, old_sc, prep, cache, results: dict, echo=print) -> list[list[dict]]:
    """The four envelopes of analysis.contributions (rebuilt earlier, new forcing on the earlier
    model, new model with the earlier damping, the new run) over the named cases."""
    from .loads import build_problem
    from .run import _stack_for

    band = sc.post.acceleration_band_hz
    old_stacks = dict(prep.stacks)      # an earlier model equal to the new one: the stack in memory
    per: list[dict] = [{}, {}, {}, {}]
    for case in sc.cases:
        old_case = next(c for c in old_sc.cases if c.name == case.name)
        old_stack = old_stacks[_stack_for(old_case, old_stacks, cache, False, echo, [])]
        new_stack = prep.stacks[prep.problems[case.name][1]]
        echo(f"  contributions [{case.name}]: the earlier case, the new case on the earlier model, "
             "the new model with the earlier damping")
        per[0][case.name] = _peaks(build_problem(old_case, old_stack, progress=False), case.name, band)
        try:
            cp1 = build_problem(case, old_stack, progress=False)
        except InputError as exc:
            raise InputError(f"--contributions: the new case {case.name!r} cannot run on the earlier model ({exc})") \
                from None
        per[1][case.name] = _peaks(cp1, case.name, band)
        damped = with_damping(new_stack, old_case.model.zeta, case.model.zeta)
        per[2][case.name] = _peaks(build_problem(case, damped, progress=False), case.name, band)
        res, cp = results[case.name]
        per[3][case.name] = report.case_maxmin(res, cp, case.name, band)
    return [report.envelope(p) for p in per]


def write(sc, old_sc, prep, cache, results: dict, old_rows: dict, out: Path, echo=print) -> list[Path]:
    """contributions.csv, and the largest changes split, echoed."""
    from liftoff.analysis.aggregate import write_rows_csv
    from liftoff.analysis.contributions import FIELDS, split

    t0 = time.perf_counter()
    try:
        rows = split(old_rows, states(sc, old_sc, prep, cache, results, echo))
    except InputError as exc:       # the run's other outputs stand; the split is said not made
        warnings.warn(f"--contributions: no split written ({exc})")
        return []
    head = ("# liftoff contributions: each compared peak (side max or min of an envelope row) split into other "
            "(the earlier run against its scenario rebuilt on today's code: code, files or cases changed), "
            "forcing (the new cases on the earlier model), modes (the new model, earlier damping) and damping "
            "(the new run); other + forcing + modes + damping = change = new - old (17 digits: to round-off); one at a "
            "time in that "
            f"order (an interaction goes to the later part); SI units (column unit); {time.perf_counter() - t0:.1f} s; "
            "items in one of the runs only are not split (compare.csv lists them, status)\n")
    path = write_rows_csv(rows, FIELDS, head, out / "contributions.csv", digits=17)    # the parts add up in the file
    big = sorted((r for r in rows if r["change"] != 0), key=lambda r: -abs(r["change"]) / max(abs(r["old"]), 1e-300))
    if big:
        echo("Largest changes from the earlier run, split (contributions.csv):")
        for r in big[:10]:
            echo(f"  {r['item'] + ' ' + r['side']:<48} {r['old']:12.5g} -> {r['new']:12.5g} {r['unit']:<6} "
                 + "  ".join(f"{k} {r[k]:+.3g}" for k in ("other", "forcing", "modes", "damping")))
    return [path]
