"""Evaluation in lock-step, its confidence intervals, and episode traces."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flctool import compile_behaviour, load_behaviour
from flctool.envs import make_env
from flctool.errors import NotDeployableError
from flctool.rollout import (
    T975,
    evaluate,
    evaluation_seeds,
    mean_interval,
    t975,
    trace_episode,
    vote_output,
    wilson_interval,
)

from .conftest import BEHAVIOURS


def test_wilson_interval_known_values() -> None:
    # 8 of 10: the Wilson 95 % interval is about [0.490, 0.943]
    estimate = wilson_interval(8, 10)
    assert estimate.value == 0.8
    assert estimate.low == pytest.approx(0.4902, abs=1e-4)
    assert estimate.high == pytest.approx(0.9433, abs=1e-4)
    assert wilson_interval(10, 10).high == pytest.approx(1.0)
    assert wilson_interval(10, 10).low == pytest.approx(0.7225, abs=1e-4)
    assert math.isnan(wilson_interval(0, 0).value)


def test_mean_interval_uses_student_t() -> None:
    estimate = mean_interval(np.array([1.0, 2.0, 3.0]))
    # t(0.975, 2) = 4.3027, sd = 1, n = 3
    assert estimate.value == 2.0
    assert estimate.high - 2.0 == pytest.approx(4.302653 / math.sqrt(3), rel=1e-6)
    single = mean_interval(np.array([5.0]))
    assert single.value == 5.0 and math.isnan(single.low)
    assert mean_interval(np.array([])).to_dict() == {"value": None, "low": None,
                                                      "high": None, "n": 0}


def test_t_quantile_table_is_scipys() -> None:
    """The table spares scipy's import; it must give scipy's quantiles (exactly with the scipy
    it was made with, within an ulp with another version), and dof off the table ask scipy."""
    from scipy.special import stdtrit

    for dof, quantile in T975.items():
        assert quantile == pytest.approx(float(stdtrit(dof, 0.975)), rel=3e-16, abs=0.0), dof
    assert 31 not in T975
    assert t975(31) == float(stdtrit(31, 0.975))


def test_t_quantile_expansion_is_within_its_bound_of_scipy() -> None:
    from scipy.special import stdtrit

    for dof in (200, 201, 350, 998, 1000, 5000, 10**6):
        assert dof not in T975
        assert abs(t975(dof) - float(stdtrit(dof, 0.975))) <= 2.3e-12, dof
    for dof in (1000, 2500, 10**5):
        assert abs(t975(dof) - float(stdtrit(dof, 0.975))) <= 1e-15, dof


def test_evaluate_collects_every_episode() -> None:
    behaviour = load_behaviour(BEHAVIOURS / "ballchase-handmade.yaml")
    controller = compile_behaviour(behaviour)
    env = make_env(behaviour, 100)
    result = evaluate(controller, env, np.arange(100))
    assert result.episodes == 100
    assert result.lengths.min() >= 1 and result.lengths.max() <= env.max_steps
    assert result.success_rate.value >= 0.9
    assert result.steps_to_success.n == int(result.success.sum())
    assert np.array_equal(result.fitness, env.episode_fitness(result.returns, result.lengths,
                                                              result.success))
    summary = result.summary()
    assert summary["episodes"] == 100 and summary["success_rate"]["value"] >= 0.9
    again = evaluate(controller, env, np.arange(100))
    assert np.array_equal(again.lengths, result.lengths)


def test_random_consequents_do_worse() -> None:
    behaviour = load_behaviour(BEHAVIOURS / "ballchase-handmade.yaml")
    controller = compile_behaviour(behaviour)
    env = make_env(behaviour, 200)
    rng = np.random.default_rng(0)
    rates = [evaluate(controller, env, np.arange(200),
                      rng.integers(0, 5, controller.n_rules)).success_rate.value
             for _ in range(5)]
    assert np.mean(rates) < 0.5


def test_a_controller_without_rules_is_an_error() -> None:
    behaviour = load_behaviour(BEHAVIOURS / "ballchase.yaml")
    with pytest.raises(NotDeployableError, match="no rule consequents"):
        evaluate(compile_behaviour(behaviour), make_env(behaviour), [0])


def test_trace_episode_rows() -> None:
    behaviour = load_behaviour(BEHAVIOURS / "ballchase-handmade.yaml")
    controller = compile_behaviour(behaviour)
    env = make_env(behaviour)
    rows = trace_episode(controller, env, 3)
    result = evaluate(controller, env, [3])
    assert len(rows) == result.lengths[0] + 1
    first, last = rows[0], rows[-1]
    assert {"step", "robot_x", "robot_y", "robot_heading", "ball_x", "ball_y", "ball_size",
            "pan", "turn", "command"} <= set(first)
    assert first["command"] in controller.command_names and last["command"] == ""
    assert rows[-2]["terminated"] is True and rows[-2]["reward"] == 1.0


# A bang-bang table on a discrete task (MountainCar-v0): push the way the car rolls. The two
# velocity sets overlap widely, so near rest both rules fire and eq. 3 averages -1 and +1 to
# about 0, whose nearest command is 'coast': a dead zone the car never leaves. A vote runs
# the command with the larger summed activation instead.
BANG_BANG = """\
flctool: 1
name: bang_bang
inputs:
  velocity:
    range: [-0.07, 0.07]
    sets:
      backward: [-0.07, -0.07, -0.03, 0.03]
      forward: [-0.03, 0.03, 0.07, 0.07]
output:
  name: push
  commands: {push_left: -1, coast: 0, push_right: 1}
rules:
  - {if: {velocity: backward}, then: push_left}
  - {if: {velocity: forward}, then: push_right}
environment:
  adapter: gymnasium
  id: MountainCar-v0
  observations: {velocity: 1}
  actions: {push_left: 0, coast: 1, push_right: 2}
  action: ACTION
"""


def bang_bang(action: str) -> tuple[float, float]:
    from flctool import parse_behaviour

    behaviour = parse_behaviour(BANG_BANG.replace("ACTION", action), "bang-bang.yaml")
    env = make_env(behaviour, 20)
    try:
        result = evaluate(compile_behaviour(behaviour), env, evaluation_seeds(0, 20))
    finally:
        env.close()
    return result.mean_return.value, result.success_rate.value


def test_the_vote_action_has_no_dead_zone_on_a_discrete_task() -> None:
    nearest_return, nearest_success = bang_bang("nearest")
    vote_return, vote_success = bang_bang("vote")
    assert nearest_return == -200.0 and nearest_success == 0.0  # coasts at the bottom
    assert vote_success == 1.0 and vote_return > -150.0


def test_vote_output_sums_each_command_s_activations() -> None:
    controller = compile_behaviour(load_behaviour(BEHAVIOURS / "ballchase-handmade.yaml"))
    rng = np.random.default_rng(2)
    states = np.column_stack([rng.uniform(0, 1, 300), rng.uniform(-90, 90, 300)])
    alpha = controller.activations(states)
    assert controller.consequents is not None
    votes = np.stack([alpha[:, controller.consequents == k].sum(axis=1)
                      for k in range(controller.n_commands)], axis=1)
    expected = controller.singletons[np.argmax(votes, axis=1)]
    np.testing.assert_array_equal(vote_output(controller, states), expected)
    assert set(vote_output(controller, states)) <= set(controller.singletons)
