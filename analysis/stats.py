"""Statistics over load cases, streamed: memory does not grow with the number of cases.

The statistical extreme of a recovery item over N dispersed cases, as in pyyeti's cla
(``DR_Results.calc_stat_ext``): the maxima of the N cases (minima alike, with the sign
turned) bound a proportion p of the population with confidence c by

* the normal tolerance bound ``mean + k std`` (sample mean, sample std with ddof = 1),
  k the one-sided k-factor k = t'_{c}(N - 1, sqrt(N) z_p) / sqrt(N) (noncentral t,
  z_p the standard normal p-quantile: the closed form behind published tables, e.g.
  k = 3.0282 for P99/90 at N = 21);
* the distribution-free order statistic: the r-th largest of the N maxima with
  r = the largest integer such that P(Binomial(N, 1 - p) >= r) >= c (at least 230 cases
  for P99/90, r = 1; 4 for N = 700).

:class:`Running` keeps count, mean and sum of squared deviations (Welford's update);
:class:`Largest` the r largest values per item with the case that gave each, r fixed
when the campaign starts (from its N), so both are O(items), not O(cases).
"""
from __future__ import annotations

import math
import warnings

import numpy as np

P99_90 = (0.99, 0.90)


def k_factor(p: float, c: float, n: int) -> float:
    """One-sided normal tolerance k-factor (proportion p, confidence c, n samples); NaN if n < 2."""
    from scipy.stats import nct, norm

    if n < 2:
        return math.nan
    with np.errstate(divide="ignore", over="ignore"), warnings.catch_warnings():   # scipy's boost at n = 2
        warnings.simplefilter("ignore", RuntimeWarning)
        return float(nct.ppf(c, n - 1, math.sqrt(n) * norm.ppf(p)) / math.sqrt(n))


def order_rank(p: float, c: float, n: int) -> int:
    """r: the r-th largest of n samples bounds proportion p with confidence >= c; 0 when
    n is too small for any (e.g. n < 230 for P99/90)."""
    from scipy.stats import binom

    if n < 1:
        return 0
    r = int(binom.ppf(1.0 - c, n, 1.0 - p))
    while r > 0 and binom.sf(r - 1, n, 1.0 - p) < c:     # guard the ppf's rounding
        r -= 1
    while binom.sf(r, n, 1.0 - p) >= c:
        r += 1
    return r


class Running:
    """Mean and standard deviation of arrays added one case at a time (Welford)."""

    def __init__(self, shape):
        self.n = 0
        self.mean = np.zeros(shape)
        self.m2 = np.zeros(shape)

    def add(self, x: np.ndarray) -> None:
        self.n += 1
        d = x - self.mean
        self.mean += d / self.n
        self.m2 += d * (x - self.mean)

    @property
    def std(self) -> np.ndarray:
        """Sample standard deviation (ddof = 1); NaN below 2 cases."""
        return np.sqrt(self.m2 / (self.n - 1)) if self.n > 1 else np.full(self.mean.shape, np.nan)

    def bound(self, k: float) -> np.ndarray:
        return self.mean + k * self.std


class Largest:
    """The ``r`` largest values per item (and the case of each), sorted descending."""

    def __init__(self, n_items: int, r: int):
        self.r = r
        self.values = np.full((n_items, max(r, 0)), -np.inf)
        self.cases = np.full((n_items, max(r, 0)), -1, dtype=np.int64)

    def add(self, x: np.ndarray, case: int) -> None:
        if self.r <= 0:
            return
        better = x > self.values[:, -1]
        for i in np.flatnonzero(better):
            row, cr = self.values[i], self.cases[i]
            k = int(np.searchsorted(-row, -x[i], side="right"))    # after equal values: first case wins
            row[k + 1:] = row[k:-1].copy()
            cr[k + 1:] = cr[k:-1].copy()
            row[k], cr[k] = x[i], case

    def rth(self) -> tuple[np.ndarray, np.ndarray]:
        """(r-th largest value, its case) per item; NaN / -1 when r == 0."""
        if self.r <= 0:
            return np.full(self.values.shape[0], np.nan), np.full(self.values.shape[0], -1)
        return self.values[:, -1].copy(), self.cases[:, -1].copy()
