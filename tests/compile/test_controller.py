"""Compiling behaviours and inference (eq. 1-3) against a plain loop-over-rules reference."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from flctool import compile_behaviour, load_behaviour, with_rules
from flctool.behaviour import behaviour_from_data, parse_behaviour
from flctool.errors import InferenceError, NotDeployableError

from .reference import random_behaviour_data, reference_output


def test_rule_grid_order_last_input_fastest(handmade_path: Path) -> None:
    controller = compile_behaviour(load_behaviour(handmade_path))
    assert controller.shape == (3, 5)
    assert controller.rule_grid.shape == (15, 2)
    assert controller.rule_grid[:7].tolist() == [[0, 0], [0, 1], [0, 2], [0, 3], [0, 4],
                                                 [1, 0], [1, 1]]
    assert [q.shape for q in controller.quadruples] == [(3, 4), (5, 4)]
    assert controller.singletons.tolist() == [-1.0, -0.5, 0.0, 0.5, 1.0]
    # rule 12 = (large, ahead) -> forward; rule 0 = (small, far_right) -> turn_right
    assert controller.consequents is not None
    assert controller.command_names[controller.consequents[12]] == "forward"
    assert controller.command_names[controller.consequents[0]] == "turn_right"


def test_arrays_are_frozen(handmade_path: Path) -> None:
    controller = compile_behaviour(load_behaviour(handmade_path))
    with pytest.raises(ValueError, match="read-only"):
        controller.singletons[0] = 5.0


def test_output_equals_loop_over_rules_on_random_controllers() -> None:
    rng = np.random.default_rng(7)
    for _ in range(60):
        controller = compile_behaviour(behaviour_from_data(random_behaviour_data(rng)))
        lo, hi = controller.ranges[:, 0], controller.ranges[:, 1]
        states = rng.uniform(lo - 0.2 * (hi - lo), hi + 0.2 * (hi - lo),
                             size=(50, controller.n_inputs))
        assert controller.consequents is not None
        expected = [reference_output(controller, s, controller.consequents) for s in states]
        np.testing.assert_allclose(controller.output(states), expected, rtol=0, atol=1e-12)


@pytest.mark.slow
def test_one_state_gives_the_bits_of_a_batch() -> None:
    # output of one state takes the one-state kernel: the same bits as in a batch, strided too
    rng = np.random.default_rng(11)
    for _ in range(20):
        controller = compile_behaviour(behaviour_from_data(random_behaviour_data(rng)))
        lo, hi = controller.ranges[:, 0], controller.ranges[:, 1]
        states = rng.uniform(lo - 0.2 * (hi - lo), hi + 0.2 * (hi - lo),
                             size=(200, controller.n_inputs))
        whole = controller.output(states)
        ones = [controller.output(states[i:i + 1]) for i in range(len(states))]
        assert all(one.shape == (1,) and one.dtype == np.float64 for one in ones)
        assert np.concatenate(ones).tobytes() == whole.tobytes()
        wide = np.repeat(states, 2, axis=1)[:, ::2]  # (B, N), not contiguous
        assert controller.output(wide[:1]).tobytes() == whole[:1].tobytes()


def test_population_of_consequents() -> None:
    rng = np.random.default_rng(3)
    controller = compile_behaviour(behaviour_from_data(random_behaviour_data(rng, 2, 4)))
    population = rng.integers(0, 4, size=(6, controller.n_rules))
    states = rng.uniform(controller.ranges[:, 0], controller.ranges[:, 1], size=(30, 2))
    outputs = controller.output(states, population)
    assert outputs.shape == (6, 30)
    for p, row in enumerate(population):
        np.testing.assert_allclose(outputs[p], controller.output(states, row), atol=1e-12)


def test_activations_and_active_rules_agree() -> None:
    rng = np.random.default_rng(11)
    for _ in range(20):
        controller = compile_behaviour(behaviour_from_data(random_behaviour_data(rng)))
        states = rng.uniform(controller.ranges[:, 0], controller.ranges[:, 1],
                             size=(20, controller.n_inputs))
        dense = controller.activations(states)
        assert dense.shape == (20, controller.n_rules)
        for row, state in zip(dense, states, strict=True):
            rules, alpha = controller.active_rules(state)
            assert rules.tolist() == np.nonzero(row)[0].tolist()
            np.testing.assert_array_equal(alpha, row[rules])


def test_out_of_range_and_infinite_inputs_are_clipped(handmade_path: Path) -> None:
    controller = compile_behaviour(load_behaviour(handmade_path))
    outside = controller.output(np.array([[5.0, -400.0], [-np.inf, np.inf]]))
    at_ends = controller.output(np.array([[1.0, -90.0], [0.0, 90.0]]))
    np.testing.assert_array_equal(outside, at_ends)


def test_nan_input_is_a_clear_error(handmade_path: Path) -> None:
    controller = compile_behaviour(load_behaviour(handmade_path))
    with pytest.raises(InferenceError, match="input 'pan' is NaN in state 1"):
        controller.output(np.array([[0.2, 0.0], [0.2, np.nan]]))
    with pytest.raises(InferenceError, match="input 'pan' is NaN in state 0"):
        controller.output(np.array([[0.2, np.nan]]))


def test_wrong_shapes_and_missing_consequents(minimal_text: str) -> None:
    controller = compile_behaviour(parse_behaviour(minimal_text))
    with pytest.raises(InferenceError, match=r"shape \(B, 1\)"):
        controller.output(np.zeros((3, 2)))
    with pytest.raises(InferenceError, match="command indices"):
        controller.output(np.zeros((3, 1)), np.array([0, 2]))
    learning = compile_behaviour(parse_behaviour(minimal_text.split("rules:")[0]))
    assert learning.consequents is None
    for batch in (1, 3, 40):  # state by state and in blocks
        with pytest.raises(NotDeployableError, match="not deployable"):
            learning.output(np.zeros((batch, 1)))
    with pytest.raises(NotDeployableError, match="not deployable"):
        learning.output_one(np.zeros(1))
    # Given consequents, it infers.
    assert learning.output(np.zeros((3, 1)), np.zeros(learning.n_rules, np.intp)).shape == (3,)


def test_with_rules_round_trips(handmade_path: Path) -> None:
    behaviour = load_behaviour(handmade_path)
    controller = compile_behaviour(behaviour)
    assert controller.consequents is not None
    empty = behaviour.model_copy(update={"rules": []})
    rebuilt = compile_behaviour(with_rules(empty, controller.consequents))
    assert rebuilt.consequents is not None
    assert rebuilt.consequents.tolist() == controller.consequents.tolist()


_finite = st.floats(allow_nan=False, allow_infinity=False, width=64)


@settings(max_examples=300, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), x=st.lists(_finite, min_size=3, max_size=3))
@pytest.mark.slow
def test_output_stays_within_the_singletons(seed: int, x: list[float]) -> None:
    rng = np.random.default_rng(seed)
    controller = compile_behaviour(behaviour_from_data(random_behaviour_data(rng, 3)))
    value = controller.output(np.array([x]))[0]
    assert controller.singletons.min() <= value <= controller.singletons.max()
    assert controller.output_one(np.array(x)) == value


def test_rounding_never_steps_past_the_singletons() -> None:
    # With one command, sum(alpha * c) / sum(alpha) is c only up to rounding (an ulp above or
    # below for most of these states); the output is that command exactly.
    for seed in range(3):
        rng = np.random.default_rng(seed)
        controller = compile_behaviour(behaviour_from_data(
            random_behaviour_data(rng, 3, n_commands=1)))
        states = rng.uniform(controller.ranges[:, 0], controller.ranges[:, 1], size=(50, 3))
        assert (controller.output(states) == controller.singletons[0]).all()
        assert all(controller.output_one(s) == controller.singletons[0] for s in states)
