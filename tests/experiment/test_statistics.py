"""Bands, areas, crossings and rank tests across seeds."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flctool.experiment.statistics import (
    area,
    band,
    compare,
    first_crossing,
    halfway_level,
    quartiles,
)


def test_bands_stay_within_the_values_they_summarise() -> None:
    rng = np.random.default_rng(0)
    # two-peaked values in [0, 2), like ballchase trial fitness: mean + std would pass 2
    curves = [np.where(rng.random(30) < 0.5, 1.95, 0.05) for _ in range(7)]
    b = band(curves)
    table = np.array(curves)
    assert np.all(b.low >= table.min(axis=0)) and np.all(b.high <= table.max(axis=0))
    assert np.all(b.low <= b.median) and np.all(b.median <= b.high)
    assert np.all(b.n == 7)
    assert (table.mean(axis=0) + table.std(axis=0)).max() > 2.0


def test_bands_of_runs_of_different_lengths() -> None:
    b = band([np.array([1.0, 2.0, 3.0]), np.array([3.0])])
    assert b.n.tolist() == [2, 1, 1]
    assert b.median.tolist() == [2.0, 2.0, 3.0]


def test_quartiles_with_runs_that_never_reached() -> None:
    assert quartiles(np.array([1.0, 2.0, 3.0, 4.0, 5.0])) == (2.0, 3.0, 4.0)
    low, median, high = quartiles(np.array([10.0, 20.0, math.inf, math.inf]))
    assert (low, median, high) == (10.0, 20.0, math.inf)


def test_area_and_crossings() -> None:
    curve = np.array([0.2, 0.9, 0.6, 1.5])
    episodes = np.array([10.0, 20.0, 30.0, 40.0])
    assert area(curve) == pytest.approx(3.2)
    assert first_crossing(curve, episodes, 0.8) == 20.0
    assert first_crossing(curve, episodes, 2.0) == math.inf
    assert first_crossing(curve, episodes, 0.6, rising=False) == 10.0
    assert halfway_level(0.4, 1.8) == pytest.approx(1.1)
    assert halfway_level(0.8, 0.2) == pytest.approx(0.5)


def test_mann_whitney_with_effect_size() -> None:
    a = np.array([5.0, 6.0, 7.0, 8.0, 9.0])
    b = np.array([0.0, 1.0, 2.0, 3.0, 4.0])
    result = compare(a, b)
    assert result.u == 25.0 and result.effect == 1.0
    assert result.p_greater == pytest.approx(1 / 252)  # exact: 1 of C(10, 5) orderings
    assert result.p == pytest.approx(2 / 252)
    assert compare(b, a).effect == 0.0
    assert compare(b, a).p_greater == pytest.approx(1.0)


def test_never_reached_ranks_last_and_ties_give_no_evidence() -> None:
    result = compare(np.array([math.inf, math.inf, math.inf]), np.array([1.0, 2.0, 3.0]))
    assert result.effect == 1.0
    same = compare(np.array([1.0, 1.0]), np.array([1.0, 1.0]))
    assert (same.p, same.effect) == (1.0, 0.5)
