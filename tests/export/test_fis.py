"""FIS: MATLAB's Sugeno text, and the import's subset."""

from __future__ import annotations

import pytest

from flctool import load_behaviour
from flctool.errors import ExportError
from flctool.export.fis import FisExporter, FisImporter

from .roundtrip import SHIPPED


def test_the_system_computes_eq_3() -> None:
    text = FisExporter().to_string(load_behaviour(SHIPPED[0]))
    for line in ("Type='sugeno'", "AndMethod='min'", "DefuzzMethod='wtaver'",
                 "MF1='small':'trapmf',[0.0 0.0 0.1 0.3]", "MF2='right':'trimf',[-60.0 -30.0 0.0]",
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
     r"tiny.fis:21: output membership function 'up' is a linear"),
    ("MF2='high':'trimf',[0.2 1 1]", "MF2='high':'gaussmf',[0.1 1]",
     r"tiny.fis:14: membership function 'high' is a gaussmf"),
    ("1, 2 (1) : 1", "1, 2 (0.5) : 1", r"tiny.fis:24: a rule weight of 0.5"),
    ("1, 2 (1) : 1", "-1, 2 (1) : 1", r"tiny.fis:24: NOT"),
    ("1, 2 (1) : 1", "0, 2 (1) : 1", r"tiny.fis:24: the rule leaves out input 'x'"),
    ("NumOutputs=1", "NumOutputs=2", r"tiny.fis:5: NumOutputs=2"),
    ("DefuzzMethod='wtaver'", "DefuzzMethod='wtsum'", r"tiny.fis:7: DefuzzMethod='wtsum'"),
    ("1, 2 (1) : 1", "1, 3 (1) : 1", r"tiny.fis:24: the output has no MF3"),
    ("1, 2 (1) : 1", "1, 2 (1) : 2", None),  # OR with a single input is the same rule
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
    with pytest.raises(ExportError, match=r"an OR rule \(connection 2\)"):
        FisImporter().from_string(text, "x.fis")


def test_duplicate_antecedents_are_refused_with_both_lines() -> None:
    text = SYSTEM.replace("2, 1 (1) : 1", "1, 1 (1) : 1")
    with pytest.raises(ExportError, match=r"tiny.fis:25: the rule repeats the antecedent of the "
                       r"rule at line 24"):
        FisImporter().from_string(text, "tiny.fis")


def test_invalid_names_are_located() -> None:
    from flctool.errors import SpecError

    with pytest.raises(SpecError, match=r"tiny.fis:10:1: inputs.*'x y' is not a valid name"):
        FisImporter().from_string(SYSTEM.replace("Name='x'", "Name='x y'"), "tiny.fis")
