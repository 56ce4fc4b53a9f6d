"""Spectra of recovered histories: shock response spectra (SRS), PSD and FFT. SI units.

* :func:`srs`: the peak absolute acceleration of single-DOF oscillators (natural
  frequency f, damping Q = 1/(2 zeta)) on a base that moves with the given acceleration
  a(t) (the 'absacce' spectrum of NASA-HDBK-7005 and pyyeti.srs). The base acceleration
  is taken as linear between samples, as the transient itself takes its forces (eq. 7-10),
  so the exact step of the oscillator over one sample,
  s_{k+1} = A s_k + B0 a_k + B1 a_{k+1} (s = [z, z'], relative motion, z'' + 2 zeta w z'
  + w^2 z = -a), comes from the same exact coefficients as the transient's modes
  (liftoff.transient.coefficients). Its transfer function is a second-order recursive
  filter (the recursion of scipy.signal.lfilter, compiled, keeping only the peak), one
  per frequency, run over every history; the output is the absolute acceleration
  y = -(w^2 z + 2 zeta w z'); initial state zero (``ic = "zero"``, pyyeti's default) or
  steady under the history's first value (``ic = "steady"``, pyyeti's 'steady': the
  oscillator at rest relative to a base that has had that value for ever, so a history
  that starts at a static level, a preloaded force, rings from no false step at t0; the run's
  spectra use it, the transient itself starting from the static state at t0).
  Sampled histories resolve frequencies up to about a tenth of the sample rate.
* :func:`psd`: Welch's PSD (scipy.signal.welch, Hann window, 50 % overlap), units^2/Hz;
  :func:`fft_amplitude`: single-sided amplitude spectrum, units.
* :func:`lowpass`: a history limited to a band (zero-phase Butterworth).
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np
from numba import njit

from liftoff.core.errors import InputError


def srs_filter(freq_hz: float, q: float, h: float) -> tuple[np.ndarray, np.ndarray]:
    """(b, a) of the recursive filter from base acceleration samples (step h, s) to the
    absolute acceleration of the oscillator (``freq_hz``, Q = ``q``)."""
    from liftoff.transient.coefficients import step_coefficients

    w, zeta = 2 * np.pi * freq_hz, 1.0 / (2.0 * q)
    c = step_coefficients(np.array([w]), np.array([zeta]), h)
    A = np.array([[c.F[0], c.G[0]], [c.Fd[0], c.Gd[0]]])
    B0, B1 = -np.array([c.Ac[0], c.Acd[0]]), -np.array([c.Bc[0], c.Bcd[0]])   # load f = -a
    out = np.array([-w * w, -2.0 * zeta * w])                                    # y = out . s
    M0 = np.array([[-A[1, 1], A[0, 1]], [A[1, 0], -A[0, 0]]])                    # adj(zI - A) = M0 + z I
    b = np.array([out @ B1, out @ (M0 @ B1 + B0), out @ (M0 @ B0)])
    a = np.array([1.0, -np.trace(A), np.linalg.det(A)])
    return b, a


#: initial conditions of the SRS oscillators (pyyeti.srs's ``ic`` of the same names)
SRS_IC = ("zero", "steady")


def srs(acc: np.ndarray, h: float, freq, q: float = 10.0, ic: str = "zero") -> np.ndarray:
    """SRS (len(freq), k): max over time of |absolute acceleration| of each oscillator, for
    each column of ``acc`` (n_t, k) sampled every ``h`` seconds (units of ``acc``); ``ic``:
    the oscillators' initial state, "zero" or "steady" (module docstring)."""
    acc = np.asarray(acc, dtype=float)
    acc = np.ascontiguousarray(acc.reshape(acc.shape[0], -1))
    freq = np.atleast_1d(np.asarray(freq, dtype=float))
    if not (h > 0 and np.all(freq > 0) and q > 0.5):
        raise InputError(f"srs: need h > 0 (got {h}), frequencies > 0 and Q > 0.5 (got {q})")
    if ic not in SRS_IC:
        raise InputError(f"srs: initial conditions {ic!r}: give one of {', '.join(SRS_IC)}")
    b, a = np.empty((freq.size, 3)), np.empty((freq.size, 3))
    for j, f in enumerate(freq):
        b[j], a[j] = _filter(float(f), float(q), float(h))
    # the filter's state for a constant unit input (transposed direct form II): y = G =
    # sum(b) / sum(a) (1 for the absolute acceleration, to round-off), z1 = G - b0, z2 = b2 - a2 G
    gain = b.sum(axis=1) / a.sum(axis=1)
    zi = np.column_stack([gain - b[:, 0], b[:, 2] - a[:, 2] * gain]) if ic == "steady" else np.zeros((freq.size, 2))
    out = np.empty((freq.size, acc.shape[1]))
    _peaks(b, a, acc, zi, out)
    return out


@lru_cache(maxsize=4096)
def _filter(f: float, q: float, h: float) -> tuple[np.ndarray, np.ndarray]:
    return srs_filter(f, q, h)


@njit(cache=True)
def _peaks(b, a, x, zi, out):
    """out[j, c] = max_i |y_i| of the filter (b[j], a[j]) run over column c of x: the
    transposed direct form II recursion of scipy.signal.lfilter, initial state zi[j] x[0, c]
    (zi zero: the zero state), without storing y. The columns' recursions are independent: they advance together,
    one sample at a time (row i of x is contiguous), so the processor overlaps them
    instead of waiting on one column's chain (2026-11-27: 0.145 -> 0.078 s for 60
    frequencies of 6 histories of 106,384 samples; the same arithmetic per column, so
    the same peaks, bit for bit)."""
    n, k = x.shape
    z1 = np.empty(k)
    z2 = np.empty(k)
    m = np.empty(k)
    for j in range(b.shape[0]):
        b0, b1, b2, a1, a2 = b[j, 0], b[j, 1], b[j, 2], a[j, 1], a[j, 2]
        for c in range(k):
            z1[c] = zi[j, 0] * x[0, c] if n else 0.0
            z2[c] = zi[j, 1] * x[0, c] if n else 0.0
        m[:] = 0.0
        for i in range(n):
            for c in range(k):
                xi = x[i, c]
                y = b0 * xi + z1[c]
                z1[c] = b1 * xi - a1 * y + z2[c]
                z2[c] = b2 * xi - a2 * y
                if abs(y) > m[c]:
                    m[c] = abs(y)
        for c in range(k):
            out[j, c] = m[c]


def srs_frequencies(f_min: float, f_max: float, n: int) -> np.ndarray:
    """``n`` frequencies log-spaced from f_min to f_max (Hz)."""
    return np.geomspace(f_min, f_max, n)


def psd(values: np.ndarray, h: float, segment: float = 2.0) -> tuple[np.ndarray, np.ndarray]:
    """(frequency (Hz), PSD (n_f, k) in units^2/Hz) of each column, Welch with segments of
    ``segment`` seconds (at most the record), Hann window, 50 % overlap, mean removed."""
    from scipy.signal import welch

    values = np.asarray(values, dtype=float).reshape(np.shape(values)[0], -1)
    nper = int(min(values.shape[0], max(8, round(segment / h))))
    f, p = welch(values, fs=1.0 / h, nperseg=nper, axis=0, detrend="constant")
    return f, p


def fft_amplitude(values: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:
    """(frequency (Hz), single-sided amplitude (n_f, k), units): |rfft| scaled so that a
    sine of amplitude A shows A at its frequency (mean removed)."""
    values = np.asarray(values, dtype=float).reshape(np.shape(values)[0], -1)
    n = values.shape[0]
    spec = np.abs(np.fft.rfft(values - values.mean(axis=0), axis=0)) * (2.0 / n)
    spec[0] /= 2.0
    if n % 2 == 0 and n > 1:           # the Nyquist bin, like the mean's, has no mirror image
        spec[-1] /= 2.0
    return np.fft.rfftfreq(n, h), spec


#: order 8: run forward and backward, |H|^2 = 1 / (1 + (f / f_c)^16), so a 40 Hz band passes
#: 0.15 % at 60 Hz, the default components' f_max (order 4 passed 3.8 %, and a 50 Hz band 19 %:
#: modes the reduction leaves out entered the peaks; issue 22)
LOWPASS_ORDER = 8


def lowpass_gain(f_hz: float, band_hz: float) -> float:
    """The amplitude :func:`lowpass` passes at ``f_hz`` for a band ``band_hz``: |H|^2 of the
    Butterworth filter (it runs twice), 1 / (1 + (f / f_c)^(2 LOWPASS_ORDER))."""
    return 1.0 / (1.0 + (f_hz / band_hz) ** (2 * LOWPASS_ORDER)) if band_hz > 0 else 1.0


def lowpass(values: np.ndarray, h: float, f_hz: float) -> np.ndarray:
    """``values`` (time along axis 0, step h s) low-pass filtered to ``f_hz``: a Butterworth
    filter of order LOWPASS_ORDER run forward and backward (scipy.signal.sosfiltfilt: zero
    phase, so peaks keep their times; -6 dB at f_hz, 2 x LOWPASS_ORDER x 6 dB per octave
    beyond: :func:`lowpass_gain`). Unchanged when f_hz <= 0, when f_hz is above 0.45 of the
    sample rate, or for fewer than 16 samples."""
    from scipy.signal import sosfiltfilt

    values = np.asarray(values, dtype=float)
    fs = 1.0 / h
    if not f_hz > 0 or f_hz >= 0.45 * fs or values.shape[0] < 16:
        return values
    sos = _butter_sos(float(f_hz), float(fs)).copy()      # (a few numbers: the cached one stays as designed)
    return sosfiltfilt(sos, values, axis=0, padlen=min(values.shape[0] - 1, 3 * (2 * len(sos) + 1)))


@lru_cache(maxsize=64)
def _butter_sos(f_hz: float, fs: float) -> np.ndarray:
    """The second-order sections of :func:`lowpass`'s filter (designed once per band and
    rate: a case filters a dozen histories with the same one)."""
    from scipy.signal import butter

    return butter(LOWPASS_ORDER, f_hz, fs=fs, output="sos")
