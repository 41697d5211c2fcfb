"""Numbers of an environment section that would overflow a simulation are refused at their
line; every number within the bound simulates without NaN (each field pushed to the bound)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from flctool import parse_behaviour
from flctool.behaviour import behaviour_to_data, load_behaviour
from flctool.behaviour.dump import data_to_yaml
from flctool.behaviour.magnitudes import MAX_MAGNITUDE
from flctool.errors import FlcError, SpecError
from flctool.evaluation import evaluate_behaviour

from ..conftest import BEHAVIOURS


def test_a_motion_table_entry_of_1e308_is_refused_at_its_line() -> None:
    text = (BEHAVIOURS / "ballchase-handmade.yaml").read_text().replace(
        "  adapter: ballchase-sim\n",
        "  adapter: ballchase-sim\n  motion:\n    forward: {forward: 1e308, sideways: 0, "
        "rotation: 0}\n  noise:\n    turn_left: {forward: 1, sideways: 1, rotation: -1e300}\n")
    with pytest.raises(SpecError) as info:
        parse_behaviour(text, "b.yaml")
    found = {(p.path, p.line) for p in info.value.problems}
    lines = text.splitlines()
    motion = next(i for i, line in enumerate(lines, 1) if "forward: {forward: 1e308" in line)
    assert (("environment", "motion", "forward", "forward"), motion) in found
    messages = " ".join(p.message for p in info.value.problems)
    assert "1e+308 is too large for a simulation" in messages


def _float_paths(data: Any, path: tuple[Any, ...]) -> list[tuple[Any, ...]]:
    if isinstance(data, dict):
        return [p for k, v in data.items() for p in _float_paths(v, (*path, k))]
    if isinstance(data, list):
        return [p for i, v in enumerate(data) for p in _float_paths(v, (*path, i))]
    return [path] if isinstance(data, float) else []


def _set(data: dict[str, Any], path: tuple[Any, ...], value: float) -> None:
    for part in path[:-1]:
        data = data[part]
    data[path[-1]] = value


@pytest.mark.parametrize("name", [
    "ballchase-handmade",
    pytest.param("avoid-obstacle-handmade", marks=pytest.mark.slow),  # the pitch: 20 s
])
@pytest.mark.slow
def test_every_environment_number_at_the_bound_simulates_without_nan(name: str) -> None:
    behaviour = load_behaviour(BEHAVIOURS / f"{name}.yaml")
    base = behaviour_to_data(behaviour)
    base["environment"]["max_steps"] = 10
    paths = _float_paths(base["environment"], ("environment",))
    assert len(paths) > 10
    for path in paths:
        for value in (MAX_MAGNITUDE, -MAX_MAGNITUDE, math.nextafter(MAX_MAGNITUDE, math.inf)):
            data = behaviour_to_data(behaviour)
            data["environment"]["max_steps"] = 10
            _set(data, path, value)
            try:
                changed = parse_behaviour(data_to_yaml(data), "b.yaml")
            except SpecError as error:  # refused: always at a line
                assert all(p.line is not None for p in error.problems), str(error)
                assert value != MAX_MAGNITUDE or any(
                    "too large" not in p.message for p in error.problems)
                continue
            assert abs(value) <= MAX_MAGNITUDE, path  # past the bound: never accepted
            try:
                result = evaluate_behaviour(changed, episodes=2).result
            except FlcError as error:  # e.g. a start the pitch cannot hold
                assert "NaN" not in str(error), (path, value, str(error))
                continue
            assert np.isfinite(result.fitness).all(), (path, value)
