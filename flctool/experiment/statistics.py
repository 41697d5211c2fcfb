"""Statistics across the seeds of an experiment: bands, areas, crossing times and rank tests.

Bands are quantiles of the runs' own values (median and inter-quartile range), so they never
leave the range the measured quantity can take -- unlike mean +- std, which for fitness in
[0, 2) can reach past 2.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class Band:
    """Median and quartiles across runs at each point of a curve, each (G,); ``n`` (G,) is
    how many runs have that point."""

    low: FloatArray
    median: FloatArray
    high: FloatArray
    n: NDArray[np.int64]


def band(curves: list[FloatArray]) -> Band:
    """Quartiles across runs of curves that may differ in length (a run stopped early has no
    later points): point g uses the runs that reached it."""
    length = max(len(c) for c in curves)
    table = np.full((len(curves), length), np.nan)
    for row, curve in enumerate(curves):
        table[row, : len(curve)] = curve
    n = np.sum(~np.isnan(table), axis=0).astype(np.int64)
    low, median, high = np.nanpercentile(table, [25, 50, 75], axis=0)
    return Band(low, median, high, n)


def quartiles(values: FloatArray) -> tuple[float, float, float]:
    """(25th percentile, median, 75th percentile) of finite and infinite values alike."""
    data = np.sort(np.asarray(values, dtype=np.float64))
    q = [float(np.percentile(data, p, method="inverted_cdf")) if np.isinf(data).any()
         else float(np.percentile(data, p)) for p in (25, 50, 75)]
    return q[0], q[1], q[2]


def area(curve: FloatArray) -> float:
    """Area under a per-generation curve: the sum of its values, one unit of width per
    generation (each generation is the same number of episodes)."""
    return float(np.sum(curve))


def first_crossing(curve: FloatArray, episodes: FloatArray, level: float,
                   rising: bool = True) -> float:
    """Episodes (cumulative, at the end of the generation) when ``curve`` first reaches
    ``level`` (>= when rising, <= when falling); ``inf`` if it never does."""
    reached = curve >= level if rising else curve <= level
    hits = np.flatnonzero(reached)
    return float(episodes[hits[0]]) if hits.size else math.inf


def halfway_level(start: float, end: float) -> float:
    """The level half way from ``start`` to ``end`` (a curve's half-rise or half-fall)."""
    return start + 0.5 * (end - start)


@dataclass(frozen=True)
class Comparison:
    """Mann-Whitney U test of samples a and b: U of a, two-sided p, one-sided p (a > b), and
    the effect size A = P(a > b) + P(a = b) / 2 (Vargha and Delaney's A12, 0.5: no effect)."""

    u: float
    p: float
    p_greater: float
    effect: float
    n_a: int
    n_b: int


def compare(a: FloatArray, b: FloatArray) -> Comparison:
    """Mann-Whitney U test (scipy, exact or normal approximation as scipy picks) of a vs b."""
    from scipy.stats import mannwhitneyu

    x = np.asarray(a, dtype=np.float64)
    y = np.asarray(b, dtype=np.float64)
    if x.size == 0 or y.size == 0:
        return Comparison(math.nan, math.nan, math.nan, math.nan, x.size, y.size)
    # inf (never reached) ranks above every finite value, as it should; scipy needs finite
    # input, so it becomes a value above all of them.
    finite = np.concatenate([x, y])
    finite = finite[np.isfinite(finite)]
    top = (float(finite.max()) + 1.0) if finite.size else 1.0
    x, y = np.where(np.isposinf(x), top, x), np.where(np.isposinf(y), top, y)
    if np.all(x == x[0]) and np.all(y == x[0]):  # all equal: no evidence either way
        return Comparison(x.size * y.size / 2, 1.0, 0.5, 0.5, x.size, y.size)
    two = mannwhitneyu(x, y, alternative="two-sided")
    greater = mannwhitneyu(x, y, alternative="greater")
    u = float(two.statistic)
    return Comparison(u, float(two.pvalue), float(greater.pvalue), u / (x.size * y.size),
                      x.size, y.size)
