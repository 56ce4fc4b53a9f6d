"""Benchmark and comparison: the core stage with shell walls against the thickened solid.

Builds the core stage (meshes.vehicle.core_stage_params) three ways:

* ``solid``: the thickened tetrahedral wall (t = 0.15 m, density and E scaled, P1);
* ``shell``: the wall's mid-surface as an Al 2219 shell of the thickness that weighs the
  dry mass (6.8 mm, a bare skin: 12 I/t^3 = 1);
* ``shell-b``: the same shell with the solid's bending stiffness (12 I/t^3 = (0.15/t)^2),
  a like-for-like check of the shell element against the solid one on the real geometry;

and for each: DOFs, total mass, the free-free modes (SLEPc), the first beam-bending modes
found by their beam content (share of the displacement that is a rigid translation of the
cross-section, per axial slice), the first lobar/dome modes (dominant circumferential wave
number n of the radial displacement and where it lives), and the Craig-Bampton time for
the pipeline's boundary (the named points) and a fixed number of modes. The bare-skin
shell has hundreds of lobar modes below the first beam mode (87 below 5 Hz): its beam
modes are found by a shift-invert solve centred on the solid's first bending frequency.

Usage: .venv/bin/python benchmarks/bench_shells.py [--mesh-solid 0.9] [--mesh-shell 0.9 1.8]
       [--cb-modes 30] [--out out/bench_shells]
Writes <out>/bench_shells.json (atomically) and prints Markdown tables. Times in seconds
(wall clock; the machine is shared, see docs/fem.md).
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import liftoff  # noqa: F401 - before numpy: it picks the OpenBLAS kernels (liftoff/core/openblas.py)
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def beam_share(model, phi: np.ndarray) -> float:
    from liftoff.fem.modes import beam_content

    return beam_content(model, phi)


def wave_number(model, phi: np.ndarray, r_wall: float = 4.125) -> tuple[int, str]:
    """(dominant circumferential wave number of the radial displacement on the cylindrical
    wall, region holding most of |u|^2: 'lh2 cyl', 'lox cyl', 'skirt', 'domes'). Nodes
    within 0.1 m of the wall's mid-radius are on the wall (both faces of the solid)."""
    u = model.nodal_displacement(phi)
    x, y, z = model.nodes.T
    r = np.hypot(x, y)
    on_wall = np.abs(r - r_wall) < 0.1
    th = np.arctan2(y, x)
    ur = u[:, 0] * np.cos(th) + u[:, 1] * np.sin(th)
    amp = [abs(np.sum(ur[on_wall] * np.exp(1j * n * th[on_wall]))) for n in range(12)]
    return int(np.argmax(amp)), _region(model, np.sum(u ** 2, axis=1), on_wall)


def _region(model, e, on_wall) -> str:
    from liftoff.meshes.tank import tank_layout
    from liftoff.meshes.vehicle import core_stage_params

    lay = tank_layout(core_stage_params())
    z = model.nodes[:, 2]
    parts = {"lh2 cyl": on_wall & (z > lay[0].z_cyl_bottom) & (z < lay[0].z_cyl_top),
             "skirt": on_wall & (z >= lay[0].z_cyl_top) & (z <= lay[1].z_cyl_bottom),
             "lox cyl": on_wall & (z > lay[1].z_cyl_bottom) & (z < lay[1].z_cyl_top)}
    parts["domes"] = ~(parts["lh2 cyl"] | parts["skirt"] | parts["lox cyl"])
    share = {k: float(e[v].sum()) for k, v in parts.items()}
    return max(share, key=share.get)


def run_variant(kind: str, mesh_size: float, out: Path, cb_modes: int, ratio: float | None = None,
                degree: int = 1) -> dict:
    from liftoff.fem import build_model, eigenmodes, mass_properties, petsc_backend as pb
    from liftoff.meshes import build_tank
    from liftoff.meshes.vehicle import core_stage_params
    from liftoff.reduction.component import Component
    from liftoff.reduction.craig_bampton import craig_bampton
    from liftoff.workflows.pipeline import boundary_points
    from liftoff.core.labels import points_labels

    walls = "solid" if kind == "solid" else "shell"
    # like for like: the shells carry the solid's rigid attach patches (the default's attach
    # rings add no stiffness; bench_prestress.py runs the default's rings)
    p = core_stage_params(mesh_size=mesh_size, walls=walls, shell_bending_ratio=ratio or 1.0, attach="patch")
    t0 = time.perf_counter()
    geo = build_tank(p, out / f"{kind}_{mesh_size}")
    t1 = time.perf_counter()
    model = build_model(geo, degree=degree)
    t2 = time.perf_counter()
    modes = eigenmodes(model, n_modes=30)
    t3 = time.perf_counter()
    r_wall = p.radius - 0.5 * p.wall_thickness
    rec = {"kind": kind + ("-P2" if degree == 2 else ""), "mesh_size": mesh_size, "n_dof": model.n_dof, "mesh_s": t1 - t0, "build_s": t2 - t1,
           "eig30_s": t3 - t2, "mass": mass_properties(model).mass, "nominal_mass": geo.nominal_mass(),
           "thickness": geo.shells.get("core_wall"), "bending_ratio": ratio or 1.0,
           "freq": modes.freq_hz.tolist()}
    rec["modes"] = [{"f": float(modes.freq_hz[j]), "beam": beam_share(model, modes.shapes[:, j]),
                     "n_region": wave_number(model, modes.shapes[:, j], r_wall)} for j in range(6, len(modes))]
    if kind == "shell" and ratio is None:     # bare skin: beam modes among hundreds of lobar ones
        sigma = (2 * np.pi * 4.6) ** 2
        t4 = time.perf_counter()
        lam, Phi = pb.eigensolve(model.K, model.M, 60, sigma, what="core shell near 4.6 Hz")
        rec["near_4p6_s"] = time.perf_counter() - t4
        rec["near_4p6"] = [{"f": float(np.sqrt(max(lam[j], 0)) / (2 * np.pi)), "beam": beam_share(model, Phi[:, j])}
                           for j in range(lam.size)]
    comp = Component(name="core", **model.component_fields())
    t5 = time.perf_counter()
    cb = craig_bampton(comp, points_labels(boundary_points(comp)), n_modes=cb_modes)
    rec["cb_s"] = time.perf_counter() - t5
    rec["cb_modes"] = cb_modes
    rec["cb_fixed_interface_hz"] = (cb.fixed_omega / (2 * np.pi)).tolist()
    return rec


def _core_wall_area() -> float:
    """CAD area of the core's mid-surface (m^2): from the closed form of the capsules and
    the skirt (meshes.tank.wetted_area of each compartment's mid-surface capsule)."""
    from liftoff.meshes.tank import tank_layout, wetted_area
    from liftoff.meshes.vehicle import core_stage_params

    p = core_stage_params()
    lay, h = tank_layout(p), 0.5 * p.wall_thickness
    rm = p.radius - h
    area = sum(wetted_area(rm, c.a_bottom - h, c.a_top - h, c.cyl_length, 1e9) for c in lay)
    return area + sum(2 * np.pi * rm * (hi.z_cyl_bottom - lo.z_cyl_top) for lo, hi in zip(lay[:-1], lay[1:]))


def main(argv=None) -> None:
    from liftoff.core.records import write_text

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--mesh-solid", type=float, nargs="+", default=[0.9])
    ap.add_argument("--mesh-shell", type=float, nargs="+", default=[0.9, 1.8])
    ap.add_argument("--cb-modes", type=int, default=30)
    ap.add_argument("--solid-p2", action="store_true", help="also the solid with P2 tetrahedra (160k DOFs at 0.9 m)")
    ap.add_argument("--no-bare", action="store_true", help="skip the bare-skin shell")
    ap.add_argument("--out", default="out/bench_shells")
    a = ap.parse_args(argv)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    runs = [run_variant("solid", h, out, a.cb_modes) for h in a.mesh_solid]
    if a.solid_p2:
        runs += [run_variant("solid", h, out, a.cb_modes, degree=2) for h in a.mesh_solid]
    for h in a.mesh_shell:
        if not a.no_bare:
            runs.append(run_variant("shell", h, out, a.cb_modes))
        t = 26_500.0 / (2840.0 * _core_wall_area())
        runs.append(run_variant("shell-b", h, out, a.cb_modes, ratio=(0.15 / t) ** 2))
    write_text(out / "bench_shells.json", json.dumps({"runs": runs}, indent=1))
    print("| variant | mesh (m) | DOFs | mass (kg) | 30 modes (s) | CB (s) | 1st beam (Hz) |")
    print("|---|---|---|---|---|---|---|")
    for r in runs:
        cands = [m for m in r["modes"] if m["beam"] > 0.5] + [m for m in r.get("near_4p6", []) if m["beam"] > 0.5]
        fb = min((m["f"] for m in cands), default=float("nan"))
        print(f"| {r['kind']} | {r['mesh_size']} | {r['n_dof']} | {r['mass']:.1f} | {r['eig30_s']:.1f} | "
              f"{r['cb_s']:.1f} | {fb:.3f} |")


if __name__ == "__main__":
    main()
