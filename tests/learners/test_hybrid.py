"""The hybrid learner: the GA guided by a q table learned during every trial."""

from __future__ import annotations

import numpy as np

from flctool.learners import make_learner, train
from flctool.learners.fuzzy_q import FuzzyQ
from flctool.learners.ga import GeneticAlgorithm
from flctool.learners.genetic import HybridLearner
from tests.learners.line_env import LineEnv, line_behaviour


def test_hybrid_is_composed_of_the_ga_and_fuzzy_q() -> None:
    learner = make_learner(line_behaviour(learner="hybrid"), LineEnv())
    assert isinstance(learner, HybridLearner)
    assert isinstance(learner.ga, GeneticAlgorithm)
    assert isinstance(learner.fuzzy_q, FuzzyQ)


def test_every_trial_updates_the_shared_q_table() -> None:
    env = LineEnv()
    learner = make_learner(line_behaviour(learner="hybrid", population=4), env)
    learner.population[:] = 2  # everyone says "up": every trial ends with +1
    learner.evaluate(0)
    assert env.resets == 4
    q = learner.fuzzy_q.table()
    assert (q[:, 2] > 0).any() and (q[:, :2] == 0).all()


def test_hybrid_learns_that_up_is_strongest() -> None:
    learner = make_learner(line_behaviour(learner="hybrid", generations=10, population=8),
                           LineEnv())
    history = train(learner)
    q = learner.strengths()
    assert int(np.argmax(q[2])) == 2  # high: up (in mid, "stay" next to "up" in high works too)
    assert history[-1].best == 1.0
    assert "q" in learner.state_dict() and "traces" in learner.state_dict()
