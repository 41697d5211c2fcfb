"""The ``credit`` learner: whole rule tables tried, every episode's outcome credited to the
rules that fired.

The genetic learners judge a table by its own few trials. Where one trial says little -- a
success decided by a single moment, such as a kick, on a task where even the best table
fails most episodes -- that judgement is mostly noise: on ``shoot`` the spread between the
tables of a generation is a fraction of the spread between two trials of one table, so
selection breeds from luck (docs/learning.md, "Which learner"). Fuzzy Q-learning credits
rules step by step, but its bootstrapped credit does not reach back from an outcome many
steps after the command that decided it.

This learner pools the evidence of every episode of every table, rule by rule (the Michigan
approach's credit assignment, applied to the Pitt approach's whole-table trials):

- each rule m keeps, for each command k, a **credit**: the mean advantage of the episodes in
  which rule m had command k and fired, weighted by how much of the episode it shaped --
  ``w_m = sqrt(sum_t phi_m(t) / sum_t sum_j phi_j(t))``, its share of the episode's
  normalised activations (eq. 7) -- where an episode's advantage is its fitness less the
  mean of its generation;
- a generation draws ``population`` tables by **Thompson sampling**: for each rule and
  command a draw from ``N(credit, spread^2 / (weight + prior))`` (``spread``: the standard
  deviation of the last generation's episode fitness; ``weight``: the evidence the credit
  rests on), and each rule takes the command with the largest draw. Commands with little
  evidence get wide draws, so they are tried until their credit is known; the first
  generation's tables are uniformly random;
- the learned controller is the **greedy** table: each rule's command of largest credit.

Every table a generation tries is one sample of how the other rules' commands are chosen, so
a rule's credit for a command is its effect averaged over the tables being tried; as the
draws concentrate, it becomes its effect beside the best commands of the others.

Nothing is forgotten, so the credit only sharpens with more episodes; a run with ``extend``
therefore runs all of its ``extend.most`` generations (the problem-sized budget) rather than
stopping when a noisy validation stops improving. As under ``fuzzy_q``, the hall of fame
holds the greedy tables of the latest generations, and their training fitness (the
generation's mean, of tables still exploring) is recorded but not ranked on.

Measured in docs/learning.md: the sqrt weighting, the per-generation advantage and keeping
every episode (no forgetting) were chosen on ``shoot``'s development seeds, where the
credit's tables beat what the hybrid's searches ever met; the rest of the suite says where
it is the learner to pick.
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from flctool.behaviour.learning import CreditConfig
from flctool.behaviour.models import Behaviour
from flctool.envs.base import BatchEnv
from flctool.learners.base import FloatArray, GenerationResult, IntArray, Learner
from flctool.learners.checkpoint import damaged
from flctool.learners.trial import run_trial


class RuleCredit:
    """Each rule's credit per command (M, K): weighted sums of advantages and their weights.

    ``spread`` scales the Thompson draws: the standard deviation of the latest generation's
    episode fitness that had any (1.0 before the first).
    """

    def __init__(self, n_rules: int, n_commands: int, prior: float) -> None:
        self.total = np.zeros((n_rules, n_commands))  # sum of w_m * advantage
        self.weight = np.zeros((n_rules, n_commands))  # sum of w_m
        self.prior = prior
        self.spread = 1.0

    def means(self) -> FloatArray:
        """The credit (M, K): each weighted mean advantage, shrunk towards 0 by the prior."""
        result: FloatArray = self.total / (self.weight + self.prior)
        return result

    def greedy(self) -> IntArray:
        """Each rule's command of largest credit (M,), ties to the lowest index."""
        best: IntArray = np.argmax(self.means(), axis=1).astype(np.intp)
        return best

    def draw(self, rng: np.random.Generator, tables: int) -> IntArray:
        """``tables`` rule tables (P, M) by Thompson sampling from the credit."""
        width = self.spread / np.sqrt(self.weight + self.prior)
        draws = self.means()[None] + rng.standard_normal((tables, *self.total.shape)) * width
        chosen: IntArray = np.argmax(draws, axis=2).astype(np.intp)
        return chosen

    def learn(self, tables: IntArray, activation: FloatArray, fitness: FloatArray) -> None:
        """Credit the episodes: ``tables (E, M)`` the consequents each acted with,
        ``activation (E, M)`` each rule's summed phi over the episode, ``fitness (E,)``."""
        totals = activation.sum(axis=1, keepdims=True)
        shares = np.divide(activation, totals, out=np.zeros_like(activation),
                           where=totals > 0)
        weights = np.sqrt(shares)
        advantage = fitness - fitness.mean()
        rules = np.arange(tables.shape[1])
        for table, weight, value in zip(tables, weights, advantage, strict=True):
            self.total[rules, table] += weight * value
            self.weight[rules, table] += weight
        spread = float(fitness.std())
        if spread > 0.0:  # all alike says nothing of the scale: keep the last one
            self.spread = spread

    def state_dict(self) -> dict[str, Any]:
        return {"credit": {"total": self.total.tolist(), "weight": self.weight.tolist(),
                           "spread": self.spread}}

    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Restore :meth:`state_dict`; the checkpoint error if it is missing or damaged."""
        shape = self.total.shape
        try:
            record = state["credit"]
            total = np.array(record["total"], dtype=np.float64)
            weight = np.array(record["weight"], dtype=np.float64)
            spread = float(record["spread"])
        except (KeyError, TypeError, ValueError) as exc:
            raise damaged(f"has no readable rule credit ({exc!r})") from None
        if total.shape != shape or weight.shape != shape or not (
                np.isfinite(total).all() and np.isfinite(weight).all()
                and (weight >= 0).all() and math.isfinite(spread) and spread > 0):
            raise damaged(f"is damaged: its rule credit is not {shape[0]} x {shape[1]} finite "
                          "sums with weights of at least 0 and a positive spread")
        self.total, self.weight, self.spread = total, weight, spread


class CreditLearner(Learner):
    """Thompson sampling over rule tables from pooled rule-wise credit (module docstring).

    A generation is ``population`` tables, each run for ``trials`` episodes; the learned
    controller is the greedy table, and its fitness in the run records is the generation's
    mean episode fitness. Rules the file gives keep their commands in every table.
    """

    name: ClassVar[str] = "credit"
    config: CreditConfig
    rank_by: ClassVar[str] = "recency"  # the tables tried are still exploring

    def __init__(self, behaviour: Behaviour, env: BatchEnv) -> None:
        super().__init__(behaviour, env)
        self.credit = RuleCredit(self.controller.n_rules, self.controller.n_commands,
                                 self.config.prior)
        self.given_first: IntArray | None = None
        self.population = self.greedy()

    def start_from(self, population: NDArray[np.intp] | None = None,
                   strengths: FloatArray | None = None) -> None:
        """A warm start: ``population`` is the first generation's tables (see
        :meth:`Learner.start_from`); the credit learner keeps no rule strengths."""
        super().start_from(population, strengths)
        if population is not None:
            self.given_first = self.population.copy()

    def greedy(self) -> IntArray:
        """The greedy controller (1, M): each rule's command of largest credit."""
        return self.keep_fixed(self.credit.greedy()[None, :])

    def evaluate(self, generation: int) -> GenerationResult:
        config = self.config
        if generation == 0 and self.given_first is not None:
            tables = self.given_first
        else:  # the first generation's draws, with no credit yet, are uniformly random
            tables = self.keep_fixed(self.credit.draw(self.rngs["ga"], config.population))
        seeds = self.episode_seeds(tables.shape[0], config.trials, common=False).ravel()
        tried = np.repeat(tables, config.trials, axis=0)  # the table of each episode (E, M)
        episodes = seeds.size
        returns = np.empty(episodes)
        lengths = np.empty(episodes, dtype=np.int64)
        success = np.empty(episodes, dtype=np.bool_)
        activation = np.zeros((episodes, self.controller.n_rules))
        for e, (consequents, seed) in enumerate(zip(tried.tolist(), seeds.tolist(),
                                                    strict=True)):
            shaped = [0.0] * self.controller.n_rules
            trial = run_trial(self.env, self.rules, seed, consequents, credit=shaped)
            returns[e], lengths[e], success[e] = trial.ret, trial.length, trial.success
            activation[e] = shaped
        fitness = self.env.episode_fitness(returns, lengths, success)
        self.credit.learn(tried, activation, fitness)
        self.population = self.greedy()
        self.fitness = np.array([float(np.mean(fitness))])
        return GenerationResult(fitness, episodes, int(lengths.sum()))

    def advance(self) -> None:
        """Nothing to breed: the next generation's tables are drawn from the credit when
        it is evaluated."""

    def extra_state(self) -> dict[str, Any]:
        return self.credit.state_dict()

    def load_extra_state(self, state: dict[str, Any]) -> None:
        self.credit.load_state_dict(state)
