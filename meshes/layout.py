"""The global frame and the one shared source of interface positions for vehicle and pad.

Global frame (SI, m), shared by every vehicle component and the pad:
- origin on the core-stage axis at the level of the booster aft-skirt bottoms, which is
  also the level of the pad's hold-down post tops (z = 0);
- z up (along the vehicle axes);
- x along the booster-booster line: ``srb_left`` at x < 0, ``srb_right`` at x > 0;
- y from the core-stage axis towards the orbiter (the orbiter sits at y > 0).
The frame is right-handed. Interface points are defined here once, so that an attach
patch on the core stage and the matching one on a booster (same name) have the same
reference point, and pad post tops coincide with the booster hold-down points.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from liftoff.core.errors import InputError

from .spec import require_positive

SIDES = ("left", "right")
#: the attach options (StackLayout fields) and their values, each field's default first: how a
#: booster's aft attach is modelled, where its forward ball sits on the tank, how the orbiter's
#: attach joints are modelled
ATTACH_OPTIONS = {"srb_aft_attach": ("point", "struts"), "srb_fwd_attach": ("wall", "beam"),
                  "orbiter_attach": ("point", "bipods")}


@dataclass(frozen=True)
class StackLayout:
    """Shuttle-like stack arrangement (m). Defaults and sources: docs/meshes.md."""

    core_radius: float = 4.2          # external tank, 8.4 m diameter
    core_bottom_z: float = 9.2        # ET aft apex; top at ~56.1 m = stack height
    srb_radius: float = 1.855         # SRB 3.71 m diameter
    srb_axis_x: float = 6.36          # booster axes at x = -/+ this (ET-SRB gap ~0.3 m)
    srb_skirt_radius: float = 2.7     # outer radius of the aft-skirt bottom
    srb_skirt_thickness: float = 0.5  # skirt wall at the bottom (thickened, see docs)
    holddown_azimuths_deg: tuple = (45.0, 135.0, 225.0, 315.0)
    srb_fwd_attach_z: float = 40.5    # ET intertank / SRB forward skirt
    srb_aft_attach_z: float = 13.2    # ET aft ring / SRB aft attach ring
    srb_aft_attach: str = "point"     # "point": one aft attach point a booster (released joint);
                                      # "struts": the end points of its three aft struts (below)
    srb_aft_strut_y: float = 1.0      # "struts": the two sway braces at y = +- this (m)
    srb_fwd_attach: str = "wall"      # "wall": the forward ball's socket on the tank's wall (a
                                      # released joint); "beam": on the intertank's thrust beam (below)
    orbiter_radius: float = 2.6       # fuselage modelled as a 5.2 m cylinder
    orbiter_axis_y: float = 7.8       # orbiter axis at (0, this)
    orbiter_bottom_z: float = 8.0     # aft bulkhead (SSME gimbal plane)
    orbiter_fwd_attach_z: float = 37.0   # forward bipod
    orbiter_aft_attach_z: float = 13.2   # aft attach (left/right)
    orbiter_aft_attach_x: float = 1.5    # aft attach points at x = -/+ this
    orbiter_attach: str = "point"        # "point": the tank's side of each orbiter attach a point
                                         # (released joints); "bipods": the feet of its struts (below)
    orbiter_fwd_bipod_x: float = 1.0     # "bipods": the forward bipod's feet at x = +- this (m)
    orbiter_aft_bipod_dz: float = 1.5    # "bipods": each aft diagonal's foot this far above (m)

    def check(self) -> None:
        require_positive("StackLayout", **{k: getattr(self, k) for k in (
            "core_radius", "srb_radius", "srb_axis_x", "srb_skirt_radius", "srb_skirt_thickness",
            "orbiter_radius", "orbiter_axis_y", "orbiter_aft_attach_x")})
        if self.srb_axis_x <= self.core_radius + self.srb_radius:
            raise InputError("StackLayout.srb_axis_x: boosters overlap the core stage")
        if self.orbiter_axis_y <= self.core_radius + self.orbiter_radius:
            raise InputError("StackLayout.orbiter_axis_y: orbiter overlaps the core stage")
        if self.srb_skirt_radius - self.srb_skirt_thickness <= 0:
            raise InputError("StackLayout.srb_skirt_thickness must be < srb_skirt_radius")
        if len(self.holddown_azimuths_deg) < 1:
            raise InputError("StackLayout.holddown_azimuths_deg is empty")
        for k, allowed in ATTACH_OPTIONS.items():
            if getattr(self, k) not in allowed:
                raise InputError(f"StackLayout.{k} must be one of {', '.join(map(repr, allowed))} "
                                 f"(got {getattr(self, k)!r})")
        if self.orbiter_attach == "bipods":             # (the feet lie on the tank's wall)
            reach = 0.8 * self.core_radius
            for k, v, hi in (("orbiter_fwd_bipod_x", self.orbiter_fwd_bipod_x, reach),
                             ("orbiter_aft_attach_x", self.orbiter_aft_attach_x, reach),
                             ("orbiter_aft_bipod_dz", self.orbiter_aft_bipod_dz, 5.0)):
                if isinstance(v, bool) or not np.isfinite(v) or not 0 < v < hi:
                    raise InputError(f"StackLayout.{k} = {v!r} m must be in (0, {hi:g}) m")
        if self.srb_aft_attach == "struts":
            a = self.srb_aft_strut_y
            hi = 0.8 * min(self.srb_radius, self.core_radius)
            if isinstance(a, bool) or not np.isfinite(a) or not 0 < a < hi:
                raise InputError(f"StackLayout.srb_aft_strut_y = {a!r} m: the sway braces' offset must be in "
                                 f"(0, {hi:g}) m (0.8 x the booster's or the tank's radius)")

    def srb_axis(self, side: str) -> np.ndarray:
        if side not in SIDES:
            raise InputError(f"booster side must be one of {SIDES} (got {side!r})")
        return np.array([-self.srb_axis_x if side == "left" else self.srb_axis_x, 0.0])

    @property
    def holddown_radius(self) -> float:
        """Radius of the hold-down points about the booster axis: mid-wall of the skirt bottom."""
        return self.srb_skirt_radius - 0.5 * self.srb_skirt_thickness

    def holddown_points(self, side: str) -> dict[str, np.ndarray]:
        """``{"srb_<side>_hd_<k>": (x, y, 0)}``, k = 1.. in the order of ``holddown_azimuths_deg``
        about the left booster's axis; the right booster's are their mirror images in the plane
        x = 0 (azimuth 180 - a), so that hold-down k of one booster is the mirror of hold-down k
        of the other (a booster mirrored from the other, liftoff.reduction.mirror, then names its
        points as the pad's posts under it)."""
        ax, r = self.srb_axis(side), self.holddown_radius
        out = {}
        for k, a in enumerate(self.holddown_azimuths_deg):
            a = math.radians(a if side == "left" else 180.0 - a)
            out[f"srb_{side}_hd_{k + 1}"] = np.array([ax[0] + r * math.cos(a), ax[1] + r * math.sin(a), 0.0])
        return out

    def srb_attach_points(self, side: str) -> dict[str, np.ndarray]:
        """Core-booster attach reference points, midway between the two outer walls: the
        forward one and, unless the aft attach is struts (:meth:`srb_aft_strut_points`), the
        aft one."""
        sgn = -1.0 if side == "left" else 1.0
        xm = sgn * 0.5 * (self.core_radius + self.srb_axis_x - self.srb_radius)
        self.srb_axis(side)
        out = {f"att_srb_{side}_fwd": np.array([xm, 0.0, self.srb_fwd_attach_z])}
        if self.srb_aft_attach == "point":
            out[f"att_srb_{side}_aft"] = np.array([xm, 0.0, self.srb_aft_attach_z])
        return out

    def srb_aft_strut_points(self, side: str) -> dict[str, dict[str, np.ndarray]]:
        """With ``srb_aft_attach = "struts"``: the end points of a booster's three aft struts,
        {"core": {...}, "booster": {...}}, on each wall's outer surface at the aft attach
        height: ``et_srb_<side>_aft_upper`` / ``_lower`` on the core at y = +- srb_aft_strut_y
        (upper: towards the orbiter), ``srb_<side>_aft_upper`` / ``_lower`` on the booster at
        the same y (empty with ``"point"``). The struts: :meth:`srb_aft_struts`."""
        if self.srb_aft_attach != "struts":
            return {"core": {}, "booster": {}}
        sgn = -1.0 if side == "left" else 1.0
        ax = self.srb_axis(side)
        z, a = self.srb_aft_attach_z, self.srb_aft_strut_y
        out: dict[str, dict[str, np.ndarray]] = {"core": {}, "booster": {}}
        for tag, y in (("upper", a), ("lower", -a)):
            out["core"][f"et_srb_{side}_aft_{tag}"] = np.array([sgn * math.sqrt(self.core_radius ** 2 - y * y), y, z])
            out["booster"][f"srb_{side}_aft_{tag}"] = np.array([ax[0] - sgn * math.sqrt(self.srb_radius ** 2 - y * y),
                                                                y, z])
        return out

    def srb_aft_struts(self, side: str) -> dict[str, tuple[str, str]]:
        """With ``srb_aft_attach = "struts"``: a booster's three aft struts in the plane
        across the axis at the aft attach height, {strut: (core end, booster end)}: the upper
        and lower sway braces (across the gap at y = +- srb_aft_strut_y) and the diagonal from
        the core's upper end to the booster's lower end; pin-ended, they carry Tx, Ty and the
        couple Rz, as the released aft joint does (public: "two lateral sway braces and a
        diagonal attachment"; their layout here is this model's reading, not a drawing)."""
        if self.srb_aft_attach != "struts":
            return {}
        et, b = f"et_srb_{side}_aft", f"srb_{side}_aft"
        return {f"{b}_strut_upper": (f"{et}_upper", f"{b}_upper"), f"{b}_strut_lower": (f"{et}_lower", f"{b}_lower"),
                f"{b}_strut_diagonal": (f"{et}_upper", f"{b}_lower")}

    def srb_thrust_beam_points(self) -> dict[str, np.ndarray]:
        """With ``srb_fwd_attach = "beam"``: where the intertank's thrust beam meets the tank's
        wall, ``et_srb_<side>_fwd`` (on the wall, at the forward attach height, on the x axis;
        empty with ``"wall"``). The beam: :meth:`srb_thrust_beam`."""
        if self.srb_fwd_attach != "beam":
            return {}
        return {f"et_srb_{side}_fwd": np.array([(-1.0 if side == "left" else 1.0) * self.core_radius, 0.0,
                                                self.srb_fwd_attach_z]) for side in SIDES}

    def srb_thrust_beam(self) -> dict[str, tuple[str, str]]:
        """With ``srb_fwd_attach = "beam"``: the intertank's thrust beam, {member: (end,
        end)}: its span across the intertank between the two wall points
        (``srb_thrust_beam``) and at each end a fitting from the booster's forward ball
        (``srb_<side>_thrust_fitting``, from ``att_srb_<side>_fwd``, midway between the walls,
        to ``et_srb_<side>_fwd``). The booster's forward attach (the ball) is then a joint of
        the booster and the fitting, not of the tank; the beam's span and fittings are welded
        to the tank where they meet its wall (public: the SRB forward attach's socket is on the
        intertank's SRB beam, which spans the intertank between the two boosters' fittings)."""
        if self.srb_fwd_attach != "beam":
            return {}
        return {"srb_left_thrust_fitting": ("att_srb_left_fwd", "et_srb_left_fwd"),
                "srb_thrust_beam": ("et_srb_left_fwd", "et_srb_right_fwd"),
                "srb_right_thrust_fitting": ("att_srb_right_fwd", "et_srb_right_fwd")}

    def srb_core_points(self, side: str) -> dict[str, np.ndarray]:
        """The core's points for booster ``side``: its attach points (the forward one unless
        on the thrust beam, the aft one unless struts), the aft struts' tank ends and the
        thrust beam's wall point."""
        out = {n: x for n, x in self.srb_attach_points(side).items()
               if not (n.endswith("_fwd") and self.srb_fwd_attach == "beam")}
        out.update(self.srb_aft_strut_points(side)["core"])
        out.update({n: x for n, x in self.srb_thrust_beam_points().items() if f"_{side}_" in n})
        return out

    def srb_booster_points(self, side: str) -> dict[str, np.ndarray]:
        """Booster ``side``'s points towards the tank: its attach points and its aft struts'
        ends."""
        return {**self.srb_attach_points(side), **self.srb_aft_strut_points(side)["booster"]}

    def orbiter_bipod_feet(self) -> dict[str, np.ndarray]:
        """With ``orbiter_attach = "bipods"``: the feet of the orbiter's attach struts on the
        tank's wall (empty with ``"point"``): the forward bipod's ``et_orb_fwd_left`` /
        ``_right`` at x = -+orbiter_fwd_bipod_x, the forward attach height; each aft bipod's
        ``et_orb_aft_<side>_vertical`` at its attach point's x and height and
        ``et_orb_aft_<side>_diagonal`` orbiter_aft_bipod_dz above it."""
        if self.orbiter_attach != "bipods":
            return {}
        r = self.core_radius

        def foot(x, z):
            return np.array([x, math.sqrt(r * r - x * x), z])

        xf, xa, dz = self.orbiter_fwd_bipod_x, self.orbiter_aft_attach_x, self.orbiter_aft_bipod_dz
        zf, za = self.orbiter_fwd_attach_z, self.orbiter_aft_attach_z
        return {"et_orb_fwd_left": foot(-xf, zf), "et_orb_fwd_right": foot(xf, zf),
                "et_orb_aft_left_vertical": foot(-xa, za), "et_orb_aft_left_diagonal": foot(-xa, za + dz),
                "et_orb_aft_right_vertical": foot(xa, za), "et_orb_aft_right_diagonal": foot(xa, za + dz)}

    def orbiter_bipods(self) -> dict[str, tuple[str, str]]:
        """With ``orbiter_attach = "bipods"``: the orbiter's six attach struts, {strut: (foot
        on the tank, the orbiter's attach point)}, two a bipod meeting at the orbiter's
        attach point (its fitting, a ball): the forward pair splayed across the vehicle
        (forces in the x-y plane), each aft pair a vertical strut across the gap and a
        diagonal from above, in the plane of the axis and the orbiter's offset (forces in
        y-z): pin-ended, they carry what the default's released joints carry. Their layout
        is this model's reading of the hardware (public: "one forward bipod, two aft
        attachments of a vertical and a diagonal strut"), not a drawing."""
        if self.orbiter_attach != "bipods":
            return {}
        return {"orbiter_fwd_bipod_left": ("et_orb_fwd_left", "att_orb_fwd"),
                "orbiter_fwd_bipod_right": ("et_orb_fwd_right", "att_orb_fwd"),
                **{f"orbiter_aft_{side}_{k}": (f"et_orb_aft_{side}_{k}", f"att_orb_aft_{side}")
                   for side in SIDES for k in ("vertical", "diagonal")}}

    def orbiter_core_points(self) -> dict[str, np.ndarray]:
        """The core's points for the orbiter: its attach points, or the bipods' feet."""
        return self.orbiter_bipod_feet() if self.orbiter_attach == "bipods" else self.orbiter_attach_points()

    def option_point_names(self) -> set[str]:
        """The names of the points the attach options place or move (either value of each:
        the attach points, the aft struts' ends, the thrust beam's wall points, the bipods'
        feet), whatever this layout's options, without their geometry (an option not set may
        have parameters that place nothing)."""
        every = replace(self, srb_aft_attach="struts", srb_fwd_attach="beam", orbiter_attach="bipods")
        members = [*every.srb_thrust_beam().values(), *every.orbiter_bipods().values(),
                   *(ends for s in SIDES for ends in every.srb_aft_struts(s).values())]
        attach = {n for s in SIDES for n in replace(self, srb_aft_attach="point").srb_attach_points(s)}
        return attach | set(self.orbiter_attach_points()) | {n for ends in members for n in ends}

    def named_points(self) -> dict[str, np.ndarray]:
        """Every named point of the layout (attach points and aft strut ends of both boosters,
        the thrust beam's wall points, the orbiter's attach points and bipod feet, the hold-down
        points), m."""
        out: dict[str, np.ndarray] = {}
        for side in SIDES:
            out.update(self.srb_attach_points(side))
            for pts in self.srb_aft_strut_points(side).values():
                out.update(pts)
            out.update(self.holddown_points(side))
        out.update(self.srb_thrust_beam_points())
        out.update(self.orbiter_attach_points())
        out.update(self.orbiter_bipod_feet())
        return out

    def orbiter_attach_points(self) -> dict[str, np.ndarray]:
        """Core-orbiter attach reference points, midway between the two outer walls."""
        ym = 0.5 * (self.core_radius + self.orbiter_axis_y - self.orbiter_radius)
        xa = self.orbiter_aft_attach_x
        return {"att_orb_fwd": np.array([0.0, ym, self.orbiter_fwd_attach_z]),
                "att_orb_aft_left": np.array([-xa, ym, self.orbiter_aft_attach_z]),
                "att_orb_aft_right": np.array([xa, ym, self.orbiter_aft_attach_z])}
