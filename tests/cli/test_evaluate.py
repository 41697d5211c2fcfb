"""``flctool evaluate`` as a user runs it."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from flctool import load_behaviour, with_rules
from flctool.behaviour import behaviour_to_yaml
from flctool.cli import app
from flctool.rollout import evaluation_seeds

from ..conftest import BEHAVIOURS

runner = CliRunner()
HANDMADE = str(BEHAVIOURS / "ballchase-handmade.yaml")


def test_table_of_statistics() -> None:
    result = runner.invoke(app, ["evaluate", HANDMADE, "--episodes", "50"])
    assert result.exit_code == 0, result.output
    for label in ("success rate (Wilson)", "steps to success", "mean fitness", "95 % CI"):
        assert label in result.output


def test_json_is_reproducible() -> None:
    first = runner.invoke(app, ["evaluate", HANDMADE, "--episodes", "30", "--seed", "4",
                                "--json"])
    second = runner.invoke(app, ["evaluate", HANDMADE, "--episodes", "30", "--seed", "4",
                                 "--json"])
    assert first.exit_code == 0, first.output
    data = json.loads(first.stdout)
    assert data == json.loads(second.stdout)
    assert data["episodes"] == 30 and data["seed"] == 4
    assert 0.0 <= data["success_rate"]["low"] <= data["success_rate"]["value"] <= 1.0


def test_trace_csv(tmp_path: Path) -> None:
    trace = tmp_path / "trace.csv"
    result = runner.invoke(app, ["evaluate", HANDMADE, "--episodes", "5", "--trace",
                                 str(trace)])
    assert result.exit_code == 0, result.output
    with trace.open() as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) >= 2
    assert {"step", "robot_x", "robot_y", "robot_heading", "ball_x", "ball_y", "ball_size",
            "pan", "turn", "command"} <= set(rows[0])
    assert rows[0]["step"] == "0" and rows[-1]["command"] == ""


def test_trace_creates_its_folder_and_is_replaced_only_with_force(tmp_path: Path) -> None:
    trace = tmp_path / "nowhere" / "trace.csv"
    first = runner.invoke(app, ["evaluate", HANDMADE, "--episodes", "2", "--trace", str(trace)])
    assert first.exit_code == 0, first.output
    again = runner.invoke(app, ["evaluate", HANDMADE, "--episodes", "2", "--trace", str(trace)])
    assert again.exit_code == 1 and "already exists" in again.output
    forced = runner.invoke(app, ["evaluate", HANDMADE, "--episodes", "2", "--trace", str(trace),
                                 "--force"])
    assert forced.exit_code == 0, forced.output


def test_non_deployable_controller_lists_missing_rules() -> None:
    result = runner.invoke(app, ["evaluate", str(BEHAVIOURS / "ballchase.yaml")])
    assert result.exit_code == 1
    assert "15 of 15 rules have no consequent" in result.output
    assert "Traceback" not in result.output


def test_bad_environment_exits_cleanly(tmp_path: Path) -> None:
    text = Path(HANDMADE).read_text().replace(
        "  adapter: ballchase-sim", "  adapter: ballchase-sim\n  pitch: {length: 900}")
    path = tmp_path / "small.yaml"
    path.write_text(text)
    result = runner.invoke(app, ["evaluate", str(path)])
    assert result.exit_code == 1
    assert "environment.pitch" in result.output and "too small" in result.output


def test_an_environment_error_points_at_the_line_of_the_file(tmp_path: Path) -> None:
    cartpole = load_behaviour(BEHAVIOURS / "cartpole.yaml")
    deployable = with_rules(cartpole, np.zeros(cartpole.rule_count, dtype=np.intp))
    text = behaviour_to_yaml(deployable).replace("id: CartPole-v1", "id: CartPol-v1")
    file = tmp_path / "cartpole.yaml"
    file.write_text(text, encoding="utf-8")
    line = next(n for n, row in enumerate(text.splitlines(), 1) if "CartPol-v1" in row)
    result = runner.invoke(app, ["evaluate", str(file), "--episodes", "2"])
    assert result.exit_code == 1
    assert f"{file}:{line}:" in result.stderr
    assert "environment.id: Gymnasium cannot make 'CartPol-v1'" in " ".join(
        result.stderr.split())


@pytest.mark.slow
def test_evaluate_on_chosen_seeds_lists_them_in_json() -> None:
    result = runner.invoke(app, ["evaluate", HANDMADE, "--seeds", "1,2,5-9", "--json"])
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    assert data["seeds"] == [1, 2, 5, 6, 7, 8, 9] and data["episodes"] == 7
    assert data["seed"] is None
    drawn = json.loads(runner.invoke(app, ["evaluate", HANDMADE, "--episodes", "4", "--json"]
                                     ).stdout)
    assert drawn["seeds"] == evaluation_seeds(0, 4).tolist() and drawn["seed"] == 0


def test_seeds_and_seed_exclude_each_other() -> None:
    result = runner.invoke(app, ["evaluate", HANDMADE, "--seeds", "1", "--seed", "2"])
    assert result.exit_code == 2 and "give either --seeds, or --seed and --episodes" in (
        result.output)
    bad = runner.invoke(app, ["evaluate", HANDMADE, "--seeds", "a-b"])
    assert bad.exit_code == 2 and "--seeds" in bad.output


def test_no_outcome_lines_for_success_the_environment_does_not_define(tmp_path: Path) -> None:
    cartpole = load_behaviour(BEHAVIOURS / "cartpole.yaml")
    deployable = with_rules(cartpole, np.zeros(cartpole.rule_count, dtype=np.intp))
    text = behaviour_to_yaml(deployable).replace("id: CartPole-v1",
                                                 "id: CartPole-v1\n  success: never")
    text = text.replace("  success: truncated\n", "")
    file = tmp_path / "cartpole.yaml"
    file.write_text(text, encoding="utf-8")
    result = runner.invoke(app, ["evaluate", str(file), "--episodes", "3"])
    assert result.exit_code == 0, result.output
    assert "mean return" in result.output and "success" not in result.output
    data = json.loads(runner.invoke(app, ["evaluate", str(file), "--episodes", "3", "--json"]
                                    ).stdout)
    assert "success_rate" not in data and "mean_return" in data
