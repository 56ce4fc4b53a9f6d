"""``liftoff init --example NAME DIR``: an editable scenario that starts from an embedded
example (liftoff.config.extends).

The files an example's scenario names (single_stick's .geo geometry and Nastran payload)
are written beside it: they are the user's to edit, and paths resolve against DIR.

By default DIR/scenario.toml is a short file, ``extends = "NAME"`` and a title, with the
keys users change most written as comments; every other key is the example's and follows
it when liftoff is updated. ``--full`` writes the example in full instead (a frozen,
self-contained copy). Nothing is overwritten: an existing DIR/scenario.toml is refused.
"""
from __future__ import annotations

import argparse
from pathlib import Path

SCENARIO_NAME = "scenario.toml"

#: the commented guide of each example's short scenario: keys users change most
_GUIDE = {
    "shuttle": '''
# Everything not set here is the "shuttle" example's (liftoff init --example shuttle --full
# DIR writes it in full). Tables merge key by key, and the entries of the arrays of tables
# (case, engine, post, force) by their name: a new name adds one. docs/workflow.md,
# "Scenarios".
#
# [model]
# degree = 1                    # P1 solids: faster, not mesh-converged (docs/workflow.md, "Convergence")
#   (or source = "stick": beams instead of FE, a fresh [model] without the FE keys such as degree)
#
# [model.component.core]
# mesh_size = 0.85              # m
# f_max = 60.0                  # Hz: every fixed-interface mode below it is kept
#
# [post_defaults]
# stiffness = [2.0e9, 2.0e9, 5.0e9]   # N/m per post (Tx, Ty, Tz)
# release_time = 6.6            # s
#
# [[engine]]
# name = "ssme_1"               # an example engine: only the keys given change
# start = 0.24                  # s
#
# [time]
# t_end = 9.6                   # s
#
# [[case]]
# name = "my-case"              # a case besides the example's "nominal" and "no-control"
''',
    "saturn_v": '''
# Everything not set here is the "saturn_v" example's (liftoff init --example saturn_v --full DIR
# writes it in full): three tank stages, two barrel interstages, the spacecraft adapter and a
# platform, every part a parametric type (docs/workflow.md, "The vehicle and the pad").
#
# [model.component.s_ic]
# mesh_size = 1.2               # m
#
# [post_defaults]
# release_time = 3.5            # s: the hold-down arms let go
#
# [[engine]]
# name = "f1_centre"            # the centre F-1: only the keys given change
# start = 0.1                   # s
#
# [[case]]
# name = "my-case"              # a case besides "controlled-release" and "instantaneous"
''',
    "single_stick": '''
# Everything not set here is the "single_stick" example's (liftoff init --example single_stick
# --full DIR writes it in full): two tank stages, the interstage, fairing and launch table from
# the .geo files beside this one, the payload from payload.pch (a Nastran Craig-Bampton model,
# inch-pound-second). Those files are yours to edit: paths resolve against this folder.
# docs/workflow.md, "The vehicle and the pad".
#
# [model.component.stage1]
# mesh_size = 0.9               # m
#
# [model.component.payload.nastran]
# file = "payload.pch"          # the payload's Craig-Bampton model: replace the file, or name yours
# units = "in-lbf-s"            # the units it is written in
#
# [post_defaults]
# release_time = 2.5            # s: the clamps open
#
# [[engine]]
# name = "engines_a"            # three of the nine engines: only the keys given change
# start = 0.0                   # s
#
# [[case]]
# name = "my-case"              # a case besides "nominal" and "controlled-release"
''',
    "barge": '''
# Everything not set here is the "barge" example's (liftoff init --example barge --full DIR
# writes it in full). Tables merge key by key, and the entries of the arrays of tables
# (case, force) by their name. docs/barge.md.
#
# [impact]
# velocity = 0.5                # m/s towards the dock
#
# [fender]
# stiffness = 1.0e8             # N/m per fender (the example's cases sweep it)
''',
}


def scenario_text(example: str, full: bool) -> str:
    """The scenario DIR/scenario.toml gets for ``example``."""
    from liftoff.config.extends import check_example, example_text

    check_example(example)
    if full:
        return example_text(example)
    return (f'# liftoff scenario: `liftoff run {SCENARIO_NAME} --out DIR` (SI units)\n'
            f'extends = "{example}"\ntitle = "my {example} scenario"\n' + _GUIDE[example])


def init(example: str, folder: Path, full: bool = False) -> Path:
    """Write ``folder``/scenario.toml and the files the example's scenario names (geometry,
    Nastran; each atomically; an existing file is refused before anything is written);
    returns the scenario's path."""
    from liftoff.config.extends import example_files
    from liftoff.core.errors import InputError
    from liftoff.core.records import write_bytes, write_text

    text = scenario_text(example, full)
    files = example_files(example)
    if folder.exists() and not folder.is_dir():
        raise InputError(f"{folder}: exists and is not a folder")
    path = folder / SCENARIO_NAME
    for target in (path, *(folder / f for f in files)):
        if target.exists():
            raise InputError(f"{target}: exists; liftoff init never overwrites a file (remove it or give "
                             "another folder)")
    folder.mkdir(parents=True, exist_ok=True)
    for name, content in files.items():
        write_bytes(folder / name, content)
    return write_text(path, text)


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Register ``liftoff init`` on the CLI's subparsers (workflows/cli.py)."""
    from liftoff.config.extends import EXAMPLES

    p = sub.add_parser(
        "init", help="write an editable scenario that starts from an example",
        description="Write DIR/scenario.toml: a scenario that extends an embedded example "
                    "(extends = NAME; only the keys it sets differ), or with --full the example in full.")
    p.add_argument("folder", type=Path, metavar="DIR", help="folder for scenario.toml (created)")
    p.add_argument("--example", default="shuttle", choices=tuple(EXAMPLES),
                   help="the example to start from [shuttle]")
    p.add_argument("--full", action="store_true", help="write the whole example instead of extends = NAME")
    p.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    path = init(args.example, args.folder, args.full)
    from liftoff.config.extends import EXAMPLES

    files = EXAMPLES[args.example].files
    also = f" and {', '.join(files)}" if files else ""
    print(f"liftoff init: wrote {path}{also} (run it: liftoff run {path} --out DIR)")
    return 0
