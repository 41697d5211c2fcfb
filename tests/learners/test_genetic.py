"""The genetic learner: one learner, two operator sets, and the warm-start hook."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from flctool.errors import LearnError
from flctool.learners import make_learner, train
from flctool.learners.ga import greedy_controller
from flctool.learners.genetic import HYBRID, PITT, GeneticLearner
from flctool.runs import open_run
from tests.learners.line_env import LineEnv, cut_and_resumed, line_behaviour

EARLIER_RUNS = Path(__file__).parent / "earlier_runs"


@pytest.mark.parametrize(("name", "operators"), [("pitt", PITT), ("hybrid", HYBRID)])
def test_pitt_and_hybrid_are_the_genetic_learner_with_their_operator_sets(
        name: str, operators: object) -> None:
    learner = make_learner(line_behaviour(learner=name), LineEnv())
    assert isinstance(learner, GeneticLearner) and learner.operator_set is operators
    assert (learner.fuzzy_q is not None) == (name == "hybrid") == learner.uses_strengths


@pytest.mark.parametrize("name", ["pitt", "hybrid"])
def test_a_run_directory_of_an_earlier_version_resumes_bit_for_bit(name: str,
                                                                    tmp_path: Path) -> None:
    # Written before pitt and hybrid became one learner and selection a run callback: two
    # generations of a run, and its generation 3 when that version resumed it to 4 (its
    # population, fitness, generator states and q table those of the run uninterrupted).
    copy = tmp_path / name
    shutil.copytree(EARLIER_RUNS / name, copy)
    run = open_run(copy)
    run.extend(4)
    run.train()
    resumed = run.checkpoint(3)
    expected = json.loads((EARLIER_RUNS / f"{name}-generation-3.json").read_text())
    # what that version recorded; this one records more (confirmation, validated success)
    assert_holds(resumed, expected)


def assert_holds(actual: object, expected: object, where: str = "checkpoint") -> None:
    """``actual`` holds ``expected``: equal, except that dicts may hold more keys and that
    validation intervals are now clipped to the possible fitness (their mean and count are
    the same)."""
    if where.endswith(".validation") and isinstance(expected, list):
        assert isinstance(actual, list)
        expected, actual = [expected[0], expected[3]], [actual[0], actual[3]]
    if where.endswith((".validation.low", ".validation.high")):
        return
    if isinstance(expected, dict):
        assert isinstance(actual, dict), where
        for key, value in expected.items():
            assert_holds(actual[key], value, f"{where}.{key}")
    elif isinstance(expected, list):
        assert isinstance(actual, list) and len(actual) == len(expected), where
        for i, (a, e) in enumerate(zip(actual, expected, strict=True)):
            assert_holds(a, e, f"{where}[{i}]")
    else:
        assert actual == expected, where


def test_a_warm_start_sets_the_first_generation_and_the_q_table() -> None:
    learner = make_learner(line_behaviour(learner="hybrid"), LineEnv())
    population = np.zeros_like(learner.population)
    q = np.full((learner.controller.n_rules, learner.controller.n_commands), 0.25)
    learner.start_from(population, q)
    assert learner.population.tolist() == population.tolist()
    assert learner.strengths() is not None and (learner.strengths() == 0.25).all()
    train(learner)
    with pytest.raises(LearnError, match="before its first generation"):
        learner.start_from(population)


def test_a_warm_start_that_does_not_fit_is_refused() -> None:
    pitt = make_learner(line_behaviour(learner="pitt"), LineEnv())
    with pytest.raises(LearnError, match="command indices"):
        pitt.start_from(np.full_like(pitt.population, pitt.controller.n_commands))
    with pytest.raises(LearnError, match="must be"):
        pitt.start_from(pitt.population[:1])
    with pytest.raises(LearnError, match="keeps no rule strengths"):
        pitt.start_from(strengths=np.zeros((pitt.controller.n_rules, 2)))
    fuzzy = make_learner(line_behaviour(learner="fuzzy_q"), LineEnv())
    with pytest.raises(LearnError, match="not a population"):
        fuzzy.start_from(fuzzy.population)
    table = np.zeros((fuzzy.controller.n_rules, fuzzy.controller.n_commands))
    table[:, -1] = 1.0
    fuzzy.start_from(strengths=table)
    assert (fuzzy.population == fuzzy.controller.n_commands - 1).all()


@pytest.mark.slow
def test_a_stalled_run_restarts_all_but_its_elites_and_resumes_bit_for_bit() -> None:
    behaviour = line_behaviour(learner="hybrid", generations=12, restart_after=2)
    learner = make_learner(behaviour, LineEnv())
    train(learner)
    assert isinstance(learner, GeneticLearner) and learner.restarts >= 1
    state = json.loads(json.dumps(learner.state_dict()))
    assert state["restarts"]["restarts"] == learner.restarts
    # cut after generation 4, resumed from the checkpoint: the same run
    second, _ = cut_and_resumed(behaviour, after=4)
    assert second.state_dict()["population"] == state["population"]
    assert second.state_dict()["restarts"] == state["restarts"]


def test_without_restarts_the_paper_s_ga_is_unchanged() -> None:
    never = make_learner(line_behaviour(learner="pitt", generations=12, restart_after=0),
                         LineEnv())
    train(never)
    assert isinstance(never, GeneticLearner) and never.restarts == 0


def test_the_greedy_controller_takes_each_rule_s_strongest_command_keeping_ties_to_the_leader(
        ) -> None:
    strengths = np.array([[0.0, 2.0, 1.0],   # one strongest: 1
                          [0.0, 0.0, 0.0],   # never fired: every command ties, leader's kept
                          [3.0, 1.0, 3.0]])  # a tie the leader is not in: the first strongest
    leader = np.array([2, 1, 1])
    assert greedy_controller(strengths, leader).tolist() == [1, 1, 0]


def test_every_bred_hybrid_generation_holds_the_q_table_s_greedy_controller() -> None:
    learner = make_learner(line_behaviour(learner="hybrid", generations=1, population=6),
                           LineEnv())
    assert isinstance(learner, GeneticLearner) and learner.greedy_individual
    learner.evaluate(0)
    leader = learner.population[int(np.argmax(learner.fitness))].copy()
    assert learner.fuzzy_q is not None
    expected = greedy_controller(learner.fuzzy_q.table(), leader)
    learner.advance()
    assert learner.population[-1].tolist() == expected.tolist()


def test_without_the_greedy_individual_the_hybrid_is_the_paper_s() -> None:
    behaviour = line_behaviour(learner="hybrid", generations=6, greedy_individual=False)
    paper = make_learner(behaviour, LineEnv())
    assert isinstance(paper, GeneticLearner) and not paper.greedy_individual
    train(paper)
    assert "greedy_individual" in paper.state_dict()
    again = make_learner(behaviour, LineEnv())
    train(again)
    assert again.state_dict()["population"] == paper.state_dict()["population"]


def test_a_run_with_the_greedy_individual_resumes_bit_for_bit() -> None:
    behaviour = line_behaviour(learner="hybrid", generations=8)
    whole = make_learner(behaviour, LineEnv())
    train(whole)
    second, _ = cut_and_resumed(behaviour, after=3)
    assert second.state_dict()["population"] == whole.state_dict()["population"]
    assert second.state_dict()["q"] == whole.state_dict()["q"]
