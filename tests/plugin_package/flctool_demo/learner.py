"""Random search: every generation draws new controllers and keeps the best ``keep``."""

import numpy as np

from flctool.learners.base import GenerationResult, Learner
from flctool.learners.ga import evaluate_population, random_population
from flctool_demo import RandomSearchConfig


class RandomSearchLearner(Learner):
    name = "random_search"
    config: RandomSearchConfig  # the model its entry names: learning.keep is typed

    def __init__(self, behaviour, env):  # type: ignore[no-untyped-def]
        super().__init__(behaviour, env)
        self.population = self.keep_fixed(self._draw(self.config.population))
        self.fitness = np.zeros(self.config.population)

    def _draw(self, count: int):  # type: ignore[no-untyped-def]
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
