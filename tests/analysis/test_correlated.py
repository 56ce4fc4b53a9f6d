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
