"""OpenBLAS kernels chosen on ``import liftoff`` (liftoff/core/openblas.py): the rule, and
that the choice changes nothing but round-off."""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from liftoff.core.openblas import CHOSEN, choose_coretype, coretype_for, cpu_flags

ROOT = Path(__file__).resolve().parents[2]
AVX512 = "fpu sse sse2 avx avx2 fma avx512f avx512cd avx512bw avx512dq avx512vl"


def _cpuinfo(tmp_path: Path, flags: str) -> str:
    p = tmp_path / "cpuinfo"
    p.write_text(f"processor\t: 0\nmodel name\t: test\nflags\t\t: {flags}\n\nprocessor\t: 1\nflags\t\t: sse\n")
    return str(p)


def test_kernels_follow_the_cpu_flags(tmp_path):
    assert cpu_flags(_cpuinfo(tmp_path, AVX512)) >= {"avx512f", "fma"}
    assert coretype_for(frozenset(AVX512.split())) == "SkylakeX"
    assert coretype_for(frozenset("sse avx avx2 fma avx512f".split())) == "Haswell"   # AVX-512 without BW, DQ, VL
    assert coretype_for(frozenset("sse avx avx2".split())) is None                    # AVX2 without FMA
    assert coretype_for(frozenset()) is None
    assert cpu_flags(str(tmp_path / "missing")) == frozenset()


def test_the_choice_is_set_only_before_numpy_and_never_over_the_users(tmp_path):
    info = _cpuinfo(tmp_path, AVX512)
    env: dict = {}
    assert choose_coretype(env, {}, "x86_64", info) == "SkylakeX"
    assert env == {"OPENBLAS_CORETYPE": "SkylakeX", CHOSEN: "SkylakeX"}
    env = {"OPENBLAS_CORETYPE": "Prescott"}                        # the user's opt-out is kept
    assert choose_coretype(env, {}, "x86_64", info) is None and env == {"OPENBLAS_CORETYPE": "Prescott"}
    env = {}
    assert choose_coretype(env, {"numpy": np}, "x86_64", info) is None and env == {}   # BLAS already loaded
    assert choose_coretype(env, {}, "aarch64", info) is None and env == {}
    assert choose_coretype(env, {}, "x86_64", _cpuinfo(tmp_path, "sse sse2")) is None and env == {}


SCRIPT = """
import json, math, sys
import liftoff
import numpy as np
sys.path.insert(0, {bench!r})
from bench_transient import problem
from liftoff.core.openblas import describe
from liftoff.transient import solve
res = solve(problem(3000, n_veh=400, n_pad=60))
print(json.dumps({{"blas": describe(), "Fc": res.contact_force.tolist(), "y": res.displacement["a"].tolist()}}))
"""


def _run(coretype: str | None) -> dict:
    env = {k: v for k, v in os.environ.items() if k not in ("OPENBLAS_CORETYPE", CHOSEN)}
    if coretype:
        env["OPENBLAS_CORETYPE"] = coretype
    out = subprocess.run([sys.executable, "-c", SCRIPT.format(bench=str(ROOT / "benchmarks"))], env=env,
                         capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_the_chosen_kernels_change_round_off_only():
    """A 3,000-step lift-off (benchmarks/bench_transient.py's problem at 400 + 60 modes: 24
    contact rows bolted for 1,500 steps, then released and lifting off) with the kernels
    liftoff chooses and with OpenBLAS's generic ones. Both march the same arithmetic in
    another summation order (round-off ~1e-16 of each product):

    * bolted (one active set): the contact forces agree to 1e-8 of their peak (measured
      1.0e-9: the stiff hold-downs, K_C ~ 1e3 x the structure's, magnify the relative
      round-off of the free displacement in f = -(C + W)^-1 e), the vehicle's outputs to 1e-12
      (measured 2e-15);
    * released: a point that opens or closes within a hair of a step end may do so a step
      apart, so the forces may differ by up to their change over one step there (measured
      131 N against 2.2 MN one-step changes), never more; the peaks agree to 1e-5 (1.2e-6)
      and the vehicle's outputs to 1e-7 of their peak (2e-9)."""
    chosen = _run(None)
    if chosen["blas"]["library"] != "openblas" or chosen["blas"]["OPENBLAS_CORETYPE"] is None:
        pytest.skip(f"no kernels chosen here: {chosen['blas']}")
    assert chosen["blas"]["chosen_by"].startswith("liftoff")
    assert chosen["blas"]["kernels"].lower() == chosen["blas"]["OPENBLAS_CORETYPE"].lower()
    generic = _run("Prescott")
    assert generic["blas"]["kernels"] == "Prescott" and generic["blas"]["chosen_by"] == "the user"
    F1, F0 = np.array(chosen["Fc"]), np.array(generic["Fc"])
    y1, y0 = np.array(chosen["y"]), np.array(generic["y"])
    bolted = slice(0, 1501)                                       # release at half the run
    Fpeak, ypeak = np.abs(F0).max(), np.abs(y0).max()
    assert np.abs(F1 - F0)[bolted].max() <= 1e-8 * Fpeak
    assert np.abs(y1 - y0)[bolted].max() <= 1e-12 * ypeak
    assert np.abs(F1 - F0).max() <= np.abs(np.diff(F0, axis=0)).max()
    assert np.abs(np.abs(F1).max(axis=0) - np.abs(F0).max(axis=0)).max() <= 1e-5 * Fpeak
    assert np.abs(y1 - y0).max() <= 1e-7 * ypeak
