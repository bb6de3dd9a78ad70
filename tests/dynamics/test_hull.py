"""The exact cross-flow drag integral against brute-force quadrature."""

from __future__ import annotations

import numpy as np
import pytest

from subenv.dynamics import HullTable, crossflow_integrals
from subenv.dynamics.hull import hull_segment


def _quadrature(vehicle, w: float, q: float, n: int = 400001) -> tuple[float, float]:
    x = np.asarray(vehicle.hull.x_m)[::-1]
    b = np.asarray(vehicle.hull.breadth_m)[::-1]
    # Dense grid including every station so that b is exactly piecewise linear on it.
    fine = np.union1d(np.linspace(x[0], x[-1], n), x)
    bf = np.interp(fine, x, b)
    f = w - fine * q
    g = bf * f * np.abs(f)
    return float(np.trapezoid(g, fine)), float(np.trapezoid(fine * g, fine))


@pytest.mark.parametrize(
    ("w", "q"),
    [
        (0.1, 0.0),
        (-0.2, 0.0),
        (0.0, 0.05),
        (0.0, -0.05),
        (0.05, 0.1),
        (-0.05, 0.1),
        (0.3, -0.02),
        (0.01, 0.2),
        (-0.4, -0.3),
        (0.0, 0.0),
    ],
)
def test_exact_integral_matches_quadrature(suboff, w, q):
    table = HullTable.from_offsets(suboff.hull.x_m, suboff.hull.breadth_m)
    I0, I1 = crossflow_integrals(table, w, q)
    Q0, Q1 = _quadrature(suboff, w, q)
    scale = (abs(w) + abs(q) * suboff.length_m) ** 2 * suboff.hull_area_m2 + 1e-30
    assert float(I0) == pytest.approx(Q0, abs=1e-8 * scale)
    assert float(I1) == pytest.approx(Q1, abs=1e-8 * scale * suboff.length_m)


def test_pure_heave_gives_area_and_centroid(suboff):
    table = HullTable.from_offsets(suboff.hull.x_m, suboff.hull.breadth_m)
    I0, I1 = crossflow_integrals(table, 0.2, 0.0)
    assert float(I0) == pytest.approx(0.04 * suboff.hull_area_m2, rel=1e-12)
    assert float(I1) == pytest.approx(0.04 * suboff.hull_area_m2 * suboff.hull_centroid_x_m, rel=1e-10)


def test_batched_equals_elementwise(suboff):
    table = HullTable.from_offsets(suboff.hull.x_m, suboff.hull.breadth_m)
    rng = np.random.default_rng(0)
    w = rng.normal(0, 0.2, size=(7, 5))
    q = rng.normal(0, 0.1, size=(7, 5))
    q[0, 0] = 0.0
    I0, I1 = crossflow_integrals(table, w, q)
    assert I0.shape == (7, 5)
    for i in range(7):
        for j in range(5):
            a, b = crossflow_integrals(table, w[i, j], q[i, j])
            assert I0[i, j] == a and I1[i, j] == b


def test_segment_search_is_searchsorted_and_the_count_of_stations_aft(suboff):
    table = HullTable.from_offsets(suboff.hull.x_m, suboff.hull.breadth_m)
    x, n_seg = table.x, table.x.size - 1
    mids = (x[:-1] + x[1:]) / 2
    s = np.concatenate([x, np.nextafter(x, -np.inf), np.nextafter(x, np.inf), mids, [-10.0, 10.0, np.nan]])
    found = np.array([hull_segment(v, table.packed) for v in s])
    with np.errstate(invalid="ignore"):
        expected = np.clip(np.searchsorted(x, s, side="right") - 1, 0, n_seg - 1)
        counted = np.array([np.count_nonzero(x[1:n_seg] <= v) for v in s])  # the block integrator's way
    expected[np.isnan(s)] = 0
    np.testing.assert_array_equal(found, expected)
    np.testing.assert_array_equal(found, counted)
