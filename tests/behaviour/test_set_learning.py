"""``learning.sets``: its settings, and located errors where it does not fit the inputs."""

from __future__ import annotations

import pytest

from flctool.behaviour.load import parse_behaviour
from flctool.errors import SpecError, format_path

BASE = """\
flctool: 1
name: sets
inputs:
  x:
    range: [0, 1]
    sets: {lo: [0, 0, 0.2, 0.5], hi: [0.2, 0.5, 1, 1]}
  y:
    range: [0, 10]
    unit: m
    sets: {lo: [0, 0, 2, 5], hi: [3, 5, 10, 10]}
output: {name: a, commands: {l: -1, r: 1}}
learning:
  sets:
"""


def _problems(sets: str) -> list[tuple[int | None, str]]:
    with pytest.raises(SpecError) as caught:
        parse_behaviour(BASE + sets, "f.yaml")
    return [(p.line, f"{format_path(p.path)}: {p.message}")
            for p in caught.value.problems]


def test_settings_resolve_per_input_over_the_sections_defaults() -> None:
    behaviour = parse_behaviour(BASE + "    inputs: {x: {bound: 0.3}, y: {mode: lateral, "
                                "floor: 0.3, fixed: [hi]}}\n    bound: 2\n")
    settings = behaviour.learning.sets.settings(behaviour.input_names)  # type: ignore[union-attr]
    assert settings["x"].mode == "partition" and settings["x"].bound == 0.3
    assert settings["y"].mode == "lateral" and settings["y"].bound == 2
    assert settings["y"].floor == 0.3 and settings["y"].fixed == ("hi",)


def test_a_list_names_the_inputs_learned() -> None:
    behaviour = parse_behaviour(BASE + "    inputs: [x]\n")
    assert list(behaviour.learning.sets.settings(  # type: ignore[union-attr]
        behaviour.input_names)) == ["x"]


def test_partition_needs_a_strong_partition_located_at_the_set() -> None:
    # y's 'hi' starts at 3, not where 'lo' ends (2, 5)
    assert _problems("    inputs: [y]\n") == [
        (10, "inputs.y.sets.hi: learning.sets learns input 'y' as a strong partition, but "
             "set 'hi' starts at [3, 5, ...], not where 'lo' ends ([..., 2, 5])")]


def test_lateral_needs_the_files_sets_to_reach_the_floor() -> None:
    (line, text), = _problems("    inputs: [x]\n    mode: lateral\n    floor: 0.9\n")
    assert line == 6 and text.startswith("inputs.x.sets: learning.sets keeps a coverage of at "
                                         "least 0.9 for input 'x'")


def test_unknown_inputs_and_sets_and_a_bound_wider_than_the_range() -> None:
    problems = _problems("    inputs: {x: {fixed: [mid]}, z: {}, y: {mode: lateral, bound: 20,"
                         " bound_in: units}}\n")
    assert [text for _, text in problems] == [
        "learning.sets.inputs.x.fixed[0]: input 'x' has no set 'mid'.",
        "learning.sets.inputs.z: there is no input 'z'.",
        "learning.sets.inputs.y.bound: a bound of 20 m is wider than the range [0, 10] of "
        "input 'y'"]
    assert {line for line, _ in problems} == {14}


def test_a_bad_mode_is_an_error_of_the_section() -> None:
    (line, text), = _problems("    mode: sideways\n")
    assert line == 14 and text.startswith("learning.sets.mode:")
