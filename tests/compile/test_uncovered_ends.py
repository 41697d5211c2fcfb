"""A range end that no set fires, but a set rises from (fuzzylite's and MATLAB's examples
write ``Triangle 0 0.25 0.5`` on ``[0, 1]``): the controller evaluates the input there an
END_MARGIN of the range inside, so it is defined everywhere and continuous at the end."""

from __future__ import annotations

import numpy as np
import pytest

from flctool import compile_behaviour, with_rules
from flctool.behaviour import Behaviour, behaviour_from_data
from flctool.behaviour.shapes import END_MARGIN, evaluated_range
from flctool.compile.sparse import SparseRules
from flctool.errors import SpecError


def dimmer(dark: list[float], bright: list[float]) -> Behaviour:
    behaviour = behaviour_from_data({
        "flctool": 1, "name": "dimmer",
        "inputs": {"ambient": {"range": [0.0, 2.0], "sets": {
            "dark": dark, "medium": [0.5, 1.0, 1.0, 1.5], "bright": bright}}},
        "output": {"name": "power", "commands": {"high": 0.75, "mid": 0.5, "low": 0.25}}})
    return with_rules(behaviour, np.array([0, 1, 2]))


def test_an_end_no_set_fires_is_evaluated_just_inside() -> None:
    behaviour = dimmer([0.0, 0.5, 0.5, 1.0], [1.0, 1.5, 1.5, 2.0])
    step = 2.0 * END_MARGIN
    assert evaluated_range((0.0, 2.0), behaviour.inputs["ambient"].sets.values()) == (
        step, 2.0 - step)
    controller = compile_behaviour(behaviour)
    ends = np.array([[0.0], [2.0], [-1.0], [3.0]])
    # only 'dark' (then 'bright') fires next to each end, so the limit there is its command
    assert controller.output(ends).tolist() == [0.75, 0.25, 0.75, 0.25]
    inside = np.array([[0.3], [1.2]])
    assert controller.output(inside).tolist() == pytest.approx([0.75, 0.39999999999999997])
    sparse = SparseRules.from_behaviour(behaviour)
    rules, alphas, _ = sparse.activations([0.0])
    assert sparse.output(alphas, [int(controller.consequents[r]) for r in rules]) == 0.75


def test_an_end_a_set_fires_keeps_its_range() -> None:
    behaviour = dimmer([0.0, 0.0, 0.5, 1.0], [1.0, 1.5, 2.0, 2.0])  # shoulders: 1 at the ends
    assert compile_behaviour(behaviour).ranges.tolist() == [[0.0, 2.0]]


def test_a_gap_wider_than_the_end_point_is_still_refused() -> None:
    with pytest.raises(SpecError, match=r"the values between 0 and 0\.1 belong to no set"):
        dimmer([0.1, 0.5, 0.5, 1.0], [1.0, 1.5, 1.5, 2.0])
