"""One generation's metrics row."""

from __future__ import annotations

import numpy as np
import pytest

from flctool.learners.metrics import GenerationMetrics


def test_statistics_and_row_round_trip() -> None:
    m = GenerationMetrics.from_fitness(3, np.array([0.5, 1.5, -1.0]), 3, 42, 0.25, 20, 310,
                                       0.75)
    assert (m.mean, m.best, m.min) == (pytest.approx(1 / 3), 1.5, -1.0)
    assert m.std == pytest.approx(np.std([0.5, 1.5, -1.0]))
    assert tuple(m.row()) == GenerationMetrics.columns()
    assert GenerationMetrics.from_row({k: str(v) for k, v in m.row().items()}) == m
    assert (m.selection_episodes, m.selection_steps, m.validated) == (20, 310, 0.75)


def test_rows_of_runs_without_selection_read_back() -> None:
    row = {"generation": "0", "mean": "1", "std": "0", "best": "1", "min": "1",
           "episodes": "10", "steps": "99", "wall_time": "0.5"}
    m = GenerationMetrics.from_row(row)
    assert (m.selection_episodes, m.selection_steps) == (0, 0) and m.validated != m.validated
