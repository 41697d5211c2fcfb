"""Safe YAML reading that remembers where every value came from.

PyYAML's ``safe_load`` forgets line numbers and silently keeps the last of two duplicate keys.
Here the document is composed into nodes, checked, and turned into plain Python values while
every field path is mapped to its line and column, so that later validation errors can point
at the exact place in the file.
"""

from __future__ import annotations

import copy
import functools
import re
import sys
from array import array
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import yaml

from flctool.behaviour.bounded import no_collection
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


class _Parser(yaml.reader.Reader, yaml.scanner.Scanner, yaml.parser.Parser):
    """PyYAML's pure-Python parser: events only (nothing is composed or constructed)."""

    def __init__(self, stream: str) -> None:
        yaml.reader.Reader.__init__(self, stream)
        yaml.scanner.Scanner.__init__(self)
        yaml.parser.Parser.__init__(self)

    def dispose(self) -> None:
        yaml.parser.Parser.dispose(self)


Path = tuple[PathPart, ...]
Mark = tuple[int, int] | int


def unpack(mark: Mark) -> tuple[int, int]:
    """The (line, column) of a mark of :attr:`SourceMap.marks`."""
    if isinstance(mark, int):
        return mark >> 32, mark & 0xFFFFFFFF
    return mark


@dataclass
class SourceMap:
    """Field path -> (line, column), both 1-based, for one YAML document."""

    file: str
    #: A mark is a (line, column) pair, or the two packed into one int (``line << 32 |
    #: column``): a large file has a mark per value, and one int takes a third of a pair's
    #: memory.
    marks: Mapping[Path, Mark] = field(default_factory=dict)
    #: The text of plain scalars read as booleans or null (``true``, ``~``) or as text that
    #: YAML 1.1 would have read as one (``off``, ``yes``, ``1:00``), so a message can say what
    #: the user wrote.
    raw: dict[Path, str] = field(default_factory=dict)
    #: Whether this map is of a parsed file (then every problem has at least line 1).
    parsed: bool = False
    #: Field paths given somewhere else than the file (a ``--set`` on the command line) ->
    #: where, e.g. ``command line (--set q.alpha)``: a problem inside one is placed there.
    overrides: dict[Path, str] = field(default_factory=dict)

    #: The marks of the items of each list (by the list's path), packed, in item order: a
    #: list of a million numbers costs 8 bytes a mark here, not a path and an entry in
    #: :attr:`marks`.
    items: Mapping[Path, Sequence[int]] = field(default_factory=dict)

    def with_overrides(self, overrides: dict[Path, str]) -> SourceMap:
        """This map with more fields given elsewhere (see :attr:`overrides`)."""
        return SourceMap(self.file, self.marks, self.raw, self.parsed,
                         {**self.overrides, **overrides}, self.items)

    def mark(self, path: Path) -> tuple[int, int] | None:
        """The (line, column) where the file gives ``path``, if it does."""
        mark = self.marks.get(path)
        if mark is not None:
            return unpack(mark)
        if path and isinstance(path[-1], int):
            items = self.items.get(path[:-1])
            if items is not None and 0 <= path[-1] < len(items):
                return unpack(items[path[-1]])
        return None

    def locate(self, path: Path) -> tuple[int | None, int | None]:
        """The position of ``path``, or of its nearest ancestor that the file has (the start
        of the file for an empty one)."""
        for end in range(len(path), -1, -1):
            mark = self.mark(tuple(path[:end]))
            if mark is not None:
                return mark
        return (1, 1) if self.parsed else (None, None)

    def problem(self, path: Path, message: str, hint: str = "") -> Problem:
        path = tuple(path)
        for given, where in self.overrides.items():
            # inside an override, or a key the file does not have that an override made
            # (``--set exploration.policy=...`` adds ``exploration`` itself)
            made_by_it = bool(path) and given[: len(path)] == path and self.mark(path) is None
            if path[: len(given)] == given or made_by_it:
                return Problem(path=path, message=message, hint=hint, file=where)
        line, column = self.locate(path)
        return Problem(path=path, message=message, hint=hint, file=self.file, line=line,
                       column=column)


class SourceRef:
    """Holds a behaviour's :class:`SourceMap` outside its value: any two compare equal, so
    two behaviours with the same fields are equal wherever they were read from."""

    __slots__ = ("source",)

    def __init__(self, source: SourceMap | None = None) -> None:
        self.source = source

    def __eq__(self, other: object) -> bool:
        return True

    def __hash__(self) -> int:
        return 0

    def __getstate__(self) -> SourceMap | None:
        return self.source

    def __setstate__(self, state: SourceMap | None) -> None:
        self.source = state

    def __repr__(self) -> str:
        return f"SourceRef({self.source.file if self.source else None!r})"


# Large files are parsed by libyaml (PyYAML's C parser) when it is installed: the pure-Python
# parser needs tens of seconds for a file of a few megabytes.
_LIBYAML_FROM = 64 * 1024
_CParser: Any
try:
    from yaml._yaml import CParser as _CParser
except ImportError:  # pragma: no cover - PyYAML built without libyaml
    _CParser = None


def _mark(event: yaml.Event) -> int:
    """The event's (line, column), both 1-based, packed (see :attr:`SourceMap.marks`)."""
    mark: Any = event.start_mark
    line, column = int(mark.line) + 1, int(mark.column) + 1
    return line << 32 | column


class _Refused(Exception):
    """A scalar cannot be read as its tag says: (message, hint)."""


def _short(tag: str) -> str:
    return tag.replace("tag:yaml.org,2002:", "!!")


def _scalar(text: str, tag: str) -> Any:
    """The value of a scalar under the YAML 1.2 core schema (an explicit tag included)."""
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


def _tag(event: Any, kind: type[yaml.Node]) -> str:
    """The tag of a node as PyYAML's composer resolves it (an explicit one, else by the YAML
    1.2 core schema)."""
    tag: str | None = event.tag
    if tag is None or tag == "!":
        if kind is yaml.ScalarNode:
            return _plain_tag(event.value) if event.implicit[0] else _STR
        return _SEQ if kind is yaml.SequenceNode else _MAP
    return tag


@functools.lru_cache(maxsize=4096)  # a behaviour file repeats its names and numbers
def _plain_tag(value: str) -> str:
    return _CORE.resolve(yaml.ScalarNode, value, (True, False))


@functools.lru_cache(maxsize=4096)
def _plain(text: str) -> Any:
    """The value of a plain scalar without a tag: one object for each text that recurs."""
    value = _scalar(str(text), _plain_tag(text))
    return sys.intern(value) if isinstance(value, str) and len(value) <= _INTERNED else value


_CORE = _CoreResolver()


@dataclass
class _Open:
    """A list or map being built."""

    is_map: bool
    #: The list or dict; None for one whose tag does not fit (its contents are skipped).
    value: Any
    path: Path
    kept: bool  # whether it is stored in the value that holds it
    anchored: _Anchored | None = None
    #: For a map: the key whose value comes next, or None when a key comes next, or
    #: _KEY_OF_NO_NAME while a refused key (a list or map) is skipped.
    key: Any = None
    drop: bool = False  # for a map: whether the next value is skipped (a refused key)


@dataclass
class _Anchored:
    """What an anchor (``&name``) names, for its aliases (``*name``) to repeat."""

    path: Path
    value: Any = None
    #: The field paths inside it (relative), with their marks and raw texts, so that a
    #: repetition is located like the original.
    marks: list[tuple[Path, int]] = field(default_factory=list)
    raw: list[tuple[Path, str]] = field(default_factory=list)
    values: int = 0  # values it holds, itself included
    done: bool = False


_KEY_OF_NO_NAME = object()
#: Longest text value kept once however often it recurs (set and command names do).
_INTERNED = 64


class _Builder:
    """Plain Python values from a stream of parser events, without composing PyYAML's node
    tree (which holds about 80 bytes per byte of input): every value's mark is kept as a
    (line, column) pair in the :class:`SourceMap`, and the building is a loop over the events
    with a stack of open lists and maps, so no nesting can exhaust Python's stack."""

    def __init__(self, source: SourceMap, marks: dict[Path, Mark],
                 items: dict[Path, array[int]]) -> None:
        self.source = source
        self.marks, self.items = marks, items  # source's, which the builder fills in
        self.problems: list[Problem] = []
        self.values = 0
        self.aliased = 0  # values built again because an alias repeats them
        self.anchors: dict[str, _Anchored] = {}
        self.recording: list[_Anchored] = []  # anchors whose value is being built
        self.stack: list[_Open] = []
        self.skipping = 0  # open lists and maps whose contents are skipped
        self.root: Any = None

    def build(self, parser: Any) -> Any:
        """The value of the stream's one document (an error if it holds more than one)."""
        while True:
            event = parser.get_event()
            if isinstance(event, yaml.StreamEndEvent):
                return None
            if isinstance(event, yaml.DocumentStartEvent):
                break
        first: Any = event
        for event in iter(parser.get_event, None):
            if isinstance(event, yaml.DocumentEndEvent):
                break
            top = self.stack[-1] if self.stack else None
            key_expected = top is not None and top.is_map and top.key is None \
                and not isinstance(event, yaml.MappingEndEvent)
            if key_expected and self._key(top, event):  # type: ignore[arg-type]
                continue
            if isinstance(event, yaml.ScalarEvent):
                self._scalar(event)
            elif isinstance(event, (yaml.MappingStartEvent, yaml.SequenceStartEvent)):
                self._open(event)
            elif isinstance(event, (yaml.MappingEndEvent, yaml.SequenceEndEvent)):
                self._close()
            elif isinstance(event, yaml.AliasEvent):
                self._alias(event)
        event = parser.get_event()
        if not isinstance(event, yaml.StreamEndEvent):
            raise yaml.composer.ComposerError(
                "expected a single document in the stream", first.start_mark,
                "but found another document", event.start_mark)
        return self.root

    # -- where a value goes --------------------------------------------------------------
    def _place(self) -> tuple[Path, bool]:
        """The path of the next value, and whether it is kept (else skipped)."""
        if not self.stack:
            return (), True
        top = self.stack[-1]
        kept = not self.skipping
        if not top.is_map:
            return (*top.path, len(top.value) if kept else 0), kept
        if top.key is _KEY_OF_NO_NAME:
            return top.path, False
        return (*top.path, top.key), kept and not top.drop

    def _put(self, value: Any, kept: bool) -> None:
        """Store a finished value in the list or map that holds it."""
        if not self.stack:
            self.root = value
            return
        top = self.stack[-1]
        if not top.is_map:
            if kept:
                top.value.append(value)
        elif top.key is _KEY_OF_NO_NAME:  # a refused key is skipped; its value is next
            top.key, top.drop = "", True
        else:
            if kept:
                top.value[top.key] = value
            top.key, top.drop = None, False

    def _key(self, top: _Open, event: Any) -> bool:
        """Take ``event`` as the next key of the map ``top``; False if it is a list, map or
        alias, which is then skipped like the value that follows it."""
        refused = not isinstance(event, yaml.ScalarEvent) or (
            event.tag is not None and _tag(event, yaml.ScalarNode) not in _SCALAR_TAGS)
        if refused:
            if not self.skipping:
                self.problems.append(self.source.problem(
                    top.path, "a key must be a plain name", "write the key as plain text"))
            if isinstance(event, yaml.ScalarEvent):
                top.key, top.drop = "", True
                return True
            top.key = _KEY_OF_NO_NAME
            return False
        if self.skipping:
            top.key, top.drop = "", True
            return True
        # Every key of a behaviour file is a name or a field, so a key is the text written:
        # `off:` is the name "off", not a boolean.
        key = sys.intern(str(event.value))
        key_path = (*top.path, key)
        mark = _mark(event)
        top.key, top.drop = key, False
        if key in top.value:
            first_line = unpack(self.marks[key_path])[0]
            self.problems.append(Problem(
                path=key_path, message=f"duplicate key '{key}' (first given on line "
                f"{first_line}); YAML would silently keep only the last one",
                hint="remove or rename one of the two", file=self.source.file,
                line=unpack(mark)[0], column=unpack(mark)[1]))
            top.drop = True
            return True
        self._mark(key_path, mark)
        return True

    # -- bookkeeping ---------------------------------------------------------------------
    def _mark(self, path: Path, mark: int) -> None:
        top = self.stack[-1] if self.stack else None
        if top is not None and not top.is_map and len(path) == len(top.path) + 1 \
                and path[:-1] == top.path:
            self.items[top.path].append(mark)  # the next item of the list being built
        else:
            self.marks.setdefault(path, mark)
        for anchored in self.recording:
            anchored.marks.append((path[len(anchored.path):], mark))

    def _raw(self, path: Path, text: str) -> None:
        self.source.raw[path] = text
        for anchored in self.recording:
            anchored.raw.append((path[len(anchored.path):], text))

    def _count(self, path: Path, values: int, aliased: int = 0) -> None:
        self.values += values
        self.aliased += aliased
        if self.values > MAX_VALUES or self.aliased > MAX_ALIASED_VALUES:
            many, limit = ("values", MAX_VALUES) if self.values > MAX_VALUES else (
                "values repeated by aliases (*name)", MAX_ALIASED_VALUES)
            raise SpecError([self.source.problem(
                path, f"the file holds more than {limit:,} {many}",
                "write fewer values, or use fewer aliases")], self.source.file)

    def _anchor(self, event: Any, path: Path) -> _Anchored | None:
        name = event.anchor
        if name is None:
            return None
        if name in self.anchors:
            raise yaml.composer.ComposerError(
                None, None, f"found duplicate anchor {name!r}", event.start_mark)
        anchored = _Anchored(path, values=self.values)  # the count so far, until it is done
        self.anchors[name] = anchored
        return anchored

    # -- events --------------------------------------------------------------------------
    def _scalar(self, event: Any) -> None:
        path, kept = self._place()
        anchored = self._anchor(event, path)
        self._count(path, 1)
        mark = _mark(event)
        if kept:
            self._mark(path, mark)
        value: Any = None
        try:
            if event.tag is None and event.implicit[0]:
                value = _plain(event.value)
            else:
                value = _scalar(str(event.value), _tag(event, yaml.ScalarNode))
        except _Refused as refused:
            if kept:
                self.problems.append(self.source.problem(path, *refused.args))
        else:
            plain = event.tag is None and event.style in (None, "")
            if kept and (value is None or isinstance(value, bool) or (
                    plain and isinstance(value, str) and _lookalike(value))):
                self._raw(path, str(event.value))
        if anchored is not None:
            anchored.value, anchored.values, anchored.done = value, 1, True
            anchored.marks.append(((), mark))
        self._put(value, kept)

    def _open(self, event: Any) -> None:
        path, kept = self._place()
        if len(self.stack) >= MAX_DEPTH:
            raise yaml.composer.ComposerError(
                None, None, f"lists and maps are nested more than {MAX_DEPTH} deep",
                event.start_mark)
        anchored = self._anchor(event, path)
        self._count(path, 1)
        if kept:
            self._mark(path, _mark(event))
        is_map = isinstance(event, yaml.MappingStartEvent)
        tag = _tag(event, yaml.MappingNode if is_map else yaml.SequenceNode)
        value: Any = {} if is_map else []
        if tag != (_MAP if is_map else _SEQ):
            if kept:
                self.problems.append(self.source.problem(
                    path, f"the YAML tag '{_short(tag)}' does not fit a "
                    f"{'map' if is_map else 'list'}", "remove the tag"))
            value = None
        frame = _Open(is_map, value, path, kept, anchored)
        if not is_map and kept and value is not None:
            self.items[path] = array("q")
        if not kept or value is None:
            self.skipping += 1
        self.stack.append(frame)
        if anchored is not None:
            self.recording.append(anchored)

    def _close(self) -> None:
        frame = self.stack.pop()
        if not frame.kept or frame.value is None:
            self.skipping -= 1
        if frame.anchored is not None:
            anchored = frame.anchored
            self.recording.remove(anchored)
            anchored.value, anchored.done = frame.value, True
            anchored.values = self.values - anchored.values
        self._put(frame.value, frame.kept)

    def _alias(self, event: Any) -> None:
        path, kept = self._place()
        anchored = self.anchors.get(event.anchor)
        if anchored is None:
            raise yaml.composer.ComposerError(
                None, None, f"found undefined alias {event.anchor!r}",
                event.start_mark)
        if not anchored.done:
            if kept:
                self._mark(path, _mark(event))
                self.problems.append(self.source.problem(
                    path, "an alias refers to the list or map that contains it, so the value "
                    "would be infinite", "remove the alias (*name) or point it elsewhere"))
            self._put(None, kept)
            return
        self._count(path, anchored.values, anchored.values)
        if kept:
            self._mark(path, _mark(event))
            for inner, inner_mark in anchored.marks:
                if inner:
                    self._mark((*path, *inner), inner_mark)
            for inner, text in anchored.raw:
                self._raw((*path, *inner), text)
        value = anchored.value
        self._put(copy.deepcopy(value) if isinstance(value, (dict, list)) else value, kept)


def read_yaml(text: str, file: str) -> tuple[Any, SourceMap]:
    """Parse ``text`` safely into plain values and a :class:`SourceMap`.

    Plain scalars follow the YAML 1.2 core schema. Raises :class:`SpecError` for malformed
    YAML, duplicate keys, object-building or misplaced tags, recursive aliases and files past
    the bounds MAX_DEPTH, MAX_VALUES, MAX_INT_DIGITS and MAX_FILE_CHARS.
    """
    marks: dict[Path, Mark] = {}
    items: dict[Path, array[int]] = {}
    source = SourceMap(file, marks, parsed=True, items=items)
    if len(text) > MAX_FILE_CHARS:
        raise SpecError([Problem((), f"the file has {len(text):,} characters, more than the "
                                 f"{MAX_FILE_CHARS:,} a behaviour file may have", file=file)],
                        file)
    parser: Any = None
    builder = _Builder(source, marks, items)
    try:
        parser = (_CParser(text) if len(text) > _LIBYAML_FROM and _CParser is not None
                  else _Parser(text))
        with no_collection():
            data = builder.build(parser)
    except yaml.MarkedYAMLError as exc:
        raise SpecError([_syntax_problem(exc, text, file)], file) from None
    except yaml.YAMLError as exc:
        raise SpecError([_unmarked_problem(exc, text, file)], file) from None
    finally:
        if parser is not None:
            parser.dispose()
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
