"""Evaluation in lock-step, its confidence intervals, and episode traces."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flctool import compile_behaviour, load_behaviour
from flctool.envs import make_env
from flctool.errors import EnvError
from flctool.rollout import evaluate, mean_interval, trace_episode, wilson_interval

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
    with pytest.raises(EnvError, match="no rule consequents"):
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
