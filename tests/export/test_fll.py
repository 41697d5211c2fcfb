"""FLL: the export runs in pyfuzzylite 7.1 with flctool's outputs; the import's subset."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from flctool import compile_behaviour, load_behaviour
from flctool.behaviour import Behaviour
from flctool.errors import ExportError, SpecError
from flctool.export.fll import FllExporter, FllImporter

from .controllers import random_behaviour, random_states
from .engines import ALL_SHIPPED, PRODUCT_SOURCES, assert_fuzzylite_agrees, reference_controller
from .roundtrip import SHIPPED

fl = pytest.importorskip("fuzzylite", reason="pyfuzzylite (the test extra) checks FLL exports")


@pytest.fixture
def exact_fuzzylite() -> Iterator[None]:
    """fuzzylite skips rules whose activation is within lib.abs_tolerance (1e-5) of 0, which
    changes eq. 3 by up to ~1e-5; with tolerance 0 every firing rule counts, as in flctool."""
    saved = fl.lib.abs_tolerance
    fl.lib.abs_tolerance = 0.0
    yield
    fl.lib.abs_tolerance = saved


def fuzzylite_outputs(behaviour: Behaviour, states: np.ndarray) -> np.ndarray:
    engine = fl.FllImporter().from_string(FllExporter().to_string(behaviour))
    inputs, output = engine.input_variables, engine.output_variables[0]
    result = np.empty(len(states))
    for row, state in enumerate(states):
        for variable, value in zip(inputs, state, strict=True):
            variable.value = float(value)
        engine.process()
        result[row] = output.value
    return result


@pytest.mark.slow
@pytest.mark.usefixtures("exact_fuzzylite")
@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: p.name)
def test_pyfuzzylite_matches_on_10000_states(path: object) -> None:
    behaviour = load_behaviour(str(path))
    # States reach 20 % past both ends of every range: lock-range clips them as flctool does.
    states = random_states(behaviour, 10_000, seed=7)
    got = fuzzylite_outputs(behaviour, states)
    assert np.max(np.abs(got - compile_behaviour(behaviour).output(states))) <= 1e-9


@pytest.mark.slow
@pytest.mark.usefixtures("exact_fuzzylite")
@pytest.mark.parametrize("seed", [3, 11, 12])
def test_pyfuzzylite_matches_random_controllers(seed: int) -> None:
    behaviour = random_behaviour(seed, max_inputs=3)
    states = random_states(behaviour, 3_000, seed=seed)
    got = fuzzylite_outputs(behaviour, states)
    assert np.max(np.abs(got - compile_behaviour(behaviour).output(states))) <= 1e-9


def test_numbers_keep_full_precision() -> None:
    behaviour = random_behaviour(5)
    text = FllExporter().to_string(behaviour)
    for variable in behaviour.inputs.values():
        for quad in variable.sets.values():
            assert repr(quad[0]) in text


def test_the_engine_computes_eq_3() -> None:
    text = FllExporter().to_string(load_behaviour(SHIPPED[0]))
    for line in ("conjunction: Minimum", "aggregation: none", "lock-range: true",
                 "defuzzifier: WeightedAverage TakagiSugeno", "activation: General"):
        assert line in text


def test_reserved_words_cannot_be_names() -> None:
    behaviour = random_behaviour(1)
    renamed = behaviour.model_copy(update={"output": behaviour.output.model_copy(
        update={"name": "very"})})
    with pytest.raises(ExportError, match="'very' is a keyword of FLL"):
        FllExporter().to_string(renamed)


ENGINE = """\
Engine: tiny
InputVariable: x
  enabled: true
  range: 0.0 1.0
  lock-range: true
  term: low Trapezoid 0.0 0.0 0.2 0.8
  term: high Triangle 0.2 1.0 1.0
OutputVariable: u
  enabled: true
  range: -1.0 1.0
  aggregation: none
  defuzzifier: WeightedAverage TakagiSugeno
  term: down Constant -1.0
  term: up Constant 1.0
RuleBlock: rules
  enabled: true
  conjunction: Minimum
  activation: General
  rule: if x is low then u is up
  rule: if x is high then u is down
"""


def test_import_reads_the_subset() -> None:
    behaviour = FllImporter().from_string(ENGINE, "tiny.fll")
    assert behaviour.inputs["x"].sets == {"low": (0.0, 0.0, 0.2, 0.8),
                                          "high": (0.2, 1.0, 1.0, 1.0)}
    assert behaviour.output.commands == {"down": -1.0, "up": 1.0}
    assert behaviour.is_deployable


@pytest.mark.parametrize(("old", "new", "message"), [
    ("term: high Triangle 0.2 1.0 1.0", "term: high Discrete 0.2 0.0 1.0 1.0",
     r"tiny.fll:7: a Discrete term"),
    ("term: high Triangle 0.2 1.0 1.0", "term: high Gaussian 0.8 0.1 0.5",
     r"tiny.fll:7: the term 'high' has height 0.5"),
    ("term: up Constant 1.0", "term: up Triangle 0.0 0.5 1.0",
     r"tiny.fll:14: output 'u' has Mamdani sets.*\(fix: import with --mamdani-singletons"),
    ("rule: if x is low then u is up", "rule: if x is low or x is high then u is up",
     r"tiny.fll:19: an OR rule: flctool's rules are one AND chain"),
    ("rule: if x is low then u is up", "rule: if x is very low then u is up",
     r"tiny.fll:19: the hedge 'very'"),
    ("rule: if x is low then u is up", "rule: if x is not low then u is up",
     r"tiny.fll:19: NOT on input 'x'"),
    ("rule: if x is low then u is up", "rule: if x is low then u is up with 0.5",
     r"tiny.fll:19: a rule weight of 0.5"),
    ("term: low Trapezoid 0.0 0.0 0.2 0.8", "term: low Trapezoid 0.0 0.0 0.2 0.8 0.5",
     r"tiny.fll:6: the term 'low' has height 0.5"),
    ("  defuzzifier: WeightedAverage TakagiSugeno", "  defuzzifier: Centroid 100",
     r"tiny.fll:12: defuzzifier Centroid"),
    ("rule: if x is high then u is down", "rule: if x is high then u is up",
     None),  # two rules may share a term without aggregation
    ("  activation: General", "  activation: Highest 1", r"tiny.fll:18: activation Highest"),
    ("  range: 0.0 1.0", "  range: 1.0 0.0",  # not "a set does not reach into the range"
     r"tiny.fll:\d+: input 'x' has the range \[1.0, 0.0\], whose low end is not below"),
])
def test_import_names_what_it_cannot_express(old: str, new: str, message: str | None) -> None:
    text = ENGINE.replace(old, new)
    assert text != ENGINE
    if message is None:
        FllImporter().from_string(text, "tiny.fll")
        return
    with pytest.raises(ExportError, match=message):
        FllImporter().from_string(text, "tiny.fll")


@pytest.mark.parametrize(("new", "message"), [
    ("rule: if x is lo then u is up", "input 'x' has no set 'lo'. Did you mean 'low'"),
    ("rule: if y is low then u is up", "rule names an unknown input 'y'"),
    ("rule: if x is low then u is upp", "unknown command 'upp'. Did you mean 'up'"),
    ("rule: if x is high then u is up", "duplicate rule"),
])
def test_rule_checks_are_the_behaviours_located_at_the_rule(new: str, message: str) -> None:
    # One set of rule checks (the behaviour's), each problem at its rule's line in the file.
    text = ENGINE.replace("rule: if x is low then u is up", new)
    with pytest.raises(SpecError) as caught:
        FllImporter().from_string(text, "tiny.fll")
    located = [(p.file, p.line) for p in caught.value.problems if message in p.message]
    assert ("tiny.fll", 19 if "duplicate" not in message else 20) in located, caught.value


def test_a_duplicate_rule_names_the_other_rules_line(tmp_path: Path) -> None:
    # The behaviour's own duplicate check, worded as an FLL file names its rules: by line.
    path = tmp_path / "tiny.fll"
    path.write_text(ENGINE.replace("if x is high then u is down", "if x is low then u is down"),
                    encoding="utf-8")
    with pytest.raises(SpecError) as caught:
        FllImporter().from_file(path)
    [problem] = caught.value.problems
    assert (problem.file, problem.line) == (str(path), 20)
    assert problem.message == ("duplicate rule: the same antecedent as the rule at line 19 "
                               "('if x is low then u is up')")


def test_a_broken_rule_table_stops_at_the_line_of_the_first_rule_left_unchecked(
        tmp_path: Path) -> None:
    from flctool.behaviour.checks import MAX_RULE_PROBLEMS

    broken = "\n".join(["  rule: if x is nowhere then u is up"] * (MAX_RULE_PROBLEMS + 5))
    path = tmp_path / "broken.fll"
    path.write_text(ENGINE.split("  rule:")[0] + broken + "\n", encoding="utf-8")
    with pytest.raises(SpecError) as caught:
        FllImporter().from_file(path)
    problems = caught.value.problems
    assert len(problems) == MAX_RULE_PROBLEMS + 1
    assert problems[0].message == "input 'x' has no set 'nowhere'."
    last = problems[-1]
    assert last.line == 19 + MAX_RULE_PROBLEMS
    assert last.message == (f"the rules from the rule at line {19 + MAX_RULE_PROBLEMS} ('if x "
                            f"is nowhere then u is up') on are not checked: {MAX_RULE_PROBLEMS} "
                            "problems already")


def test_aggregation_merging_shared_terms_is_refused() -> None:
    text = ENGINE.replace("aggregation: none", "aggregation: Maximum").replace(
        "then u is down", "then u is up")
    with pytest.raises(ExportError, match=r"tiny.fll:11: aggregation Maximum merges rules "
                       r"that share an output term \(lines 19 and 20"):
        FllImporter().from_string(text, "tiny.fll")
    # with no shared term, a maximum changes nothing
    FllImporter().from_string(ENGINE.replace("aggregation: none", "aggregation: Maximum"))


@pytest.mark.parametrize(("old", "new", "message"), [
    ("  term: up Constant 1.0", "  term: up Constant 1.0\n  term: down Constant 2.0",
     r"tiny.fll:15: the output term 'down' is defined twice, at lines 13 and 15"),
    ("OutputVariable: u", "InputVariable: x\n  range: 0.0 1.0\n  term: all Trapezoid 0 0 1 1\n"
     "OutputVariable: u", r"tiny.fll:8: the input 'x' is defined twice, at lines 2 and 8"),
    ("  term: high Triangle 0.2 1.0 1.0", "  term: high Triangle 0.2 1.0 1.0\n"
     "  term: low Triangle 0.0 0.5 1.0",
     r"tiny.fll:8: the set 'low' of input 'x' is defined twice, at lines 6 and 8"),
])
def test_duplicate_names_are_refused_with_both_lines(old: str, new: str, message: str) -> None:
    with pytest.raises(ExportError, match=message):
        FllImporter().from_string(ENGINE.replace(old, new), "tiny.fll")


@pytest.mark.usefixtures("exact_fuzzylite")
def test_infinite_shoulders_reach_the_range_ends_exactly() -> None:
    text = ENGINE.replace("Trapezoid 0.0 0.0 0.2 0.8", "Trapezoid -inf -inf 0.2 0.8").replace(
        "Triangle 0.2 1.0 1.0", "Triangle 0.2 1.0 inf")
    behaviour = FllImporter().from_string(text, "tiny.fll")
    assert behaviour.inputs["x"].sets == {"low": (0.0, 0.0, 0.2, 0.8),
                                          "high": (0.2, 1.0, 1.0, 1.0)}
    # the same outputs as fuzzylite running the file itself (lock-range clips its inputs)
    engine = fl.FllImporter().from_string(text)
    states = np.linspace(-0.5, 1.5, 401)
    want = np.empty(len(states))
    for row, value in enumerate(states):
        engine.input_variables[0].value = float(value)
        engine.process()
        want[row] = engine.output_variables[0].value
    assert np.array_equal(compile_behaviour(behaviour).output(states[:, None]), want)


def test_an_infinite_point_inside_a_term_is_refused() -> None:
    # an infinite foot makes the membership 1 up to the next top, whatever b is
    behaviour = FllImporter().from_string(
        ENGINE.replace("Trapezoid 0.0 0.0 0.2 0.8", "Trapezoid -inf 0.1 0.2 0.8"))
    assert behaviour.inputs["x"].sets["low"] == (0.0, 0.0, 0.2, 0.8)
    text = ENGINE.replace("Trapezoid 0.0 0.0 0.2 0.8", "Trapezoid 0.0 inf inf 0.8")
    with pytest.raises(ExportError, match=r"tiny.fll:6: a Trapezoid with an infinite point"):
        FllImporter().from_string(text, "tiny.fll")


@pytest.mark.parametrize(("source", "activation"),
                         [*((s, "min") for s in [*ALL_SHIPPED, 3, 11, 12, 21]),
                          *((s, "product") for s in PRODUCT_SOURCES)],
                         ids=lambda s: getattr(s, "name", str(s)))
@pytest.mark.slow
def test_fuzzylite6_computes_the_same_outputs(source: object, activation: str,
                                              tmp_path: Path) -> None:
    """The fuzzylite 6 command line reads the export and agrees within 1e-12, apart from its
    1e-6 tolerance; the states include set corners and states 20 % out of range. With
    activation: product, conjunction AlgebraicProduct."""
    behaviour = reference_controller(source, activation)
    states = random_states(behaviour, 10_000, seed=5)
    quads = [list(v.sets.values()) for v in behaviour.inputs.values()]
    assert_fuzzylite_agrees(behaviour, FllExporter().to_string(behaviour), "fll", states,
                            quads, tmp_path)


def test_ramps_and_zero_order_linear_terms_import_exactly() -> None:
    text = (ENGINE.replace("Trapezoid 0.0 0.0 0.2 0.8", "Ramp 0.8 0.2")
            .replace("Triangle 0.2 1.0 1.0", "Ramp 0.2 1.0")
            .replace("Constant 1.0", "Linear 0.0 1.0"))
    behaviour = FllImporter().from_string(text, "tiny.fll")
    assert behaviour.inputs["x"].sets == {"low": (0.0, 0.0, 0.2, 0.8),
                                          "high": (0.2, 1.0, 1.0, 1.0)}
    assert behaviour.output.commands == {"down": -1.0, "up": 1.0}
    with pytest.raises(ExportError, match=r"tiny.fll:14: output term 'up' is first-order"):
        FllImporter().from_string(ENGINE.replace("Constant 1.0", "Linear 0.5 1.0"), "tiny.fll")


@pytest.mark.parametrize("line", ["  lock-range: maybe", "  range: 0 1 x", "  default: soon"])
def test_the_outputs_settings_must_be_valid(line: str) -> None:
    text = ENGINE.replace("  range: -1.0 1.0", line)
    with pytest.raises(ExportError, match=r"tiny.fll:\d+: "):
        FllImporter().from_string(text, "tiny.fll")


def test_several_outputs_import_as_one_behaviour_each() -> None:
    """Each output keeps the rules that conclude on it: fuzzylite computes the outputs
    independently, so each behaviour is exact."""
    text = (ENGINE.replace("RuleBlock: rules", "OutputVariable: v\n  enabled: true\n"
                           "  defuzzifier: WeightedAverage\n  term: slow Constant 0.5\n"
                           "  term: fast Constant 2.0\nRuleBlock: rules")
            .replace("then u is up", "then u is up and v is fast")
            .replace("then u is down", "then v is slow and u is down"))
    importer = FllImporter()
    with pytest.raises(ExportError, match=r"tiny.fll:1: the controller has 2 outputs"):
        importer.from_string(text, "tiny.fll")
    u, v = importer.from_string_all(text, "tiny.fll")
    assert (u.name, u.output.name, v.name, v.output.name) == ("u", "u", "v", "v")
    assert [(r.if_["x"], r.then) for r in u.rules] == [("low", "up"), ("high", "down")]
    assert [(r.if_["x"], r.then) for r in v.rules] == [("low", "fast"), ("high", "slow")]
    assert "2 outputs, imported as one behaviour each" in importer.report
