"""The genetic learner: one learner, two operator sets, and the warm-start hook."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from flctool.errors import LearnError
from flctool.learners import make_learner, train
from flctool.learners.genetic import HYBRID, PITT, GeneticLearner
from flctool.runs import open_run
from tests.learners.line_env import LineEnv, line_behaviour

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
    for key, value in expected.items():
        if key == "selection":
            assert {k: resumed[key][k] for k in value} == value
        else:
            assert resumed[key] == value, key


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
