"""The GA operators of paper Sec. IV, each pinned on its own."""

from __future__ import annotations

import numpy as np
import pytest

from flctool.learners.ga import (
    ROULETTE_FLOOR,
    GeneticAlgorithm,
    boltzmann_mutation,
    boltzmann_probabilities,
    elite_indices,
    one_point_crossover,
    random_population,
    roulette_probabilities,
    roulette_select,
    strength_crossover,
    uniform_crossover,
    uniform_mutation,
)


def chi_square(counts: np.ndarray, expected: np.ndarray) -> float:
    return float(((counts - expected) ** 2 / expected).sum())


def test_random_population_is_uniform_over_commands() -> None:
    population = random_population(np.random.default_rng(0), 400, 15, 5)
    assert population.shape == (400, 15)
    counts = np.bincount(population.ravel(), minlength=5)
    # chi-square with 4 degrees of freedom: 18.5 is its 0.999 quantile
    assert chi_square(counts, np.full(5, population.size / 5)) < 18.5


def test_roulette_probabilities_are_proportional_to_shifted_fitness() -> None:
    fitness = np.array([-1.0, 0.0, 1.0, 3.0])
    spread = 4.0
    weights = fitness + 1.0 + ROULETTE_FLOOR * spread
    assert roulette_probabilities(fitness) == pytest.approx(weights / weights.sum())


def test_the_worst_keeps_a_small_share_and_equal_fitness_is_uniform() -> None:
    p = roulette_probabilities(np.array([-5.0, -2.0, 0.5]))
    assert 0 < p[0] < p[1] < p[2]
    assert roulette_probabilities(np.zeros(4)) == pytest.approx(np.full(4, 0.25))
    assert roulette_probabilities(np.full(3, -2.0)) == pytest.approx(np.full(3, 1 / 3))


def test_roulette_selection_frequencies_match_the_wheel() -> None:
    fitness = np.array([0.2, 1.0, -0.5, 2.0, 0.0])
    draws = 50_000
    picks = roulette_select(np.random.default_rng(1), fitness, draws)
    counts = np.bincount(picks, minlength=5)
    assert chi_square(counts, roulette_probabilities(fitness) * draws) < 18.5


def test_elitism_keeps_the_best_first_and_unchanged() -> None:
    rng = np.random.default_rng(2)
    population = random_population(rng, 10, 15, 5)
    fitness = rng.normal(size=10)
    ga = GeneticAlgorithm(crossover_rate=1.0, elites=2)
    nxt = ga.breed(rng, population, fitness, uniform_crossover,
                   lambda r, c: uniform_mutation(r, c, 1.0, 5))
    order = np.argsort(-fitness)
    assert nxt.shape == population.shape
    np.testing.assert_array_equal(nxt[0], population[order[0]])
    np.testing.assert_array_equal(nxt[1], population[order[1]])
    assert list(elite_indices(np.array([1.0, 3.0, 3.0, 0.0]), 2)) == [1, 2]  # ties: lower index


def test_breeding_without_crossover_or_mutation_copies_roulette_parents() -> None:
    rng = np.random.default_rng(3)
    population = np.arange(12).reshape(4, 3)
    nxt = GeneticAlgorithm(crossover_rate=0.0, elites=1).breed(
        rng, population, np.array([0.0, 1.0, 2.0, 3.0]), uniform_crossover, lambda r, c: c)
    rows = {tuple(row) for row in population.tolist()}
    assert all(tuple(row) in rows for row in nxt.tolist())


def test_strength_guided_crossover_takes_the_stronger_gene() -> None:
    q = np.array([[0.0, 0.9, 0.1],
                  [0.5, -0.2, 0.0],
                  [-1.0, 0.0, -0.5]])
    a = np.array([1, 1, 0])
    b = np.array([2, 0, 2])
    child = strength_crossover(np.random.default_rng(0), a, b, q)
    assert list(child) == [1, 0, 2]  # q: 0.9 > 0.1, 0.5 > -0.2, -0.5 > -1.0


def test_strength_guided_crossover_breaks_ties_with_a_fair_coin() -> None:
    q = np.zeros((2000, 2))
    a, b = np.zeros(2000, dtype=np.intp), np.ones(2000, dtype=np.intp)
    child = strength_crossover(np.random.default_rng(4), a, b, q)
    assert 900 < child.sum() < 1100
    # an untried consequent (q = 0) beats one that failed (q < 0)
    q[:, 1] = -0.3
    assert strength_crossover(np.random.default_rng(4), a, b, q).sum() == 0


def test_boltzmann_mutation_frequencies_match_exp_q_over_t() -> None:
    temperature = 0.15
    row = np.array([0.1, -0.2, 0.3, 0.0, 0.25])
    genes = 40_000
    strengths = np.tile(row, (genes, 1))
    child = boltzmann_mutation(np.random.default_rng(5), np.zeros(genes, dtype=np.intp), 1.0,
                               strengths, temperature)
    expected = np.exp(row / temperature) / np.exp(row / temperature).sum()
    assert boltzmann_probabilities(row, temperature) == pytest.approx(expected)
    counts = np.bincount(child, minlength=5)
    assert chi_square(counts, expected * genes) < 18.5


def test_mutation_touches_each_gene_with_probability_pm() -> None:
    genes = 20_000
    child = np.zeros(genes, dtype=np.intp)
    mutated = uniform_mutation(np.random.default_rng(6), child, 0.1, 5)
    # a redrawn gene keeps its value with probability 1/K, so changes happen at pm (K-1)/K
    assert (mutated != 0).mean() == pytest.approx(0.1 * 4 / 5, abs=0.01)
    q = np.zeros((genes, 5))
    assert (boltzmann_mutation(np.random.default_rng(6), child, 0.0, q, 0.15) == 0).all()


def test_pitt_crossovers_mix_the_parents() -> None:
    a, b = np.zeros(15, dtype=np.intp), np.full(15, 4, dtype=np.intp)
    rng = np.random.default_rng(7)
    child = uniform_crossover(rng, a, b)
    assert set(child.tolist()) <= {0, 4}
    cut = one_point_crossover(rng, a, b)
    first_b = int(np.argmax(cut == 4))
    # one cut strictly inside: a's genes before it, b's after
    assert first_b in range(1, 15)
    assert (cut[:first_b] == 0).all() and (cut[first_b:] == 4).all()
