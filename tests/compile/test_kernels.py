"""The compiled kernels give exactly what the plain eq. 1-3 give (bit for bit, not close).

Every fast path (batched output on both the all-rules and the fired-rules walk, one-state
output, dense activations, active rules) is compared with ``reference.py``'s loop over rules
on random controllers, at set breakpoints, vertical edges, out-of-range and infinite inputs.
"""

from __future__ import annotations

import itertools
import tracemalloc
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from flctool import compile_behaviour, load_behaviour
from flctool.behaviour import behaviour_from_data
from flctool.behaviour.checks import MAX_RULES
from flctool.compile import Controller, kernels
from flctool.errors import InferenceError
from flctool.membership import trapezoid_scalar

from .reference import combine, random_behaviour_data, reference_output

#: Eq. 2 as the paper's min and as the product (activation: product): every path must give
#: the reference's bits for both.
ACTIVATIONS = ["min", "product"]


def reference_activations(controller: Controller, state: np.ndarray) -> np.ndarray:
    """(M,) activations (eq. 2) by a loop over rules."""
    clipped = [min(max(float(s), lo), hi) for s, (lo, hi) in zip(state, controller.ranges,
                                                                  strict=True)]
    return np.array([
        combine(controller, [trapezoid_scalar(clipped[i], *controller.quadruples[i][j])
                             for i, j in enumerate(sets)])
        for sets in itertools.product(*(range(len(q)) for q in controller.quadruples))])


def awkward_states(controller: Controller, rng: np.random.Generator, count: int) -> np.ndarray:
    """Random states, plus every set breakpoint, out-of-range values and +-inf per input."""
    lo, hi = controller.ranges[:, 0], controller.ranges[:, 1]
    states = rng.uniform(lo - 0.3 * (hi - lo), hi + 0.3 * (hi - lo),
                         size=(count, controller.n_inputs))
    for i, quads in enumerate(controller.quadruples):
        special = np.concatenate([quads.ravel(), [-np.inf, np.inf, lo[i], hi[i]]])
        rows = rng.integers(0, count, size=len(special))
        states[rows, i] = special
    return states


def sparse_output(controller: Controller, states: np.ndarray, table: np.ndarray) -> np.ndarray:
    """kernels.infer forced onto the fired-rules walk (an empty grid), whatever M is."""
    layout = controller._layout
    tables = np.array(table, dtype=np.intp).reshape(-1, controller.n_rules)
    out = np.empty(tables.shape[0] * len(states))
    nan_state = kernels.infer(np.ascontiguousarray(states), layout.floats, layout.ints, tables,
                              out, 0, len(states), False)
    assert nan_state == -1
    return out.reshape(tables.shape[0], len(states))


def many_overlapping_sets() -> Controller:
    """Up to four sets of one input non-zero at once, with vertical edges inside the range."""
    data = {
        "flctool": 1, "name": "overlap",
        "inputs": {
            "a": {"range": [0, 10], "sets": {"wide": [0, 0, 10, 10], "mid": [1, 4, 6, 9],
                                             "step": [3, 3, 7, 7], "late": [5, 8, 10, 10],
                                             "tri": [0, 5, 5, 10]}},
            "b": {"range": [-1, 1], "sets": {"lo": [-1, -1, 0, 1], "hi": [-1, 0, 1, 1],
                                             "all": [-1, -1, 1, 1]}},
            "c": {"range": [0, 1], "sets": {"x": [0, 0, 0.5, 1], "y": [0, 0.5, 1, 1],
                                            "z": [0, 0.2, 0.2, 1]}},
        },
        "output": {"name": "u", "commands": {"p": -2.5, "q": 0.1, "r": 3.75}},
    }
    controller = compile_behaviour(behaviour_from_data(data))
    rng = np.random.default_rng(5)
    return controller.with_consequents(rng.integers(0, 3, size=controller.n_rules))


@pytest.mark.slow
@pytest.mark.parametrize("activation", ACTIVATIONS)
def test_fast_paths_equal_the_reference_exactly_on_random_controllers(activation: str) -> None:
    rng = np.random.default_rng(2024)
    for _ in range(40):
        controller = compile_behaviour(behaviour_from_data(
            random_behaviour_data(rng, activation=activation)))
        assert controller.product == (activation == "product")
        assert controller.consequents is not None
        states = awkward_states(controller, rng, 40)
        expected = np.array([reference_output(controller, s, controller.consequents)
                             for s in states])
        np.testing.assert_array_equal(controller.output(states), expected)
        np.testing.assert_array_equal(sparse_output(controller, states,
                                                    controller.consequents)[0], expected)
        np.testing.assert_array_equal([controller.output_one(s) for s in states], expected)
        dense = np.array([reference_activations(controller, s) for s in states])
        np.testing.assert_array_equal(controller.activations(states), dense)
        for state, row in zip(states, dense, strict=True):
            rules, alpha = controller.active_rules(state)
            assert rules.tolist() == np.nonzero(row)[0].tolist()
            np.testing.assert_array_equal(alpha, row[rules])


def test_many_overlapping_sets_per_input() -> None:
    controller = many_overlapping_sets()
    assert controller.consequents is not None
    rng = np.random.default_rng(9)
    states = awkward_states(controller, rng, 60)
    expected = np.array([reference_output(controller, s, controller.consequents)
                         for s in states])
    np.testing.assert_array_equal(controller.output(states), expected)
    np.testing.assert_array_equal(sparse_output(controller, states, controller.consequents)[0],
                                  expected)
    np.testing.assert_array_equal([controller.output_one(s) for s in states], expected)
    fired = [len(controller.active_rules(s)[0]) for s in states]
    assert max(fired) > 2 ** controller.n_inputs  # more than two sets per input fire


def test_populations_on_both_walks() -> None:
    rng = np.random.default_rng(17)
    for n_inputs in (2, 3):
        controller = compile_behaviour(behaviour_from_data(
            random_behaviour_data(rng, n_inputs, 4, rules=False)))
        population = rng.integers(0, 4, size=(5, controller.n_rules))
        states = awkward_states(controller, rng, 25)
        expected = np.array([[reference_output(controller, s, row) for s in states]
                             for row in population])
        np.testing.assert_array_equal(controller.output(states, population), expected)
        np.testing.assert_array_equal(sparse_output(controller, states, population), expected)


@pytest.mark.slow
def test_large_rule_base_never_makes_a_dense_batch_by_rules_array() -> None:
    # 6 inputs x 5 sets: M = 15,625; a (B, M) float array for B = 400 would be 50 MB.
    sets = {f"s{j}": [max(0.0, j - 1.0), j - 0.25, j + 0.25, min(4.0, j + 1.0)]
            for j in range(5)}
    sets["s0"][:2] = [0.0, 0.0]
    sets["s4"][2:] = [4.0, 4.0]
    data = {"flctool": 1, "name": "big",
            "inputs": {f"x{i}": {"range": [0, 4], "sets": sets} for i in range(6)},
            "output": {"name": "u", "commands": {"a": -1, "b": 0.5, "c": 2}}}
    learning = compile_behaviour(behaviour_from_data(data))
    rng = np.random.default_rng(1)
    controller = learning.with_consequents(rng.integers(0, 3, size=learning.n_rules))
    assert controller.consequents is not None
    states = rng.uniform(-0.5, 4.5, size=(400, 6))
    controller.output(states[:2])  # compile (or load) the kernels outside the measurement
    tracemalloc.start()
    values = controller.output(states)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    assert peak < 1_000_000
    for row in (0, 199, 399):
        assert values[row] == reference_output(controller, states[row], controller.consequents)


def test_one_state_inputs(handmade_path: Path) -> None:
    controller = compile_behaviour(load_behaviour(handmade_path))
    state = np.array([0.35, -12.5])
    expected = controller.output(state[None, :])[0]
    readonly = state.copy()
    readonly.setflags(write=False)
    for argument in (state, [0.35, -12.5], (0.35, -12.5), state[None, :], readonly,
                  np.array([[0.35, 0.0], [-12.5, 0.0]])[:, 0]):
        assert controller.output_one(argument) == expected
    with pytest.raises(InferenceError, match=r"shape \(B, 2\)"):
        controller.output_one([0.1, 0.2, 0.3])


def test_nan_raises_on_every_path(handmade_path: Path) -> None:
    controller = compile_behaviour(load_behaviour(handmade_path))
    states = np.array([[0.2, 0.0]] * 300 + [[np.nan, 0.0]])
    with pytest.raises(InferenceError, match="input 'ball_size' is NaN in state 300"):
        controller.output(states)
    with pytest.raises(InferenceError, match="input 'ball_size' is NaN in state 300"):
        controller.activations(states)
    with pytest.raises(InferenceError, match="input 'pan' is NaN in state 0"):
        controller.output_one([0.5, np.nan])
    with pytest.raises(InferenceError, match="input 'pan' is NaN in state 0"):
        controller.active_rules(np.array([0.5, np.nan]))


def test_with_consequents_shares_the_layout(handmade_path: Path) -> None:
    controller = compile_behaviour(load_behaviour(handmade_path))
    controller.output_one([0.5, 10.0])
    layout, rules = controller._layout, controller._rules  # what each path builds
    flipped = controller.with_consequents(4 - np.asarray(controller.consequents))
    assert flipped._layout is layout and flipped._rules is rules
    assert flipped.output_one([0.5, 10.0]) == -controller.output_one([0.5, 10.0])


def underflowing_controller(extra_sets: int) -> Controller:
    """Sets so far apart that both memberships of x = 5e-324 underflow to 0: valid on paper
    (the partition covers the range), but eq. 3 would be 0 / 0 there. A second input with
    ``extra_sets`` sets makes M large enough for the fired-rules walk."""
    y_sets = {f"y{j}": [max(0, j - 1), j, j, min(extra_sets - 1, j + 1)]
              for j in range(extra_sets)}
    data = {"flctool": 1, "name": "apart",
            "inputs": {"x": {"range": [-1e300, 1e300],
                             "sets": {"a": [-1e300, -1e300, -1e300, 1e-310],
                                      "b": [0, 1e300, 1e300, 1e300]}},
                       "y": {"range": [0, extra_sets - 1], "sets": y_sets}},
            "output": {"name": "u", "commands": {"l": -1, "r": 1}}}
    controller = compile_behaviour(behaviour_from_data(data))
    return controller.with_consequents(np.arange(controller.n_rules) % 2)


@pytest.mark.parametrize("extra_sets", [2, 17])  # M = 4, M = 34
def test_no_rule_firing_raises_instead_of_giving_nan(extra_sets: int) -> None:
    controller = underflowing_controller(extra_sets)
    fine = np.array([[1.0, 0.5], [-1.0, 0.5]])
    states = np.vstack([np.tile(fine, (20, 1)), [[5e-324, 0.5]]])  # state 40, second block
    with pytest.raises(InferenceError, match=r"no rule fires for state 40: the sets overlap "
                                             r"too little.*widen their overlap"):
        controller.output(states)
    with pytest.raises(InferenceError, match="no rule fires for state 0"):
        controller.output_one([5e-324, 0.5])
    rules, alpha = controller.active_rules(np.array([5e-324, 0.5]))
    assert rules.shape == alpha.shape == (0,)
    assert not controller.activations(states[40:]).any()
    # Elsewhere nothing changes: the same values as the plain eq. 1-3, bit for bit.
    assert controller.consequents is not None
    np.testing.assert_array_equal(controller.output(fine), [reference_output(
        controller, s, controller.consequents) for s in fine])
    # Both walks (and the state-by-state path of small batches) report the state rather
    # than write NaN.
    with pytest.raises(InferenceError, match="no rule fires for state 1"):
        controller.output(states[39:41])
    layout = controller._layout
    out = np.empty(len(states))
    table = np.array(controller.consequents, dtype=np.intp)[None, :]
    for dense in (True, False):
        assert kernels.infer(states, layout.floats, layout.ints, table, out, 0, len(states),
                             dense) == 40


def both_walks(controller: Controller, states: np.ndarray, tables: np.ndarray) -> list:
    """kernels.infer on the every-rule walk (a layout that keeps the rule grid whatever M is)
    and on the fired-rules walk, for ``tables (P, M)``: two (P, B) arrays."""
    layout = kernels.layout(controller.ranges, controller.quadruples, controller.rule_grid,
                            controller.singletons, controller.kinds, controller.product)
    with_grid = kernels.keep_grid(layout, controller.rule_grid)
    results = []
    for chosen, dense in ((with_grid, True), (layout, False)):
        out = np.empty(tables.shape[0] * len(states))
        assert kernels.infer(states, chosen.floats, chosen.ints, tables, out, 0, len(states),
                             dense) == -1
        results.append(out.reshape(tables.shape[0], len(states)))
    return results


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n_inputs=st.integers(1, 4),
       batch=st.sampled_from([1, 2, kernels.SMALL_DENSE_BATCH, kernels.SMALL_DENSE_BATCH + 1,
                               kernels.SMALL_BATCH, kernels.SMALL_BATCH + 1,
                               kernels.OWN_SMALL_BATCH_FEW_INPUTS,
                               kernels.OWN_SMALL_BATCH_FEW_INPUTS + 1, 63, 64, 65, 130]),
       population=st.integers(1, 3), activation=st.sampled_from(ACTIVATIONS))
@pytest.mark.slow
def test_every_path_equals_the_reference(seed: int, n_inputs: int, batch: int,
                                         population: int, activation: str) -> None:
    """Small batches (state by state), blocks on both walks, strided states, populations
    and one-state calls: all give the plain eq. 1-3 bit for bit, eq. 2 the min or the
    product."""
    rng = np.random.default_rng(seed)
    controller = compile_behaviour(behaviour_from_data(
        random_behaviour_data(rng, n_inputs, rules=False, activation=activation)))
    tables = rng.integers(0, controller.n_commands, size=(population, controller.n_rules))
    states = awkward_states(controller, rng, batch)
    expected = np.array([[reference_output(controller, s, row) for s in states]
                         for row in tables])
    for walked in both_walks(controller, states, tables):
        np.testing.assert_array_equal(walked, expected)
    np.testing.assert_array_equal(controller.output(states, tables), expected)
    strided = np.asfortranarray(states)  # read through its strides, not copied
    np.testing.assert_array_equal(controller.output(strided, tables), expected)
    deployed = controller.with_consequents(tables[0])
    np.testing.assert_array_equal(deployed.output(states), expected[0])
    np.testing.assert_array_equal([deployed.output_one(s) for s in states], expected[0])


@pytest.mark.parametrize("activation", ACTIVATIONS)
@pytest.mark.parametrize("n_inputs", [1, 2, 3, 4])
def test_own_consequents_entry_on_both_sides_of_its_switch(n_inputs: int,
                                                           activation: str) -> None:
    """Controller.output without a population goes to kernels.infer_own: state by state up
    to its switch, in blocks past it (on the walk of every rule and on the fired rules'),
    bit for bit the plain eq. 1-3, output_one and the population entry (kernels.infer)."""
    rng = np.random.default_rng(40 + n_inputs)
    switch = (kernels.OWN_SMALL_BATCH_FEW_INPUTS if n_inputs <= 2
              else kernels.OWN_SMALL_BATCH)
    for _ in range(6):
        controller = compile_behaviour(behaviour_from_data(
            random_behaviour_data(rng, n_inputs, rules=False, activation=activation)))
        controller = controller.with_consequents(
            rng.integers(0, controller.n_commands, size=controller.n_rules))
        assert controller.consequents is not None
        for batch in (1, 2, switch - 1, switch, switch + 1, 70):
            states = awkward_states(controller, rng, batch)
            expected = [reference_output(controller, s, controller.consequents)
                        for s in states]
            output = controller.output(states)
            np.testing.assert_array_equal(output, expected)
            np.testing.assert_array_equal(controller.output(states, controller.consequents),
                                          expected)
            np.testing.assert_array_equal(sparse_output(controller, states,
                                                        controller.consequents)[0], expected)
            np.testing.assert_array_equal([controller.output_one(s) for s in states],
                                          expected)
            np.testing.assert_array_equal(controller.output(np.asfortranarray(states)),
                                          expected)


@pytest.mark.slow
def test_own_consequents_entry_on_the_fired_rules_walk() -> None:
    # 4 inputs x 5 sets (M = 625): past the switch, infer_own's blocks walk the fired rules.
    sets = {f"s{j}": [max(0.0, j - 1.0), j - 0.25, j + 0.25, min(4.0, j + 1.0)]
            for j in range(5)}
    sets["s0"][:2] = [0.0, 0.0]
    sets["s4"][2:] = [4.0, 4.0]
    data = {"flctool": 1, "name": "sparse",
            "inputs": {f"x{i}": {"range": [0, 4], "sets": sets} for i in range(4)},
            "output": {"name": "u", "commands": {"a": -1, "b": 0.5, "c": 2}}}
    rng = np.random.default_rng(8)
    learning = compile_behaviour(behaviour_from_data(data))
    controller = learning.with_consequents(rng.integers(0, 3, size=learning.n_rules))
    assert controller.consequents is not None and not controller._layout.dense
    for batch in (kernels.OWN_SMALL_BATCH, kernels.OWN_SMALL_BATCH + 1, 70):
        states = awkward_states(controller, rng, batch)
        expected = [reference_output(controller, s, controller.consequents) for s in states]
        np.testing.assert_array_equal(controller.output(states), expected)


@pytest.mark.parametrize("batch", [3, kernels.OWN_SMALL_BATCH_FEW_INPUTS + 1])
def test_own_consequents_entry_reports_nan(handmade_path: Path, batch: int) -> None:
    controller = compile_behaviour(load_behaviour(handmade_path))
    states = np.full((batch, 2), 0.2)
    states[batch - 1, 1] = np.nan
    with pytest.raises(InferenceError, match=f"input 'pan' is NaN in state {batch - 1}"):
        controller.output(states)
    layout = controller._layout
    ints = np.concatenate([layout.ints, controller.require_consequents()])
    assert kernels.infer_own(layout.floats, ints, states, np.empty(batch)) == batch - 1


def test_threads_give_identical_outputs(handmade_path: Path) -> None:
    from flctool.compile.controller import THREADED_STATES

    controller = compile_behaviour(load_behaviour(handmade_path))
    rng = np.random.default_rng(3)
    states = awkward_states(controller, rng, THREADED_STATES + 77)
    one = controller.output(states)
    np.testing.assert_array_equal(controller.output(states, threads=2), one)
    np.testing.assert_array_equal(controller.output(states, threads=3), one)
    population = rng.integers(0, controller.n_commands, size=(2, controller.n_rules))
    np.testing.assert_array_equal(controller.output(states, population, threads=2),
                                  controller.output(states, population))
    states[THREADED_STATES + 5, 1] = np.nan  # in the second thread's part
    with pytest.raises(InferenceError, match=f"NaN in state {THREADED_STATES + 5}"):
        controller.output(states, threads=2)


def test_the_walks_switch_where_their_costs_cross() -> None:
    # Two inputs of 5 or 6 sets (M = 25, 36) walk every rule, as does any small rule base;
    # six inputs of five sets (M = 15,625) walk only the fired rules.
    assert kernels.walks_every_rule(25, 2, 10) and kernels.walks_every_rule(36, 2, 12)
    assert kernels.walks_every_rule(3, 1, 3)
    assert not kernels.walks_every_rule(15_625, 6, 30)


def test_the_walk_choice_is_measured_for_every_size_it_decides() -> None:
    # The cost model's per-state costs are tabulated (measured) for every N up to 8, and for
    # each N the walk changes at most once as the sets grow: every rule for small bases,
    # each state's fired rules past the switch, never back (no size where the model, read
    # between its measurements, flips).
    assert len(kernels._SPARSE_NS_BY_INPUTS) > 8
    for n_inputs in range(1, 9):
        choices = [kernels.walks_every_rule(n_sets ** n_inputs, n_inputs, n_sets * n_inputs)
                   for n_sets in range(2, 10) if n_sets ** n_inputs <= MAX_RULES]
        assert choices[0], n_inputs  # two sets an input: every rule
        switches = sum(a != b for a, b in itertools.pairwise(choices))
        assert switches <= 1 and (switches == 0 or not choices[-1]), (n_inputs, choices)
    # the sizes issue 29 found on the wrong walk
    assert not kernels.walks_every_rule(3 ** 6, 6, 18)
    assert kernels.walks_every_rule(7 ** 3, 3, 21)


def strong_partition_controller(n_inputs: int, n_sets: int, seed: int,
                                activation: str = "min") -> Controller:
    """N inputs on [0, 1] of L trapezoids whose slopes overlap their neighbours' (at most
    two sets of an input fire), with random consequents; eq. 2 is ``activation``."""
    step = 1.0 / (n_sets - 1)
    sets = {}
    for j in range(n_sets):
        quad = [j * step - step, j * step - 0.2 * step, j * step + 0.2 * step, j * step + step]
        if j == 0:
            quad[:2] = [0.0, 0.0]
        if j == n_sets - 1:
            quad[2:] = [1.0, 1.0]
        sets[f"s{j}"] = quad
    data = {"flctool": 1, "name": "strong",
            "inputs": {f"x{i}": {"range": [0, 1], "sets": sets} for i in range(n_inputs)},
            "output": {"name": "u", "commands": {"a": -1, "b": 0.5, "c": 2}},
            "activation": activation}
    learning = compile_behaviour(behaviour_from_data(data))
    rng = np.random.default_rng(seed)
    return learning.with_consequents(rng.integers(0, 3, size=learning.n_rules))


def test_fired_rules_bound_counts_the_sets_that_overlap() -> None:
    # Two sets of [0, 1] fire together everywhere inside it: every rule fires (M = 2^N).
    two = strong_partition_controller(6, 2, seed=1)
    assert kernels.fired_rules_bound(two.ranges, two.quadruples, two.kinds) == 64
    # Neighbours overlap, never three at once: 2^N of the 5^N rules.
    five = strong_partition_controller(3, 5, seed=1)
    assert kernels.fired_rules_bound(five.ranges, five.quadruples, five.kinds) == 8
    # many_overlapping_sets: at some point of each input every one of its sets fires (5, 3
    # and 3 sets), so every rule can fire at once.
    many = many_overlapping_sets()
    assert kernels.fired_rules_bound(many.ranges, many.quadruples, many.kinds) == 45
    assert many.n_rules == 45


@pytest.mark.slow
@pytest.mark.parametrize("activation", ACTIVATIONS)
def test_a_few_states_of_bases_where_every_rule_fires_walk_them_four_at_a_time(
        activation: str) -> None:
    # 6 x 2 and 8 x 2 sets (every rule fires) take the interleaved walk of every rule for up
    # to OWN_SMALL_BATCH_FEW_INPUTS states; 3 x 6 (8 of 216 rules fire) the fired rules'.
    assert not strong_partition_controller(3, 6, seed=2)._layout.ints[4]
    rng = np.random.default_rng(12)
    for n_inputs in (6, 8):
        controller = strong_partition_controller(n_inputs, 2, seed=n_inputs,
                                                 activation=activation)
        assert controller._layout.ints[4] == kernels.EVERY_RULE_FIRES
        assert controller.consequents is not None
        for batch in (1, 2, 3, 4, 5, 7, kernels.OWN_SMALL_BATCH_FEW_INPUTS):
            states = awkward_states(controller, rng, batch)
            expected = [reference_output(controller, s, controller.consequents)
                        for s in states]
            np.testing.assert_array_equal(controller.output(states), expected)
            np.testing.assert_array_equal(controller.output(np.asfortranarray(states)),
                                          expected)
        states = np.full((5, n_inputs), 0.3)
        states[3, 2] = np.nan
        with pytest.raises(InferenceError, match="input 'x2' is NaN in state 3"):
            controller.output(states)


@pytest.mark.parametrize(("n_inputs", "n_sets"), [(4, 3), (5, 3), (7, 2)])
def test_a_few_states_of_larger_bases_walk_every_rule_as_two_halves(n_inputs: int,
                                                                    n_sets: int) -> None:
    # From SPLIT_RULE_INPUTS rule-inputs the interleaved walk takes each rule's alpha as the
    # min of its two halves' (kernels._halves_sums): one state alone, four at a time, and a
    # last group of two or three, all the reference's bits. With 3 sets an input few of the
    # rules fire, and one or two states walk those instead (FEW_STATES_FIRED).
    controller = strong_partition_controller(n_inputs, n_sets, seed=n_inputs)
    assert controller._layout.ints[4] == (kernels.EVERY_RULE_FIRES if n_sets == 2 else 1)
    assert controller.consequents is not None
    assert controller.n_rules * n_inputs >= kernels.SPLIT_RULE_INPUTS
    rng = np.random.default_rng(n_inputs * 10 + n_sets)
    for batch in (1, 2, 3, 4, 5, 6, 7, kernels.INTERLEAVED_HALVES_STATES,
                  kernels.INTERLEAVED_HALVES_STATES + 1):
        states = awkward_states(controller, rng, batch)
        expected = [reference_output(controller, s, controller.consequents) for s in states]
        np.testing.assert_array_equal(controller.output(states), expected)
    states = np.full((6, n_inputs), 0.4)
    states[5, 1] = np.nan
    with pytest.raises(InferenceError, match="input 'x1' is NaN in state 5"):
        controller.output(states)


def test_a_few_states_of_small_bases_of_three_inputs_or_more_walk_every_rule() -> None:
    # 3 x 2 sets (24 rule-inputs): every rule four states at a time up to INTERLEAVED_STATES,
    # blocks past it; the same bits on both sides.
    controller = strong_partition_controller(3, 2, seed=3)
    assert controller._layout.ints[4] and controller.consequents is not None
    assert controller.n_rules * 3 < kernels.SPLIT_RULE_INPUTS
    rng = np.random.default_rng(32)
    for batch in (1, 5, kernels.INTERLEAVED_STATES, kernels.INTERLEAVED_STATES + 1):
        states = awkward_states(controller, rng, batch)
        expected = [reference_output(controller, s, controller.consequents) for s in states]
        np.testing.assert_array_equal(controller.output(states), expected)


@pytest.mark.parametrize(("n_inputs", "n_sets"), [(1, 4), (2, 4), (2, 6)])
def test_small_bases_of_one_or_two_inputs_walk_every_rule_from_a_few_states(
        n_inputs: int, n_sets: int) -> None:
    # State by state below TINY_FROM states, then every rule four at a time: up to
    # TINY_BATCH states for 1 x 4 and 2 x 4 sets, up to OWN_SMALL_BATCH_FEW_INPUTS for 2 x 6
    # (M = 36), blocks past them; the same bits on every side.
    controller = strong_partition_controller(n_inputs, n_sets, seed=n_inputs)
    assert controller.consequents is not None
    rng = np.random.default_rng(n_inputs)
    for batch in (1, kernels.TINY_FROM - 1, kernels.TINY_FROM, 8,
                  kernels.OWN_SMALL_BATCH_FEW_INPUTS, kernels.OWN_SMALL_BATCH_FEW_INPUTS + 1,
                  kernels.TINY_BATCH, kernels.TINY_BATCH + 1):
        states = awkward_states(controller, rng, batch)
        expected = [reference_output(controller, s, controller.consequents) for s in states]
        np.testing.assert_array_equal(controller.output(states), expected)
