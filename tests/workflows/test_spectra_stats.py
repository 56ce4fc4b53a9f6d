"""Loads post-processing against independent references: the SRS against pyyeti.srs and the
closed-form steady-state transmissibility, PSD against Parseval, FFT amplitude of a sine,
the P99/90 k-factor against published tables and its coverage on normal samples, the order
statistic against pyyeti and binomial coverage, streaming statistics against batch ones."""
import math

import numpy as np
import pytest

from liftoff.analysis.spectra import LOWPASS_ORDER, fft_amplitude, lowpass, psd, srs
from liftoff.analysis.stats import Largest, Running, k_factor, order_rank


def test_srs_equals_pyyeti_on_the_same_input():
    """Both take the base acceleration as linear between samples (pyyeti's Smallwood
    ramp-invariant filter, here the transient's exact step coefficients turned into a
    filter), so with pyyeti's resampling off they agree to round-off over 6000 steps of
    the recursion: rtol 1e-9 (measured 2e-13). With pyyeti's default band-limited
    resampling they agree to 1e-3 on a smooth (band-limited) signal below sr/12."""
    from pyyeti import srs as ysrs

    h = 1 / 550.0
    t = np.arange(6000) * h
    rng = np.random.default_rng(3)
    sig = np.column_stack([np.sin(2 * np.pi * 7.3 * t) * np.exp(-0.5 * t), rng.standard_normal(t.size),
                           np.where(t < 1.0, t, 0.0)])
    freq = np.geomspace(0.5, 50.0, 45)
    for q in (5.0, 10.0, 25.0):
        ours = srs(sig, h, freq, q)
        ref = ysrs.srs(sig, 1 / h, freq, q, rolloff=None)
        np.testing.assert_allclose(ours, ref, rtol=1e-9, atol=1e-12 * np.abs(ref).max())
    smooth = sig[:, :1]
    low = freq[freq < 550.0 / 12]
    np.testing.assert_allclose(srs(smooth, h, low, 10.0), ysrs.srs(smooth, 1 / h, low, 10.0), rtol=1e-3)


def test_srs_columns_march_together_as_each_alone_and_as_lfilter():
    """The compiled peaks advance every column's recursion together: each column's SRS is
    the one it has alone, bit for bit (the same arithmetic in the same order), and the
    peak of scipy.signal.lfilter's output with the same (b, a) (the same transposed direct
    form II; rtol 1e-12 for a different compiled loop)."""
    from scipy.signal import lfilter

    from liftoff.analysis.spectra import srs_filter

    h = 1e-3
    rng = np.random.default_rng(5)
    sig = np.cumsum(rng.standard_normal((4000, 5)), axis=0)
    freq = np.array([2.0, 17.0, 90.0])
    both = srs(sig, h, freq, 10.0)
    for c in range(sig.shape[1]):
        assert np.array_equal(both[:, c], srs(sig[:, c], h, freq, 10.0)[:, 0])
        for j, f in enumerate(freq):
            b, a = srs_filter(f, 10.0, h)
            assert both[j, c] == pytest.approx(np.abs(lfilter(b, a, sig[:, c])).max(), rel=1e-12)


def test_srs_of_a_long_sine_is_the_transmissibility():
    """A sine of amplitude A at the oscillator's frequency: the steady absolute
    acceleration is A sqrt(1 + (2 zeta)^2) / (2 zeta) (closed form, r = 1); 60 cycles with
    Q = 10 settle to exp(-2 pi 60 / 20) = 7e-9 of the transient: rtol 1e-3 (sampling)."""
    h, f, q, amp = 1e-3, 5.0, 10.0, 2.0
    t = np.arange(int(60 / f / h)) * h
    zeta = 1 / (2 * q)
    expect = amp * math.sqrt(1 + (2 * zeta) ** 2) / (2 * zeta)
    assert srs(amp * np.sin(2 * np.pi * f * t), h, [f], q)[0, 0] == pytest.approx(expect, rel=1e-3)


def test_psd_parseval_and_fft_amplitude():
    h = 1e-3
    t = np.arange(20000) * h
    rng = np.random.default_rng(0)
    x = rng.standard_normal(t.size)
    f, p = psd(x, h, segment=1.0)
    assert np.sum(p[:, 0]) * (f[1] - f[0]) == pytest.approx(x.var(), rel=0.02)   # Welch, Hann: ~1 % bias
    fa, a = fft_amplitude(3.0 * np.sin(2 * np.pi * 12.5 * t) + 0.7, h)
    j = int(np.argmin(np.abs(fa - 12.5)))
    assert a[j, 0] == pytest.approx(3.0, rel=1e-9) and a[0, 0] < 1e-9


def test_k_factor_against_tables_and_pyyeti():
    """Published one-sided P99/90 factors (e.g. NASA-HDBK-7005 / Owen tables): N = 21 ->
    3.028; large N -> z_0.99 = 2.3263; pyyeti.stats.ksingle: the same closed form."""
    from pyyeti.stats import ksingle

    assert k_factor(0.99, 0.90, 21) == pytest.approx(3.028, abs=5e-4)
    assert k_factor(0.99, 0.90, 10 ** 7) == pytest.approx(2.3263, abs=2e-3)
    for n in (3, 10, 50, 1000):
        assert k_factor(0.99, 0.90, n) == pytest.approx(float(ksingle(0.99, 0.90, n)), rel=1e-12)


def test_p99_90_covers_the_99th_percentile_90_percent_of_the_time():
    """2000 samples of N = 21 normal maxima (mean 5, std 2): the bound mean + k std lies
    above the true 99th percentile 5 + 2 z_0.99 in 90 % of the samples: 0.90 +- 3 sigma of
    a binomial proportion, sqrt(0.09 / 2000) = 0.0067."""
    from scipy.stats import norm

    rng = np.random.default_rng(12)
    n, trials = 21, 2000
    k = k_factor(0.99, 0.90, n)
    x = 5.0 + 2.0 * rng.standard_normal((trials, n))
    bound = x.mean(axis=1) + k * x.std(axis=1, ddof=1)
    cover = np.mean(bound >= 5.0 + 2.0 * norm.ppf(0.99))
    assert abs(cover - 0.90) < 3 * math.sqrt(0.09 / trials)


def test_order_statistic_rank_and_coverage():
    """r against pyyeti.stats.order_stats and the published table (P99/90: N = 230 -> 1,
    700 -> 4); the r-th largest of N = 700 uniform samples exceeds the 0.99 quantile with
    probability binom.sf(r - 1, N, 0.01) = 0.919: 3000 trials, within 3 sigma."""
    from pyyeti.stats import order_stats
    from scipy.stats import binom

    assert order_rank(0.99, 0.90, 229) == 0 and order_rank(0.99, 0.90, 230) == 1
    assert order_rank(0.99, 0.90, 700) == 4
    for n in (300, 1000, 4000):
        assert order_rank(0.99, 0.90, n) == order_stats("r", p=0.99, c=0.90, n=n)
    rng = np.random.default_rng(5)
    n, r, trials = 700, 4, 3000
    top = Largest(trials, r)
    for k, col in enumerate(rng.random((n, trials))):
        top.add(col, k)
    rth, _ = top.rth()
    c = binom.sf(r - 1, n, 0.01)
    assert abs(np.mean(rth >= 0.99) - c) < 3 * math.sqrt(c * (1 - c) / trials)


def test_streaming_equals_batch():
    rng = np.random.default_rng(1)
    x = rng.standard_normal((300, 7)) * 1e6 + 3e6
    run, top = Running(7), Largest(7, 5)
    for i, row in enumerate(x):
        run.add(row)
        top.add(row, i)
    np.testing.assert_allclose(run.mean, x.mean(axis=0), rtol=1e-13)
    np.testing.assert_allclose(run.std, x.std(axis=0, ddof=1), rtol=1e-11)
    srt = -np.sort(-x, axis=0)
    np.testing.assert_array_equal(top.values.T, srt[:5])
    np.testing.assert_array_equal(top.rth()[1], np.argsort(-x, axis=0, kind="stable")[4])


def test_lowpass_keeps_the_band_and_its_peak_times():
    """The acceleration band of the max/min tables (analysis/spectra.lowpass): a Butterworth
    filter of order n run forward and backward has |H|^2 = 1 / (1 + (f/f_c)^(2n)); a sine
    at 10 Hz under a 50 Hz band keeps its amplitude to that (1 - 7e-12 for n = 8) and its
    peak times (zero phase), one at 400 Hz is cut to (50/400)^16 = 3e-15 of it, one at 1.5
    f_c to 1 / (1 + 1.5^16) = 0.15 % (the band's margin below the components' f_max); away
    from the ends (the start-up of the filter over a few periods of f_c)."""
    h = 1e-4
    t = np.arange(0.0, 2.0, h)
    low, high = np.sin(2 * np.pi * 10 * t), np.sin(2 * np.pi * 400 * t)
    y = lowpass(np.column_stack([low, high, low + high]), h, 50.0)
    mid = (t > 0.3) & (t < 1.7)
    gain = lambda f: 1 / (1 + (f / 50.0) ** (2 * LOWPASS_ORDER))  # noqa: E731
    near = lowpass(np.sin(2 * np.pi * 75 * t), h, 50.0)                # 1.5 f_c: the band's margin
    assert np.abs(near[mid]).max() == pytest.approx(gain(75.0), abs=1e-3) and gain(75.0) < 2e-3
    assert np.abs(y[mid, 0] - gain(10) * low[mid]).max() < 1e-3
    assert np.abs(y[mid, 1]).max() < 10 * gain(400) + 1e-3
    assert np.abs(y[mid, 2] - y[mid, 0]).max() < 1e-3
    one = (t > 1.0) & (t < 1.1)                                         # one period of the 10 Hz sine
    assert abs(t[one][np.argmax(y[one, 2])] - t[one][np.argmax(low[one])]) < 2 * h   # zero phase: the same peak time
    assert lowpass(low, h, 0.0) is not None and np.array_equal(lowpass(low, h, 0.0), low)   # 0: unfiltered
    assert np.array_equal(lowpass(low, h, 6000.0), low)                 # above 0.45 of the sample rate: as is


def test_srs_steady_initial_conditions_against_pyyeti():
    """``ic = "steady"``: the oscillators start at rest relative to a base that has had the
    history's first value for ever. Against pyyeti.srs's ic='steady' (resampling off) on
    histories that start away from zero, as a preloaded force does: rtol 1e-9 (the same
    ramp-invariant filter, round-off over 6000 steps). A constant history then has the SRS
    of its value at every frequency (the absolute acceleration of an oscillator on a base at
    constant acceleration: closed form; from rest, "zero", it overshoots towards twice it);
    a history starting at zero has the zero state's SRS, bit for bit; an unknown ``ic`` is
    named."""
    from pyyeti import srs as ysrs

    from liftoff.core.errors import InputError

    h = 1 / 550.0
    t = np.arange(6000) * h
    rng = np.random.default_rng(7)
    sig = np.column_stack([3.0 + np.sin(2 * np.pi * 7.3 * t) * np.exp(-0.5 * t),
                           -2.0 + 0.3 * rng.standard_normal(t.size), np.cos(2 * np.pi * 1.1 * t)])
    freq = np.geomspace(0.5, 50.0, 45)
    for q in (5.0, 10.0, 25.0):
        ours = srs(sig, h, freq, q, ic="steady")
        ref = ysrs.srs(sig, 1 / h, freq, q, ic="steady", rolloff=None)
        np.testing.assert_allclose(ours, ref, rtol=1e-9, atol=1e-12 * np.abs(ref).max())
    const = np.full((2000, 1), 4.0)
    np.testing.assert_allclose(srs(const, h, freq, 10.0, ic="steady"), 4.0, rtol=1e-9)
    assert srs(const, h, freq, 10.0).max() > 1.5 * 4.0
    zero_start = np.sin(2 * np.pi * 3.0 * t)[:, None]
    assert np.array_equal(srs(zero_start, h, freq, 10.0, ic="steady"), srs(zero_start, h, freq, 10.0))
    with pytest.raises(InputError, match="initial conditions 'mean'"):
        srs(zero_start, h, freq, 10.0, ic="mean")
