"""The genetic algorithm of paper Sec. IV: operators on chromosomes of M consequent indices.

A population is an int array ``(P, M)``: row p is one controller, gene m the command index of
rule m (grid order, eq. 1). Every operator takes the numpy ``Generator`` it draws from, so a
run is reproducible from its seed.

Choices the paper leaves open, made here:

- **Roulette wheel on shifted fitness.** Fitness may be negative (a lost ball), so slices are
  proportional to ``f - min(f) + epsilon`` with ``epsilon = 1 %`` of the spread
  ``max(f) - min(f)``: the worst individual keeps a small chance, the order is preserved. When
  every fitness is equal (including all zero) the wheel is uniform.
- **Elitism**: the ``elites`` best (ties to the lower index) are copied unchanged, first.
- **One child per crossover.** Each remaining slot takes a roulette parent; with probability
  ``pc`` a second roulette parent is drawn and the two make one child -- gene by gene the
  consequent with the higher strength ``q_m^k`` (hybrid; equal strengths: a fair coin), or the
  Pitt crossover (uniform: each gene from either parent with probability 1/2; or one-point).
- **Mutation per gene** with probability ``pm``; the new consequent is drawn over all K
  commands (so it may equal the old one): uniformly (Pitt) or from the Boltzmann
  distribution ``exp(q_m^k / T) / sum_j exp(q_m^j / T)`` over the rule's strengths (hybrid).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from flctool.envs.base import BatchEnv
from flctool.learners.set_genes import SetOperators
from flctool.learners.trial import SparseRules, TemporalDifference, run_trial

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]

#: The worst individual's slice of the roulette wheel, as a fraction of the fitness spread.
ROULETTE_FLOOR = 0.01

#: ``(rng, parent_a (M,), parent_b (M,)) -> child (M,)``
Crossover = Callable[[np.random.Generator, IntArray, IntArray], IntArray]
#: ``(rng, child (M,)) -> mutated child (M,)``
Mutation = Callable[[np.random.Generator, IntArray], IntArray]


def random_population(rng: np.random.Generator, size: int, n_rules: int,
                      n_commands: int) -> IntArray:
    """Uniform random initialisation: every gene drawn evenly from the K commands -> (P, M)."""
    return rng.integers(n_commands, size=(size, n_rules)).astype(np.intp)


def roulette_probabilities(fitness: FloatArray) -> FloatArray:
    """Selection probabilities (P,) proportional to the shifted fitness (see module doc)."""
    f = np.asarray(fitness, dtype=np.float64)
    spread = float(f.max() - f.min())
    if spread == 0.0 or not np.isfinite(spread):
        return np.full(f.shape, 1.0 / f.size)
    weights = f - f.min() + ROULETTE_FLOOR * spread
    probabilities: FloatArray = weights / weights.sum()
    return probabilities


def roulette_select(rng: np.random.Generator, fitness: FloatArray, count: int) -> IntArray:
    """``count`` parent indices drawn with replacement by roulette wheel -> (count,)."""
    cdf = np.cumsum(roulette_probabilities(fitness))
    picks = np.searchsorted(cdf, rng.random(count) * cdf[-1], side="right")
    indices: IntArray = np.minimum(picks, len(cdf) - 1).astype(np.intp)
    return indices


def elite_indices(fitness: FloatArray, count: int) -> IntArray:
    """The ``count`` fittest individuals, best first, ties to the lower index -> (count,)."""
    return np.argsort(-np.asarray(fitness), kind="stable")[:count].astype(np.intp)


def uniform_crossover(rng: np.random.Generator, a: IntArray, b: IntArray) -> IntArray:
    """Pitt: each gene from parent ``a`` or ``b`` with probability 1/2 -> child (M,)."""
    return np.where(rng.random(a.shape[0]) < 0.5, a, b)


def one_point_crossover(rng: np.random.Generator, a: IntArray, b: IntArray) -> IntArray:
    """Pitt: genes before a random cut from ``a``, the rest from ``b`` -> child (M,)."""
    cut = int(rng.integers(1, a.shape[0])) if a.shape[0] > 1 else 0
    return np.concatenate([a[:cut], b[cut:]])


def strength_crossover(rng: np.random.Generator, a: IntArray, b: IntArray,
                       strengths: FloatArray) -> IntArray:
    """Hybrid (Sec. IV): gene by gene, the parent consequent with the higher q_m^k.

    ``strengths (M, K)`` is the q table; equal strengths are settled by a fair coin. An untried
    consequent (q at its initial value) beats one that has failed (q below it).
    """
    rows = np.arange(a.shape[0])
    qa, qb = strengths[rows, a], strengths[rows, b]
    coin = rng.random(a.shape[0]) < 0.5
    return np.where((qa > qb) | ((qa == qb) & coin), a, b)


def uniform_mutation(rng: np.random.Generator, child: IntArray, rate: float,
                     n_commands: int) -> IntArray:
    """Pitt: each gene, with probability ``rate``, becomes a uniformly drawn command."""
    mask = rng.random(child.shape[0]) < rate
    drawn = rng.integers(n_commands, size=child.shape[0])
    return np.where(mask, drawn, child).astype(np.intp)


def boltzmann_probabilities(strengths: FloatArray, temperature: float) -> FloatArray:
    """``exp(q/T)`` normalised over the last axis: (..., K) -> (..., K)."""
    z = (strengths - strengths.max(axis=-1, keepdims=True)) / temperature
    weights = np.exp(z)
    probabilities: FloatArray = weights / weights.sum(axis=-1, keepdims=True)
    return probabilities


def boltzmann_mutation(rng: np.random.Generator, child: IntArray, rate: float,
                       strengths: FloatArray, temperature: float) -> IntArray:
    """Hybrid: each gene, with probability ``rate``, redrawn from Boltzmann over q_m (K,).

    ``strengths (M, K)`` is the q table; ``temperature`` T > 0.
    """
    genes = int(child.shape[0])
    mask = rng.random(genes) < rate
    cdf = np.cumsum(boltzmann_probabilities(strengths, temperature), axis=1)  # (M, K)
    u = rng.random(genes)[:, None] * cdf[:, -1:]
    drawn = np.minimum((cdf <= u).sum(axis=1), strengths.shape[1] - 1)
    return np.where(mask, drawn, child).astype(np.intp)


def greedy_controller(strengths: FloatArray, leader: IntArray) -> IntArray:
    """The q table's greedy controller: each rule's strongest command -> (M,).

    ``strengths (M, K)`` is the q table; where several commands are strongest (a rule that
    never fired keeps every q at its initial value) and ``leader (M,)``'s command is one of
    them, the leader's is kept, so a rule q knows nothing about keeps what selection found.
    """
    rows = np.arange(strengths.shape[0])
    top = strengths.max(axis=1)
    keep = strengths[rows, leader] >= top
    greedy: IntArray = np.where(keep, leader, np.argmax(strengths, axis=1)).astype(np.intp)
    return greedy


@dataclass(frozen=True)
class GeneticAlgorithm:
    """One generation of breeding: elitism, roulette selection, crossover, mutation."""

    crossover_rate: float
    elites: int

    def breed(self, rng: np.random.Generator, population: IntArray, fitness: FloatArray,
              crossover: Crossover, mutation: Mutation) -> IntArray:
        """The next population (P, M) from this one and its fitness (P,)."""
        return self.breed_genomes(rng, population, fitness, crossover, mutation)[0]

    def breed_genomes(self, rng: np.random.Generator, population: IntArray,
                      fitness: FloatArray, crossover: Crossover, mutation: Mutation,
                      set_genes: FloatArray | None = None, set_operators: SetOperators | None
                      = None) -> tuple[IntArray, FloatArray | None]:
        """The next population (P, M), and with ``set_genes (P, G)`` the next set genomes:
        a child's set genes come from the same parents as its consequents, crossed when they
        cross, mutated after them (:mod:`flctool.learners.set_genes`)."""
        size = population.shape[0]
        elites = elite_indices(fitness, min(self.elites, size))
        children = size - len(elites)
        parents = roulette_select(rng, fitness, children)
        mates = roulette_select(rng, fitness, children)
        crossing = rng.random(children) < self.crossover_rate
        nxt = np.empty_like(population)
        nxt[: len(elites)] = population[elites]
        genes = None if set_genes is None or set_operators is None else set_genes
        nxt_genes = None if genes is None else np.empty_like(genes)
        if nxt_genes is not None and genes is not None:
            nxt_genes[: len(elites)] = genes[elites]
        for slot in range(children):
            child = population[parents[slot]]
            if crossing[slot]:
                child = crossover(rng, child, population[mates[slot]])
            nxt[len(elites) + slot] = mutation(rng, child)
            if nxt_genes is not None and genes is not None and set_operators is not None:
                child_genes = genes[parents[slot]]
                if crossing[slot]:
                    child_genes = set_operators.crossover(rng, child_genes, genes[mates[slot]])
                nxt_genes[len(elites) + slot] = set_operators.mutation(rng, child_genes)
        return nxt, nxt_genes


def evaluate_population(env: BatchEnv, rules: SparseRules | Sequence[SparseRules],
                        population: IntArray, seeds: NDArray[np.int64],
                        td: TemporalDifference | None = None) -> tuple[FloatArray, int]:
    """Fitness (P,) of each individual, the mean over its trials, and the steps taken.

    ``seeds (P, T)`` start individual p's trial t. Trials run one after the other -- with
    ``td`` (the hybrid) the q table learns from each before the next begins. ``rules`` is
    the rule base of all, or each individual's (P,) when the run learns the sets.
    """
    each = [rules] * population.shape[0] if isinstance(rules, SparseRules) else rules
    size, trials = seeds.shape
    returns = np.empty(size * trials)
    lengths = np.empty(size * trials, dtype=np.int64)
    success = np.empty(size * trials, dtype=np.bool_)
    for p in range(size):
        consequents = population[p].tolist()
        for t in range(trials):
            trial = run_trial(env, each[p], int(seeds[p, t]), consequents, td=td)
            i = p * trials + t
            returns[i], lengths[i], success[i] = trial.ret, trial.length, trial.success
    fitness = env.episode_fitness(returns, lengths, success).reshape(size, trials)
    return fitness.mean(axis=1), int(lengths.sum())
