"""``learning.sets``: which inputs' fuzzy sets are learned with the consequents, and how.

The paper's future work ("how to evolve fuzzy antecedents"): a learner then searches the
sets' positions too, through a codec (:mod:`flctool.sets.codec`) that turns a vector of genes
into partitions that always validate. This module holds the section's model and the checks
that relate it to the inputs (which need no numpy); the codec does the rest.

Two modes:

- ``partition``: the input's sets form a *strong partition* -- the first set starts at the
  range's low end with a shoulder, the last ends at the high end with one, and each set's
  left foot and shoulder are the previous set's right shoulder and foot, so adjacent sets
  cross and every value's memberships sum to 1. The genes scale the gaps between consecutive
  breakpoints, which are then laid end to end from the low end to the high one: any genome
  is a strong partition again.
- ``lateral``: each set shifts as a whole (lateral tuning, Alcala and Herrera), by at most
  ``bound``; a shift that would change the sets' order or let the coverage (the largest
  membership of any value) fall below ``floor`` is pulled back towards the file's sets.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal

from pydantic import Field

from flctool.behaviour.base import Name, Section
from flctool.behaviour.shapes import is_trapezoid, trapezoids
from flctool.errors import PathPart, Problem
from flctool.registry import did_you_mean

if TYPE_CHECKING:
    from flctool.behaviour.fuzzy import InputVariable

Mode = Literal["partition", "lateral"]
BoundIn = Literal["spacing", "units"]

_BOUND = ("how far a set may move: with bound_in spacing a fraction of the spacing (partition: "
          "each gap between breakpoints may grow to (1 + bound) times its length or shrink "
          "to 1 / (1 + bound) of it; lateral: a set shifts by at most bound times the "
          "distance to its nearest neighbour's centre), with bound_in units in the input's "
          "units (partition: a gap grows by at most bound; lateral: the largest shift)")


class InputSetsConfig(Section):
    """One input's set learning; a key left out takes the ``learning.sets`` value."""

    mode: Mode | None = Field(None, description="partition or lateral (default: the section's)")
    bound: float | None = Field(None, gt=0, description=_BOUND)
    bound_in: BoundIn | None = Field(None, description="spacing or units (default: the "
                                     "section's)")
    floor: float | None = Field(None, gt=0, lt=1, description=(
        "lateral: the least coverage (largest membership of any value) a learned partition "
        "keeps"))
    fixed: list[Name] = Field(default_factory=list, description=(
        "sets of this input that stay as the file writes them"))


class SetLearningConfig(Section):
    """``learning.sets``: learn the fuzzy sets of some inputs with the consequents."""

    inputs: Literal["all"] | list[Name] | dict[Name, InputSetsConfig] = Field("all", description=(
        "which inputs' sets are learned: all, a list of input names, or input name -> its "
        "own settings"))
    mode: Mode = Field("partition", description=(
        "partition: a strong partition (adjacent sets cross, memberships sum to 1), the "
        "gaps between breakpoints learned; lateral: each set shifts within bound, order and "
        "a coverage floor kept"))
    bound: float = Field(0.5, gt=0, description=_BOUND)
    bound_in: BoundIn = Field("spacing", description=(
        "spacing: bound is a fraction of the sets' spacing; units: in the input's units"))
    floor: float = Field(0.2, gt=0, lt=1, description=(
        "lateral: the least coverage (largest membership of any value) a learned partition "
        "keeps; the file's sets must reach it"))
    mutation: float = Field(0.2, ge=0, le=1, description=(
        "GA learners: probability that a set gene is mutated (a Gaussian step of sigma)"))
    sigma: float = Field(0.3, gt=0, le=2, description=(
        "GA learners: the standard deviation of a mutation step and of the initial genes, "
        "in gene units (every gene lies in [-1, 1]; 0 is the file's sets)"))

    def settings(self, input_names: Sequence[str]) -> dict[str, InputSetting]:
        """The resolved settings of each input whose sets are learned, in file order
        (names the file does not have are left out; :func:`set_learning_problems` reports
        them)."""
        chosen = self.inputs
        if chosen == "all":
            own: Mapping[str, InputSetsConfig] = {n: InputSetsConfig() for n in input_names}
        elif isinstance(chosen, list):
            own = {n: InputSetsConfig() for n in chosen}
        else:
            own = chosen
        return {name: InputSetting(
            own[name].mode or self.mode, own[name].bound or self.bound,
            own[name].bound_in or self.bound_in, own[name].floor or self.floor,
            tuple(own[name].fixed)) for name in input_names if name in own}


@dataclass(frozen=True)
class InputSetting:
    """How one input's sets are learned (a :class:`SetLearningConfig` resolved)."""

    mode: Mode
    bound: float
    bound_in: BoundIn
    floor: float
    fixed: tuple[str, ...]


def set_learning_problems(config: SetLearningConfig | None,
                          inputs: Mapping[str, InputVariable]) -> list[Problem]:
    """What in ``learning.sets`` (``config``, None if the learner learns no sets) does not fit
    the behaviour's ``inputs``: unknown names, and sets that the chosen mode cannot start
    from."""
    if config is None:
        return []
    problems: list[Problem] = []
    here: tuple[PathPart, ...] = ("learning", "sets", "inputs")
    known = tuple(inputs)
    chosen = config.inputs
    named = [] if chosen == "all" else list(chosen)
    for index, name in enumerate(named):
        if name not in inputs:
            path = (*here, index) if isinstance(chosen, list) else (*here, name)
            problems.append(Problem(path, f"there is no input '{name}'."
                                    f"{did_you_mean(name, known)}",
                                    f"use one of the inputs: {', '.join(known)}"))
    for name, setting in config.settings(known).items():
        variable = inputs[name]
        shaped = [(s, v.kind) for s, v in variable.sets.items() if not is_trapezoid(v)]
        if shaped:  # the set genes code trapezoids only (flctool.behaviour.shapes)
            set_name, kind = shaped[0]
            problems.append(Problem(
                ("inputs", name, "sets", set_name), f"learning.sets learns the sets of input "
                f"'{name}', but set '{set_name}' is a {kind}: only trapezoid partitions can "
                "be learned", f"leave '{name}' out of learning.sets.inputs (list the inputs "
                "to learn), or write its sets as trapezoids"))
            continue
        for index, set_name in enumerate(setting.fixed):
            if set_name not in variable.sets:
                problems.append(Problem(
                    (*here, name, "fixed", index), f"input '{name}' has no set "
                    f"'{set_name}'.{did_you_mean(set_name, tuple(variable.sets))}",
                    f"use one of: {', '.join(variable.sets)}"))
        if setting.bound_in == "units" and setting.bound > variable.range[1] - variable.range[0]:
            path = (*here, name, "bound") if isinstance(chosen, dict) and \
                chosen[name].bound is not None else ("learning", "sets", "bound")
            lo, hi = variable.range
            problems.append(Problem(path, f"a bound of {setting.bound:g} {variable.unit or 'units'}"
                                    f" is wider than the range [{lo:g}, {hi:g}] of input "
                                    f"'{name}'",
                                    "use a bound within the range, or bound_in: spacing"))
        if setting.mode == "partition":
            problems += strong_partition_problems(name, variable)
        else:
            problems += coverage_floor_problems(name, variable, setting.floor)
    return problems


def strong_partition_problems(name: str, variable: InputVariable) -> list[Problem]:
    """Why the sets of input ``name`` are not a strong partition the ``partition`` mode can
    start from (empty if they are)."""
    lo, hi = variable.range
    sets = list(zip(variable.sets, trapezoids(variable.sets.values()), strict=True))
    hint = ("write a strong partition (the first set [low, low, c, d], each next one starting "
            "[c, d, ...] where the previous ends, the last [..., high, high]), or learn this "
            "input's sets with mode: lateral")
    where = f"learning.sets learns input '{name}' as a strong partition, but"

    def problem(set_name: str, text: str) -> Problem:
        return Problem(("inputs", name, "sets", set_name), f"{where} {text}", hint)

    first_name, (pa, pb, _, _) = sets[0]
    if not pa == pb == lo:
        return [problem(first_name, f"its first set '{first_name}' does not start with a "
                        f"shoulder at the range's low end {lo:g} ([{lo:g}, {lo:g}, ...])")]
    last_name, (_, _, pc, pd) = sets[-1]
    if not pc == pd == hi:
        return [problem(last_name, f"its last set '{last_name}' does not end with a "
                        f"shoulder at the range's high end {hi:g} ([..., {hi:g}, {hi:g}])")]
    for (before, (_, _, c, d)), (after, (a, b, _, _)) in itertools.pairwise(sets):
        if (a, b) != (c, d):
            return [problem(after, f"set '{after}' starts at [{a:g}, {b:g}, ...], not where "
                            f"'{before}' ends ([..., {c:g}, {d:g}])")]
        if not c < d:
            return [problem(before, f"sets '{before}' and '{after}' meet at a vertical edge "
                            f"at {c:g} instead of crossing on a slope")]
    return []


def coverage_floor_problems(name: str, variable: InputVariable,
                            floor: float) -> list[Problem]:
    """The file's sets of input ``name`` below the ``lateral`` mode's coverage floor."""
    lowest, where = coverage(variable.range, trapezoids(variable.sets.values()))
    if lowest >= floor:
        return []
    return [Problem(("inputs", name, "sets"), f"learning.sets keeps a coverage of at least "
                    f"{floor:g} for input '{name}', but the file's sets cover {where:g} only "
                    f"to {lowest:.3g}", "widen the sets' overlap, or lower learning.sets.floor")]


Quad = tuple[float, float, float, float]


def membership(s: float, quad: Sequence[float]) -> float:
    """The trapezoid membership of paper Sec. II (the formula of
    :mod:`flctool.membership`)."""
    pa, pb, pc, pd = quad
    if s > pc:
        return max(0.0, (pd - s) / (pd - pc)) if pd > pc else 0.0
    if s < pb:
        return max(0.0, (s - pa) / (pb - pa)) if pb > pa else 0.0
    return 1.0


def coverage(bounds: Sequence[float], quads: Sequence[Sequence[float]]) -> tuple[float, float]:
    """The least coverage of a partition over its range and where: ``min_s max_j mu_j(s)``.

    The upper envelope of trapezoids is piecewise linear, with corners at the sets' corners
    and where a rising edge crosses a falling one, so the least value is at one of those
    points or just beside a vertical edge (looked at a billionth of the range away).
    """
    lo, hi = float(bounds[0]), float(bounds[1])
    points = {lo, hi}
    rising = [(pa, pb) for pa, pb, _, _ in quads if pb > pa]
    falling = [(pc, pd) for _, _, pc, pd in quads if pd > pc]
    for quad in quads:
        points.update(float(v) for v in quad)
    for pa, pb in rising:
        for pc, pd in falling:
            # (s - pa) / (pb - pa) == (pd - s) / (pd - pc)
            s = (pa * (pd - pc) + pd * (pb - pa)) / ((pd - pc) + (pb - pa))
            points.add(s)
    nudge = (hi - lo) * 1e-9
    looked = sorted({min(hi, max(lo, p + d)) for p in points for d in (-nudge, 0.0, nudge)})
    lowest, where = math.inf, lo
    for s in looked:
        value = max(membership(s, quad) for quad in quads)
        if value < lowest:
            lowest, where = value, s
    return lowest, where
