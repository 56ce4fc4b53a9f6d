"""Work done beside the run (workflows/beside.py, issue 28): a named case's results file,
plots and snapshots written by a forked child while the run goes on.

* The job's files come back in submission order; an inline Beside (LIFTOFF_BESIDE = 0, MPI)
  gives the same.
* A failing job's error comes back naming it, an InputError as an InputError and anything
  else as a RuntimeError, after every child has been waited for.
* kill() leaves no child behind.
* A run (tests/data/beam_stick, a few seconds) writes the same files with the same contents
  (but the HDF5 creation stamps) forked and inline."""
from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np
import pytest

from liftoff.core.errors import InputError
from liftoff.workflows.beside import Beside


def _write(path: Path, text: str) -> list[Path]:
    path.write_text(text)
    return [path]


@pytest.mark.parametrize("forked", [True, False])
def test_jobs_return_their_files_in_order(tmp_path, forked):
    b = Beside(forked)
    b.submit("one", lambda: _write(tmp_path / "a.txt", "a"))
    b.submit("two", lambda: _write(tmp_path / "b.txt", "b") + _write(tmp_path / "c.txt", "c"))
    assert b.wait() == [tmp_path / "a.txt", tmp_path / "b.txt", tmp_path / "c.txt"]
    assert (tmp_path / "c.txt").read_text() == "c" and set(b.seconds) == {"one", "two"}


def test_at_most_live_limit_children_draw_at_once(tmp_path, monkeypatch):
    """A submission beyond LIVE_LIMIT children drawing waits for the oldest: with a limit of
    2, five jobs (each recording the children alive while it runs, by their marker files)
    never run three at once, and their files still come back in submission order, the failed
    one's error after every child was waited for."""
    from liftoff.workflows import beside

    monkeypatch.setattr(beside, "LIVE_LIMIT", 2)

    def job(k):
        mark = tmp_path / f"running{k}"
        mark.write_text("")
        time.sleep(0.3)
        alive = len(list(tmp_path.glob("running*")))
        mark.unlink()
        if k == 3:
            raise InputError("job 3 is wrong")
        return _write(tmp_path / f"out{k}.txt", str(alive))

    b = Beside(True)
    for k in range(5):
        b.submit(f"job {k}", lambda k=k: job(k))
        assert sum(j[4] is None for j in b._jobs) <= 2
    with pytest.raises(InputError, match=r"^job 3: job 3 is wrong$"):
        b.wait()
    assert [int((tmp_path / f"out{k}.txt").read_text()) <= 2 for k in (0, 1, 2, 4)] == [True] * 4
    b.submit("again", lambda: _write(tmp_path / "z.txt", "z"))
    assert b.wait() == [tmp_path / "z.txt"]


def test_errors_come_back_naming_the_job(tmp_path):
    def bad_input():
        raise InputError("a key is wrong")

    def broken():
        raise ZeroDivisionError("division by zero")

    b = Beside(True)
    b.submit("case 'a'", bad_input)
    b.submit("case 'b'", lambda: _write(tmp_path / "ok.txt", "ok"))
    with pytest.raises(InputError, match=r"^case 'a': a key is wrong$"):
        b.wait()
    assert (tmp_path / "ok.txt").is_file()          # the other job ran to its end
    b.submit("case 'c'", broken)
    with pytest.raises(RuntimeError, match=r"case 'c': ZeroDivisionError: division by zero"):
        b.wait()


def test_preloads_run_once_in_the_parent_before_the_first_fork(tmp_path):
    """Beside.preload: each loader runs once, in this process, before the first child is
    forked (which then has what it loaded); a loader that fails is no error here (the child
    that needs it says why); an inline Beside runs none."""
    calls = []

    def loader():
        calls.append(os.getpid())

    def broken():
        raise ImportError("no such library")

    b = Beside(True)
    b.preload(loader, broken)
    assert calls == []                               # nothing before a job comes
    b.submit("one", lambda: _write(tmp_path / "one.txt", str(len(calls))))
    b.submit("two", lambda: _write(tmp_path / "two.txt", str(len(calls))))
    b.wait()
    assert calls == [os.getpid()]                     # once, here
    assert (tmp_path / "one.txt").read_text() == "1" == (tmp_path / "two.txt").read_text()   # children inherit it
    inline = Beside(False)
    inline.preload(loader)
    inline.submit("three", lambda: [])
    assert calls == [os.getpid()]


def test_kill_leaves_no_child(tmp_path):
    b = Beside(True)
    b.submit("slow", lambda: time.sleep(60) or [])
    pid = b._jobs[0][1]
    b.kill()
    with pytest.raises(ChildProcessError):
        os.waitpid(pid, os.WNOHANG)


def test_a_run_writes_the_same_files_forked_and_inline(tmp_path, monkeypatch):
    pytest.importorskip("petsc4py")
    import h5py

    from liftoff.workflows.run import run

    scenario = Path(__file__).resolve().parents[1] / "data" / "beam_stick" / "scenario.toml"
    outs = {}
    for mode in ("1", "0"):
        monkeypatch.setenv("LIFTOFF_BESIDE", mode)
        outs[mode] = run(scenario, out=tmp_path / f"out{mode}", cache_dir=tmp_path / "cache", progress=False,
                         echo=lambda *a, **k: None, error_estimate=False)
    names = {m: sorted(p.name for p in o.out.iterdir()) for m, o in outs.items()}
    assert names["1"] == names["0"] and "results_nominal.h5" in names["1"] and any(n.endswith(".png") for n in names["1"])
    assert any("(beside the run)" in s for s, _ in outs["1"].stage_times)
    # inline, a job's time is inside the stage that ran it: marked so, not to be summed again
    inline = [s for s, _ in outs["0"].stage_times if "(inline: within a stage above)" in s]
    assert inline and not any("(beside the run)" in s for s, _ in outs["0"].stage_times)
    for n in names["1"]:
        a, b = outs["1"].out / n, outs["0"].out / n
        if n.startswith("results_"):
            with h5py.File(a) as fa, h5py.File(b) as fb:
                assert sorted(fa["recovered"]) == sorted(fb["recovered"])
                np.testing.assert_array_equal(fa["contact/force"][()], fb["contact/force"][()])
        elif n.endswith((".csv", ".txt")) and n != "summary.txt":
            assert a.read_bytes() == b.read_bytes(), n


def test_outputs_registered_beside_are_written_by_a_child(tmp_path, monkeypatch):
    """outputs.write: an output registered beside=True runs in a forked child (one job for the
    stage), its files returned by wait(); the others inline, in order, before write returns."""
    from liftoff.workflows import outputs

    monkeypatch.setattr(outputs, "OUTPUTS", {})

    def mark(name):
        def fn(out):
            return _write(out / f"{name}.txt", str(os.getpid()))
        return fn

    outputs.register_output("table", "run")(mark("table"))
    outputs.register_output("picture", "run", beside=True)(mark("picture"))
    outputs.register_output("series", "run", beside=True)(mark("series"))
    b = Beside(True)
    assert outputs.write("run", tmp_path, beside=b) == [tmp_path / "table.txt"]
    assert (tmp_path / "table.txt").read_text() == str(os.getpid())
    assert b.wait() == [tmp_path / "picture.txt", tmp_path / "series.txt"]
    assert list(b.seconds) == ["picture, series"]
    child = (tmp_path / "picture.txt").read_text()
    assert child != str(os.getpid()) and (tmp_path / "series.txt").read_text() == child
    # without a Beside (an MPI run, LIFTOFF_BESIDE=0): everything inline, in registration order
    assert outputs.write("run", tmp_path) == [tmp_path / f"{n}.txt" for n in ("table", "picture", "series")]
