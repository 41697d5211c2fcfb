"""Interpretability measures of a partition and the movement of its sets."""

from __future__ import annotations

import pytest

from flctool.behaviour.load import behaviour_from_data
from flctool.behaviour.models import Behaviour
from flctool.sets.measures import crossing_height, interpretability, movements, partition_measures


def _behaviour(sets: dict[str, list[float]]) -> Behaviour:
    return behaviour_from_data({
        "flctool": 1, "name": "m", "inputs": {"x": {"range": [0, 1], "sets": sets}},
        "output": {"name": "a", "commands": {"l": -1.0, "r": 1.0}}})


@pytest.mark.parametrize(("left", "right", "height"), [
    ([0, 0, 0.2, 0.6], [0.2, 0.6, 1, 1], 0.5),  # a strong partition crosses at 1/2
    ([0, 0, 0.2, 0.4], [0.4, 0.8, 1, 1], 0.0),  # feet touching
    ([0, 0, 0.5, 0.6], [0.4, 0.5, 1, 1], 1.0),  # cores meet
    ([0, 0, 0.2, 0.6], [0.4, 0.6, 1, 1], 1 / 3),  # (0.6 - s) / 0.4 == (s - 0.4) / 0.2 at 7/15
])
def test_crossing_height(left: list[float], right: list[float], height: float) -> None:
    assert crossing_height(left, right) == pytest.approx(height)


def test_a_strong_partition_is_covered_to_one_half() -> None:
    measures = partition_measures((0, 1), {"a": [0, 0, 0.2, 0.6], "b": [0.2, 0.6, 1, 1]})
    assert measures["coverage"] == pytest.approx(0.5)
    assert measures["least_covered_at"] == pytest.approx(0.4)
    assert measures["overlaps"] == {"a|b": pytest.approx(0.5)}


def test_movement_is_the_largest_corner_change() -> None:
    before = _behaviour({"a": [0, 0, 0.2, 0.6], "b": [0.2, 0.6, 1, 1]})
    after = _behaviour({"a": [0, 0, 0.3, 0.5], "b": [0.3, 0.5, 1, 1]})
    moved = movements(before, after)
    assert [(m.set, m.largest) for m in moved] == [("a", pytest.approx(0.1)),
                                                    ("b", pytest.approx(0.1))]
    record = interpretability(before, after)
    assert record["x"]["movement"]["a"]["moved_fraction_of_range"] == pytest.approx(0.1)
    assert record["x"]["coverage"] == pytest.approx(0.5)
