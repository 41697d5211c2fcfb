"""The genetic learner of paper Sec. IV, with its two operator sets: ``pitt`` and ``hybrid``.

Both evolve a population of whole controllers by :class:`~flctool.learners.ga.
GeneticAlgorithm` (elitism, roulette selection, crossover, mutation); they differ only in
their operators and in whether rule strengths learn during the trials:

- **pitt** (the Pitt approach): no rule strengths, fitness from the trials is all it learns
  from; crossover is uniform or one-point (``learning.pitt_crossover``), mutation draws a
  command uniformly.
- **hybrid** (the paper's method, Sec. III-IV): one q table
  (:class:`~flctool.learners.fuzzy_q.FuzzyQ`), shared by the whole population, learns by eq.
  4-9 during every trial -- trial after trial, so each trial starts from what the previous
  ones taught (summing the updates of simultaneous episodes instead measurably lowered
  results in a prototype). Every individual acts with its own fixed consequents; q only
  guides breeding: strength-guided crossover and Boltzmann mutation.

The genome is handled here and only here: :meth:`GeneticLearner.initial_population` makes
the first generation (or takes the one :meth:`~flctool.learners.base.Learner.start_from`
gave), :meth:`GeneticLearner.advance` breeds, and rules the file gives are put back after
every operator (:meth:`~flctool.learners.base.Learner.keep_fixed`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from typing import ClassVar

import numpy as np

from flctool.envs.base import BatchEnv
from flctool.errors import LearnError
from flctool.learners.base import GenerationResult, IntArray, Learner
from flctool.learners.fuzzy_q import FuzzyQ, new_fuzzy_q
from flctool.learners.ga import (
    Crossover,
    GeneticAlgorithm,
    Mutation,
    boltzmann_mutation,
    evaluate_population,
    one_point_crossover,
    random_population,
    strength_crossover,
    uniform_crossover,
    uniform_mutation,
)
from flctool.spec.learning import GeneticConfig, HybridConfig, PittConfig, QConfig
from flctool.spec.models import Behaviour


def pitt_operators(learner: GeneticLearner) -> tuple[Crossover, Mutation]:
    """Pitt's crossover (uniform, or one-point with ``pitt_crossover: one_point``) and
    uniform mutation."""
    config = learner.config
    one_point = getattr(config, "pitt_crossover", "uniform") == "one_point"
    return (one_point_crossover if one_point else uniform_crossover,
            partial(uniform_mutation, rate=config.mutation,
                    n_commands=learner.controller.n_commands))


def hybrid_operators(learner: GeneticLearner) -> tuple[Crossover, Mutation]:
    """Strength-guided crossover and Boltzmann mutation over the current q table."""
    if learner.fuzzy_q is None:
        raise LearnError("the hybrid operators need rule strengths")
    strengths = learner.fuzzy_q.table()
    return (partial(strength_crossover, strengths=strengths),
            partial(boltzmann_mutation, rate=learner.config.mutation, strengths=strengths,
                    temperature=learner.temperature))


@dataclass(frozen=True)
class OperatorSet:
    """How a genetic learner breeds: what tells ``pitt`` and ``hybrid`` apart."""

    #: Whether rule strengths (a q table, ``learning.q``) learn during every trial.
    strengths: bool
    #: The crossover and mutation of the learner's next breeding.
    operators: Callable[[GeneticLearner], tuple[Crossover, Mutation]]


#: The Pitt approach: crossover and mutation blind to rule strengths.
PITT = OperatorSet(strengths=False, operators=pitt_operators)
#: The paper's hybrid: strength-guided crossover, Boltzmann mutation over q.
HYBRID = OperatorSet(strengths=True, operators=hybrid_operators)


class GeneticLearner(Learner):
    """A population of controllers evolved by a GA; ``operator_set`` says which one."""

    operator_set: ClassVar[OperatorSet]
    config: GeneticConfig
    fuzzy_q: FuzzyQ | None

    def __init__(self, behaviour: Behaviour, env: BatchEnv) -> None:
        super().__init__(behaviour, env)
        config = self.config
        self.ga = GeneticAlgorithm(config.crossover, config.elites)
        self.fuzzy_q = None
        self.temperature = math.nan  # Boltzmann mutation's, with rule strengths
        if self.operator_set.strengths:
            q = getattr(config, "q", None)
            if not isinstance(q, QConfig):
                raise LearnError(f"the {self.name} learner's rule strengths need a "
                                 "learning.q section", hint="extend HybridConfig")
            self.fuzzy_q = new_fuzzy_q(q, self.controller.n_rules, self.controller.n_commands)
            self.temperature = q.temperature
        self.population = self.initial_population()
        self.fitness = np.zeros(config.population)

    def initial_population(self) -> IntArray:
        """The first generation (P, M): uniform random consequents, given rules as given."""
        return self.keep_fixed(random_population(
            self.rngs["ga"], self.config.population, self.controller.n_rules,
            self.controller.n_commands))

    def elite_count(self) -> int:
        return max(1, self.config.elites)

    def evaluate(self, generation: int) -> GenerationResult:
        config = self.config
        seeds = self.episode_seeds(config.population, config.trials, config.common_starts)
        self.fitness, steps = evaluate_population(self.env, self.rules, self.population, seeds,
                                                  td=self.fuzzy_q)
        return GenerationResult(self.fitness, seeds.size, steps)

    def advance(self) -> None:
        crossover, mutation = self.operator_set.operators(self)
        # Given rules are fixed: whatever crossover and mutation did to them is undone.
        self.population = self.keep_fixed(self.ga.breed(
            self.rngs["ga"], self.population, self.fitness, crossover, mutation))


class PittLearner(GeneticLearner):
    """``learner: pitt``: the GA with Pitt's operators, learning from fitness alone."""

    name: ClassVar[str] = "pitt"
    operator_set: ClassVar[OperatorSet] = PITT
    config: PittConfig


class HybridLearner(GeneticLearner):
    """``learner: hybrid``: the GA guided by fuzzy-Q rule strengths (the paper's method)."""

    name: ClassVar[str] = "hybrid"
    operator_set: ClassVar[OperatorSet] = HYBRID
    config: HybridConfig
