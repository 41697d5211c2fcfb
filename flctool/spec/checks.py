"""Checks that relate the fields of a behaviour to each other.

Each returns :class:`Problem` objects with the field path, so the loader can attach lines.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from flctool.errors import Problem
from flctool.registry import did_you_mean

if TYPE_CHECKING:
    from flctool.spec.models import Behaviour, InputVariable


def find_problems(behaviour: Behaviour) -> list[Problem]:
    problems: list[Problem] = []
    for name, variable in behaviour.inputs.items():
        problems += _check_input(name, variable)
    if behaviour.output.name in behaviour.inputs:
        problems.append(Problem(("output", "name"), f"the output is named '{behaviour.output.name}'"
                                ", like an input", "give the output a name of its own"))
    problems += _check_rules(behaviour)
    environment = behaviour.environment
    if environment is not None and hasattr(environment, "fit_problems"):
        problems += environment.fit_problems(behaviour.input_names,
                                             tuple(behaviour.output.commands))
    return problems


def _check_input(name: str, variable: InputVariable) -> list[Problem]:
    lo, hi = variable.range
    problems = []
    for set_name, (pa, _, _, pd) in variable.sets.items():
        if pa < lo or pd > hi:
            problems.append(Problem(
                ("inputs", name, "sets", set_name),
                f"set '{set_name}' [{pa:g} .. {pd:g}] reaches outside the input's range "
                f"[{lo:g}, {hi:g}]",
                "move the set's feet inside the range (a shoulder at the end of the range is "
                f"written [{lo:g}, {lo:g}, ...] or [..., {hi:g}, {hi:g}]) or widen the range"))
    if not problems:
        gap = uncovered_gap(variable)
        if gap is not None:
            a, b = gap
            where = f"the point {a:g}" if a == b else f"the values between {a:g} and {b:g}"
            problems.append(Problem(
                ("inputs", name, "sets"),
                f"{where} belong to no set (membership 0 everywhere), so eq. 3 would divide "
                "by zero there",
                "widen or add a set so that the sets overlap across the whole range"))
    return problems


def uncovered_gap(variable: InputVariable) -> tuple[float, float] | None:
    """The first stretch of the range where every set has membership 0, or None.

    A set is non-zero on the open interval (pa, pd), and also on pa itself when pa == pb
    (vertical left edge) and on pd itself when pc == pd (vertical right edge).
    """
    lo, hi = variable.range
    supports = sorted(
        ((pa, pa == pb, pd, pc == pd) for pa, pb, pc, pd in variable.sets.values()),
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
    if reach < hi or not reach_closed:
        return reach, hi
    return None


def _check_rules(behaviour: Behaviour) -> list[Problem]:
    problems = []
    inputs = behaviour.inputs
    commands = behaviour.output.commands
    seen: dict[tuple[str, ...], int] = {}
    for index, rule in enumerate(behaviour.rules):
        path = ("rules", index)
        complete = True
        for input_name, set_name in rule.if_.items():
            if input_name not in inputs:
                complete = False
                problems.append(Problem(
                    (*path, "if", input_name), f"rule names an unknown input '{input_name}'."
                    f"{did_you_mean(input_name, tuple(inputs))}",
                    f"use one of the inputs: {', '.join(inputs)}"))
            elif set_name not in inputs[input_name].sets:
                complete = False
                sets = tuple(inputs[input_name].sets)
                problems.append(Problem(
                    (*path, "if", input_name), f"input '{input_name}' has no set '{set_name}'."
                    f"{did_you_mean(set_name, sets)}", f"use one of: {', '.join(sets)}"))
        missing = [n for n in inputs if n not in rule.if_]
        if missing:
            complete = False
            problems.append(Problem(
                (*path, "if"), f"rule gives no set for input(s) {', '.join(missing)}",
                "name every input once in each rule (the rule grid is complete, eq. 1)"))
        if rule.then not in commands:
            problems.append(Problem(
                (*path, "then"), f"unknown command '{rule.then}'."
                f"{did_you_mean(rule.then, tuple(commands))}",
                f"use one of the output's commands: {', '.join(commands)}"))
        if complete:
            key = tuple(rule.if_[n] for n in inputs)
            if key in seen:
                problems.append(Problem(
                    path, f"duplicate rule: the same antecedent as rules[{seen[key]}]",
                    "each combination of sets gets one rule; delete one of them"))
            else:
                seen[key] = index
    return problems
