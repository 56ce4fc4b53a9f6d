"""OpenBLAS kernels on CPUs the installed OpenBLAS does not recognise (standard library only at import).

Debian bookworm's OpenBLAS 0.3.21 is built for many CPUs at once (DYNAMIC_ARCH) and picks
its kernels from the CPU model when it is loaded. It does not recognise this project's
development machine (an AVX-512 Intel Xeon): it falls back to its generic "Prescott"
(SSE3) kernels, and every BLAS-3 product runs several times slower than the CPU allows
(docs/workflow.md, "BLAS kernels", gives the measurements). numpy, scipy, numba's
BLAS calls, PETSc, MUMPS and SLEPc all load that one library.

``OPENBLAS_CORETYPE`` names the kernels and is read once, when OpenBLAS is loaded, so it is
set here, on ``import liftoff``, before numpy loads it, on Linux x86-64: to the AVX-512
kernels ("SkylakeX") where the CPU has every AVX-512 subset they use, else the AVX2 ones
("Haswell") where it has AVX2 and FMA, else left alone. This also replaces OpenBLAS's own
choice on CPUs it does recognise (an AMD Zen gets the Haswell kernels, a Sapphire Rapids
the SkylakeX ones, which its own targets build on for double precision). A value the user
set is kept (set it to the name OpenBLAS itself picks, e.g. ``OPENBLAS_CORETYPE=Prescott``
here, to opt out). Nothing is set once numpy is imported: the process's BLAS is then
already chosen, and its child processes (case pools, pictures) must run the same kernels.
The kernels change the summation order only: with a fixed contact set the results agree to
round-off with and without the setting, and where a point opens or closes within a hair of
a step end it may do so a step apart (tests/core/test_openblas.py; docs/workflow.md, "BLAS
kernels"). Each run's MANIFEST.json records the kernels it ran (:func:`describe`).
"""
from __future__ import annotations

import os
import platform
import sys
from collections.abc import Mapping, MutableMapping

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


def choose_coretype(environ: MutableMapping[str, str] = os.environ, modules: Mapping[str, object] = sys.modules,
                    machine: str | None = None, system: str | None = None,
                    cpuinfo: str = "/proc/cpuinfo") -> str | None:
    """Set ``OPENBLAS_CORETYPE`` in ``environ`` (module docstring) and return it; None where
    it is left alone or removed: set by the user, numpy already loaded, not Linux on x86-64,
    or a CPU without AVX2 and FMA.

    A value liftoff set in a parent process (``CHOSEN`` equal to it) is chosen again for
    this CPU: the parent may have run on another host (mpirun, a batch system), and OpenBLAS
    does not check a forced core type (AVX-512 kernels on a CPU without AVX-512 die on their
    first instruction). Where numpy is already loaded the choice is declined and ``CHOSEN``
    records that (empty), so that the processes this one starts run the kernels it runs."""
    inherited = CHOSEN in environ
    if inherited and environ.get(CHOSEN) not in ("", environ.get("OPENBLAS_CORETYPE")):
        return None                                 # the user replaced liftoff's value: theirs
    if inherited and environ[CHOSEN] == "":
        return None                                 # a parent declined: run what it ran
    if not inherited and "OPENBLAS_CORETYPE" in environ:
        return None                                 # the user's
    if not inherited and "numpy" in modules:
        environ[CHOSEN] = ""
        return None
    linux_x86 = ((machine or platform.machine()).lower() in ("x86_64", "amd64")
                 and (system or sys.platform).startswith("linux"))
    name = coretype_for(cpu_flags(cpuinfo)) if linux_x86 else None
    if name is None:
        if inherited:                               # liftoff's value from a parent, not for this CPU
            environ.pop("OPENBLAS_CORETYPE", None)
            environ[CHOSEN] = ""
        return None
    environ["OPENBLAS_CORETYPE"] = name
    environ[CHOSEN] = name
    return name


def describe() -> dict:
    """The BLAS libraries this process has loaded (threadpoolctl, imported here), the
    first one's library, version and kernels, and who chose them: liftoff or the user where
    that library is OpenBLAS running the kernels ``OPENBLAS_CORETYPE`` names, else OpenBLAS
    itself (or the other library); for a run's record."""
    from threadpoolctl import threadpool_info

    libs = [i for i in threadpool_info() if i.get("user_api") == "blas"]
    first = libs[0] if libs else {}
    value = os.environ.get("OPENBLAS_CORETYPE")
    kernels = first.get("architecture")
    library = first.get("internal_api", "unknown")
    applied = library == "openblas" and value is not None and str(kernels).lower() == value.lower()
    if applied and os.environ.get(CHOSEN) == value:
        chosen_by = "liftoff (liftoff/core/openblas.py)"
    elif applied:
        chosen_by = "the user"
    elif value is not None:
        chosen_by = f"{library} (OPENBLAS_CORETYPE={value} not applied)"
    else:
        chosen_by = library
    return {"library": library, "version": first.get("version"), "kernels": kernels,
            "OPENBLAS_CORETYPE": value, "chosen_by": chosen_by,
            "loaded": [f"{i.get('internal_api')} {i.get('version')} {i.get('architecture')}" for i in libs]}
