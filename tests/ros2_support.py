"""What the ROS 2 tests share: rclpy or a skip, a graph of their own on localhost, and the
reference robot (``flctool serve --ros2``) in this process or as a child process.

The tests skip only when rclpy is missing *and* ``FLCTOOL_REQUIRE_ROS2`` is unset; CI sets it
(and installs ``flctool[ros2]``), so there a missing rclpy fails them instead. Every test
graph stays on this machine (``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``) in a DDS domain of
its own, drawn from the process id, so two test runs on one machine do not hear each other.
"""

from __future__ import annotations

import contextlib
import os
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

from flctool.behaviour import Behaviour, behaviour_from_data, behaviour_to_data, load_behaviour

from .conftest import BEHAVIOURS, restore_sigint

ROBOT_FILE = BEHAVIOURS / "ballchase-ros2.yaml"
SIM_FILE = BEHAVIOURS / "ballchase-handmade.yaml"


def ros_environment() -> dict[str, str]:
    """The variables every test graph (and each child process) runs with."""
    return {"RMW_IMPLEMENTATION": os.environ.get("RMW_IMPLEMENTATION", "rmw_fastrtps_cpp"),
            "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST",
            "ROS_DOMAIN_ID": os.environ.get("FLCTOOL_TEST_ROS_DOMAIN_ID",
                                            str(20 + os.getpid() % 80))}


def require_ros2() -> None:
    """Skip (or, with FLCTOOL_REQUIRE_ROS2, fail) when rclpy is missing; else set up the
    test graph's environment."""
    try:
        import rclpy  # noqa: F401
    except ImportError:
        if os.environ.get("FLCTOOL_REQUIRE_ROS2"):
            pytest.fail("FLCTOOL_REQUIRE_ROS2 is set but rclpy is missing "
                        "(pip install -e '.[ros2]')")
        pytest.skip("rclpy is not installed (pip install -e '.[ros2]')")
    os.environ.update(ros_environment())


def robot_behaviour(namespace: str = "/robot", **environment: Any) -> Behaviour:
    """behaviours/ballchase-ros2.yaml with its topics under ``namespace`` and the given
    environment keys replaced (short timeouts for tests)."""
    data = behaviour_to_data(load_behaviour(ROBOT_FILE))
    data["environment"] = {**_renamed(data["environment"], namespace), **environment}
    return behaviour_from_data(data)


def _renamed(value: Any, namespace: str) -> Any:
    if isinstance(value, dict):
        return {key: _renamed(item, namespace) for key, item in value.items()}
    if isinstance(value, str) and value.startswith("/robot/"):
        return namespace + value[len("/robot"):]
    return value


def composition_robot(names: tuple[str, ...], namespace: str = "/robot",
                      **environment: Any) -> Behaviour:
    """A robot file for a composition: behaviours/ballchase-ros2.yaml's topics with an input
    for each channel the composition reads (``deployable(...).observations``), each on
    ``NAMESPACE/<channel>`` as ``flctool serve --ros2`` publishes it."""
    data = behaviour_to_data(load_behaviour(ROBOT_FILE))
    data["inputs"] = {name: {"range": [-1e4, 1e4], "sets": {"any": [-1e4, -1e4, 1e4, 1e4]}}
                      for name in names}
    data["environment"] = {**_renamed(data["environment"], namespace),
                           "inputs": {name: f"{namespace}/{name} std_msgs/Float64 .data"
                                      for name in names}, **environment}
    return behaviour_from_data(data)


def handmade_rules(behaviour: Behaviour) -> Behaviour:
    """``behaviour`` with the handmade controller's rules (a deployable controller)."""
    data = behaviour_to_data(behaviour)
    data["rules"] = behaviour_to_data(load_behaviour(SIM_FILE))["rules"]
    return behaviour_from_data(data)


@contextlib.contextmanager
def sim_robot(namespace: str = "/robot", **options: Any) -> Iterator[Any]:
    """The reference robot (the handmade file's simulator) in this process."""
    require_ros2()
    from flctool.envs.ros2_robot import SimRobot

    robot = SimRobot.from_behaviour(load_behaviour(SIM_FILE), namespace=namespace, **options)
    try:
        yield robot
    finally:
        robot.close()


@contextlib.contextmanager
def served_robot(*args: str, sim: Path = SIM_FILE) -> Iterator[subprocess.Popen[str]]:
    """``flctool serve --ros2 SIM ARGS`` as a child process, once it has said it serves."""
    require_ros2()
    process = subprocess.Popen(
        [sys.executable, "-m", "flctool", "serve", str(sim), "--ros2", *args],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        env={**os.environ, **ros_environment()}, preexec_fn=restore_sigint)
    try:
        assert process.stdout is not None
        line = _read_line(process.stdout, 60.0)
        assert line.startswith("serving ROS 2 robot"), line + _rest(process)
        yield process
    finally:
        if process.poll() is None:
            process.kill()
        process.wait(timeout=10)


def _read_line(stream: Any, timeout: float) -> str:
    got: list[str] = []
    reader = threading.Thread(target=lambda: got.append(stream.readline()), daemon=True)
    reader.start()
    reader.join(timeout)
    return got[0] if got else ""


def _rest(process: subprocess.Popen[str]) -> str:
    if process.poll() is None:
        process.kill()
    _, err = process.communicate(timeout=10)
    return err


def wait_until(ready: Callable[[], bool], timeout: float) -> bool:
    """Whether ``ready()`` became true within ``timeout`` s (polled every 10 ms)."""
    deadline = time.monotonic() + timeout
    while not ready():
        if time.monotonic() > deadline:
            return False
        time.sleep(0.01)
    return True
