"""FCL: point lists in IEC's reading, NSUM accumulation, and the import's subset."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from flctool import compile_behaviour, load_behaviour
from flctool.errors import ExportError, SpecError
from flctool.export import ExportOptions
from flctool.export.base import sloped_quad
from flctool.export.fcl import FclExporter, FclImporter, fcl_number, set_points

from .controllers import random_behaviour, random_states, with_product
from .engines import ALL_SHIPPED, PRODUCT_SOURCES, assert_fuzzylite_agrees, reference_controller
from .roundtrip import SHIPPED, assert_same_controller


def test_numbers_are_iec_real_literals() -> None:
    assert fcl_number(1e-05) == "1.0e-05"
    assert fcl_number(-90.0) == "-90.0"
    assert fcl_number(0.1) == "0.1"
    assert fcl_number(1e16) == "1.0e+16"


@pytest.mark.parametrize(("quad", "points"), [
    ((0.0, 0.0, 0.1, 0.3), [(0.0, 1), (0.1, 1), (0.3, 0)]),  # shoulder at the low end
    ((0.4, 0.6, 1.0, 1.0), [(0.4, 0), (0.6, 1), (1.0, 1)]),  # shoulder at the high end
    ((0.2, 0.5, 0.5, 0.7), [(0.2, 0), (0.5, 1), (0.7, 0)]),  # triangle
    # a vertical edge inside the range: its foot one ulp away, so every reader agrees
    ((0.2, 0.2, 0.5, 0.7), [(math.nextafter(0.2, 0), 0), (0.2, 1), (0.5, 1), (0.7, 0)]),
    ((0.2, 0.4, 0.6, 0.6), [(0.2, 0), (0.4, 1), (0.6, 1), (math.nextafter(0.6, 1), 0)]),
    ((0.0, 0.0, 1.0, 1.0), [(0.0, 1), (1.0, 1)]),
])
def test_set_points(quad: tuple[float, float, float, float],
                    points: list[tuple[float, int]]) -> None:
    assert set_points(quad, (0.0, 1.0)) == points


def test_the_block_computes_eq_3() -> None:
    text = FclExporter().to_string(load_behaviour(SHIPPED[0]))
    for line in ("METHOD : COGS;", "AND : MIN;", "ACCU : NSUM;", "TERM turn_right := -1.0;",
                 "RULE 1 : IF ball_size IS small AND pan IS far_right THEN turn IS turn_right;"):
        assert line in text


BLOCK = """\
FUNCTION_BLOCK tiny (* a comment *)
VAR_INPUT
    x : REAL;
END_VAR
VAR_OUTPUT
    u : REAL;
END_VAR
FUZZIFY x
    TERM low := (0, 1) (0.2, 1) (0.8, 0);
    TERM high := (0.2, 0) (1, 1);
    RANGE := (0 .. 1);
END_FUZZIFY
DEFUZZIFY u
    TERM down := -1;
    TERM up := 1;
    METHOD : COGS;
    DEFAULT := 0;
END_DEFUZZIFY
RULEBLOCK rules
    AND : MIN;
    ACCU : NSUM;
    RULE 1 : IF x IS low THEN u IS up;
    RULE 2 : IF x IS high THEN u IS down;
END_RULEBLOCK
END_FUNCTION_BLOCK
"""


def test_import_reads_the_subset() -> None:
    behaviour = FclImporter().from_string(BLOCK, "tiny.fcl")
    assert behaviour.inputs["x"].range == (0.0, 1.0)
    assert behaviour.inputs["x"].sets == {"low": (0.0, 0.0, 0.2, 0.8),
                                          "high": (0.2, 1.0, 1.0, 1.0)}
    assert behaviour.output.commands == {"down": -1.0, "up": 1.0}
    assert behaviour.is_deployable


def test_jfuzzylogics_terms_are_read_in_any_case() -> None:
    """jFuzzyLogic reads ``GAUSS 0.2 0.3`` as ``gauss 0.2 0.3`` (its examples write both)."""
    low = "TERM low := (0, 1) (0.2, 1) (0.8, 0);"
    lower = FclImporter().from_string(BLOCK.replace(low, "TERM low := gauss 0.2 0.3;"),
                                      "tiny.fcl")
    upper = FclImporter().from_string(BLOCK.replace(low, "TERM low := GAUSS 0.2 0.3;"),
                                      "tiny.fcl")
    assert lower.inputs["x"].sets == upper.inputs["x"].sets
    assert upper.inputs["x"].sets["low"].kind == "gauss"


@pytest.mark.parametrize(("old", "new", "message"), [
    ("TERM up := 1;", "TERM up := (0, 0) (1, 1) (2, 0);",
     r"tiny.fcl:15: output term 'up' is not a singleton: a Mamdani output set"),
    ("IF x IS low THEN", "IF x IS low OR x IS high THEN", r"tiny.fcl:22: an OR rule"),
    ("IF x IS low THEN", "IF x IS NOT low THEN", r"tiny.fcl:22: NOT on input 'x'"),
    ("IF x IS low THEN", "IF x IS very low THEN", r"tiny.fcl:22: the hedge 'very'"),
    ("THEN u IS up;", "THEN u IS up WITH 0.5;", r"tiny.fcl:22: a rule weight of 0.5"),
    ("TERM low := (0, 1) (0.2, 1) (0.8, 0);", "TERM low := (0, 1) (0.2, 0.5) (0.8, 0);",
     r"tiny.fcl:9: term 'low' with membership values \[1.0, 0.5, 0.0\] is not a trapezoid"),
    ("TERM low := (0, 1) (0.2, 1) (0.8, 0);", "TERM low := cosine 0.2 0.1;",
     r"tiny.fcl:9: a cosine term: flctool's sets do not include it"),
    ("METHOD : COGS;", "METHOD : COG;", r"tiny.fcl:16: METHOD : COG"),
    ("    u : REAL;\n", "    u : REAL;\n    v : REAL;\n",
     r"tiny.fcl:7: output 'v' has no DEFUZZIFY block"),
    ("ACCU : NSUM;", "ACCU : MAX;", None),  # no two rules share a term: MAX changes nothing
])
def test_import_names_what_it_cannot_express(old: str, new: str, message: str | None) -> None:
    text = BLOCK.replace(old, new)
    assert text != BLOCK
    if message is None:
        FclImporter().from_string(text, "tiny.fcl")
        return
    with pytest.raises(ExportError, match=message):
        FclImporter().from_string(text, "tiny.fcl")


def test_a_duplicate_rule_names_the_other_rules_line(tmp_path: Path) -> None:
    # The behaviour's own duplicate check, worded as an FCL file names its rules: by line,
    # with the rule as written (RULE 1 : ...).
    path = tmp_path / "tiny.fcl"
    path.write_text(BLOCK.replace("IF x IS high THEN u IS down", "IF x IS low THEN u IS down"),
                    encoding="utf-8")
    with pytest.raises(SpecError) as caught:
        FclImporter().from_file(path)
    [problem] = caught.value.problems
    assert (problem.file, problem.line) == (str(path), 23)
    assert problem.message == ("duplicate rule: the same antecedent as the rule at line 22 "
                               "('RULE 1 : IF x IS low THEN u IS up')")


def test_fuzzylites_rules_without_semicolons_are_named_as_written(tmp_path: Path) -> None:
    # fuzzylite ends a rule at the line's end: the next rule is not part of the text.
    path = tmp_path / "tiny.fcl"
    path.write_text(BLOCK.replace("u IS up;", "u IS up").replace(
        "RULE 2 : IF x IS high THEN u IS down;", "RULE 2 : IF x IS low THEN u IS down"),
        encoding="utf-8")
    with pytest.raises(SpecError) as caught:
        FclImporter().from_file(path)
    assert [p.message for p in caught.value.problems] == [
        "duplicate rule: the same antecedent as the rule at line 22 ('RULE 1 : IF x IS low "
        "THEN u IS up')"]


def test_max_accumulation_of_shared_terms_is_refused() -> None:
    text = BLOCK.replace("ACCU : NSUM;", "ACCU : MAX;").replace("u IS down", "u IS up")
    with pytest.raises(ExportError, match=r"tiny.fcl:21: ACCU : MAX merges rules that share "
                       r"an output term \(lines 22 and 23"):
        FclImporter().from_string(text, "tiny.fcl")


def test_import_refuses_a_conjunction_other_than_min_or_product() -> None:
    text = FclExporter().to_string(load_behaviour(SHIPPED[0])).replace("AND : MIN;",
                                                                       "AND : BDIF;")
    with pytest.raises(ExportError, match=r"x.fcl:\d+: AND : BDIF: flctool's rules combine "
                       r"their memberships by the minimum \(eq. 2\) or the product"):
        FclImporter().from_string(text, "x.fcl")


def test_and_prod_imports_as_product_activation() -> None:
    behaviour = load_behaviour(SHIPPED[0])
    text = FclExporter().to_string(behaviour).replace("AND : MIN;", "AND : PROD;")
    imported = FclImporter().from_string(text, "x.fcl")
    assert imported.activation == "product"
    assert_same_controller(imported, with_product(behaviour),
                           random_states(behaviour, 2_000, seed=4))


def test_an_input_without_fuzzify_is_refused() -> None:
    text = BLOCK.replace(
        "VAR_INPUT\n    x : REAL;", "VAR_INPUT\n    x : REAL;\n    y : REAL;")
    with pytest.raises(ExportError, match=r"tiny.fcl:\d+: input 'y' has no FUZZIFY block"):
        FclImporter().from_string(text, "tiny.fcl")


def test_keywords_cannot_be_names() -> None:
    behaviour = load_behaviour(SHIPPED[0])
    renamed = behaviour.model_copy(update={"name": "rule"})
    with pytest.raises(ExportError, match="'rule' is an FCL keyword"):
        FclExporter().to_string(renamed)


@pytest.mark.parametrize(("old", "new", "message"), [
    ("END_FUNCTION_BLOCK", "FUZZIFY x\n    TERM all := (0, 1) (1, 1);\nEND_FUZZIFY\n"
     "END_FUNCTION_BLOCK", r"tiny.fcl:25: the input 'x' is defined twice, at lines 8 and 25"),
    ("    x : REAL;\n", "    x : REAL;\n    x : REAL;\n",
     r"tiny.fcl:4: the input 'x' is defined twice, at lines 3 and 4"),
    ("    TERM high := (0.2, 0) (1, 1);\n", "    TERM high := (0.2, 0) (1, 1);\n"
     "    TERM low := (0, 1) (1, 0);\n",
     r"tiny.fcl:11: the set 'low' of input 'x' is defined twice, at lines 9 and 11"),
    ("    TERM up := 1;\n", "    TERM up := 1;\n    TERM down := 2;\n",
     r"tiny.fcl:16: the output term 'down' is defined twice, at lines 14 and 16"),
])
def test_duplicate_names_are_refused_with_both_lines(old: str, new: str, message: str) -> None:
    text = BLOCK.replace(old, new)
    assert text != BLOCK
    with pytest.raises(ExportError, match=message):
        FclImporter().from_string(text, "tiny.fcl")


@pytest.mark.parametrize(("written", "value"), [
    ("(0..1)", (0.0, 1.0)), ("(0.0..1.0)", (0.0, 1.0)), ("(-1..+1)", (-1.0, 1.0)),
    ("(-.5 .. 1.)", (-0.5, 1.0)), ("(-1.5e-1..2E1)", (-0.15, 20.0)), ("(0..1_000.0)", (0.0, 1e3)),
])
def test_iec_number_forms_are_read(written: str, value: tuple[float, float]) -> None:
    lo, hi = value
    text = BLOCK.replace("RANGE := (0 .. 1);", f"RANGE := {written};").replace(
        "TERM high := (0.2, 0) (1, 1);", f"TERM high := (0.2, 0) ({hi!r}, 1);").replace(
        "TERM low := (0, 1)", f"TERM low := ({lo!r}, 1)")
    assert FclImporter().from_string(text, "tiny.fcl").inputs["x"].range == value


def test_shoulder_points_beyond_the_range_move_to_its_ends() -> None:
    text = BLOCK.replace("TERM low := (0, 1) (0.2, 1) (0.8, 0);",
                         "TERM low := (-0.5, 1) (0.2, 1) (0.8, 0);").replace(
        "TERM high := (0.2, 0) (1, 1);", "TERM high := (0.2, 0) (1, 1) (3, 1);")
    behaviour = FclImporter().from_string(text, "tiny.fcl")
    assert behaviour.inputs["x"].sets == {"low": (0.0, 0.0, 0.2, 0.8),
                                          "high": (0.2, 1.0, 1.0, 1.0)}
    # The same membership inside the range as the point lists read by IEC (constant outside
    # the points), so the same controller for clipped inputs.
    s = np.linspace(0.0, 1.0, 201)
    low = np.interp(s, [-0.5, 0.2, 0.8], [1.0, 1.0, 0.0])
    high = np.interp(s, [0.2, 1.0, 3.0], [0.0, 1.0, 1.0])
    want = (low * 1.0 + high * -1.0) / (low + high)
    assert np.allclose(compile_behaviour(behaviour).output(s[:, None]), want, rtol=0,
                       atol=1e-15)


def test_a_ramp_crossing_the_range_end_is_still_refused() -> None:
    text = BLOCK.replace("TERM low := (0, 1) (0.2, 1) (0.8, 0);",
                         "TERM low := (-0.5, 1) (0.8, 0);")
    with pytest.raises(ExportError, match=r"tiny.fcl:9: set 'low' .* has a ramp that the "
                       r"range's low end 0.0 cuts"):
        FclImporter().from_string(text, "tiny.fcl")


def test_options_is_a_keyword_and_an_empty_block_is_read() -> None:
    for word in ("options", "ASUM", "End_Options"):
        renamed = load_behaviour(SHIPPED[0]).model_copy(update={"name": word})
        with pytest.raises(ExportError, match="is an FCL keyword"):
            FclExporter().to_string(renamed)
    FclImporter().from_string(BLOCK.replace("END_FUNCTION_BLOCK", "OPTIONS\nEND_OPTIONS\n"
                                            "END_FUNCTION_BLOCK"), "tiny.fcl")
    with pytest.raises(ExportError, match=r"tiny.fcl:25: an OPTIONS block"):
        FclImporter().from_string(BLOCK.replace("END_FUNCTION_BLOCK", "OPTIONS\nfast;\n"
                                                "END_OPTIONS\nEND_FUNCTION_BLOCK"), "tiny.fcl")


@pytest.mark.parametrize(("source", "activation"),
                         [*((s, "min") for s in [*ALL_SHIPPED, 3, 11, 12, 21]),
                          *((s, "product") for s in PRODUCT_SOURCES)],
                         ids=lambda s: getattr(s, "name", str(s)))
@pytest.mark.slow
def test_fuzzylite6_reads_the_fuzzylite_dialect(source: object, activation: str,
                                                tmp_path: Path) -> None:
    """fuzzylite 6 reads --dialect fuzzylite and agrees within 1e-12 apart from its 1e-6
    tolerance, 20 % past the range's ends too (AND : PROD as fuzzylite's AlgebraicProduct)."""
    behaviour = reference_controller(source, activation)
    states = random_states(behaviour, 10_000, seed=5)
    text = FclExporter(ExportOptions(dialect="fuzzylite")).to_string(behaviour)
    quads = [[sloped_quad(q, v.range, interior=False) for q in v.sets.values()]
             for v in behaviour.inputs.values()]
    assert_fuzzylite_agrees(behaviour, text, "fcl", states, quads, tmp_path)


@pytest.mark.parametrize("activation", ["min", "product"])
@pytest.mark.parametrize("dialect", ["iec", "fuzzylite"])
@pytest.mark.parametrize("seed", range(8))
def test_both_dialects_import_back_exactly(dialect: str, seed: int, activation: str) -> None:
    behaviour = random_behaviour(seed, activation=activation)
    text = FclExporter(ExportOptions(dialect=dialect)).to_string(behaviour)
    assert_same_controller(FclImporter().from_string(text), behaviour,
                           random_states(behaviour, 2_000, seed=seed))


def test_fuzzylite_written_fcl_imports() -> None:
    """fuzzylite writes Trapezoid / Triangle terms, rules without ';', 'DEFAULT := nan | NC'
    and ACCU in DEFUZZIFY."""
    text = (BLOCK.replace("(0, 1) (0.2, 1) (0.8, 0)", "Trapezoid 0.0 0.0 0.2 0.8")
            .replace("(0.2, 0) (1, 1)", "Triangle 0.2 1.0 1.0")
            .replace("DEFAULT := 0;", "DEFAULT := nan | NC;\n    ACCU : NSUM;")
            .replace("    ACCU : NSUM;\n    RULE", "    RULE")
            .replace("THEN u IS up;", "then u is up").replace("THEN u IS down;", "then u is down"))
    behaviour = FclImporter().from_string(text, "tiny.fcl")
    assert behaviour.inputs["x"].sets == {"low": (0.0, 0.0, 0.2, 0.8),
                                          "high": (0.2, 1.0, 1.0, 1.0)}
    assert [r.then for r in behaviour.rules] == ["up", "down"]
