"""Scenarios that start from another (``extends``, liftoff.config.extends) and ``liftoff init``."""
from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

from liftoff.config import default_text, load_barge, load_scenario, merge, parse_scenario, parse_toml
from liftoff.config.extends import EXAMPLES, example_text
from liftoff.core.errors import InputError
from liftoff.workflows.init import init, scenario_text


def _write(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


def _default_with(over: dict):
    return parse_scenario(merge(parse_toml(default_text(), "d"), over), "d")


def test_extends_is_the_example_with_the_keys_given(tmp_path):
    """A file that extends the Shuttle and sets three keys parses to the same mapping (and
    cases) as the embedded default with those keys merged in."""
    f = _write(tmp_path / "s.toml", 'extends = "shuttle"\ntitle = "mine"\n[model.component.core]\nf_max = 50.0\n'
                                    '[[engine]]\nname = "ssme_1"\nstart = 0.3\n[[case]]\nname = "extra"\n')
    sc = load_scenario(f)
    ref = _default_with({"title": "mine", "model": {"component": {"core": {"f_max": 50.0}}},
                         "engine": [{"name": "ssme_1", "start": 0.3}], "case": [{"name": "extra"}]})
    assert sc.data == ref.data and "extends" not in sc.data
    assert [c.name for c in sc.cases] == ["nominal", "no-control", "extra"]
    assert sc.cases[0].model.components["core"].f_max == 50.0
    assert next(e for e in sc.cases[0].engines if e.name == "ssme_1").start == 0.3
    assert len(sc.cases[0].engines) == 5            # the others are the example's


def test_a_chain_of_files(tmp_path):
    _write(tmp_path / "base.toml", 'extends = "shuttle"\n[time]\nt_end = 8.0\n')
    sub = tmp_path / "sub"
    sub.mkdir()
    f = _write(sub / "s.toml", 'extends = "../base.toml"\n[time]\nh = 1e-4\n')
    sc = load_scenario(f)
    assert sc.data["time"]["t_end"] == 8.0 and sc.data["time"]["h"] == 1e-4
    assert sc.data["model"] == parse_toml(default_text(), "d")["model"]


def test_another_model_source_does_not_inherit_the_model(tmp_path):
    """One key switches the Shuttle to the stick model: the example's FE [model] (meshes,
    materials, builder parameters) is not inherited; an FE key the file itself sets with
    the stick source is still refused."""
    sc = load_scenario(_write(tmp_path / "a.toml", 'extends = "shuttle"\n[model]\nsource = "stick"\n'))
    assert sc.cases[0].model.source == "stick" and sc.data["model"] == {"source": "stick"}
    assert sc.data["post"] == parse_toml(default_text(), "d")["post"]
    with pytest.raises(InputError, match=r"b\.toml: model\.walls: .*source = \"fe\""):
        load_scenario(_write(tmp_path / "b.toml", 'extends = "shuttle"\n[model]\nsource = "stick"\nwalls = "shell"\n'))
    # the same source: the model merges key by key
    sc = load_scenario(_write(tmp_path / "c.toml", 'extends = "shuttle"\n[model]\nsource = "fe"\ndegree = 1\n'))
    assert sc.cases[0].model.degree == 1 and sc.cases[0].model.components["core"].mesh_size == 0.85


@pytest.mark.parametrize("text, match", [
    ('extends = "shutle"\n', r"s\.toml: extends: no example and no file 'shutle' .*examples: shuttle, barge"),
    ('extends = "s.toml"\n', r"s\.toml: extends: .*cycle"),
    ('extends = 3\n', r"s\.toml: extends: "),
    ('extends = "shuttle"\n[model]\nfoo = 1\n', r"s\.toml: model: unknown key 'foo'"),
    ('extends = "shuttle"\nkind = "barge"\n', r"s\.toml: kind: 'barge' differs from the kind of the scenario it extends"),
    ('extends = "missing/base.toml"\n', r"s\.toml: extends: no example and no file 'missing/base.toml'"),
])
def test_bad_extends_is_one_line(tmp_path, text, match):
    f = _write(tmp_path / "s.toml", text)
    with pytest.raises(InputError, match=match) as exc:
        load_scenario(f)
    assert "\n" not in str(exc.value)


def test_a_two_file_cycle(tmp_path):
    _write(tmp_path / "a.toml", 'extends = "b.toml"\n')
    _write(tmp_path / "b.toml", 'extends = "a.toml"\n')
    with pytest.raises(InputError, match=r"cycle: .*a\.toml -> .*b\.toml -> .*a\.toml"):
        load_scenario(tmp_path / "a.toml")


def test_barge_extends_the_barge_example(tmp_path):
    f = _write(tmp_path / "b.toml", 'extends = "barge"\n[impact]\nvelocity = 0.5\n')
    from liftoff.config import scenario_kind

    assert scenario_kind(f) == "barge"
    ref = parse_toml(example_text("barge"), "b")
    sc = load_barge(f)
    assert sc.title == ref["title"] and len(sc.cases) == len(ref["case"])
    assert all(c.velocity == 0.5 for c in sc.cases) and ref["impact"]["velocity"] != 0.5


def test_init_writes_a_short_scenario_whose_guide_is_valid(tmp_path):
    """``liftoff init``: the short file extends the example; every commented key of its
    guide, uncommented, is a valid scenario (the guide cannot rot)."""
    for name in EXAMPLES:
        path = init(name, tmp_path / name)
        text = path.read_text()
        assert f'extends = "{name}"' in text
        loader = load_barge if name == "barge" else load_scenario
        loader(path)
        guide = re.sub(r"^# (?=\[|[a-z_]+ = )", "", text, flags=re.M)     # uncomment the keys and tables
        assert guide != text
        loader(_write(path.parent / "all.toml", guide))     # beside the example's files (single_stick)
        full = init(name, tmp_path / f"{name}_full", full=True)
        assert full.read_text() == example_text(name)


def test_init_never_overwrites(tmp_path):
    init("shuttle", tmp_path)
    (tmp_path / "scenario.toml").write_text("mine")
    with pytest.raises(InputError, match="exists; liftoff init never overwrites"):
        init("shuttle", tmp_path)
    assert (tmp_path / "scenario.toml").read_text() == "mine"
    assert scenario_text("shuttle", True) == default_text()


def test_init_writes_the_files_the_example_names(tmp_path):
    """``liftoff init --example single_stick``: the .geo geometry and the Nastran payload are
    written beside the scenario, byte for byte examples/single_stick's (the package data is
    that folder), so the short scenario runs from DIR; an existing one of them is refused
    before anything is written; without them, a scenario that extends the example fails
    naming the missing file."""
    folder = Path(__file__).resolve().parents[2] / "examples" / "single_stick"
    assert example_text("single_stick") == (folder / "scenario.toml").read_text()
    path = init("single_stick", tmp_path / "a")
    for name in EXAMPLES["single_stick"].files:
        assert (path.parent / name).read_bytes() == (folder / name).read_bytes(), name
    sc = load_scenario(path)
    assert set(sc.cases[0].model.components) >= {"stage1", "interstage", "fairing", "payload"}
    (tmp_path / "b").mkdir()
    (tmp_path / "b" / "pad.geo").write_text("mine")
    with pytest.raises(InputError, match="pad.geo: exists; liftoff init never overwrites"):
        init("single_stick", tmp_path / "b")
    assert sorted(p.name for p in (tmp_path / "b").iterdir()) == ["pad.geo"]
    lone = _write(tmp_path / "lone.toml", 'extends = "single_stick"\n')
    with pytest.raises(InputError, match=r"file not found: .*\.(pch|geo)"):
        load_scenario(lone)


def test_init_cli(tmp_path):
    cmd = [sys.executable, "-m", "liftoff.workflows.cli", "init", str(tmp_path / "x"), "--example", "barge"]
    r = subprocess.run(cmd, capture_output=True, text=True)
    assert r.returncode == 0 and "wrote" in r.stdout
    r = subprocess.run(cmd, capture_output=True, text=True)
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and "never overwrites" in r.stderr


def test_the_documented_example_parses(tmp_path):
    """docs/workflow.md's extends example is a valid scenario that changes what it says."""
    doc = (Path(__file__).resolve().parents[2] / "docs" / "workflow.md").read_text()
    section = doc[doc.index("### Scenarios that start from an example"):]
    block = re.search(r"```toml\n(.*?)```", section, re.S).group(1)
    sc = load_scenario(_write(tmp_path / "doc.toml", block))
    assert sc.cases[0].model.source == "stick"
    assert next(e for e in sc.cases[0].engines if e.name == "ssme_1").start == 0.30


def test_an_entry_of_the_base_is_removed_by_name(tmp_path):
    """Arrays of named tables merge by name at any depth (a stage's compartments too: a user's
    own were added to the example's, doubling its propellant; a review), and
    `{name = "x", remove = true}` takes the base's entry x out: an example's engine, or a
    stage's compartments replaced by removing the base's and giving one's own."""
    f = _write(tmp_path / "s.toml", 'extends = "shuttle"\n[[engine]]\nname = "ssme_3"\nremove = true\n')
    sc = load_scenario(f)
    assert len(sc.cases[0].engines) == 4 and "ssme_3" not in {e.name for e in sc.cases[0].engines}
    base = {"stage": {"compartments": [{"name": "rp1", "cyl_length": 10.0}, {"name": "lox", "cyl_length": 12.0}]}}
    over = {"stage": {"compartments": [{"name": "rp1", "remove": True}, {"name": "lox", "remove": True},
                                       {"name": "fuel", "cyl_length": 8.0}]}}
    assert merge(base, over)["stage"]["compartments"] == [{"name": "fuel", "cyl_length": 8.0}]
    assert [c["name"] for c in merge(base, {"stage": {"compartments": [{"name": "fuel", "cyl_length": 8.0}]}})[
        "stage"]["compartments"]] == ["rp1", "lox", "fuel"]          # (without remove: added, as documented)
    with pytest.raises(InputError, match="remove = true for 'x', which the scenario extended has not"):
        merge(base, {"stage": {"compartments": [{"name": "x", "remove": True}]}})
    with pytest.raises(InputError, match="remove = true takes nothing but the name"):
        merge(base, {"stage": {"compartments": [{"name": "rp1", "remove": True, "cyl_length": 3.0}]}})
