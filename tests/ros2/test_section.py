"""Which ROS 2 section a controller runs with: its own, or a robot file's, checked against the
controller either way (no rclpy needed)."""

from __future__ import annotations

from pathlib import Path

import pytest

from flctool.behaviour import load_behaviour
from flctool.errors import FlcError, SpecError
from flctool.ros2.section import ros2_section

from ..conftest import BEHAVIOURS

ROBOT = BEHAVIOURS / "ballchase-ros2.yaml"
SIM = BEHAVIOURS / "ballchase-handmade.yaml"


def test_the_controllers_own_section_or_the_robot_files() -> None:
    robot = load_behaviour(ROBOT)
    config, where = ros2_section(robot, str(ROBOT))
    assert config == robot.environment and where == str(ROBOT)
    # a controller learned in the simulator takes the robot file's topics
    config, where = ros2_section(load_behaviour(SIM), str(SIM), ROBOT)
    assert config == robot.environment and where == str(ROBOT)


def test_a_simulator_controller_without_a_robot_file_is_told_to_name_one() -> None:
    with pytest.raises(FlcError, match="environment is not a ROS 2 robot") as caught:
        ros2_section(load_behaviour(SIM), str(SIM))
    assert "--robot ROBOT.yaml" in (caught.value.hint or "")
    with pytest.raises(FlcError, match=f"{SIM} has no 'environment: {{adapter: ros2"):
        ros2_section(load_behaviour(SIM), str(SIM), SIM)


def test_a_robot_file_that_maps_other_inputs_is_a_located_error(tmp_path: Path) -> None:
    robot = tmp_path / "robot.yaml"
    # a valid robot file of its own, whose second input is tilt where the controller has pan
    robot.write_text(ROBOT.read_text(encoding="utf-8").replace("pan", "tilt"),
                     encoding="utf-8")
    assert load_behaviour(robot).input_names == ("ball_size", "tilt")
    with pytest.raises(SpecError) as caught:
        ros2_section(load_behaviour(SIM), str(SIM), robot)
    text = str(caught.value)
    assert "input 'pan' has no source" in text and "'tilt' is not an input" in text, text
    line = next(i for i, row in enumerate(robot.read_text(encoding="utf-8").splitlines(), 1)
                if row.startswith("    tilt: "))
    assert f"{robot}:{line}:" in text, text  # placed at the robot file's line
