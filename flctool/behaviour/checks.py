"""Checks that relate the fields of a behaviour to each other.

Each returns :class:`Problem` objects with the field path, so the loader can attach lines. A
problem whose message names another rule is a :class:`RuleProblem`, which the loader words
the way the file being read names its rules (a behaviour file by field path, an imported
FLL, FCL or FIS file by line).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Collection, Iterable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING

from flctool.behaviour.shapes import evaluated_range, is_trapezoid, set_row, trapezoids
from flctool.errors import PathPart, Problem
from flctool.membership import firing_sets
from flctool.registry import did_you_mean

if TYPE_CHECKING:
    from flctool.behaviour.fuzzy import InputVariable, Rule

# Resource limits (docs/behaviour-files.md): past them a run would need more memory or time
# than any robot behaviour does, so the file is refused up front instead of hanging.
MAX_RULES = 1_000_000  # M = prod(L_i), the rule grid
MAX_POPULATION = 10_000
MAX_TRIALS = 1_000
MAX_GENERATIONS = 1_000_000
MAX_EPISODE_STEPS = 1_000_000  # an environment's max_steps
#: Controllers held at once: population x M rule consequents (8 bytes each, plus q tables).
MAX_POPULATION_RULES = 20_000_000
#: Steps of one generation run side by side: population x trials x max_steps.
MAX_GENERATION_STEPS = 20_000_000
#: Rule problems listed before the rest of the table is skipped.
MAX_RULE_PROBLEMS = 100

#: How a file names the rule with an index: a behaviour file by its field path (rule_path).
RuleNamer = Callable[[int], str]


def rule_path(index: int) -> str:
    """How a behaviour file names a rule: by its field path, ``rules[3]``."""
    return f"rules[{index}]"


@dataclass(frozen=True)
class RuleProblem(Problem):
    """A problem whose message names rules other than the one it is located at.

    ``parts`` is the message as text and rule indices; ``message`` names those rules by field
    path, as a behaviour file does, and :meth:`worded` names them the way another file does.
    """

    parts: tuple[str | int, ...] = ()

    def worded(self, name: RuleNamer) -> str:
        """The message with each rule named by ``name``."""
        return _worded(self.parts, name)


def rule_problem(path: tuple[PathPart, ...], parts: tuple[str | int, ...],
                 hint: str = "") -> RuleProblem:
    """The problem at ``path`` whose message is ``parts`` (text and rule indices)."""
    return RuleProblem(path, _worded(parts, rule_path), hint, parts=parts)


def _worded(parts: tuple[str | int, ...], name: RuleNamer) -> str:
    return "".join(part if isinstance(part, str) else name(part) for part in parts)


def limit_problems(set_counts: list[int], population: int | None, trials: int | None,
                   generations: int | None, max_steps: int | None) -> list[Problem]:
    """Sizes past the resource limits; a None is a size the file does not (validly) give."""
    problems = []
    rules = math.prod(set_counts) if set_counts else 1
    if rules > MAX_RULES:
        problems.append(Problem(
            ("inputs",), f"the rule grid has M = {' x '.join(map(str, set_counts))} = {rules:,} "
            f"rules, more than flctool's limit of {MAX_RULES:,}",
            "use fewer inputs or fewer sets per input (M is the product of the set counts)"))
    for path, value, limit in ((("learning", "population"), population, MAX_POPULATION),
                               (("learning", "trials"), trials, MAX_TRIALS),
                               (("learning", "generations"), generations, MAX_GENERATIONS),
                               (("environment", "max_steps"), max_steps, MAX_EPISODE_STEPS)):
        if value is not None and value > limit:
            problems.append(Problem(path, f"{path[-1]} {value:,} is more than flctool's limit "
                                    f"of {limit:,}", f"use at most {limit:,}"))
    if problems:
        return problems
    if population is not None and rules <= MAX_RULES and population * rules > \
            MAX_POPULATION_RULES:
        problems.append(Problem(
            ("learning", "population"), f"a population of {population:,} controllers of "
            f"{rules:,} rules holds {population * rules:,} consequents, more than flctool's "
            f"limit of {MAX_POPULATION_RULES:,}", "use a smaller population or fewer rules"))
    if population is not None and trials is not None and max_steps is not None and \
            population * trials * max_steps > MAX_GENERATION_STEPS:
        problems.append(Problem(
            ("environment", "max_steps"), f"a generation runs population x trials x max_steps "
            f"= {population * trials * max_steps:,} steps side by side, more than flctool's "
            f"limit of {MAX_GENERATION_STEPS:,}",
            "use fewer steps per episode, trials or individuals"))
    return problems


def command_warnings(commands: Mapping[str, float]) -> list[Problem]:
    """Two commands on one singleton: the controller's output cannot tell them apart (eq. 3),
    and an adapter executing the nearest command always picks the first."""
    seen: dict[float, str] = {}
    problems = []
    for name, value in commands.items():
        if value in seen:
            problems.append(Problem(("output", "commands", name),
                                    f"commands '{seen[value]}' and '{name}' have the same value "
                                    f"{value:g}", "give each command its own value"))
        else:
            seen[value] = name
    return problems


def check_input(name: str, variable: InputVariable) -> list[Problem]:
    lo, hi = variable.range
    problems = []
    for set_name, value in variable.sets.items():
        if not is_trapezoid(value):
            continue  # the other shapes reach across the whole line
        pa, _, _, pd = value
        if pa < lo or pd > hi:
            problems.append(Problem(
                ("inputs", name, "sets", set_name),
                f"set '{set_name}' [{pa:g} .. {pd:g}] reaches outside the input's range "
                f"[{lo:g}, {hi:g}]",
                "move the set's feet inside the range (a shoulder at the end of the range is "
                f"written [{lo:g}, {lo:g}, ...] or [..., {hi:g}, {hi:g}]) or widen the range"))
    if not problems:
        gap = uncovered_gap(variable.model_copy(
            update={"range": evaluated_range(variable.range, variable.sets.values())}))
        if gap is not None:
            a, b = gap
            where = f"the point {a:g}" if a == b else f"the values between {a:g} and {b:g}"
            if all(is_trapezoid(v) for v in variable.sets.values()):
                what = (f"{'belongs' if a == b else 'belong'} to no set (membership 0 "
                        "everywhere), so eq. 3 would divide by zero there")
            else:
                what = (f"{'has' if a == b else 'have'} a membership below {COVERS_FROM:g} in "
                        "every set (an input with a shape other than the trapezoid must "
                        "reach that in some set "
                        "everywhere, so that eq. 3's denominator stays well above 0)")
            problems.append(Problem(
                ("inputs", name, "sets"), f"{where} {what}",
                "widen or add a set so that the sets overlap across the whole range"))
    return problems


#: For an input with a set of another shape than the trapezoid, where a set covers a point:
#: its membership there is at least this (Gaussians, bells and sigmoids never reach 0).
COVERS_FROM = 1e-6
#: The points of a range (besides its ends and the sets' parameters) where that is checked.
COVERAGE_POINTS = 1025


def _shaped_gap(variable: InputVariable) -> tuple[float, float] | None:
    """:func:`uncovered_gap` for an input with a set of another shape than the trapezoid.

    Every point of the range must lie where some set's membership is at least
    :data:`COVERS_FROM`. Checked on a grid (the range's ends, :data:`COVERAGE_POINTS` points
    across it and every set parameter inside it): each two neighbouring grid points need one
    set at least that high at both. Each shape rises and then falls (is quasi-concave), so
    that set is at least that high between them too, and the check holds for the whole range.
    """
    lo, hi = variable.range
    rows = [set_row(v) for v in variable.sets.values()]
    kinds = [code for code, _ in rows]
    params = [p for _, p in rows]
    inside = [x for p in params for x in p if lo < x < hi]
    step = (hi - lo) / (COVERAGE_POINTS - 1)
    grid = sorted({lo, hi, *inside, *(lo + k * step for k in range(1, COVERAGE_POINTS - 1))})
    previous: set[int] | None = None
    for k, x in enumerate(grid):
        high = {j for j, mu in firing_sets(x, params, kinds) if mu >= COVERS_FROM}
        if not high:
            return x, x
        if previous is not None and not previous & high:
            return grid[k - 1], x
        previous = high
    return None


def uncovered_gap(variable: InputVariable) -> tuple[float, float] | None:
    """The first stretch of the range where every set has membership 0, or None.

    A set is non-zero on the open interval (pa, pd), and also on pa itself when pa == pb
    (vertical left edge) and on pd itself when pc == pd (vertical right edge). An input with
    a set of another shape is checked by :func:`_shaped_gap` instead.
    """
    if not all(is_trapezoid(v) for v in variable.sets.values()):
        return _shaped_gap(variable)
    lo, hi = variable.range
    supports = sorted(
        ((pa, pa == pb, pd, pc == pd) for pa, pb, pc, pd in trapezoids(variable.sets.values())),
        key=lambda s: (s[0], not s[1]),
    )
    reach, reach_closed = lo, False  # [lo, reach) is covered, and reach too if reach_closed
    for start, start_closed, end, end_closed in supports:
        if start > reach or (start == reach and not reach_closed and not start_closed):
            return reach, start
        if end > reach:
            reach, reach_closed = end, end_closed
        elif end == reach:
            reach_closed = reach_closed or end_closed
    if reach < hi or (reach == hi and not reach_closed):
        return min(reach, hi), hi
    return None


def check_rules(inputs: Mapping[str, Collection[str]], commands: Collection[str],
                rules: Iterable[tuple[int, Rule]]) -> list[Problem]:
    """Rule references against ``inputs`` (input name -> its set names) and ``commands``."""
    problems: list[Problem] = []
    seen: dict[tuple[str, ...], int] = {}
    known = {name: frozenset(sets) for name, sets in inputs.items()}  # O(1) look-ups
    commands_known = frozenset(commands)
    for index, rule in rules:
        if len(problems) >= MAX_RULE_PROBLEMS:  # a whole broken table need not be listed
            problems.append(rule_problem(
                ("rules", index), ("the rules from ", index, f" on are not checked: "
                                   f"{len(problems)} problems already"),
                "fix the rules above first"))
            break
        path = ("rules", index)
        complete = True
        for input_name, set_name in rule.if_.items():
            if input_name not in inputs:
                complete = False
                problems.append(Problem(
                    (*path, "if", input_name), f"rule names an unknown input '{input_name}'."
                    f"{did_you_mean(input_name, tuple(inputs))}",
                    f"use one of the inputs: {', '.join(inputs)}"))
            elif set_name not in known[input_name]:
                complete = False
                sets = tuple(inputs[input_name])
                problems.append(Problem(
                    (*path, "if", input_name), f"input '{input_name}' has no set '{set_name}'."
                    f"{did_you_mean(set_name, sets)}", f"use one of: {', '.join(sets)}"))
        missing = [n for n in inputs if n not in rule.if_]
        if missing:
            complete = False
            problems.append(Problem(
                (*path, "if"), f"rule gives no set for input(s) {', '.join(missing)}",
                "name every input once in each rule (the rule grid is complete, eq. 1)"))
        if rule.then not in commands_known:
            problems.append(Problem(
                (*path, "then"), f"unknown command '{rule.then}'."
                f"{did_you_mean(rule.then, tuple(commands))}",
                f"use one of the output's commands: {', '.join(commands)}"))
        if complete:
            key = tuple(rule.if_[n] for n in inputs)
            if key in seen:
                problems.append(rule_problem(
                    path, ("duplicate rule: the same antecedent as ", seen[key]),
                    "each combination of sets gets one rule; delete one of them"))
            else:
                seen[key] = index
    return problems
