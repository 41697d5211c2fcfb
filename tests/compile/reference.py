"""A plain, loop-over-rules implementation of eq. 1-3: the reference the fast paths must match."""

from __future__ import annotations

import itertools

import numpy as np

from flctool.compile import Controller
from flctool.membership import trapezoid_scalar


def combine(controller: Controller, memberships: list[float]) -> float:
    """Eq. 2: the rule's memberships combined by their min, or with ``activation: product``
    multiplied one after the other in input order."""
    if not controller.product:
        return min(memberships)
    alpha = memberships[0]
    for mu in memberships[1:]:
        alpha = alpha * mu
    return alpha


def reference_output(controller: Controller, state: np.ndarray, consequents: np.ndarray) -> float:
    clipped = [min(max(float(s), lo), hi) for s, (lo, hi) in zip(state, controller.ranges,
                                                                  strict=True)]
    numerator = denominator = 0.0
    for m, sets in enumerate(itertools.product(*(range(len(q)) for q in controller.quadruples))):
        alpha = combine(controller, [trapezoid_scalar(clipped[i], *controller.quadruples[i][j])
                                     for i, j in enumerate(sets)])  # eq. 2
        numerator += alpha * controller.singletons[consequents[m]]
        denominator += alpha
    value = numerator / denominator  # eq. 3
    # a convex combination: only rounding can step past the singletons, and that is clipped
    return min(max(value, float(controller.singletons.min())),
               float(controller.singletons.max()))


def random_behaviour_data(rng: np.random.Generator, n_inputs: int | None = None,
                          n_commands: int | None = None, rules: bool = True,
                          activation: str = "min") -> dict:
    """A random valid behaviour: covering partitions with triangles, shoulders and vertical
    edges, random singletons, and (optionally) a complete random rule table; eq. 2 is
    ``activation`` (min, the paper's, or product)."""
    n_inputs = n_inputs or int(rng.integers(1, 4))
    inputs = {}
    for i in range(n_inputs):
        lo = float(rng.uniform(-10, 0))
        hi = lo + float(rng.uniform(0.5, 20))
        count = int(rng.integers(1, 5))
        # Peaks t_0 = lo < t_1 < ... < t_{L-1} = hi; set j spans (t_{j-1}, t_{j+1}), so every
        # point is inside some set's open support and the range is covered.
        peaks = np.concatenate([[lo], np.sort(rng.uniform(lo, hi, size=max(count - 2, 0))),
                                [hi]]) if count > 1 else np.array([lo, hi])
        sets = {}
        for j in range(count):
            pa = float(peaks[j - 1]) if j > 0 else lo
            pd = float(peaks[j + 1]) if j + 1 < len(peaks) and count > 1 else hi
            shape = int(rng.integers(0, 4))
            if shape == 0:  # triangle
                pb = pc = float(rng.uniform(pa, pd))
            elif shape == 1:  # trapezoid
                pb, pc = sorted(rng.uniform(pa, pd, size=2).tolist())
            elif shape == 2:  # vertical left edge
                pb, pc = pa, float(rng.uniform(pa, pd))
            else:  # vertical right edge
                pb, pc = float(rng.uniform(pa, pd)), pd
            if j == 0:  # the range's ends must have membership > 0: shoulders there
                pb = pa
            if j == count - 1:
                pc = pd
            sets[f"s{j}"] = [pa, pb, max(pb, pc), pd]
        inputs[f"x{i}"] = {"range": [lo, hi], "sets": sets}
    n_commands = n_commands or int(rng.integers(1, 6))
    commands = {f"c{k}": float(rng.uniform(-5, 5)) for k in range(n_commands)}
    data = {"flctool": 1, "name": "random", "inputs": inputs,
            "output": {"name": "y", "commands": commands}, "activation": activation}
    if rules:
        names = list(inputs)
        data["rules"] = [
            {"if": dict(zip(names, combo, strict=True)),
             "then": f"c{int(rng.integers(n_commands))}"}
            for combo in itertools.product(*(list(v["sets"]) for v in inputs.values()))]
    return data
