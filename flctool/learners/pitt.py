"""The Pitt approach (paper Sec. IV, the first method): a plain GA over whole controllers.

No rule strengths and no temporal credit assignment: fitness from the trials is all it learns
from. Operators are documented in :mod:`flctool.learners.ga`; crossover is uniform or
one-point (``learning.pitt_crossover``), mutation draws a command uniformly.
"""

from __future__ import annotations

from functools import partial
from typing import ClassVar

import numpy as np

from flctool.envs.base import BatchEnv
from flctool.learners.base import GenerationResult, Learner
from flctool.learners.ga import (
    GeneticAlgorithm,
    evaluate_population,
    one_point_crossover,
    random_population,
    uniform_crossover,
    uniform_mutation,
)
from flctool.spec.learning import PittConfig
from flctool.spec.models import Behaviour


class PittLearner(Learner):
    """A population of controllers evolved by fitness alone."""

    name: ClassVar[str] = "pitt"
    config: PittConfig

    def __init__(self, behaviour: Behaviour, env: BatchEnv) -> None:
        super().__init__(behaviour, env)
        config = self.config
        self.ga = GeneticAlgorithm(config.crossover, config.elites)
        self.crossover = (uniform_crossover if config.pitt_crossover == "uniform"
                          else one_point_crossover)
        self.mutation = partial(uniform_mutation, rate=config.mutation,
                                n_commands=self.controller.n_commands)
        self.population = self.keep_fixed(random_population(
            self.rngs["ga"], config.population, self.controller.n_rules,
            self.controller.n_commands))
        self.fitness = np.zeros(config.population)

    def elite_count(self) -> int:
        return max(1, self.config.elites)

    def evaluate(self, generation: int) -> GenerationResult:
        config = self.config
        seeds = self.episode_seeds(config.population, config.trials, config.common_starts)
        self.fitness, steps = evaluate_population(self.env, self.rules, self.population, seeds)
        return GenerationResult(self.fitness, seeds.size, steps)

    def advance(self) -> None:
        # Given rules are fixed: whatever crossover and mutation did to them is undone.
        self.population = self.keep_fixed(self.ga.breed(
            self.rngs["ga"], self.population, self.fitness, self.crossover, self.mutation))
