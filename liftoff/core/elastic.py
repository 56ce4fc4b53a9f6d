"""The bounds of a linear isotropic elastic material: the one check of E, nu and rho, for
meshed materials (meshes.spec.Material) and the beams of reduction/ (Strut, BeamStick)."""
from __future__ import annotations

import math

from .errors import InputError


def check_elastic(who: str, E, nu, rho) -> tuple[float, float, float]:
    """(E, nu, rho) as floats, or an InputError naming ``who`` and the value: E > 0 (Pa),
    -1 < nu < 0.5, rho > 0 (kg/m^3), all finite numbers (not booleans)."""
    try:
        if any(isinstance(v, bool) for v in (E, nu, rho)):
            raise TypeError("a boolean")
        E, nu, rho = float(E), float(nu), float(rho)
    except (TypeError, ValueError):
        raise InputError(f"{who}: E, nu and rho must be numbers (got {E!r}, {nu!r}, {rho!r})") from None
    if not (math.isfinite(E) and E > 0):
        raise InputError(f"{who}: Young's modulus E = {E!r} Pa must be > 0")
    if not (math.isfinite(nu) and -1.0 < nu < 0.5):
        raise InputError(f"{who}: Poisson's ratio nu = {nu!r} must be in (-1, 0.5)")
    if not (math.isfinite(rho) and rho > 0):
        raise InputError(f"{who}: density rho = {rho!r} kg/m^3 must be > 0")
    return E, nu, rho
