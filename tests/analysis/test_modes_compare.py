"""MAC and mode pairing (analysis/modes_compare.py) on a perturbed model with known pairs."""
import numpy as np
import pytest
import scipy.linalg as sla

from liftoff.analysis.modes_compare import MAC_PAIRED, mac, pair_modes
from liftoff.core.errors import InputError


def chain(k: np.ndarray, m: np.ndarray):
    """A fixed-free spring-mass chain: frequencies (Hz) and mass-normalised shapes."""
    n = m.size
    K = np.zeros((n, n))
    for i in range(n):
        K[i, i] += k[i]
        if i + 1 < n:
            K[i, i] += k[i + 1]
            K[i, i + 1] = K[i + 1, i] = -k[i + 1]
    lam, phi = sla.eigh(K, np.diag(m))
    return np.sqrt(lam) / (2 * np.pi), phi


def test_mac_is_one_for_the_same_shape_and_zero_for_orthogonal_ones():
    f, phi = chain(np.full(6, 1e4), np.full(6, 2.0))
    M = mac(phi, -3.0 * phi)                         # scale and sign do not matter
    np.testing.assert_allclose(np.diag(M), 1.0, rtol=1e-12)
    # uniform masses: the shapes are orthogonal in the plain dot product too
    assert np.abs(M - np.diag(np.diag(M))).max() < 1e-12
    with pytest.raises(InputError, match="same DOFs"):
        mac(phi, phi[:3])


def test_pairing_finds_the_known_pairs_of_a_perturbed_model():
    """Stiffen one spring by 3 %: every mode keeps its shape closely (MAC > 0.99) and its
    index; the pairing finds mode k -> mode k with the frequency change of the eigensolution.
    Then the old model's modes are shuffled: the pairing undoes the permutation."""
    n = 12
    k, m = np.linspace(2e4, 1e4, n), np.linspace(3.0, 1.0, n)
    f_old, phi_old = chain(k, m)
    k2 = k.copy()
    k2[4] *= 1.03
    f_new, phi_new = chain(k2, m)
    pairs = pair_modes(f_new, phi_new, f_old, phi_old)
    assert [p.old for p in pairs] == list(range(n))
    assert min(p.mac for p in pairs) > 0.99
    # the same change computed two ways: round-off of f (1e-16) over changes down to 4e-6
    np.testing.assert_allclose([p.change_pct for p in pairs], 100 * (f_new / f_old - 1), rtol=1e-8, atol=1e-12)
    perm = np.random.default_rng(3).permutation(n)
    shuffled = pair_modes(f_new, phi_new, f_old[perm], phi_old[:, perm])
    assert [perm[p.old] for p in shuffled] == list(range(n))


def test_a_changed_shape_is_unmatched_and_rigid_modes_are_left_out():
    f, phi = chain(np.full(5, 1e4), np.full(5, 1.0))
    f_new = np.r_[0.0, f]                                     # one rigid mode first
    phi_new = np.c_[np.ones(5), phi]
    phi_new[:, 3] = np.roll(phi_new[:, 3], 2)                 # mode 3 changes its shape
    pairs = pair_modes(f_new, phi_new, f, phi)
    assert [p.new for p in pairs] == [1, 2, 3, 4, 5]          # the rigid mode is not paired
    by = {p.new: p for p in pairs}
    assert by[3].old is None and by[3].mac < MAC_PAIRED and np.isnan(by[3].change_pct)
    assert [by[i].old for i in (1, 2, 4, 5)] == [0, 1, 3, 4]
