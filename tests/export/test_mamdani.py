"""Mamdani outputs as singletons: only on request, and with the error measured; the Mamdani
output the measurement uses is fuzzylite 6's."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from flctool.cli import app
from flctool.errors import ExportError
from flctool.export.fis import FisImporter
from flctool.export.mamdani import centroid, mamdani_outputs

from .engines import fuzzylite_outputs

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
    with pytest.raises(ExportError, match=r"mam.fis:31: output term 'left' is a trimf, a "
                       r"Mamdani output set.*\(fix: import with --mamdani-singletons"):
        FisImporter().from_string(MAMDANI, "mam.fis")


def test_the_conversion_reports_its_largest_error() -> None:
    importer = FisImporter(mamdani_singletons=True)
    behaviour = importer.from_string(MAMDANI, "mam.fis")
    assert behaviour.output.commands == {n: centroid(q) for n, q in SETS.items()}
    assert "largest difference from the Mamdani output (centroid over 100 midpoints" in \
        importer.report
    deviation = float(importer.report.split(") is ")[1].split()[0])
    assert 0.01 < deviation < 0.1  # measured 0.0444: a real, stated approximation


@pytest.mark.parametrize("setting", ["ImpMethod='prod'", "AggMethod='sum'",
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
    got = mamdani_outputs(behaviour, SETS, states, (-1.0, 1.0), 100)
    assert np.max(np.abs(got - want)) <= 1e-12


def test_the_cli_option(tmp_path: Path) -> None:
    path = tmp_path / "mam.fis"
    path.write_text(MAMDANI, encoding="utf-8")
    result = CliRunner().invoke(app, ["import", str(path), "--mamdani-singletons",
                                      "-o", str(tmp_path / "mam.yaml")])
    assert result.exit_code == 0, result.output
    assert "largest difference from the Mamdani output" in result.output
    assert CliRunner().invoke(app, ["import", str(path)]).exit_code != 0
