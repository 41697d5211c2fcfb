"""The ``ros2`` environment section: message mapping checked against the message definitions
when a file is loaded, with located errors, and no ROS installed needed."""

from __future__ import annotations

import contextlib
import os
from pathlib import Path

import pytest
import yaml
from hypothesis import given
from hypothesis import strategies as st

from flctool.behaviour import load_behaviour
from flctool.behaviour.ros2 import Ros2Config
from flctool.behaviour.ros2_messages import MESSAGES, field_type, parse_path
from flctool.errors import SpecError

from ..conftest import BEHAVIOURS

ROBOT = BEHAVIOURS / "ballchase-ros2.yaml"


def _with_environment(tmp_path: Path, environment: dict[str, object]) -> Path:
    data = yaml.safe_load(ROBOT.read_text(encoding="utf-8"))
    data["environment"] = environment
    path = tmp_path / "robot.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    return path


def test_the_shipped_robot_file_loads_with_its_shorthand_expanded() -> None:
    config = load_behaviour(ROBOT).environment
    assert isinstance(config, Ros2Config)
    size = config.inputs["ball_size"]
    assert (size.topic, size.type, size.field) == ("/robot/ball_size", "std_msgs/Float64", ".data")
    assert config.command.fixed == {"linear.x": 1.0}
    assert config.episode.reset is not None and config.episode.reset.type == "std_msgs/Int64"
    assert config.period == 0.25 and config.stale_bound == 0.75


def test_laser_slices_poses_and_msg_spellings_are_accepted(tmp_path: Path) -> None:
    path = _with_environment(tmp_path, {
        "adapter": "ros2",
        "inputs": {"ball_size": "/scan sensor_msgs/msg/LaserScan ranges[0:90] min",
                   "pan": {"topic": "/odom", "type": "nav_msgs/Odometry", "pose": "bearing",
                           "target": [2.1, 0.0], "valid": [-180, 180]}},
        "command": {"topic": "/cmd", "type": "std_msgs/String"},
        "episode": {"reset": {"service": "/reset", "type": "std_srvs/srv/Trigger"},
                    "outcomes": [{"input": "ball_size", "max": 0.2, "reward": -1}]}})
    config = load_behaviour(path).environment
    assert isinstance(config, Ros2Config)
    scan = config.inputs["ball_size"]
    assert scan.type == "sensor_msgs/LaserScan" and scan.reduce == "min"
    assert str(scan.path) == ".ranges[0:90]"
    assert config.episode.reset is not None and config.episode.reset.type == "std_srvs/Trigger"


BAD = [
    ({"ball_size": "/scan sensor_msgs/LaserScan ranges[0:90]"}, "inputs.ball_size",
     "a slice needs reduce"),
    ({"ball_size": "/s std_msgs/Float32 .dta"}, "inputs.ball_size",
     "std_msgs/Float32 has no field 'dta'. Did you mean 'data'?"),
    ({"ball_size": "/s std_msgs/Flaot32"}, "inputs.ball_size",
     "unknown message type 'std_msgs/Flaot32'. Did you mean 'std_msgs/Float32'?"),
    ({"ball_size": "/s std_msgs/String"}, "inputs.ball_size", "is a string, not a number"),
    ({"ball_size": "/s nav_msgs/Odometry pose.pose"}, "inputs.ball_size",
     "is a geometry_msgs/Pose, not a number: name a numeric field (e.g. '.pose.pose.position.x')"),
    ({"ball_size": "/s sensor_msgs/LaserScan ranges"}, "inputs.ball_size",
     "is an array (float32[]): index it"),
    ({"ball_size": "/s std_msgs/Float64 data[0]"}, "inputs.ball_size", "not an array"),
    ({"ball_size": "/only_a_topic"}, "inputs.ball_size", "TOPIC TYPE"),
    ({"ball_size": "/1bad std_msgs/Float64"}, "inputs.ball_size.topic",
     "not a ROS 2 topic or service name"),
    ({"ball_size": {"topic": "/o", "type": "std_msgs/Float64", "pose": "heading"}},
     "inputs.ball_size", "carries no pose"),
]


@pytest.mark.parametrize(("inputs", "where", "message"), BAD,
                         ids=[b[2][:30] for b in BAD])
def test_a_bad_input_mapping_is_a_located_error(tmp_path: Path, inputs: dict[str, object],
                                                where: str, message: str) -> None:
    path = _with_environment(tmp_path, {
        "adapter": "ros2", "inputs": {"pan": "/pan std_msgs/Float64", **inputs},
        "command": {"topic": "/cmd_vel", "type": "geometry_msgs/Twist", "field": "angular.z"}})
    with pytest.raises(SpecError) as caught:
        load_behaviour(path)
    text = str(caught.value)
    assert f"environment.{where}" in text and message in text, text
    assert f"{path}:" in text  # file and line


def test_command_reset_and_fit_problems_are_located(tmp_path: Path) -> None:
    path = _with_environment(tmp_path, {
        "adapter": "ros2", "inputs": {"ball_size": "/s std_msgs/Float64", "pann": "/p "
                                      "std_msgs/Float64"},
        "command": {"topic": "/cmd_vel", "type": "geometry_msgs/Twist", "field": "angular.w"},
        "episode": {"reset": {"topic": "/reset", "type": "std_msgs/Float32"}}})
    with pytest.raises(SpecError) as caught:
        load_behaviour(path)
    text = str(caught.value)
    assert "environment.command: field geometry_msgs/Vector3 has no field 'w'" in text
    assert "environment.episode.reset: a reset topic cannot be of type 'std_msgs/Float32'" in text
    fixed = _with_environment(tmp_path, {
        "adapter": "ros2", "inputs": {"ball_size": "/s std_msgs/Float64", "pann": "/p "
                                      "std_msgs/Float64"},
        "command": {"topic": "/cmd_vel", "type": "geometry_msgs/Twist", "field": "angular.z"},
        "episode": {"outcomes": [{"input": "size", "min": 0.9}]}})
    with pytest.raises(SpecError) as caught:
        load_behaviour(fixed)
    text = str(caught.value)
    assert "environment.inputs: input 'pan' has no source" in text
    assert "environment.inputs.pann: 'pann' is not an input. Did you mean 'pan'?" in text
    assert "environment.episode.outcomes[0].input: 'size' is not an input" in text


@given(st.text(max_size=40))
def test_any_field_path_text_parses_or_is_refused_cleanly(text: str) -> None:
    try:
        path = parse_path(text)
    except ValueError as error:
        assert "field path" in str(error) or "slice" in str(error)
        return
    for type_name in ("sensor_msgs/LaserScan", "nav_msgs/Odometry"):
        with contextlib.suppress(ValueError):  # a path into fields it lacks: a clear refusal
            field_type(type_name, path)


def _rosbags_store() -> object:
    try:
        from rosbags.typesys import Stores, get_typestore
    except ImportError:
        if os.environ.get("FLCTOOL_REQUIRE_ROS2"):
            pytest.fail("FLCTOOL_REQUIRE_ROS2 is set but rosbags is missing "
                        "(pip install 'flctool[ros2]')")
        pytest.skip("rosbags is not installed (pip install 'flctool[ros2]')")
    return get_typestore(Stores.ROS2_KILTED)


def test_the_message_table_matches_ros2_kilted() -> None:
    """Every type and field of the closed table as rosbags' Kilted type store defines it."""
    store = _rosbags_store()
    defs = store.fielddefs  # type: ignore[attr-defined]
    for type_name, fields in MESSAGES.items():
        package, _, name = type_name.partition("/")
        _, definition = defs[f"{package}/msg/{name}"]
        assert [f for f, _ in definition] == list(fields) or (not fields and definition == [
            ("structure_needs_at_least_one_member", definition[0][1])]), type_name
        for field, (node, detail) in definition:
            if not fields:
                break
            expected = fields[field]
            if node.name == "BASE":
                assert detail[0] == expected, (type_name, field)
            elif node.name == "NAME":
                assert detail.replace("/msg/", "/") == expected, (type_name, field)
            else:  # SEQUENCE or ARRAY: (element, size)
                element, size = detail
                assert expected == f"{element[1][0]}[{size or ''}]", (type_name, field)
