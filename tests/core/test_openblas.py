"""OpenBLAS kernels chosen on ``import liftoff`` (liftoff/core/openblas.py): the rule, and
that the choice changes nothing but round-off."""
from __future__ import annotations

import json
import os
import platform
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

    def choose(env, modules=None, machine="x86_64", cpu=info, system="linux"):
        return choose_coretype(env, {} if modules is None else modules, machine, system, cpu)

    env: dict = {}
    assert choose(env) == "SkylakeX" and env == {"OPENBLAS_CORETYPE": "SkylakeX", CHOSEN: "SkylakeX"}
    env = {"OPENBLAS_CORETYPE": "Prescott"}                        # the user's opt-out is kept
    assert choose(env) is None and env == {"OPENBLAS_CORETYPE": "Prescott"}
    env = {}                                                      # BLAS already loaded: declined, said so
    assert choose(env, {"numpy": np}) is None and env == {CHOSEN: ""}
    assert choose(env) is None and env == {CHOSEN: ""}            # ... and a child runs what its parent runs
    for machine, system in (("aarch64", "linux"), ("x86_64", "darwin")):
        env = {}
        assert choose(env, machine=machine, system=system) is None and env == {}
    env = {}
    assert choose(env, cpu=_cpuinfo(tmp_path, "sse sse2")) is None and env == {}


def test_a_value_liftoff_chose_elsewhere_is_chosen_again_for_this_cpu(tmp_path):
    """mpirun or a batch system may start a child on another host with the parent's
    environment: OpenBLAS runs a forced kernel type unchecked, so AVX-512 kernels on an
    AVX2 CPU would die on an illegal instruction."""
    parent = {"OPENBLAS_CORETYPE": "SkylakeX", CHOSEN: "SkylakeX"}
    env = dict(parent)
    assert choose_coretype(env, {}, "x86_64", "linux", _cpuinfo(tmp_path, "avx avx2 fma")) == "Haswell"
    assert env == {"OPENBLAS_CORETYPE": "Haswell", CHOSEN: "Haswell"}
    env = dict(parent)
    assert choose_coretype(env, {}, "x86_64", "linux", _cpuinfo(tmp_path, "sse sse2")) is None
    assert env == {CHOSEN: ""}
    env = dict(parent)                          # numpy loaded in the child already: still rechecked
    assert choose_coretype(env, {"numpy": np}, "x86_64", "linux", _cpuinfo(tmp_path, "avx avx2 fma")) == "Haswell"
    env = {"OPENBLAS_CORETYPE": "Prescott", CHOSEN: "SkylakeX"}   # the user replaced liftoff's value
    assert choose_coretype(env, {}, "x86_64", "linux", _cpuinfo(tmp_path, AVX512)) is None
    assert env["OPENBLAS_CORETYPE"] == "Prescott"


def test_the_record_says_who_chose_the_kernels_the_library_runs(monkeypatch):
    import threadpoolctl

    from liftoff.core import openblas

    def loaded(arch, api="openblas"):
        monkeypatch.setattr(threadpoolctl, "threadpool_info", lambda: [
            {"user_api": "blas", "internal_api": api, "version": "0.3.21", "architecture": arch}])

    for env, arch, who in (({"OPENBLAS_CORETYPE": "SkylakeX", CHOSEN: "SkylakeX"}, "SkylakeX", "liftoff"),
                           ({"OPENBLAS_CORETYPE": "Haswell"}, "Haswell", "the user"),
                           ({"OPENBLAS_CORETYPE": "SkylakeX", CHOSEN: "SkylakeX"}, "Prescott", "openblas (OPENBLAS"),
                           ({}, "Zen", "openblas")):
        monkeypatch.delenv("OPENBLAS_CORETYPE", raising=False)
        monkeypatch.delenv(CHOSEN, raising=False)
        for k, v in env.items():
            monkeypatch.setenv(k, v)
        loaded(arch)
        d = openblas.describe()
        assert d["chosen_by"].startswith(who) and d["kernels"] == arch and d["loaded"] == [f"openblas 0.3.21 {arch}"]
    loaded(None, "mkl")
    monkeypatch.setenv("OPENBLAS_CORETYPE", "SkylakeX")
    assert openblas.describe()["chosen_by"] == "mkl (OPENBLAS_CORETYPE=SkylakeX not applied)"


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
      apart, so a force may differ by up to its own change over the step before or after
      that instant (+ 1e-8 of the peak), never more (measured 131 N); the peaks agree to 1e-5 (1.2e-6)
      and the vehicle's outputs to 1e-7 of their peak (2e-9)."""
    expected = coretype_for(cpu_flags()) if (sys.platform.startswith("linux") and platform.machine() == "x86_64") \
        else None
    chosen = _run(None)
    if chosen["blas"]["library"] != "openblas" or expected is None:
        pytest.skip(f"liftoff chooses no OpenBLAS kernels here: {chosen['blas']}")
    assert chosen["blas"]["OPENBLAS_CORETYPE"] == expected              # the hook of import liftoff ran
    assert chosen["blas"]["chosen_by"].startswith("liftoff")
    assert chosen["blas"]["kernels"].lower() == expected.lower()
    generic = _run("Prescott")
    assert generic["blas"]["kernels"] == "Prescott" and generic["blas"]["chosen_by"] == "the user"
    F1, F0 = np.array(chosen["Fc"]), np.array(generic["Fc"])
    y1, y0 = np.array(chosen["y"]), np.array(generic["y"])
    bolted = slice(0, 1501)                                       # release at half the run
    Fpeak, ypeak = np.abs(F0).max(), np.abs(y0).max()
    assert np.abs(F1 - F0)[bolted].max() <= 1e-8 * Fpeak
    assert np.abs(y1 - y0)[bolted].max() <= 1e-12 * ypeak
    step = np.abs(np.diff(F0, axis=0))                           # each force's change over each step
    local = np.zeros_like(F0)                                    # ... over the steps before and after each end
    local[1:] = step
    local[:-1] = np.maximum(local[:-1], step)
    assert np.all(np.abs(F1 - F0) <= local + 1e-8 * Fpeak)
    assert np.abs(np.abs(F1).max(axis=0) - np.abs(F0).max(axis=0)).max() <= 1e-5 * Fpeak
    assert np.abs(y1 - y0).max() <= 1e-7 * ypeak
