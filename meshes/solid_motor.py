"""A solid rocket motor anywhere: an in-line solid stage or a strap-on booster
(:class:`SolidMotorParams`, built by meshes.vehicle.build_booster).

The Shuttle booster (meshes.vehicle.BoosterParams) takes its axis, radii and points from
the shared StackLayout; a solid motor gives its own: the axis at ``axis_xy``, the case's
outer ``case_radius``, the aft skirt's bottom (outer radius ``skirt_bottom_radius``, foot
ring ``skirt_foot_thickness``), hold-down points on the skirt's bottom (``holddown``, each
at z = 0: the motor stands on the pad) and points tied to a patch of the case wall facing
them (``points``: attach fittings of a strap-on, an interstage joint). The case, domes,
skirt, propellant (smeared on the case's inner wall) and the nozzle at
``<name>_gimbal`` are the booster's, walls solid or shell alike.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from liftoff.core.errors import InputError

from .vehicle import BoosterParams


@dataclass
class SolidMotorParams(BoosterParams):
    """BoosterParams (case, domes, skirt, masses, walls) placed by its own fields (SI)."""

    motor: str = "motor"                 # the component's name: groups <motor>_case, <motor>_skirt, ...
    axis_xy: tuple = (0.0, 0.0)
    case_radius: float = 1.855
    skirt_bottom_radius: float = 2.7
    skirt_foot_thickness: float = 0.5
    holddown: dict = field(default_factory=dict)   # {name: (x, y, 0)} on the skirt's foot ring
    points: dict = field(default_factory=dict)     # {name: (x, y, z)} tied to the case wall facing them

    @property
    def name(self) -> str:
        return self.motor

    @property
    def radius(self) -> float:
        return self.case_radius

    @property
    def axis(self) -> np.ndarray:
        return np.asarray(self.axis_xy, dtype=float).reshape(2)

    @property
    def skirt_radius(self) -> float:
        return self.skirt_bottom_radius

    @property
    def skirt_thickness(self) -> float:
        return self.skirt_foot_thickness

    def holddown_points(self) -> dict[str, np.ndarray]:
        return {n: np.asarray(p, dtype=float) for n, p in self.holddown.items()}

    def attach_points(self) -> dict[str, np.ndarray]:
        return {n: np.asarray(p, dtype=float) for n, p in self.points.items()}

    def _check_placement(self, o: str) -> None:
        for key in ("case_radius", "skirt_bottom_radius", "skirt_foot_thickness"):
            if not getattr(self, key) > 0:
                raise InputError(f"{o}.{key} must be > 0 m")
        if np.shape(self.axis_xy) != (2,) or not np.all(np.isfinite(self.axis)):
            raise InputError(f"{o}.axis_xy must be two finite numbers (m)")
        if not self.holddown and not self.points:
            raise InputError(f"{o}: no points (holddown or points): nothing would hold or join the motor")
        clash = sorted(set(self.holddown) & set(self.points) | {f"{self.motor}_gimbal"} & (set(self.holddown)
                                                                                            | set(self.points)))
        if clash:
            raise InputError(f"{o}: point name {clash[0]!r} given twice (holddown, points, <name>_gimbal)")
        r_foot = self.skirt_bottom_radius - 0.5 * self.skirt_foot_thickness
        slack = 0.5 * self.skirt_foot_thickness - self.holddown_patch_radius
        for n, p in self.holddown_points().items():
            if p.shape != (3,) or not np.all(np.isfinite(p)):
                raise InputError(f"{o}.holddown.{n} must be three finite numbers (m)")
            r = math.hypot(*(p[:2] - self.axis))
            if p[2] != 0.0 or abs(r - r_foot) > slack:
                raise InputError(f"{o}.holddown.{n}: {p.tolist()} is not on the skirt's foot ring (z = 0, "
                                 f"{r_foot:g} +/- {slack:g} m from the axis; it is {r:g} m)")
        for n, p in self.attach_points().items():
            if p.shape != (3,) or not np.all(np.isfinite(p)):
                raise InputError(f"{o}.points.{n} must be three finite numbers (m)")
            if math.hypot(*(p[:2] - self.axis)) < self.case_radius:
                raise InputError(f"{o}.points.{n}: {p.tolist()} is inside the case (radius {self.case_radius:g} m "
                                 "about axis_xy): a wall point lies on or outside the wall")
            if not self.case_bottom_z + self.attach_patch_half_width <= p[2] <= self.cyl_top_z - \
                    self.attach_patch_half_width:
                raise InputError(f"{o}.points.{n}: z = {p[2]:g} m is off the case's cylinder "
                                 f"({self.case_bottom_z:g} .. {self.cyl_top_z:g} m, less the patch half width)")
