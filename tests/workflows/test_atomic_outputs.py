"""A run's outputs appear together or not at all (workflows/outdir.py): a manifest that
matches the files, a failed or interrupted run that leaves the previous output folder as
it was, a killed run whose staging folder the next run removes, and a folder of the
user's own files that is never replaced."""
import json
import os
import signal
import subprocess
import sys
import time
import tomllib
from pathlib import Path

import pytest

from liftoff.config import default_text
from liftoff.core.errors import InputError
from liftoff.workflows.outdir import MANIFEST, check_target, staged_output, verify

from .test_run import STICK, _toml


def _stick_scenario(tmp_path, name="s.toml", t_end=7.0):
    d = tomllib.loads(default_text())
    d["model"] = STICK
    d["time"]["t_end"] = t_end
    d["case"] = [{"name": "nominal"}, {"name": "no-control", "control": {"enabled": False}}]
    p = tmp_path / name
    p.write_text(_toml(d))
    return p


def _cmd(*args):
    exe = os.path.join(os.path.dirname(sys.executable), "liftoff")
    return [exe, *args] if os.path.exists(exe) else [sys.executable, "-m", "liftoff.workflows.cli", *args]


def _staging(tmp_path, name="out"):
    return [p for p in tmp_path.iterdir() if p.name.startswith(f".{name}.liftoff-tmp-")]


def test_staged_output_publishes_all_or_nothing(tmp_path):
    out = tmp_path / "out"
    with staged_output(out, "test") as stage:
        (stage / "results_a.h5").write_bytes(b"new a")
        (stage / "summary.txt").write_text("first")
    man = json.loads((out / MANIFEST).read_text())
    assert {f["name"] for f in man["files"]} == {"results_a.h5", "summary.txt"} and verify(out) == []
    from liftoff.core.openblas import describe                # the BLAS the run ran on (docs/workflow.md)
    assert man["blas"] == json.loads(json.dumps(describe())) and man["blas"]["library"]
    with pytest.raises(RuntimeError):                      # a run that fails half-way
        with staged_output(out, "test") as stage:
            (stage / "results_a.h5").write_bytes(b"half")
            raise RuntimeError("case 2 failed")
    assert (out / "summary.txt").read_text() == "first" and verify(out) == [] and not _staging(tmp_path)
    with staged_output(out, "test") as stage:              # a second run replaces the set as a whole
        (stage / "results_b.h5").write_bytes(b"b")
    assert sorted(p.name for p in out.iterdir()) == [MANIFEST, "results_b.h5"] and verify(out) == []
    (out / "results_b.h5").write_bytes(b"tampered")
    assert verify(out) == ["changed results_b.h5"]


def test_foreign_folders_are_refused(tmp_path):
    """Only a folder that liftoff wrote, proven by its own manifest, is replaced (issue 27):
    output-like names (a user's data.csv, photo.png), a hand-made MANIFEST.json, or a file
    added to a previous output are refused, and nothing in the folder is touched."""
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "thesis.tex").write_text("x")
    with pytest.raises(InputError, match="holds 'thesis.tex' and no MANIFEST.json, so liftoff did not write it"):
        check_target(tmp_path / "mine")
    look_alike = tmp_path / "ud"
    look_alike.mkdir()
    for name in ("mydata.csv", "photo.png", "experiment_data.h5", "settings.json"):
        (look_alike / name).write_text("user data")
    with pytest.raises(InputError, match="holds 'experiment_data.h5' and no MANIFEST.json"):
        check_target(look_alike)
    (look_alike / MANIFEST).write_text('{"files": []}')
    with pytest.raises(InputError, match="not a liftoff run manifest"):
        check_target(look_alike)
    (look_alike / MANIFEST).write_text('{"format": "liftoff-run-manifest", "files": []}')
    with pytest.raises(InputError, match=r"does not match its MANIFEST.json \(extra experiment_data.h5\)"):
        check_target(look_alike)
    (look_alike / MANIFEST).write_text("not json")
    with pytest.raises(InputError, match="MANIFEST.json cannot be read"):
        check_target(look_alike)
    assert sorted(p.name for p in look_alike.iterdir()) == sorted(
        ["mydata.csv", "photo.png", "experiment_data.h5", "settings.json", MANIFEST])
    # a real output with a file (or an empty folder) added by the user, or a file changed
    out = tmp_path / "run"
    with staged_output(out, "test") as stage:
        (stage / "results.h5").write_bytes(b"r")
    check_target(out)                                      # liftoff's own: replaceable
    (out / "notes.txt").write_text("mine")
    with pytest.raises(InputError, match="extra notes.txt"):
        check_target(out)
    (out / "notes.txt").unlink()
    (out / "photos").mkdir()
    with pytest.raises(InputError, match="extra photos"):
        check_target(out)
    (out / "photos").rmdir()
    (out / "results.h5").write_bytes(b"edited")
    with pytest.raises(InputError, match="changed results.h5"):
        check_target(out)
    (out / "results.h5").unlink()                          # a file the user removed is no loss
    check_target(out)
    for bad in ("", "."):
        with pytest.raises(InputError, match="give a folder of its own"):
            check_target(__import__("pathlib").Path(bad))


@pytest.mark.slow
def test_sigterm_and_sigkill_leave_the_previous_run(tmp_path):
    """Kill `liftoff run` while it writes (its staging folder exists): SIGTERM exits 143 and
    cleans up; SIGKILL leaves a staging folder that the next run removes; in both cases
    the output folder keeps the previous run's complete, manifest-checked set."""
    out, cache = tmp_path / "out", tmp_path / "cache"
    args = ["--out", str(out), "--cache", str(cache), "--no-progress", "--no-snapshots"]
    first = subprocess.run(_cmd("run", str(_stick_scenario(tmp_path)), *args), capture_output=True, text=True,
                           timeout=600)
    assert first.returncode == 0, first.stderr
    before = (out / MANIFEST).read_text()
    longer = _stick_scenario(tmp_path, "long.toml", t_end=9.0)
    for sig, code in ((signal.SIGTERM, 143), (signal.SIGKILL, -9)):
        proc = subprocess.Popen(_cmd("run", str(longer), *args), stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                                text=True)
        t0 = time.time()
        while not _staging(tmp_path) and proc.poll() is None and time.time() - t0 < 300:
            time.sleep(0.02)
        assert proc.poll() is None, "the run ended before its staging folder was seen"
        proc.send_signal(sig)
        err = proc.communicate(timeout=120)[1]
        assert proc.returncode == code, err
        assert (out / MANIFEST).read_text() == before and verify(out) == []
        if sig == signal.SIGTERM:
            assert not _staging(tmp_path) and "terminated (SIGTERM), no results written" in err
    assert _staging(tmp_path)                              # SIGKILL: nothing could clean up
    again = subprocess.run(_cmd("run", str(longer), *args), capture_output=True, text=True, timeout=600)
    assert again.returncode == 0, again.stderr
    assert not _staging(tmp_path) and verify(out) == [] and (out / MANIFEST).read_text() != before


def test_usage_errors_and_version_in_one_line(capsys):
    from liftoff import __version__
    from liftoff.workflows.cli import main

    with pytest.raises(SystemExit) as e:
        main(["transient"])
    err = capsys.readouterr().err
    assert e.value.code == 2 and err.count("\n") == 1 and err.startswith("liftoff: error: ") and "--out" in err
    with pytest.raises(SystemExit) as e:
        main(["--version"])
    assert e.value.code == 0 and capsys.readouterr().out.strip() == f"liftoff {__version__}"


def test_unusable_out_paths_fail_before_the_run(tmp_path):
    """A dangling symlink, a folder that cannot be written and a name too long for the
    staging folder beside it are refused by check_target, before any stage (issue 27:
    they failed after the run, naming the hidden staging path)."""
    (tmp_path / "dang").symlink_to(tmp_path / "nowhere" / "x")
    with pytest.raises(InputError, match="a symbolic link to nothing"):
        check_target(tmp_path / "dang")
    with pytest.raises(InputError, match=r"cannot write in '/proc'"):
        check_target(Path("/proc/liftoff-test/out"))
    with pytest.raises(InputError, match="a folder name longer than"):
        check_target(tmp_path / ("a" * 240))
    (tmp_path / "file").write_text("x")
    with pytest.raises(InputError, match="is not a folder"):
        check_target(tmp_path / "file" / "out")
    check_target(tmp_path / "new" / "deeper" / "out")           # parents are made at the end
    assert not (tmp_path / "new").exists() and not [p for p in tmp_path.iterdir() if "probe" in p.name]


def test_compare_table_is_read_before_the_first_stage(tmp_path, monkeypatch):
    """--compare at a missing, empty or binary file fails at once (issue 27: after the whole
    run, or an empty compare.csv)."""
    from liftoff.workflows import run as run_mod
    from liftoff.analysis.aggregate import read_maxmin

    def no_stage(*a, **k):
        raise AssertionError("a model stage ran before --compare was checked")

    monkeypatch.setattr(run_mod, "prepare_models", no_stage)
    (tmp_path / "empty.csv").write_text("")
    (tmp_path / "binary.csv").write_bytes(bytes(range(256)) * 4)
    for name, match in (("typo.csv", "no such max/min table"), ("empty.csv", "holds no max/min rows"),
                        ("binary.csv", "not a text file")):
        with pytest.raises(InputError, match=match):
            run_mod.run(None, tmp_path / "out", cache_dir=False, progress=False, echo=lambda *a: None,
                        options=run_mod.Options(compare=tmp_path / name))
        with pytest.raises(InputError, match=match):
            read_maxmin(tmp_path / name)
    assert not (tmp_path / "out").exists()


def test_files_sha256_on_threads_is_each_files_sha256_in_order(tmp_path):
    """The manifest's digests (records.files_sha256, a few threads) against hashlib on each
    file's bytes: empty, small, several MiB (many 1 MiB blocks), in the order given."""
    import hashlib

    import numpy as np

    from liftoff.core.records import files_sha256

    rng = np.random.default_rng(3)
    paths = []
    for k, size in enumerate((0, 10, (5 << 20) + 7, 3 << 20, 1)):
        p = tmp_path / f"f{k}.bin"
        p.write_bytes(rng.bytes(size))
        paths.append(p)
    assert files_sha256(paths) == [hashlib.sha256(p.read_bytes()).hexdigest() for p in paths]
    assert files_sha256(paths[:1]) == [hashlib.sha256(b"").hexdigest()] and files_sha256([]) == []


@pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")   # the lost exception, by design
def test_a_sigterm_whose_exception_is_lost_publishes_nothing(tmp_path, monkeypatch):
    """SIGTERM's exception raised while Python runs a destructor's (or an import's) code is
    printed as "Exception ignored" and lost; the run goes on (`make test` met one so: the run
    exited 0 with its files published). The handler's record (outdir.SIGNALLED) still stops
    the run before its files are published: exit 143, the folder as it was, no staging folder
    left."""
    import argparse

    from liftoff.workflows import cli, outdir

    out = tmp_path / "out"
    out.mkdir()                                  # an empty folder: the run may write there
    went_on = []

    class Signalled:                             # SIGTERM delivered inside its destructor
        def __del__(self):
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(0.5)                      # the handler runs (and raises) here

    def command(args):
        with cli.staged_output(args.out) as stage:
            (stage / "result.txt").write_text("1\n")
            Signalled()                          # its exception printed and lost
            went_on.append(True)                 # the run went on
        return 0

    parser = cli.build_parser()
    monkeypatch.setattr(cli, "build_parser", lambda: parser)
    monkeypatch.setattr(parser, "parse_args", lambda argv: argparse.Namespace(out=out, func=command))
    assert cli.main([]) == 143
    assert went_on == [True]                     # the exception was lost: SIGNALLED stopped it
    assert list(out.iterdir()) == [] and not _staging(tmp_path)
    assert not outdir.SIGNALLED                  # main()'s own: a later run() in this process publishes


def test_published_folder_mode_links_mounts_and_files_added_meanwhile(tmp_path, monkeypatch):
    """The published folder takes the umask (mkdtemp's 0700 kept group members out); a
    symbolic link --out is followed (its folder replaced, the link kept); a mount point is
    refused before the run (the staging folder beside it is on another file system); a file
    put into the output folder during the run is never deleted: the run ends with the
    foreign-folder error and the folder as the user left it."""
    import stat

    out = tmp_path / "res"
    old = os.umask(0o022)
    try:
        with staged_output(out, "test") as stage:
            (stage / "a.txt").write_text("a")
    finally:
        os.umask(old)
    assert stat.S_IMODE(out.stat().st_mode) == 0o755
    real = tmp_path / "target"
    with staged_output(real, "test") as stage:
        (stage / "a.txt").write_text("old")
    link = tmp_path / "link"
    link.symlink_to(real)
    with staged_output(link, "test") as stage:
        (stage / "a.txt").write_text("new")
    assert link.is_symlink() and (real / "a.txt").read_text() == "new" and not verify(real)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link", "res", "target"]     # nothing staged left
    monkeypatch.setattr(os.path, "ismount", lambda p: str(p) == str(real))
    with pytest.raises(InputError, match="a mount point"):
        check_target(real)
    monkeypatch.undo()
    with pytest.raises(InputError, match="holds 'notes.txt' and no MANIFEST.json"):
        with staged_output(tmp_path / "fresh", "test") as stage:
            (stage / "a.txt").write_text("a")
            (tmp_path / "fresh").mkdir()
            (tmp_path / "fresh" / "notes.txt").write_text("mine")
    assert (tmp_path / "fresh" / "notes.txt").read_text() == "mine"
    with pytest.raises(InputError, match="does not match its MANIFEST.json"):
        with staged_output(real, "test") as stage:
            (stage / "a.txt").write_text("newer")
            (real / "notes.txt").write_text("mine")
    assert (real / "notes.txt").read_text() == "mine" and (real / "a.txt").read_text() == "new"


def test_a_sigterm_during_publication_comes_after_it_and_says_so(tmp_path, monkeypatch, capsys):
    """A SIGTERM that arrives while the run publishes its folder is held until the swap is
    done (it could stop it half way: the fallback's two renames left no output folder), then
    taken: exit 143, the new set in place and verified, and the message says where the results
    were written instead of "no results written"."""
    import argparse

    from liftoff.workflows import cli, outdir

    out = tmp_path / "out"
    real = outdir._publish

    def publish_signalled(stage, target):
        os.kill(os.getpid(), signal.SIGTERM)     # held: the handler does not run inside the swap
        time.sleep(0.2)
        real(stage, target)

    monkeypatch.setattr(outdir, "_publish", publish_signalled)

    def command(args):
        with cli.staged_output(args.out) as stage:
            (stage / "result.txt").write_text("1\n")
        return 0

    parser = cli.build_parser()
    monkeypatch.setattr(cli, "build_parser", lambda: parser)
    monkeypatch.setattr(parser, "parse_args", lambda argv: argparse.Namespace(out=out, func=command))
    assert cli.main([]) == 143
    assert (out / "result.txt").read_text() == "1\n" and not verify(out)
    err = capsys.readouterr().err
    assert "terminated (SIGTERM), after its results were written to" in err and str(out) in err
    assert outdir.PUBLISHED == [] and outdir.SIGNALLED == []
