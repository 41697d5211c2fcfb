"""Reading and writing tables of states as CSV (a header row of column names), streamed.

:class:`StateReader` reads a CSV text stream chunk by chunk, so memory follows the chunk size,
not the file: ``flctool infer`` on a million rows holds one chunk of lines, its (B, N) states
and their outputs at a time. Each data line is kept as written, so the output repeats the
user's cells exactly and adds one column.

What is accepted, and what is an error (every error names the file, line and column):

- a UTF-8 byte order mark before the header, and any line ending (LF, CRLF, CR alone);
- blank lines at the end of the file (a blank line between rows is an error: a lost reading);
- a header naming every input; a column named twice, or one with the output's name, is an
  error (which of the two would be meant?);
- a cell of an input column must be a number in one grammar (:data:`NUMBER`): ASCII
  decimal digits with an optional sign, point and exponent, or ``inf``/``infinity`` (any
  case), with spaces or tabs around -- not ``1_0`` or Arabic-Indic digits, which Python's
  ``float`` reads; NaN is an error; infinities are clipped to the input's range like any
  value beyond it;
- text that is not UTF-8 (a Latin-1 file, UTF-16 with its byte order mark) is an error at
  the line and column of its first byte that is not.

Two readings of a chunk give the same values and the same errors: :meth:`StateReader.chunks`
(numpy's C parser for a chunk of printable ASCII without ``_``, where it reads exactly
:data:`NUMBER`; else cell by cell) and :meth:`StateReader.chunks_in_python` (cell by cell,
each cell matched against :data:`NUMBER` and read by ``float``, for a small table in a
process that never loads numpy).
"""

from __future__ import annotations

import csv
import io
import itertools
import math
import re
from collections.abc import Iterator, Sequence
from typing import TYPE_CHECKING, Any, BinaryIO, TextIO

from flctool.errors import Problem, SpecError
from flctool.inputs import not_utf8

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import NDArray

#: Characters of rows parsed, inferred and written per step of a stream (a chunk of 2 MB
#: holds about 100,000 rows of a few columns).
CHUNK_CHARACTERS = 2**21
#: Longest cell shown in a message; longer ones are cut (a cell may be megabytes long).
SHOWN_CELL = 40
#: Most problems reported for one chunk before the rest are summarised.
LISTED_PROBLEMS = 20
#: What a cell of an input column may hold: a decimal number in ASCII digits, or an infinity
#: (NaN matches too, and is refused as a missing reading), with spaces or tabs around.
NUMBER = re.compile(r"[ \t]*[+-]?(?:(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?"
                    r"|(?i:inf|infinity|nan))[ \t]*")
#: A chunk without these is read by numpy's parser, which there reads exactly NUMBER: beyond
#: printable ASCII it also reads other spaces (U+00A0) and skips control characters, and
#: Python's float reads ``1_0`` and other scripts' digits.
_BEYOND_NUMPY = re.compile(r'[^\x20-\x7e\t\n]|[_"]')
#: Bytes that are not UTF-8 are decoded as lone surrogates (``surrogateescape``), so the
#: reader can say at which line and column the first one is.
_UNDECODED = re.compile("[\udc80-\udcff]")


def text_stream(binary: BinaryIO) -> TextIO:
    """A text view of a binary stream that drops a UTF-8 BOM and reads every line ending
    (LF, CRLF, CR) as LF; bytes that are not UTF-8 become lone surrogates, which
    :class:`StateReader` refuses at their line and column."""
    return io.TextIOWrapper(binary, encoding="utf-8-sig", errors="surrogateescape",
                            newline=None)


def _shown(cell: str) -> str:
    if len(cell) <= SHOWN_CELL:
        return cell
    return f"{cell[:SHOWN_CELL]}... ({len(cell):,} characters)"


class StateReader:
    """The states of a CSV stream, chunk by chunk.

    ``header`` holds the column names; :meth:`chunks` yields ``(lines, states)``: the data
    lines as written (without line ending) and their inputs as a (B, N) float array in the
    order of ``columns``. Raises :class:`SpecError` with located problems.
    """

    def __init__(self, stream: TextIO, columns: Sequence[str], file: str,
                 reserved: Sequence[str] = ()) -> None:
        self._stream = stream
        self.columns = list(columns)
        self.file = file
        self._line = 1  # 1-based number of the last line read
        try:
            first = stream.readline()
        except UnicodeDecodeError:  # a stream that does not escape them
            raise self._not_utf8_here(1, None, 0) from None
        self._check_decoded(first, 1)
        if not first.strip():
            raise self._error(1, None, "the CSV is empty; it needs a header row naming the "
                              f"columns {', '.join(self.columns)}")
        self.header_line = first.rstrip("\n")
        cells = self._split(self.header_line, 1)
        self.header = [name.strip() for name in cells]
        self._check_header(reserved)
        self._index = [self.header.index(c) for c in self.columns]
        self._blank: list[int] = []  # blank lines seen since the last row
        self._numbers: Sequence[int] = []  # line numbers of the rows of the current chunk
        self._beyond_numpy = False  # whether numpy cannot read the current chunk (see NUMBER)

    # -- header --------------------------------------------------------------------------
    def _check_header(self, reserved: Sequence[str]) -> None:
        seen: set[str] = set()
        for position, name in enumerate(self.header, start=1):
            if name in seen:
                raise self._error(1, position, f"the column '{_shown(name)}' appears twice",
                                  "give every column its own name")
            if name in reserved:
                raise self._error(1, position, f"the column '{_shown(name)}' is the output's "
                                  "name, which the result adds",
                                  "rename or drop that column")
            seen.add(name)
        missing = [c for c in self.columns if c not in seen]
        if missing:
            raise self._error(1, None, f"the header lacks the column(s) {', '.join(missing)}",
                              f"the header must name the inputs: {', '.join(self.columns)}")

    # -- rows ----------------------------------------------------------------------------
    def chunks(self, size: int = CHUNK_CHARACTERS
               ) -> Iterator[tuple[list[str], NDArray[np.float64]]]:
        """``(lines, states (B, N))`` for about ``size`` characters of rows at a time."""
        for rows in self.row_chunks(size):
            yield rows, self.parse(rows)

    def chunks_in_python(self, size: int = CHUNK_CHARACTERS
                         ) -> Iterator[tuple[list[str], list[list[float]]]]:
        """:meth:`chunks` with each state a list of Python floats, read without numpy."""
        for rows in self.row_chunks(size):
            yield rows, self.parse_in_python(rows)

    def row_chunks(self, size: int = CHUNK_CHARACTERS) -> Iterator[list[str]]:
        """The data lines of about ``size`` characters at a time, not yet parsed: parse each
        with :meth:`parse` or :meth:`parse_in_python` before taking the next."""
        while True:
            try:
                text = self._stream.read(size)
                if text and not text.endswith("\n"):
                    text += self._stream.readline()  # complete the last line
            except UnicodeDecodeError:  # a stream that does not escape them
                raise self._not_utf8_here(self._line + 1, None, 0) from None
            if not text:
                return
            self._check_decoded(text, self._line + 1)
            lines = text.split("\n")
            if lines[-1] == "":
                lines.pop()  # the end of the last line, not a line
            first = self._line + 1
            self._line += len(lines)
            rows = self._rows(lines, first)
            # (one search of the text, not one per line)
            self._beyond_numpy = _BEYOND_NUMPY.search(text) is not None
            if rows:
                yield rows

    def _rows(self, lines: list[str], first: int) -> list[str]:
        """The rows of a chunk, and their line numbers in ``self._numbers``. A blank line is
        kept back until a row follows it, which makes it an error; blank lines at the end of
        the file are fine."""
        if "" not in lines and lines[-1].strip() and (len(self.header) > 1
                                                       or all(map(str.strip, lines))):
            # no blank line (one of spaces between rows has too few cells: _parse says so)
            if self._blank:
                raise self._blank_error()
            self._numbers = range(first, first + len(lines))
            return lines
        rows: list[str] = []
        numbers: list[int] = []
        for number, line in enumerate(lines, start=first):
            if not line.strip():
                self._blank.append(number)
                continue
            if self._blank:
                raise self._blank_error()
            rows.append(line)
            numbers.append(number)
        self._numbers = numbers
        return rows

    def _blank_error(self) -> SpecError:
        return self._error(self._blank[0], None, "a blank line between rows",
                           "remove it, or give the missing reading")

    def parse(self, lines: list[str]) -> NDArray[np.float64]:
        """The inputs of the latest chunk's rows (``lines``, from :meth:`row_chunks`) as a
        (B, N) array."""
        import numpy as np

        if not self._beyond_numpy:
            values = self._parse_plain(lines)
            if values is not None:
                return values
        return np.array(self._parse_cells(lines), dtype=np.float64).reshape(
            len(lines), len(self.columns))

    def parse_in_python(self, lines: list[str]) -> list[list[float]]:
        """The inputs of the latest chunk's rows as lists of floats, read cell by cell without
        loading numpy, exactly as :meth:`parse` reads them: each cell matched against
        :data:`NUMBER` and read by ``float``, which rounds correctly like numpy's parser
        (tests compare the two on generated cells)."""
        return self._parse_cells(lines)

    def _parse_plain(self, lines: list[str]) -> NDArray[np.float64] | None:
        """The input columns of rows without quotes, read by numpy's C parser (correctly
        rounded, like float()); None if it refuses anything, which :meth:`_parse_cells` then
        re-reads cell by cell to name the culprit.

        When every cell is a number, the parser reads them all and itself checks that every
        row has as many cells as the first; else (a text column) it reads the input columns
        once each row's cells are counted.
        """
        import numpy as np

        options: dict[str, Any] = {"delimiter": ",", "dtype": np.float64, "ndmin": 2,
                                   "comments": None, "encoding": None, "quotechar": None}
        try:
            values = np.loadtxt(lines, **options)
        except ValueError:  # a cell that is no number (perhaps text), or rows of two lengths
            values = None
        if values is not None and values.shape[1] == len(self.header):
            if self._index != list(range(len(self.header))):
                values = values[:, self._index]
        elif self._cell_counts_agree(lines):
            try:
                values = np.loadtxt(lines, usecols=self._index, **options)
            except ValueError:
                return None
        else:
            return None
        if values.shape[0] != len(lines) or np.isnan(values).any():
            return None
        return values

    def _cell_counts_agree(self, lines: list[str]) -> bool:
        """Whether every line has exactly ``len(header) - 1`` commas."""
        return set(map(str.count, lines, itertools.repeat(","))) == {len(self.header) - 1}

    def _parse_cells(self, lines: list[str]) -> list[list[float]]:
        width = len(self.header)
        values: list[list[float]] = []
        problems: list[Problem] = []
        for line, number in zip(lines, self._numbers, strict=True):
            cells = self._split(line, number)
            if len(cells) != width:
                problems.append(Problem((), f"expected {width} cells, found {len(cells)}",
                                        file=self.file, line=number))
                continue
            row = []
            for c, i in enumerate(self._index):
                if NUMBER.fullmatch(cells[i]) is None:
                    problems.append(Problem((self.columns[c],),
                                            f"'{_shown(cells[i])}' is not a number",
                                            _number_hint(cells[i]),
                                            file=self.file, line=number, column=i + 1))
                    continue
                value = float(cells[i])
                if math.isnan(value):
                    problems.append(Problem((self.columns[c],),
                                            "NaN is a missing reading, not a value",
                                            "filter or replace missing readings",
                                            file=self.file, line=number, column=i + 1))
                row.append(value)
            values.append(row)
        if problems:
            if len(problems) > LISTED_PROBLEMS:
                rest = len(problems) - LISTED_PROBLEMS
                problems = [*problems[:LISTED_PROBLEMS],
                            Problem((), f"and {rest} more problem(s) in the lines that follow",
                                    file=self.file)]
            raise SpecError(problems, self.file)
        return values

    def _split(self, line: str, number: int) -> list[str]:
        if '"' not in line:
            return line.split(",")
        try:
            return next(csv.reader([line], strict=True))
        except csv.Error as error:
            raise self._error(number, None, f"not a CSV row: {error}",
                              "quote cells that contain commas or quotes") from None

    def _check_decoded(self, text: str, line: int) -> None:
        """Refuse ``text`` (starting at ``line``) if it holds bytes that are not UTF-8."""
        found = _UNDECODED.search(text)
        if found is None:
            return
        at = found.start()
        line += text.count("\n", 0, at)
        column = at - (text.rfind("\n", 0, at) + 1) + 1
        raise self._not_utf8_here(line, column, ord(found.group()) - 0xDC00,
                                  utf16=line == 1 and column == 1 and text[:2] in _UTF16_BOMS)

    def _not_utf8_here(self, line: int, column: int | None, byte: int | None = None,
                       utf16: bool = False) -> SpecError:
        return not_utf8(self.file, "CSV", line, column, None if utf16 else byte)

    def _error(self, line: int | None, column: int | None, message: str,
               hint: str = "") -> SpecError:
        return SpecError([Problem((), message, hint, file=self.file, line=line,
                                  column=column)], self.file)


#: The byte order marks of UTF-16 as surrogateescape decodes them (FF FE, FE FF).
_UTF16_BOMS = ("\udcff\udcfe", "\udcfe\udcff")


def _number_hint(cell: str) -> str:
    if "_" in cell:
        return "write the digits without _"
    if not cell.isascii():
        return "write the number in ASCII digits 0-9, with a point for decimals"
    return ""


def format_rows(lines: Sequence[str], values: NDArray[np.float64] | Sequence[float]) -> str:
    """The lines with one more cell each: the value's shortest round-trip text (``repr``)."""
    numbers = values.tolist() if hasattr(values, "tolist") else list(values)
    if len(lines) != len(numbers):
        raise ValueError(f"{len(lines)} lines but {len(numbers)} values")
    if not lines:
        return ""
    # One formatting pass in C over a template of the rows as written (their '%' escaped):
    # '%r' of a float is its repr. About 1.2x faster than joining row by row.
    template = ("\n".join(lines) + "\n").replace("%", "%%").replace("\n", ",%r\n")
    return template % tuple(numbers)


def write_table(header: Sequence[str], rows: Sequence[Sequence[object]]) -> str:
    """A whole table as CSV text (for small tables, e.g. an episode's trace)."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(header)
    writer.writerows(rows)
    return buffer.getvalue()
