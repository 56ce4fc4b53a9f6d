"""Model outputs kept in the stage cache (workflows/outputs.py, ``cache_on``): a run on a
cached model copies the files another run wrote from the same stack, and writes them again
whenever anything they depend on changed."""
from __future__ import annotations

import os
import warnings
from pathlib import Path
from types import SimpleNamespace

import pytest

from liftoff.core.errors import InputError
from liftoff.workflows import outputs
from liftoff.workflows.beside import Beside
from liftoff.workflows.cache import StageCache


class Calls:
    """The processes that wrote the output, one line each (a child beside the run too)."""

    def __init__(self, path: Path):
        self.path = path

    def __call__(self) -> None:
        with open(self.path, "a") as f:
            f.write(f"{os.getpid()}\n")

    def __len__(self) -> int:
        return len(self.pids())

    def pids(self) -> list[int]:
        return [int(x) for x in self.path.read_text().split()] if self.path.is_file() else []


@pytest.fixture
def registry(monkeypatch, tmp_path):
    monkeypatch.setattr(outputs, "OUTPUTS", {})
    calls = Calls(tmp_path / "calls.txt")

    def shapes(stack, cp, out):
        calls()
        (out / "shapes.vtu").write_bytes(f"{getattr(stack, 'key', '')} {cp['n']}".encode() * 1000)
        (out / "shapes_index.csv").write_text(f"n,{cp['n']}\n")
        return [out / "shapes.vtu", out / "shapes_index.csv"]

    outputs.register_output("shapes", "model", cache_on=lambda stack, cp: {"n": cp["n"]})(shapes)
    return calls


def _write(tmp_path: Path, name: str, stack, cp, cache, beside=None) -> tuple[Path, list[Path]]:
    out = tmp_path / name
    out.mkdir()
    files = outputs.write("model", stack, cp, out, beside=beside, cache=cache)
    if beside is not None:
        files += beside.wait()
    return out, files


def test_a_second_run_copies_the_cached_files(tmp_path, registry):
    """Written once (stored), then copied byte for byte (the function not called), in this
    process even where it would have been written beside the run; a changed dependency
    (``cache_on``) or another stack writes them again."""
    cache = StageCache(tmp_path / "cache")
    stack = SimpleNamespace(key="stack-1")
    a, fa = _write(tmp_path, "a", stack, {"n": 3}, cache)
    assert registry.pids() == [os.getpid()] and sorted(p.name for p in fa) == ["shapes.vtu", "shapes_index.csv"]
    b, fb = _write(tmp_path, "b", stack, {"n": 3}, cache)
    assert len(registry) == 1 and [p.parent for p in fb] == [b, b]
    for f in fa:
        assert (b / f.name).read_bytes() == f.read_bytes()
    _write(tmp_path, "c", stack, {"n": 4}, cache)                      # what else it depends on changed
    _write(tmp_path, "d", SimpleNamespace(key="stack-2"), {"n": 3}, cache)    # another model
    assert len(registry) == 3
    assert (tmp_path / "c" / "shapes_index.csv").read_text() == "n,4\n"


def test_beside_the_run_only_when_not_cached(tmp_path, monkeypatch, registry):
    """Registered beside=True: a miss is written (and stored) by the child beside the run, a
    hit copied by the run itself (no child for a copy)."""
    outputs.OUTPUTS["shapes"] = outputs.Output(**{**outputs.OUTPUTS["shapes"].__dict__, "beside": True})
    cache = StageCache(tmp_path / "cache")
    stack = SimpleNamespace(key="stack-1")
    b = Beside(True)
    _, files = _write(tmp_path, "a", stack, {"n": 3}, cache, beside=b)
    assert len(files) == 2 and len(registry) == 1 and registry.pids()[0] != os.getpid()          # the child wrote them
    b = Beside(True)
    _, files = _write(tmp_path, "b", stack, {"n": 3}, cache, beside=b)
    assert len(files) == 2 and len(registry) == 1 and not b.seconds             # copied here, no job


def test_without_cache_or_key_every_run_writes(tmp_path, registry):
    """No cache (``--no-cache``) or a stack without a key (built by hand): written each time."""
    cache = StageCache(tmp_path / "cache")
    _write(tmp_path, "a", SimpleNamespace(key="s"), {"n": 1}, None)
    _write(tmp_path, "b", SimpleNamespace(key="s"), {"n": 1}, StageCache(None))
    _write(tmp_path, "c", SimpleNamespace(key=""), {"n": 1}, cache)
    _write(tmp_path, "d", SimpleNamespace(), {"n": 1}, cache)
    assert len(registry) == 4 and not (tmp_path / "cache").exists()


def test_a_damaged_cached_file_is_written_again(tmp_path, registry):
    """A cached file that no longer matches its checksum is not copied: a warning, and the
    output written (and stored) again."""
    cache = StageCache(tmp_path / "cache")
    stack = SimpleNamespace(key="stack-1")
    a, _ = _write(tmp_path, "a", stack, {"n": 3}, cache)
    stored = next((tmp_path / "cache" / outputs.CACHE_STAGE).glob("*.shapes.vtu"))
    stored.write_bytes(b"damaged")
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        b, _ = _write(tmp_path, "b", stack, {"n": 3}, cache)
    assert any("does not match its checksum" in str(x.message) for x in w)
    assert len(registry) == 2 and (b / "shapes.vtu").read_bytes() == (a / "shapes.vtu").read_bytes()


def test_only_model_outputs_in_their_folder_are_cached(tmp_path, monkeypatch):
    monkeypatch.setattr(outputs, "OUTPUTS", {})
    with pytest.raises(InputError, match="only \"model\" outputs can be cached"):
        outputs.register_output("x", "case", cache_on=lambda stack, cp: {})
    (tmp_path / "a" / "sub").mkdir(parents=True)

    def nested(stack, cp, out):
        return [Path(out / "sub" / "f.txt").resolve()] if (out / "sub" / "f.txt").write_text("x") else []

    outputs.register_output("nested", "model", cache_on=lambda stack, cp: {})(nested)
    with pytest.raises(InputError, match="output 'nested': a cached output writes into the run's folder itself"):
        outputs.write("model", SimpleNamespace(key="k"), None, tmp_path / "a", cache=StageCache(tmp_path / "cache"))
