"""CSV of states: the hostile and awkward inputs each get a clear, located answer."""

from __future__ import annotations

import io

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from flctool.errors import SpecError
from flctool.tabular import StateReader, format_rows, text_stream


def _read(data: bytes, size: int = 2**20
          ) -> tuple[StateReader, list[tuple[list[str], np.ndarray]]]:
    reader = StateReader(text_stream(io.BytesIO(data)), ["a", "b"], "t.csv", reserved=["y"])
    return reader, list(reader.chunks(size))


def _error(data: bytes) -> str:
    with pytest.raises(SpecError) as caught:
        _read(data)
    return str(caught.value)


def test_rows_in_chunks_keep_the_cells_as_written() -> None:
    data = b"id,a,b\nx,1,2\ny, 3.5 ,-inf\nz,0,1e-3\nw,5,6"  # no newline at the end
    reader, chunks = _read(data, size=10)
    assert reader.header == ["id", "a", "b"]
    assert len(chunks) > 1  # whole lines in each chunk, however small the size
    assert [line for lines, _ in chunks for line in lines] == [
        "x,1,2", "y, 3.5 ,-inf", "z,0,1e-3", "w,5,6"]
    assert np.concatenate([values for _, values in chunks]).tolist() == [
        [1.0, 2.0], [3.5, -np.inf], [0.0, 0.001], [5.0, 6.0]]
    _, whole = _read(data)
    assert len(whole) == 1


def test_bom_crlf_cr_only_and_trailing_blank_lines_are_accepted() -> None:
    for data in (b"\xef\xbb\xbfa,b\n1,2\n", b"a,b\r\n1,2\r\n\r\n\r\n", b"a,b\r1,2\r\r",
                 b"a,b\n1,2\n   \n"):
        _, chunks = _read(data)
        assert [lines for lines, _ in chunks] == [["1,2"]], data


def test_a_blank_line_between_rows_is_an_error() -> None:
    assert "t.csv:3: (top level): a blank line between rows" in _error(b"a,b\n1,2\n\n3,4\n")
    with pytest.raises(SpecError, match=r"t\.csv:3: .*a blank line between rows"):
        _read(b"a,b\n1,2\n\n3,4\n", size=5)  # the blank line ends one chunk
    assert "t.csv:3: (top level): expected 2 cells, found 1" in _error(b"a,b\n1,2\n  \n3,4\n")


def test_duplicated_and_reserved_columns_are_errors() -> None:
    assert "t.csv:1:3: (top level): the column 'a' appears twice" in _error(b"a,b,a\n1,2,3\n")
    assert "the column 'y' is the output's name" in _error(b"a,b,y\n1,2,3\n")


def test_a_huge_cell_is_reported_shortened() -> None:
    huge = b"x" * 200_000
    message = _error(b"a,b\n" + huge + b",2\n")
    assert "t.csv:2:1: a: 'xxxx" in message and "(200,000 characters)' is not a number" in message
    assert len(message) < 400
    _, chunks = _read(b"a,b,note\n1,2," + huge + b"\n")  # in another column: just text
    assert chunks[0][1].tolist() == [[1.0, 2.0]]


def test_bad_cells_are_all_located() -> None:
    message = _error(b"a,b\n1,nan\nq,2\n1,2,3\n")
    assert "t.csv:2:2: b: NaN is a missing reading" in message
    assert "t.csv:3:1: a: 'q' is not a number" in message
    assert "t.csv:4: (top level): expected 2 cells, found 3" in message


def test_quoted_cells_and_a_broken_quote() -> None:
    _, chunks = _read(b'a,b,note\n1,2,"x, y"\n')
    assert chunks[0][1].tolist() == [[1.0, 2.0]]
    assert "not a CSV row" in _error(b'a,b\n1,"2\n')


def test_empty_and_headerless_input() -> None:
    assert "the CSV is empty" in _error(b"")
    assert "lacks the column(s) b" in _error(b"a\n1\n")


def test_format_rows_adds_the_shortest_round_trip_text() -> None:
    text = format_rows(["1,2", "3,4"], np.array([0.1, 1 / 3]))
    assert text == "1,2,0.1\n3,4,0.3333333333333333\n"


def test_numeric_tables_in_any_column_order_and_extra_columns() -> None:
    # every cell a number: numpy reads them all, then the inputs are picked in input order
    _, chunks = _read(b"b,x,a\n2,nan,1\n4,5,3\n")
    assert chunks[0][1].tolist() == [[1.0, 2.0], [3.0, 4.0]]  # NaN outside the inputs is fine
    # a row with a cell too many or too few among numbers is located, not read
    assert "t.csv:3: (top level): expected 3 cells, found 4" in _error(b"a,b,x\n1,2,3\n4,5,6,7\n")
    assert "t.csv:2: (top level): expected 3 cells, found 2" in _error(b"a,b,x\n1,2\n4,5,6\n")
    # a text column: the cells are counted, the inputs read
    _, chunks = _read(b"a,note,b\n1,left,2\n3,,4\n")
    assert chunks[0][1].tolist() == [[1.0, 2.0], [3.0, 4.0]]
    assert "t.csv:3: (top level): expected 3 cells, found 2" in _error(b"a,note,b\n1,x,2\n3,4\n")


def test_format_rows_keeps_percent_signs_and_formats_like_repr() -> None:
    values = np.array([0.1, -0.0, 1e-7, 1e16, 2.0 / 3.0, 5e-324])
    lines = ["1,50%", "%r,%s", "%%", "", "x", "y"]
    expected = "".join(f"{line},{value!r}\n" for line, value in zip(lines, values.tolist(),
                                                                       strict=True))
    assert format_rows(lines, values) == expected
    assert format_rows([], np.array([])) == ""


# -- the plain-Python reading (flctool infer on a small table) ---------------------------------

def _outcome(data: str, in_python: bool) -> tuple[bytes, ...] | str:
    """What a reading gives for a CSV: each chunk's values as bytes, or the error's text."""
    reader = StateReader(io.StringIO(data), ["a", "b"], "t.csv", reserved=["y"])
    try:
        if in_python:
            return tuple(np.array(values, dtype=np.float64).tobytes()
                         for _, values in reader.chunks_in_python(64))
        return tuple(values.tobytes() for _, values in reader.chunks(64))
    except SpecError as error:
        return str(error)


_SPELLINGS = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.floats(width=32).map(lambda v: f"{v:.9e}"),
    st.decimals(allow_nan=False, allow_infinity=False).map(str),
    st.integers(-10**30, 10**30).map(lambda v: f"{v:_}"),
    # what float() and numpy's parser may read differently: signs, exponents, underscores,
    # spellings of infinity and NaN, Unicode digits and spaces, control characters
    st.lists(st.sampled_from([*"0123456789.+-eE_ \t", "inf", "Infinity", "nan", "\x1c",
                              "\x0b", "\xa0", "\u3000", "\u0661", "\x00", "'", "d", "x"]),
             max_size=8).map("".join),
)


@settings(max_examples=400, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.tuples(_SPELLINGS, _SPELLINGS), min_size=1, max_size=6))
@pytest.mark.slow
def test_the_python_reading_accepts_and_refuses_as_numpys(cells: list[tuple[str, str]]
                                                          ) -> None:
    # no cell holds the delimiter or a line ending here: those make rows, tested above
    data = "a,b\n" + "".join(f"{a},{b}\n" for a, b in cells)
    assert _outcome(data, in_python=True) == _outcome(data, in_python=False)


@pytest.mark.parametrize("cell", ["1\x1c", "1_000", "\u0661", "nan", "x", "\x0b2 "])
def test_the_python_reading_matches_on_spellings_the_parsers_disagree_on(cell: str) -> None:
    # numpy's parser skips 0x1c as space and float() does not; float() reads '1_000' and
    # Arabic-Indic digits and numpy's parser does not: the readings still agree
    for data in (f"a,b\n{cell},1\n", f"a,b\n{cell},1\n1_0,\u0661\n", f'a,b\n"{cell}",1\n'):
        assert _outcome(data, in_python=True) == _outcome(data, in_python=False)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(_SPELLINGS)
@pytest.mark.slow
def test_both_readings_accept_exactly_the_documented_grammar(cell: str) -> None:
    """A cell is a number when it matches NUMBER (ASCII digits, no _), whichever reading
    reads its chunk: numpy's parser, the cell-by-cell fallback, or plain Python."""
    import math

    from flctool.tabular import NUMBER

    data = f"a,b\n{cell},1\n"
    for in_python in (True, False):
        outcome = _outcome(data, in_python)
        if NUMBER.fullmatch(cell) is None:
            assert isinstance(outcome, str) and "is not a number" in outcome
        elif math.isnan(float(cell)):
            assert isinstance(outcome, str) and "NaN is a missing reading" in outcome
        else:
            assert outcome == (np.array([[float(cell), 1.0]]).tobytes(),)


@pytest.mark.parametrize(("cell", "hint"), [("1_0", "without _"), ("\u0661.\u0662", "ASCII"),
                                            ("1\xa0", "ASCII"), ("\x1c1", "")])
def test_underscores_and_other_scripts_digits_are_not_numbers(cell: str, hint: str) -> None:
    for in_python in (True, False):
        outcome = _outcome(f"a,b\n0,1\n{cell},2\n", in_python)
        assert isinstance(outcome, str) and "t.csv:3:1: a: '" in outcome
        assert hint in outcome


@pytest.mark.parametrize(("data", "where", "what"), [
    ("a,b\n1,2\n3,caf\u00e9\n".encode("latin-1"), "t.csv:3:6", "not UTF-8 text (byte 0xe9;"),
    ("a,b\n1,2\n".encode("utf-16"), "t.csv:1:1", "UTF-16 text (it starts with a UTF-16 byte "
     "order mark)"),
    (b"a,\xff\n1,2\n", "t.csv:1:3", "(byte 0xff;"),
])
def test_text_that_is_not_utf8_is_refused_at_its_line_and_column(data: bytes, where: str,
                                                                 what: str) -> None:
    message = _error(data)
    assert f"{where}: the CSV is" in message and what in message
