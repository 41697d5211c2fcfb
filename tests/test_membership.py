"""Trapezoid membership (Sec. II) equals scikit-fuzzy's trapmf, edges included."""

from __future__ import annotations

import numpy as np
import pytest
import skfuzzy

from flctool.membership import trapezoid, trapezoid_scalar


def _random_quads(rng: np.random.Generator, count: int) -> np.ndarray:
    quads = np.sort(rng.uniform(-5, 5, size=(count, 4)), axis=1)
    kind = rng.integers(0, 5, size=count)
    quads[kind == 1, 2] = quads[kind == 1, 1]  # triangle
    quads[kind == 2, 1] = quads[kind == 2, 0]  # vertical left edge
    quads[kind == 3, 3] = quads[kind == 3, 2]  # vertical right edge
    quads[kind == 4, 1] = quads[kind == 4, 0]  # a rectangle: both edges vertical
    quads[kind == 4, 3] = quads[kind == 4, 2]
    return quads


def test_equals_skfuzzy_trapmf_on_random_quadruples() -> None:
    rng = np.random.default_rng(1)
    quads = _random_quads(rng, 400)
    for quad in quads:
        # random points, plus the corners themselves where the edge cases live
        x = np.concatenate([rng.uniform(-6, 6, size=200), quad])
        expected = skfuzzy.trapmf(x, quad)
        np.testing.assert_array_equal(trapezoid(x, quad[None, :])[:, 0], expected)
        assert [trapezoid_scalar(v, *quad) for v in x] == expected.tolist()


@pytest.mark.parametrize(("quad", "x", "mu"), [
    ((0, 1, 1, 2), [0, 0.5, 1, 1.5, 2, 3], [0, 0.5, 1, 0.5, 0, 0]),  # triangle
    ((0, 0, 1, 2), [-1, 0, 0.5, 1.5], [0, 1, 1, 0.5]),  # vertical left edge: 1 from pa on
    ((0, 1, 2, 2), [1.5, 2, 2.0001], [1, 1, 0]),  # vertical right edge: 0 after pd
    ((0, 0, 0, 0), [-1, 0, 1], [0, 1, 0]),  # a single point
])
def test_documented_shapes(quad: tuple[float, ...], x: list[float], mu: list[float]) -> None:
    np.testing.assert_allclose(trapezoid(np.array(x), np.array([quad], float))[:, 0], mu)


@pytest.mark.slow
def test_the_scalar_form_gives_the_vectorised_bits() -> None:
    # The learners' one-value form and the array form are the one formula: same operations,
    # so the same bits, on random sets of every shape and values at and around their corners.
    from flctool.membership import firing_sets

    rng = np.random.default_rng(7)
    quads = _random_quads(rng, 300)
    corners = quads.ravel()
    x = np.concatenate([rng.uniform(-6, 6, size=2_000), corners,
                        np.nextafter(corners, -np.inf), np.nextafter(corners, np.inf)])
    dense = trapezoid(x, quads)
    sets = [tuple(q) for q in quads.tolist()]
    for row, value in zip(dense, x.tolist(), strict=True):
        fired = firing_sets(value, sets)
        assert [j for j, _ in fired] == np.flatnonzero(row > 0).tolist()
        assert [mu for _, mu in fired] == row[row > 0].tolist()


def test_float32_membership_rounds_each_operation_in_float() -> None:
    # The float C export's membership (what export.float_error measures): the same formula
    # with every operation rounded to float32.
    rng = np.random.default_rng(3)
    quads = _random_quads(rng, 50).astype(np.float32)
    x = rng.uniform(-6, 6, size=500).astype(np.float32)
    got = trapezoid(x, quads)
    assert got.dtype == np.float32
    f = np.float32
    for i, s in enumerate(x):
        for j, (pa, pb, pc, pd) in enumerate(quads):
            if s > pc:
                want = max(f(0), f(f(pd - s) / f(pd - pc))) if pd > pc else f(0)
            elif s < pb:
                want = max(f(0), f(f(s - pa) / f(pb - pa))) if pb > pa else f(0)
            else:
                want = f(1)
            assert got[i, j] == want
