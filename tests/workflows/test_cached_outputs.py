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
    """No cache (``--no-cache``; with generated cases only the run's temporary one, gone with
    it) or a stack without a key (built by hand): written each time."""
    cache = StageCache(tmp_path / "cache")
    _write(tmp_path, "a", SimpleNamespace(key="s"), {"n": 1}, None)
    _write(tmp_path, "b", SimpleNamespace(key="s"), {"n": 1}, StageCache(None))
    _write(tmp_path, "c", SimpleNamespace(key=""), {"n": 1}, cache)
    _write(tmp_path, "d", SimpleNamespace(), {"n": 1}, cache)
    _write(tmp_path, "e", SimpleNamespace(key="s"), {"n": 1}, StageCache(tmp_path / "tmp", temporary=True))
    assert len(registry) == 5 and not (tmp_path / "cache").exists() and not (tmp_path / "tmp").exists()


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


SCRIPT = "liftoff_test_a_script_not_a_module"


def test_an_output_of_a_script_is_keyed_by_its_source(tmp_path, monkeypatch):
    """An output defined in a script (module ``__main__`` of ``python script.py``, which has no
    spec; here a module name no finder knows) is keyed by its function's source; one whose
    source cannot be read is written each time, with a warning."""
    monkeypatch.setattr(outputs, "OUTPUTS", {})
    calls = Calls(tmp_path / "calls.txt")

    def table(stack, cp, out):
        calls()
        return [Path(out / "t.txt")] if (out / "t.txt").write_text("t") else []

    table.__module__ = SCRIPT
    outputs.register_output("table", "model", cache_on=lambda stack, cp: {})(table)
    cache, stack = StageCache(tmp_path / "cache"), SimpleNamespace(key="k")
    for name in ("a", "b"):
        _write(tmp_path, name, stack, None, cache)
    assert len(calls) == 1 and (tmp_path / "b" / "t.txt").read_text() == "t"
    ns: dict = {}
    exec("def hidden(stack, cp, out):\n    return []\n", ns)          # no source file behind it
    ns["hidden"].__module__ = SCRIPT
    outputs.register_output("hidden", "model", cache_on=lambda stack, cp: {})(ns["hidden"])
    with pytest.warns(UserWarning, match="output 'hidden': neither its module nor its source can be read"):
        _write(tmp_path, "c", stack, None, cache)


def test_a_killed_writers_leftovers_are_not_recorded(tmp_path, registry):
    """Files of an entry whose writer died before its record are not part of the entry that
    is then written (nor copied on later hits)."""
    cache = StageCache(tmp_path / "cache")
    stack = SimpleNamespace(key="stack-1")
    _write(tmp_path, "a", stack, {"n": 3}, cache)
    folder = tmp_path / "cache" / outputs.CACHE_STAGE
    record = next(folder.glob("*.entry.json"))
    key = record.name.split(".")[0]
    record.unlink()
    (folder / f"{key}.stale.txt").write_text("from a killed run")
    _write(tmp_path, "b", stack, {"n": 3}, cache)
    _, files = _write(tmp_path, "c", stack, {"n": 3}, cache)
    assert len(registry) == 2 and sorted(p.name for p in files) == ["shapes.vtu", "shapes_index.csv"]
    assert not (folder / f"{key}.stale.txt").exists() and not (tmp_path / "c" / "stale.txt").exists()


def test_a_failing_copy_into_the_run_keeps_the_entry(tmp_path, registry, monkeypatch):
    """An error writing into the run's folder (a full disk) is the run's error, not a damaged
    entry: the entry stays for the next run."""
    import shutil

    cache = StageCache(tmp_path / "cache")
    stack = SimpleNamespace(key="stack-1")
    _write(tmp_path, "a", stack, {"n": 3}, cache)
    real = shutil.copyfile

    def full(src, dst, **kw):
        if Path(dst).parent.name == "b":
            raise OSError(28, "No space left on device")
        return real(src, dst, **kw)

    monkeypatch.setattr(shutil, "copyfile", full)
    with pytest.raises(OSError, match="No space left"):
        _write(tmp_path, "b", stack, {"n": 3}, cache)
    monkeypatch.setattr(shutil, "copyfile", real)
    _write(tmp_path, "c", stack, {"n": 3}, cache)
    assert len(registry) == 1


def test_the_keys_see_what_the_files_depend_on():
    """The stack's key changes with the damping, the modes kept and a joint's releases; the
    recovery OP4's with any recovery matrix of the vehicle (not the pad's); the mode shapes'
    with a mode's sign."""
    import dataclasses

    import numpy as np

    from liftoff.config import load_scenario
    from liftoff.workflows.fields import mode_shapes_inputs
    from liftoff.workflows.pipeline import stack_key
    from liftoff.workflows.report import recovery_op4_inputs

    model = load_scenario(None).cases[0].model
    ckeys = {n: f"key-{n}" for n in list(model.vehicle) + ["pad"]}
    free = SimpleNamespace(released=[])
    base = stack_key(model, free, ckeys)
    assert stack_key(model, free, dict(ckeys)) == base
    others = [stack_key(dataclasses.replace(model, zeta=model.zeta * 2), free, ckeys),
              stack_key(dataclasses.replace(model, system=dataclasses.replace(model.system, f_max=50.0)), free, ckeys),
              stack_key(model, SimpleNamespace(released=[("att", "srb_left", 2)]), ckeys),
              stack_key(model, free, {**ckeys, "pad": "other"})]
    assert len({base, *others}) == 5

    rng = np.random.default_rng(1)

    def rec(body):
        return SimpleNamespace(body=body, name="r", category="attach", labels=["a", "b"], units=["N", "N"],
                               disp=rng.standard_normal((2, 5)), vel=None, acc=rng.standard_normal((2, 5)), const=None)

    recs = [rec("a"), rec("b")]
    cp = SimpleNamespace(problem=SimpleNamespace(recoveries=recs))
    k0 = recovery_op4_inputs(None, cp)
    recs[1].disp[0, 0] += 1.0                                  # the pad's: not in the OP4
    assert recovery_op4_inputs(None, cp) == k0
    recs[0].acc[1, 4] = np.nextafter(recs[0].acc[1, 4], np.inf)
    assert recovery_op4_inputs(None, cp) != k0

    phi = rng.standard_normal((8, 4))
    stack = SimpleNamespace(vehicle_modes=SimpleNamespace(omega=np.arange(4.0), phi=phi))
    m0 = mode_shapes_inputs(stack, None)
    phi[:, 2] *= -1.0
    assert mode_shapes_inputs(stack, None) != m0


def test_the_modal_tables_key_sees_the_contacts_and_both_bodies_modes():
    """The modal tables (modes_vehicle.csv/.h5, the held vehicle's and the pad's effective mass)
    are keyed, besides the stack, by the vehicle's contact DOFs (the held condition) and both
    bodies' system modes; a rigid ground has none of its own."""
    import numpy as np

    from liftoff.workflows.report import modal_tables_inputs

    rng = np.random.default_rng(2)
    vm = SimpleNamespace(omega=np.arange(4.0), phi=rng.standard_normal((8, 4)))
    pm = SimpleNamespace(omega=np.arange(1.0, 3.0), phi=rng.standard_normal((5, 2)))
    contacts = [SimpleNamespace(labels_a=["hd_1:Tx", "hd_1:Tz"])]
    stack = SimpleNamespace(vehicle_modes=vm, pad_modes=pm, pad=SimpleNamespace(is_ground=False))
    cp = SimpleNamespace(problem=SimpleNamespace(contacts=contacts))
    k0 = modal_tables_inputs(stack, cp)
    assert modal_tables_inputs(stack, cp) == k0
    pm.phi[3, 1] *= -1.0                                       # the pad's modes
    k1 = modal_tables_inputs(stack, cp)
    vm.phi[0, 2] *= -1.0                                       # the vehicle's
    k2 = modal_tables_inputs(stack, cp)
    contacts[0].labels_a.append("hd_1:Ty")                     # another held DOF
    k3 = modal_tables_inputs(stack, cp)
    assert len({repr(k) for k in (k0, k1, k2, k3)}) == 4
    ground = SimpleNamespace(vehicle_modes=vm, pad_modes=None, pad=SimpleNamespace(is_ground=True))
    assert modal_tables_inputs(ground, cp) != k3
