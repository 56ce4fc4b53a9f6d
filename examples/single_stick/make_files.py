"""Write the single-stick example's geometry and payload files (run from anywhere):

* ``interstage.geo``, ``fairing.geo``: thin-walled barrels (gmsh built-in kernel, shell
  surfaces), each end's circle split into four 30-degree arcs, one around each joint
  azimuth (45, 135, 225, 315 deg), named curve groups for the joint ties, and gap arcs;
* ``pad.geo``: the launch table, a steel deck with four posts up to the hold-down points
  (OpenCASCADE kernel), its bottom face clamped;
* ``payload.pch``: the payload as a Nastran Craig-Bampton model (DMIG punch, inch-pound-
  second units, GRID cards in the basic frame): a 4 m beam of 4.85 t reduced to its
  adapter interface (grid 1) and its top (grid 2), as a payload provider delivers it.

The numbers are those of ``scenario.toml`` (STATIONS below); ``tests/workflows/
test_single_stick.py`` checks the committed files against this script's output.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
R = 1.83                            # m, tank outer radius (3.66 m diameter)
AZIMUTHS = (45.0, 135.0, 225.0, 315.0)
ARC = 15.0                          # deg, half-width of a joint arc
# stations (m): the scenario's tank_stage patches use the same numbers
STATIONS = {"interstage_low": 40.2, "interstage_up": 44.1, "fairing_low": 51.8, "fairing_top": 64.9,
            "holddown": 3.6, "payload_if": 53.43, "payload_top": 57.43}
PAYLOAD_MASS = 4850.0               # kg
FAIRING_RADIUS = 2.6                # m (5.2 m fairing)
PAYLOAD_TUBE = (0.6, 0.01)          # m: outer radius and wall of the payload's steel tube


def joint_points(prefix: str, z: float, r: float = R) -> dict[str, list[float]]:
    return {f"{prefix}_{k + 1}": [round(r * math.cos(math.radians(a)), 6), round(r * math.sin(math.radians(a)), 6), z]
            for k, a in enumerate(AZIMUTHS)}


def barrel_geo(title: str, wall: str, r: float, z0: float, z1: float, low: str, up: str | None, size: float) -> str:
    """A .geo barrel of radius r from z0 to z1: surface group ``wall``; curve groups
    ``<low>_<k>`` (bottom arcs) and ``<up>_<k>`` (top arcs, if ``up``)."""
    angles = sorted(a + s for a in AZIMUTHS for s in (-ARC, ARC))
    lines = [f"// {title} (written by make_files.py)", f"lc = {size};", f"Point(1) = {{0, 0, {z0}, lc}};"]
    for k, a in enumerate(angles):
        x, y = r * math.cos(math.radians(a)), r * math.sin(math.radians(a))
        lines.append(f"Point({10 + k}) = {{{x:.9f}, {y:.9f}, {z0}, lc}};")
    for k in range(8):
        lines.append(f"Circle({20 + k}) = {{{10 + k}, 1, {10 + (k + 1) % 8}}};")
    lines.append(f"out[] = Extrude {{0, 0, {z1 - z0:.9f}}} {{ Curve{{20:27}}; }};")
    lines.append("For i In {0:7}\n  surf[i] = out[4 * i + 1];\n  top[i] = out[4 * i];\nEndFor")
    lines.append(f'Physical Surface("{wall}") = {{surf[]}};')
    for k in range(4):              # arcs 0, 2, 4, 6 lie around the joint azimuths
        lines.append(f'Physical Curve("{low}_{k + 1}") = {{{20 + 2 * k}}};')
        if up:
            lines.append(f'Physical Curve("{up}_{k + 1}") = {{top[{2 * k}]}};')
    return "\n".join(lines) + "\n"


def pad_geo() -> str:
    z_top, post = STATIONS["holddown"], 0.6
    lines = ["// launch table: steel deck 10 x 10 x 2 m (top at z = -1), four 0.6 m posts up to the hold-down",
             "// points (written by make_files.py)", 'SetFactory("OpenCASCADE");',
             "Box(1) = {-5, -5, -3, 10, 10, 2};"]
    for k, (x, y, _) in enumerate(joint_points("p", z_top).values()):
        lines.append(f"Box({2 + k}) = {{{x - post / 2:.6f}, {y - post / 2:.6f}, -1, {post}, {post}, {z_top + 1}}};")
    lines.append("BooleanUnion(10) = { Volume{1}; Delete; }{ Volume{2:5}; Delete; };")
    lines.append('Physical Volume("pad_steel") = {10};')
    lines.append('Physical Surface("foundation") = Surface In BoundingBox{-5.01, -5.01, -3.01, 5.01, 5.01, -2.99};')
    for k, (x, y, _) in enumerate(joint_points("p", z_top).values()):
        lines.append(f'Physical Surface("pad_post_{k + 1}") = Surface In BoundingBox{{{x - 0.31:.6f}, {y - 0.31:.6f}, '
                     f'{z_top - 0.01}, {x + 0.31:.6f}, {y + 0.31:.6f}, {z_top + 0.01}}};')
    return "\n".join(lines) + "\n"


def payload_cb():
    """The payload's CB model: a steel-tube beam of PAYLOAD_MASS on its adapter, 9 nodes."""
    from liftoff.reduction import Component, craig_bampton
    from liftoff.reduction.models import chain_component

    z0, z1 = STATIONS["payload_if"], STATIONS["payload_top"]
    nodes = np.column_stack([np.zeros(9), np.zeros(9), np.linspace(z0, z1, 9)])
    r_o, t = PAYLOAD_TUBE
    A = math.pi * (r_o ** 2 - (r_o - t) ** 2)
    I = math.pi / 4 * (r_o ** 4 - (r_o - t) ** 4)
    rho = PAYLOAD_MASS / (A * (z1 - z0))                  # the payload's mass carried by its structure
    comp = chain_component("payload", nodes, 0, E=200e9, nu=0.3, A=A, Iy=I, Iz=I, J=2 * I, rho=rho)
    names = {"n0": "payload_if", "n8": "payload_top"}
    comp = Component(name="payload", K=comp.K, M=comp.M,
                     dof_labels=[f"{names.get(l.split(':')[0], l.split(':')[0])}:{l.split(':')[1]}"
                                 for l in comp.dof_labels],
                     label_dofs=comp.label_dofs, points=tuple(names.get(p, p) for p in comp.points),
                     point_coords=comp.point_coords)
    return craig_bampton(comp, [f"{p}:{c}" for p in ("payload_if", "payload_top")
                                for c in ("Tx", "Ty", "Tz", "Rx", "Ry", "Rz")], None, 200.0)


def main(out: Path = HERE) -> None:
    from liftoff.core.records import write_text
    from liftoff.reduction.nastran import write_dmig

    out = Path(out)
    s = STATIONS
    write_text(out / "interstage.geo", barrel_geo("interstage: aluminium barrel joining the stages", "interstage_wall",
                                                 R, s["interstage_low"], s["interstage_up"], "is_low", "is_up", 0.45))
    write_text(out / "fairing.geo", barrel_geo("payload fairing barrel (nose cone left out)", "fairing_wall",
                                              FAIRING_RADIUS, s["fairing_low"], s["fairing_top"], "fr", None, 0.6))
    write_text(out / "pad.geo", pad_geo())
    write_dmig(payload_cb(), out / "payload.pch", units="in-lbf-s", grid_ids={"payload_if": 1, "payload_top": 2})


if __name__ == "__main__":
    main()
