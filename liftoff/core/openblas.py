"""OpenBLAS kernels on CPUs the installed OpenBLAS does not recognise (standard library only).

Debian bookworm's OpenBLAS 0.3.21 is built for many CPUs at once (DYNAMIC_ARCH) and picks
its kernels from the CPU model when it is loaded. It does not recognise this project's
development machine (an AVX-512 Intel Xeon): it falls back to its generic "Prescott"
(SSE3) kernels, and every BLAS-3 product runs several times slower than the CPU allows
(2026-11-28, one process, 2 threads: a 2000 x 2000 dgemm 1.18 s with them, 0.15 s with the
"SkylakeX" kernels; the default run's output recovery in the transient kernel, a
64 x 1,372 x 148 product a block of steps, 53 -> 22 us a step). numpy, scipy, numba's
BLAS calls, PETSc, MUMPS and SLEPc all load that one library.

``OPENBLAS_CORETYPE`` names the kernels and is read once, when OpenBLAS is loaded, so it is
set here, on ``import liftoff``, before numpy loads it: to the AVX-512 kernels
("SkylakeX") where the CPU has every AVX-512 subset they use, else the AVX2 ones
("Haswell") where it has AVX2 and FMA, else left alone. A value the user set is kept (set
it to the name OpenBLAS itself picks, e.g. ``OPENBLAS_CORETYPE=Prescott``, to opt out).
Nothing is set once numpy is imported: the process's BLAS is then already chosen, and its
child processes (case pools, pictures) would otherwise use other kernels than the parent.
The kernels change the summation order only: with a fixed contact set the results agree to
round-off with and without the setting, and where a point opens or closes within a hair of
a step end it may do so a step apart (tests/core/test_openblas.py; docs/workflow.md, "BLAS
kernels"). Each run's MANIFEST.json records the kernels it ran (:func:`describe`).
"""
from __future__ import annotations

import os
import platform
import sys

#: kernels a CPU qualifies for, best first, and the CPU flags (/proc/cpuinfo) each needs
CORETYPES = (("SkylakeX", ("avx512f", "avx512cd", "avx512bw", "avx512dq", "avx512vl", "fma")),
             ("Haswell", ("avx2", "fma")))
#: set in os.environ when liftoff chose the kernels (the run's record says so)
CHOSEN = "LIFTOFF_OPENBLAS_CORETYPE"


def cpu_flags(cpuinfo: str = "/proc/cpuinfo") -> frozenset[str]:
    """The first processor's flags (empty where the file is missing or has none)."""
    try:
        with open(cpuinfo, encoding="ascii", errors="replace") as fh:
            for line in fh:
                if line.startswith("flags"):
                    return frozenset(line.split(":", 1)[1].split())
    except OSError:
        pass
    return frozenset()


def coretype_for(flags: frozenset[str]) -> str | None:
    """The best kernels of :data:`CORETYPES` these CPU flags run, or None."""
    for name, needs in CORETYPES:
        if all(f in flags for f in needs):
            return name
    return None


def choose_coretype(environ=os.environ, modules=sys.modules, machine: str | None = None,
                    cpuinfo: str = "/proc/cpuinfo") -> str | None:
    """Set ``OPENBLAS_CORETYPE`` in ``environ`` (module docstring) and return it; None where
    it is left alone: already set, numpy already loaded, not Linux on x86_64, or a CPU
    without AVX2."""
    if "OPENBLAS_CORETYPE" in environ or "numpy" in modules:
        return None
    if (machine or platform.machine()).lower() not in ("x86_64", "amd64") or not sys.platform.startswith("linux"):
        return None
    name = coretype_for(cpu_flags(cpuinfo))
    if name is not None:
        environ["OPENBLAS_CORETYPE"] = name
        environ[CHOSEN] = name
    return name


def describe() -> dict:
    """The BLAS this process runs (threadpoolctl, imported here): library, version, kernels,
    and who chose them; for a run's record."""
    from threadpoolctl import threadpool_info

    libs = [i for i in threadpool_info() if i.get("user_api") == "blas"]
    out = {"library": libs[0].get("internal_api", "unknown") if libs else "unknown",
           "version": libs[0].get("version") if libs else None,
           "kernels": libs[0].get("architecture") if libs else None,
           "OPENBLAS_CORETYPE": os.environ.get("OPENBLAS_CORETYPE"),
           "chosen_by": "liftoff (liftoff/core/openblas.py)" if os.environ.get(CHOSEN)
           and os.environ.get(CHOSEN) == os.environ.get("OPENBLAS_CORETYPE") else
           ("the user" if os.environ.get("OPENBLAS_CORETYPE") else "OpenBLAS")}
    return out
