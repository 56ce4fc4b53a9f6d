"""The default run with each booster's aft attach as the released joint (the default) and as
its three aft struts, pin-ended tube beams (issue 26: "the ET-SRB struts ... as beams").

The default joins each booster to the external tank at one aft point, midway between the
walls, with Tz Rx Ry released: the three aft struts lie in a plane across the axis and carry
Tx, Ty and the couple Rz only, rigidly. Here they are members: ``[model.vehicle.params]
srb_aft_attach = "struts"`` puts their end points on the tank's aft attach ring and the
booster's wall (meshes.layout.StackLayout.srb_aft_strut_points: the two sway braces at y =
+-1 m, 0.72 m long between the walls, the diagonal from the tank's upper end to the
booster's lower one), and three ``type = "strut"`` components per booster join them, each ``pinned = true``
(a two-force member: its end elements' bending released, as Nastran's pin flags,
liftoff.core.beam.release; reduction/strut.py). The struts'
sizes are illustrative, not the Shuttle's drawings: steel tubes of 0.2 m outer diameter,
20 mm wall (EA 2.3 GN), and half that wall as a second variant, to show how far the loads
depend on the struts' stiffness. Each strut's axial force is the force on it at one end
(``point@strut``: the lower strut's and the diagonal's at the tank, the upper strut's from the
force on the booster at its upper point, where it is the only strut), and the forces on the
booster at its two strut points sum to the aft attach's (the default's
``att_srb_<side>_aft`` row).

Variants (each a whole run of both named cases without the error estimate, stage cache
shared: the core's and the boosters' FE and CB stages are rebuilt, their patches moved):

* ``joint``: the default;
* ``struts``: the pin-ended struts, tube r_out 0.1 m, t 20 mm;
* ``struts_fine``: those struts, the boosters meshed 0.7 x as fine (0.42 m instead of the
  builder's 0.6 m: their new patches' convergence in the mesh, as docs/workflow.md's "mesh
  x0.7" row does for the default);
* ``struts_thin``: the same struts with a 10 mm wall (EA 1.2 GN);
* ``struts_beam``: the 20 mm struts, and the forward balls on the intertank's thrust beam
  (``srb_fwd_attach = "beam"``: an aluminium box 0.6 m x 1.0 m x 30 mm across the
  intertank, with a fitting out to each ball);
* ``all``: those, and the orbiter's attach bipods as pin-ended struts (``orbiter_attach =
  "bipods"``: the forward bipod's two struts splayed across the vehicle, each aft bipod's
  vertical and diagonal struts, tubes as the aft struts'), every attach as beams.

Writes docs/figures/struts.json, rendered into README.md by benchmarks/default_figures.py
(block ``aft-struts``).

    .venv/bin/python benchmarks/strut_compare.py [--cache DIR] [--json FILE] [--variants ...]
"""
from __future__ import annotations

import runpy
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
JSON = ROOT / "docs" / "figures" / "struts.json"
SIDES = ("left", "right")
TUBE = {"shape": "tube", "r_out": 0.1, "t": 0.02}
#: the intertank's thrust beam (span and fittings): an aluminium box, 1 m deep (illustrative)
BEAM = {"section": {"shape": "box", "b": 0.6, "h": 1.0, "t": 0.03}, "E": 72e9, "nu": 0.33, "rho": 2840.0}
#: variant -> the aft struts' tube section and the thrust beam (None: the default's joints)
VARIANTS = {"joint": {"struts": None, "beam": None, "bipods": None},
            "struts": {"struts": TUBE, "beam": None, "bipods": None},
            "struts_fine": {"struts": TUBE, "beam": None, "bipods": None, "booster_mesh": 0.42},
            "struts_thin": {"struts": dict(TUBE, t=0.01), "beam": None, "bipods": None},
            "struts_beam": {"struts": TUBE, "beam": BEAM, "bipods": None},
            "all": {"struts": TUBE, "beam": BEAM, "bipods": TUBE}}


def strut_recoveries(side: str) -> dict[str, str]:
    """{what: attach recovery spec} of one booster's aft struts: the forces on the booster at
    its two strut points (their sum is the aft attach's), and the lower and diagonal struts'
    own end forces at the tank (``point@strut``; the upper strut's is the force on the
    booster at its upper point, where it is the only strut)."""
    b, et = f"srb_{side}_aft", f"et_srb_{side}_aft"
    return {"booster_upper": f"{b}_upper@srb_{side}", "booster_lower": f"{b}_lower@srb_{side}",
            "strut_lower": f"{et}_lower@{b}_strut_lower", "strut_diagonal": f"{et}_upper@{b}_strut_diagonal"}


def _add_strut(model: dict, name: str, ends, **params) -> None:
    """A ``type = "strut"`` component ``name`` between the layout's points ``ends``."""
    model["component"][name] = {"type": "strut", "f_max": 120.0, "params": {"ends": list(ends), **params}}


def edit_for(name: str):
    """The edit of the default scenario's data for variant ``name``."""
    from liftoff.meshes.layout import StackLayout

    spec = VARIANTS[name]

    def edit(d):
        model = d["model"]
        params = model.setdefault("vehicle", {}).setdefault("params", {})
        if spec.get("booster_mesh"):          # (the right booster mirrors the left one)
            model["component"]["srb_left"]["mesh_size"] = spec["booster_mesh"]
        joints = list(model["joint"])
        if spec["struts"] is not None:
            params["srb_aft_attach"] = "struts"
            lay = StackLayout(srb_aft_attach="struts")
            joints = [j for j in joints if not (j["name"].startswith("att_srb") and j["name"].endswith("_aft"))]
            for side in SIDES:
                shared: dict[str, list[str]] = {}
                for strut, (a, b) in lay.srb_aft_struts(side).items():
                    _add_strut(model, strut, (a, b), section=dict(spec["struts"]), pinned=True)
                    shared.setdefault(a, ["core"]).append(strut)
                    shared.setdefault(b, [f"srb_{side}"]).append(strut)
                joints += [{"name": p, "components": comps} for p, comps in shared.items()]
            rec = d["recovery"]
            rec["attach"] = [a for a in rec["attach"] if not (a.startswith("att_srb") and a.endswith("_aft"))] + \
                [r for side in SIDES for r in strut_recoveries(side).values()]
        if spec["beam"] is not None:
            params["srb_fwd_attach"] = "beam"
            lay = StackLayout(srb_fwd_attach="beam")
            members = lay.srb_thrust_beam()
            for member, ends in members.items():
                _add_strut(model, member, ends, elements=2 if member.endswith("fitting") else 8,
                           **{k: (dict(v) if isinstance(v, dict) else v) for k, v in spec["beam"].items()})
            for j in joints:                  # the ball: the booster and the fitting, no longer the tank
                if j["name"] in ("att_srb_left_fwd", "att_srb_right_fwd"):
                    j["components"] = [f"srb_{j['name'].split('_')[2]}_thrust_fitting", j["components"][-1]]
            for wall in lay.srb_thrust_beam_points():
                joints.append({"name": wall, "components": ["core"] + [m for m, e in members.items() if wall in e]})
            d["recovery"]["attach"] = list(d["recovery"]["attach"]) + [BEAM_END]
        if spec["bipods"] is not None:
            params["orbiter_attach"] = "bipods"
            lay = StackLayout(orbiter_attach="bipods")
            struts = lay.orbiter_bipods()
            for strut, ends in struts.items():
                _add_strut(model, strut, ends, section=dict(spec["bipods"]), pinned=True)
            apexes = {e for _, e in struts.values()}
            joints = [j for j in joints if j["name"] not in apexes]
            joints += [{"name": a, "components": [k for k, (_, e) in struts.items() if e == a] + ["orbiter"]}
                       for a in sorted(apexes)]
            joints += [{"name": foot, "components": ["core", strut]} for strut, (foot, _) in struts.items()]
            d["recovery"]["attach"] = list(d["recovery"]["attach"]) + [f"{foot}@{strut}"
                                                                       for strut, (foot, _) in struts.items()]
        model["joint"] = joints
        return d

    return edit


#: the thrust beam's loads: the force and moment on its span at the left booster's wall point
BEAM_END = "et_srb_left_fwd@srb_thrust_beam"


def beam_figures(out) -> dict:
    """The thrust beam's span at its left end over both named cases: the peak of each of the
    six components of the force and moment on it there (N, N m; global axes: Tx along the
    beam, Tz the thrust's shear, Ry its bending)."""
    comps = ("Tx", "Ty", "Tz", "Rx", "Ry", "Rz")
    peaks: dict = {}
    for res, _ in out.results.values():
        f = np.asarray(res.recovered[f"attach_{BEAM_END.split('@')[0]}"])
        for i, c in enumerate(comps):
            peaks[c] = _larger(peaks.get(c), f[:, i])
    return peaks


def bipod_figures(out) -> dict:
    """Each orbiter attach strut's peak axial force (N, + tension) over both named cases,
    from the force on it at its foot (the tank's pull away from the orbiter's end: tension)."""
    from liftoff.meshes.layout import StackLayout

    lay = StackLayout(orbiter_attach="bipods")
    pts = {**lay.orbiter_bipod_feet(), **lay.orbiter_attach_points()}
    peaks: dict = {}
    for res, _ in out.results.values():
        for strut, (foot, apex) in lay.orbiter_bipods().items():
            axis = (pts[apex] - pts[foot]) / np.linalg.norm(pts[apex] - pts[foot])
            h = -np.asarray(res.recovered[f"attach_{foot}"])[:, :3] @ axis
            _axial_peaks(peaks, strut, h)
    return peaks


def _axial_peaks(peaks: dict, strut: str, axial: np.ndarray) -> None:
    """``peaks[strut]``'s largest tension and compression (N) with those of ``axial``."""
    q = peaks.setdefault(strut, {"tension_n": -np.inf, "compression_n": np.inf})
    q["tension_n"] = max(q["tension_n"], float(axial.max()))
    q["compression_n"] = min(q["compression_n"], float(axial.min()))


def _larger(prev, v: np.ndarray) -> float:
    """The value of larger magnitude: ``prev`` or the largest of ``v``."""
    x = float(v[int(np.argmax(np.abs(v)))])
    return x if prev is None or abs(x) > abs(prev) else prev


def aft_attach_figures(out, side: str = "left") -> dict:
    """The booster's aft attach over both named cases, as the default's released joint
    carries it: the peak Tx, Ty (N) and Rz (N m, about the joint's point) of the force on
    the booster there, and their static values at t0 (``"t0"``) (the joint's rows, or the
    struts' resultant on the booster, its moment taken about the joint's point); with
    struts also each strut's peak axial force (N, + tension)."""
    from liftoff.meshes.layout import StackLayout

    lay = StackLayout(srb_aft_attach="struts")
    p0 = StackLayout().srb_attach_points(side)[f"att_srb_{side}_aft"]
    peaks: dict = {}
    for res, _ in out.results.values():
        if f"attach_att_srb_{side}_aft" in res.recovered:           # the released joint
            f = np.asarray(res.recovered[f"attach_att_srb_{side}_aft"])
            for c, i in (("Tx", 0), ("Ty", 1), ("Rz", 5)):
                peaks[c] = _larger(peaks.get(c), f[:, i])
                peaks.setdefault("t0", {})[c] = float(f[0, i])     # the static state at t0 (the cases' same)
            continue
        pts = {**lay.srb_aft_strut_points(side)["core"], **lay.srb_aft_strut_points(side)["booster"]}
        b = f"srb_{side}_aft"
        axis = {k: pts[e] - pts[s] for k, (s, e) in lay.srb_aft_struts(side).items()}
        axis = {k: v / np.linalg.norm(v) for k, v in axis.items()}
        f = {k: np.asarray(res.recovered[f"attach_{spec.split('@')[0]}"]) for k, spec in strut_recoveries(side).items()}
        # tension positive: the pull of the rest of the vehicle on a strut's end away from its
        # other end, or the booster's pull towards the strut's tank end (the upper strut's)
        axial = {f"{b}_strut_upper": -f["booster_upper"][:, :3] @ axis[f"{b}_strut_upper"],
                 f"{b}_strut_lower": -f["strut_lower"][:, :3] @ axis[f"{b}_strut_lower"],
                 f"{b}_strut_diagonal": -f["strut_diagonal"][:, :3] @ axis[f"{b}_strut_diagonal"]}
        for k, h in axial.items():
            _axial_peaks(peaks.setdefault("struts", {}), k, h)
        force = f["booster_upper"][:, :3] + f["booster_lower"][:, :3]
        moment = sum(np.cross(pts[f"{b}_{tag}"] - p0, f[f"booster_{tag}"][:, :3])[:, 2]
                     for tag in ("upper", "lower"))                 # (the pinned ends pass no moment)
        for c, v in (("Tx", force[:, 0]), ("Ty", force[:, 1]), ("Rz", moment)):
            peaks[c] = _larger(peaks.get(c), v)
            peaks.setdefault("t0", {})[c] = float(v[0])
    return peaks


def variant_figures(name: str, cache: Path) -> dict:
    """Figures of the default run with the aft attach as ``name``."""
    fig = runpy.run_path(str(ROOT / "benchmarks" / "default_figures.py"), run_name="default_figures")
    out, wall_s = fig["timed_variant"](edit_for(name), cache)
    summary = fig["variant_summary"](out, wall_s, "srb_left")
    stack = next(iter(out.stacks.values()))
    times = {label.split(" (")[0]: s for label, s in out.stage_times if " (built)" in label}
    summary["core"] = {"fe_dofs": fig["_fe_dofs"](stack.components.get("core")), "cb_modes": stack.cbs["core"].n_modes,
                       "fe_s": times.get("fe core"), "cb_s": times.get("cb core")}
    summary["hardware"] = VARIANTS[name]
    summary["aft_attach"] = aft_attach_figures(out)
    if VARIANTS[name]["bipods"] is not None:
        summary["bipods"] = bipod_figures(out)
    if VARIANTS[name]["beam"] is not None:
        summary["thrust_beam"] = beam_figures(out)
    return summary


def main(argv=None) -> int:
    fig = runpy.run_path(str(ROOT / "benchmarks" / "default_figures.py"), run_name="default_figures")
    return fig["compare_main"](argv, __doc__, VARIANTS, variant_figures, JSON, "strut_compare")


if __name__ == "__main__":
    sys.exit(main())
