"""The one checkpoint model: a learner's own state reads back whole; hostile files are refused
with one clear error, never a traceback."""

from __future__ import annotations

import json
from functools import cache
from typing import Any

import numpy as np
import pytest

from flctool.errors import LearnError
from flctool.learners import make_learner, train
from flctool.learners.checkpoint import Expected, read_checkpoint
from tests.learners.line_env import LineEnv, line_behaviour


@cache
def _trained() -> str:
    learner = make_learner(line_behaviour(learner="fuzzy_q"), LineEnv())
    train(learner)
    return json.dumps(learner.state_dict())


def _state() -> dict[str, Any]:
    """A trained learner's state, as a checkpoint file holds it (a fresh copy each call)."""
    state: dict[str, Any] = json.loads(_trained())
    return state


EXPECTED = Expected(3, 3, learner="fuzzy_q", strengths=True)


def test_a_learners_state_reads_back_as_typed_arrays() -> None:
    state = _state()
    checkpoint = read_checkpoint(state, EXPECTED)
    assert checkpoint.population.dtype == np.intp and checkpoint.population.shape[1] == 3
    assert checkpoint.q is not None and checkpoint.q.tolist() == state["q"]
    assert checkpoint.traces is not None and checkpoint.traces.shape == (3, 3)
    assert checkpoint.selection is not None
    assert [c.to_dict() for c in checkpoint.selection.hall] == state["selection"]["hall"]
    assert checkpoint.rng == state["rng"] and checkpoint.metrics is None


def _deep(depth: int) -> Any:
    value: Any = 1
    for _ in range(depth):
        value = {"a": value}
    return value


@pytest.mark.parametrize(("change", "message"), [
    ({"rng": {"ga": _deep(6), "env": {}, "explore": {}}}, "nested too deep"),
    ({"rng": {"ga": {str(i): i for i in range(20)}, "env": {}, "explore": {}}},
     "too many fields"),
    ({"rng": {"ga": {"state": 1.5}, "env": {}, "explore": {}}}, "hold a float"),
    ({"rng": [1, 2]}, "not a small object"),
    ({"population": "0,1,2"}, "its 'population' is not a table of whole numbers"),
    ({"population": [[True, False, True]]}, "not a table of whole numbers"),
    ({"population": []}, r"population has shape \(0,\)"),
    ({"q": [["a"] * 3] * 3}, "its 'q' is not a table of numbers"),
    ({"traces": [[1e400] * 3] * 3}, "its 'traces' holds NaN or infinity"),
    ({"learner": 3}, "is of learner '3', not 'fuzzy_q'"),
    ({"elapsed": True}, "'elapsed' is not a finite number"),
    ({"generation": 2**70}, "'generation' is not a generation number"),
    ({"selection": {"hall": "?"}}, "selection record is damaged"),
    ({"selection": []}, "selection record is damaged"),
])
def test_hostile_fields_are_refused_with_the_damage_named(change: dict[str, Any],
                                                          message: str) -> None:
    with pytest.raises(LearnError, match=message) as caught:
        read_checkpoint({**_state(), **change}, EXPECTED)
    assert "delete the damaged checkpoint" in caught.value.hint or "learner" in str(caught.value)


def test_a_run_directorys_checkpoint_holds_its_generations_metrics() -> None:
    state = _state()
    with pytest.raises(LearnError, match="has no 'metrics'"):
        read_checkpoint(state, Expected(3, 3, metrics=True))
    with pytest.raises(LearnError, match="is of generation"):
        read_checkpoint(state, Expected(3, 3, generation=state["generation"] + 1))
    with pytest.raises(LearnError, match="more than the run's population of 1"):
        read_checkpoint({**state, "population": state["population"] * 2,
                         "fitness": state["fitness"] * 2}, Expected(3, 3, max_population=1))
