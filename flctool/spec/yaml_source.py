"""Safe YAML reading that remembers where every value came from.

PyYAML's ``safe_load`` forgets line numbers and silently keeps the last of two duplicate keys.
Here the document is composed into nodes, checked, and turned into plain Python values while
every field path is mapped to its line and column, so that later validation errors can point
at the exact place in the file.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import yaml

from flctool.errors import PathPart, Problem, SpecError

# Tags that build plain data. Anything else (``!!python/object``, custom ``!tags``) would
# construct objects, so it is refused rather than ignored.
_PLAIN_TAGS = {
    "tag:yaml.org,2002:str",
    "tag:yaml.org,2002:int",
    "tag:yaml.org,2002:float",
    "tag:yaml.org,2002:bool",
    "tag:yaml.org,2002:null",
    "tag:yaml.org,2002:map",
    "tag:yaml.org,2002:seq",
}

Path = tuple[PathPart, ...]


@dataclass
class SourceMap:
    """Field path -> (line, column), both 1-based, for one YAML document."""

    file: str
    marks: dict[Path, tuple[int, int]] = field(default_factory=dict)
    #: The text of plain scalars that YAML read as booleans or null (``off``, ``yes``, ``~``),
    #: so a message can say what the user wrote.
    raw: dict[Path, str] = field(default_factory=dict)

    def locate(self, path: Path) -> tuple[int | None, int | None]:
        """The position of ``path``, or of its nearest ancestor that the file has."""
        for end in range(len(path), -1, -1):
            mark = self.marks.get(tuple(path[:end]))
            if mark is not None:
                return mark
        return None, None

    def problem(self, path: Path, message: str, hint: str = "") -> Problem:
        line, column = self.locate(path)
        return Problem(path=tuple(path), message=message, hint=hint, file=self.file, line=line,
                       column=column)


def _mark(node: yaml.Node) -> tuple[int, int]:
    return node.start_mark.line + 1, node.start_mark.column + 1


class _Builder:
    def __init__(self, source: SourceMap) -> None:
        self.source = source
        self.problems: list[Problem] = []
        self.scalars = yaml.SafeLoader("")  # only its scalar constructors are used

    def build(self, node: yaml.Node, path: Path) -> Any:
        self.source.marks.setdefault(path, _mark(node))
        if node.tag not in _PLAIN_TAGS:
            self.problems.append(self.source.problem(
                path, f"the YAML tag '{node.tag}' is not allowed",
                "remove the tag; behaviour files hold plain numbers, strings, lists and maps"))
            return None
        if isinstance(node, yaml.MappingNode):
            result: dict[Any, Any] = {}
            for key_node, value_node in node.value:
                # Every key of a behaviour file is a name or a field, so a key is the text
                # written: `off:` is the name "off", not YAML 1.1's boolean false.
                if not isinstance(key_node, yaml.ScalarNode) or key_node.tag not in _PLAIN_TAGS:
                    self.problems.append(self.source.problem(
                        path, "a key must be a plain name", "write the key as plain text"))
                    continue
                key = str(key_node.value)
                key_path = (*path, key)
                if key in result:
                    first_line = self.source.marks[key_path][0]
                    self.problems.append(Problem(
                        path=key_path, message=f"duplicate key '{key}' (first given on line "
                        f"{first_line}); YAML would silently keep only the last one",
                        hint="remove or rename one of the two", file=self.source.file,
                        line=_mark(key_node)[0], column=_mark(key_node)[1]))
                    continue
                self.source.marks[key_path] = _mark(key_node)
                result[key] = self.build(value_node, key_path)
                self.source.marks[key_path] = _mark(key_node)
            return result
        if isinstance(node, yaml.SequenceNode):
            return [self.build(item, (*path, i)) for i, item in enumerate(node.value)]
        value = self.scalars.construct_object(node, deep=True)
        if (value is None or isinstance(value, bool)) and isinstance(node, yaml.ScalarNode):
            self.source.raw[path] = str(node.value)
        return value


def read_yaml(text: str, file: str) -> tuple[Any, SourceMap]:
    """Parse ``text`` safely into plain values and a :class:`SourceMap`.

    Raises :class:`SpecError` for malformed YAML, duplicate keys or object-building tags.
    """
    source = SourceMap(file)
    try:
        node = yaml.compose(text, Loader=yaml.SafeLoader)
    except yaml.MarkedYAMLError as exc:
        raise SpecError([_syntax_problem(exc, text, file)], file) from None
    except yaml.YAMLError as exc:  # pragma: no cover - PyYAML marks nearly all its errors
        raise SpecError([Problem((), f"not valid YAML: {exc}", file=file)], file) from None
    if node is None:
        return None, source
    builder = _Builder(source)
    data = builder.build(node, ())
    if builder.problems:
        raise SpecError(builder.problems, file)
    return data, source


def _syntax_problem(exc: yaml.MarkedYAMLError, text: str, file: str) -> Problem:
    mark = exc.problem_mark or exc.context_mark
    line = mark.line + 1 if mark else None
    column = mark.column + 1 if mark else None
    what = exc.problem or "malformed YAML"
    hint = "check the indentation and punctuation on this line and the one before"
    if mark is not None:
        bad_line = text.splitlines()[mark.line] if mark.line < len(text.splitlines()) else ""
        if "\t" in bad_line[: mark.column + 1] or "found character '\\t'" in what:
            what = "a tab character is used for indentation"
            hint = "YAML indents with spaces only; replace the tab with spaces"
    return Problem((), f"not valid YAML: {what}", hint=hint, file=file, line=line,
                   column=column)
