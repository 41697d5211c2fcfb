"""The Pitt learner: a GA on fitness alone, no strengths."""

from __future__ import annotations

import numpy as np

from flctool.learners import make_learner, train
from flctool.learners.genetic import PittLearner
from tests.learners.line_env import LineEnv, line_behaviour


def test_pitt_keeps_no_strengths_and_improves_on_the_line() -> None:
    learner = make_learner(line_behaviour(learner="pitt", generations=10, population=8),
                           LineEnv())
    assert isinstance(learner, PittLearner)
    history = train(learner)
    assert learner.strengths() is None
    assert "q" not in learner.state_dict()
    assert history[-1].best == 1.0
    assert max(m.mean for m in history[5:]) > history[0].mean


def test_initial_population_is_drawn_from_all_commands() -> None:
    learner = make_learner(line_behaviour(learner="pitt", population=50), LineEnv())
    assert learner.population.shape == (50, 3)
    assert set(np.unique(learner.population)) == {0, 1, 2}


def test_common_starts_give_every_individual_the_same_episode() -> None:
    learner = make_learner(line_behaviour(learner="pitt", population=6, common_starts=True,
                                          trials=2), LineEnv())
    learner.population[:] = learner.population[0]  # identical controllers
    result = learner.evaluate(0)
    assert result.episodes == 12
    assert np.all(learner.fitness == learner.fitness[0])
