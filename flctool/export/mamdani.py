"""Mamdani outputs as singletons: a conversion done only on request, with its error measured.

A Mamdani controller's output sets are implied by each rule's activation (clipped by the
minimum, or scaled by the product), aggregated by the maximum (or the algebraic sum), and
defuzzified by the centroid over ``resolution`` midpoints of the output range, as fuzzylite
computes it. flctool's commands are singletons (eq. 3). ``flctool import FILE
--mamdani-singletons`` replaces each output set by a singleton at its centroid, and measures
how far the converted controller's output is from the Mamdani one on a dense grid of states:
the report gives the largest difference, so the user decides whether the approximation is
good enough.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from flctool.behaviour import Behaviour
from flctool.behaviour.shapes import set_row
from flctool.compile import compile_behaviour
from flctool.export.imported import ImportedController, OriginalRule, as_written
from flctool.membership import memberships

Quad = tuple[float, float, float, float]
#: How many random states the deviation is measured on (besides every range's ends, every
#: set parameter inside a range, and a grid of GRID_POINTS per input across the ranges).
STATES = 4_000
GRID_POINTS = 41
#: The implications and aggregations the measurement computes (fuzzylite's names).
IMPLICATIONS = ("Minimum", "AlgebraicProduct")
AGGREGATIONS = ("Maximum", "AlgebraicSum")


def centroid(quad: Quad) -> float:
    """The centroid of the trapezoid ``(a, b, c, d)`` (its membership's centre of area)."""
    a, b, c, d = quad
    denominator = 3.0 * (c + d - a - b)
    if denominator == 0:
        return a
    return ((c * c + c * d + d * d) - (a * a + a * b + b * b)) / denominator


@dataclass(frozen=True)
class MamdaniOutput:
    """A Mamdani output as read: each command's set (shape code and row, as
    :func:`flctool.behaviour.shapes.set_row` gives them), the output range, the centroid's
    resolution, the implication and the aggregation."""

    sets: Mapping[str, tuple[int, Quad]]
    range: tuple[float, float]
    resolution: int
    implication: str = "Minimum"
    aggregation: str = "Maximum"
    #: The rules as the file writes them (:func:`flctool.export.imported.as_written`): the
    #: Mamdani output is computed from them, so that OR rules and rules that leave out an
    #: input (expanded over the sets), weights and a product conjunction (which the
    #: converted controller does not have) are part of what is measured. Empty: the
    #: behaviour's rules, which are then the file's.
    rules: tuple[OriginalRule, ...] = ()
    #: Whether the behaviour's rules differ from ``rules`` (said in the report).
    rewritten: bool = False
    #: How a rule's conditions combine: Minimum (eq. 2) or AlgebraicProduct.
    conjunction: str = "Minimum"

    def midpoints(self) -> np.ndarray:
        lo, hi = self.range
        dx = (hi - lo) / self.resolution
        return np.asarray(lo + (np.arange(self.resolution) + 0.5) * dx, dtype=np.float64)

    def singleton(self, name: str) -> float:
        """The singleton replacing set ``name``: a trapezoid's centroid, or, for another
        shape, its centroid over the midpoints of the output range (as fuzzylite computes a
        centroid); a set with no area there keeps its parameters' mean."""
        code, row = self.sets[name]
        if code == 0:
            return centroid(row)
        y = self.midpoints()
        mu = memberships(y, np.array([row]), [code])[:, 0]
        area = float(mu.sum())
        return float(mu @ y) / area if area > 0 else float(np.mean(row))


def mamdani_outputs(behaviour: Behaviour, output: MamdaniOutput, states: np.ndarray
                    ) -> np.ndarray:
    """(S,) the Mamdani output for (S, N) ``states``: each rule's activation (eq. 2) implies
    its command's set, the implied sets aggregate, and the output is their centroid over
    the midpoints of the output range (as fuzzylite computes it); NaN where no rule fires."""
    controller = compile_behaviour(behaviour)
    names = list(behaviour.output.commands)
    if output.rules:
        names = list(output.sets)  # (merged commands of the behaviour are not the file's)
        alpha, consequents = written_activations(behaviour, output, names, states)
    else:
        alpha = controller.activations(states)  # (S, M)
        assert controller.consequents is not None  # measured for complete rule bases only
        consequents = controller.consequents
    y = output.midpoints()
    rows = np.array([output.sets[n][1] for n in names], dtype=np.float64)
    shapes = memberships(y, rows, [output.sets[n][0] for n in names])  # (Y, K)
    result = np.empty(len(states))
    chunk = max(1, 2_000_000 // max(1, len(y) * alpha.shape[1]))
    for start in range(0, len(states), chunk):
        a = alpha[start:start + chunk]
        merged = np.zeros((len(a), len(y)))
        for m in np.flatnonzero(a.any(axis=0)):  # rules in order; one that never fires adds 0
            mu = shapes[:, consequents[m]][None, :]
            implied = (np.minimum(a[:, m, None], mu) if output.implication == "Minimum"
                       else a[:, m, None] * mu)
            merged = (np.maximum(merged, implied) if output.aggregation == "Maximum"
                      else merged + implied - merged * implied)
        with np.errstate(invalid="ignore", divide="ignore"):
            result[start:start + chunk] = (merged @ y) / merged.sum(axis=1)
    return result


def written_activations(behaviour: Behaviour, output: MamdaniOutput, names: list[str],
                        states: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(S, R) each written rule's activation, as fuzzylite and MATLAB compute it: its weight
    times the minimum (eq. 2) or product of its conditions' memberships (1 - mu for NOT), or
    their maximum for an OR rule; and (R,) the index in ``names`` of each rule's command."""
    alpha = rule_activations(behaviour, output.rules, output.conjunction, states)
    return alpha, np.array([names.index(c) for _, _, c, _ in output.rules])


def rule_activations(behaviour: Behaviour, rules: Sequence[OriginalRule], conjunction: str,
                     states: np.ndarray) -> np.ndarray:
    """(S, R) each rule's activation as written (see :func:`written_activations`), with the
    conjunction ``conjunction`` (fuzzylite's name: Minimum or AlgebraicProduct)."""
    controller = compile_behaviour(behaviour)
    mus = controller.memberships(states)  # per input, (S, L_i)
    inputs = {name: (i, list(v.sets)) for i, (name, v) in enumerate(behaviour.inputs.items())}
    combine = (np.multiply.reduce if conjunction == "AlgebraicProduct"
               else np.minimum.reduce)
    alpha = np.empty((len(states), len(rules)))
    for r, (conditions, disjunction, _, weight) in enumerate(rules):
        columns = [mus[inputs[n][0]][:, inputs[n][1].index(t)] for n, t, _ in conditions]
        columns = [1.0 - c if negated else c
                   for c, (_, _, negated) in zip(columns, conditions, strict=True)]
        alpha[:, r] = weight * (np.maximum.reduce(columns) if disjunction
                                else combine(columns))
    return alpha


def round_up(x: float) -> float:
    """``x`` rounded up to 4 significant digits, as a report states a measured deviation
    (never below it)."""
    if not (math.isfinite(x) and x > 0):
        return x
    step = 10.0 ** (math.floor(math.log10(x)) - 3)
    stated = math.ceil(x / step) * step
    return stated if stated >= x else math.nextafter(stated, math.inf)


@dataclass(frozen=True)
class Conversion:
    """What converting a Mamdani output changed, measured: ``deviation`` is the largest
    |converted - Mamdani| output over ``states`` states; ``span`` the output range's width."""

    deviation: float
    states: int
    span: float
    resolution: int
    expanded: bool = False

    def stated(self) -> float:
        """The deviation rounded up to 4 significant digits, as the report states it (never
        below the measured one)."""
        return round_up(self.deviation)

    def report(self) -> str:
        stated = self.stated()
        share = f" ({stated / self.span:.2%} of the output range)" if self.span else ""
        expanded = (" (and the rules rewritten as flctool's: OR, NOT and rules that leave "
                    "out an input expanded over the sets, a combination given several "
                    "commands given their mean, weights and a product conjunction dropped; "
                    "measured against the rules as written)" if self.expanded else "")
        return (f"Mamdani output sets replaced by singletons at their centroids{expanded}: "
                f"the largest difference from the Mamdani output (centroid over "
                f"{self.resolution} midpoints, as fuzzylite computes it) is {stated:.4g}"
                f"{share}, measured on {self.states} states")


def measurement_states(behaviour: Behaviour, seed: int = 0) -> np.ndarray:
    """The states the deviation is measured on: random ones in the ranges (``seed``), every
    range end and set parameter inside a range, and a grid across the ranges."""
    rng = np.random.default_rng(seed)
    columns = []
    for variable in behaviour.inputs.values():
        lo, hi = variable.range
        special = [lo, hi, *(x for q in variable.sets.values() for x in set_row(q)[1]
                             if lo <= x <= hi), *np.linspace(lo, hi, GRID_POINTS)]
        column = rng.uniform(lo, hi, STATES)
        picks = rng.random(STATES) < 0.25  # a quarter of each input's values on them
        column[picks] = rng.choice(np.array(special), int(picks.sum()))
        column[: len(special)] = special
        columns.append(column)
    return np.column_stack(columns)


def measure(behaviour: Behaviour, output: MamdaniOutput) -> Conversion:
    """The converted controller against the Mamdani one: on :func:`measurement_states`, on
    :func:`grid_states`, and on the states :func:`climbed` finds from the worst of them."""
    controller = compile_behaviour(behaviour)

    def difference(at: np.ndarray) -> np.ndarray:
        gap = np.abs(controller.output(at) - mamdani_outputs(behaviour, output, at))
        return np.where(np.isfinite(gap), gap, 0.0)

    states = np.vstack([measurement_states(behaviour), grid_states(behaviour, MAMDANI_GRID)])
    states = np.vstack([states, climbed(difference, states, behaviour)])
    deviation = float(np.max(difference(states)))
    lo, hi = output.range
    return Conversion(deviation, len(states), hi - lo, output.resolution,
                      output.rewritten or output.conjunction != "Minimum")


#: The most states :func:`grid_states` gives.
GRID_STATES = 20_000


def grid_states(behaviour: Behaviour, most: int = GRID_STATES) -> np.ndarray:
    """Every combination of each input's range ends and set parameters inside its range
    (where the differences have their kinds), and of points evenly across it, as many as
    ``most`` allows; none when the parameters alone exceed it."""
    axes = []
    for variable in behaviour.inputs.values():
        lo, hi = variable.range
        axes.append(sorted({lo, hi, *(x for q in variable.sets.values()
                                      for x in set_row(q)[1] if lo <= x <= hi)}))
    size = math.prod(len(a) for a in axes)
    if size > most:
        return np.empty((0, len(axes)))
    factor = (most / size) ** (1 / len(axes))  # how much longer each axis may get
    for i, variable in enumerate(behaviour.inputs.values()):
        across = int(len(axes[i]) * factor)  # points evenly across the range
        if across > 2:
            axes[i] = sorted({*axes[i], *np.linspace(*variable.range, across)})
    while math.prod(len(a) for a in axes) > most:  # (the union may add fewer)
        longest = max(range(len(axes)), key=lambda k: len(axes[k]))
        axes[longest] = axes[longest][::2] + ([axes[longest][-1]]
                                             if len(axes[longest]) % 2 == 0 else [])
    mesh = np.meshgrid(*[np.asarray(a, dtype=np.float64) for a in axes], indexing="ij")
    return np.column_stack([m.ravel() for m in mesh])


#: The hill climb towards the largest difference: from how many of the worst states, how
#: many rounds, and how many steps around each per round.
CLIMBERS, CLIMB_ROUNDS, CLIMB_STEPS = 32, 40, 32
#: Climbers start from the worst of this many states, each at least APART (a share of each
#: range) from the others.
CANDIDATES, APART = 4_000, 0.1


def climbed(difference: Callable[[np.ndarray], np.ndarray], states: np.ndarray,
            behaviour: Behaviour) -> np.ndarray:
    """States where ``difference`` is larger than at ``states``, found by climbing from the
    worst of them (random steps, shrinking, inside the ranges; seed 2): a sample's largest
    difference falls short of the largest one between its states, more so with more
    inputs."""
    rng = np.random.default_rng(2)
    ranges = np.array([v.range for v in behaviour.inputs.values()], dtype=np.float64)
    gaps = difference(states)
    # from the worst states that lie apart (each its own hill, not all on the highest one)
    span = np.where(ranges[:, 1] > ranges[:, 0], ranges[:, 1] - ranges[:, 0], 1.0)
    scaled = (states - ranges[:, 0]) / span
    order: list[int] = []
    for k in np.argsort(gaps)[::-1][:CANDIDATES]:
        if all(np.max(np.abs(scaled[k] - scaled[j])) > APART for j in order):
            order.append(int(k))
            if len(order) == CLIMBERS:
                break
    points, best = states[order].copy(), gaps[order].copy()
    width = (ranges[:, 1] - ranges[:, 0]) / 8.0
    n = len(points)
    for _ in range(CLIMB_ROUNDS):
        steps = points[:, None, :] + rng.normal(size=(n, CLIMB_STEPS, points.shape[1])) * width
        steps = np.clip(steps, ranges[:, 0], ranges[:, 1])
        found = difference(steps.reshape(-1, points.shape[1])).reshape(n, CLIMB_STEPS)
        pick = np.argmax(found, axis=1)
        better = found[np.arange(n), pick] > best
        points[better] = steps[np.arange(n), pick][better]
        best[better] = found[np.arange(n), pick][better]
        width = width * 0.85
    return np.asarray(points, dtype=np.float64)


#: The most states :func:`grid_states` gives a Mamdani measurement (each costs a centroid).
MAMDANI_GRID = 5_000


#: The fix offered when a Mamdani output is imported without the conversion.
MAMDANI_HINT = ("import with --mamdani-singletons to replace each output set by a singleton "
                "at its centroid: an approximation, whose largest error the import measures "
                "and reports")


def mamdani_report(behaviour: Behaviour, output: MamdaniOutput) -> str:
    """What converting ``output`` changed: measured where the rules are complete (else the
    converted controller has no output to compare everywhere)."""
    if behaviour.is_deployable:
        return measure(behaviour, output).report()
    return ("Mamdani output sets replaced by singletons at their centroids; the difference "
            "is not measured, since the rules do not give every combination of sets a "
            "command")


def import_notes(file: str, behaviours: Sequence[Behaviour],
                 conversions: Sequence[tuple[ImportedController, MamdaniOutput] | str | None]
                 ) -> str:
    """What importing ``file`` did, for the user: how a file of several outputs was split,
    then, for each output read as Mamdani sets (its controller as read and its sets; None
    for a Sugeno output), what converting it to singletons changed; for an output whose
    conversion was already measured (a first-order one, :mod:`flctool.export.linear`), its
    note as given."""
    notes = []
    if len(behaviours) > 1:
        notes.append(f"{file}: {len(behaviours)} outputs, imported as one behaviour each, "
                     "named after its output (" + ", ".join(f"'{b.name}'" for b in behaviours)
                     + "); each keeps the rules that conclude on its output, which computes "
                     "it exactly as the file does")
    for behaviour, conversion in zip(behaviours, conversions, strict=True):
        if isinstance(conversion, str):
            notes.append(f"{file}: output '{behaviour.output.name}': {conversion}")
        elif conversion is not None:
            controller, output = conversion
            notes += [f"{file}: {note}" for note in controller.notes]
            written = dataclasses.replace(output, **as_written(controller))
            notes.append(f"{file}: output '{behaviour.output.name}': "
                         + mamdani_report(behaviour, written))
    return "\n".join(notes)
