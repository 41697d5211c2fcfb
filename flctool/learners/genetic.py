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
every operator (:meth:`~flctool.learners.base.Learner.keep_fixed`). With ``learning.sets``
each controller also carries a set genome (``set_genes``), bred from the same parents by the
set operators of :mod:`flctool.learners.set_genes`, and acts with its own sets.

**Fresh attempts** (an extended run's room, :mod:`~flctool.learners.extension`) start the
whole population, set genes and q table anew; the run's hall of fame carries on.

**Restarts** answer premature convergence: when the run's selected controller (the best
validated one; without selection, the best training fitness) has not improved for
``restart_after`` generations, every individual but the elites is drawn afresh after
breeding (from the ``ga`` stream; the q table is kept). A population stuck on a poor table --
the hybrid's operators pull every child towards the q table's favourites, which on some seeds
are a controller that loses the ball or times out -- then gets a fresh start within the same
budget (measured in docs/learning.md). Runs started by versions without restarts continue
without them, so they resume bit for bit. A restarted individual gets fresh set genes too.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from typing import Any, ClassVar

import numpy as np

from flctool.behaviour.learning import GeneticConfig, HybridConfig, PittConfig, QConfig
from flctool.behaviour.models import Behaviour
from flctool.envs.base import BatchEnv
from flctool.errors import LearnError
from flctool.learners.base import GenerationResult, IntArray, Learner
from flctool.learners.checkpoint import damaged
from flctool.learners.fuzzy_q import FuzzyQ, new_fuzzy_q
from flctool.learners.ga import (
    Crossover,
    GeneticAlgorithm,
    Mutation,
    boltzmann_mutation,
    evaluate_population,
    greedy_controller,
    one_point_crossover,
    random_population,
    strength_crossover,
    uniform_crossover,
    uniform_mutation,
)
from flctool.learners.set_genes import SetOperators, initial_set_genes


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
    fresh_attempts: ClassVar[bool] = True

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
        self.set_operators: SetOperators | None = None
        if self.codec is not None and config.sets is not None:
            self.set_operators = SetOperators(self.codec.slices, config.sets.mutation,
                                              config.sets.sigma)
            self.set_genes = initial_set_genes(self.rngs["ga"], config.population,
                                               self.codec.size, config.sets.sigma)
        #: Whether every bred generation holds the q table's greedy controller
        #: (``learning.greedy_individual``, hybrid only).
        self.greedy_individual = bool(getattr(config, "greedy_individual", False)
                                      and self.fuzzy_q is not None)
        #: Premature-convergence restarts: enabled, best figure seen, generations since it
        #: improved, restarts made.
        self.restart_after = config.restarts_after
        self.best_seen = -math.inf
        self.stalled_for = 0
        self.restarts = 0

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
        self.fitness, steps = evaluate_population(self.env, self.population_rules(),
                                                  self.population, seeds, td=self.fuzzy_q)
        return GenerationResult(self.fitness, seeds.size, steps)

    def advance(self) -> None:
        if self.extension.begins_attempt(self.generation + 1):
            self._fresh_attempt()
            return
        stalled = self._stalled()
        # the greedy individual starts from the last generation's best, taken before breeding
        leader = int(np.argmax(self.fitness))
        leader_genes = None if self.set_genes is None else self.set_genes[leader].copy()
        leader_consequents = self.population[leader].copy()
        crossover, mutation = self.operator_set.operators(self)
        population, self.set_genes = self.ga.breed_genomes(
            self.rngs["ga"], self.population, self.fitness, crossover, mutation,
            self.set_genes, self.set_operators)
        if stalled:
            self._restart(population)
        if self.greedy_individual:
            assert self.fuzzy_q is not None
            # the last individual is never an elite (elites < population)
            population[-1] = greedy_controller(self.fuzzy_q.table(), leader_consequents)
            if self.set_genes is not None and leader_genes is not None:
                self.set_genes[-1] = leader_genes
        # Given rules are fixed: whatever crossover and mutation did to them is undone.
        self.population = self.keep_fixed(population)

    def _fresh_attempt(self) -> None:
        """Start the run afresh (:mod:`~flctool.learners.extension`): a new random
        population, new set genes and, with rule strengths, a new q table; the run's hall of
        fame, validations and budget carry on."""
        config = self.config
        self.population = self.initial_population()
        if self.set_genes is not None and self.codec is not None and config.sets is not None:
            self.set_genes = initial_set_genes(self.rngs["ga"], config.population,
                                               self.codec.size, config.sets.sigma)
        q = getattr(config, "q", None)
        if self.fuzzy_q is not None and isinstance(q, QConfig):
            self.fuzzy_q = new_fuzzy_q(q, self.controller.n_rules, self.controller.n_commands)
        self.stalled_for = 0

    def _restart(self, population: IntArray) -> None:
        """Redraw every individual of ``population`` (P, M) but the elites, in place (and
        their set genes)."""
        keep = min(self.elite_count(), population.shape[0] - 1)
        fresh = population.shape[0] - keep
        population[keep:] = random_population(self.rngs["ga"], fresh, self.controller.n_rules,
                                              self.controller.n_commands)
        config = self.config
        if self.set_genes is not None and self.codec is not None and config.sets is not None:
            self.set_genes[keep:] = initial_set_genes(self.rngs["ga"], fresh, self.codec.size,
                                                      config.sets.sigma)
        self.restarts += 1

    def _stalled(self) -> bool:
        """Whether the run's figure has not improved for ``restart_after`` generations (then
        the count starts again)."""
        if self.restart_after <= 0:
            return False
        best = self.selection.best
        figure = best.validation_value() if best is not None else float(self.fitness.max())
        if figure > self.best_seen:
            self.best_seen, self.stalled_for = figure, 0
            return False
        self.stalled_for += 1
        if self.stalled_for < self.restart_after:
            return False
        self.stalled_for = 0
        return True

    def extra_state(self) -> dict[str, Any]:
        state = {**super().extra_state(),
                 "restarts": {"after": self.restart_after, "best_seen": self.best_seen,
                              "stalled_for": self.stalled_for, "restarts": self.restarts}}
        if self.fuzzy_q is not None:
            state["greedy_individual"] = self.greedy_individual
        return state

    def load_extra_state(self, state: dict[str, Any]) -> None:
        super().load_extra_state(state)
        if self.fuzzy_q is not None:
            # a run of a version without the greedy individual continues without it
            greedy = state.get("greedy_individual", False)
            if not isinstance(greedy, bool):
                raise damaged("is damaged: its greedy_individual is not true or false")
            self.greedy_individual = greedy
        record = state.get("restarts")
        if record is None:  # a run of a version without restarts: it continues without
            self.restart_after = 0
            return
        try:
            after, best_seen = int(record["after"]), float(record["best_seen"])
            stalled_for, restarts = int(record["stalled_for"]), int(record["restarts"])
        except (KeyError, TypeError, ValueError, OverflowError) as exc:
            raise damaged(f"is damaged: its restart record cannot be read ({exc!r})") from None
        if after < 0 or stalled_for < 0 or restarts < 0 or math.isnan(best_seen):
            raise damaged("is damaged: its restart record holds negative counts or NaN")
        self.restart_after, self.best_seen = after, best_seen
        self.stalled_for, self.restarts = stalled_for, restarts


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
