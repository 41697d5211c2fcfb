"""Mamdani outputs as singletons: a conversion done only on request, with its error measured.

A Mamdani controller's output sets (triangles, trapezoids) are clipped at each rule's
activation (implication by minimum), merged by maximum, and defuzzified by the centroid.
flctool's commands are singletons (eq. 3). ``flctool import FILE --mamdani-singletons``
replaces each output set by a singleton at its centroid, and measures how far the converted
controller's output is from the Mamdani one on a grid of states: the report gives the largest
difference, so the user decides whether the approximation is good enough.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from flctool.compile import compile_behaviour
from flctool.compile.membership import trapezoid
from flctool.spec import Behaviour
from flctool.spec.shapes import set_row

Quad = tuple[float, float, float, float]
#: How many states the deviation is measured on (besides every range's ends and corners).
STATES = 4_000


def centroid(quad: Quad) -> float:
    """The centroid of the trapezoid ``(a, b, c, d)`` (its membership's centre of area)."""
    a, b, c, d = quad
    denominator = 3.0 * (c + d - a - b)
    if denominator == 0:
        return a
    return ((c * c + c * d + d * d) - (a * a + a * b + b * b)) / denominator


@dataclass(frozen=True)
class Conversion:
    """What converting a Mamdani output changed, measured: ``deviation`` is the largest
    |converted - Mamdani| output over ``states`` states; ``span`` the output range's width."""

    deviation: float
    states: int
    span: float
    resolution: int

    def report(self) -> str:
        share = f" ({self.deviation / self.span:.2%} of the output range)" if self.span else ""
        return (f"Mamdani output sets replaced by singletons at their centroids: the largest "
                f"difference from the Mamdani output (centroid over {self.resolution} "
                f"midpoints, as fuzzylite computes it) is {self.deviation:.4g}{share}, "
                f"measured on {self.states} states")


def mamdani_outputs(behaviour: Behaviour, sets: Mapping[str, Quad], states: np.ndarray,
                    output_range: tuple[float, float], resolution: int) -> np.ndarray:
    """(S,) the Mamdani output for (S, N) ``states``: each rule's activation (eq. 2) clips
    its command's set, the clipped sets merge by maximum, and the output is their centroid
    over ``resolution`` midpoints of ``output_range`` (as fuzzylite computes it)."""
    controller = compile_behaviour(behaviour)
    alpha = controller.activations(states)  # (S, M)
    assert controller.consequents is not None
    names = list(behaviour.output.commands)
    lo, hi = output_range
    dx = (hi - lo) / resolution
    y = np.asarray(lo + (np.arange(resolution) + 0.5) * dx, dtype=np.float64)
    strength = np.zeros((len(states), len(names)))
    for k in range(len(names)):  # the strongest rule of each command: max aggregation
        rules = controller.consequents == k
        if rules.any():
            strength[:, k] = alpha[:, rules].max(axis=1)
    shapes = trapezoid(y, np.array([sets[n] for n in names], dtype=np.float64))
    shapes = np.asarray(shapes).reshape(len(y), len(names))  # (Y, K)
    merged = np.max(np.minimum(strength[:, None, :], shapes[None, :, :]), axis=2)  # (S, Y)
    with np.errstate(invalid="ignore", divide="ignore"):
        result: np.ndarray = (merged @ y) / merged.sum(axis=1)
    return result


def measure(behaviour: Behaviour, sets: Mapping[str, Quad], output_range: tuple[float, float],
            resolution: int) -> Conversion:
    """The converted controller against the Mamdani one, on random states in the ranges
    (seed 0) and on every range end and set corner."""
    rng = np.random.default_rng(0)
    columns = []
    for variable in behaviour.inputs.values():
        lo, hi = variable.range
        corners = np.array([lo, hi, *(x for q in variable.sets.values()
                                      for x in set_row(q)[1] if lo <= x <= hi)])
        column = rng.uniform(lo, hi, STATES)
        column[: len(corners)] = corners
        columns.append(column)
    states = np.column_stack(columns)
    want = mamdani_outputs(behaviour, sets, states, output_range, resolution)
    got = compile_behaviour(behaviour).output(states)
    finite = np.isfinite(want)
    deviation = float(np.max(np.abs(got[finite] - want[finite]))) if finite.any() else 0.0
    return Conversion(deviation, len(states), output_range[1] - output_range[0], resolution)
