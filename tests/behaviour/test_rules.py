"""Rules that leave out an input ("don't care") expand over its sets, conflicts located."""

from __future__ import annotations

import pytest

from flctool import compile_behaviour, parse_behaviour
from flctool.errors import SpecError

HEAD = """\
flctool: 1
name: dc
inputs:
  x:
    range: [0, 1]
    sets: {lo: [0, 0, 0.2, 0.8], hi: [0.2, 0.8, 1, 1]}
  y:
    range: [0, 1]
    sets: {lo: [0, 0, 0.2, 0.8], mid: [0, 0.5, 0.5, 1], hi: [0.2, 0.8, 1, 1]}
output:
  name: u
  commands: {a: -1, b: 1}
rules:
"""


def test_a_rule_leaving_out_an_input_stands_for_each_of_its_sets() -> None:
    behaviour = parse_behaviour(HEAD + "  - {if: {x: lo}, then: a}\n"
                                       "  - {if: {x: hi, y: lo}, then: b}\n"
                                       "  - {if: {x: hi}, then: b}\n")  # merges with rule 1
    assert behaviour.is_deployable
    assert [(r.if_["x"], r.if_["y"], r.then) for r in behaviour.rules] == [
        ("lo", "lo", "a"), ("lo", "mid", "a"), ("lo", "hi", "a"),
        ("hi", "lo", "b"), ("hi", "mid", "b"), ("hi", "hi", "b")]
    assert compile_behaviour(behaviour).n_rules == 6


def test_conflicting_expansions_name_both_rules() -> None:
    with pytest.raises(SpecError) as caught:
        parse_behaviour(HEAD + "  - {if: {x: lo}, then: a}\n  - {if: {y: hi}, then: b}\n",
                        "dc.yaml")
    [problem] = caught.value.problems
    assert (problem.file, problem.line) == ("dc.yaml", 15)
    assert "rules[1] (then b) and rules[0] (line 14) (then a) both cover IF x IS lo AND y IS " \
        "hi" in problem.message


def test_an_error_inside_an_expanded_rule_is_located_at_its_line() -> None:
    with pytest.raises(SpecError) as caught:
        parse_behaviour(HEAD + "  - {if: {x: hi, y: lo}, then: b}\n  - {if: {x: lo}, then: c}\n",
                        "dc.yaml")
    assert {(p.line, p.message.split(".")[0]) for p in caught.value.problems} == {
        (15, "unknown command 'c'")}
