"""The shared trial loop and its plain-Python rule firing."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from flctool import compile_behaviour, load_behaviour
from flctool.errors import InferenceError
from flctool.learners.fuzzy_q import FuzzyQ
from flctool.learners.trial import SparseRules, add_in_order, run_trial
from tests.conftest import BEHAVIOURS
from tests.learners.line_env import LineEnv, line_behaviour

BALLCHASE = compile_behaviour(load_behaviour(BEHAVIOURS / "ballchase-handmade.yaml"))
SPARSE = SparseRules(BALLCHASE)


@settings(max_examples=200, deadline=None)
@given(st.floats(-0.2, 1.2), st.floats(-120.0, 120.0))
def test_fire_equals_controller_active_rules(size: float, pan: float) -> None:
    rules, alphas, phi = SPARSE.fire([size, pan])
    expected_rules, alpha = BALLCHASE.active_rules(np.array([size, pan]))
    assert rules == expected_rules.tolist()
    assert alphas == alpha.tolist()
    assert phi == (alpha / alpha.sum()).tolist()
    assert BALLCHASE.consequents is not None
    commands = [int(BALLCHASE.consequents[m]) for m in rules]
    # the controller acts during learning exactly as the deployed one: same bits
    assert SPARSE.output(alphas, commands) == BALLCHASE.output_one(np.array([size, pan]))
    assert SPARSE.output(alphas, commands) == BALLCHASE.output(np.array([[size, pan]]))[0]


def test_a_trial_runs_to_the_end_of_the_episode() -> None:
    rules = SparseRules(compile_behaviour(line_behaviour()))
    env = LineEnv(max_steps=20)
    up = run_trial(env, rules, 5, [2, 2, 2])
    assert up.success and up.ret == 1.0 and 1 <= up.length <= 7
    down = run_trial(env, rules, 5, [0, 0, 0])
    assert not down.success and down.ret == -1.0
    stay = run_trial(env, rules, 5, [1, 1, 1])
    assert not stay.success and stay.ret == 0.0 and stay.length == 20


def test_the_truncated_last_step_bootstraps() -> None:
    rules = SparseRules(compile_behaviour(line_behaviour()))
    fq = FuzzyQ(np.ones((3, 3)), alpha=0.5, gamma=1.0, lambda_=0.0)
    # staying: reward 0 and target 0 + max q(S') = 1 = Q(S, a), so nothing changes, even on
    # the truncated last step
    run_trial(LineEnv(max_steps=3), rules, 5, [1, 1, 1], td=fq)
    np.testing.assert_array_equal(fq.table(), np.ones((3, 3)))


def test_a_trial_needs_consequents_or_a_chooser() -> None:
    rules = SparseRules(compile_behaviour(line_behaviour()))
    with pytest.raises(ValueError, match="consequents or a chooser"):
        run_trial(LineEnv(), rules, 0, None)


@pytest.mark.parametrize("action", ["crisp", "vote"])
def test_a_learned_controller_acts_as_it_will_when_deployed(action: str) -> None:
    # What learning measured for a controller (run_trial, one episode at a time) is what
    # flctool evaluate measures for it once deployed (batched rollout): the same episodes.
    from flctool.envs import make_env
    from flctool.rollout import evaluate
    from flctool.runs import resolve_behaviour

    behaviour = resolve_behaviour(load_behaviour(BEHAVIOURS / "ballchase-handmade.yaml"),
                                  {"environment.action": action})
    assert BALLCHASE.consequents is not None
    consequents = BALLCHASE.consequents.tolist()
    seeds = list(range(40))
    deployed = evaluate(BALLCHASE, make_env(behaviour, len(seeds)), seeds)
    env = make_env(behaviour)
    learned = [run_trial(env, SPARSE, seed, consequents) for seed in seeds]
    assert [t.length for t in learned] == deployed.lengths.tolist()
    assert [t.ret for t in learned] == deployed.returns.tolist()
    assert [t.success for t in learned] == deployed.success.tolist()


class FixedChooser:
    """Chooses the fixed consequents, so run_trial takes its general loop."""

    def __init__(self, consequents: list[int]) -> None:
        self.consequents = consequents

    def choose(self, rules: list[int]) -> list[int]:
        return [self.consequents[m] for m in rules]


def test_the_fixed_consequents_path_equals_the_general_loop() -> None:
    # pitt's trials and validation take a shorter loop; it must be the same episode
    from flctool.envs import make_env

    env = make_env(load_behaviour(BEHAVIOURS / "ballchase-handmade.yaml"))
    assert BALLCHASE.consequents is not None
    consequents = BALLCHASE.consequents.tolist()
    for seed in range(40):
        assert run_trial(env, SPARSE, seed, consequents) == run_trial(
            env, SPARSE, seed, None, chooser=FixedChooser(consequents))


@settings(max_examples=200, deadline=None)
@given(st.floats(-0.2, 1.2), st.floats(-120.0, 120.0))
def test_activations_add_alpha_in_rule_order(size: float, pan: float) -> None:
    rules, alphas, total = SPARSE.activations([size, pan])
    assert (rules, alphas) == SPARSE.fire([size, pan])[:2]
    assert total == add_in_order(alphas)


@settings(max_examples=200, deadline=None)
@given(st.floats(-0.2, 1.2), st.floats(-120.0, 120.0))
def test_vote_equals_the_batched_vote(size: float, pan: float) -> None:
    from flctool.rollout import vote_output

    rules, alphas, _ = SPARSE.fire([size, pan])
    assert BALLCHASE.consequents is not None
    commands = [int(BALLCHASE.consequents[m]) for m in rules]
    assert SPARSE.vote(alphas, commands) == vote_output(BALLCHASE, np.array([[size, pan]]))[0]


def test_a_vote_ties_to_the_command_listed_first() -> None:
    rules = SparseRules(compile_behaviour(line_behaviour()))
    assert rules.vote([0.5, 0.5], [2, 0]) == -1.0  # down (listed first) over up
    assert rules.vote([0.25, 0.25, 0.5], [2, 2, 0]) == -1.0
    assert rules.vote([0.25, 0.3, 0.5], [2, 2, 0]) == 1.0


def test_a_nan_observation_is_an_error_as_in_the_controller() -> None:
    with pytest.raises(InferenceError, match="observed NaN for input 'ball_size'"):
        SPARSE.fire([float("nan"), 10.0])


def test_no_rule_firing_is_an_error_not_a_division_by_zero() -> None:
    from flctool.behaviour import behaviour_from_data

    data = {"flctool": 1, "name": "tiny", "output": {"name": "y", "commands": {"a": 1.0}},
            "inputs": {"x": {"range": [-1e300, 1e300],
                             "sets": {"lo": [-1e300, -1e300, -1e300, 1e-310],
                                      "hi": [0.0, 1e300, 1e300, 1e300]}}}}
    rules = SparseRules(compile_behaviour(behaviour_from_data(data)))
    with pytest.raises(InferenceError, match="no rule fires"):
        rules.fire([5e-324])


def test_sums_add_left_to_right_on_every_python() -> None:
    # 1e16 + 1 + 1 rounds to 1e16 twice when added in order; a compensated sum (Python 3.12's
    # builtin sum of floats) gives 1e16 + 2, so results would depend on the Python version.
    from flctool.learners.trial import add_in_order

    assert add_in_order([1e16, 1.0, 1.0]) == 1e16
    assert add_in_order(iter([0.1, 0.2, 0.3])) == (0.1 + 0.2) + 0.3


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 10_000), st.integers(3, 5), st.sampled_from(["min", "product"]))
def test_learning_acts_as_the_deployed_controller_with_three_and_more_inputs(
        seed: int, inputs: int, activation: str) -> None:
    # The learning loop's sparse path (eq. 1-3 over the fired rules) and the deployed
    # controller (compiled kernels, one state and batched) give the same bits, eq. 2 the min
    # or the product.
    from flctool.compile.sparse import SparseRules as PlainRules
    from tests.export.controllers import random_behaviour, random_states

    behaviour = random_behaviour(seed, max_inputs=inputs, max_sets=3, min_inputs=inputs,
                                 activation=activation)
    assert len(behaviour.inputs) == inputs
    controller = compile_behaviour(behaviour)
    sparse = SparseRules(controller)
    # the rule base read from the behaviour (as set learning reads it) is the same
    first = random_states(behaviour, 1, seed)[0].tolist()
    assert PlainRules.from_behaviour(behaviour).fire(first) == sparse.fire(first)
    assert controller.consequents is not None
    states = random_states(behaviour, 50, seed)
    batched = controller.output(states)
    for row, state in enumerate(states):
        rules, alphas, _ = sparse.fire(state.tolist())
        learned = sparse.output(alphas, [int(controller.consequents[m]) for m in rules])
        assert learned == controller.output_one(state) == batched[row]
