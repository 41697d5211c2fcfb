"""FIS: MATLAB's Sugeno text, and the import's subset."""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pytest

from flctool import compile_behaviour, load_behaviour
from flctool.behaviour import Behaviour
from flctool.errors import ExportError, SpecError
from flctool.export.base import sloped_quad
from flctool.export.fis import FisExporter, FisImporter
from flctool.export.imported import DONT_CARE_HINT

from .controllers import random_behaviour, random_states
from .engines import (
    ALL_SHIPPED,
    PRODUCT_SOURCES,
    assert_fuzzylite_agrees,
    octave_outputs,
    reference_controller,
)
from .roundtrip import SHIPPED


def test_the_system_computes_eq_3() -> None:
    text = FisExporter().to_string(load_behaviour(SHIPPED[0]))
    for line in ("Type='sugeno'", "AndMethod='min'", "DefuzzMethod='wtaver'",
                 "MF1='small':'trapmf',[-2.0 -1.0 0.1 0.3]",
                 "MF2='right':'trimf',[-60.0 -30.0 0.0]",
                 "MF1='turn_right':'constant',[-1.0]", "1 1, 1 (1) : 1"):
        assert line in text


SYSTEM = """\
[System]
Name='tiny'
Type='sugeno'
NumInputs=1
NumOutputs=1
AndMethod='min'
DefuzzMethod='wtaver'

[Input1]
Name='x'
Range=[0 1]
NumMFs=2
MF1='low':'trapmf',[0 0 0.2 0.8]
MF2='high':'trimf',[0.2 1 1]

[Output1]
Name='u'
Range=[-1 1]
NumMFs=2
MF1='down':'constant',[-1]
MF2='up':'constant',[1]

[Rules]
1, 2 (1) : 1
2, 1 (1) : 1
"""


def test_import_reads_the_subset() -> None:
    behaviour = FisImporter().from_string(SYSTEM, "tiny.fis")
    assert behaviour.inputs["x"].sets == {"low": (0.0, 0.0, 0.2, 0.8),
                                          "high": (0.2, 1.0, 1.0, 1.0)}
    assert behaviour.output.commands == {"down": -1.0, "up": 1.0}
    assert behaviour.is_deployable


@pytest.mark.parametrize(("old", "new", "message"), [
    ("Type='sugeno'", "Type='mamdani'", r"tiny.fis:3: Type='mamdani'.*Mamdani output sets"),
    ("MF2='up':'constant',[1]", "MF2='up':'linear',[1 0]",
     r"tiny.fis:21: output term 'up' is first-order Takagi-Sugeno"),
    ("MF2='high':'trimf',[0.2 1 1]", "MF2='high':'discretemf',[0.1 1]",
     r"tiny.fis:14: membership function 'high' is a discretemf"),
    ("MF2='high':'trimf',[0.2 1 1]", "MF2='high':'gaussmf',[0 1]",
     r"tiny.fis:14: .*sigma is 0.0; it must be above 0"),
    ("1, 2 (1) : 1", "1, 2 (0.5) : 1", r"tiny.fis:24: a rule weight of 0.5"),
    ("1, 2 (1) : 1", "-1, 2 (1) : 1", r"tiny.fis:24: NOT"),
    ("NumOutputs=1", "NumOutputs=2", r"tiny.fis:5: NumOutputs=2"),
    ("DefuzzMethod='wtaver'", "DefuzzMethod='wtsum'", r"tiny.fis:7: DefuzzMethod='wtsum'"),
    ("1, 2 (1) : 1", "1, 3 (1) : 1", r"tiny.fis:24: the output has no MF3"),
    ("1, 2 (1) : 1", "1, 2 (1) : 2", None),  # OR with a single input is the same rule
    ("Range=[0 1]", "Range=[1 0]",  # not "a set does not reach into the range"
     r"tiny.fis:\d+: input 'x' has the range \[1.0, 0.0\], whose low end is not below"),
])
def test_import_names_what_it_cannot_express(old: str, new: str, message: str | None) -> None:
    text = SYSTEM.replace(old, new)
    assert text != SYSTEM
    if message is None:
        FisImporter().from_string(text, "tiny.fis")
        return
    with pytest.raises(ExportError, match=message):
        FisImporter().from_string(text, "tiny.fis")


def test_an_or_rule_over_two_inputs_is_refused() -> None:
    text = FisExporter().to_string(load_behaviour(SHIPPED[0])).replace(
        "1 1, 1 (1) : 1", "1 1, 1 (1) : 2")
    with pytest.raises(ExportError, match=r"x.fis:\d+: an OR rule: .*--mamdani-singletons"):
        FisImporter().from_string(text, "x.fis")


def test_a_duplicate_rule_names_the_other_rules_line(tmp_path: Path) -> None:
    # The behaviour's own duplicate check, worded as a FIS file names its rules: by line.
    path = tmp_path / "tiny.fis"
    path.write_text(SYSTEM.replace("2, 1 (1) : 1", "1, 1 (1) : 1"), encoding="utf-8")
    with pytest.raises(SpecError) as caught:
        FisImporter().from_file(path)
    [problem] = caught.value.problems
    assert (problem.file, problem.line) == (str(path), 25)
    assert problem.message == ("duplicate rule: the same antecedent as the rule at line 24 "
                               "('1, 2 (1) : 1')")
    assert problem.hint == "each combination of sets gets one rule; delete one of them"


#: SYSTEM with a second input y, and rules over both.
TWO_INPUTS = SYSTEM.replace("NumInputs=1", "NumInputs=2").replace("[Output1]", """\
[Input2]
Name='y'
Range=[0 1]
NumMFs=2
MF1='low':'trapmf',[0 0 0.2 0.8]
MF2='high':'trimf',[0.2 1 1]

[Output1]""").replace("[Rules]\n1, 2 (1) : 1\n2, 1 (1) : 1\n", "[Rules]\n1 1, 2 (1) : 1\n")


@pytest.mark.parametrize(("rule", "left_out"), [
    ("0 1, 2 (1) : 1", "input 'x'"),
    ("1 0, 2 (1) : 1", "input 'y'"),
    ("0 0, 2 (1) : 1", "inputs 'x', 'y'"),
])
def test_an_input_left_out_by_index_0_is_refused_once(rule: str, left_out: str,
                                                      tmp_path: Path) -> None:
    # The parser reads index 0 as the input left out, and the check all formats share refuses
    # it: one message, naming every input the rule leaves out and how the file says so.
    path = tmp_path / "two.fis"
    path.write_text(TWO_INPUTS.replace("1 1, 2 (1) : 1", rule), encoding="utf-8")
    assert FisImporter().from_string(TWO_INPUTS).rule_count == 4  # the file is valid without it
    with pytest.raises(ExportError) as caught:
        FisImporter().from_file(path)
    assert str(caught.value) == (
        f"{path}:31: the rule leaves out {left_out} (index 0): it fires with the other inputs' "
        "minimum alone, which no rule of the full grid (eq. 1-2) does, so expanding it over "
        f"the sets would change the output (fix: {DONT_CARE_HINT})")


def test_names_become_identifiers_unless_two_collide() -> None:
    """MATLAB files name things 'Food-Quality': the import derives 'Food_Quality'."""
    text = SYSTEM.replace("Name='x'", "Name='x y'").replace("'low'", "'Low-1'")
    behaviour = FisImporter().from_string(text, "tiny.fis")
    assert list(behaviour.inputs) == ["x_y"]
    assert list(behaviour.inputs["x_y"].sets) == ["Low_1", "high"]
    assert behaviour.rules[0].if_ == {"x_y": "Low_1"}
    with pytest.raises(ExportError, match=r"tiny.fis:14: the set of input 'x' names 'low-1' "
                       r"\(line 13\) and 'low_1' both become 'low_1'"):
        FisImporter().from_string(SYSTEM.replace("'low'", "'low-1'").replace(
            "'high'", "'low_1'"), "tiny.fis")


@pytest.mark.parametrize(("old", "new", "message"), [
    ("MF2='high':'trimf',[0.2 1 1]", "MF2='low':'trimf',[0.2 1 1]",
     r"tiny.fis:14: the set 'low' of input 'x' is defined twice, at lines 13 and 14"),
    ("MF2='up':'constant',[1]", "MF2='down':'constant',[1]",
     r"tiny.fis:21: the output term 'down' is defined twice, at lines 20 and 21"),
    ("NumInputs=1", "NumInputs=2", r"tiny.fis:4: NumInputs=2, but the file has 1 input sections"),
    ("NumMFs=2\nMF1='low'", "NumMFs=3\nMF1='low'", r"tiny.fis:12: NumMFs=3, but \[Input1\] "
     r"has 2 MFs"),
    ("NumMFs=2\nMF1='down'", "NumMFs=1\nMF1='down'", r"tiny.fis:19: NumMFs=1, but \[Output1\] "
     r"has 2 MFs"),
    ("MF2='high'", "MF3='high'", r"tiny.fis:14: MF3 where MF2 should come"),
    ("MF1='down'", "MF2='down'", r"tiny.fis:20: MF2 where MF1 should come"),
    ("[Input1]", "[Input2]", r"tiny.fis:9: \[Input2\] where \[Input1\] should come"),
    ("NumOutputs=1", "NumOutputs=1\nNumRules=3", r"tiny.fis:6: NumRules=3, but the file has 2"),
    ("NumInputs=1", "NumInputs=one", r"tiny.fis:4: NumInputs=one is not a whole number"),
])
def test_counts_indices_and_names_must_match_the_file(old: str, new: str, message: str) -> None:
    text = SYSTEM.replace(old, new)
    assert text != SYSTEM
    with pytest.raises(ExportError, match=message):
        FisImporter().from_string(text, "tiny.fis")


def test_a_second_input_with_the_same_name_is_refused() -> None:
    text = FisExporter().to_string(load_behaviour(SHIPPED[0])).replace("Name='pan'",
                                                                       "Name='ball_size'")
    with pytest.raises(ExportError, match=r"the input 'ball_size' is defined twice, at lines "
                       r"\d+ and \d+"):
        FisImporter().from_string(text, "x.fis")


def _fis_quads(behaviour: Behaviour) -> list[list[tuple[float, ...]]]:
    return [[sloped_quad(q, v.range) for q in v.sets.values()]
            for v in behaviour.inputs.values()]


@pytest.mark.parametrize(("source", "activation"),
                         [*((s, "min") for s in [*ALL_SHIPPED, 3, 11, 12, 21]),
                          *((s, "product") for s in PRODUCT_SOURCES)],
                         ids=lambda s: getattr(s, "name", str(s)))
@pytest.mark.slow
def test_fuzzylite6_computes_the_same_outputs(source: object, activation: str,
                                              tmp_path: Path) -> None:
    """fuzzylite 6 reads the export and agrees within 1e-12 apart from its 1e-6 tolerance,
    20 % past the range's ends too: shoulders' feet lie a range width outside it. With
    activation: product, AndMethod='prod'."""
    behaviour = reference_controller(source, activation)
    states = random_states(behaviour, 10_000, seed=5)
    assert_fuzzylite_agrees(behaviour, FisExporter().to_string(behaviour), "fis", states,
                            _fis_quads(behaviour), tmp_path)


def test_no_mf_has_a_vertical_edge() -> None:
    """Octave's toolkit refuses trapmf with a == b and trimf with a == b or b == c."""
    for seed in range(20):
        for line in FisExporter().to_string(random_behaviour(seed)).splitlines():
            if "'trapmf'" in line or "'trimf'" in line:
                values = [float(v) for v in line.split("[")[1].rstrip("]").split()]
                assert all(a < b for a, b in itertools.pairwise(values)) or (
                    len(values) == 4 and values[0] < values[1] <= values[2] < values[3])


@pytest.mark.slow
@pytest.mark.parametrize(("source", "activation"),
                         [*((s, "min") for s in [*SHIPPED, 12]),
                          *((s, "product") for s in [SHIPPED[0], 12])], ids=str)
def test_octave_reads_and_agrees(source: object, activation: str, tmp_path: Path) -> None:
    """Optional: Octave's fuzzy-logic-toolkit (readfis / evalfis) reads the export and agrees
    within 1e-12 on states clipped to the ranges (evalfis refuses others); AndMethod='prod'
    as Octave's product."""
    behaviour = reference_controller(source, activation)
    controller = compile_behaviour(behaviour)
    states = np.clip(random_states(behaviour, 300, seed=5), controller.ranges[:, 0],
                     controller.ranges[:, 1])
    got = octave_outputs(FisExporter().to_string(behaviour), states, tmp_path)
    assert np.max(np.abs(got - controller.output(states))) <= 1e-12


def test_what_other_toolchains_write_imports_exactly() -> None:
    """MATLAB's shoulder feet outside the range, a zero-order linear output, fuzzylite's
    Enabled / Default / LockRange keys, and max aggregation where no rules share a term."""
    text = (SYSTEM.replace("[0 0 0.2 0.8]", "[-1 0 0.2 0.8]").replace("[0.2 1 1]", "[0.2 1 7]")
            .replace("'constant',[1]", "'linear',[0 1]")
            .replace("Name='x'", "Name='x'\nEnabled=1")
            .replace("Name='u'", "Name='u'\nDefault=nan\nLockPrevious=0\nLockRange=0")
            .replace("DefuzzMethod", "AggMethod='max'\nDefuzzMethod"))
    behaviour = FisImporter().from_string(text, "tiny.fis")
    assert behaviour.inputs["x"].sets == {"low": (0.0, 0.0, 0.2, 0.8),
                                          "high": (0.2, 1.0, 1.0, 1.0)}
    assert behaviour.output.commands == {"down": -1.0, "up": 1.0}


@pytest.mark.parametrize(("old", "new", "message"), [
    ("[0 0 0.2 0.8]", "[-1 0.5 0.6 0.8]", r"tiny.fis:13: set 'low' .* has a ramp that the "
     r"range's low end 0.0 cuts.*\(fix: move its first two points"),
    ("'constant',[1]", "'linear',[2 1]", r"tiny.fis:21: output term 'up' is first-order"),
    ("'constant',[1]", "'trimf',[0 1 2]", r"tiny.fis:21: output term 'up' is a trimf, a Mamdani "
     r"output set.*\(fix: import with --mamdani-singletons"),
    ("Name='x'", "Name='x'\nEnabled=0", r"tiny.fis:11: a disabled variable"),
    ("Name='x'", "Name='x'\nColour=1", r"tiny.fis:11: 'Colour' in an input section \(fix:"),
])
def test_refusals_of_other_toolchains_files_say_what_to_do(old: str, new: str,
                                                           message: str) -> None:
    with pytest.raises(ExportError, match=message):
        FisImporter().from_string(SYSTEM.replace(old, new), "tiny.fis")


TWO_OUTPUTS = (SYSTEM.replace("NumOutputs=1", "NumOutputs=2")
               .replace("[Rules]", "[Output2]\nName='v'\nRange=[0 2]\nNumMFs=2\n"
                        "MF1='slow':'constant',[0.5]\nMF2='fast':'constant',[2]\n\n[Rules]")
               .replace("1, 2 (1) : 1\n2, 1 (1) : 1", "1, 2 2 (1) : 1\n2, 1 0 (1) : 1\n"
                        "2, 0 1 (1) : 1"))


def test_several_outputs_import_as_one_behaviour_each(tmp_path: Path) -> None:
    """Each output keeps the rules that give it an MF (index 0 gives none), and fuzzylite 6
    computes each output of the file as the behaviour of that output does."""
    importer = FisImporter()
    with pytest.raises(ExportError, match=r"tiny.fis:1: the controller has 2 outputs"):
        importer.from_string(TWO_OUTPUTS, "tiny.fis")
    u, v = importer.from_string_all(TWO_OUTPUTS, "tiny.fis")
    assert (u.name, v.name) == ("u", "v")
    assert [(r.if_["x"], r.then) for r in u.rules] == [("low", "up"), ("high", "down")]
    assert [(r.if_["x"], r.then) for r in v.rules] == [("low", "fast"), ("high", "slow")]
    assert "2 outputs, imported as one behaviour each" in importer.report
    with pytest.raises(ExportError, match=r"tiny.fis:33: a rule weight of 0.5"):
        importer.from_string_all(TWO_OUTPUTS.replace("2, 0 1 (1)", "2, 0 1 (0.5)"), "tiny.fis")
    states = np.linspace(0.0, 1.0, 101)[:, None]
    got = fuzzylite_outputs_all(TWO_OUTPUTS, states, tmp_path)
    for k, behaviour in enumerate((u, v)):
        assert np.max(np.abs(got[:, k] - compile_behaviour(behaviour).output(states))) <= 1e-12


def fuzzylite_outputs_all(text: str, states: np.ndarray, folder: Path) -> np.ndarray:
    import subprocess

    from .engines import fuzzylite_binary

    (folder / "e.fis").write_text(text, encoding="utf-8")
    (folder / "s.fld").write_text("\n".join(repr(float(x)) for x in states[:, 0]) + "\n")
    result = subprocess.run([fuzzylite_binary(), "-i", str(folder / "e.fis"), "-if", "fis",
                             "-of", "fld", "-d", str(folder / "s.fld"), "-dheader", "false",
                             "-dinputs", "false", "-decimals", "17"],
                            capture_output=True, text=True, timeout=60, check=True)
    return np.array([[float(v) for v in line.split()] for line in result.stdout.splitlines()])
