"""Property-based fuzzing of behaviour files: every shipped behaviour, mutated, is loaded and
compiled in process. Whatever the mutation, only flctool's own errors may escape, every
problem names its line, and a value written as a YAML 1.2 boolean or string never becomes a
number. (benchmarks/mutation_fuzz.py runs the same idea at scale, with a time limit.)"""

from __future__ import annotations

import math
import re
from typing import Any

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from flctool.behaviour import parse_behaviour
from flctool.compile import compile_behaviour
from flctool.errors import FlcError, SpecError

from ..conftest import BEHAVIOURS

SOURCES = {path.name: path.read_text(encoding="utf-8")
           for path in sorted(BEHAVIOURS.glob("*.yaml"))}

#: Hostile scalars, each with the number YAML 1.2 reads it as (None: not a number).
TOKENS: list[tuple[str, float | None]] = [
    ("yes", None), ("no", None), ("on", None), ("off", None), ("true", None), ("False", None),
    ("~", None), ("", None), ("1:00", None), ("1_000", None), ("0b11", None), (".nan", None),
    ("010", 10.0), ("0x10", 16.0), ("0o10", 8.0), ("-0", 0.0), ("1e309", math.inf),
    ("1e8", 1e8), ("100000000", 1e8), ("-1", -1.0), ("9" * 5000, None), ("chase-mine", None),
    ("'2'", None), ("[1, 2]", None), ("{a: 1}", None), ("!!null ''", None), ("!!bool 3", None),
    ("!!int abc", None), ("!!float x", None), ("!!seq x", None), ("!!map x", None),
    ("!!str 1", None), ("!!binary aGk=", None), ("!!python/object:os.system x", None),
    ("!x 1", None), ("*nowhere", None), ("&a [*a]", None), ("[" * 300 + "]" * 300, None),
    ("\"\\x1b[31m\"", None), ("this:CartPole-v1", None), ("{success: 2}", None),
    ("{sucess: 0.5}", None), ("{angle: [0, x]}", None),
]

#: What pydantic calls its own parts; a problem must speak of the file's.
INTERNAL = re.compile(r"function-(after|before|wrap|plain)\[|constrained-|instance of|"
                      r"lax-or-strict|json-or-python|\[key\]")


def _scalars(text: str) -> list[tuple[tuple[Any, ...], yaml.ScalarNode]]:
    found: list[tuple[tuple[Any, ...], yaml.ScalarNode]] = []

    def walk(node: yaml.Node, path: tuple[Any, ...]) -> None:
        if isinstance(node, yaml.MappingNode):
            for key, value in node.value:
                walk(value, (*path, key.value))
        elif isinstance(node, yaml.SequenceNode):
            for i, item in enumerate(node.value):
                walk(item, (*path, i))
        elif isinstance(node, yaml.ScalarNode):
            found.append((path, node))

    walk(yaml.compose(text, Loader=yaml.SafeLoader), ())
    return found


SCALARS = {name: _scalars(text) for name, text in SOURCES.items()}


def _load(text: str) -> Any:
    """Load and compile; returns the behaviour, or None after a located flctool error."""
    try:
        behaviour = parse_behaviour(text, "fuzzed.yaml")
        compile_behaviour(behaviour)
    except SpecError as error:
        assert error.problems
        for problem in error.problems:
            assert problem.file == "fuzzed.yaml" and problem.line is not None, str(error)
            assert not INTERNAL.search(str(problem)), str(problem)
        return None
    except FlcError:
        return None
    return behaviour


def _value_at(data: Any, path: tuple[Any, ...]) -> Any:
    for part in path:
        found = (isinstance(data, dict) and part in data) or (
            isinstance(data, list) and isinstance(part, int) and part < len(data))
        if not found:
            return None
        data = data[part]
    return data


FUZZ = settings(max_examples=80, deadline=None, derandomize=True,
                suppress_health_check=[HealthCheck.too_slow])


@FUZZ
@given(st.sampled_from(sorted(SOURCES)), st.data())
@pytest.mark.slow
def test_a_replaced_scalar_is_read_as_written_or_refused_at_its_line(name: str,
                                                                     data: st.DataObject) -> None:
    path, node = data.draw(st.sampled_from(SCALARS[name]), label="scalar")
    token, number = data.draw(st.sampled_from(TOKENS), label="token")
    text = SOURCES[name]
    mutated = text[:node.start_mark.index] + token + text[node.end_mark.index:]
    behaviour = _load(mutated)
    if behaviour is None:
        return
    value = _value_at(behaviour.model_dump(by_alias=True), path)
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        assert number is not None and float(value) == number, (token, path, value)


@FUZZ
@given(st.sampled_from(sorted(SOURCES)), st.data())
@pytest.mark.slow
def test_random_text_in_place_of_a_scalar_never_crashes(name: str, data: st.DataObject) -> None:
    _, node = data.draw(st.sampled_from(SCALARS[name]), label="scalar")
    token = data.draw(st.text(max_size=12), label="text")
    text = SOURCES[name]
    _load(text[:node.start_mark.index] + token + text[node.end_mark.index:])


@FUZZ
@given(st.sampled_from(sorted(SOURCES)), st.data())
@pytest.mark.slow
def test_line_edits_never_crash(name: str, data: st.DataObject) -> None:
    lines = SOURCES[name].splitlines()
    i = data.draw(st.integers(0, len(lines) - 1), label="line")
    edit = data.draw(st.sampled_from(["delete", "duplicate", "indent", "dedent", "tab",
                                      "truncate", "swap", "insert"]), label="edit")
    if edit == "delete":
        del lines[i]
    elif edit == "duplicate":
        lines.insert(i, lines[i])
    elif edit == "indent":
        lines[i] = "  " + lines[i]
    elif edit == "dedent":
        lines[i] = lines[i].removeprefix("  ")
    elif edit == "tab":
        lines[i] = "\t" + lines[i].lstrip()
    elif edit == "truncate":
        lines = lines[:i]
    elif edit == "swap":
        j = data.draw(st.integers(0, len(lines) - 1), label="other line")
        lines[i], lines[j] = lines[j], lines[i]
    else:
        lines.insert(i, data.draw(st.text(max_size=20), label="inserted"))
    _load("\n".join(lines) + "\n")


@pytest.mark.slow
def test_sizes_and_bombs_are_refused_at_their_line() -> None:
    text = SOURCES["ballchase.yaml"]
    bomb = "a0: &a0 [lol, lol, lol, lol, lol, lol, lol, lol, lol]\n" + "".join(
        f"a{n}: &a{n} [" + ", ".join([f"*a{n - 1}"] * 9) + "]\n" for n in range(1, 10))
    wide = "".join(f"  x{i}:\n    range: [0, 1]\n    sets: {{lo: [0, 0, 0, 1], "
                   "hi: [0, 1, 1, 1]}\n" for i in range(30))
    for mutated in (
            text.replace("description:", bomb + "description:", 1),
            text.replace("rules: []", "rules: &r [*r]"),
            text + "x: " + "[" * 3000 + "]" * 3000 + "\n",
            text.replace("learning:\n", "learning:\n  population: 100000000\n", 1),
            text.replace("adapter: ballchase-sim", "adapter: ballchase-sim\n  max_steps: "
                         "100000000"),
            text.split("inputs:")[0] + "inputs:\n" + wide + "output:" + text.split("output:")[1],
    ):
        assert _load(mutated) is None
