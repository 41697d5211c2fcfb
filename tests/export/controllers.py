"""Random deployable controllers for the round-trip tests: varied N, L_i and K, sets with
triangles, plateaus and vertical edges (inside the range and at its ends), odd floats."""

from __future__ import annotations

from typing import Any

import numpy as np

from flctool import with_rules
from flctool.behaviour import Behaviour, behaviour_from_data, behaviour_to_data
from flctool.behaviour.shapes import set_row


def _partition(rng: np.random.Generator, lo: float, hi: float, count: int
               ) -> list[list[float]]:
    """``count`` trapezoids covering [lo, hi]: cores in order, each boundary a ramp crossing,
    a vertical left edge, a vertical right edge, or (cores touching) both."""
    if count == 1:
        return [[lo, lo, hi, hi]]
    xs = np.sort(rng.uniform(lo, hi, 2 * count - 2)).tolist()
    xs = [lo, *xs, hi]
    for j in range(count):  # some cores shrink to a point: triangles
        if rng.random() < 0.4:
            if j == count - 1:  # the last core keeps reaching the range's end
                xs[2 * j] = xs[2 * j + 1]
            else:
                xs[2 * j + 1] = xs[2 * j]
    if rng.random() < 0.3:  # cores that touch: both edges vertical
        j = int(rng.integers(1, count))
        xs[2 * j] = xs[2 * j - 1]
    sets = [[0.0, xs[2 * j], xs[2 * j + 1], 0.0] for j in range(count)]
    sets[0][0] = lo
    sets[-1][3] = hi
    for j in range(1, count):
        left_core_end, right_core_start = xs[2 * j - 1], xs[2 * j]
        style = rng.integers(3) if right_core_start > left_core_end else 3
        if style == 0:  # ramps crossing
            sets[j - 1][3], sets[j][0] = right_core_start, left_core_end
        elif style == 1:  # vertical left edge of set j
            sets[j - 1][3], sets[j][0] = right_core_start, right_core_start
        elif style == 2:  # vertical right edge of set j - 1
            sets[j - 1][3], sets[j][0] = left_core_end, left_core_end
        else:
            sets[j - 1][3], sets[j][0] = left_core_end, right_core_start
    return sets


def random_behaviour(seed: int, max_inputs: int = 4, max_sets: int = 4,
                     min_inputs: int = 1, activation: str = "min") -> Behaviour:
    """A deployable behaviour drawn from ``seed``, combining memberships by ``activation``."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(min_inputs, max_inputs + 1))
    inputs: dict[str, Any] = {}
    for i in range(n):
        lo = float(rng.normal(0, 50))
        hi = lo + float(rng.uniform(1e-3, 100))
        count = int(rng.integers(1, max_sets + 1))
        inputs[f"x{i}"] = {"range": [lo, hi],
                           "sets": {f"s{j}": q for j, q in
                                    enumerate(_partition(rng, lo, hi, count))}}
    k = int(rng.integers(1, 7))
    commands = {f"c{j}": float(rng.normal(0, 10)) for j in range(k)}
    behaviour = behaviour_from_data({"flctool": 1, "name": f"random_{seed}", "inputs": inputs,
                                     "output": {"name": "u", "commands": commands},
                                     "activation": activation})
    return with_rules(behaviour, rng.integers(0, k, behaviour.rule_count))


def random_states(behaviour: Behaviour, count: int, seed: int, margin: float = 0.2
                  ) -> np.ndarray:
    """(count, N) states reaching ``margin`` of each range beyond both ends, and the ends and
    set corners themselves, where the membership functions change their formula."""
    rng = np.random.default_rng(seed)
    columns = []
    for variable in behaviour.inputs.values():
        lo, hi = variable.range
        width = hi - lo
        column = rng.uniform(lo - margin * width, hi + margin * width, count)
        corners = np.array([lo, hi, *(x for q in variable.sets.values() for x in set_row(q)[1]
                                      if lo <= x <= hi)])
        pick = rng.random(count) < 0.1
        column[pick] = rng.choice(corners, int(pick.sum()))
        columns.append(column)
    return np.column_stack(columns)


def with_product(behaviour: Behaviour) -> Behaviour:
    """``behaviour`` with ``activation: product`` (eq. 2 as the product), validated anew."""
    return behaviour_from_data({**behaviour_to_data(behaviour), "activation": "product"})
