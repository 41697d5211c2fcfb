"""The gymnasium adapter with real Gymnasium environments, and its errors."""

from __future__ import annotations

import sys

import gymnasium
import numpy as np
import pytest
from gymnasium.envs.classic_control.cartpole import CartPoleEnv

from flctool import compile_behaviour, load_behaviour, parse_behaviour
from flctool.behaviour.environment import ObservationFeature
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


@pytest.mark.slow
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
     r"environment\.options\.colour: 'CartPole-v1' takes no option 'colour'"),
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


# -- inputs computed from the observation (ObservationFeature) -------------------------------
PENDULUM_ANGLE = """\
flctool: 1
name: pendulum_angle
inputs:
  angle:
    sets: {negative: [-3.141592653589793, -3.141592653589793, -1, 0], upright: [-1, 0, 0, 1],
           positive: [0, 1, 3.141592653589793, 3.141592653589793]}
  speed:
    sets: {slow: [0, 0, 1, 4], fast: [1, 4, 8, 8]}
  swing:
    range: [-20, 20]
    sets: {low: [-20, -20, -5, 5], high: [-5, 5, 20, 20]}
output:
  name: torque
  commands: {left: -2.0, none: 0.0, right: 2.0}
environment:
  adapter: gymnasium
  id: Pendulum-v1
  observations:
    angle: {angle: [0, 1]}
    speed: {component: 2, abs: true}
    swing: {difference: [2, 0], scale: 2, offset: 1}
  success: never
"""


def test_features_compute_inputs_from_the_observation() -> None:
    behaviour = parse_behaviour(PENDULUM_ANGLE)
    env = make_env(behaviour, 3)
    obs, _ = env.reset(np.array([0, 1, 2]))
    raw = np.array([[env.trace_state()[f"obs_{i}"][b] for i in range(3)] for b in range(3)])
    cos, sin, velocity = raw.T
    assert np.array_equal(obs[:, 0], np.arctan2(sin, cos))
    assert np.array_equal(obs[:, 1], np.abs(velocity))
    assert np.array_equal(obs[:, 2], (velocity - cos) * 2 + 1)
    check_env(lambda: make_env(behaviour, 2), batch_size=2)


def test_ranges_default_to_the_feature_bounds_over_the_observation_space() -> None:
    behaviour = parse_behaviour(PENDULUM_ANGLE)
    assert behaviour.inputs["angle"].range == (-np.pi, np.pi)  # atan2's range
    assert behaviour.inputs["speed"].range == (0.0, 8.0)  # |velocity| with velocity in [-8, 8]
    assert behaviour.inputs["swing"].range == (-20.0, 20.0)  # given: kept


def test_an_unbounded_component_needs_its_range() -> None:
    # CartPole's cart velocity is unbounded (+-inf): there is nothing to default to
    text = (BEHAVIOURS / "cartpole.yaml").read_text()
    text = text.replace("    range: [-2.0, 2.0]\n    unit: m/s\n", "    unit: m/s\n", 1)
    with pytest.raises(SpecError, match=r"inputs\.cart_velocity\.range: required field "
                                        r"'range' is missing"):
        parse_behaviour(text)
    # a bounded one defaults: the cart position's space bound is +-4.8
    text = (BEHAVIOURS / "cartpole.yaml").read_text()
    text = text.replace("    range: [-2.4, 2.4]\n", "", 1).replace("2.4", "4.8")
    # float32 4.8 is read as the decimal 4.8 it prints as, so sets up to 4.8 cover the range
    assert parse_behaviour(text).inputs["cart_position"].range == (-4.8, 4.8)


def test_a_module_id_is_never_imported_to_find_a_range() -> None:
    text = PENDULUM_ANGLE.replace("id: Pendulum-v1", "id: 'no_such_module_xyz:Env-v0'")
    with pytest.raises(SpecError, match=r"inputs\.angle\.range: required field"):
        parse_behaviour(text)
    assert "no_such_module_xyz" not in sys.modules


@pytest.mark.parametrize(("feature", "message"), [
    ("{component: 0, angle: [0, 1]}", "give exactly one of component, angle or difference "
                                      r"\(got component, angle\)"),
    ("{abs: true}", r"give exactly one of component, angle or difference \(got none\)"),
    ("{component: 0, scale: 0}", "scale 0 makes the input a constant"),
    ("{angle: [0, -1]}", "greater than or equal to 0"),
    ("{component: 0, degrees: true}", "unknown key 'degrees'"),
])
def test_a_bad_feature_names_its_field(feature: str, message: str) -> None:
    text = PENDULUM_ANGLE.replace("speed: {component: 2, abs: true}", f"speed: {feature}")
    text = text.replace("    sets: {slow:", "    range: [0, 8]\n    sets: {slow:")
    with pytest.raises(SpecError, match=rf"environment\.observations\.speed.*{message}"):
        parse_behaviour(text)


def test_a_feature_index_beyond_the_observation_is_an_error() -> None:
    text = PENDULUM_ANGLE.replace("angle: {angle: [0, 1]}", "angle: {angle: [0, 3]}")
    text = text.replace("  angle:\n    sets:", "  angle:\n    range: [-3.141592653589793, "
                        "3.141592653589793]\n    sets:")
    with pytest.raises(SpecError, match=r"environment\.observations\.angle: index 3 is out of "
                                        "range"):
        make_env(parse_behaviour(text))


def test_feature_bounds() -> None:
    low, high = [-1.0, -2.0, -np.inf], [3.0, 5.0, np.inf]
    assert ObservationFeature(component=0).bounds(low, high) == (-1.0, 3.0)
    assert ObservationFeature(difference=(0, 1)).bounds(low, high) == (-6.0, 5.0)
    assert ObservationFeature(component=0, abs=True).bounds(low, high) == (0.0, 3.0)
    assert ObservationFeature(component=0, abs=True).bounds([-4.0], [-1.0]) == (1.0, 4.0)
    assert ObservationFeature(component=0, scale=-2, offset=1).bounds(low, high) == (-5.0, 3.0)
    lo, hi = ObservationFeature(component=2).bounds(low, high)
    assert np.isinf(lo) and np.isinf(hi)


def test_acrobot_reads_each_angle_as_one_input() -> None:
    behaviour = load_behaviour(BEHAVIOURS / "acrobot.yaml")
    assert behaviour.inputs["elbow_angle"].range == (-180.0, 180.0)  # defaulted, in degrees
    env = make_env(behaviour, 2)
    obs, _ = env.reset(np.array([5, 6]))
    trace = env.trace_state()
    expected = np.degrees(np.arctan2(trace["obs_3"], trace["obs_2"]))
    np.testing.assert_allclose(obs[:, 0], expected, rtol=1e-12)
    assert np.array_equal(obs[:, 1], trace["obs_5"])
    # torque along the elbow's velocity pumps energy into the swing (and a push when still
    # starts it): the sets can hold a controller that reaches the goal
    controller = compile_behaviour(behaviour)
    push = {0: 0, 1: 2, 2: 2}  # velocity set negative, still, positive -> command index
    consequents = np.array([push[int(v)] for v in controller.rule_grid[:, 1]], dtype=np.intp)
    result = evaluate(controller, make_env(behaviour, 20), np.arange(20), consequents)
    assert result.success_rate.value >= 0.9


def test_options_are_checked_against_the_registered_environment() -> None:
    """render_mode against the environment's metadata, other keys against its constructor,
    each at its line, before Gymnasium makes it (and warns in its own words)."""
    import tempfile

    from typer.testing import CliRunner

    from flctool.cli import app as cli_app

    text = (BEHAVIOURS / "cartpole.yaml").read_text().replace(
        "  id: CartPole-v1\n",
        "  id: CartPole-v1\n  options: {render_mode: rgb_arary, sutton_barto: true}\n")
    with pytest.raises(SpecError) as info:
        make_env(parse_behaviour(text, "cartpole.yaml"))
    messages = {p.path[-1]: (p.message, p.hint) for p in info.value.problems}
    assert messages["render_mode"][0] == ("'rgb_arary' is not a render mode of 'CartPole-v1'. "
                                          "Did you mean 'rgb_array'?")
    assert "Did you mean 'sutton_barto_reward'?" in messages["sutton_barto"][0]
    assert all(p.line is not None for p in info.value.problems)
    good = text.replace("render_mode: rgb_arary, sutton_barto: true",
                        "render_mode: rgb_array, sutton_barto_reward: true")
    make_env(parse_behaviour(good, "cartpole.yaml")).close()
    with tempfile.TemporaryDirectory() as folder:
        path = f"{folder}/cartpole.yaml"
        with open(path, "w", encoding="utf-8") as handle:
            handle.write(text)
        result = CliRunner().invoke(cli_app, ["validate", path])
    assert result.exit_code == 1 and "not a render mode" in result.output
    assert "WARN" not in result.output  # Gymnasium's own warning never shows


def _needs_a_package(**kwargs: object) -> gymnasium.Env:  # type: ignore[type-arg]
    raise gymnasium.error.DependencyNotInstalled("Box2D is not installed, pip install box2d")


def test_an_environment_whose_package_is_missing_says_to_install_it() -> None:
    """Gymnasium knows the id but not its package: the fix is an install, not another id."""
    from flctool.behaviour.gym_registry import MISSING_PACKAGE_HINT
    from flctool.behaviour.scaffold import parse_command, parse_input, scaffold_behaviour
    from flctool.errors import FlcError

    env_id = "flctool-test/NeedsPackage-v0"
    if env_id not in gymnasium.envs.registry:
        gymnasium.register(env_id, entry_point=_needs_a_package)
    behaviour = parse_behaviour(_cartpole_env(
        f"environment: {{adapter: gymnasium, id: '{env_id}', actions: {{push_left: 0, "
        "push_right: 1}}\n"))
    with pytest.raises(SpecError) as caught:
        make_env(behaviour)
    (problem,) = caught.value.problems
    assert problem.message == (f"Gymnasium cannot make '{env_id}': Box2D is not installed, "
                               "pip install box2d")
    assert problem.hint == MISSING_PACKAGE_HINT
    with pytest.raises(FlcError, match="Box2D is not installed") as scaffolded:
        scaffold_behaviour("lander", [parse_input("x:-1:1:3")],
                           [parse_command("left:-1"), parse_command("right:1")],
                           adapter=f"gymnasium:{env_id}")
    assert scaffolded.value.hint == MISSING_PACKAGE_HINT
