"""Rules that leave out an input: "don't care", expanded over that input's sets.

A behaviour file's rule may name a set for some inputs only::

    - if: {ball_size: large}      # whatever the pan
      then: forward

It stands for one rule per combination of the left-out inputs' sets (here: large with every
set of pan), each with the rule's command, so the rule grid of eq. 1 stays complete and every
rule still fires with the minimum over all inputs (eq. 2). Expansion happens on the parsed
data, before validation; an expanded rule is located at the line of the rule it came from.
Two rules whose expansions give one combination of sets different commands are a conflict,
reported at both; expansions that agree are merged.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterable
from typing import Any, SupportsInt

from flctool.behaviour.checks import MAX_RULES
from flctool.behaviour.fuzzy import Rule
from flctool.behaviour.models import Behaviour
from flctool.behaviour.yaml_source import Mark, SourceMap
from flctool.errors import FlcError, PathPart, Problem


def expand_dont_care(data: Any, source: SourceMap) -> tuple[Any, SourceMap, list[Problem]]:
    """(data with every partial rule expanded, the source map renumbered to match, conflicts).

    Data that is not shaped as expected (no input sets, a rule naming an unknown input, a
    grid beyond the rule limit) is returned unchanged, for validation to report.
    """
    if not isinstance(data, dict):
        return data, source, []
    inputs, rules = data.get("inputs"), data.get("rules")
    if not (isinstance(inputs, dict) and isinstance(rules, list)):
        return data, source, []
    sets: dict[str, list[str]] = {}
    for name, variable in inputs.items():
        if not (isinstance(variable, dict) and isinstance(variable.get("sets"), dict)):
            return data, source, []
        sets[str(name)] = [str(s) for s in variable["sets"]]
    expanded: list[Any] = []
    origin: list[int] = []  # the index in the file of each rule in ``expanded``
    # antecedent -> (rule, command) of the complete rules (whose repeats validation reports),
    # then of the expansions
    concluded: dict[tuple[str, ...], tuple[int, Any]] = {}
    for index, rule in enumerate(rules):
        if not _left_out(rule, sets):
            condition = rule.get("if") if isinstance(rule, dict) else None
            if isinstance(condition, dict) and set(map(str, condition)) == set(sets):
                key = tuple(str(condition[n]) for n in sets)
                concluded.setdefault(key, (index, rule.get("then")))
    problems: list[Problem] = []
    changed = False
    for index, rule in enumerate(rules):
        left_out = _left_out(rule, sets)
        condition = rule.get("if")
        count = math.prod(len(sets[n]) for n in left_out)
        if not left_out or count > MAX_RULES:
            expanded.append(rule)
            origin.append(index)
            continue
        changed = True
        assert isinstance(condition, dict)
        for combination in itertools.product(*(sets[n] for n in left_out)):
            chosen = {**{str(k): v for k, v in condition.items()},
                      **dict(zip(left_out, combination, strict=True))}
            key = tuple(str(chosen[n]) for n in sets)
            if key in concluded:
                other, command = concluded[key]
                if command != rule.get("then"):
                    problems.append(_conflict(source, index, other, key, sets, rule, command))
                continue  # agreeing expansions merge
            concluded[key] = (index, rule.get("then"))
            expanded.append({**rule, "if": {n: chosen[n] for n in sets}})
            origin.append(index)
        if len(expanded) > MAX_RULES:
            return data, source, []
    if not changed:
        return data, source, []
    return {**data, "rules": expanded}, _renumbered(source, origin), problems


def _left_out(rule: Any, sets: dict[str, list[str]]) -> list[str]:
    """The inputs a rule leaves out, if it is a mapping naming known inputs only."""
    condition = rule.get("if") if isinstance(rule, dict) else None
    if not (isinstance(condition, dict) and condition
            and all(str(k) in sets for k in condition)):
        return []
    return [n for n in sets if n not in condition]


def _conflict(source: SourceMap, index: int, other: int, key: tuple[str, ...],
              sets: dict[str, list[str]], rule: dict[str, Any], command: Any) -> Problem:
    where, _ = source.locate(("rules", other))
    combination = " AND ".join(f"{n} IS {s}" for n, s in zip(sets, key, strict=True))
    return source.problem(
        ("rules", index), f"rules[{index}] (then {rule.get('then')}) and rules[{other}]"
        f"{f' (line {where})' if where else ''} (then {command}) both cover IF {combination}, "
        "with different commands", "narrow one of the rules by naming a set of the input it "
        "leaves out, or give both the same command")


def _renumbered(source: SourceMap, origin: list[int]) -> SourceMap:
    """The source map with rule k located where rule ``origin[k]`` of the file is."""
    marks = {path: mark for path, mark in source.marks.items()
             if not (len(path) >= 2 and path[0] == "rules")}
    raw = {path: text for path, text in source.raw.items()
           if not (len(path) >= 2 and path[0] == "rules")}
    by_rule: dict[int, list[tuple[tuple[PathPart, ...], Mark]]] = {}
    for path, mark in source.marks.items():
        if len(path) >= 2 and path[0] == "rules" and isinstance(path[1], int):
            by_rule.setdefault(path[1], []).append((path[2:], mark))
    for k, index in enumerate(origin):
        for rest, mark in by_rule.get(index, []):
            renumbered: tuple[PathPart, ...] = ("rules", k, *rest)
            marks[renumbered] = mark
    items = dict(source.items)
    rule_items = items.pop(("rules",), None)
    for k, index in enumerate(origin):
        if rule_items is not None and index < len(rule_items):
            marks[("rules", k)] = rule_items[index]
    return SourceMap(source.file, marks, raw, source.parsed, source.overrides, items)


def with_rules(behaviour: Behaviour, consequents: Iterable[SupportsInt]) -> Behaviour:
    """The behaviour with a complete rule table from (M,) consequent indices (grid order,
    eq. 1): how a learned consequent vector becomes a behaviour file."""
    commands = tuple(behaviour.output.commands)
    try:
        table = [int(k) for k in consequents]
    except TypeError:
        table = []
    if len(table) != behaviour.rule_count or not all(0 <= k < len(commands) for k in table):
        raise FlcError(f"consequents must be {behaviour.rule_count} command indices in "
                       f"0..{len(commands) - 1}", hint="give one command index per rule")
    rules = [Rule.model_validate({"if": dict(zip(behaviour.input_names, sets, strict=True)),
                                  "then": commands[k]})
             for sets, k in zip(behaviour.antecedents(), table, strict=True)]
    return behaviour.model_copy(update={"rules": rules})
