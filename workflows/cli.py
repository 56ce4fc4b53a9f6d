"""The ``liftoff`` command line (console script ``liftoff`` -> :func:`main`).

Subcommands are registered in ``COMMANDS``: each entry adds its own argparse subparser
and sets ``func`` (``args -> exit status``). A failure ends with one line
``liftoff: error: ...`` on stderr, never a traceback and never a results file, and the
exit status says what kind: 2 bad input (or a usage error), 3 no convergence or a
diverged solution, 4 not enough resources (memory, disk), 1 an internal error (a bug:
the line asks to report it), 130/143 interrupted by SIGINT/SIGTERM.

    liftoff transient SCENARIO.toml --out DIR [--method direct|fixed-point] [--no-progress]
                      [--no-error-estimate] [--max-memory GB]
    liftoff run [SCENARIO.toml] --out DIR ...      (workflows/run.py)
    liftoff init DIR [--example shuttle|barge|saturn_v|single_stick] [--full]   (workflows/init.py)

Under ``mpirun -n N`` (or ``liftoff run --ranks N``) every rank prints its own error line
and exits at once (workflows/parallel.py: errors are raised on every rank).
"""
from __future__ import annotations

import argparse
import os
import shlex
import sys
import time
import warnings
from pathlib import Path
from typing import Callable

from .outdir import PUBLISHED, SIGNALLED, Terminated, check_target, staged_output

EXIT_OK, EXIT_INTERNAL, EXIT_INPUT, EXIT_CONVERGENCE, EXIT_RESOURCES = 0, 1, 2, 3, 4
EXIT_SIGINT, EXIT_SIGTERM = 130, 143
#: packages a command may need that an install can lack -> how to get them (exit 2, one line)
_VIZ = "pip install 'liftoff-loads[viz]', or run with --no-snapshots (and without --fields)"
_FE = "the FE stack comes from Debian packages (`make setup`); without it use [model] source = \"stick\""
OPTIONAL_PACKAGES = {
    "h5py": "pip install h5py (on Debian, the system venv of `make setup` uses python3-h5py: pip's wheel "
            "clashes with the HDF5 that dolfinx loads)",
    "pyvista": _VIZ, "vtk": _VIZ, "imageio": _VIZ, "vtkmodules": _VIZ,
    "distributed": "pip install 'liftoff-loads[dask]' (for --dask)", "dask": "pip install 'liftoff-loads[dask]'",
    "pyyeti": "pip install 'liftoff-loads[nastran]' and pip install --no-deps pyyeti==1.4.7 (the Nastran reader)",
    "pandas": "pip install 'liftoff-loads[nastran]'", "mpi4py": "Debian's python3-mpi4py (for --mpi and --ranks)",
    "dolfinx": _FE, "gmsh": _FE, "petsc4py": _FE, "slepc4py": _FE, "ufl": _FE, "basix": _FE, "ffcx": _FE,
}
RESULTS_NAME = "results.h5"


def _one_line(exc: BaseException) -> str:
    if isinstance(exc, OSError) and exc.filename is not None:
        msg = f"{exc.strerror or type(exc).__name__}: {exc.filename!s}"
    else:
        msg = str(exc) or type(exc).__name__
    return " ".join(msg.split())


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    print(f"liftoff: warning: {_one_line(Exception(str(message)))}", file=sys.stderr)


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
    add_common(p)
    p.set_defaults(func=_run_transient)


def add_common(p: argparse.ArgumentParser) -> None:
    """Options shared by ``transient`` and ``run``: the error estimate and the memory limit."""
    p.add_argument("--no-error-estimate", action="store_true",
                   help="skip the second run at h/2 that estimates the error of every peak (Richardson); "
                        "[time] accuracy needs it and keeps it")
    p.add_argument("--max-memory", type=_positive, default=None, metavar="GB",
                   help="memory the transient (and the record of a run's generated cases) may use, in GB "
                        "(default: 80 %% of the memory available)")


def _positive(text: str) -> float:
    try:
        x = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not (x > 0 and x < float("inf")):
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}")
    return x


def _run_transient(args: argparse.Namespace) -> int:
    """Serial: under mpirun, rank 0 runs it and the other ranks wait."""
    from liftoff.workflows.parallel import root_only, world

    root_only(world(), lambda: _transient(args))
    return EXIT_OK


def _transient(args: argparse.Namespace) -> None:
    from liftoff.config import load_twobody

    scenario = load_twobody(args.scenario, method=args.method, progress=not args.no_progress)
    from liftoff.transient import solve, solve_estimated

    problem = scenario.problem
    if args.max_memory is not None:
        problem.memory_limit = args.max_memory * 1e9
    check_target(args.out)
    started = time.perf_counter()
    est = None
    if args.no_error_estimate and problem.accuracy is None:
        result = solve(problem)
    else:
        est = solve_estimated(problem)
        result = est.result
    wall = time.perf_counter() - started
    with staged_output(args.out, command=getattr(args, "command_line", f"liftoff transient {args.scenario}")) as stage:
        result.save(stage / RESULTS_NAME)
    print(summary(scenario, result, args.out / RESULTS_NAME, wall, est))
    return EXIT_OK


def summary(scenario, result, path: Path, wall: float, est=None) -> str:
    """A short text summary: per contact, release, first separation and peak forces, with
    the estimated error of each peak when ``est`` (transient.accuracy.Estimated) is given."""
    from liftoff.transient.accuracy import error_estimate

    p = scenario.problem
    lines = [f"liftoff transient: {scenario.title}",
             f"  bodies   a = {p.body_a.name} ({p.body_a.n_modes} modes), "
             f"b = {p.body_b.name} ({p.body_b.n_modes} modes)",
             f"  time     {result.time[0]:g} .. {result.time[-1]:g} s, {result.time.size - 1} steps of "
             f"h = {result.h:.4g} s, method {p.method}, {wall:.2f} s wall",
             "  modes    as the body files give them: no truncation check here (a body file carries modes, not the "
             "stiffness they came from; `liftoff run` checks its bodies against their CB models)"]
    if result.metadata.get("static_above_hz") is not None:
        n_a, n_b = result.metadata["static_modes"]
        lines.append(f"  static   {n_a} modes of a and {n_b} of b above {result.metadata['static_above_hz']:g} Hz solved "
                     "quasi-statically ([time] static_above_hz; docs/transient.md)")
    lines.append(f"  {'contact':<16}{'release (s)':>12}{'separation (s)':>16}{'recontacts':>12}"
                 f"{'peak compression (N)':>22}{'est. error':>12}{'peak tension (N)':>18}{'est. error':>12}")
    fine = est.check.contact_summary() if est is not None else None
    for i, c in enumerate(result.contact_summary()):
        sep = "never" if c["separation_time"] is None else f"{c['separation_time']:.6g}"
        rel = {float("inf"): "never", float("-inf"): "unbolted"}.get(c["release_time"], f"{c['release_time']:.6g}")
        errs = ["-", "-"] if fine is None else [
            f"{abs(error_estimate(c[k], fine[i][k])):.3g}" for k in ("peak_compression", "peak_tension")]
        lines.append(f"  {c['name']:<16}{rel:>12}{sep:>16}{c['recontacts']:>12d}"
                     f"{c['peak_compression'] + 0.0:>22.6g}{errs[0]:>12}{c['peak_tension'] + 0.0:>18.6g}{errs[1]:>12}")
    if est is not None:
        acc = "" if p.accuracy is None else f"; accuracy {p.accuracy:g} reached"
        lines.append(f"  est. error: an estimate of each peak's error, 4/3 (peak at h/2 - peak at h) (Richardson, "
                     f"order 2); worst {est.relative:.3g} of the largest contact force{acc}")
    captured = result.metadata.get("capture_time") or {}
    if captured:
        lines.append("  latches  " + ", ".join(f"{k} {'captured at ' + format(t, '.6g') + ' s' if t is not None else 'open'}"
                                             for k, t in captured.items()))
    soft = result.metadata.get("soft_release") or {}
    if soft:
        def _t(t):
            return "never" if t is None else format(t, ".6g") + " s"
        lines.append("  soft release  " + ", ".join(f"{k} yields {_t(v['first_yield'])}, drawn out {_t(v['drawn_out'])}"
                                                   for k, v in soft.items()))
    lines.append(f"  results  {path}")
    return "\n".join(lines)


# ------------------------------------------------------------------ entry point
from liftoff.workflows.init import add_parser as _add_init  # noqa: E402  `liftoff init` (workflows/init.py)
from liftoff.workflows.run import add_parser as _add_run  # noqa: E402  `liftoff run` (workflows/run.py)
from liftoff.workflows.slosh import add_parser as _add_slosh  # noqa: E402  `liftoff slosh` (workflows/slosh.py)

COMMANDS: list[Callable[[argparse._SubParsersAction], None]] = [_add_transient, _add_run, _add_init, _add_slosh]


class _Parser(argparse.ArgumentParser):
    """Usage errors in one line (``liftoff: error: ...``), exit status 2."""

    def error(self, message: str):
        where = "" if self.prog == "liftoff" else f"{self.prog}: "      # no "liftoff: error: liftoff: ..."
        self.exit(EXIT_INPUT, f"liftoff: error: {where}{_one_line(Exception(message))} "
                              f"(usage: {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    from liftoff import __version__

    parser = _Parser(
        prog="liftoff",
        description="Lift-off transient of a launch vehicle on a flexible pad "
                    "(two-body modal contact, Prabhakar & Palermo). SI units throughout.")
    parser.add_argument("--version", action="version", version=f"liftoff {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for register in COMMANDS:
        register(sub)
    return parser


def _on_sigterm(signum, frame):
    SIGNALLED.append(signum)      # (outdir.SIGNALLED: its exception may surface as another one, or be lost)
    raise Terminated()


def main(argv: list[str] | None = None) -> int:
    """Run the command line; returns the exit status (see the module docstring)."""
    import errno
    import signal

    from liftoff.core.errors import ConvergenceError, InputError, ResourceError

    args = build_parser().parse_args(argv)
    # the command as given, for each published folder's MANIFEST.json (it said `liftoff run <scenario>`
    # whatever the options, so a campaign's manifest read as the two-case run's)
    # (ranks launched by `--ranks N` are handed the command as given: LIFTOFF_COMMAND, run.launch)
    args.command_line = os.environ.pop("LIFTOFF_COMMAND", "") or \
        shlex.join(["liftoff", *map(str, sys.argv[1:] if argv is None else argv)])
    warnings.showwarning = _show_warning
    previous = signal.signal(signal.SIGTERM, _on_sigterm)
    try:
        return args.func(args)
    except InputError as exc:
        return _fail(EXIT_INPUT, exc)
    except ConvergenceError as exc:
        return _fail(EXIT_CONVERGENCE, exc)
    except (ResourceError, MemoryError) as exc:
        return _fail(EXIT_RESOURCES, exc if str(exc) else "out of memory: use fewer steps, outputs or modes")
    except OSError as exc:
        full = exc.errno in (errno.ENOSPC, errno.EDQUOT, errno.ENOMEM)
        return _fail(EXIT_RESOURCES if full else EXIT_INPUT, exc)
    except KeyboardInterrupt:
        print(f"liftoff: interrupted (SIGINT), {_written()}", file=sys.stderr)
        return EXIT_SIGINT
    except Terminated:
        print(f"liftoff: terminated (SIGTERM), {_written()}", file=sys.stderr)
        return EXIT_SIGTERM
    except ModuleNotFoundError as exc:
        how = OPTIONAL_PACKAGES.get((exc.name or "").split(".")[0])
        if how is None:
            return _fail(EXIT_INTERNAL, f"internal error (ModuleNotFoundError: {exc}); please report it with the "
                                        "command and input that caused it")
        return _fail(EXIT_INPUT, f"this needs the Python package {exc.name.split('.')[0]!r}, which is not installed: "
                                 f"{how}")
    except Exception as exc:  # a bug: still one line, and a way to report it
        if SIGNALLED:         # SIGTERM inside a C extension's import surfaces as "ImportError: initialization failed"
            print(f"liftoff: terminated (SIGTERM), {_written()}", file=sys.stderr)
            return EXIT_SIGTERM
        return _fail(EXIT_INTERNAL, f"internal error ({type(exc).__name__}: {exc}); please report it with the "
                                    "command and input that caused it")
    finally:
        signal.signal(signal.SIGTERM, previous)
        SIGNALLED.clear()         # this main()'s own: not a later run()'s in this process
        PUBLISHED.clear()


def _written() -> str:
    """What a signalled command wrote: nothing, or the folders it had published before."""
    return ("after its results were written to " + ", ".join(repr(p) for p in PUBLISHED)) if PUBLISHED \
        else "no results written"


def _fail(code: int, exc) -> int:
    """Print the one-line error. Under mpirun every rank prints its own and leaves at once,
    without MPI_Finalize: its barrier would wait forever for a rank that is still inside a
    collective operation when the error is this rank's alone (mpirun then stops the others)."""
    from liftoff.workflows.parallel import launched_size

    line = f"liftoff: error: {_one_line(exc if isinstance(exc, BaseException) else Exception(exc))}"
    if launched_size() > 1:
        sys.stdout.flush()
        sys.stderr.flush()
        os.write(2, (line + "\n").encode())    # one write: lines of several ranks do not interleave
        os._exit(code)
    print(line, file=sys.stderr)
    return code


if __name__ == "__main__":
    sys.exit(main())
