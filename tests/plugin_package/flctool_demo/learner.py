"""Random search: every generation draws new controllers and keeps the best ``keep``."""

from __future__ import annotations

from typing import Any

import numpy as np

from flctool.behaviour import Behaviour
from flctool.envs.base import BatchEnv
from flctool.learners.base import GenerationResult, IntArray, Learner
from flctool.learners.ga import evaluate_population, random_population
from flctool_demo import RandomSearchConfig


class RandomSearchLearner(Learner):
    name = "random_search"
    config: RandomSearchConfig  # the model its entry names: learning.keep is typed

    def __init__(self, behaviour: Behaviour, env: BatchEnv) -> None:
        super().__init__(behaviour, env)
        self.drawn = 0  # controllers drawn so far: learner state a checkpoint must keep
        self.population = self.keep_fixed(self._draw(self.config.population))
        self.fitness = np.zeros(self.config.population)

    def _draw(self, count: int) -> IntArray:
        self.drawn += count
        return random_population(self.rngs["ga"], count, self.controller.n_rules,
                                 self.controller.n_commands)

    def evaluate(self, generation: int) -> GenerationResult:
        seeds = self.episode_seeds(self.config.population, self.config.trials, False)
        self.fitness, steps = evaluate_population(self.env, self.rules, self.population, seeds)
        return GenerationResult(self.fitness, seeds.size, steps)

    def advance(self) -> None:
        keep = self.config.keep
        best = self.population[np.argsort(-self.fitness, kind="stable")[:keep]]
        fresh = self._draw(self.config.population - keep)
        self.population = self.keep_fixed(np.concatenate([best, fresh]))

    # The checkpoint holds the population, its fitness and every random stream already;
    # anything else the learner keeps goes here (JSON-compatible), so a resumed run
    # continues bit for bit.
    def extra_state(self) -> dict[str, Any]:
        return {"drawn": self.drawn}

    def load_extra_state(self, state: dict[str, Any]) -> None:
        self.drawn = int(state["drawn"])
