"""The paper's method (Sec. III-IV): the GA of Pitt guided by fuzzy-Q rule strengths.

Composed of the two other learners' parts, not a copy of either: the population is bred by
:class:`~flctool.learners.ga.GeneticAlgorithm` with strength-guided crossover and Boltzmann
mutation, and one q table (:class:`~flctool.learners.fuzzy_q.FuzzyQ`), shared by the whole
population, learns by eq. 4-9 during every trial -- trial after trial, so each trial starts
from what the previous ones taught (summing the updates of simultaneous episodes instead
measurably lowered results in a prototype). Every individual acts with its own fixed
consequents; q only guides breeding.
"""

from __future__ import annotations

from functools import partial
from typing import ClassVar

import numpy as np

from flctool.envs.base import BatchEnv
from flctool.learners.base import GenerationResult, Learner
from flctool.learners.fuzzy_q import FuzzyQ, new_fuzzy_q
from flctool.learners.ga import (
    GeneticAlgorithm,
    boltzmann_mutation,
    evaluate_population,
    random_population,
    strength_crossover,
)
from flctool.spec.learning import HybridConfig
from flctool.spec.models import Behaviour


class HybridLearner(Learner):
    """GA exploration of whole controllers + Q-learning credit assignment to single rules."""

    name: ClassVar[str] = "hybrid"
    config: HybridConfig
    fuzzy_q: FuzzyQ

    def __init__(self, behaviour: Behaviour, env: BatchEnv) -> None:
        super().__init__(behaviour, env)
        config = self.config
        n_rules, n_commands = self.controller.n_rules, self.controller.n_commands
        self.ga = GeneticAlgorithm(config.crossover, config.elites)
        self.fuzzy_q = new_fuzzy_q(config.q, n_rules, n_commands)
        self.population = self.keep_fixed(random_population(
            self.rngs["ga"], config.population, n_rules, n_commands))
        self.fitness = np.zeros(config.population)

    def elite_count(self) -> int:
        return max(1, self.config.elites)

    def evaluate(self, generation: int) -> GenerationResult:
        config = self.config
        seeds = self.episode_seeds(config.population, config.trials, config.common_starts)
        self.fitness, steps = evaluate_population(self.env, self.rules, self.population, seeds,
                                                  td=self.fuzzy_q)
        return GenerationResult(self.fitness, seeds.size, steps)

    def advance(self) -> None:
        strengths = self.fuzzy_q.table()
        # Given rules are fixed: whatever crossover and mutation did to them is undone.
        self.population = self.keep_fixed(self.ga.breed(
            self.rngs["ga"], self.population, self.fitness,
            partial(strength_crossover, strengths=strengths),
            partial(boltzmann_mutation, rate=self.config.mutation, strengths=strengths,
                    temperature=self.config.q.temperature)))
