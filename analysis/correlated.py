"""Correlated loads: the pairs of an interface's load components that size a joint, plotted
against each other over time and cases, and their convex hull (issue 24).

Enveloping each component alone takes every maximum at its own time, and designs the joint
to a combination that never occurs. The pairs here are the ones a joint is checked for:

* **axial force with bending moment**: Tz against Mb = sqrt(Rx^2 + Ry^2);
* **shear with torque**: V = sqrt(Tx^2 + Ty^2) against Rz;

(forces N, moments N m, on the named component; the interface's own axes). Over a run the
correlated envelope of a pair is the convex hull of its (x(t), y(t)) samples; over cases,
the hull of the cases' hulls (the hull of a union is the hull of the union of the hulls).
Each hull vertex is a sample of one case at one time, so it is a load the structure saw;
a straight hull edge between two vertices is the (conservative) convex combination.

A hull of a finely stepped run traces smooth curves with thousands of vertices (the
default's: 6,522 in all). :func:`simplify` keeps a subset of them (Douglas-Peucker on the
closed convex polygon, in coordinates scaled by each axis's range): the extremes of each
axis (the single-component envelopes) always, and every dropped vertex lies within
``tolerance`` of that range outside the kept polygon (``CorrelatedHull.shortfall`` says by
how much at most), so the kept vertices are still loads the structure saw.

numpy/scipy only.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Iterable

import numpy as np

from liftoff.core.errors import InputError

#: (name, x, y): the pairs, by the interface's component labels (Tx Ty Tz Rx Ry Rz)
PAIRS = (("axial-bending", "Tz", "Mb"), ("shear-torque", "V", "Rz"))


def pair_values(labels, values: np.ndarray, name: str) -> np.ndarray:
    """The component ``name`` of an interface's histories: one of its labels, or Mb =
    |(Rx, Ry)|, V = |(Tx, Ty)|."""
    labels = list(labels)
    derived = {"Mb": ("Rx", "Ry"), "V": ("Tx", "Ty")}
    try:
        if name in derived:
            a, b = (labels.index(c) for c in derived[name])
            return np.hypot(values[:, a], values[:, b])
        return values[:, labels.index(name)]
    except ValueError:
        raise InputError(f"correlated loads: the interface has no {derived.get(name, name)} among "
                         f"its components {labels}") from None


def hull_indices(points: np.ndarray) -> np.ndarray:
    """Indices of the convex hull's vertices of 2-D ``points``, counter-clockwise; collinear or
    coincident points (a degenerate hull) give the two extreme points of the segment."""
    from scipy.spatial import ConvexHull, QhullError

    pts = np.asarray(points, float)
    if pts.ndim != 2 or pts.shape[1] != 2 or pts.shape[0] == 0:
        raise InputError(f"correlated loads: {np.shape(points)} is not a set of 2-D points")
    finite = np.isfinite(pts).all(axis=1)
    if not finite.all():
        raise InputError("correlated loads: a history holds NaN or inf")
    span = np.ptp(pts, axis=0)
    scale = np.where(span > 0, span, 1.0)
    try:
        return ConvexHull(pts / scale).vertices           # counter-clockwise in 2-D
    except (QhullError, ValueError):
        d = pts - pts.mean(axis=0)
        u = np.linalg.svd(d, full_matrices=False)[2][0] if np.any(d) else np.array([1.0, 0.0])
        s = d @ u
        return np.unique([int(np.argmin(s)), int(np.argmax(s))])


@dataclass
class CorrelatedHull:
    """The correlated envelope of one pair of one interface: hull vertices (x, y) with the
    time (s) and case of each, counter-clockwise."""

    interface: str
    pair: str
    x_name: str
    y_name: str
    x_unit: str
    y_unit: str
    x: np.ndarray
    y: np.ndarray
    time: np.ndarray
    case: list[str]
    shortfall: float = 0.0       # largest distance of a dropped vertex outside the kept polygon / axis range


def simplify(h: CorrelatedHull, tolerance: float) -> CorrelatedHull:
    """``h`` with the fewest vertices :func:`simplify`'s Douglas-Peucker keeps: the extremes
    of x and y, and any vertex farther than ``tolerance`` (a fraction of each axis's range)
    outside the polygon of those kept; ``tolerance`` 0 keeps every vertex."""
    if not (np.isfinite(tolerance) and tolerance >= 0):
        raise InputError(f"correlated loads: simplification tolerance must be >= 0 (got {tolerance!r})")
    n = h.x.size
    if n <= 4 or tolerance == 0:
        return h
    span = np.array([np.ptp(h.x), np.ptp(h.y)])
    pts = np.column_stack([h.x, h.y]) / np.where(span > 0, span, 1.0)
    keep = np.zeros(n, bool)
    keep[[np.argmin(h.x), np.argmax(h.x), np.argmin(h.y), np.argmax(h.y)]] = True
    worst = 0.0
    anchors = np.flatnonzero(keep)
    stack = [(int(a), int(b)) for a, b in zip(anchors, np.roll(anchors, -1))]
    while stack:
        a, b = stack.pop()
        idx = (np.arange(a + 1, b if b > a else b + n) % n)
        if idx.size == 0:
            continue
        d = pts[b] - pts[a]
        rel = pts[idx] - pts[a]
        # distance to the chord's segment: at least the vertex's distance to the kept polygon
        t = np.clip(rel @ d / max(float(d @ d), 1e-300), 0.0, 1.0)
        dist = np.hypot(*(rel - t[:, None] * d).T)
        j = int(np.argmax(dist))
        if dist[j] > tolerance:
            keep[idx[j]] = True
            stack += [(a, int(idx[j])), (int(idx[j]), b)]
        else:
            worst = max(worst, float(dist[j]))
    k = np.flatnonzero(keep)
    return CorrelatedHull(h.interface, h.pair, h.x_name, h.y_name, h.x_unit, h.y_unit, h.x[k], h.y[k], h.time[k],
                          [h.case[i] for i in k], max(h.shortfall, worst))


def correlated(time: np.ndarray, interfaces: Iterable, case: str) -> list[CorrelatedHull]:
    """The hull of every pair (:data:`PAIRS`) of every interface (analysis.interface_loads
    InterfaceHistory) over one run."""
    time = np.asarray(time, float)
    out = []
    for itf in interfaces:
        units = dict(zip(itf.labels, itf.units))
        for pair, xn, yn in PAIRS:
            x, y = pair_values(itf.labels, itf.values, xn), pair_values(itf.labels, itf.values, yn)
            k = hull_indices(np.column_stack([x, y]))
            ux = units.get(xn, units.get("Tx" if xn == "V" else "Rx", ""))
            uy = units.get(yn, units.get("Rx" if yn == "Mb" else "Tx", ""))
            out.append(CorrelatedHull(itf.name, pair, xn, yn, ux, uy, x[k], y[k], time[k], [case] * k.size))
    return out


def envelope(per_case: Iterable[list[CorrelatedHull]]) -> list[CorrelatedHull]:
    """Over cases: per (interface, pair) the hull of the cases' hull vertices."""
    groups: dict[tuple[str, str], list[CorrelatedHull]] = {}
    for hulls in per_case:
        for h in hulls:
            groups.setdefault((h.interface, h.pair), []).append(h)
    out = []
    for hs in groups.values():
        x = np.concatenate([h.x for h in hs])
        y = np.concatenate([h.y for h in hs])
        t = np.concatenate([h.time for h in hs])
        c = [name for h in hs for name in h.case]
        k = hull_indices(np.column_stack([x, y]))
        h0 = hs[0]
        out.append(CorrelatedHull(h0.interface, h0.pair, h0.x_name, h0.y_name, h0.x_unit, h0.y_unit, x[k], y[k],
                                  t[k], [c[i] for i in k]))
    return out


def rows(hulls: list[CorrelatedHull]) -> list[dict]:
    """One dict per hull vertex (interface, pair, vertex, x and y with their names and units,
    time, case): the table correlated_loads.csv holds."""
    out = []
    for h in hulls:
        for v in range(h.x.size):
            out.append({"interface": h.interface, "pair": h.pair, "vertex": v + 1, "x_name": h.x_name,
                        "x": float(h.x[v]), "x_unit": h.x_unit, "y_name": h.y_name, "y": float(h.y[v]),
                        "y_unit": h.y_unit, "time": float(h.time[v]), "case": h.case[v]})
    return out


# ------------------------------------------------------------ statistical contour
#: directions of the support function (every 5 degrees), in the plane (x, y / MOMENT_ARM):
#: a moment (N m) over 1 m compares with a force (N); the directions' spacing sets only how
#: closely the polygon follows a round contour, never whether it holds the loads
N_DIRECTIONS = 72
MOMENT_ARM = 1.0
#: samples per block in :func:`support`: a default case's 106,383 samples x 72 directions at
#: once (61 MB) took 27-38 ms a pair, in blocks of 4,096 9 ms (the same values), 14 pairs a case
SUPPORT_ROWS = 4096


def directions(n: int = N_DIRECTIONS) -> np.ndarray:
    """(n, 2) unit normals at angles 2 pi k / n (n a multiple of 4: the axes are among them)."""
    if n < 4 or n % 4:
        raise InputError(f"correlated loads: the number of directions must be a multiple of 4 >= 4 (got {n})")
    a = 2 * np.pi * np.arange(n) / n
    return np.column_stack([np.cos(a), np.sin(a)])


def support(x: np.ndarray, y: np.ndarray, n: int = N_DIRECTIONS) -> np.ndarray:
    """The support function h_k = max over the samples of n_k . (x, y / MOMENT_ARM) in each
    direction (:func:`directions`): a history's pair reduced to n numbers; the polygon
    {p : n_k . p <= h_k} (:func:`contour`) holds every sample and is the hull cut by n lines."""
    d = directions(n)
    pts = np.column_stack([np.asarray(x, float), np.asarray(y, float) / MOMENT_ARM])
    if not np.isfinite(pts).all():
        raise InputError("correlated loads: a history holds NaN or inf")
    if not pts.shape[0]:
        raise InputError("correlated loads: a history holds no samples")
    h = np.full(n, -np.inf)
    for i in range(0, pts.shape[0], SUPPORT_ROWS):       # blocks of samples x directions that stay in cache
        np.maximum(h, (pts[i:i + SUPPORT_ROWS] @ d.T).max(axis=0), out=h)
    return h


def case_support(interfaces: Iterable, n: int = N_DIRECTIONS) -> tuple[tuple[str, ...], np.ndarray]:
    """(names ``<interface>|<pair>``, (n_names, n) support functions) of every pair
    (:data:`PAIRS`) of every interface of one run: what a campaign keeps of each case's
    correlated loads."""
    names, rows = [], []
    for itf in interfaces:
        for pair, xn, yn in PAIRS:
            names.append(f"{itf.name}|{pair}")
            rows.append(support(pair_values(itf.labels, itf.values, xn), pair_values(itf.labels, itf.values, yn), n))
    return tuple(names), np.array(rows).reshape(len(rows), n)


def contour(h: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The polygon {p : n_k . p <= h_k} of support values ``h`` (:func:`directions`), vertices
    (x, y) counter-clockwise in the pair's units (y back in N m); empty arrays when the
    half-planes hold no point (values that are no support function of any set)."""
    h = np.asarray(h, float)
    d = directions(h.size)
    q = h.size // 4
    # the box of the four axis directions, clipped by each other half-plane (Sutherland-Hodgman)
    poly = np.array([[h[0], h[q]], [-h[2 * q], h[q]], [-h[2 * q], -h[3 * q]], [h[0], -h[3 * q]]])
    if h[0] < -h[2 * q] or h[q] < -h[3 * q]:
        return np.zeros(0), np.zeros(0)
    scale = max(float(np.abs(h).max()), 1e-300)
    for k in range(h.size):
        if k % q == 0 or poly.shape[0] == 0:
            continue
        s = poly @ d[k] - h[k]
        inside = s <= 1e-12 * scale
        out = []
        for i in range(poly.shape[0]):
            j = (i + 1) % poly.shape[0]
            if inside[i]:
                out.append(poly[i])
            if inside[i] != inside[j]:
                out.append(poly[i] + (poly[j] - poly[i]) * (s[i] / (s[i] - s[j])))
        poly = np.array(out).reshape(-1, 2)
    if poly.shape[0] < 3:
        return np.zeros(0), np.zeros(0)
    return poly[:, 0].copy(), poly[:, 1] * MOMENT_ARM
