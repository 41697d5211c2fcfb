"""The paper's figures from real run directories and traces."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from flctool import load_behaviour
from flctool.cli import app
from flctool.errors import MissingDependencyError, RunDirError, SpecError
from flctool.plots import (
    most_contested_rule,
    plot_fitness,
    plot_strengths,
    plot_trajectory,
    read_trace,
    strength_history,
)
from flctool.runs import Run, create_run, resolve_behaviour

from .conftest import BEHAVIOURS

PNG = b"\x89PNG\r\n\x1a\n"
runner = CliRunner()


def _run(tmp_path: Path, learner: str, name: str) -> Run:
    behaviour = resolve_behaviour(load_behaviour(BEHAVIOURS / "ballchase.yaml"),
                                  {"learner": learner, "generations": 3, "population": 4})
    run = create_run(behaviour, tmp_path / name)
    run.train()
    return run


def test_fitness_and_strengths_of_a_run(tmp_path: Path) -> None:
    run = _run(tmp_path, "hybrid", "hybrid")
    plot_fitness([run], tmp_path / "fitness.png")
    assert (tmp_path / "fitness.png").read_bytes().startswith(PNG)
    generations, q = strength_history(run)
    assert generations.tolist() == [0, 1, 2] and q.shape == (3, 15, 5)
    plotted = plot_strengths(run, tmp_path / "strengths.png")
    assert plotted == most_contested_rule(q)
    assert (tmp_path / "strengths.png").read_bytes().startswith(PNG)
    with pytest.raises(RunDirError, match=r"rule 15 does not exist: .* rules 0\.\.14"):
        plot_strengths(run, tmp_path / "bad.png", rule=15)


def test_most_contested_rule_is_the_one_whose_strengths_moved() -> None:
    q = np.zeros((4, 3, 2))
    q[:, 2, 1] = [0.0, 0.5, 1.0, 0.2]
    q[:, 0, 0] = [0.1, 0.1, 0.1, 0.1]  # large but constant
    assert most_contested_rule(q) == 2


def test_pitt_keeps_no_strengths(tmp_path: Path) -> None:
    run = _run(tmp_path, "pitt", "pitt")
    with pytest.raises(RunDirError, match="the pitt learner keeps no rule strengths"):
        strength_history(run)


def test_trajectory_from_an_evaluate_trace(tmp_path: Path) -> None:
    trace = tmp_path / "trace.csv"
    result = runner.invoke(app, ["evaluate", str(BEHAVIOURS / "ballchase-handmade.yaml"),
                                 "--episodes", "1", "--trace", str(trace)])
    assert result.exit_code == 0, result.output
    columns = read_trace(trace)
    assert len(columns["robot_x"]) > 1
    plot_trajectory(columns, tmp_path / "trajectory.png", "chase")
    assert (tmp_path / "trajectory.png").read_bytes().startswith(PNG)


def test_a_file_that_is_not_a_trace(tmp_path: Path) -> None:
    other = tmp_path / "states.csv"
    other.write_text("ball_size,pan\n0.1,2\n")
    with pytest.raises(SpecError, match="not a ballchase trace: no column"):
        read_trace(other)


def test_missing_matplotlib_gives_the_install_hint(tmp_path: Path,
                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    with pytest.raises(MissingDependencyError) as info:
        plot_trajectory({"robot_x": np.zeros(2), "robot_y": np.zeros(2),
                         "ball_x": np.zeros(2), "ball_y": np.zeros(2)}, tmp_path / "t.png", "t")
    assert info.value.hint == "pip install 'flctool[plot]'"
    assert not (tmp_path / "t.png").exists()


def test_plot_command(tmp_path: Path) -> None:
    hybrid = _run(tmp_path, "hybrid", "hybrid")
    pitt = _run(tmp_path, "pitt", "pitt")
    result = runner.invoke(app, ["plot", str(hybrid.path), "--rule", "7"])
    assert result.exit_code == 0, result.output
    assert "(rule 7)" in result.output
    assert (hybrid.path / "fitness.png").is_file() and (hybrid.path / "strengths.png").is_file()
    out = tmp_path / "compare"
    result = runner.invoke(app, ["plot", str(hybrid.path), str(pitt.path), "-o", str(out)])
    assert result.exit_code == 0, result.output
    assert (out / "fitness.png").is_file() and not (out / "strengths.png").exists()
    result = runner.invoke(app, ["plot", str(pitt.path), "--rule", "3"])
    assert result.exit_code == 1
    assert "--rule picks the rule of one run" in result.output
