"""Released joint DOFs (reduction.assembly ``released``; ``[[model.joint]] release``).

Reference: two uniform Euler-Bernoulli beams of length L, collinear, joined end to end at
a hinge that releases both bending rotations (Rx, Ry) and keeps the translations, axial
force and torque. By symmetry about the hinge each bending mode of the pair is either
symmetric (the hinge carries neither moment nor shear: each half is a free-free beam of
length L, beta L = 4.730041, 7.853205) or antisymmetric (the hinge does not move and
carries no moment: each half is a pinned-free beam of length L, beta L = 3.926602,
7.068583; Blevins, Formulas for Natural Frequency and Mode Shape, 1979, table 8-1),
f = (beta L)^2 / (2 pi L^2) sqrt(E I / m'), each in both bending planes. The hinge adds
one zero-frequency mechanism per released rotation to the six rigid-body modes; welded,
the pair is one free-free beam of length 2 L. The axial and torsion modes are the welded
bar's either way.

Tolerance: both CB models keep every fixed-interface mode, so the assembly is the FE
model exactly; 80 cubic elements per half converge as (h/lambda)^4: the four bending
frequencies' errors are 1.5e-8 to 4.4e-8 here, the two planes' round-off apart by 1.2e-7
(required 1e-6); the linear axial elements' O(h^2) error 1.6e-5 (required 1e-4). A zero
frequency is round-off of the dense eigensolution (of order eps lambda_max, lambda_max
the finest element's): 2e-4 to 7e-3 Hz here, required below 1e-2 of the first bending
frequency (31 Hz), far below the first elastic one (21.6 Hz).
"""
from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla

from liftoff.core.beam import tube
from liftoff.core.errors import InputError
from liftoff.core.labels import point_labels
from liftoff.reduction import assemble, craig_bampton, system_modes
from liftoff.reduction.assembly import released_label
from liftoff.reduction.beam_stick import BeamStick, beam_stick_component

L, R, T, E, NU, RHO = 20.0, 1.0, 0.01, 70e9, 0.33, 2800.0
FREE_FREE = (4.730040745, 7.853204624)
PINNED_FREE = (3.926602312, 7.068582745)
HINGE = [("upper", "hinge:Rx"), ("upper", "hinge:Ry")]


def _half(name: str, z0: float, ends: dict):
    p = BeamStick(name=name, stations=(z0, z0 + L), radius=(R,), thickness=(T,), E=E, nu=NU, rho=RHO,
                  shear=False, points=ends, element_length=0.25)
    comp, _ = beam_stick_component(p)
    return craig_bampton(comp, point_labels("hinge"), n_modes=comp.n_dof - 6)


@pytest.fixture(scope="module")
def halves():
    return _half("lower", 0.0, {"hinge": L}), _half("upper", L, {"hinge": L})


def _hz(asm) -> np.ndarray:
    lam = sla.eigh(asm.K, asm.M, eigvals_only=True)
    return np.sqrt(np.abs(lam)) / (2 * np.pi)


def _bending(beta_l, length):
    s = tube(R, T, NU)
    return np.array([b ** 2 / (2 * np.pi * length ** 2) * np.sqrt(E * s.Iy / (RHO * s.A)) for b in beta_l])


def test_hinge_gives_free_free_and_pinned_free_halves(halves):
    f = _hz(assemble(halves, "pair", HINGE))
    f_rigid = _hz(assemble(halves, "pair"))
    scale = _bending(FREE_FREE, L)[0]
    assert np.all(f[:8] < 1e-2 * scale) and f[8] > 0.5 * scale          # six rigid modes + two mechanisms
    assert np.all(f_rigid[:6] < 1e-2 * scale) and f_rigid[6] > 0.1 * scale
    for ref in np.concatenate([_bending(FREE_FREE, L), _bending(PINNED_FREE, L)]):
        close = np.isclose(f, ref, rtol=1e-6)
        assert close.sum() == 2, (ref, f[np.argmin(np.abs(f - ref))])     # both bending planes
    welded = _bending(FREE_FREE, 2 * L)[0]                                # no release: one beam of 2 L
    assert np.isclose(f_rigid, welded, rtol=1e-6).sum() == 2
    axial = np.sqrt(E / RHO) / (4 * L)
    assert np.isclose(f, axial, rtol=1e-4).sum() == 1 and np.isclose(f_rigid, axial, rtol=1e-4).sum() == 1


def test_released_dof_is_the_component_s_own(halves):
    asm = assemble(halves, "pair", HINGE)
    assert released_label("hinge:Rx", "upper") == "hinge@upper:Rx"
    assert "hinge:Rx" in asm.boundary_labels and "hinge@upper:Rx" in asm.boundary_labels
    assert "hinge@upper:Tx" not in asm.boundary_labels                   # translations still shared
    assert np.array_equal(asm.point_coord("hinge@upper"), asm.point_coord("hinge"))
    lower, upper = (asm.boundary_labels[i] for i in (asm.boundary_index["lower"][3], asm.boundary_index["upper"][3]))
    assert (lower, upper) == ("hinge:Rx", "hinge@upper:Rx")
    assert asm.n_dof == assemble(halves, "pair").n_dof + 2
    for comp in ("lower", "upper"):                                      # a released direction joins no one
        assert asm.released_apart(comp, "hinge:Rx") and asm.released_apart(comp, "hinge:Ry")
        assert not asm.released_apart(comp, "hinge:Tx") and not asm.released_apart(comp, "hinge:Rz")
        assert not assemble(halves, "pair").released_apart(comp, "hinge:Rx")


def test_a_mechanism_is_refused_by_the_system_modes(halves):
    with pytest.raises(InputError, match="more than six zero-frequency modes"):
        system_modes(assemble(halves, "pair", HINGE))


@pytest.mark.parametrize("released, message", [
    ([("middle", "hinge:Rx")], "no such component"),
    ([("upper", "top:Rx")], "not one of its boundary DOFs"),
])
def test_a_bad_release_names_the_culprit(halves, released, message):
    with pytest.raises(InputError, match=message):
        assemble(halves, "pair", released)
