"""``type = "beam"`` (reduction.beam_stick): a component as a stick of beams.

References, closed forms of the uniform free-free beam of length L (Blevins, Formulas for
Natural Frequency and Mode Shape, 1979, table 8-1 and 8-16): bending f_i = (beta_i L)^2 /
(2 pi L^2) sqrt(E I / m'), beta L = 4.730041, 7.853205, 10.995608; axial f = c / (2 L),
c = sqrt(E / rho); torsion f = sqrt(G J / (rho J_p)) / (2 L) with J_p = J for a tube.
Tolerance: 80 Euler-Bernoulli elements with consistent mass converge as (h/lambda)^4:
the third bending mode's error is below 1e-7 here, required 1e-6; the linear axial and
torsion elements as (h/lambda)^2: (pi h / L)^2 / 24 = 6.4e-5 for the first, required 1e-4.

Mass: the translational rigid-body mass of M is the line densities times the lengths, the
lumped masses and the links' mass (LINK's line density over each link's length): sums of a
few products, 1e-12."""
from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla

from liftoff.core.beam import tube
from liftoff.core.errors import InputError
from liftoff.reduction.beam_stick import LINK, BeamStick, beam_stick_component

L, R, T, E, NU, RHO = 40.0, 1.0, 0.01, 70e9, 0.33, 2800.0
BETA_L = (4.730040745, 7.853204624, 10.995607838)


def _frequencies(comp) -> np.ndarray:
    w = sla.eigh(comp.K.toarray(), comp.M.toarray(), eigvals_only=True)
    return np.sqrt(np.abs(w)) / (2 * np.pi)


def _first_bending(f: np.ndarray) -> float:
    """The lowest elastic frequency that comes twice (bending in two planes of a tube)."""
    return next(float(f[i]) for i in range(6, f.size - 1) if np.isclose(f[i], f[i + 1], rtol=1e-8))


def test_free_free_uniform_stick_against_closed_forms():
    p = BeamStick(name="b", stations=(0.0, L), radius=(R,), thickness=(T,), E=E, nu=NU, rho=RHO, shear=False,
                  points={"bottom": 0.0, "top": L}, element_length=0.5)
    comp, thermal = beam_stick_component(p)
    assert thermal == {} and comp.points[0] == "bottom" and comp.points[-1] == "top"
    f = _frequencies(comp)
    s = tube(R, T, NU)
    bend = [bl ** 2 / (2 * np.pi * L ** 2) * np.sqrt(E * s.Iy / (RHO * s.A)) for bl in BETA_L]
    axial = np.sqrt(E / RHO) / (2 * L)
    torsion = np.sqrt(E / (2 * (1 + NU)) / RHO) / (2 * L)
    # six rigid-body modes: zero to round-off, sqrt(eps lambda_max) / 2 pi = 2.0e-3 Hz here (measured
    # 3e-4 to 1.1e-3 Hz; the first elastic mode is at 7.8 Hz)
    assert np.all(np.abs(f[:6]) < 10 * np.sqrt(np.finfo(float).eps) * f[-1])
    for ref, tol in ((bend[0], 1e-6), (bend[1], 1e-6), (bend[2], 1e-6), (axial, 1e-4), (torsion, 1e-4)):
        k = int(np.argmin(np.abs(f - ref)))
        assert f[k] == pytest.approx(ref, rel=tol), ref
    assert np.sum(np.isclose(f, bend[0], rtol=1e-6)) == 2                      # two planes, one frequency


def test_timoshenko_is_softer_and_tends_to_euler_bernoulli():
    """Shear and rotary inertia lower each frequency, less for a slender stick: the first
    bending of L/R = 200 within 0.2 % of Euler-Bernoulli (the correction goes as (R/L)^2:
    2.4 % at L/R = 40 for a thin tube, shear coefficient 0.53), of L/R = 4 more than 10 % below."""
    for length, lo, hi in ((200.0, 0.998, 1.0), (4.0, 0.0, 0.9)):
        kw = dict(name="b", stations=(0.0, length), radius=(R,), thickness=(T,), points={"a": 0.0},
                  element_length=length / 40)
        eb = _first_bending(_frequencies(beam_stick_component(BeamStick(shear=False, **kw))[0]))
        ti = _first_bending(_frequencies(beam_stick_component(BeamStick(shear=True, **kw))[0]))
        assert lo < ti / eb < hi, (length, ti / eb)


def test_mass_of_segments_lumped_masses_and_links():
    p = BeamStick(name="s", stations=(0.0, 2.0, 40.0), radius=(1.83,), thickness=(0.01,),
                  mass_per_length=(3000.0, 10000.0), points={"mount": 0.0, "hd": [1.3, 0.0, 2.0], "top": 40.0},
                  masses={"top": (5000.0, 8000.0, 8000.0, 3000.0)})
    comp, _ = beam_stick_component(p)
    u = np.zeros(comp.n_dof)
    u[2::6] = 1.0                                   # a rigid translation along z
    link = LINK["mass_per_length"] * 1.3
    assert u @ comp.M @ u == pytest.approx(3000.0 * 2 + 10000.0 * 38 + 5000.0 + link, rel=1e-12)
    assert p.mass() == pytest.approx(3000.0 * 2 + 10000.0 * 38 + 5000.0, rel=1e-12)
    assert comp.point_coords[comp.points.index("hd")].tolist() == [1.3, 0.0, 2.0]


@pytest.mark.parametrize("change, message", [
    (dict(stations=(0.0, 0.0)), "stations: at least two z (m), strictly increasing"),
    (dict(radius=(1.0, 1.0, 1.0)), "radius: one value or one per segment (1), got 3"),
    (dict(thickness=(2.0,)), "thickness: a wall thicker than its radius"),
    (dict(points={}), "points: none"),
    (dict(points={"p": 50.0}), "points.p: z = 50 m is off the stick"),
    (dict(points={"p": [1.0, 2.0]}), "points.p: a z (on the axis) or [x, y, z]"),
    (dict(masses={"q": (1.0, 0.0, 0.0, 0.0)}), "masses.q: not one of the points"),
    (dict(masses={"p": (0.0, 0.0, 0.0, 0.0)}), "masses.p: [kg > 0"),
    (dict(nu=0.5), "BeamStick(b): Poisson's ratio nu = 0.5 must be in (-1, 0.5)"),
    (dict(E=0.0), "BeamStick(b): Young's modulus E = 0.0 Pa must be > 0"),
    (dict(rho=True), "BeamStick(b): E, nu and rho must be numbers"),
    (dict(element_length=-1.0), "BeamStick(b).element_length must be > 0 m"),
])
def test_bad_sticks_fail_in_one_line(change, message):
    kw = dict(name="b", stations=(0.0, 10.0), radius=(1.0,), thickness=(0.01,), points={"p": 5.0})
    with pytest.raises(InputError) as exc:
        beam_stick_component(BeamStick(**{**kw, **change}))
    assert message in str(exc.value) and "\n" not in str(exc.value)
