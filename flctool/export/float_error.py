"""The float C export's error, measured when it is exported.

The C source computes eq. 1-3 in ``float`` with flctool's formulas and order of operations
(see :mod:`flctool.export.c_source`). Here the same arithmetic runs in numpy ``float32``, step
by step (IEEE single precision rounds each operation as C's ``float`` does where
``FLT_EVAL_METHOD`` is 0, as on x86-64 and ARM), on a grid of states, and is compared with
flctool's double output. The documented bound is :data:`FLOAT_BOUND` times the largest
|command| (at least 1); a controller beyond it is refused: narrow ranges at large magnitudes
lose most of float's 24 bits.
"""

from __future__ import annotations

import numpy as np

from flctool.behaviour import Behaviour
from flctool.behaviour.shapes import trapezoids
from flctool.compile import compile_behaviour
from flctool.compile.defuzzify import centre_of_area
from flctool.errors import ExportError
from flctool.membership import trapezoid

#: The float export's documented bound, relative to max(1, largest |command|).
FLOAT_BOUND = 1e-5
#: How many (rule, state) pairs the measurement may evaluate: it stays within about a second.
WORK = 20_000_000
#: The most states it measures on (a small controller gets this many).
MAX_STATES = 200_000
F32 = np.float32


def grid_states(behaviour: Behaviour) -> np.ndarray:
    """(S, N) float-representable states: each input takes, half the time, a value from 257
    points across its range, its ends, every set corner and the floats next to them, and
    otherwise a uniform random float in its range, combined at random (seed 0; S shrinks
    with the number of rules, from 200,000 to at least 1,000)."""
    count = int(min(MAX_STATES, max(1_000, WORK // behaviour.rule_count)))
    rng = np.random.default_rng(0)
    columns = []
    for variable in behaviour.inputs.values():
        lo, hi = variable.range
        points = np.array([*np.linspace(lo, hi, 257), *(x for q in variable.sets.values()
                                                       for x in q)], dtype=F32)
        points = np.concatenate([points, np.nextafter(points, F32(-np.inf)),
                                 np.nextafter(points, F32(np.inf))])
        points = points[(points >= F32(lo)) & (points <= F32(hi))]
        column = rng.choice(np.unique(points), count)
        # half the states anywhere in the range: the largest errors lie between grid points
        spread = rng.random(count) < 0.5
        column[spread] = np.clip(rng.uniform(lo, hi, int(spread.sum())).astype(F32),
                                 F32(lo), F32(hi))
        columns.append(column)
    return np.column_stack(columns).astype(np.float64)


def float_outputs(behaviour: Behaviour, states: np.ndarray) -> np.ndarray:
    """(S,) the float C export's outputs for (S, N) ``states`` (rounded to float)."""
    controller = compile_behaviour(behaviour)
    memberships = []
    for i, variable in enumerate(behaviour.inputs.values()):
        lo, hi = (F32(v) for v in variable.range)
        s = states[:, i].astype(F32)
        s = np.where(s < lo, lo, np.where(s > hi, hi, s))
        memberships.append(trapezoid(s, np.array(list(variable.sets.values()), dtype=F32)))
    singletons = controller.singletons.astype(F32)
    assert controller.consequents is not None  # a deployable behaviour has every rule
    with np.errstate(divide="ignore", invalid="ignore"):
        out = centre_of_area(((_activation(memberships, sets, controller.product),
                               singletons[controller.consequents[m]])
                              for m, sets in enumerate(controller.rule_grid.tolist())),
                             np.zeros(len(states), dtype=F32))  # rule order, eq. 1
    clipped: np.ndarray = np.clip(out, singletons.min(), singletons.max())
    return clipped.astype(np.float64)


def _activation(memberships: list[np.ndarray], sets: list[int], product: bool) -> np.ndarray:
    """One rule's activation over the states: the minimum of its sets' memberships (eq. 2),
    or with ``product`` their product in input order, in float as the C source computes it."""
    alpha = memberships[0][:, sets[0]]
    for i in range(1, len(sets)):
        mu = memberships[i][:, sets[i]]
        alpha = alpha * mu if product else np.minimum(alpha, mu)
    return alpha


def near_vertical_edges(behaviour: Behaviour, states: np.ndarray) -> np.ndarray:
    """(S,) True where an input lies within two float ulps of a vertical edge inside its
    range: rounding the edge to float moves it, so there the two outputs differ by a jump."""
    near = np.zeros(len(states), dtype=bool)
    for i, variable in enumerate(behaviour.inputs.values()):
        lo, hi = variable.range
        quads = trapezoids(variable.sets.values())  # (the float export refuses other shapes)
        edges = [pa for pa, pb, _, _ in quads if pa == pb and pa > lo]
        edges += [pd for _, _, pc, pd in quads if pc == pd and pd < hi]
        for edge in edges:
            width = 2 * float(np.spacing(F32(abs(edge)))) + abs(float(F32(edge)) - edge)
            near |= np.abs(states[:, i] - edge) <= width
    return near


def check_float_error(behaviour: Behaviour) -> tuple[float, float, int]:
    """(largest error, bound, states measured); refuses an export beyond the bound.

    Left out of the maximum: states within two float ulps of a vertical edge inside a range
    (:func:`near_vertical_edges`), and states where the float controller gives NaN (every
    membership underflowing to 0, as the C source documents).
    """
    states = grid_states(behaviour)
    want = compile_behaviour(behaviour).output(states)
    got = float_outputs(behaviour, states)
    gap = np.abs(got - want)
    finite = np.isfinite(gap) & ~near_vertical_edges(behaviour, states)
    error = float(np.max(gap[finite])) if finite.any() else 0.0
    scale = max(1.0, float(np.max(np.abs(list(behaviour.output.commands.values())))))
    bound = FLOAT_BOUND * scale
    if error > bound:
        row = int(np.argmax(np.where(finite, gap, -1.0)))
        state = ", ".join(f"{name}={states[row, i]!r}"
                          for i, name in enumerate(behaviour.inputs))
        raise ExportError(
            f"in float, the controller differs from flctool's double output by up to "
            f"{error:.3g} (at {state}), beyond the float export's bound of {bound:.3g} "
            f"({FLOAT_BOUND:g} of the largest command)",
            hint="export without --float (double arithmetic), or move the ranges and "
            "commands closer to 0 (float keeps 24 bits of each number)")
    return error, bound, len(states)
