"""Mamdani outputs as singletons: only on request, and with the error measured; the Mamdani
output the measurement uses is fuzzylite 6's."""

from __future__ import annotations

import dataclasses
import re
import subprocess
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from flctool import compile_behaviour
from flctool.cli import app
from flctool.errors import ExportError, ImportRefusals
from flctool.export.fcl import FclImporter
from flctool.export.fis import FisImporter, _FisReader
from flctool.export.fll import FllImporter
from flctool.export.imported import as_written, build_behaviour
from flctool.export.mamdani import MamdaniOutput, centroid, mamdani_outputs

from .engines import fuzzylite_binary, fuzzylite_outputs

MAMDANI = """\
[System]
Name='mam'
Type='mamdani'
NumInputs=2
NumOutputs=1
NumRules=4
AndMethod='min'
OrMethod='max'
ImpMethod='min'
AggMethod='max'
DefuzzMethod='centroid'

[Input1]
Name='x'
Range=[0 1]
NumMFs=2
MF1='lo':'trapmf',[-1 0 0.2 0.8]
MF2='hi':'trapmf',[0.2 0.8 1 2]

[Input2]
Name='y'
Range=[0 10]
NumMFs=2
MF1='lo':'trimf',[-10 0 10]
MF2='hi':'trimf',[0 10 20]

[Output1]
Name='u'
Range=[-1 1]
NumMFs=3
MF1='left':'trimf',[-1 -0.5 0]
MF2='mid':'trimf',[-0.5 0 0.5]
MF3='right':'trapmf',[0 0.5 0.8 1]

[Rules]
1 1, 1 (1) : 1
1 2, 2 (1) : 1
2 1, 2 (1) : 1
2 2, 3 (1) : 1
"""
SETS = {"left": (-1.0, -0.5, -0.5, 0.0), "mid": (-0.5, 0.0, 0.0, 0.5),
        "right": (0.0, 0.5, 0.8, 1.0)}


def test_centroids() -> None:
    assert centroid((-1.0, -0.5, -0.5, 0.0)) == -0.5
    assert centroid((0.0, 1.0, 3.0, 4.0)) == 2.0
    assert centroid((0.0, 0.5, 0.8, 1.0)) == pytest.approx(0.5615384615384615)
    assert centroid((2.0, 2.0, 2.0, 2.0)) == 2.0


def test_a_mamdani_system_is_refused_unless_converting() -> None:
    with pytest.raises(ExportError, match=r"mam.fis:3: Type='mamdani': .*Mamdani output "
                       r"sets .*\(fix: import with --mamdani-singletons"):
        FisImporter().from_string(MAMDANI, "mam.fis")


def test_the_conversion_reports_its_largest_error() -> None:
    importer = FisImporter(mamdani_singletons=True)
    behaviour = importer.from_string(MAMDANI, "mam.fis")
    assert behaviour.output.commands == {n: centroid(q) for n, q in SETS.items()}
    assert "largest difference from the Mamdani output (centroid over 100 midpoints" in \
        importer.report
    deviation = float(importer.report.split(") is ")[1].split()[0])
    assert 0.01 < deviation < 0.1  # measured 0.0444: a real, stated approximation


@pytest.mark.parametrize("setting", ["ImpMethod='custom'", "AggMethod='sum'",
                                     "DefuzzMethod='bisector'"])
def test_settings_the_measurement_does_not_compute_are_refused(setting: str) -> None:
    key = setting.split("=")[0]
    text = "\n".join(setting if line.startswith(key + "=") else line
                     for line in MAMDANI.splitlines())
    with pytest.raises(ExportError, match=rf"mam.fis:\d+: {key}="):
        FisImporter(mamdani_singletons=True).from_string(text, "mam.fis")


@pytest.mark.slow
def test_the_mamdani_reference_is_fuzzylites(tmp_path: Path) -> None:
    """The output the error is measured against is what fuzzylite 6 computes for the file."""
    behaviour = FisImporter(mamdani_singletons=True).from_string(MAMDANI, "mam.fis")
    rng = np.random.default_rng(1)
    states = np.column_stack([rng.uniform(0, 1, 500), rng.uniform(0, 10, 500)])
    want = fuzzylite_outputs(MAMDANI, "fis", states, tmp_path)
    output = MamdaniOutput({n: (0, q) for n, q in SETS.items()}, (-1.0, 1.0), 100)
    got = mamdani_outputs(behaviour, output, states)
    assert np.max(np.abs(got - want)) <= 1e-12


def test_the_cli_option(tmp_path: Path) -> None:
    path = tmp_path / "mam.fis"
    path.write_text(MAMDANI, encoding="utf-8")
    result = CliRunner().invoke(app, ["import", str(path), "--mamdani-singletons",
                                      "-o", str(tmp_path / "mam.yaml")])
    assert result.exit_code == 0, result.output
    assert "largest difference from the Mamdani output" in result.output
    assert CliRunner().invoke(app, ["import", str(path)]).exit_code != 0


@pytest.mark.slow
@pytest.mark.parametrize(("implication", "aggregation"), [("min", "max"), ("prod", "probor")])
def test_the_reference_computes_fuzzylites_methods_and_shapes(implication: str,
                                                              aggregation: str,
                                                              tmp_path: Path) -> None:
    """Product implication, probabilistic-or aggregation and a Gaussian output set too."""
    text = (MAMDANI.replace("ImpMethod='min'", f"ImpMethod='{implication}'")
            .replace("AggMethod='max'", f"AggMethod='{aggregation}'")
            .replace("MF2='mid':'trimf',[-0.5 0 0.5]", "MF2='mid':'gaussmf',[0.2 0]"))
    importer = FisImporter(mamdani_singletons=True)
    behaviour = importer.from_string(text, "mam.fis")
    assert "largest difference from the Mamdani output" in importer.report
    rng = np.random.default_rng(2)
    states = np.column_stack([rng.uniform(0, 1, 500), rng.uniform(0, 10, 500)])
    want = fuzzylite_outputs(text, "fis", states, tmp_path)
    sets = {"left": (0, (-1.0, -0.5, -0.5, 0.0)), "mid": (1, (0.0, 0.2, 0.0, 0.0)),
            "right": (0, (0.0, 0.5, 0.8, 1.0))}
    output = MamdaniOutput(sets, (-1.0, 1.0), 100,
                           "Minimum" if implication == "min" else "AlgebraicProduct",
                           "Maximum" if aggregation == "max" else "AlgebraicSum")
    assert np.max(np.abs(mamdani_outputs(behaviour, output, states) - want)) <= 1e-12


MAMDANI_FLL = """\
Engine: mam
InputVariable: x
  enabled: true
  range: 0.0 1.0
  lock-range: true
  term: lo Trapezoid -1 0 0.2 0.8
  term: hi Gaussian 1.0 0.3
InputVariable: y
  enabled: true
  range: 0.0 10.0
  lock-range: true
  term: lo Triangle -10 0 10
  term: hi Triangle 0 10 20
OutputVariable: u
  enabled: true
  range: -1.0 1.0
  lock-range: false
  aggregation: Maximum
  defuzzifier: Centroid 200
  default: nan
  term: left Triangle -1 -0.5 0
  term: mid Gaussian 0 0.2
  term: right Bell 0.6 0.3 2
RuleBlock: rules
  enabled: true
  conjunction: Minimum
  implication: Minimum
  activation: General
  rule: if x is lo and y is lo then u is left
  rule: if x is lo and y is hi then u is mid
  rule: if x is hi and y is lo then u is mid
  rule: if x is hi and y is hi then u is right
"""


@pytest.mark.slow
@pytest.mark.parametrize(("implication", "aggregation"), [
    ("Minimum", "Maximum"), ("AlgebraicProduct", "AlgebraicSum")])
def test_an_fll_mamdani_output_converts_and_its_reference_is_fuzzylites(
        implication: str, aggregation: str, tmp_path: Path) -> None:
    text = (MAMDANI_FLL.replace("implication: Minimum", f"implication: {implication}")
            .replace("aggregation: Maximum", f"aggregation: {aggregation}"))
    with pytest.raises(ExportError, match=r"mam.fll:21: output 'u' has Mamdani sets"):
        FllImporter().from_string(text, "mam.fll")
    importer = FllImporter(mamdani_singletons=True)
    behaviour = importer.from_string(text, "mam.fll")
    assert behaviour.output.commands["mid"] == pytest.approx(0.0, abs=1e-12)
    assert "output 'u': Mamdani output sets replaced" in importer.report
    deviation = float(importer.report.split(" is ")[1].split()[0])
    rng = np.random.default_rng(3)
    states = np.column_stack([rng.uniform(0, 1, 2000), rng.uniform(0, 10, 2000)])
    want = fuzzylite_outputs(text, "fll", states, tmp_path)
    output = MamdaniOutput({"left": (0, (-1.0, -0.5, -0.5, 0.0)), "mid": (1, (0.0, 0.2, 0, 0)),
                            "right": (3, (0.3, 2.0, 0.6, 0.0))}, (-1.0, 1.0), 200,
                           implication, aggregation)
    assert np.max(np.abs(mamdani_outputs(behaviour, output, states) - want)) <= 1e-12
    # the stated error bounds what fuzzylite 6 measures on other states, within 1 %
    converted = compile_behaviour(behaviour).output(states)
    assert np.max(np.abs(converted - want)) <= 1.01 * deviation


#: Two outputs: 'u' Mamdani (a point list, a fuzzylite Triangle, a jFuzzyLogic gauss) and
#: 'v' singletons, sharing one rule block; fuzzylite 6 reads both.
MAMDANI_FCL = """\
FUNCTION_BLOCK mam
VAR_INPUT
  x : REAL;
  y : REAL;
END_VAR
VAR_OUTPUT
  u : REAL;
  v : REAL;
END_VAR
FUZZIFY x
  RANGE := (0.0 .. 1.0);
  TERM lo := (0.0, 1.0) (0.2, 1.0) (0.8, 0.0);
  TERM hi := (0.2, 0.0) (0.8, 1.0);
END_FUZZIFY
FUZZIFY y
  RANGE := (0.0 .. 10.0);
  TERM lo := Triangle -10.0 0.0 10.0;
  TERM hi := Triangle 0.0 10.0 20.0;
END_FUZZIFY
DEFUZZIFY u
  RANGE := (-1.0 .. 1.0);
  TERM left := (-1.0, 0.0) (-0.5, 1.0) (0.0, 0.0);
  TERM mid := Triangle -0.5 0.0 0.5;
  TERM right := Gaussian 0.6 0.3;
  METHOD : COG;
  ACCU : MAX;
  DEFAULT := nan;
END_DEFUZZIFY
DEFUZZIFY v
  TERM down := -1.0;
  TERM up := 1.0;
  METHOD : COGS;
  ACCU : NSUM;
  DEFAULT := nan;
END_DEFUZZIFY
RULEBLOCK rules
  AND : MIN;
  ACT : MIN;
  RULE 1 : if x is lo and y is lo then u is left and v is down
  RULE 2 : if x is lo and y is hi then u is mid and v is up
  RULE 3 : if x is hi and y is lo then u is mid and v is down
  RULE 4 : if x is hi and y is hi then u is right and v is up
END_RULEBLOCK
END_FUNCTION_BLOCK
"""


def test_an_fcl_mamdani_output_is_refused_unless_converting() -> None:
    with pytest.raises(ExportError, match=r"mam.fcl:22: output term 'left' is not a "
                       r"singleton.*\(fix: import with --mamdani-singletons"):
        FclImporter().from_string_all(MAMDANI_FCL, "mam.fcl")


@pytest.mark.parametrize(("old", "new", "message"), [
    ("METHOD : COG;", "METHOD : MM;", r"mam.fcl:25: METHOD : MM of the Mamdani output 'u'"),
    ("ACCU : MAX;", "ACCU : BSUM;", r"mam.fcl:26: ACCU : BSUM of the Mamdani output 'u'"),
    ("ACT : MIN;", "ACT : LM;", r"mam.fcl:38: ACT : LM"),
    ("TERM mid := Triangle -0.5 0.0 0.5;", "TERM mid := 0.0;",
     r"mam.fcl:22: output 'u' mixes singletons and sets"),
])
def test_fcl_mamdani_settings_the_measurement_does_not_compute_are_refused(
        old: str, new: str, message: str) -> None:
    text = MAMDANI_FCL.replace(old, new)
    assert text != MAMDANI_FCL
    with pytest.raises(ExportError, match=message):
        FclImporter(mamdani_singletons=True).from_string_all(text, "mam.fcl")


def test_an_fcl_file_with_two_outputs_converts_one_and_keeps_the_other_exact() -> None:
    importer = FclImporter(mamdani_singletons=True)
    u, v = importer.from_string_all(MAMDANI_FCL, "mam.fcl")
    assert (u.name, v.name) == ("u", "v")
    assert u.output.commands["left"] == -0.5 and u.output.commands["mid"] == 0.0
    assert v.output.commands == {"down": -1.0, "up": 1.0}
    assert [r.then for r in v.rules] == ["down", "up", "down", "up"]
    assert "2 outputs, imported as one behaviour each" in importer.report
    assert "output 'u': Mamdani output sets replaced" in importer.report
    assert "output 'v'" not in importer.report


@pytest.mark.slow
def test_an_fcl_mamdani_output_converts_and_its_reference_is_fuzzylites(tmp_path: Path
                                                                          ) -> None:
    importer = FclImporter(mamdani_singletons=True)
    u, v = importer.from_string_all(MAMDANI_FCL, "mam.fcl")
    rng = np.random.default_rng(4)
    states = np.column_stack([rng.uniform(0, 1, 2000), rng.uniform(0, 10, 2000)])
    want = fuzzylite_outputs(MAMDANI_FCL, "fcl", states, tmp_path, outputs=2)
    output = MamdaniOutput({"left": (0, (-1.0, -0.5, -0.5, 0.0)),
                            "mid": (0, (-0.5, 0.0, 0.0, 0.5)), "right": (1, (0.6, 0.3, 0, 0))},
                           (-1.0, 1.0), 100)
    assert np.max(np.abs(mamdani_outputs(u, output, states) - want[:, 0])) <= 1e-12
    # the singleton output is exact; the Mamdani one within the stated error
    assert np.max(np.abs(compile_behaviour(v).output(states) - want[:, 1])) <= 1e-12
    line = next(t for t in importer.report.splitlines() if "output 'u'" in t)
    deviation = float(line.split(" is ")[1].split()[0])
    assert np.max(np.abs(compile_behaviour(u).output(states) - want[:, 0])) <= 1.01 * deviation


#: MAMDANI with rules flctool's grid does not have: a product conjunction, a rule that leaves
#: out y (weight 0.5) and an OR rule, which fuzzylite 6 and MATLAB read.
REWRITTEN = (MAMDANI.replace("AndMethod='min'", "AndMethod='prod'").replace("NumRules=4",
                                                                             "NumRules=3")
             .split("[Rules]")[0] + "[Rules]\n1 1, 1 (1) : 1\n2 0, 3 (0.5) : 1\n1 2, 2 (1) : 2\n")


#: REWRITTEN as a Sugeno system (constant outputs), whose rules must be exact.
SUGENO = (REWRITTEN.replace("Type='mamdani'", "Type='sugeno'")
          .replace("AndMethod='prod'", "AndMethod='min'").replace("AggMethod='max'",
                                                                  "AggMethod='sum'")
          .replace("DefuzzMethod='centroid'", "DefuzzMethod='wtaver'")
          .replace("'trimf',[-1 -0.5 0]", "'constant',[-0.5]")
          .replace("'trimf',[-0.5 0 0.5]", "'constant',[0]")
          .replace("'trapmf',[0 0.5 0.8 1]", "'constant',[0.5]"))


def test_a_first_order_output_and_an_unknown_mf_are_listed_with_the_rules() -> None:
    text = (SUGENO.replace("'constant',[0.5]", "'linear',[1 0 0.5]")
            .replace("'trimf',[0 10 20]", "'discretemf',[0 0 10 1]"))
    with pytest.raises(ExportError) as caught:
        FisImporter().from_string(text, "mam.fis")
    listed = str(caught.value).splitlines()
    assert listed[0] == "mam.fis: 5 constructs flctool cannot import"
    assert "mam.fis:25: membership function 'hi' is a discretemf" in listed[1]
    assert "mam.fis:33: output term 'right' is first-order Takagi-Sugeno" in listed[2]
    assert [line.split(":")[1] for line in listed[3:]] == ["37", "37", "38"]


def test_rules_outside_the_grid_are_refused_unless_converting() -> None:
    """A Sugeno system's rules are imported exactly or not at all."""
    sugeno = SUGENO
    with pytest.raises(ExportError, match=r"mam.fis:37: a rule weight of 0.5"):
        FisImporter().from_string(sugeno, "mam.fis")
    with pytest.raises(ExportError, match=r"mam.fis:37: the rule leaves out input 'y'"):
        FisImporter().from_string(sugeno.replace("(0.5)", "(1)"), "mam.fis")
    with pytest.raises(ExportError, match=r"mam.fis:38: an OR rule: .*--mamdani-singletons"):
        FisImporter().from_string(sugeno.replace("2 0, 3 (0.5)", "2 1, 3 (1)"), "mam.fis")


def test_converting_expands_the_rules_and_merges_a_combination_given_two_commands() -> None:
    importer = FisImporter(mamdani_singletons=True)
    behaviour = importer.from_string(REWRITTEN, "mam.fis")
    rules = {tuple(r.if_.values()): r.then for r in behaviour.rules}
    # rule 1 (lo, lo) -> left, rule 2 (hi, *) -> right, rule 3 (lo, *) or (*, hi) -> mid
    assert rules == {("lo", "lo"): "left_or_mid", ("hi", "lo"): "right",
                     ("lo", "hi"): "mid", ("hi", "hi"): "mid_or_right"}
    commands = behaviour.output.commands
    assert commands["left_or_mid"] == (commands["left"] + commands["mid"]) / 2
    assert "rules rewritten as flctool's" in importer.report
    assert behaviour.is_deployable


def test_a_rule_without_a_condition_is_refused_at_its_line() -> None:
    text = REWRITTEN.replace("2 0, 3 (0.5) : 1", "0 0, 3 (1) : 1")
    with pytest.raises(ExportError, match=r"mam.fis:37: the rule has no condition"):
        FisImporter(mamdani_singletons=True).from_string(text, "mam.fis")


#: REWRITTEN with an OR rule of two NOTs (negative indices).
NEGATED = REWRITTEN.replace("NumRules=3", "NumRules=4") + "-2 -1, 1 (1) : 2\n"


def test_not_expands_over_the_other_sets_when_converting() -> None:
    behaviour = FisImporter(mamdani_singletons=True).from_string(NEGATED, "mam.fis")
    rules = {tuple(r.if_.values()): r.then for r in behaviour.rules}
    # x not hi (lo, *) or y not lo (*, hi) -> left, merged with the rules above
    assert rules[("lo", "hi")] == "left_or_mid"
    with pytest.raises(ExportError, match=r"mam.fis:39: NOT on input 'x'"):
        FisImporter().from_string(NEGATED, "mam.fis")


@pytest.mark.slow
@pytest.mark.parametrize("text", [REWRITTEN, NEGATED], ids=["rewritten", "negated"])
def test_the_rewritten_rules_are_measured_against_fuzzylites_output(text: str,
                                                                    tmp_path: Path) -> None:
    """The Mamdani output the measurement computes from the rules as written (weights, OR,
    NOT, a left-out input, product) is fuzzylite 6's, and the converted controller stays
    within the stated difference of it."""
    reader = _FisReader("mam.fis", mamdani_singletons=True)
    behaviour = build_behaviour(reader.read(text))
    output = dataclasses.replace(reader.mamdani_output(), **as_written(reader.result))
    assert output.conjunction == "AlgebraicProduct" and output.rewritten
    rng = np.random.default_rng(5)
    states = np.column_stack([rng.uniform(0, 1, 2000), rng.uniform(0, 10, 2000)])
    want = fuzzylite_outputs(text, "fis", states, tmp_path)
    assert np.max(np.abs(mamdani_outputs(behaviour, output, states) - want)) <= 1e-12
    importer = FisImporter(mamdani_singletons=True)
    converted = importer.from_string(text, "mam.fis")
    deviation = float(importer.report.split(") is ")[-1].split()[0])
    # the stated error bounds what fuzzylite 6 computes on other states, within 1 %
    assert np.max(np.abs(compile_behaviour(converted).output(states) - want)) <= \
        1.01 * deviation


def test_every_construct_that_keeps_a_file_out_is_reported_at_once() -> None:
    """Not converting REWRITTEN: the Mamdani system, the weight, the rule that leaves out y
    and the OR rule, each at its line with its fix, in one error (its product conjunction
    is no refusal: it imports as activation: product)."""
    with pytest.raises(ExportError) as caught:
        FisImporter().from_string(REWRITTEN, "mam.fis")
    text = str(caught.value)
    assert text.startswith("mam.fis: 4 constructs flctool cannot import\n")
    listed = text.splitlines()[1:]
    assert [line.split(":")[1] for line in listed] == ["3", "37", "37", "38"]
    assert all("(fix: " in line for line in listed)
    assert "AndMethod='prod'" not in text and "a rule weight of 0.5" in text
    assert "leaves out input 'y'" in text and "an OR rule" in listed[3]


@pytest.mark.slow
def test_fll_and_fcl_rewrite_and_measure_as_fis_does(tmp_path: Path) -> None:
    """fuzzylite 6 writes NEGATED as FLL and FCL (`or`, `is not`, `with 0.5`, a left-out
    input, AlgebraicProduct / AND : PROD); each imports to the same behaviour and states the
    same difference as the FIS."""
    source = tmp_path / "neg.fis"
    source.write_text(NEGATED, encoding="utf-8")
    results = []
    for format, importer in (("fis", FisImporter), ("fll", FllImporter), ("fcl", FclImporter)):
        path = tmp_path / f"neg.{format}"
        if format != "fis":
            subprocess.run([fuzzylite_binary(), "-i", str(source), "-if", "fis", "-of", format,
                            "-o", str(path)], check=True, capture_output=True, timeout=60)
        converting = importer(mamdani_singletons=True)
        behaviour = converting.from_file(path)
        results.append((behaviour.inputs, behaviour.output.commands,
                        [(r.if_, r.then) for r in behaviour.rules],
                        converting.report.split(") is ")[-1].split()[0]))
    assert results[0] == results[1] == results[2]


def test_every_setting_the_measurement_does_not_compute_is_listed() -> None:
    """ImpMethod, AggMethod and DefuzzMethod are each reported, with the file's other
    refusals, not only the first."""
    text = (MAMDANI.replace("ImpMethod='min'", "ImpMethod='custom'")
            .replace("AggMethod='max'", "AggMethod='sum'")
            .replace("DefuzzMethod='centroid'", "DefuzzMethod='bisector'"))
    with pytest.raises(ImportRefusals) as caught:
        FisImporter(mamdani_singletons=True).from_string(text, "mam.fis")
    message = str(caught.value)
    for key in ("ImpMethod='custom'", "AggMethod='sum'", "DefuzzMethod='bisector'"):
        assert re.search(rf"mam.fis:\d+: {key}: .*\(fix: use ", message), message
