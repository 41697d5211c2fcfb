"""Shared import helpers: point lists to trapezoids, and the imported behaviour file."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from flctool.errors import ExportError, FlcError, SpecError
from flctool.export import EXPORTERS, IMPORTERS, ExportOptions
from flctool.export.base import MAX_IMPORT_CHARS
from flctool.export.fis import FisExporter
from flctool.export.fll import FllExporter, FllImporter
from flctool.export.imported import ImportRefusals, imported_yaml, quad_from_points

from .controllers import random_behaviour

WHERE = ("t.fcl", 4)


@pytest.mark.parametrize(("points", "quad"), [
    ([(1, 0), (2, 1), (3, 1), (4, 0)], (1, 2, 3, 4)),
    ([(1, 0), (2, 1), (4, 0)], (1, 2, 2, 4)),
    ([(1, 1), (3, 1), (4, 0)], (0, 0, 3, 4)),  # starts at 1: a shoulder from the low end
    ([(3, 1), (4, 0)], (0, 0, 3, 4)),
    ([(1, 0), (2, 1)], (1, 2, 10, 10)),  # ends at 1: a shoulder to the high end
    ([(1, 0), (1, 1), (3, 1), (3, 0)], (1, 1, 3, 3)),  # vertical edges inside the range
    ([(5, 0), (5, 1), (5, 0)], (5, 5, 5, 5)),
    ([(0, 1), (10, 1)], (0, 0, 10, 10)),
])
def test_points_to_quadruples(points: list[tuple[float, float]],
                              quad: tuple[float, ...]) -> None:
    assert quad_from_points([(float(x), float(y)) for x, y in points], (0.0, 10.0), WHERE,
                            "t") == quad


@pytest.mark.parametrize("points", [
    [(1, 0), (2, 0.5), (3, 0)], [(1, 0), (2, 1), (3, 0), (4, 1)], [(2, 0), (1, 1)], [],
])
def test_other_point_lists_are_refused(points: list[tuple[float, float]]) -> None:
    with pytest.raises(ExportError, match=r"t.fcl:4: term 't'"):
        quad_from_points(points, (0.0, 10.0), WHERE, "t")


def test_imported_file_has_no_learning_section() -> None:
    behaviour = FllImporter().from_string(FllExporter().to_string(random_behaviour(2)))
    text = imported_yaml(behaviour, "imported")
    assert text.startswith("# imported\nflctool: 1\n")
    assert "learning:" not in text and "environment:" not in text
    assert "rules:" in text


# -- hostile imports: bounded in size and time, every error located -------------------------
def _located(error: FlcError, file: str) -> bool:
    """The message starts with the file and a line number (``file:line:``), each listed
    construct's when it lists several."""
    text = str(error)
    if isinstance(error, ImportRefusals):
        return all(_located(e, file) for e in error.errors)
    if isinstance(error, SpecError):
        return all(p.file == file and p.line is not None for p in error.problems)
    return re.match(re.escape(file) + r":\d+:", text) is not None


#: A valid FIS up to its rules, so that a hostile rule line reaches the rule parser.
_FIS_HEAD = "\n".join(
    line for line in FisExporter().to_string(random_behaviour(1, max_inputs=1))
    .split("[Rules]")[0].splitlines() if not line.startswith("NumRules="))


@pytest.mark.parametrize(("format", "text"), [
    # these used to backtrack: 20,000 spaces in an FLL value took 1.4 s CPU (100,000: ~35 s),
    # 2,000 spaces twice in an FIS rule's weight over 9 s
    ("fll", "Engine: a" + " " * 100_000 + "b\n"),
    ("fll", "Engine:" + " " * 100_000 + "x\n"),
    ("fll", " " * 100_000 + "x\n"),
    ("fll", "InputVariable: x\n  range:" + " " * 100_000 + "0 1 x\n"),
    ("fis", _FIS_HEAD + "[Rules]\n1, 1 (" + " " * 5_000 + "1" + " " * 5_000 + ") : 1 x\n"),
    ("fis", _FIS_HEAD + "[Rules]\n1, 1 (" + " " * 5_000 + "x\n"),
    ("fis", _FIS_HEAD + "[Rules]\n1" + " " * 5_000 + "1, 1 (1) : 1 x\n"),
    ("fis", "[Rules]\n1," + " " * 5_000 + "(" + " " * 5_000 + "1\n"),
    ("fis", "[System]\nName" + " " * 100_000 + "x\n"),
    ("fis", "[Input" + "1" * 5_000 + "]\n"),  # int() refuses > 4,300 digits
    ("fis", "[System]\nNumInputs=\u00b2\n"),  # '²'.isdigit() is True, int('²') fails
    ("fis", "[System]\nNumInputs=" + "9" * 5_000 + "\n"),
    ("fis", "[Input1]\nNumMFs=\u00b2\n"),
    ("fcl", "FUNCTION_BLOCK x\n(*" + " " * 100_000 + "\n"),
    ("fcl", "FUNCTION_BLOCK x\nVAR_INPUT\n" + "1" * 5_000 + "\n"),
])
def test_hostile_lines_are_refused_quickly_with_a_line(format: str, text: str) -> None:
    with pytest.raises(FlcError) as caught:
        IMPORTERS.get(format)().from_string(text, "hostile." + format)
    assert _located(caught.value, "hostile." + format), str(caught.value)


@pytest.mark.parametrize("format", ["fll", "fcl", "fis"])
def test_a_file_too_large_is_refused_before_it_is_read(format: str, tmp_path: Path) -> None:
    path = tmp_path / f"big.{format}"
    path.write_text("#" * (MAX_IMPORT_CHARS + 1), encoding="utf-8")
    with pytest.raises(ExportError, match=rf"big\.\w+:1: the file holds {MAX_IMPORT_CHARS + 1:,} "
                       "characters"):
        IMPORTERS.get(format)().from_file(path)


#: Pieces a mutation inserts: separators, keywords, odd numbers and characters.
_PIECES = st.sampled_from([
    " ", " " * 300, "\n", "\t", ":", "=", ";", ",", "(", ")", "[", "]", "'", "(*", "*)", "//",
    "#", "%", "0", "-1", "1e308", "1e999", "nan", "inf", "-inf", "\u00b2", "\u0663", "9" * 400,
    "..", ":=", "IF", "is", "and", "THEN", "OR", "NOT", "very", "TERM", "END_VAR", "RULE",
    "[Input1]", "[Rules]", "NumMFs=", "MF1=", "Trapezoid", "Ramp", "rule:", "term:",
    "\u2028", "\x00", "\ufeff", "é"])


@st.composite
def _mutated(draw: st.DrawFn) -> tuple[str, str]:
    format = draw(st.sampled_from(["fll", "fcl", "fis"]))
    seed = draw(st.integers(0, 7))
    options = ExportOptions(dialect=draw(st.sampled_from(["iec", "fuzzylite"])))
    text = EXPORTERS.get(format)(options).to_string(random_behaviour(seed, max_inputs=2))
    for _ in range(draw(st.integers(1, 4))):
        at = draw(st.integers(0, len(text)))
        kind = draw(st.sampled_from(["insert", "delete", "replace", "duplicate"]))
        if kind == "insert":
            text = text[:at] + draw(_PIECES) + text[at:]
        elif kind == "delete":
            text = text[:at] + text[at + draw(st.integers(1, 40)):]
        elif kind == "replace":
            text = text[:at] + draw(_PIECES) + text[at + 1:]
        else:
            end = text.find("\n", at) + 1 or len(text)
            text = text[:end] + text[at:end] + text[end:]
    return format, text


@settings(max_examples=300, deadline=None, derandomize=True)
@given(_mutated())
@pytest.mark.slow
def test_mutated_exports_import_or_fail_with_a_location(case: tuple[str, str]) -> None:
    """Mutations of our own exports either import or raise one of flctool's errors that
    names the file and a line; nothing else escapes."""
    format, text = case
    file = f"mutated.{format}"
    try:
        IMPORTERS.get(format)().from_string(text, file)
    except FlcError as error:
        assert _located(error, file), str(error)


@pytest.mark.parametrize("format", ["fll", "fis", "fcl"])
def test_a_byte_order_mark_is_read_as_nothing(format: str, tmp_path: Path) -> None:
    from flctool import load_behaviour
    from flctool.export import EXPORTERS, IMPORTERS

    from .roundtrip import SHIPPED

    behaviour = load_behaviour(SHIPPED[0])
    path = tmp_path / f"bom.{format}"
    path.write_text("\ufeff" + EXPORTERS.get(format)().to_string(behaviour), encoding="utf-8")
    imported = IMPORTERS.get(format)().from_file(path)
    assert [v.sets for v in imported.inputs.values()] == [v.sets for v in behaviour.inputs.values()]
