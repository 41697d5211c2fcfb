"""make_env finds adapters by name; every registered adapter passes the checker."""

from __future__ import annotations

import numpy as np
import pytest

from flctool import load_behaviour, parse_behaviour
from flctool.behaviour import behaviour_from_data, behaviour_to_data
from flctool.envs import ENVIRONMENTS, BatchEnv, SingleEnv, check_env, make_env
from flctool.envs.robot_server import RobotServer
from flctool.errors import EnvError
from flctool.plugins import BUILTIN
from flctool.registry import UnknownNameError

from ..conftest import BEHAVIOURS, MINIMAL
from ..ros2_support import robot_behaviour, sim_robot

# One shipped behaviour per registered adapter.
EXAMPLES = {"ballchase-sim": "ballchase.yaml", "gymnasium": "cartpole.yaml",
            "robot-link": "ballchase-robot.yaml", "pitch": "face-goal.yaml",
            "ros2": "ballchase-ros2.yaml"}


def test_every_adapter_has_a_config_and_an_example() -> None:
    assert set(ENVIRONMENTS.names()) == {p.name for p in BUILTIN["environment"]} == set(EXAMPLES)


@pytest.mark.parametrize("adapter", sorted(EXAMPLES))
@pytest.mark.slow
def test_every_registered_adapter_passes_the_checker(adapter: str) -> None:
    behaviour = load_behaviour(BEHAVIOURS / EXAMPLES[adapter])
    assert behaviour.environment is not None
    assert behaviour.environment.adapter == adapter
    if adapter == "ros2":  # a ROS 2 robot, one episode at a time: the reference robot
        with sim_robot("/checked"):
            check_env(lambda: make_env(robot_behaviour("/checked"), 1), batch_size=1)
        return
    if adapter != "robot-link":
        check_env(lambda: make_env(behaviour, 3), batch_size=3)
        return
    # The link needs a robot: the reference server, on a free port of this machine.
    robot = RobotServer.from_behaviour(load_behaviour(BEHAVIOURS / "ballchase.yaml"), port=0,
                                       idle_timeout=5.0)
    thread = robot.serve_in_background()
    try:
        data = behaviour_to_data(behaviour)
        data["environment"]["port"] = robot.port
        linked = behaviour_from_data(data)
        check_env(lambda: make_env(linked, 3), batch_size=3)
    finally:
        robot.close()
        thread.join(timeout=5)


def test_single_env_wraps_a_batch_of_one() -> None:
    env = SingleEnv(make_env(load_behaviour(BEHAVIOURS / "ballchase.yaml")))
    obs, info = env.reset(seed=5)
    assert obs.shape == (2,) and info == {}
    obs, reward, terminated, truncated, _ = env.step(0.0)
    assert obs.shape == (2,) and isinstance(reward, float)
    assert isinstance(terminated, bool) and isinstance(truncated, bool)


def test_no_environment_section() -> None:
    with pytest.raises(EnvError, match="has no 'environment' section"):
        make_env(parse_behaviour(MINIMAL))


def test_unknown_adapter_in_the_registry_suggests_a_name() -> None:
    with pytest.raises(UnknownNameError, match="Did you mean 'ballchase-sim'"):
        ENVIRONMENTS.get("ballchase-simm")


class _Leaky(BatchEnv):
    """Breaks the contract: episodes share one random stream."""

    observation_names = ("x",)
    max_steps = 5
    action_bounds = (-1.0, 1.0)

    def __init__(self) -> None:
        self.rng = np.random.default_rng(0)
        self.t = np.zeros(1, dtype=np.int64)

    def reset(self, seeds: np.ndarray) -> tuple[np.ndarray, dict[str, object]]:
        self.t = np.zeros(len(seeds), dtype=np.int64)
        return self.rng.random((len(seeds), 1)), {}

    def step(self, actions: np.ndarray):  # type: ignore[no-untyped-def]
        from flctool.envs import Step

        self.t += 1
        done = self.t >= self.max_steps
        return Step(self.rng.random((len(actions), 1)), np.zeros(len(actions)), done,
                    np.zeros(len(actions), dtype=bool))

    def success(self) -> np.ndarray:
        return np.zeros(len(self.t), dtype=bool)


def test_checker_catches_shared_randomness() -> None:
    with pytest.raises(EnvError, match="adapter check failed"):
        check_env(_Leaky)
