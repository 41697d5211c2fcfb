"""Warm start: a run begun around a controller learned elsewhere, rules and commands matched
by name, q values carried over."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from flctool.behaviour import behaviour_from_data, behaviour_to_data, load_behaviour
from flctool.cli import app
from flctool.compile.rules import rule_consequents
from flctool.errors import LearnError
from flctool.runs import open_run
from flctool.training import start_run
from flctool.warm_start import command_map, rule_map, seeded_population, warm_start_from_path

from .conftest import BEHAVIOURS

runner = CliRunner()
SMALL = ["-g", "2", "-p", "4", "--set", "selection.candidates=2", "--set",
         "selection.episodes=3"]


def test_rules_and_commands_are_matched_by_name() -> None:
    source = load_behaviour(BEHAVIOURS / "ballchase-handmade.yaml")
    data = behaviour_to_data(source)
    # pan's sets in another order, a command renamed, ball_size's last set renamed
    pan = data["inputs"]["pan"]["sets"]
    data["inputs"]["pan"]["sets"] = dict(reversed(list(pan.items())))
    data["inputs"]["ball_size"]["sets"]["huge"] = data["inputs"]["ball_size"]["sets"].pop("large")
    data["output"]["commands"]["spin_left"] = data["output"]["commands"].pop("turn_left")
    data["rules"] = []
    del data["environment"]  # the simulator's motion table names the commands
    target = behaviour_from_data(data)
    rules = rule_map(target, source)
    assert rules[0] == 4  # (small, far_left) is the source's rule 4: small x 5th pan set
    assert rules[5:10] == [9, 8, 7, 6, 5]  # medium, pan reversed
    assert rules[10:] == [None] * 5  # no 'huge' in the source
    assert command_map(target, source) == [0, 1, 2, 3, None]


def test_a_seeded_population_is_the_controller_then_mutants_of_it() -> None:
    genes = np.array([0, 1, 2, 3, 4, 0])
    known = np.array([True] * 5 + [False])
    rng = np.random.default_rng(0)
    population = seeded_population(genes, known, 10, 5, 0.1, rng)
    assert population.shape == (10, 6)
    assert (population[0, :5] == genes[:5]).all()
    assert 0 < (population[1:, :5] != genes[:5]).mean() < 0.2  # about 10 % redrawn


@pytest.mark.slow
def test_a_run_starts_around_a_learned_controller_with_its_q_values(tmp_path: Path) -> None:
    source = tmp_path / "sim"
    assert runner.invoke(app, ["learn", str(BEHAVIOURS / "ballchase.yaml"), *SMALL, "-o",
                               str(source)]).exit_code == 0
    best = rule_consequents(load_behaviour(source / "best.yaml"))
    run = open_run(source)
    q = np.array(run.checkpoint(run.checkpoint_generations()[-1])["q"])
    with start_run(BEHAVIOURS / "ballchase.yaml", {"population": 4},
                   tmp_path / "warm") as training:
        started = warm_start_from_path(training.learner, training.run.behaviour, source)
        learner = training.learner
        assert started.rules_matched == 15 and started.q_values == 75
        assert learner.population[0].tolist() == best  # type: ignore[attr-defined]
        assert np.array_equal(learner.fuzzy_q.table(), q)  # type: ignore[union-attr]

    result = runner.invoke(app, ["learn", str(BEHAVIOURS / "ballchase.yaml"), *SMALL, "-o",
                                 str(tmp_path / "cli"), "--init", str(source), "--json"])
    assert result.exit_code == 0, result.output
    assert f"warm start from {source}: 15 of 15 rules matched, 75 q values" in result.output
    again = runner.invoke(app, ["learn", str(BEHAVIOURS / "ballchase.yaml"), *SMALL, "-o",
                                str(tmp_path / "again"), "--init", str(source), "--json"])
    first = (tmp_path / "cli" / "metrics.csv").read_text().splitlines()
    second = (tmp_path / "again" / "metrics.csv").read_text().splitlines()
    drop = first[0].split(",").index("wall_time")
    assert [r.split(",")[:drop] for r in first] == [r.split(",")[:drop] for r in second]
    assert json.loads(again.output[again.output.index("{"):])["status"] == "finished"


def test_init_is_refused_with_resume_and_from_a_controller_that_does_not_match(
        tmp_path: Path) -> None:
    resumed = runner.invoke(app, ["learn", "--resume", str(tmp_path), "--init",
                                  str(BEHAVIOURS / "ballchase-handmade.yaml")])
    assert resumed.exit_code == 1 and "--init starts a new run" in resumed.output
    with start_run(BEHAVIOURS / "ballchase.yaml", {"population": 4},
                   tmp_path / "other") as training, pytest.raises(LearnError,
                                                                  match="no rule of"):
        warm_start_from_path(training.learner, training.run.behaviour,
                             BEHAVIOURS / "face-goal-handmade.yaml")


def test_the_credit_learner_starts_from_tables_around_the_controller(tmp_path: Path) -> None:
    """Its first generation's tables must differ for the episodes to credit anything: the
    controller, then tables with about 10 % of its commands redrawn."""
    source = BEHAVIOURS / "ballchase-handmade.yaml"
    handmade = rule_consequents(load_behaviour(source))
    with start_run(BEHAVIOURS / "ballchase.yaml", {"learner": "credit", "population": 20,
                                                   "generations": 1}, tmp_path / "run") as training:
        warm_start_from_path(training.learner, training.run.behaviour, source)
        first = training.learner.population
        assert first.shape == (20, 15) and first[0].tolist() == handmade
        assert 0 < (first[1:] != np.array(handmade)).mean() < 0.2
