"""Set genes: the genetic operators of the set genomes that ``learning.sets`` adds.

A set genome is a vector of G genes in [-1, 1] (0: the file's sets); what the genes mean is the
codec's business (:mod:`flctool.sets.codec`), so these operators know genomes, not sets:

- **initialisation**: the first individual keeps the file's sets (all genes 0), so the hand
  design is always in the first generation; every other gene is drawn from a normal
  distribution of standard deviation ``sets.sigma``, clipped to [-1, 1].
- **crossover** (when the consequents cross, with probability ``crossover``): input by input,
  the child takes the whole block of one parent's genes for that input, each parent with
  probability 1/2. An input's genes act together (a partition's gaps are stretched to fill
  the range together), so a block is inherited whole rather than gene by gene.
- **mutation**: each gene, with probability ``sets.mutation``, takes a normal step of
  standard deviation ``sets.sigma`` and is clipped to [-1, 1].

All draw from the generator they are given (the run's ``ga`` stream), after the consequents'
draws of the same child, so a run that learns no sets draws exactly what it did before.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


def initial_set_genes(rng: np.random.Generator, individuals: int, size: int,
                      sigma: float) -> FloatArray:
    """The first generation's set genomes (P, G): row 0 the file's sets, the rest near them."""
    genes = np.clip(rng.normal(0.0, sigma, size=(individuals, size)), -1.0, 1.0)
    genes[0] = 0.0
    return genes


@dataclass(frozen=True)
class SetOperators:
    """Crossover and mutation of set genomes (see the module docstring)."""

    #: Each learned input's genes as a (start, stop) slice of the genome.
    blocks: Sequence[tuple[int, int]]
    rate: float  # per-gene mutation probability (sets.mutation)
    sigma: float  # the mutation step's standard deviation (sets.sigma)

    def crossover(self, rng: np.random.Generator, a: FloatArray, b: FloatArray) -> FloatArray:
        """Input by input, one parent's whole block -> child (G,)."""
        child = np.array(a, dtype=np.float64)
        takes_b = rng.random(len(self.blocks)) < 0.5
        for (start, stop), other in zip(self.blocks, takes_b, strict=True):
            if other:
                child[start:stop] = b[start:stop]
        return child

    def mutation(self, rng: np.random.Generator, child: FloatArray) -> FloatArray:
        """Each gene, with probability ``rate``, a normal step of ``sigma``, clipped."""
        size = child.shape[0]
        mask = rng.random(size) < self.rate
        steps = rng.normal(0.0, self.sigma, size=size)
        mutated: FloatArray = np.clip(np.where(mask, child + steps, child), -1.0, 1.0)
        return mutated
