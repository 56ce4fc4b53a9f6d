"""``make setup`` compiles the transient kernel (transient/warm.py). A run without contact
laws must use march's specialisation with ``laws`` None, whose laws branches numba prunes
before typing (the reason the first reference run compiles in about half the time)."""
import subprocess
import sys
from pathlib import Path

import pytest
from numba import types

from liftoff.transient import warm
from liftoff.transient.kernel import march

ROOT = Path(__file__).resolve().parents[2]


def test_reference_path_is_the_pruned_specialisation():
    assert warm.warm("reference") >= 0.0
    laws_types = [sig[-1] for sig in march.signatures]
    assert any(t == types.none or isinstance(t, types.Omitted) for t in laws_types), laws_types


def test_unknown_path_is_refused():
    with pytest.raises(ValueError, match="reference"):
        warm.warm("fast")


def test_batch_path_is_the_specialisation_cases_marched_together_use():
    """``make setup`` warms the batch kernels with two toy cases; a batch with what the
    default's generated cases carry (gravity softening as rank-3 feedback, tabulated forces,
    quasi-static modes) must run on those same specialisations, or the first campaign with
    --march-together still compiles (43 s a worker, 2026-12-07). In a fresh process, so that
    no other test's batch has compiled a signature first. (march_group's callees are compiled
    into it: its signatures are the batch's.)"""
    code = (
        "import numpy as np\n"
        "from liftoff.transient import warm, batch\n"
        "from tests.transient.test_batch import _case\n"
        "from liftoff.transient.examples import toy_pad, toy_vehicle\n"
        "warm.warm('batch')\n"
        "before = list(batch.march_group.signatures)\n"
        "v, p = toy_vehicle(), toy_pad()\n"
        "batch.solve_batch([_case(k, v, p, static_above_hz=40.0) for k in range(3)], group=8)\n"
        "after = list(batch.march_group.signatures)\n"
        "print(before == after and len(before) == 1, before, after)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, timeout=600)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.startswith("True"), out.stdout
