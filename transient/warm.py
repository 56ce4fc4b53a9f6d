"""Compile the transient kernel into numba's on-disk cache (``make setup`` runs this), so
that the first run after an install or a change of transient/kernel.py does not pay for it.

    python -m liftoff.transient.warm [reference | laws | batch]

``reference``: the kernel's path for the reference's contacts (a run without friction,
dashpots, latches or soft release, as the default scenario); ``laws``: the path with
them (:func:`transient.kernel.march`, ``laws``); ``batch``: the kernels of cases marched
together (transient/batch.py, ``liftoff run --cases N --march-together K``: 43 s of
compiling in a campaign's first task, 2026-12-07, each worker paying it). Each solves a
0.03 s transient of the toy stack of transient/examples.py (the batch two cases of it);
the paths are separate specialisations, so the commands can run at once.
"""
from __future__ import annotations

import dataclasses
import sys
import time


#: the compiled paths, each a specialisation of its own
PATHS = ("reference", "laws", "batch")


def warm(path: str) -> float:
    """Compile the kernel's ``path`` ("reference", "laws" or "batch"); the seconds it took."""
    from .batch import solve_batch
    from .examples import holddown_contacts, toy_pad, toy_vehicle
    from .model import Forcing, TransientProblem
    from .solver import solve

    if path not in PATHS:
        raise ValueError(f"path must be one of {', '.join(map(repr, PATHS))}, got {path!r}")
    contacts = holddown_contacts(3, 1e10, release_time=0.02)
    if path == "laws":
        contacts = [dataclasses.replace(c, friction=0.3) for c in contacts]
    problem = TransientProblem(toy_vehicle(3), toy_pad(3), contacts, Forcing(gravity=(0.0, 0.0, -9.81)), t_end=0.03,
                               progress=False)
    t0 = time.perf_counter()
    if path == "batch":
        solve_batch([problem, dataclasses.replace(problem, forcing=Forcing(gravity=(0.0, 0.0, -9.7)))])
    else:
        solve(problem)
    return time.perf_counter() - t0


def main(argv=None) -> int:
    args = sys.argv[1:] if argv is None else argv
    for path in args or PATHS:
        print(f"liftoff setup: transient kernel ({path} path) compiled in {warm(path):.1f} s", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
