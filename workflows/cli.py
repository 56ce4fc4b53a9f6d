"""The ``liftoff`` command line (console script ``liftoff`` -> :func:`main`).

Subcommands are registered in ``COMMANDS``: each entry adds its own argparse subparser
and sets ``func`` (``args -> exit status``). Bad input and non-converged contact
iterations end with one line ``liftoff: error: ...`` on stderr and exit status 2,
never a traceback and never a results file.

    liftoff transient SCENARIO.toml --out DIR [--method direct|fixed-point] [--no-progress]

Under ``mpirun -n N`` (or ``liftoff run --ranks N``) every rank prints its own error line
and exits at once (workflows/parallel.py: errors are raised on every rank).
"""
from __future__ import annotations

import argparse
import os
import sys
import time
import warnings
from pathlib import Path
from typing import Callable

EXIT_OK, EXIT_INPUT = 0, 2
RESULTS_NAME = "results.h5"


def _one_line(exc: BaseException) -> str:
    if isinstance(exc, OSError) and exc.filename is not None:
        msg = f"{exc.strerror or type(exc).__name__}: {exc.filename!s}"
    else:
        msg = str(exc) or type(exc).__name__
    return " ".join(msg.split())


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    print(f"liftoff: warning: {_one_line(Exception(str(message)))}", file=sys.stderr)


def _prepare_out(out: Path) -> Path:
    """Create the output directory up front, so a long run does not fail at the end."""
    if out.exists() and not out.is_dir():
        raise FileExistsError(17, "output path exists and is not a directory", str(out))
    out.mkdir(parents=True, exist_ok=True)
    if not os.access(out, os.W_OK):
        raise PermissionError(13, "output directory is not writable", str(out))
    return out


# ------------------------------------------------------------------ transient
def _add_transient(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "transient", help="run a two-body contact transient from a scenario file",
        description="Run a two-body modal contact transient (Prabhakar & Palermo) described by a "
                    "scenario TOML file (see docs/transient-cli.md) and write DIR/results.h5.")
    p.add_argument("scenario", type=Path, help="scenario file (TOML)")
    p.add_argument("--out", type=Path, required=True, metavar="DIR",
                   help=f"output directory (created); results go to DIR/{RESULTS_NAME}")
    p.add_argument("--method", choices=("direct", "fixed-point"), default=None,
                   help="contact solve: direct active-set solve (default) or the reference's "
                        "fixed-point iteration; overrides [time] method")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=_run_transient)


def _run_transient(args: argparse.Namespace) -> int:
    """Serial: under mpirun, rank 0 runs it and the other ranks wait."""
    from liftoff.workflows.parallel import root_only, world

    root_only(world(), lambda: _transient(args))
    return EXIT_OK


def _transient(args: argparse.Namespace) -> None:
    from liftoff.config import load_twobody

    scenario = load_twobody(args.scenario, method=args.method, progress=not args.no_progress)
    from liftoff.transient import solve

    out = _prepare_out(args.out)
    started = time.perf_counter()
    result = solve(scenario.problem)
    wall = time.perf_counter() - started
    path = Path(result.save(out / RESULTS_NAME))
    print(summary(scenario, result, path, wall))


def summary(scenario, result, path: Path, wall: float) -> str:
    """A short text summary: per contact, release, first separation and peak forces."""
    p = scenario.problem
    lines = [f"liftoff transient: {scenario.title}",
             f"  bodies   a = {p.body_a.name} ({p.body_a.n_modes} modes), "
             f"b = {p.body_b.name} ({p.body_b.n_modes} modes)",
             f"  time     {result.time[0]:g} .. {result.time[-1]:g} s, {result.time.size - 1} steps of "
             f"h = {result.h:.4g} s, method {p.method}, {wall:.2f} s wall"]
    lines.append(f"  {'contact':<16}{'release (s)':>12}{'separation (s)':>16}{'recontacts':>12}"
                 f"{'peak compression (N)':>22}{'peak tension (N)':>18}")
    for c in result.contact_summary():
        sep = "never" if c["separation_time"] is None else f"{c['separation_time']:.6g}"
        rel = {float("inf"): "never", float("-inf"): "unbolted"}.get(c["release_time"], f"{c['release_time']:.6g}")
        lines.append(f"  {c['name']:<16}{rel:>12}{sep:>16}{c['recontacts']:>12d}"
                     f"{c['peak_compression'] + 0.0:>22.6g}{c['peak_tension'] + 0.0:>18.6g}")
    lines.append(f"  results  {path}")
    return "\n".join(lines)


# ------------------------------------------------------------------ entry point
from liftoff.workflows.run import add_parser as _add_run  # noqa: E402  `liftoff run` (workflows/run.py)

COMMANDS: list[Callable[[argparse._SubParsersAction], None]] = [_add_transient, _add_run]


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="liftoff",
        description="Lift-off transient of a launch vehicle on a flexible pad "
                    "(two-body modal contact, Prabhakar & Palermo). SI units throughout.")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for register in COMMANDS:
        register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the command line; returns the exit status (0 ok, 2 bad input or no convergence)."""
    from liftoff.core.errors import ConvergenceError, InputError

    args = build_parser().parse_args(argv)
    warnings.showwarning = _show_warning
    try:
        return args.func(args)
    except (InputError, ConvergenceError, OSError) as exc:
        return _fail(f"liftoff: error: {_one_line(exc)}", EXIT_INPUT)
    except MemoryError:
        return _fail("liftoff: error: out of memory: use fewer steps or outputs (keep_modal = false keeps memory "
                     "independent of the number of modes)", EXIT_INPUT)
    except KeyboardInterrupt:
        return _fail("liftoff: interrupted, no results written", 130)


def _fail(line: str, status: int) -> int:
    """Print the one-line error. Under mpirun every rank prints its own and leaves at once,
    without MPI_Finalize: its barrier would wait forever for a rank that is still inside a
    collective operation when the error is this rank's alone (mpirun then stops the others)."""
    from liftoff.workflows.parallel import launched_size

    if launched_size() > 1:
        sys.stdout.flush()
        sys.stderr.flush()
        os.write(2, (line + "\n").encode())    # one write: lines of several ranks do not interleave
        os._exit(status)
    print(line, file=sys.stderr)
    return status


if __name__ == "__main__":
    sys.exit(main())
