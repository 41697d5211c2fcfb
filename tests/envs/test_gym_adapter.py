"""The gymnasium adapter with real Gymnasium environments, and its errors."""

from __future__ import annotations

import sys

import gymnasium
import numpy as np
import pytest
from gymnasium.envs.classic_control.cartpole import CartPoleEnv

from flctool import compile_behaviour, load_behaviour, parse_behaviour
from flctool.envs import check_env, make_env
from flctool.errors import MissingDependencyError, SpecError
from flctool.rollout import evaluate

from ..conftest import BEHAVIOURS

PENDULUM = """\
flctool: 1
name: pendulum
inputs:
  cos_angle:
    range: [-1, 1]
    sets: {down: [-1, -1, -0.5, 0.5], up: [-0.5, 0.5, 1, 1]}
  velocity:
    range: [-8, 8]
    sets: {ccw: [-8, -8, -1, 1], cw: [-1, 1, 8, 8]}
output:
  name: torque
  commands: {left: -2.0, none: 0.0, right: 2.0}
environment:
  adapter: gymnasium
  id: Pendulum-v1
  observations: {cos_angle: 0, velocity: 2}
  success: never
"""


def _cartpole_env(extra: str) -> str:
    text = (BEHAVIOURS / "cartpole.yaml").read_text()
    return text[: text.index("environment:")] + extra


def test_cartpole_maps_inputs_and_actions() -> None:
    behaviour = load_behaviour(BEHAVIOURS / "cartpole.yaml")
    env = make_env(behaviour, 2)
    assert env.max_steps == 500
    assert env.action_bounds == (-1.0, 1.0)
    obs, _ = env.reset(np.array([0, 1]))
    trace = env.trace_state()
    assert np.array_equal(obs[:, 3], trace["obs_3"])
    # a rule table that pushes towards the side the pole falls to (and, less, the side the
    # cart drifts to) balances it: the partitions can hold a good controller
    controller = compile_behaviour(behaviour)
    side = controller.rule_grid - 1.0  # set index -> -1 (left), 0, +1 (right)
    score = 0.5 * side[:, 1] + side[:, 2] + side[:, 3]
    consequents = (score >= 0).astype(np.intp)  # 1 = push_right
    result = evaluate(controller, make_env(behaviour, 20), np.arange(20), consequents)
    assert result.success_rate.value > 0.9
    assert np.array_equal(result.success, result.lengths == 500)


def test_box_actions_are_the_crisp_output() -> None:
    behaviour = parse_behaviour(PENDULUM)
    env = make_env(behaviour, 2)
    check_env(lambda: make_env(behaviour, 2), batch_size=2)
    env.reset(np.array([3, 4]))
    step = env.step(np.array([1.5, -5.0]))  # -5 is clipped to the action space's -2
    assert step.rewards.shape == (2,)
    assert not env.success().any()


def test_gymnasium_missing_gives_the_install_hint(monkeypatch: pytest.MonkeyPatch) -> None:
    behaviour = load_behaviour(BEHAVIOURS / "cartpole.yaml")
    monkeypatch.setitem(sys.modules, "gymnasium", None)
    with pytest.raises(MissingDependencyError) as caught:
        make_env(behaviour)
    assert caught.value.package == "gymnasium"
    assert "pip install 'flctool[gym]'" in str(caught.value)


def test_unknown_id_suggests_a_registered_one() -> None:
    behaviour = parse_behaviour(_cartpole_env(
        "environment: {adapter: gymnasium, id: CartPole-v2, actions: {push_left: 0, "
        "push_right: 1}}\n"))
    with pytest.raises(SpecError, match=r"environment\.id: Gymnasium cannot make "
                                        r"'CartPole-v2'.*Did you mean 'CartPole-v1'"):
        make_env(behaviour)


def test_an_unknown_name_gets_one_suggestion_not_two() -> None:
    behaviour = parse_behaviour(_cartpole_env(
        "environment: {adapter: gymnasium, id: CartPol-v1, actions: {push_left: 0, "
        "push_right: 1}}\n"))
    with pytest.raises(SpecError) as caught:
        make_env(behaviour)
    message = str(caught.value)
    assert "Environment `CartPol` doesn't exist. Did you mean 'CartPole-v1'?" in message
    assert message.count("Did you mean") == 1


CLOSED: list[str] = []


class _ClosingCartPole(CartPoleEnv):
    """CartPole that records its closing, to see that a refused environment is closed."""

    def close(self) -> None:
        CLOSED.append("closed")
        super().close()


def test_an_environment_that_does_not_fit_is_closed() -> None:
    env_id = "flctool-test/ClosingCartPole-v0"
    if env_id not in gymnasium.envs.registry:
        gymnasium.register(env_id, entry_point=_ClosingCartPole, max_episode_steps=50)
    CLOSED.clear()
    behaviour = parse_behaviour(_cartpole_env(
        f"environment: {{adapter: gymnasium, id: '{env_id}', actions: {{push_left: 0, "
        "push_right: 2}}\n"))
    with pytest.raises(SpecError, match="action 2 is not in the action space"):
        make_env(behaviour, 3)
    assert CLOSED == ["closed"]


@pytest.mark.parametrize(("environment", "message"), [
    ("{adapter: gymnasium, id: CartPole-v1, actions: {push_left: 0, push_right: 1}, "
     "observations: {cart_position: 0, cart_velocity: 1, pole_angle: 2, pole_velocity: 7}}",
     r"environment\.observations\.pole_velocity: index 7 is out of range"),
    ("{adapter: gymnasium, id: CartPole-v1, actions: {push_left: 0, push_right: 1}, "
     "observations: {cart_position: 0, cart_velocity: 1, pole_angle: 2}}",
     r"environment\.observations: input 'pole_velocity' reads no observation component"),
    ("{adapter: gymnasium, id: CartPole-v1, actions: {push_left: 0, push_right: 2}}",
     r"environment\.actions\.push_right: action 2 is not in the action space Discrete\(2\)"),
    ("{adapter: gymnasium, id: CartPole-v1}",
     r"environment\.actions: command 'push_left' has no action"),
    ("{adapter: gymnasium, id: FrozenLake-v1, actions: {push_left: 0, push_right: 1}}",
     r"environment\.id: 'FrozenLake-v1' observes Discrete\(16\); the gymnasium adapter needs "
     r"a one-dimensional Box"),
    ("{adapter: gymnasium, id: MountainCar-v0, actions: {push_left: 0, push_right: 2}}",
     r"inputs: the behaviour has 4 inputs but 'MountainCar-v0' observes only 2"),
    ("{adapter: gymnasium, id: CartPole-v1, options: {colour: red}}",
     r"environment\.options: 'CartPole-v1' does not accept these options"),
])
def test_a_space_that_does_not_fit_names_the_field(environment: str, message: str) -> None:
    behaviour = parse_behaviour(_cartpole_env(f"environment: {environment}\n"))
    with pytest.raises(SpecError, match=message):
        make_env(behaviour)


def test_box_action_singletons_must_fit_the_space() -> None:
    behaviour = parse_behaviour(PENDULUM.replace("right: 2.0", "right: 3.0"))
    with pytest.raises(SpecError, match=r"output\.commands\.right: singleton 3 is outside "
                                        r"the action space \[-2, 2\]"):
        make_env(behaviour)


def test_max_steps_truncates_before_the_environment_limit() -> None:
    env = make_env(parse_behaviour(PENDULUM + "  max_steps: 7\n"))
    env.reset(np.array([0]))
    for _ in range(6):
        assert not env.step(np.array([0.0])).truncated[0]
    assert env.step(np.array([0.0])).truncated[0] and env.max_steps == 7
