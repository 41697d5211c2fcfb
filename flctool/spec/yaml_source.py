"""Safe YAML reading that remembers where every value came from.

PyYAML's ``safe_load`` forgets line numbers and silently keeps the last of two duplicate keys.
Here the document is composed into nodes, checked, and turned into plain Python values while
every field path is mapped to its line and column, so that later validation errors can point
at the exact place in the file.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Any

import yaml

from flctool.errors import PathPart, Problem, SpecError

#: Bounds on what a behaviour file may hold, so a hostile or broken file is refused with a
#: message instead of exhausting the stack or the memory (docs/behaviour-files.md).
MAX_DEPTH = 64  # nested lists and maps; a behaviour file needs about 6
MAX_VALUES = 10_000_000  # values in all
MAX_ALIASED_VALUES = 100_000  # values repeated by aliases (*name): "billion laughs"
MAX_FILE_CHARS = 50_000_000
MAX_INT_DIGITS = 100

_STR = "tag:yaml.org,2002:str"
_INT = "tag:yaml.org,2002:int"
_FLOAT = "tag:yaml.org,2002:float"
_BOOL = "tag:yaml.org,2002:bool"
_NULL = "tag:yaml.org,2002:null"
_MAP = "tag:yaml.org,2002:map"
_SEQ = "tag:yaml.org,2002:seq"
# Tags that build plain data. Anything else (``!!python/object``, custom ``!tags``) would
# construct objects, so it is refused rather than ignored.
_SCALAR_TAGS = {_STR, _INT, _FLOAT, _BOOL, _NULL}

# The YAML 1.2 core schema (yaml.org/spec/1.2.2 10.3.2). PyYAML implements YAML 1.1, which
# reads yes/no/on/off as booleans, 010 as 8 and 1:00 as 60: a number must be what was written.
_CORE_NULL = re.compile(r"^(?:~|null|Null|NULL|)$")
_CORE_BOOL = re.compile(r"^(?:true|True|TRUE|false|False|FALSE)$")
_CORE_INT = re.compile(r"^(?:[-+]?[0-9]+|0o[0-7]+|0x[0-9a-fA-F]+)$")
_CORE_FLOAT = re.compile(
    r"^(?:[-+]?(?:\.[0-9]+|[0-9]+(?:\.[0-9]*)?)(?:[eE][-+]?[0-9]+)?"
    r"|[-+]?\.(?:inf|Inf|INF)|\.(?:nan|NaN|NAN))$")
#: Plain scalars YAML 1.1 reads as booleans or numbers but YAML 1.2 as text; flctool keeps
#: them as text, and says so when a number or a yes/no was meant.
_YAML11_LOOKALIKE = re.compile(
    r"^(?:y|Y|yes|Yes|YES|n|N|no|No|NO|on|On|ON|off|Off|OFF"
    r"|[-+]?[0-9][0-9_]*(?::[0-5]?[0-9])+(?:\.[0-9_]*)?"
    r"|[-+]?0b[01_]+|[-+]?(?:[0-9][0-9_]*)?\.?[0-9_]*(?:[eE][-+]?[0-9]+)?)$")


class _CoreResolver(yaml.resolver.BaseResolver):
    """Plain scalars resolve by the YAML 1.2 core schema, not PyYAML's YAML 1.1 rules."""

    def resolve(self, kind: Any, value: Any, implicit: Any) -> str:
        if kind is yaml.ScalarNode and implicit[0]:
            if _CORE_NULL.match(value):
                return _NULL
            if _CORE_BOOL.match(value):
                return _BOOL
            if _CORE_INT.match(value):
                return _INT
            if _CORE_FLOAT.match(value):
                return _FLOAT
            return _STR
        if kind is yaml.ScalarNode:  # quoted: always text
            return _STR
        return _SEQ if kind is yaml.SequenceNode else _MAP


class _Loader(yaml.reader.Reader, yaml.scanner.Scanner, yaml.parser.Parser,
              yaml.composer.Composer, _CoreResolver):
    """Composes nodes only (nothing is constructed), refusing nesting past MAX_DEPTH before
    PyYAML's recursive composer can exhaust the stack."""

    def __init__(self, stream: str) -> None:
        yaml.reader.Reader.__init__(self, stream)
        yaml.scanner.Scanner.__init__(self)
        yaml.parser.Parser.__init__(self)
        yaml.composer.Composer.__init__(self)
        _CoreResolver.__init__(self)
        self.depth = 0

    def compose_node(self, parent: Any, index: Any) -> Any:
        self.depth += 1
        if self.depth > MAX_DEPTH:
            raise yaml.composer.ComposerError(
                None, None, f"lists and maps are nested more than {MAX_DEPTH} deep",
                self.peek_event().start_mark)  # type: ignore[no-untyped-call]
        try:
            return super().compose_node(parent, index)
        finally:
            self.depth -= 1


Path = tuple[PathPart, ...]


@dataclass
class SourceMap:
    """Field path -> (line, column), both 1-based, for one YAML document."""

    file: str
    marks: dict[Path, tuple[int, int]] = field(default_factory=dict)
    #: The text of plain scalars read as booleans or null (``true``, ``~``) or as text that
    #: YAML 1.1 would have read as one (``off``, ``yes``, ``1:00``), so a message can say what
    #: the user wrote.
    raw: dict[Path, str] = field(default_factory=dict)
    #: Whether this map is of a parsed file (then every problem has at least line 1).
    parsed: bool = False
    #: Field paths given somewhere else than the file (a ``--set`` on the command line) ->
    #: where, e.g. ``command line (--set q.alpha)``: a problem inside one is placed there.
    overrides: dict[Path, str] = field(default_factory=dict)

    def with_overrides(self, overrides: dict[Path, str]) -> SourceMap:
        """This map with more fields given elsewhere (see :attr:`overrides`)."""
        return SourceMap(self.file, self.marks, self.raw, self.parsed,
                         {**self.overrides, **overrides})

    def locate(self, path: Path) -> tuple[int | None, int | None]:
        """The position of ``path``, or of its nearest ancestor that the file has (the start
        of the file for an empty one)."""
        for end in range(len(path), -1, -1):
            mark = self.marks.get(tuple(path[:end]))
            if mark is not None:
                return mark
        return (1, 1) if self.parsed else (None, None)

    def problem(self, path: Path, message: str, hint: str = "") -> Problem:
        path = tuple(path)
        for given, where in self.overrides.items():
            # inside an override, or a key the file does not have that an override made
            # (``--set exploration.policy=...`` adds ``exploration`` itself)
            made_by_it = bool(path) and given[: len(path)] == path and path not in self.marks
            if path[: len(given)] == given or made_by_it:
                return Problem(path=path, message=message, hint=hint, file=where)
        line, column = self.locate(path)
        return Problem(path=path, message=message, hint=hint, file=self.file, line=line,
                       column=column)


# Large files are parsed by libyaml (PyYAML's C parser) when it is installed: the pure-Python
# parser needs tens of seconds for a file of a few megabytes.
_LIBYAML_FROM = 64 * 1024
_CParser: Any
try:
    from yaml._yaml import CParser as _CParser
except ImportError:  # pragma: no cover - PyYAML built without libyaml
    _CParser = None


if _CParser is not None:
    class _CLoader(_CParser, _CoreResolver):  # type: ignore[misc]
        """libyaml's composer with the YAML 1.2 core resolver."""

        def __init__(self, stream: str) -> None:
            _CParser.__init__(self, stream)
            _CoreResolver.__init__(self)


def _check_depth(text: str) -> None:
    """Refuse nesting past MAX_DEPTH before libyaml's (recursive) composer sees it; walking
    the events needs no recursion."""
    parser = _CParser(text)
    depth = 0
    while True:
        event = parser.get_event()
        if isinstance(event, (yaml.SequenceStartEvent, yaml.MappingStartEvent)):
            depth += 1
            if depth > MAX_DEPTH:
                mark: Any = event.start_mark
                raise yaml.composer.ComposerError(
                    None, None, f"lists and maps are nested more than {MAX_DEPTH} deep", mark)
        elif isinstance(event, (yaml.SequenceEndEvent, yaml.MappingEndEvent)):
            depth -= 1
        elif isinstance(event, yaml.StreamEndEvent):
            return


def _mark(node: yaml.Node) -> tuple[int, int]:
    return node.start_mark.line + 1, node.start_mark.column + 1


class _Refused(Exception):
    """A scalar cannot be read as its tag says: (message, hint)."""


def _short(tag: str) -> str:
    return tag.replace("tag:yaml.org,2002:", "!!")


def _scalar(node: yaml.ScalarNode) -> Any:
    """The value of a scalar under the YAML 1.2 core schema (an explicit tag included)."""
    text, tag = str(node.value), node.tag
    if tag == _STR:
        return text
    if tag == _NULL:
        if _CORE_NULL.match(text):
            return None
        raise _Refused(f"'!!null' is given the value '{text}'", "remove the tag or the value")
    if tag == _BOOL:
        if _CORE_BOOL.match(text):
            return text.lower() == "true"
        raise _Refused(f"'{text}' is not a boolean", "write true or false")
    if tag == _INT:
        if not _CORE_INT.match(text):
            raise _Refused(f"'{text}' is not an integer", "write digits, e.g. 10")
        digits = len(text.lstrip("+-"))
        if digits > MAX_INT_DIGITS:
            raise _Refused(f"an integer of {digits} digits is too large (at most "
                           f"{MAX_INT_DIGITS})", "write a smaller number")
        if text.startswith("0o"):
            return int(text[2:], 8)
        if text.startswith("0x"):
            return int(text[2:], 16)
        return int(text, 10)
    if tag == _FLOAT:
        if not (_CORE_FLOAT.match(text) or _CORE_INT.match(text)):
            raise _Refused(f"'{text}' is not a number", "write e.g. 0.5 or 1e-3")
        lowered = text.lower()
        if lowered.endswith((".inf", ".nan")):
            return float(lowered.replace(".", ""))
        if _CORE_INT.match(text) and not text.lstrip("+-").isdigit():
            return float(int(text[2:], 8 if text.startswith("0o") else 16))
        return float(text)
    if tag in (_SEQ, _MAP):
        raise _Refused(f"the YAML tag '{_short(tag)}' does not fit a single value",
                       "remove the tag")
    raise _Refused(f"the YAML tag '{_short(tag)}' is not allowed",
                   "remove the tag; behaviour files hold plain numbers, strings, lists and maps")


def _lookalike(text: str) -> bool:
    """Whether YAML 1.1 (but not 1.2) would have read this plain text as a bool or number."""
    return bool(text) and bool(_YAML11_LOOKALIKE.match(text)) and any(
        c.isalnum() for c in text)


class _Builder:
    def __init__(self, source: SourceMap) -> None:
        self.source = source
        self.problems: list[Problem] = []
        self.values = 0
        self.aliased = 0  # values built again because an alias repeats them
        self.built: set[int] = set()  # ids of the nodes built so far
        self.building: set[int] = set()  # ids of the collections being built: alias cycles
        self.repeating = 0  # > 0 inside a node that is built a second time

    def build(self, node: yaml.Node, path: Path) -> Any:
        self.source.marks.setdefault(path, _mark(node))
        self.values += 1
        repeat = id(node) in self.built
        self.built.add(id(node))
        self.repeating += repeat
        try:
            if self.repeating:
                self.aliased += 1
            if self.values > MAX_VALUES or self.aliased > MAX_ALIASED_VALUES:
                many, limit = ("values", MAX_VALUES) if self.values > MAX_VALUES else (
                    "values repeated by aliases (*name)", MAX_ALIASED_VALUES)
                raise SpecError([self.source.problem(
                    path, f"the file holds more than {limit:,} {many}",
                    "write fewer values, or use fewer aliases")], self.source.file)
            return self._node(node, path)
        finally:
            self.repeating -= repeat

    def _node(self, node: yaml.Node, path: Path) -> Any:
        if isinstance(node, yaml.ScalarNode):
            return self._scalar(node, path)
        wanted = _MAP if isinstance(node, yaml.MappingNode) else _SEQ
        if node.tag != wanted:
            self.problems.append(self.source.problem(
                path, f"the YAML tag '{_short(node.tag)}' does not fit a "
                f"{'map' if wanted == _MAP else 'list'}", "remove the tag"))
            return None
        if id(node) in self.building:
            self.problems.append(self.source.problem(
                path, "an alias refers to the list or map that contains it, so the value "
                "would be infinite", "remove the alias (*name) or point it elsewhere"))
            return None
        self.building.add(id(node))
        try:
            if isinstance(node, yaml.MappingNode):
                return self._mapping(node, path)
            return [self.build(item, (*path, i)) for i, item in enumerate(node.value)]
        finally:
            self.building.discard(id(node))

    def _scalar(self, node: yaml.ScalarNode, path: Path) -> Any:
        try:
            value = _scalar(node)
        except _Refused as refused:
            message, hint = refused.args
            self.problems.append(self.source.problem(path, message, hint))
            return None
        if value is None or isinstance(value, bool) or (
                node.tag == _STR and node.style is None and _lookalike(node.value)):
            self.source.raw[path] = str(node.value)
        return value

    def _mapping(self, node: yaml.MappingNode, path: Path) -> dict[Any, Any]:
        result: dict[Any, Any] = {}
        for key_node, value_node in node.value:
            # Every key of a behaviour file is a name or a field, so a key is the text
            # written: `off:` is the name "off", not a boolean.
            if not isinstance(key_node, yaml.ScalarNode) or key_node.tag not in _SCALAR_TAGS:
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


def read_yaml(text: str, file: str) -> tuple[Any, SourceMap]:
    """Parse ``text`` safely into plain values and a :class:`SourceMap`.

    Plain scalars follow the YAML 1.2 core schema. Raises :class:`SpecError` for malformed
    YAML, duplicate keys, object-building or misplaced tags, recursive aliases and files past
    the bounds MAX_DEPTH, MAX_VALUES, MAX_INT_DIGITS and MAX_FILE_CHARS.
    """
    source = SourceMap(file, parsed=True)
    if len(text) > MAX_FILE_CHARS:
        raise SpecError([Problem((), f"the file has {len(text):,} characters, more than the "
                                 f"{MAX_FILE_CHARS:,} a behaviour file may have", file=file)],
                        file)
    loader: Any = None
    try:
        if len(text) > _LIBYAML_FROM and _CParser is not None:
            _check_depth(text)
            loader = _CLoader(text)
        else:
            loader = _Loader(text)
        node = loader.get_single_node()
    except yaml.MarkedYAMLError as exc:
        raise SpecError([_syntax_problem(exc, text, file)], file) from None
    except yaml.YAMLError as exc:
        raise SpecError([_unmarked_problem(exc, text, file)], file) from None
    finally:
        if loader is not None:
            loader.dispose()
    if node is None:
        return None, source
    builder = _Builder(source)
    data = builder.build(node, ())
    if builder.problems:
        raise SpecError(builder.problems, file)
    return data, source


def _unmarked_problem(exc: yaml.YAMLError, text: str, file: str) -> Problem:
    """Errors PyYAML gives a position, not a mark (e.g. a control character)."""
    position = getattr(exc, "position", None)
    line = column = None
    if isinstance(position, int):
        before = text[:position]
        line = before.count("\n") + 1
        column = position - (before.rfind("\n") + 1) + 1
    what = getattr(exc, "reason", None) or str(exc).splitlines()[0]
    character = getattr(exc, "character", None)
    if isinstance(character, (int, str)):
        code = character if isinstance(character, int) else ord(character)
        what = f"the character U+{code:04X} is not allowed in YAML"
    return Problem((), f"not valid YAML: {what}", hint="delete the character", file=file,
                   line=line, column=column)


def _syntax_problem(exc: yaml.MarkedYAMLError, text: str, file: str) -> Problem:
    mark = exc.problem_mark or exc.context_mark
    line = mark.line + 1 if mark else None
    column = mark.column + 1 if mark else None
    what = exc.problem or "malformed YAML"
    hint = "check the indentation and punctuation on this line and the one before"
    if "nesting depth" in what:  # libyaml's own limit, past ours
        what = f"lists and maps are nested more than {MAX_DEPTH} deep"
    if "nested more than" in what:
        hint = "a behaviour file needs only a few levels; flatten the value"
    if mark is not None:
        bad_line = text.splitlines()[mark.line] if mark.line < len(text.splitlines()) else ""
        if "\t" in bad_line[: mark.column + 1] or "found character '\\t'" in what:
            what = "a tab character is used for indentation"
            hint = "YAML indents with spaces only; replace the tab with spaces"
    return Problem((), f"not valid YAML: {what}", hint=hint, file=file, line=line,
                   column=column)
