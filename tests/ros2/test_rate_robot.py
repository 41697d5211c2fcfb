"""The ros2 adapter against a robot that behaves like most real ones: sensors published at
their own rate, a reset service, named commands (std_msgs/String), and the episode ended by
outcome rules over the inputs -- with ``sync: rate`` (one control period a step)."""

from __future__ import annotations

import time
from typing import Any

import pytest

from flctool.behaviour import behaviour_from_data, behaviour_to_data, load_behaviour

from ..conftest import BEHAVIOURS
from ..ros2_support import require_ros2, wait_until


@pytest.fixture(autouse=True)
def _ros() -> None:
    require_ros2()


class _Robot:
    """ball_size grows while the robot walks 'forward' and shrinks otherwise, published at
    50 Hz; pan stays 0. The reset service puts ball_size back to 0.2."""

    def __init__(self) -> None:
        from flctool.behaviour.ros2 import Qos
        from flctool.ros2.fields import message_class
        from flctool.ros2.graph import RosGraph

        self.graph = RosGraph("rate_robot")
        self.float64 = message_class("std_msgs/Float64")
        self.size = self.graph.publisher("/rate/ball_size", "std_msgs/Float64", Qos())
        self.pan = self.graph.publisher("/rate/pan", "std_msgs/Float64", Qos())
        self.value = 0.2
        self.command = "stop"
        self.received: list[str] = []
        self.resets = 0
        node = self.graph.node
        node.create_subscription(message_class("std_msgs/String"), "/rate/command",
                                 self._on_command, 10)
        node.create_service(message_class("std_srvs/Trigger", "srv"), "/rate/reset",
                            self._on_reset)
        node.create_timer(0.02, self._publish)

    def _on_command(self, message: Any) -> None:
        self.command = str(message.data)
        self.received.append(self.command)

    def _on_reset(self, request: Any, response: Any) -> Any:
        del request
        self.value, self.command = 0.2, "stop"
        self.resets += 1
        response.success = True
        return response

    def _publish(self) -> None:
        if self.command == "forward":
            self.value = min(1.0, self.value + 0.02)
        elif self.command != "stop":
            self.value = max(0.0, self.value - 0.01)
        self.size.publish(self.float64(data=self.value))
        self.pan.publish(self.float64(data=0.0))


def _behaviour() -> Any:
    data = behaviour_to_data(load_behaviour(BEHAVIOURS / "ballchase-handmade.yaml"))
    data["environment"] = {
        "adapter": "ros2", "rate": 10.0, "sync": "rate", "stale_after": 0.5,
        "inputs": {"ball_size": "/rate/ball_size std_msgs/Float64",
                   "pan": {"topic": "/rate/pan", "type": "std_msgs/Float64",
                           "valid": [-90, 90]}},
        "command": {"topic": "/rate/command", "type": "std_msgs/String", "stop": "halt"},
        "episode": {"max_steps": 40, "reset": {"service": "/rate/reset",
                                               "type": "std_srvs/Trigger"},
                    "outcomes": [{"input": "ball_size", "min": 0.5, "reward": 1.0,
                                  "success": True},
                                 {"input": "ball_size", "max": 0.05, "reward": -1.0}]}}
    return behaviour_from_data(data)


def test_a_rate_robot_with_a_reset_service_named_commands_and_outcome_rules() -> None:
    from flctool.envs import make_env

    robot = _Robot()
    try:
        with make_env(_behaviour()) as env:
            observation = env.reset_one(0)
            assert robot.resets == 1 and observation[0] == pytest.approx(0.2, abs=0.05)
            started = time.monotonic()
            steps, total, ended = 0, 0.0, False
            while not ended:
                observation, reward, terminated, truncated = env.step_one(0.0)  # 'forward'
                steps, total = steps + 1, total + reward
                ended = terminated or truncated
            elapsed = time.monotonic() - started
            assert terminated and not truncated and bool(env.success()[0])
            assert total == 1.0 and observation[0] >= 0.5
            # one control period (0.1 s) a step: 0.2 -> 0.5 at +0.02 per 20 ms is ~0.3 s
            assert 2 <= steps <= 10 and elapsed >= 0.1 * (steps - 1)
            assert wait_until(lambda: robot.received[-1:] == ["halt"], 5.0), robot.received
            assert "forward" in robot.received  # the nearest command's name
            env.reset_one(1)
            assert robot.resets == 2
    finally:
        robot.graph.close()
