"""The YAML reader: YAML 1.2 core scalars, tags checked against their nodes, and bounds on
nesting, alias expansion and integer size. Every refusal is a located SpecError."""

from __future__ import annotations

from typing import Any

import pytest

from flctool.behaviour.yaml_source import MAX_ALIASED_VALUES, MAX_DEPTH, MAX_INT_DIGITS, read_yaml
from flctool.errors import SpecError


def _value(text: str) -> Any:
    data, _ = read_yaml(f"a: {text}\n", "f.yaml")
    return data["a"]


def _refusal(text: str) -> tuple[int | None, str]:
    with pytest.raises(SpecError) as info:
        read_yaml(text, "f.yaml")
    problem = info.value.problems[0]
    assert problem.file == "f.yaml"
    return problem.line, problem.message


@pytest.mark.parametrize(("written", "value"), [
    # YAML 1.1 reads these as booleans or sexagesimal / octal numbers; YAML 1.2 does not.
    ("yes", "yes"), ("no", "no"), ("on", "on"), ("off", "off"), ("Y", "Y"),
    ("1:00", "1:00"), ("1_000", "1_000"), ("0b11", "0b11"),
    ("010", 10), ("0o10", 8), ("0x10", 16), ("-7", -7), ("+3", 3),
    ("2.5", 2.5), ("1e3", 1000.0), (".5", 0.5), ("-.inf", float("-inf")),
    ("true", True), ("False", False), ("~", None), ("null", None), ("", None),
    ("!!str 1", "1"), ("!!float 3", 3.0), ("!!int 0x1f", 31), ("!!null ''", None),
    ("!!bool true", True), ("'yes'", "yes"),
])
def test_scalars_follow_the_yaml_1_2_core_schema(written: str, value: Any) -> None:
    got = _value(written)
    assert got == value and type(got) is type(value)


@pytest.mark.parametrize(("written", "message"), [
    ("!!int abc", "'abc' is not an integer"),
    ("!!float x", "'x' is not a number"),
    ("!!bool 3", "'3' is not a boolean"),
    ("!!null x", "'!!null' is given the value 'x'"),
    ("!!seq x", "the YAML tag '!!seq' does not fit a single value"),
    ("!!map x", "the YAML tag '!!map' does not fit a single value"),
    ("!!binary aGk=", "the YAML tag '!!binary' is not allowed"),
    ("!!python/object:os.system x", "is not allowed"),
    ("!!int [1]", "the YAML tag '!!int' does not fit a list"),
    ("!!seq {b: 1}", "the YAML tag '!!seq' does not fit a map"),
])
def test_a_tag_that_does_not_fit_its_value_is_refused_at_its_line(written: str,
                                                                     message: str) -> None:
    line, got = _refusal(f"x: 1\na: {written}\n")
    assert line == 2 and message in got


def test_integers_past_the_digit_limit_are_refused() -> None:
    assert _value("9" * MAX_INT_DIGITS) == int("9" * MAX_INT_DIGITS)
    line, message = _refusal("a: " + "9" * 5000 + "\n")
    assert line == 1 and "5000 digits is too large" in message


def test_deep_nesting_is_refused_before_the_stack_runs_out() -> None:
    assert _value("[" * (MAX_DEPTH - 1) + "]" * (MAX_DEPTH - 1)) is not None
    for depth in (MAX_DEPTH + 1, 600, 50_000):
        line, message = _refusal("a: " + "[" * depth + "]" * depth + "\n")
        assert line == 1 and f"nested more than {MAX_DEPTH} deep" in message


def test_a_recursive_alias_is_refused() -> None:
    line, message = _refusal("x: 1\na: &loop [1, *loop]\n")
    assert line == 2 and "refers to the list or map that contains it" in message


def test_alias_expansion_is_bounded() -> None:
    bomb = "a0: &a0 [lol, lol, lol, lol, lol, lol, lol, lol, lol]\n"
    for level in range(1, 10):
        bomb += f"a{level}: &a{level} [" + ", ".join([f"*a{level - 1}"] * 9) + "]\n"
    line, message = _refusal(bomb)
    assert line is not None and f"more than {MAX_ALIASED_VALUES:,} values repeated" in message


def test_plain_aliases_still_work() -> None:
    data, _ = read_yaml("a: &s [0, 0, 1, 1]\nb: *s\n", "f.yaml")
    assert data == {"a": [0, 0, 1, 1], "b": [0, 0, 1, 1]}


@pytest.mark.parametrize("character", ["\x00", "\x07", "\x1b"])
def test_a_control_character_is_refused_with_its_line(character: str) -> None:
    line, message = _refusal(f"x: 1\na: b{character}c\n")
    assert line == 2 and f"U+{ord(character):04X}" in message


@pytest.mark.slow
def test_a_large_file_reads_like_a_small_one() -> None:
    from flctool.behaviour import yaml_source

    body = "".join(f"k{i}: [{i}, yes, 010, 1:00, ~, true, 0x10]\n" for i in range(3000))
    assert len(body) > yaml_source._LIBYAML_FROM  # read by libyaml, where installed
    data, source = read_yaml(body, "big.yaml")
    assert data["k2999"] == [2999, "yes", 10, "1:00", None, True, 16]
    assert source.locate(("k2999", 1)) == (3000, 15)
    for bad, message in (("x: " + "[" * 100 + "]" * 100, f"nested more than {MAX_DEPTH} deep"),
                         ("x: &a [1, *a]", "refers to the list or map that contains it"),
                         ("x: !!int abc", "'abc' is not an integer")):
        line, got = _refusal(body + bad + "\n")
        assert line == 3001 and message in got


def test_both_parsers_read_the_same_values_marks_and_raw_texts() -> None:
    """Files above _LIBYAML_FROM are read by libyaml, smaller ones by PyYAML's parser: the
    same events, so the same values, positions and remembered spellings."""
    from flctool.behaviour import yaml_source

    body = ("a: &x [1, yes, 010, {b: ~, c: 'q'}]\nd: *x\ne: [off, 1:00, !!str 2]\n"
            "f:\n  - {g: true}\n  - [h, [i]]\n")
    padding = "#" + " " * yaml_source._LIBYAML_FROM + "\n"
    small_data, small = read_yaml(body, "f.yaml")
    large_data, large = read_yaml(padding + body, "f.yaml")
    assert small_data == large_data
    paths = [("a",), ("a", 1), ("a", 3, "b"), ("d", 2), ("d", 3, "c"), ("e", 1), ("f", 1, 1, 0)]
    for path in paths:
        line, column = small.locate(path)
        assert large.locate(path) == (line + 1 if line else line, column)
    assert small.raw == large.raw
    assert small.raw[("e", 0)] == "off" and small.raw[("d", 3, "b")] == "~"
    assert small.locate(("d", 3, "c")) == (1, 28)  # inside an alias: where the anchor has it


@pytest.mark.parametrize(("text", "message"), [
    ("a: &x 1\nb: &x 2\n", "found duplicate anchor 'x'"),
    ("a: *nowhere\n", "found undefined alias 'nowhere'"),
    ("a: 1\n---\nb: 2\n", "found another document"),
    ("? [a, b]\n: 1\n", "a key must be a plain name"),
])
def test_a_broken_document_is_refused_with_its_line(text: str, message: str) -> None:
    line, got = _refusal(text)
    assert line is not None and message in got


def test_a_value_after_a_refused_key_is_skipped_and_the_map_goes_on() -> None:
    with pytest.raises(SpecError) as info:
        read_yaml("m:\n  ? {k: 1}\n  : [1, 2]\n  n: 3\n", "f.yaml")
    assert [p.message for p in info.value.problems] == ["a key must be a plain name"]
    data, _ = read_yaml("m:\n  n: 3\n", "f.yaml")
    assert data == {"m": {"n": 3}}


def test_the_garbage_collector_runs_again_after_a_read_however_it_ends() -> None:
    import gc

    from flctool.behaviour import parse_behaviour

    assert gc.isenabled()
    read_yaml("a: [1, 2]\n", "f.yaml")
    assert gc.isenabled()
    with pytest.raises(SpecError):
        parse_behaviour("flctool: 1\na: [\n", "f.yaml")
    assert gc.isenabled()
    gc.disable()
    try:  # a caller that paused it keeps it paused
        read_yaml("a: 1\n", "f.yaml")
        assert not gc.isenabled()
    finally:
        gc.enable()
