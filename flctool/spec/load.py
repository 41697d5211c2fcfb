"""Loading behaviour files: YAML text -> validated, frozen :class:`Behaviour`.

Every problem in a file is reported at once, each with file, line, column, field path, what is
wrong and how to fix it.
"""

from __future__ import annotations

import types
import typing
from pathlib import Path
from typing import Any

from pydantic import BaseModel, ValidationError

from flctool.errors import PathPart, Problem, SpecError
from flctool.registry import did_you_mean
from flctool.spec.environment import ADAPTER_NAMES
from flctool.spec.models import FORMAT_VERSION, Behaviour
from flctool.spec.yaml_source import SourceMap, read_yaml


def load_behaviour(path: str | Path) -> Behaviour:
    """Read and validate a behaviour file; raises :class:`SpecError` listing every problem."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise SpecError([Problem((), "no such file", "check the path", file=str(path))],
                        str(path)) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise SpecError([Problem((), f"cannot read the file: {exc}", file=str(path))],
                        str(path)) from None
    return parse_behaviour(text, str(path))


def parse_behaviour(text: str, file: str = "<string>") -> Behaviour:
    """Validate behaviour YAML given as text (``file`` names it in messages)."""
    data, source = read_yaml(text, file)
    return behaviour_from_data(data, source)


def behaviour_from_data(data: Any, source: SourceMap | None = None) -> Behaviour:
    """Validate already-parsed data (e.g. from JSON); ``source`` locates errors if known."""
    source = source or SourceMap("<data>")
    if not isinstance(data, dict):
        kind = "empty" if data is None else f"a {type(data).__name__}"
        raise SpecError([source.problem((), f"a behaviour file must be a mapping, but this is "
                                        f"{kind}", "start from behaviours/ballchase.yaml")],
                        source.file)
    version_problem = _version_problem(data, source)
    if version_problem is not None:  # other errors in a file of another version are noise
        raise SpecError([version_problem], source.file)
    semantic: list[Problem] = []
    try:
        behaviour = Behaviour.model_validate(data, context={"problems": semantic})
    except ValidationError as exc:
        problems = [_translate(error, source) for error in exc.errors()]
        raise SpecError(problems, source.file) from None
    if semantic:
        raise SpecError([source.problem(p.path, p.message, p.hint) for p in semantic],
                        source.file)
    return behaviour


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


def _translate(error: Any, source: SourceMap) -> Problem:
    """A pydantic error dict -> a located, human :class:`Problem`."""
    loc: list[PathPart] = list(error["loc"])
    kind = error["type"]
    message = error["msg"]
    hint = ""
    # A discriminated union puts the chosen tag into the path; the file does not have it.
    if len(loc) >= 2 and loc[0] == "environment" and loc[1] in ADAPTER_NAMES:
        del loc[1]
    raw = source.raw.get(tuple(loc))
    if loc and loc[-1] == "[key]":
        loc.pop()
        message = (f"'{loc[-1]}' is not a valid name: use letters, digits and _ only, "
                   "starting with a letter or _")
        hint = "rename it, e.g. far_left instead of far-left"
    elif raw is not None and kind in ("string_type", "float_type", "int_type"):
        if raw:
            reads = "null" if raw in ("~", "null", "Null", "NULL") else "a boolean"
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
    elif kind == "extra_forbidden":
        allowed = _allowed_keys(loc[:-1], error)
        message = f"unknown key '{loc[-1]}'.{did_you_mean(str(loc[-1]), allowed)}"
        hint = f"allowed keys here: {', '.join(allowed)}" if allowed else "remove it"
    elif kind == "union_tag_invalid":
        tag = error["ctx"]["tag"]
        loc.append("adapter")
        message = f"unknown adapter '{tag}'.{did_you_mean(tag, ADAPTER_NAMES)}"
        hint = f"use one of: {', '.join(ADAPTER_NAMES)}"
    elif kind == "union_tag_not_found":
        loc.append("adapter")
        message = "the environment names no 'adapter'"
        hint = f"add 'adapter:' with one of: {', '.join(ADAPTER_NAMES)}"
    elif kind == "too_short":
        message = f"'{loc[-1]}' is empty"
        hint = f"give at least {error['ctx']['min_length']} entry"
    elif kind == "value_error":
        message = message.removeprefix("Value error, ")
    else:
        got = error.get("input")
        if not isinstance(got, (dict, list)):
            message = f"{message[0].lower()}{message[1:]}, got {got!r}"
    return source.problem(tuple(loc), message, hint)


def _is_tuple_item(loc: list[PathPart], kind: str) -> bool:
    """Whether the error is about the length of a range pair or a set quadruple."""
    if kind == "missing":
        return len(loc) >= 2 and isinstance(loc[-1], int)
    return len(loc) >= 2 and (loc[-1] == "range" or loc[-2] == "sets")


def _allowed_keys(path: list[PathPart], error: Any) -> list[str]:
    """The keys the model at ``path`` accepts, found by walking the type annotations."""
    annotation: Any = Behaviour
    for part in path:
        annotation = _step(annotation, part)
        if annotation is None:
            return []
    models = [m for m in _members(annotation) if isinstance(m, type) and issubclass(m, BaseModel)]
    keys: list[str] = []
    for model in models:
        for name, info in model.model_fields.items():
            key = info.alias or name
            if key not in keys:
                keys.append(key)
    return keys


def _members(annotation: Any) -> list[Any]:
    origin = typing.get_origin(annotation)
    if origin is typing.Annotated:
        return _members(typing.get_args(annotation)[0])
    if origin in (typing.Union, types.UnionType):
        return [m for arg in typing.get_args(annotation) for m in _members(arg)]
    return [annotation]


def _step(annotation: Any, part: PathPart) -> Any:
    for member in _members(annotation):
        origin = typing.get_origin(member)
        if isinstance(member, type) and issubclass(member, BaseModel):
            for name, info in member.model_fields.items():
                if part in (name, info.alias):
                    return info.annotation
        elif origin is dict and isinstance(part, str):
            return typing.get_args(member)[1]
        elif origin is list and isinstance(part, int):
            return typing.get_args(member)[0]
    return None
