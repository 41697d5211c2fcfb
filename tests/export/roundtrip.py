"""Helpers of the round-trip tests: which behaviours ship complete, and 'the same controller'."""

from __future__ import annotations

import numpy as np

from flctool import compile_behaviour, load_behaviour
from flctool.behaviour import Behaviour

from ..conftest import BEHAVIOURS

#: Every shipped behaviour with a complete rule table (the golden round trips run on each).
# ballchase-handmade first: tests take SHIPPED[0] as the two-input example (ball_size, pan)
SHIPPED = sorted((p for p in BEHAVIOURS.glob("*.yaml") if load_behaviour(p).is_deployable),
                 key=lambda p: (p.name != "ballchase-handmade.yaml", p.name))


def assert_same_controller(got: Behaviour, want: Behaviour, states: np.ndarray) -> None:
    """Same names, the same arrays, and bit-for-bit the same outputs."""
    a, b = compile_behaviour(got), compile_behaviour(want)
    assert a.input_names == b.input_names
    assert a.set_names == b.set_names
    assert a.output_name == b.output_name
    assert a.command_names == b.command_names
    assert a.product == b.product
    assert np.array_equal(a.ranges, b.ranges)
    for qa, qb in zip(a.quadruples, b.quadruples, strict=True):
        assert np.array_equal(qa, qb)
    assert np.array_equal(a.singletons, b.singletons)
    assert a.consequents is not None and b.consequents is not None
    assert np.array_equal(a.consequents, b.consequents)
    assert np.array_equal(a.output(states), b.output(states))
