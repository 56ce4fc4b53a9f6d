"""The single-stick example's figures, generated: docs/workflow.md quotes them from here.

    .venv/bin/python benchmarks/single_stick_figures.py [--out DIR] [--cache DIR]

Runs examples/single_stick/scenario.toml (both cases, no pictures) and writes
``docs/figures/single_stick.json``: the vehicle's mass and first free-free bending
frequency (FE), the same of a Timoshenko beam (stick) model of the stack built here from
closed forms (the second method, :func:`stick_of_example`), the first stage's alone, and
the payload's peak axial load factor and interface force of each case; then renders the
``single-stick`` block of docs/workflow.md (benchmarks/default_figures.py). The example's
test (tests/workflows/test_single_stick.py) checks the run against the file.
"""
from __future__ import annotations

import argparse
import csv
import json
import math
import runpy
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "single_stick"
JSON = ROOT / "docs" / "figures" / "single_stick.json"
CASES = ("nominal", "controlled-release")


def _union(iv, power: int) -> float:
    """pi (b^2 - a^2) (power 2: area) or pi/4 (b^4 - a^4) (power 4: I) over the union of
    radius intervals [a, b]."""
    merged: list[list[float]] = []
    for a, b in sorted(x for x in iv if x[1] > x[0]):
        if merged and a <= merged[-1][1]:
            merged[-1][1] = max(merged[-1][1], b)
        else:
            merged.append([a, b])
    k = math.pi if power == 2 else math.pi / 4
    return sum(k * (b ** power - a ** power) for a, b in merged)


def _dome(z: float, zc: float, a: float, r: float) -> float:
    u = abs(z - zc) / a
    return r * math.sqrt(1 - u * u) if u <= 1 else 0.0


def _timoshenko(EI: float, kGA: float, L: float) -> np.ndarray:
    """Planar Timoshenko beam element (w, theta at both ends), phi = 12 EI / (k G A L^2)."""
    ph = 12 * EI / (kGA * L * L)
    c = EI / ((1 + ph) * L ** 3)
    return c * np.array([[12, 6 * L, -12, 6 * L], [6 * L, (4 + ph) * L * L, -6 * L, (2 - ph) * L * L],
                         [-12, -6 * L, 12, -6 * L], [6 * L, (2 - ph) * L * L, -6 * L, (4 + ph) * L * L]])


class _Stick:
    """Beam segments on the z axis with lumped translational mass and rotary inertia."""

    def __init__(self):
        self.nodes: dict[float, int] = {}
        self.segments: list[tuple] = []
        self.mass: dict[int, float] = {}
        self.inertia: dict[int, float] = {}

    def _node(self, z: float) -> int:
        return self.nodes.setdefault(round(z, 9), len(self.nodes))

    def segment(self, z1, z2, EI, kGA, dm, dJ):
        a, b = self._node(z1), self._node(z2)
        self.segments.append((a, b, EI, kGA, z2 - z1))
        for i in (a, b):
            self.mass[i] = self.mass.get(i, 0.0) + dm / 2
            self.inertia[i] = self.inertia.get(i, 0.0) + dJ / 2

    def frequencies(self) -> np.ndarray:
        import scipy.linalg as sla

        n = len(self.nodes)
        K, M = np.zeros((2 * n, 2 * n)), np.zeros((2 * n, 2 * n))
        for a, b, EI, kGA, L in self.segments:
            d = [2 * a, 2 * a + 1, 2 * b, 2 * b + 1]
            K[np.ix_(d, d)] += _timoshenko(EI, kGA, L)
        for i in range(n):
            M[2 * i, 2 * i] = self.mass.get(i, 0.0)
            M[2 * i + 1, 2 * i + 1] = max(self.inertia.get(i, 0.0), 1e-12 * max(self.mass.values()))
        return np.sqrt(np.abs(sla.eigh(K, M, eigvals_only=True))) / (2 * math.pi)


def _grid(z0, z1, must, dz):
    z = set(np.linspace(z0, z1, int(math.ceil((z1 - z0) / dz)) + 1).round(9))
    return np.array(sorted(z | {round(m, 9) for m in must if z0 <= m <= z1}))


def _add_tank(stick: _Stick, p, must, dz=0.1) -> None:
    """A tank stage: the wall's cross-section (union of the compartments' capsule shells and
    the intertank skirts, thickened: rho and E of the builder's equivalent material) and the
    propellant below each height (meshes.tank.liquid_volume), smeared on the wall as the
    FE model has it (its rotary inertia that of a ring)."""
    from liftoff.meshes.tank import liquid_volume, tank_layout, wall_volume

    R, t, lay = p.radius, p.wall_thickness, tank_layout(p)
    rho = p.dry_mass / wall_volume(p)
    E = p.material.E * rho / p.material.rho
    G = E / (2 * (1 + p.material.nu))

    def annuli(z):
        iv = []
        for c in lay:
            if c.z_cyl_bottom <= z <= c.z_cyl_top:
                iv.append((c.r_inner, R))
            elif z < c.z_cyl_bottom:
                iv.append((_dome(z, c.z_cyl_bottom, c.a_bottom_inner, c.r_inner), _dome(z, c.z_cyl_bottom, c.a_bottom, R)))
            else:
                iv.append((_dome(z, c.z_cyl_top, c.a_top_inner, c.r_inner), _dome(z, c.z_cyl_top, c.a_top, R)))
        iv += [(R - t, R) for lo, hi in zip(lay[:-1], lay[1:]) if lo.z_cyl_top <= z <= hi.z_cyl_bottom]
        return iv

    def liquid_below(z):
        return sum(c.liquid_density * liquid_volume(l.r_inner, l.a_bottom_inner, l.a_top_inner, l.cyl_length,
                                                    min(max(z - l.z_inner_bottom, 0.0), l.fill_height))
                   for l, c in zip(lay, p.compartments))

    zs = _grid(p.z_bottom, lay[-1].z_cyl_top + lay[-1].a_top, must, dz)
    for z1, z2 in zip(zs[:-1], zs[1:]):
        iv = annuli(0.5 * (z1 + z2))
        A, I = _union(iv, 2), _union(iv, 4)
        ml = liquid_below(z2) - liquid_below(z1)
        r_wall = max([b for _, b in iv] + [0.0])
        stick.segment(z1, z2, max(E * I, 1e3), max(0.5 * G * A, 1e3), rho * A * (z2 - z1) + ml,
                      rho * I * (z2 - z1) + ml * r_wall ** 2 / 2)


def _add_barrel(stick: _Stick, z0, z1, E, nu, R, t, rho, dz=0.25) -> None:
    """A thin barrel (or tube) of radius R, wall t: A = 2 pi R t, I = pi R^3 t, k = 0.5."""
    A, I = 2 * math.pi * R * t, math.pi * R ** 3 * t
    zs = _grid(z0, z1, [], dz)
    for a, b in zip(zs[:-1], zs[1:]):
        stick.segment(a, b, E * I, 0.5 * E / (2 * (1 + nu)) * A, rho * A * (b - a), rho * I * (b - a))


def stick_of_example(stages=("stage1", "stage2"), upper: bool = True):
    """The example's stack as a stick, from the scenario's own parameters (``stages`` and,
    with ``upper``, the interstage, fairing and payload)."""
    import tomllib

    from liftoff.config import load_scenario

    make = runpy.run_path(str(EXAMPLE / "make_files.py"), run_name="make_files")
    st, R = make["STATIONS"], make["R"]
    model = load_scenario(EXAMPLE / "scenario.toml").cases[0].model
    raw = tomllib.loads((EXAMPLE / "scenario.toml").read_text())["model"]["component"]
    joints = [st["interstage_low"], st["interstage_up"], st["fairing_low"], st["payload_if"]]
    stick = _Stick()
    for name in stages:
        _add_tank(stick, model.components[name].builder, joints)
    if not upper:
        return stick
    for name, z0, z1, r in (("interstage", st["interstage_low"], st["interstage_up"], R),
                            ("fairing", st["fairing_low"], st["fairing_top"], make["FAIRING_RADIUS"])):
        (wall, sh), = raw[name]["params"]["shells"].items()
        _add_barrel(stick, z0, z1, sh["E"], sh["nu"], r, sh["thickness"], sh["rho"])
    r_o, t = make["PAYLOAD_TUBE"]                        # outer radius, wall (m)
    A, L = math.pi * (r_o ** 2 - (r_o - t) ** 2), st["payload_top"] - st["payload_if"]
    _add_barrel(stick, st["payload_if"], st["payload_top"], 200e9, 0.3, r_o - t / 2, t,
                make["PAYLOAD_MASS"] / (A * L), dz=0.5)
    return stick


def _rows(path: Path) -> list[list[str]]:
    return list(csv.reader(line for line in path.open() if not line.startswith("#")))


def figures_of_run(out: Path) -> dict:
    """The figures of a run of the example in ``out`` (SI; load factors in g)."""
    rows = _rows(out / "modes_vehicle.csv")
    f_fe = [float(r[1]) for r in rows[1:] if r[2] == "elastic"][:2]
    summary = (out / "summary.txt").read_text()
    mass = float(summary.split("mass ")[1].split(" t")[0]) * 1e3
    stick = stick_of_example().frequencies()
    stage1 = stick_of_example(("stage1",), upper=False).frequencies()
    cases = {}
    for case in CASES:
        r = {row[0]: row for row in _rows(out / f"maxmin_{case}.csv")}
        cases[case] = {"payload_nz_max_g": float(r["load factor payload Nz"][2]),
                       "payload_if_tz_max_n": float(r["attach payload_if on payload Tz"][2])}
    return {"units": "Hz, kg, g (9.80665 m/s^2), N", "vehicle_mass_kg": mass, "first_bending_fe_hz": f_fe[0],
            "stick_mass_kg": sum(stick_of_example().mass.values()), "first_bending_stick_hz": float(stick[2]),
            "stage1_first_bending_stick_hz": float(stage1[2]), "cases": cases}


def render(fig: dict) -> str:
    c = fig["cases"]
    gap = 1 - fig["first_bending_fe_hz"] / fig["first_bending_stick_hz"]
    return ("| figure of the single-stick example (`benchmarks/single_stick_figures.py`) | value |\n|---|---|\n"
            f"| vehicle mass (FE; the stick's closed forms) | {fig['vehicle_mass_kg'] / 1e3:.1f} t "
            f"({fig['stick_mass_kg'] / 1e3:.1f} t) |\n"
            f"| first free-free bending, FE (P1, 0.9 m) | {fig['first_bending_fe_hz']:.3f} Hz |\n"
            f"| first free-free bending, Timoshenko stick | {fig['first_bending_stick_hz']:.3f} Hz "
            f"(FE {100 * gap:.1f} % below) |\n"
            f"| payload axial load factor, instantaneous release | "
            f"{c['nominal']['payload_nz_max_g']:.2f} g ({c['nominal']['payload_if_tz_max_n'] / 1e3:.0f} kN at the "
            "adapter) |\n"
            f"| payload axial load factor, controlled release | "
            f"{c['controlled-release']['payload_nz_max_g']:.2f} g "
            f"({c['controlled-release']['payload_if_tz_max_n'] / 1e3:.0f} kN) |\n")


def run_example(out: Path, cache: Path | None) -> None:
    import subprocess
    import sys

    cmd = [sys.executable, "-m", "liftoff.workflows.cli", "run", str(EXAMPLE / "scenario.toml"), "--out", str(out),
           "--no-snapshots", "--no-progress"] + (["--cache", str(cache)] if cache else [])
    subprocess.run(cmd, check=True)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, help="an existing run of the example (default: run it now)")
    ap.add_argument("--cache", type=Path)
    args = ap.parse_args(argv)
    if args.out is None:
        args.out = Path(tempfile.mkdtemp(prefix="single-stick-")) / "out"
        run_example(args.out, args.cache)
    fig = figures_of_run(args.out)
    from liftoff.core.records import write_text

    write_text(JSON, json.dumps(fig, indent=1) + "\n")
    print(render(fig))
    df = runpy.run_path(str(ROOT / "benchmarks" / "default_figures.py"), run_name="default_figures")
    for doc in df["DOCS"]:
        doc.write_text(df["apply_blocks"](doc.read_text(), {"single-stick": render(fig)}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
