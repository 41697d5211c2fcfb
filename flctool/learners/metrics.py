"""What training measures: a generation's trials, its row of metrics.csv, a run's spending.

:class:`GenerationResult` is what a learner's trials of one generation gave;
:class:`GenerationMetrics` is the row of a run's metrics.csv made of it. Training and
validation (model selection) are counted apart: ``episodes`` and ``steps`` are the
generation's training trials, ``selection_episodes`` and ``selection_steps`` the validation
episodes run after it; the run used the sum of both. :class:`Usage` counts all a run has
spent. This module imports no other part of the learners, so every part can use it.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields
from typing import Any

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]


@dataclass(frozen=True)
class GenerationResult:
    """What :meth:`~flctool.learners.base.Learner.evaluate` measured."""

    fitness: FloatArray  # (P,) per individual, or (E,) per episode for fuzzy_q
    episodes: int
    steps: int


@dataclass(frozen=True)
class GenerationMetrics:
    """Fitness statistics of one generation, over its individuals (fuzzy_q: its episodes)."""

    generation: int
    mean: float
    std: float
    best: float
    min: float
    episodes: int  # training episodes run in this generation
    steps: int  # environment steps of those training episodes
    wall_time: float  # seconds since the run started, summed over resumed sessions
    selection_episodes: int = 0  # validation episodes run after this generation
    selection_steps: int = 0  # environment steps of those validation episodes
    validated: float = math.nan  # validated mean fitness of the run's best so far (NaN: none)
    confirmation_episodes: int = 0  # confirmation episodes run after this generation
    confirmation_steps: int = 0

    @classmethod
    def from_fitness(cls, generation: int, fitness: FloatArray, episodes: int, steps: int,
                     wall_time: float, selection_episodes: int = 0, selection_steps: int = 0,
                     validated: float = math.nan, confirmation_episodes: int = 0,
                     confirmation_steps: int = 0) -> GenerationMetrics:
        f = np.asarray(fitness, dtype=np.float64)
        return cls(generation, float(f.mean()), float(f.std()), float(f.max()), float(f.min()),
                   episodes, steps, wall_time, selection_episodes, selection_steps, validated,
                   confirmation_episodes, confirmation_steps)

    @classmethod
    def columns(cls) -> tuple[str, ...]:
        return tuple(f.name for f in fields(cls))

    def row(self) -> dict[str, Any]:
        return asdict(self)

    @classmethod
    def from_row(cls, row: dict[str, Any]) -> GenerationMetrics:
        return cls(int(row["generation"]), float(row["mean"]), float(row["std"]),
                   float(row["best"]), float(row["min"]), int(row["episodes"]),
                   int(row["steps"]), float(row["wall_time"]),
                   # absent from the records of runs made before model selection
                   int(row.get("selection_episodes", 0)), int(row.get("selection_steps", 0)),
                   float(row.get("validated", math.nan)),
                   # absent from the records of runs made before confirmation
                   int(row.get("confirmation_episodes", 0)),
                   int(row.get("confirmation_steps", 0)))


@dataclass
class Usage:
    """Episodes and environment steps spent: training, selection (validation),
    confirmation and the baselines' comparison apart."""

    training_episodes: int = 0
    training_steps: int = 0
    selection_episodes: int = 0
    selection_steps: int = 0
    confirmation_episodes: int = 0
    confirmation_steps: int = 0
    baseline_episodes: int = 0  # the end-of-run comparison (flctool.learners.baselines)
    baseline_steps: int = 0

    @property
    def episodes(self) -> int:
        return (self.training_episodes + self.selection_episodes + self.confirmation_episodes
                + self.baseline_episodes)

    @property
    def steps(self) -> int:
        return (self.training_steps + self.selection_steps + self.confirmation_steps
                + self.baseline_steps)

    def to_dict(self) -> dict[str, int]:
        return {"training_episodes": self.training_episodes,
                "training_steps": self.training_steps,
                "selection_episodes": self.selection_episodes,
                "selection_steps": self.selection_steps,
                "confirmation_episodes": self.confirmation_episodes,
                "confirmation_steps": self.confirmation_steps,
                "baseline_episodes": self.baseline_episodes,
                "baseline_steps": self.baseline_steps,
                "episodes": self.episodes, "steps": self.steps}
