"""Coverage of an input's range by its sets: where membership is 0 everywhere."""

from __future__ import annotations

import pytest

from flctool.behaviour.checks import uncovered_gap
from flctool.behaviour.fuzzy import InputVariable


def _gap(sets: dict[str, list[float]], lo: float = 0.0, hi: float = 1.0) -> object:
    return uncovered_gap(InputVariable.model_validate({"range": [lo, hi], "sets": sets}))


@pytest.mark.parametrize(("sets", "gap"), [
    # overlapping shoulders and a triangle: covered
    ({"a": [0, 0, 0.2, 0.5], "b": [0.3, 0.5, 0.5, 0.7], "c": [0.5, 0.8, 1, 1]}, None),
    # a foot touching the next set's shoulder: that point is in the shoulder, covered
    ({"a": [0, 0, 0.2, 0.5], "b": [0.2, 0.5, 1, 1]}, None),
    # two feet meeting at 0.5: membership 0 at exactly that point
    ({"a": [0, 0, 0.2, 0.5], "b": [0.5, 0.7, 1, 1]}, (0.5, 0.5)),
    # a stretch nobody covers
    ({"a": [0, 0, 0.2, 0.3], "b": [0.4, 0.7, 1, 1]}, (0.3, 0.4)),
    # the range's ends need a vertical edge (shoulder) to have membership > 0
    ({"a": [0, 0.1, 0.5, 1]}, (0.0, 0.0)),
    ({"a": [0, 0, 0.5, 1]}, (1.0, 1.0)),
    ({"a": [0, 0, 1, 1]}, None),
    # a vertical edge inside the range covers its own point
    ({"a": [0, 0, 0.5, 0.5], "b": [0.5, 1, 1, 1]}, None),
    # order in the file does not matter
    ({"c": [0.5, 0.8, 1, 1], "a": [0, 0, 0.2, 0.6]}, None),
])
def test_uncovered_gap(sets: dict[str, list[float]], gap: object) -> None:
    assert _gap(sets) == gap


def test_two_commands_with_the_same_value_are_a_warning() -> None:
    from flctool.behaviour.checks import command_warnings

    warnings = command_warnings({"left": 1.0, "ahead": 0.0, "also_left": 1.0})
    assert [(w.path, w.message) for w in warnings] == [
        (("output", "commands", "also_left"),
         "commands 'left' and 'also_left' have the same value 1")]
    assert command_warnings({"a": 0.0, "b": 1.0}) == []


def test_a_broken_rule_table_is_reported_up_to_a_limit() -> None:
    from flctool.behaviour.checks import MAX_RULE_PROBLEMS, check_rules
    from flctool.behaviour.fuzzy import Rule

    rule = Rule.model_validate({"if": {"x": "nowhere"}, "then": "up"})
    problems = check_rules({"x": ("low", "high")}, ("up",), enumerate([rule] * 10_000))
    assert len(problems) == MAX_RULE_PROBLEMS + 1
    assert problems[-1].message == (f"the rules from rules[{MAX_RULE_PROBLEMS}] on are not "
                                    f"checked: {MAX_RULE_PROBLEMS} problems already")


def test_a_duplicate_rule_is_named_the_way_the_file_names_rules() -> None:
    from flctool.behaviour.checks import RuleProblem, check_rules
    from flctool.behaviour.fuzzy import Rule

    rule = Rule.model_validate({"if": {"x": "low"}, "then": "up"})
    [problem] = check_rules({"x": ("low", "high")}, ("up",), [(3, rule), (7, rule)])
    assert isinstance(problem, RuleProblem)
    assert problem.path == ("rules", 7)
    assert problem.message == "duplicate rule: the same antecedent as rules[3]"  # YAML's way
    assert problem.worded(lambda index: f"the rule at line {10 + index}") == (
        "duplicate rule: the same antecedent as the rule at line 13")

