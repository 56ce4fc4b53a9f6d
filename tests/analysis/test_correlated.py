"""Correlated loads (analysis/correlated.py): the hull holds every sample, its vertices are
samples of the histories at their times, its extremes are the single-component envelopes,
and over cases it is the hull of the union."""
import numpy as np
import pytest

from liftoff.analysis import correlated as cl
from liftoff.analysis.interface_loads import InterfaceHistory
from liftoff.core.errors import InputError

LABELS = ("Tx", "Ty", "Tz", "Rx", "Ry", "Rz")
UNITS = ("N", "N", "N", "N m", "N m", "N m")


def _itf(t, seed):
    rng = np.random.default_rng(seed)
    w = rng.uniform(1, 8, 6)
    vals = np.column_stack([rng.uniform(0.5, 2) * np.sin(w[j] * t + rng.uniform(0, 6)) for j in range(6)])
    vals[:, 2] += 5.0                                   # an axial preload
    return InterfaceHistory("attach p on core", LABELS, UNITS, vals)


def _inside(hx, hy, x, y, tol):
    """Every (x, y) on the inner side of every edge of the counter-clockwise polygon (hx, hy)."""
    ex, ey = np.roll(hx, -1) - hx, np.roll(hy, -1) - hy
    cross = ex[:, None] * (y[None, :] - hy[:, None]) - ey[:, None] * (x[None, :] - hx[:, None])
    return bool(np.all(cross >= -tol))


def test_hull_holds_every_sample_and_its_vertices_are_samples():
    t = np.linspace(0, 5, 2001)
    itf = _itf(t, 1)
    for h in cl.correlated(t, [itf], "nominal"):
        x = cl.pair_values(LABELS, itf.values, h.x_name)
        y = cl.pair_values(LABELS, itf.values, h.y_name)
        scale = max(np.ptp(x), np.ptp(y))
        assert _inside(h.x, h.y, x, y, 1e-12 * scale * scale)
        for v in range(h.x.size):                        # a vertex is the sample at its time
            i = int(np.flatnonzero(t == h.time[v])[0])
            assert (h.x[v], h.y[v]) == (x[i], y[i])
        # the hull's extremes are the single-component envelopes
        assert h.x.max() == x.max() and h.x.min() == x.min() and h.y.max() == y.max() and h.y.min() == y.min()
    mb = cl.pair_values(LABELS, itf.values, "Mb")
    np.testing.assert_array_equal(mb, np.hypot(itf.values[:, 3], itf.values[:, 4]))


def test_envelope_is_the_hull_of_the_union_over_cases():
    t = np.linspace(0, 5, 801)
    a, b = _itf(t, 2), _itf(t, 3)
    env = cl.envelope([cl.correlated(t, [a], "a"), cl.correlated(t, [b], "b")])
    for h in env:
        xs = np.concatenate([cl.pair_values(LABELS, i.values, h.x_name) for i in (a, b)])
        ys = np.concatenate([cl.pair_values(LABELS, i.values, h.y_name) for i in (a, b)])
        direct = cl.hull_indices(np.column_stack([xs, ys]))
        assert sorted(zip(xs[direct], ys[direct])) == sorted(zip(h.x, h.y))
        assert set(h.case) <= {"a", "b"}


def test_degenerate_and_bad_histories():
    # collinear samples: the two ends of the segment
    k = cl.hull_indices(np.column_stack([np.linspace(0, 1, 5), np.linspace(0, 2, 5)]))
    assert sorted(k.tolist()) == [0, 4]
    with pytest.raises(InputError, match="NaN"):
        cl.hull_indices(np.array([[0.0, 1.0], [np.nan, 2.0], [1.0, 0.0]]))
    with pytest.raises(InputError, match=r"no \('Rx', 'Ry'\)"):
        cl.pair_values(("Tx", "Ty", "Tz"), np.zeros((3, 3)), "Mb")
    rows = cl.rows(cl.correlated(np.linspace(0, 1, 50), [_itf(np.linspace(0, 1, 50), 4)], "c"))
    assert {r["pair"] for r in rows} == {"axial-bending", "shear-torque"}
    assert {(r["x_unit"], r["y_unit"]) for r in rows} == {("N", "N m")}


def _segment_distance(px, py, hx, hy):
    """Distance of each point (px, py) to the closed polygon (hx, hy)'s boundary."""
    ax, ay = hx, hy
    bx, by = np.roll(hx, -1), np.roll(hy, -1)
    dx, dy = bx - ax, by - ay
    rx, ry = px[:, None] - ax[None, :], py[:, None] - ay[None, :]
    t = np.clip((rx * dx + ry * dy) / np.maximum(dx * dx + dy * dy, 1e-300), 0, 1)
    return np.hypot(rx - t * dx, ry - t * dy).min(axis=1)


@pytest.mark.parametrize("tol", [1e-2, 1e-3, 1e-4])
def test_simplified_hull_keeps_samples_extremes_and_the_stated_shortfall(tol):
    """The simplified hull's vertices are a subset of the hull's (loads the structure saw),
    keep each axis's extremes exactly, and every sample lies inside it or within the
    tolerance (of each axis's range) outside, which the hull states as its shortfall; the
    check is independent: each sample's distance to the kept polygon, by brute force."""
    t = np.linspace(0, 20, 20001)
    itf = _itf(t, 5)
    full = cl.correlated(t, [itf], "nominal")
    for h in full:
        s = cl.simplify(h, tol)
        assert s.x.size < h.x.size and s.x.size >= 4
        assert set(zip(s.x, s.y, s.time)) <= set(zip(h.x, h.y, h.time))
        assert (s.x.max(), s.x.min(), s.y.max(), s.y.min()) == (h.x.max(), h.x.min(), h.y.max(), h.y.min())
        x = cl.pair_values(LABELS, itf.values, h.x_name) / np.ptp(h.x)
        y = cl.pair_values(LABELS, itf.values, h.y_name) / np.ptp(h.y)
        sx, sy = s.x / np.ptp(h.x), s.y / np.ptp(h.y)
        ex, ey = np.roll(sx, -1) - sx, np.roll(sy, -1) - sy
        outside = np.any(ex[:, None] * (y[None, :] - sy[:, None]) - ey[:, None] * (x[None, :] - sx[:, None]) < 0,
                         axis=0)
        d = _segment_distance(x[outside], y[outside], sx, sy)
        assert 0 <= s.shortfall <= tol
        assert d.size == 0 or d.max() <= s.shortfall * (1 + 1e-9) + 1e-12
    # tolerance 0 keeps the hull; a bad tolerance is refused
    assert cl.simplify(full[0], 0.0).x.size == full[0].x.size
    with pytest.raises(InputError, match="tolerance"):
        cl.simplify(full[0], -1.0)


def test_contour_of_a_disc_and_of_samples():
    """contour(support) against closed forms: a disc's support c . n + r gives the regular
    72-gon circumscribed about it (vertices at r / cos(pi / 72)); the contour of a history's
    support holds every sample and each of its edges touches the hull (h_k is attained)."""
    d = cl.directions()
    c, r = np.array([1.0e6, 3.0e6]), 2.0e6
    x, y = cl.contour(d @ c + r)
    assert x.size == 72
    np.testing.assert_allclose(np.hypot(x - c[0], y - c[1]), r / np.cos(np.pi / 72), rtol=1e-12)
    assert np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y) > 0          # counter-clockwise
    t = np.linspace(0, 5, 2001)
    itf = _itf(t, 6)
    names, h = cl.case_support([itf])
    assert names == ("attach p on core|axial-bending", "attach p on core|shear-torque")
    for j, (pair, xn, yn) in enumerate(cl.PAIRS):
        sx, sy = cl.pair_values(LABELS, itf.values, xn), cl.pair_values(LABELS, itf.values, yn)
        px, py = cl.contour(h[j])
        scale = max(np.abs(sx).max(), np.abs(sy).max())
        assert _inside(px, py, sx, sy, 1e-12 * scale * scale)
        np.testing.assert_allclose((np.column_stack([sx, sy]) @ d.T).max(axis=0), h[j], rtol=1e-14)
    # half-planes that hold no point, and bad direction counts
    assert cl.contour(np.full(72, -1.0))[0].size == 0
    with pytest.raises(InputError, match="multiple of 4"):
        cl.directions(30)


def test_campaign_contours_of_scaled_cases_are_the_scaled_support():
    """Over dispersed cases whose loads are one history scaled by a_i (a_i > 0, so h_i = a_i
    h), the aggregate's P99/90 normal contour is the support of (mean(a) + k std(a)) h and
    its order-statistic contour the r-th largest a_i times h: closed forms per direction
    from numpy's batch mean/std and a sort, against the streaming aggregate."""
    from liftoff.analysis.aggregate import Aggregate, contour_rows
    from liftoff.analysis.stats import k_factor, order_rank
    from liftoff.workflows.campaign import CaseSummary

    t = np.linspace(0, 5, 501)
    names, h = cl.case_support([_itf(t, 7)])
    h = h - h.min() + 1.0                   # positive in every direction (the origin inside), so h_i = a_i h
    n = 300
    a = np.random.default_rng(8).normal(1.0, 0.1, n)
    agg = Aggregate(n)
    one = np.zeros(1)
    for i, ai in enumerate(a):
        agg.add(CaseSummary(f"d{i:04d}", i, ("x",), ("N",), ("c",), one, one, one, one,
                            support_items=names, support=ai * h), generated=True)
    st = agg.support_statistics()
    k, r = k_factor(0.99, 0.90, n), order_rank(0.99, 0.90, n)
    assert r >= 1
    np.testing.assert_allclose(st["normal"], (a.mean() + k * a.std(ddof=1)) * h, rtol=1e-10)
    np.testing.assert_allclose(st["order"], np.sort(a)[::-1][r - 1] * h, rtol=1e-14)
    np.testing.assert_allclose(st["envelope"], a.max() * h, rtol=1e-14)
    rows = contour_rows(agg)
    assert {(r_["pair"], r_["contour"]) for r_ in rows} == {(p, c) for p, _, _ in cl.PAIRS
                                                             for c in ("envelope", "normal", "order")}


def test_support_in_blocks_equals_every_sample_at_once():
    """support() takes the samples in blocks of SUPPORT_ROWS (so that samples x directions stays
    in cache): over several blocks and a partial last one it equals the maximum over all the
    samples at once (to a few units of round-off: each value is a two-term dot product, x c + y s,
    whose BLAS kernel may or may not fuse its multiply-add in a partial block), and is attained
    by a sample; no samples is a one-line error."""
    rng = np.random.default_rng(3)
    n_s = 3 * cl.SUPPORT_ROWS + 17
    x, y = np.cumsum(rng.standard_normal(n_s)), 1e3 * np.cumsum(rng.standard_normal(n_s))
    x[cl.SUPPORT_ROWS] = 1e6                   # the largest x at the first sample of the second block
    y[-1] = 1e9                                # the largest y at the last sample of the partial block
    d = cl.directions()
    every = (np.column_stack([x, y / cl.MOMENT_ARM]) @ d.T).max(axis=0)
    h = cl.support(x, y)
    np.testing.assert_allclose(h, every, rtol=0, atol=4 * np.finfo(float).eps * np.abs(np.c_[x, y]).sum(axis=1).max())
    q = d.shape[0] // 4
    assert h[0] == 1e6 and h[q] == 1e9 / cl.MOMENT_ARM
    with pytest.raises(InputError, match="no samples"):
        cl.support(np.zeros(0), np.zeros(0))
