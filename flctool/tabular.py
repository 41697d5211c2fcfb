"""Reading and writing tables of states as CSV (header row of column names)."""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from flctool.errors import Problem, SpecError


def read_states(
    text: str, columns: Sequence[str], file: str
) -> tuple[list[str], list[list[str]], NDArray[np.float64]]:
    """Parse CSV text into its header, its data rows, and a (rows, len(columns)) float array.

    Every unparseable cell is reported, with its line, in one :class:`SpecError`.
    """
    rows = list(csv.reader(io.StringIO(text)))
    if not rows:
        raise SpecError([Problem((), "the CSV is empty; it needs a header row naming the "
                                 f"columns {', '.join(columns)}", file=file, line=1)], file)
    header = [name.strip() for name in rows[0]]
    missing = [c for c in columns if c not in header]
    if missing:
        raise SpecError([Problem((), f"the header lacks the column(s) {', '.join(missing)}",
                                 f"the header must name the inputs: {', '.join(columns)}",
                                 file=file, line=1)], file)
    index = [header.index(c) for c in columns]
    problems = []
    values = np.empty((len(rows) - 1, len(columns)))
    for r, row in enumerate(rows[1:]):
        line = r + 2
        if len(row) != len(header):
            problems.append(Problem((), f"expected {len(header)} cells, found {len(row)}",
                                    file=file, line=line))
            continue
        for c, i in enumerate(index):
            try:
                values[r, c] = float(row[i])
            except ValueError:
                problems.append(Problem((columns[c],), f"'{row[i]}' is not a number",
                                        file=file, line=line, column=i + 1))
                continue
            if math.isnan(values[r, c]):
                problems.append(Problem((columns[c],), "NaN is a missing reading, not a value",
                                        "filter or replace missing readings",
                                        file=file, line=line, column=i + 1))
    if problems:
        raise SpecError(problems, file)
    return header, rows[1:], values


def write_table(header: Sequence[str], rows: Sequence[Sequence[object]]) -> str:
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(header)
    writer.writerows(rows)
    return buffer.getvalue()
