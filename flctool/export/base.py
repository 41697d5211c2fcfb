"""The exporter / importer contract, and what every format shares.

An :class:`Exporter` turns a deployable behaviour into the text of one format (``to_string``)
and writes it atomically (``to_file``); an :class:`Importer` reads that text back
(``from_string`` / ``from_file``). Each format module supplies one of each, registered by
format name in :mod:`flctool.export`.
"""

from __future__ import annotations

import math
import os
import re
from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import ClassVar

from flctool.atomic import regular_target, replace_all, write_text_atomic
from flctool.behaviour import Behaviour
from flctool.behaviour.bounded import no_collection
from flctool.errors import ExportError
from flctool.inputs import read_input
from flctool.version import __version__


@dataclass(frozen=True)
class ExportOptions:
    """What an export may be told besides the behaviour.

    ``provenance`` (source, learner, seed, generation, individual, fitness; any may be absent)
    becomes a header comment where the format has comments. ``prefix`` and ``single`` only
    concern the C exporter: the prefix of its public names, and ``float`` instead of
    ``double`` arithmetic. ``dialect`` concerns FCL only.
    """

    provenance: Mapping[str, object] = field(default_factory=dict)
    prefix: str = "flc_"
    single: bool = False
    #: FCL only: ``iec`` (IEC 61131-7 point lists) or ``fuzzylite`` (what fuzzylite 6 reads).
    dialect: str = "iec"


class Exporter(ABC):
    """Writes a deployable behaviour in one format."""

    #: The format's name in the registry and on the command line.
    format: ClassVar[str]

    def __init__(self, options: ExportOptions | None = None) -> None:
        self.options = options or ExportOptions()

    @abstractmethod
    def to_string(self, behaviour: Behaviour) -> str:
        """The whole controller as this format's text (raises ExportError if it cannot)."""

    def texts(self, behaviour: Behaviour, path: Path) -> dict[Path, str]:
        """The text of every file that :meth:`to_file` writes for ``path``."""
        return {path: self.to_string(behaviour)}

    def to_file(self, behaviour: Behaviour, path: str | Path, *, force: bool = False
                ) -> list[Path]:
        """Write the export atomically; returns the files written.

        Everything is checked before anything is written: the controller must be exportable,
        no target may exist unless ``force``, and the folder must exist and be writable.
        """
        return write_files(self.texts(behaviour, Path(path)), force=force)


#: The largest file an importer reads, in characters: far above any controller written by
#: hand or by a tool (a 4-input, 10-set grid of 10,000 rules is about 1 MB of FCL), and small
#: enough that the densest format (FIS, 14 characters a rule: 140,000 rules) imports in
#: seconds (benchmarks/bench_limits.py).
MAX_IMPORT_CHARS = 2_000_000


class Importer(ABC):
    """Reads the subset of one format that flctool can express.

    Every importer reads its text in time linear in its length (no backtracking regular
    expression), and refuses a text longer than :data:`MAX_IMPORT_CHARS`.
    """

    format: ClassVar[str]
    #: What the last import changed or split, to tell the user ("" when nothing).
    report: str = ""

    def from_string(self, text: str, file: str = "<string>") -> Behaviour:
        """The controller in ``text`` as a behaviour (``file`` names it in messages); a file
        with several outputs is refused here (see :meth:`from_string_all`)."""
        behaviours = self.from_string_all(text, file)
        if len(behaviours) > 1:
            names = ", ".join(f"'{b.output.name}'" for b in behaviours)
            raise ExportError(f"{file}:1: the controller has {len(behaviours)} outputs "
                              f"({names}); a behaviour has one",
                              hint="import it as one behaviour per output: flctool import "
                              "FILE -o NAME.yaml writes NAME_<output>.yaml for each")
        return behaviours[0]

    def from_string_all(self, text: str, file: str = "<string>") -> list[Behaviour]:
        """The controller in ``text`` as one behaviour per output, in file order (outputs
        are independent: each is computed from its own rules)."""
        if len(text) > MAX_IMPORT_CHARS:
            raise ExportError(f"{file}:1: the file holds {len(text):,} characters, more than "
                              f"the {MAX_IMPORT_CHARS:,} an import reads",
                              hint="is it really a controller? split it or shorten it")
        # a UTF-8 byte-order mark (Windows editors write one) is not part of the text
        text = text.removeprefix("\ufeff")
        with no_collection():  # see flctool.behaviour.bounded
            return self.parse_all(text, file)

    @abstractmethod
    def parse(self, text: str, file: str) -> Behaviour:
        """The controller in ``text`` (at most MAX_IMPORT_CHARS long) as a behaviour."""

    def parse_all(self, text: str, file: str) -> list[Behaviour]:
        """:meth:`parse` for a format whose files may hold several outputs: one behaviour
        per output. A format that reads one output only keeps this default."""
        return [self.parse(text, file)]

    def from_file(self, path: str | Path) -> Behaviour:
        return self.from_string(*self._read(path))

    def from_file_all(self, path: str | Path) -> list[Behaviour]:
        """:meth:`from_string_all` of a file."""
        return self.from_string_all(*self._read(path))

    def _read(self, path: str | Path) -> tuple[str, str]:
        path = Path(path)
        text = read_input(path, f"{self.format.upper()} file", MAX_IMPORT_CHARS)
        return text, str(path)


def write_files(texts: Mapping[Path, str], *, force: bool) -> list[Path]:
    """Write every file or none: check all targets, then write them (see
    :func:`flctool.atomic.replace_all`).

    Returns the files written; an OSError becomes an ExportError naming the file.
    """
    for target in texts:
        check_writable(target, force=force)
    try:
        if len(texts) == 1:
            [(target, text)] = texts.items()
            write_text_atomic(target, text)
        else:
            replace_all({target: text.encode("utf-8") for target, text in texts.items()})
    except OSError as exc:
        where = exc.filename or ", ".join(map(str, texts))
        raise ExportError(f"cannot write {where}: {exc.strerror or exc}",
                          hint="choose another path with -o") from None
    return list(texts)


def check_writable(path: Path, *, force: bool) -> None:
    """Refuse to overwrite without ``force``, and say early when a path cannot be written."""
    if path.is_dir():
        raise ExportError(f"{path} is a folder", hint="give a file name with -o")
    try:
        regular_target(path)
    except OSError as exc:
        raise ExportError(f"cannot write {path}: {exc.strerror or exc}",
                          hint="choose another path with -o") from None
    if path.exists() and not force:
        raise ExportError(f"{path} already exists", hint="pass --force to overwrite it")
    folder = path.parent
    if not folder.is_dir():
        raise ExportError(f"cannot write {path}: the folder {folder} does not exist",
                          hint=f"create it first (mkdir -p {folder}) or choose another path")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise ExportError(f"cannot write {path}: the folder {folder} is not writable",
                          hint="choose another path with -o")


#: Line breaks and other control characters (including Unicode's line and paragraph
#: separators), which would end a comment line early.
_CONTROL = re.compile(r"[\x00-\x1f\x7f-\x9f\u2028\u2029]")


def comment_safe(value: object) -> str:
    """``value`` as text that stays inside a one-line comment of every format: control
    characters become escapes (``\\n``), and the comment ends and starts of C (``*/``, ``/*``)
    and FCL (``*)``, ``(*``) get a space between their two characters."""
    text = _CONTROL.sub(lambda m: m.group().encode("unicode_escape").decode("ascii"),
                        str(value))
    text = re.sub(r"\*(?=[/)])", "* ", text)
    return re.sub(r"(?<=[/(])\*", " *", text)


def header_lines(behaviour: Behaviour, provenance: Mapping[str, object]) -> list[str]:
    """Where an export came from, as comment lines (without comment markers); the values
    are made :func:`comment_safe`, since a path may hold anything."""
    lines = [f"{comment_safe(behaviour.name)}: exported by flctool {__version__}"]
    if "source" in provenance:
        lines.append(f"source: {comment_safe(provenance['source'])}")
    facts = [f"{key}: {comment_safe(provenance[key])}"
             for key in ("learner", "seed", "generation", "individual", "fitness")
             if provenance.get(key) is not None]
    if facts:
        lines.append(", ".join(facts))
    return lines


def vote_note(behaviour: Behaviour) -> list[str]:
    """What an engine file (FLL, FCL: eq. 3's output only) says of a behaviour that acts by
    vote, as comment lines; none for one that does not."""
    if not behaviour.acts_by_vote:
        return []
    return ["It acts by vote (environment.action: vote): the command whose firing rules'",
            "activations sum highest runs, not the one nearest the output computed here."]


def number(value: float) -> str:
    """The shortest text that reads back to the same double (never rounded)."""
    return repr(float(value))


Quad = tuple[float, float, float, float]


def beyond(lo: float, hi: float, side: int, widths: int) -> float:
    """A point ``widths`` range widths beyond the range's low (``side`` -1) or high (+1)
    end, or ``widths`` ulps beyond it where that would overflow."""
    end = lo if side < 0 else hi
    point = end + side * widths * (hi - lo)
    if math.isfinite(point) and point != end:
        return point
    for _ in range(widths):
        end = math.nextafter(end, side * math.inf)
    return end


def sloped_quad(quad: Quad, span: tuple[float, float], *, interior: bool = True) -> Quad:
    """The same set with no vertical edge, for readers that refuse (or misread) one.

    A shoulder at the range's end keeps membership 1 for a range width past it, and its foot
    lies two widths past it: inputs are clipped to the range, so inside the range nothing
    changes, and a reader that does not clip still gets 1 up to a width past the end.
    With ``interior``, a vertical edge inside the range gets its foot one ulp away, so no
    double lies on the ramp and the membership at every double is the same as flctool's
    (0 at the foot, 1 at the edge).
    """
    pa, pb, pc, pd = quad
    lo, hi = span
    if pa == pb:
        if pa <= lo:
            pa, pb = beyond(lo, hi, -1, 2), beyond(lo, hi, -1, 1)
        elif interior:
            pa = math.nextafter(pb, -math.inf)
    if pc == pd:
        if pd >= hi:
            pc, pd = beyond(lo, hi, +1, 1), beyond(lo, hi, +1, 2)
        elif interior:
            pd = math.nextafter(pc, math.inf)
    return pa, pb, pc, pd
