"""The launcher examples' figures, generated: docs/workflow.md quotes them from here.

    .venv/bin/python benchmarks/example_figures.py NAME [--out DIR] [--cache DIR]

NAME is ``single_stick`` or ``saturn_v`` (examples/NAME). Runs the example's scenario (all
its cases, no pictures) and writes ``docs/figures/NAME.json``: the vehicle's mass and first
free-free bending frequency (FE), the same of a Timoshenko beam (stick) model of the stack
built here from closed forms (the second method, :func:`stick_of`), and the payload's peak
axial load factor and interface force in each case; then renders the example's block of
docs/workflow.md (benchmarks/default_figures.py). The examples' tests
(tests/workflows/test_examples_liftoff.py) check their runs against these files.
"""
from __future__ import annotations

import argparse
import csv
import json
import math
import runpy
import tempfile
from dataclasses import dataclass
from pathlib import Path

import liftoff  # noqa: F401 - before numpy: it picks the OpenBLAS kernels (liftoff/core/openblas.py)
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
FIGURES = ROOT / "docs" / "figures"


@dataclass(frozen=True)
class Example:
    """What the figures of one example are: its folder, its cases, the payload component and
    the attach point of its interface."""

    name: str
    title: str
    cases: tuple[str, ...]
    payload: str
    interface: str

    @property
    def folder(self) -> Path:
        return ROOT / "examples" / self.name

    @property
    def json(self) -> Path:
        return FIGURES / f"{self.name}.json"

    @property
    def block(self) -> str:
        return self.name.replace("_", "-")


EXAMPLES = {e.name: e for e in (
    Example("single_stick", "the single-stick example", ("nominal", "controlled-release"), "payload", "payload_if"),
    Example("saturn_v", "the Saturn V example", ("controlled-release", "instantaneous"), "spacecraft", "sc_1"))}


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
    """Planar Timoshenko beam element (w, theta at both ends), phi = 12 EI / (k G A L^2):
    liftoff.core.beam's bending plane."""
    from liftoff.core.beam import bending_stiffness

    return bending_stiffness(EI, L, 12 * EI / (kGA * L * L))


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

    def add_mass(self, z: float, mass: float, inertia: float) -> None:
        """A lumped mass (kg) and rotary inertia about a lateral axis (kg m^2) at height z."""
        i = self._node(z)
        self.mass[i] = self.mass.get(i, 0.0) + mass
        self.inertia[i] = self.inertia.get(i, 0.0) + inertia

    def frequencies(self, n_freq: int = 8) -> np.ndarray:
        """The lowest ``n_freq`` frequencies (Hz) of the planar stick, rigid-body modes first."""
        import scipy.linalg as sla

        n = len(self.nodes)
        K, M = np.zeros((2 * n, 2 * n)), np.zeros((2 * n, 2 * n))
        for a, b, EI, kGA, L in self.segments:
            d = [2 * a, 2 * a + 1, 2 * b, 2 * b + 1]
            K[np.ix_(d, d)] += _timoshenko(EI, kGA, L)
        for i in range(n):
            M[2 * i, 2 * i] = self.mass.get(i, 0.0)
            M[2 * i + 1, 2 * i + 1] = max(self.inertia.get(i, 0.0), 1e-12 * max(self.mass.values()))
        lam = sla.eigh(K, M, eigvals_only=True, subset_by_index=[0, min(n_freq, 2 * n) - 1])
        return np.sqrt(np.abs(lam)) / (2 * math.pi)


def _grid(z0, z1, must, dz):
    z = set(np.linspace(z0, z1, int(math.ceil((z1 - z0) / dz)) + 1).round(9))
    return np.array(sorted(z | {round(m, 9) for m in must if z0 <= m <= z1}))


def _add_tank(stick: _Stick, p, must, dz=0.1) -> None:
    """A tank stage: its mass from the wall's cross-section (union of the compartments'
    capsule shells and the intertank skirts, thickened: rho and E of the builder's equivalent
    material) and the propellant smeared on the wall as the FE model has it: each
    compartment's liquid mass uniform per wetted area up to its fill level
    (meshes.tank.wetted_area; not the liquid's own distribution, which puts less of it on the
    domes), its rotary inertia that of a ring; its stiffness from
    the walls continuous along the axis there: the barrels and the intertank skirts (a dome
    hangs on its barrel's end and carries no bending across the intertank), the domes
    themselves only beyond the end barrels."""
    from liftoff.meshes.tank import tank_layout, wall_volume, wetted_area

    R, t, lay = p.radius, p.wall_thickness, tank_layout(p)
    rho = p.dry_mass / wall_volume(p)
    E = p.material.E * rho / p.material.rho
    G = E / (2 * (1 + p.material.nu))

    def annuli(z, continuous=False):
        iv = []
        if continuous:
            iv = [(c.r_inner, R) for c in lay if c.z_cyl_bottom <= z <= c.z_cyl_top]
            iv += [(R - t, R) for lo, hi in zip(lay[:-1], lay[1:]) if lo.z_cyl_top <= z <= hi.z_cyl_bottom]
            if iv or lay[0].z_cyl_bottom <= z <= lay[-1].z_cyl_top:
                return iv
        for c in lay:
            if c.z_cyl_bottom <= z <= c.z_cyl_top:
                iv.append((c.r_inner, R))
            elif z < c.z_cyl_bottom:
                iv.append((_dome(z, c.z_cyl_bottom, c.a_bottom_inner, c.r_inner), _dome(z, c.z_cyl_bottom, c.a_bottom, R)))
            else:
                iv.append((_dome(z, c.z_cyl_top, c.a_top_inner, c.r_inner), _dome(z, c.z_cyl_top, c.a_top, R)))
        iv += [(R - t, R) for lo, hi in zip(lay[:-1], lay[1:]) if lo.z_cyl_top <= z <= hi.z_cyl_bottom]
        return iv

    def liquid_below(z):            # the FE's smeared liquid: each compartment's mass uniform per wetted area
        return sum(c.liquid_density * l.liquid_volume()
                   * wetted_area(l.r_inner, l.a_bottom_inner, l.a_top_inner, l.cyl_length,
                                 min(max(z - l.z_inner_bottom, 0.0), l.fill_height)) / l.wetted_area()
                   for l, c in zip(lay, p.compartments))

    zs = _grid(p.z_bottom, lay[-1].z_cyl_top + lay[-1].a_top, must, dz)
    for z1, z2 in zip(zs[:-1], zs[1:]):
        iv, path = annuli(0.5 * (z1 + z2)), annuli(0.5 * (z1 + z2), continuous=True)
        A, I = _union(iv, 2), _union(iv, 4)
        ml = liquid_below(z2) - liquid_below(z1)
        r_wall = max([b for _, b in iv] + [0.0])
        stick.segment(z1, z2, max(E * _union(path, 4), 1e3), max(0.5 * G * _union(path, 2), 1e3),
                      rho * A * (z2 - z1) + ml, rho * I * (z2 - z1) + ml * r_wall ** 2 / 2)


def _add_barrel(stick: _Stick, z0, z1, E, nu, r0, r1, t, rho, dz=0.25) -> None:
    """A thin barrel (or tube, or cone frustum) of radius r0 at z0 to r1 at z1, wall t: A = 2
    pi R t, I = pi R^3 t at each segment's mid radius, shear coefficient 0.5."""
    zs = _grid(z0, z1, [], dz)
    for a, b in zip(zs[:-1], zs[1:]):
        r = r0 + (r1 - r0) * (0.5 * (a + b) - z0) / (z1 - z0)
        A, I = 2 * math.pi * r * t, math.pi * r ** 3 * t
        stick.segment(a, b, E * I, 0.5 * E / (2 * (1 + nu)) * A, rho * A * (b - a), rho * I * (b - a))


def stick_of(model, barrels: dict | None = None, only: tuple[str, ...] | None = None) -> _Stick:
    """A stick of a scenario's vehicle (liftoff.config ModelConfig): ``tank_stage`` and
    ``barrel`` components from their parameters (a barrel's axis point rigidly above its
    ring, carrying its point mass), any other component (a ``geometry`` barrel, a
    ``nastran`` payload) from ``barrels`` {component: (z0, z1, E, nu, r0, r1, t, rho[, dz])};
    joints rigid (nodes shared at equal heights). ``only``: those components alone."""
    from liftoff.meshes.barrel import BarrelParams

    barrels = barrels or {}
    names = only or model.vehicle
    heights = set()
    for n in model.vehicle:
        b = model.components[n].builder
        if isinstance(b, BarrelParams):
            heights |= {b.z_bottom, b.z_top}
        elif n in barrels:
            heights |= {barrels[n][0], barrels[n][1]}
    stick = _Stick()
    for n in names:
        comp = model.components[n]
        if comp.type == "tank_stage":
            _add_tank(stick, comp.builder, sorted(heights))
        elif comp.type == "barrel":
            p = comp.builder
            area = p.wall_area()
            rho = p.material.rho if p.mass is None else p.mass / (area * p.thickness)
            E = p.material.E * rho / p.material.rho if p.mass is not None else p.material.E
            _add_barrel(stick, p.z_bottom, p.z_top, E, p.material.nu, p.radius_bottom, p.radius_top, p.thickness, rho)
            for point, z in {**p.bottom_point, **p.top_point}.items():
                ring = p.z_top if point in p.top_point else p.z_bottom
                m = p.point_masses.get(point, [0.0, 0.0, 0.0, 0.0])
                big = 1e3 * max(s[2] for s in stick.segments)
                stick.segment(min(ring, z), max(ring, z), big, big, 0.0, 0.0)
                stick.add_mass(z, m[0], m[2])
        elif n in barrels:
            _add_barrel(stick, *barrels[n])
        else:
            raise ValueError(f"no stick for component {n!r} of type {comp.type!r}")
    return stick


def _single_stick_extras(model) -> dict:
    """The single-stick example's .geo barrels and its Nastran payload tube, as barrels."""
    import tomllib

    ex = EXAMPLES["single_stick"]
    make = runpy.run_path(str(ex.folder / "make_files.py"), run_name="make_files")
    st, R = make["STATIONS"], make["R"]
    raw = tomllib.loads((ex.folder / "scenario.toml").read_text())["model"]["component"]
    out = {}
    for name, z0, z1, r in (("interstage", st["interstage_low"], st["interstage_up"], R),
                            ("fairing", st["fairing_low"], st["fairing_top"], make["FAIRING_RADIUS"])):
        (_, sh), = raw[name]["params"]["shells"].items()
        out[name] = (z0, z1, sh["E"], sh["nu"], r, r, sh["thickness"], sh["rho"])
    r_o, t = make["PAYLOAD_TUBE"]                        # outer radius, wall (m)
    A, L = math.pi * (r_o ** 2 - (r_o - t) ** 2), st["payload_top"] - st["payload_if"]
    out["payload"] = (st["payload_if"], st["payload_top"], 200e9, 0.3, r_o - t / 2, r_o - t / 2, t,
                      make["PAYLOAD_MASS"] / (A * L), 0.5)
    return out


def stick_of_example(name: str, only: tuple[str, ...] | None = None) -> _Stick:
    from liftoff.config import load_scenario

    model = load_scenario(EXAMPLES[name].folder / "scenario.toml").cases[0].model
    extras = _single_stick_extras(model) if name == "single_stick" else {}
    return stick_of(model, extras, only)


def _rows(path: Path) -> list[list[str]]:
    return list(csv.reader(line for line in path.open() if not line.startswith("#")))


def figures_of_run(name: str, out: Path) -> dict:
    """The figures of a run of example ``name`` in ``out`` (SI; load factors in g)."""
    ex = EXAMPLES[name]
    rows = _rows(out / "modes_vehicle.csv")
    f_fe = [float(r[1]) for r in rows[1:] if r[2] == "elastic"][0]
    summary = (out / "summary.txt").read_text()
    mass = float(summary.split("mass ")[1].split(" t")[0]) * 1e3
    stick = stick_of_example(name)
    cases = {}
    for case in ex.cases:
        r = {row[0]: row for row in _rows(out / f"maxmin_{case}.csv")}
        cases[case] = {"payload_nz_max_g": float(r[f"load factor {ex.payload} Nz"][2]),
                       "payload_if_tz_max_n": float(r[f"attach {ex.interface} on {ex.payload} Tz"][2])}
    return {"units": "Hz, kg, g (9.80665 m/s^2), N", "vehicle_mass_kg": mass, "first_bending_fe_hz": f_fe,
            "stick_mass_kg": sum(stick.mass.values()), "first_bending_stick_hz": float(stick.frequencies()[2]),
            "cases": cases}


def render(name: str, fig: dict) -> str:
    ex = EXAMPLES[name]
    gap = 1 - fig["first_bending_fe_hz"] / fig["first_bending_stick_hz"]
    lines = [f"| figure of {ex.title} (`benchmarks/example_figures.py {name}`) | value |", "|---|---|",
             f"| vehicle mass (FE; the stick's closed forms) | {fig['vehicle_mass_kg'] / 1e3:.1f} t "
             f"({fig['stick_mass_kg'] / 1e3:.1f} t) |",
             f"| first free-free bending, FE | {fig['first_bending_fe_hz']:.3f} Hz |",
             f"| first free-free bending, Timoshenko stick | {fig['first_bending_stick_hz']:.3f} Hz "
             f"(FE {100 * gap:.1f} % below) |"]
    for case, c in fig["cases"].items():
        lines.append(f"| {ex.payload} axial load factor, case {case} | {c['payload_nz_max_g']:.2f} g "
                     f"({c['payload_if_tz_max_n'] / 1e3:.0f} kN at {ex.interface}) |")
    return "\n".join(lines) + "\n"


def run_example(name: str, out: Path, cache: Path | None) -> None:
    import subprocess
    import sys

    cmd = [sys.executable, "-m", "liftoff.workflows.cli", "run", str(EXAMPLES[name].folder / "scenario.toml"),
           "--out", str(out), "--no-snapshots", "--no-progress"] + (["--cache", str(cache)] if cache else [])
    subprocess.run(cmd, check=True)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("name", choices=sorted(EXAMPLES))
    ap.add_argument("--out", type=Path, help="an existing run of the example (default: run it now)")
    ap.add_argument("--cache", type=Path)
    args = ap.parse_args(argv)
    if args.out is None:
        args.out = Path(tempfile.mkdtemp(prefix=f"{args.name}-")) / "out"
        run_example(args.name, args.out, args.cache)
    fig = figures_of_run(args.name, args.out)
    from liftoff.core.records import write_text

    write_text(EXAMPLES[args.name].json, json.dumps(fig, indent=1) + "\n")
    print(render(args.name, fig))
    df = runpy.run_path(str(ROOT / "benchmarks" / "default_figures.py"), run_name="default_figures")
    for doc in df["DOCS"]:
        doc.write_text(df["apply_blocks"](doc.read_text(), {EXAMPLES[args.name].block: render(args.name, fig)}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
