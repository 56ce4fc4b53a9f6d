"""Exact one-step coefficients for a modal equation under a force linear over the step.

For one mode  q'' + 2 zeta omega q' + omega^2 q = A + B tau  (eq. 7), with
A = P0 and B = (P1 - P0)/h (eq. 8a-8b), the end-of-step state is exactly (eq. 9-10)

    q1 = F  q0 + G  v0 + Ac  P0 + Bc  P1
    v1 = Fd q0 + Gd v0 + Acd P0 + Bcd P1
    a1 = P1 - 2 zeta omega v1 - omega^2 q1.

Writing g for the impulse response (g(0) = 0, g'(0) = 1), I0 = int_0^h g and
I1 = int_0^h u g(u) du:  F = g' + 2 zeta omega g, G = g, Fd = -omega^2 g, Gd = g',
Ac = I1/h, Bc = I0 - I1/h, Acd = g - I0/h, Bcd = I0/h.

Evaluation, chosen per mode so that no formula cancels or overflows:

* rigid (omega = 0): polynomials (eq. 9);
* small rho h (rho = largest |root| of the characteristic equation, rho h <= 2): the
  Taylor series of g (an entire function), summed to machine precision; this covers
  every damping ratio including zeta = 1 exactly and |zeta - 1| tiny;
* otherwise closed forms (eq. 10) in terms of E cos / E sin(x)/x (underdamped,
  zeta = 0 included) or E cosh / E sinh(x)/x (critically and over-damped), written with
  exp of non-positive arguments only (no overflow for any omega h);
* strongly overdamped with a slow root (|r1| h < 1 while x > 1): the two real roots
  separately through expm1(z)/z and (e^z (z - 1) + 1)/z^2 (no 1 - F cancellation).

Residual-flexibility ("static") modes: a mode far above the forcing and the contact
frequencies responds quasi-statically, q = P/omega^2 at each step end, with no velocity or
acceleration (pyyeti's ``SolveUnc`` ``rf`` modes): Bc = 1/omega^2 and every other
coefficient 0, so that its static flexibility stays in W (section 2.3) while its period no
longer limits the step (:func:`step_coefficients` ``static``; TransientProblem.static_above_hz).
The kernel's acceleration P - 2 zeta omega v - omega^2 q is then 0 to round-off of P.
"""
from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass, fields

import numpy as np

from liftoff.core.errors import InputError
from liftoff.core.locks import ForkSafeLock

_SERIES_LIMIT = 2.0  # rho*h below which the Taylor series is used (terms <= 2^k/k!)


@dataclass
class StepCoefficients:
    """Per-mode coefficient vectors for a fixed step h (all shape (n_modes,))."""

    h: float
    F: np.ndarray
    G: np.ndarray
    Ac: np.ndarray
    Bc: np.ndarray
    Fd: np.ndarray
    Gd: np.ndarray
    Acd: np.ndarray
    Bcd: np.ndarray

    def step(self, q0, v0, P0, P1):
        """Advance q, v over one step (vectorised over modes); returns (q1, v1)."""
        q1 = self.F * q0 + self.G * v0 + self.Ac * P0 + self.Bc * P1
        v1 = self.Fd * q0 + self.Gd * v0 + self.Acd * P0 + self.Bcd * P1
        return q1, v1

    def flexibility(self, phi_rows: np.ndarray, kind: str = "Bc") -> np.ndarray:
        """Step flexibility of the DOFs ``phi_rows`` (k, n_modes): Phi diag(c) Phi^T (k, k).

        The response over one step at those DOFs to unit forces at them, for the coefficient
        ``kind`` (pyyeti's ``get_f2x`` pattern): ``"Bc"`` end-of-step force -> end
        displacement (W of section 2.3), ``"Ac"`` start force -> end displacement, ``"Bcd"``
        and ``"Acd"`` the same to the end velocity (eq. 9-10)."""
        if kind not in ("Ac", "Bc", "Acd", "Bcd"):
            raise InputError(f"flexibility: kind must be Ac, Bc, Acd or Bcd, got {kind!r}")
        return (phi_rows * getattr(self, kind)) @ phi_rows.T

    def packed(self) -> np.ndarray:
        """(8, n_modes) rows F G Ac Bc Fd Gd Acd Bcd, the layout of the compiled kernel."""
        return np.vstack([self.F, self.G, self.Ac, self.Bc, self.Fd, self.Gd, self.Acd, self.Bcd])


def _series(w: float, z: float, h: float):
    """g(h), g'(h), I0, I1 from the Taylor series of g (valid for any zeta; used for rho h <= 2)."""
    wh = w * h
    c1 = -2.0 * z * wh
    c2 = -wh * wh
    b_prev, b = 0.0, 1.0  # b_k = g^(k)(0) h^(k-1) / k!, b_0 = 0, b_1 = 1
    sg, sdg, s0, s1 = 1.0, 1.0, 0.5, 1.0 / 3.0  # sums of b_k, k b_k, b_k/(k+1), b_k/(k+2) (k=1 term)
    k = 1
    while k < 200:
        # g^(k+1) = -2 z w g^(k) - w^2 g^(k-1) in the scaled variables b_k:
        b_next = c1 * b / (k + 1) + c2 * b_prev / (k * (k + 1))
        b_prev, b = b, b_next
        k += 1
        sg += b
        sdg += k * b
        s0 += b / (k + 1)
        s1 += b / (k + 2)
        if abs(b) * k < 1e-18 * max(abs(sg), abs(sdg)) and abs(b_prev) * k < 1e-17 * max(abs(sg), abs(sdg)):
            break
    return h * sg, sdg, h * h * s0, h ** 3 * s1


def _phi1(z: float) -> float:
    """(e^z - 1)/z for z <= 0."""
    return 1.0 if z == 0.0 else np.expm1(z) / z


def _psi(z: float) -> float:
    """int_0^1 s e^(z s) ds = (e^z (z - 1) + 1)/z^2 for z <= 0 (series for |z| < 1)."""
    if abs(z) < 1.0:
        total, term, k = 0.5, 1.0, 0
        while True:
            k += 1
            term *= z / k
            add = term / (k + 2)
            total += add
            if abs(add) < 1e-18 * abs(total) or k > 60:
                return total
    return (np.exp(z) * (z - 1.0) + 1.0) / (z * z)


def _closed(w: float, z: float, h: float):
    """g(h), g'(h), I0, I1 from closed forms (eq. 10); w h large enough that 1 - F does not cancel."""
    wh = w * h
    if z < 1.0:
        wd = w * np.sqrt((1.0 - z) * (1.0 + z))
        x = wd * h
        E = np.exp(-z * wh)
        P = E * np.cos(x)
        Q = E * (np.sin(x) / x if x > 0 else 1.0)
    else:
        root = np.sqrt((z - 1.0) * (z + 1.0))
        x = w * root * h
        if x < 1.0:
            E = np.exp(-z * wh)
            P = E * np.cosh(x)
            Q = E * (np.sinh(x) / x if x > 0 else 1.0)
        else:
            a = -wh / (z + root)  # = -z w h + x  (slow root times h), <= 0
            b = -wh * (z + root)  # = -z w h - x  (fast root times h)
            ea, eb = np.exp(a), np.exp(b)
            P = 0.5 * (ea + eb)
            Q = -ea * np.expm1(b - a) / (2.0 * x)
    g = h * Q
    dg = P - z * wh * Q
    F = P + z * wh * Q
    I0 = (1.0 - F) / (w * w)
    I1 = (g - h * dg - 2.0 * z * w * (h * g - I0)) / (w * w)
    return g, dg, I0, I1


def _two_roots(w: float, z: float, h: float):
    """Overdamped, well-separated roots with a slow root: root-by-root forms (no cancellation)."""
    root = np.sqrt((z - 1.0) * (z + 1.0))
    r1 = -w / (z + root)  # slow root
    r2 = -w * (z + root)  # fast root
    d = r1 - r2  # > 0
    e1, e2 = np.exp(r1 * h), np.exp(r2 * h)
    g = -e1 * np.expm1((r2 - r1) * h) / d
    dg = (r1 * e1 - r2 * e2) / d
    I0 = h * (_phi1(r1 * h) - _phi1(r2 * h)) / d
    I1 = h * h * (_psi(r1 * h) - _psi(r2 * h)) / d
    return g, dg, I0, I1


def mode_integrals(omega: float, zeta: float, h: float):
    """(g(h), g'(h), I0, I1) for one mode, choosing the accurate formulation."""
    w, z = float(omega), float(zeta)
    if w == 0.0:
        return h, 1.0, 0.5 * h * h, h ** 3 / 3.0
    rho = w * (z + np.sqrt((z - 1.0) * (z + 1.0))) if z > 1.0 else w
    if rho * h <= _SERIES_LIMIT:
        return _series(w, z, h)
    if z > 1.0:
        root = np.sqrt((z - 1.0) * (z + 1.0))
        if w * root * h >= 1.0 and w * h / (z + root) < 1.0:
            return _two_roots(w, z, h)
    return _closed(w, z, h)


def step_coefficients(omega, zeta, h: float, static=None) -> StepCoefficients:
    """Exact coefficients (eq. 7-10) for every mode for the fixed step h (s); the modes
    where the boolean mask ``static`` is True (elastic ones only) get the residual-flexibility
    coefficients of the module docstring (Bc = 1/omega^2, the others 0)."""
    omega = np.asarray(omega, dtype=float).reshape(-1)
    zeta = np.broadcast_to(np.asarray(zeta, dtype=float), omega.shape)
    if not (np.isfinite(h) and h > 0):
        raise InputError(f"time step h = {h!r} s must be positive and finite")
    n = omega.size
    static = np.zeros(n, dtype=bool) if static is None else np.asarray(static, dtype=bool).reshape(-1)
    if static.shape != (n,):
        raise InputError(f"static: {static.size} flags for {n} modes")
    if np.any(static & ~(omega > 0)):
        raise InputError("static: a rigid-body mode (omega = 0) has no static flexibility; only elastic modes may be "
                         "residual-flexibility modes")
    key = (omega.tobytes(), np.ascontiguousarray(zeta).tobytes(), float(h), static.tobytes()) \
        if n >= RECENT_MIN_MODES else None
    if key is not None:
        with _RECENT_LOCK:
            known = _RECENT.get(key)
            if known is not None:
                _RECENT.move_to_end(key)
        if known is not None:
            return _copied(known)
    out = {k: np.empty(n) for k in ("F", "G", "Ac", "Bc", "Fd", "Gd", "Acd", "Bcd")}
    for i in range(n):
        w, z = omega[i], zeta[i]
        if static[i]:
            for k in out:
                out[k][i] = 0.0
            out["Bc"][i] = 1.0 / (w * w)
            continue
        g, dg, I0, I1 = mode_integrals(w, z, h)
        out["G"][i] = g
        out["Gd"][i] = dg
        out["F"][i] = dg + 2.0 * z * w * g
        out["Fd"][i] = -w * w * g
        out["Ac"][i] = I1 / h
        out["Bc"][i] = I0 - I1 / h
        out["Acd"][i] = g - I0 / h
        out["Bcd"][i] = I0 / h
    coefficients = StepCoefficients(h=float(h), **out)
    if key is None:
        return coefficients
    with _RECENT_LOCK:
        _RECENT[key] = _copied(coefficients)
        while len(_RECENT) > RECENT_SIZE:
            _RECENT.popitem(last=False)
    return coefficients


#: the coefficients of this many recent (omega, zeta, h, static) sets are kept: a campaign's
#: cases share the bodies and the step, and the per-mode evaluation above (a Python loop, a
#: series of up to 200 terms a mode) took 5 ms of a default generated case (2026-12-07); a run
#: at h and its error estimate at h/2 use two sets
RECENT_SIZE = 8
#: fewer modes than this are not kept (the SRS's one-mode filters, cached by analysis.spectra,
#: would push a body's coefficients out)
RECENT_MIN_MODES = 32
_RECENT: OrderedDict = OrderedDict()
_RECENT_LOCK = ForkSafeLock()         # the error estimate's halved runs step in a thread of their own


def _copied(c: StepCoefficients) -> StepCoefficients:
    """A StepCoefficients with arrays of its own (a caller may change its copy)."""
    return StepCoefficients(**{f.name: (getattr(c, f.name).copy() if f.name != "h" else c.h) for f in fields(c)})
