"""What one generation of training measured: one row of a run's metrics.csv."""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields
from typing import Any

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class GenerationMetrics:
    """Fitness statistics of one generation, over its individuals (fuzzy_q: its episodes)."""

    generation: int
    mean: float
    std: float
    best: float
    min: float
    episodes: int  # episodes run in this generation
    steps: int  # environment steps taken in this generation
    wall_time: float  # seconds since the run started, summed over resumed sessions

    @classmethod
    def from_fitness(cls, generation: int, fitness: FloatArray, episodes: int, steps: int,
                     wall_time: float) -> GenerationMetrics:
        f = np.asarray(fitness, dtype=np.float64)
        return cls(generation, float(f.mean()), float(f.std()), float(f.max()), float(f.min()),
                   episodes, steps, wall_time)

    @classmethod
    def columns(cls) -> tuple[str, ...]:
        return tuple(f.name for f in fields(cls))

    def row(self) -> dict[str, Any]:
        return asdict(self)

    @classmethod
    def from_row(cls, row: dict[str, Any]) -> GenerationMetrics:
        return cls(int(row["generation"]), float(row["mean"]), float(row["std"]),
                   float(row["best"]), float(row["min"]), int(row["episodes"]),
                   int(row["steps"]), float(row["wall_time"]))
