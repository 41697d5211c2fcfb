"""Shared import helpers: point lists to trapezoids, and the imported behaviour file."""

from __future__ import annotations

import pytest

from flctool.errors import ExportError
from flctool.export.fll import FllExporter, FllImporter
from flctool.export.imported import imported_yaml, quad_from_points

from .controllers import random_behaviour

WHERE = ("t.fcl", 4)


@pytest.mark.parametrize(("points", "quad"), [
    ([(1, 0), (2, 1), (3, 1), (4, 0)], (1, 2, 3, 4)),
    ([(1, 0), (2, 1), (4, 0)], (1, 2, 2, 4)),
    ([(1, 1), (3, 1), (4, 0)], (0, 0, 3, 4)),  # starts at 1: a shoulder from the low end
    ([(3, 1), (4, 0)], (0, 0, 3, 4)),
    ([(1, 0), (2, 1)], (1, 2, 10, 10)),  # ends at 1: a shoulder to the high end
    ([(1, 0), (1, 1), (3, 1), (3, 0)], (1, 1, 3, 3)),  # vertical edges inside the range
    ([(5, 0), (5, 1), (5, 0)], (5, 5, 5, 5)),
    ([(0, 1), (10, 1)], (0, 0, 10, 10)),
])
def test_points_to_quadruples(points: list[tuple[float, float]],
                              quad: tuple[float, ...]) -> None:
    assert quad_from_points([(float(x), float(y)) for x, y in points], (0.0, 10.0), WHERE,
                            "t") == quad


@pytest.mark.parametrize("points", [
    [(1, 0), (2, 0.5), (3, 0)], [(1, 0), (2, 1), (3, 0), (4, 1)], [(2, 0), (1, 1)], [],
])
def test_other_point_lists_are_refused(points: list[tuple[float, float]]) -> None:
    with pytest.raises(ExportError, match=r"t.fcl:4: term 't'"):
        quad_from_points(points, (0.0, 10.0), WHERE, "t")


def test_imported_file_has_no_learning_section() -> None:
    behaviour = FllImporter().from_string(FllExporter().to_string(random_behaviour(2)))
    text = imported_yaml(behaviour, "imported")
    assert text.startswith("# imported\nflctool: 1\n")
    assert "learning:" not in text and "environment:" not in text
    assert "rules:" in text
