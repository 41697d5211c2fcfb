"""Loading behaviour files: YAML text -> validated, frozen :class:`Behaviour`.

Every problem in a file is reported at once, each with file, line, column, field path, what is
wrong and how to fix it.
"""

from __future__ import annotations

import re
import types
import typing
from pathlib import Path
from typing import Any

from pydantic import BaseModel, ValidationError

from flctool.behaviour.bounded import no_collection
from flctool.behaviour.checks import (
    RuleNamer,
    RuleProblem,
    check_input,
    check_rules,
    limit_problems,
    rule_path,
)
from flctool.behaviour.compose import inline_parts
from flctool.behaviour.dump import behaviour_to_data
from flctool.behaviour.environment import AdapterConfig
from flctool.behaviour.fuzzy import InputVariable, Rule
from flctool.behaviour.located import attach_source
from flctool.behaviour.magnitudes import magnitude_problems
from flctool.behaviour.models import FORMAT_VERSION, Behaviour
from flctool.behaviour.rules import expand_dont_care
from flctool.behaviour.sections import CHOSEN, foreign_key_message, section_model
from flctool.behaviour.yaml_source import MAX_FILE_CHARS, SourceMap, read_yaml
from flctool.errors import PathPart, Problem, SpecError
from flctool.inputs import read_input
from flctool.plugins import blamed, names
from flctool.registry import did_you_mean


def load_behaviour(path: str | Path) -> Behaviour:
    """Read and validate a behaviour file; raises :class:`SpecError` listing every problem."""
    return parse_behaviour(read_behaviour_text(path), str(path))


def read_behaviour_text(path: str | Path) -> str:
    """The text of a behaviour file; a missing or unreadable one is a :class:`SpecError`."""
    # read no further than the limit read_yaml refuses a file past (a 10 GB file costs no
    # more than a 50 MB one)
    return read_input(path, "behaviour file", MAX_FILE_CHARS)


def parse_behaviour(text: str, file: str = "<string>") -> Behaviour:
    """Validate behaviour YAML given as text (``file`` names it in messages)."""
    with no_collection():  # see flctool.behaviour.bounded
        data, source = read_yaml(text, file)
        return behaviour_from_data(data, source)


def behaviour_from_data(data: Any, source: SourceMap | None = None,
                        rule_names: RuleNamer = rule_path) -> Behaviour:
    """Validate already-parsed data (e.g. from JSON); ``source`` locates errors if known, and
    a message about another rule names it by ``rule_names`` (an imported file: by line)."""
    source = source or SourceMap("<data>")
    if not isinstance(data, dict):
        kind = "empty" if data is None else f"a {type(data).__name__}"
        raise SpecError([source.problem((), f"a behaviour file must be a mapping, but this is "
                                        f"{kind}", "start from behaviours/ballchase.yaml")],
                        source.file)
    version_problem = _version_problem(data, source)
    if version_problem is not None:  # other errors in a file of another version are noise
        raise SpecError([version_problem], source.file)
    data, source, problems = expand_dont_care(data, source)  # rules leaving out inputs
    data, part_problems = inline_parts(data, source, load_behaviour, behaviour_to_data)
    problems += part_problems
    # Numbers first: pydantic would quietly turn `true` into 1 and "1.5" into 1.5.
    problems += _number_problems(data, source)
    semantic: list[Problem] = []
    try:
        behaviour = Behaviour.model_validate(data, context={"problems": semantic})
    except ValidationError as exc:
        reported = {p.path for p in problems}
        problems += [p for p in (_translate(error, source, data)
                                 for error in _in_written_form(exc.errors(), data))
                     if p.path not in reported]
        # Report the cross-field problems of the parts that did validate too, in one pass.
        semantic = [p for p in _partial_problems(data)
                    if not any(_within(p.path, q.path) for q in problems)]
        problems += [_located(p, source, rule_names) for p in semantic]
        raise SpecError(_in_file_order(problems), source.file) from None
    problems += [_located(p, source, rule_names) for p in semantic]
    if problems:
        raise SpecError(_in_file_order(problems), source.file)
    attach_source(behaviour, source)  # later layers locate their errors with it
    return behaviour


def _located(problem: Problem, source: SourceMap, rule_names: RuleNamer) -> Problem:
    """A check's problem at its place in the file, naming other rules as the file does."""
    message = (problem.worded(rule_names) if isinstance(problem, RuleProblem)
               else problem.message)
    return source.problem(problem.path, message, problem.hint)


def _in_file_order(problems: list[Problem]) -> list[Problem]:
    return sorted(problems, key=lambda p: (p.line or 0, p.column or 0))


def _within(path: tuple[PathPart, ...], reported: tuple[PathPart, ...]) -> bool:
    """Whether ``path`` is ``reported`` or inside it, or contains it."""
    shorter = min(len(path), len(reported))
    return path[:shorter] == reported[:shorter]


def _partial_problems(data: dict[str, Any]) -> list[Problem]:
    """The cross-field checks of :mod:`flctool.behaviour.checks`, run on the sections of a file
    that validate on their own (the file as a whole did not)."""
    problems: list[Problem] = []
    inputs = data.get("inputs")
    sets: dict[str, list[str]] = {}
    if isinstance(inputs, dict):
        for name, raw in inputs.items():
            raw_sets = raw.get("sets") if isinstance(raw, dict) else None
            if isinstance(raw_sets, dict):
                sets[name] = list(raw_sets)
            try:
                variable = InputVariable.model_validate(raw)
            except ValidationError:
                continue
            problems += check_input(name, variable)
    output = data.get("output")
    commands = output.get("commands") if isinstance(output, dict) else None
    rules = data.get("rules")
    if isinstance(inputs, dict) and len(sets) == len(inputs) and isinstance(commands, dict) \
            and isinstance(rules, list):
        valid: list[tuple[int, Rule]] = []
        for index, raw in enumerate(rules):
            try:
                valid.append((index, Rule.model_validate(raw)))
            except ValidationError:
                continue
        problems += check_rules(sets, list(commands), valid)
    learning: dict[str, Any] = data.get("learning") or {}
    if not isinstance(learning, dict):
        learning = {}
    environment = data.get("environment")
    max_steps = environment.get("max_steps") if isinstance(environment, dict) else None
    problems += limit_problems([len(s) for s in sets.values()], *(
        value if isinstance(value, int) and not isinstance(value, bool) else None
        for value in (learning.get("population"), learning.get("trials"),
                      learning.get("generations"), max_steps)))
    if isinstance(environment, dict):  # the numbers as written, whatever else is wrong
        problems += magnitude_problems(environment)
    if isinstance(environment, dict) and isinstance(inputs, dict) and \
            isinstance(commands, dict):
        model = section_model("environment", environment)
        try:
            config = model.model_validate(environment) if model is not None else None
        except ValidationError:
            return problems
        if isinstance(config, AdapterConfig):
            with blamed("environment", config.adapter):
                problems += config.fit_problems(tuple(inputs), tuple(commands))
    return problems


def _number_problems(data: Any, source: SourceMap) -> list[Problem]:
    """Booleans and text given where the model wants a number, which pydantic would convert
    (``true`` -> 1, ``"2"`` -> 2.0) without a word."""
    problems: list[Problem] = []

    # The annotation of a part depends on the part and the annotation holding it (and, for a
    # section chosen by 'adapter', on that): looked up once each, not once per value.
    steps: dict[tuple[Any, Any], Any] = {}
    numeric: dict[Any, bool] = {}

    def step(annotation: Any, part: PathPart, container: Any) -> Any:
        if isinstance(container, dict) and "adapter" in container:
            return _step(annotation, part, container)
        key = (id(annotation), part if isinstance(part, str) or _positional(annotation)
               else int)
        if key not in steps:
            steps[key] = (_step(annotation, part, container), annotation)
        return steps[key][0]

    def walk(value: Any, annotation: Any, path: tuple[PathPart, ...]) -> None:
        if isinstance(value, dict):
            for key, item in value.items():
                inner = step(annotation, key, value)
                if inner is not None:
                    walk(item, inner, (*path, key))
        elif isinstance(value, list):
            for index, item in enumerate(value):
                inner = step(annotation, index, value)
                if inner is not None:
                    walk(item, inner, (*path, index))
        elif isinstance(value, (bool, str)):
            if id(annotation) not in numeric:
                numeric[id(annotation)] = _numeric(annotation)
            if numeric[id(annotation)]:
                problems.append(_not_a_number(value, source.raw.get(path), source, path))

    walk(data, Behaviour, ())
    return problems


def _positional(annotation: Any) -> bool:
    """Whether the items of a list at ``annotation`` may differ in type by position (a
    fixed-length tuple), so an index cannot stand for all."""
    return any(typing.get_origin(m) is tuple and Ellipsis not in typing.get_args(m)
               for m in _members(annotation))


def _numeric(annotation: Any) -> bool:
    members = [m for m in _members(annotation) if m is not type(None)]
    return bool(members) and all(m in (int, float) for m in members)


def _not_a_number(value: bool | str, raw: str | None, source: SourceMap,
                  path: tuple[PathPart, ...]) -> Problem:
    written = raw if raw is not None else str(value)
    if isinstance(value, bool):
        return source.problem(path, f"'{written}' is a boolean, not a number",
                              "write a number here")
    if raw is None:
        return source.problem(path, f"'{value}' is not a number",
                              "write a number here (a quoted number is text)")
    if ":" in value:
        hint = "write the number itself (YAML 1.1 read 1:00 as 60; flctool reads YAML 1.2)"
    elif "_" in value:
        hint = f"write it without _, e.g. {value.replace('_', '')}"
    else:
        hint = "write a number (yes/no/on/off are not numbers in YAML 1.2)"
    return source.problem(path, f"'{value}' is not a number", hint)


def _version_problem(data: dict[str, Any], source: SourceMap) -> Problem | None:
    version = data.get("flctool")
    if "flctool" not in data:
        return source.problem((), "the format version 'flctool' is missing",
                              f"add 'flctool: {FORMAT_VERSION}' as the first line")
    if isinstance(version, int) and not isinstance(version, bool) and version > FORMAT_VERSION:
        return source.problem(
            ("flctool",), f"this file uses format version {version}, but this flctool reads "
            f"version {FORMAT_VERSION} only", "upgrade flctool: pip install --upgrade flctool")
    return None


def _translate(error: Any, source: SourceMap, data: dict[str, Any]) -> Problem:
    """A pydantic error dict about ``data`` -> a located, human :class:`Problem`."""
    loc: list[PathPart] = list(error["loc"])
    kind = error["type"]
    message = error["msg"]
    hint = error.get("hint", "")  # one _in_written_form gave
    # The plugin whose model read the section the error is in, if it is a chosen one.
    chosen = CHOSEN[loc[0]].chosen(data.get(loc[0])) if loc and loc[0] in CHOSEN else None
    if len(loc) >= 5 and loc[0] == "inputs" and loc[2] == "sets" and loc[4] in _SET_FORMS:
        loc.pop(4)  # the form of a set (models.FuzzySet), chosen by how it is written
    raw = source.raw.get(tuple(loc))
    if loc and loc[-1] == "[key]":
        loc.pop()
        message = (f"'{loc[-1]}' is not a valid name: use letters, digits and _ only, "
                   "starting with a letter or _")
        hint = "rename it, e.g. far_left instead of far-left"
    elif kind == "string_pattern_mismatch":
        message = (f"'{error.get('input')}' is not a valid name: use letters, digits and _ "
                   "only, starting with a letter or _")
        hint = "rename it, e.g. far_left instead of far-left"
    elif raw is not None and kind in ("string_type", "float_type", "int_type"):
        if raw:
            reads = "null" if raw in ("~", "null", "Null", "NULL") else "a boolean"
            reads = reads if isinstance(error.get("input"), (bool, type(None))) else "text"
            message = f"'{raw}' reads as {reads} in YAML"
            hint = f"write it in quotes, '{raw}', if it is a name"
        else:
            message, hint = "no value is given", "write the value after the colon"
    elif kind in ("missing", "too_short", "too_long") and _is_tuple_item(loc, kind):
        if kind != "too_long":
            loc = loc[:-1]
        what = "a range needs 2 numbers [low, high]" if loc[-1] == "range" else (
            "a set needs 4 numbers [pa, pb, pc, pd]")
        message = f"{what}; this one has {'more' if kind == 'too_long' else 'fewer'}"
        hint = "write all of them, in order"
    elif kind == "missing":
        message = f"required field '{loc[-1]}' is missing"
        hint = f"add '{loc[-1]}:' here"
        environment = data.get("environment")
        if (len(loc) == 3 and loc[0] == "inputs" and loc[2] == "range"
                and isinstance(environment, dict) and environment.get("adapter") == "gymnasium"):
            # default_gymnasium_ranges reads it from a valid environment with finite bounds
            hint += (", or let the environment give it: fix the environment's problems, if "
                     "any; an observation with infinite bounds needs a range")
    elif kind == "extra_forbidden" and len(loc) == 2 and loc[0] == "learning" and chosen \
            and (foreign := foreign_key_message(str(loc[1]), chosen)) is not None:
        message = foreign  # another learner's key: say whose
    elif kind == "extra_forbidden":
        allowed = _allowed_keys(loc[:-1], data)
        message = f"unknown key '{loc[-1]}'.{did_you_mean(str(loc[-1]), allowed)}"
        hint = f"allowed keys here: {', '.join(allowed)}" if allowed else "remove it"
    elif kind == "union_tag_invalid" and loc and loc[0] in CHOSEN:
        tag = error["ctx"]["tag"]
        section = CHOSEN[str(loc[0])]
        known = names(section.kind)
        loc.append(section.key)
        message = f"unknown {section.key} '{tag}'.{did_you_mean(tag, known)}"
        hint = f"use one of: {', '.join(known)}"
    elif kind == "union_tag_not_found" and loc and loc[0] in CHOSEN:
        section = CHOSEN[str(loc[0])]
        loc.append(section.key)
        message = f"the {loc[0]} names no '{section.key}'"
        hint = f"add '{section.key}:' with one of: {', '.join(names(section.kind))}"
    elif kind == "too_short":
        message = f"'{loc[-1]}' is empty"
        hint = f"give at least {error['ctx']['min_length']} entry"
    elif kind == "value_error":
        message = message.removeprefix("Value error, ")
    elif kind in _MAPPING_EXPECTED:  # pydantic would name the model class
        message = f"a mapping is expected here, got {error.get('input')!r}"
        keys = _allowed_keys(loc, data)
        hint = hint or (f"write a mapping with one of: {', '.join(keys)}" if keys else "")
    else:
        got = error.get("input")
        if not isinstance(got, (dict, list)):
            message = f"{message[0].lower()}{message[1:]}, got {got!r}"
    return source.problem(tuple(loc), message, hint)


#: pydantic's error types that say a mapping was expected.
_MAPPING_EXPECTED = frozenset({"model_type", "model_attributes_type", "dict_type",
                               "dataclass_type"})
#: ... that a list was expected, or a list's length is wrong.
_LIST_EXPECTED = frozenset({"list_type", "tuple_type", "too_short", "too_long"})
#: ... and that a single value was expected.
_SCALAR_EXPECTED = frozenset({"float_type", "float_parsing", "int_type", "int_parsing",
                              "int_from_float", "string_type", "bool_type", "bool_parsing",
                              "literal_error", "finite_number"})
#: The names pydantic gives the forms of a union in an error's location: a type (float,
#: constrained-int, list[...], function-after[...]) or a model class.
_FORM_NAME = re.compile(r"(float|int|str|bool|constrained-[a-z]+|[a-z-]+\[.*\]|[A-Z]\w*)\Z")


def _in_written_form(errors: list[Any], data: dict[str, Any]) -> list[Any]:
    """The errors of a value that may be written in several forms (``stop.target``: a number
    or a mapping) about the form it is written in, and without the form's name.

    pydantic tries every form and reports each one's errors under the form's name (``float``,
    ``function-after[...]``); a user who wrote a mapping wants to hear about its keys, one who
    wrote a number about the number (and that a mapping would also do). An error whose form
    cannot be told (a validator's own message) is kept."""
    kept: list[Any] = []
    dropped: list[Any] = []  # about another form: said only if nothing else is at the place
    for error in errors:
        loc = list(error["loc"])
        value: Any = data
        for i, part in enumerate(loc):
            if (isinstance(value, dict) and part in value) or (
                    isinstance(value, list) and isinstance(part, int)):
                value = _item(value, part)
                continue
            if isinstance(part, str) and _FORM_NAME.match(part):
                shape = _shape_of_form(part, error["type"], loc[i + 1:])
                error = {**error, "loc": (*loc[:i], *loc[i + 1:]), "form": True}
                if shape is not None and shape != _shape(value):
                    dropped.append((tuple(loc[:i]), error))
                    break
                if _shape(value) == "scalar" and (keys := _allowed_keys(loc[:i], data)):
                    error["hint"] = f"a mapping with one of: {', '.join(keys)} would do too"
            kept.append(error)
            break
        else:
            kept.append(error)
    kept += [error for place, error in dropped
             if not any(tuple(e["loc"][:len(place)]) == place for e in kept)]
    return _one_per_place(kept)


def _shape(value: Any) -> str:
    return "mapping" if isinstance(value, dict) else "list" if isinstance(value, list) else (
        "scalar")


def _shape_of_form(name: str, kind: str, inner: list[PathPart]) -> str | None:
    """The shape of value a form's error is about (None: cannot be told): what its location
    goes on into, or what its type says was expected. A form that converts the value first
    (``function-before[...]``) may be about any shape."""
    if name.startswith(("function-before", "function-wrap", "function-plain")):
        return None
    if inner:
        return "list" if isinstance(inner[0], int) else "mapping"
    for shape, kinds in (("mapping", _MAPPING_EXPECTED), ("list", _LIST_EXPECTED),
                         ("scalar", _SCALAR_EXPECTED)):
        if kind in kinds:
            return shape
    return None


def _one_per_place(errors: list[Any]) -> list[Any]:
    """The errors of several forms at one place as one: "input should be 'all', or a valid
    list"."""
    merged: list[Any] = []
    at: dict[tuple[Any, ...], Any] = {}
    for error in errors:
        place = tuple(error["loc"])
        first = at.get(place) if error.get("form") else None
        if first is None:
            merged.append(error)
            if error.get("form"):
                at[place] = error
            continue
        other = error["msg"].removeprefix("Input should be ").removeprefix("input should be ")
        first["msg"] = f"{first['msg']}, or {other}"
    return merged


#: The tags of models.FuzzySet's forms.
_SET_FORMS = ("trapezoid", "shape")


def _is_tuple_item(loc: list[PathPart], kind: str) -> bool:
    """Whether the error is about the length of a range pair or a set quadruple."""
    if kind == "missing":
        return len(loc) >= 2 and isinstance(loc[-1], int)
    return len(loc) >= 2 and (loc[-1] == "range" or loc[-2] == "sets")


def _allowed_keys(path: list[PathPart], data: dict[str, Any]) -> list[str]:
    """The keys the model at ``path`` in ``data`` accepts, found by walking the type
    annotations (a section chosen by name: the named plugin's model)."""
    annotation: Any = Behaviour
    container: Any = data
    for part in path:
        annotation = _step(annotation, part, container)
        if annotation is None:
            return []
        container = _item(container, part)
    models = [m for m in _members(annotation, container)
              if isinstance(m, type) and issubclass(m, BaseModel)]
    keys: list[str] = []
    for model in models:
        for name, info in model.model_fields.items():
            key = info.alias or name
            if key not in keys:
                keys.append(key)
    return keys


def _members(annotation: Any, value: Any = None) -> list[Any]:
    """The types ``annotation`` allows; the base of a section chosen by name is the model of
    the plugin ``value`` (the section as data, if known) names."""
    origin = typing.get_origin(annotation)
    if origin is typing.Annotated:
        return _members(typing.get_args(annotation)[0], value)
    if origin in (typing.Union, types.UnionType):
        return [m for arg in typing.get_args(annotation) for m in _members(arg, value)]
    for chosen in CHOSEN.values():
        if annotation is chosen.base:
            name = chosen.chosen(value)
            return [(chosen.model(name) if name is not None else None) or annotation]
    return [annotation]


def _item(container: Any, part: PathPart) -> Any:
    """The value at ``part`` in ``container`` (None where there is none)."""
    if isinstance(container, dict):
        return container.get(part)
    if isinstance(container, list) and isinstance(part, int) and 0 <= part < len(container):
        return container[part]
    return None


def _step(annotation: Any, part: PathPart, container: Any) -> Any:
    """The annotation of ``part`` inside ``annotation`` (None if it has none); ``container``
    is the value holding ``part``, if known (it names the model of a chosen section)."""
    members = _members(annotation, container)
    for member in members:
        origin = typing.get_origin(member)
        if origin is tuple and isinstance(part, int):
            args = typing.get_args(member)
            if len(args) == 2 and args[1] is Ellipsis:
                return args[0]
            return args[part] if part < len(args) else None
        if isinstance(member, type) and issubclass(member, BaseModel):
            for name, info in member.model_fields.items():
                if part in (name, info.alias):
                    return info.annotation
        elif origin is dict and isinstance(part, str):
            return typing.get_args(member)[1]
        elif origin is list and isinstance(part, int):
            return typing.get_args(member)[0]
    return None
