"""Numbers out of real ROS 2 messages by field path, pose, slice; commands into them."""

from __future__ import annotations

import math

import pytest

from flctool.behaviour.ros2 import CommandTopic, InputSource
from flctool.ros2.fields import CommandWriter, input_reader, message_class, nearest_command

from ..ros2_support import require_ros2


@pytest.fixture(autouse=True)
def _ros() -> None:
    require_ros2()


def test_a_laser_slice_reduces_its_finite_values() -> None:
    scan = message_class("sensor_msgs/LaserScan")()
    scan.ranges = [math.inf, 2.0, 0.5, math.nan, 3.0] + [9.0] * 10
    low = input_reader(InputSource.model_validate("/scan sensor_msgs/LaserScan ranges[0:5] min"))
    mean = input_reader(InputSource(topic="/scan", type="sensor_msgs/LaserScan",
                                    field="ranges[0:5]", reduce="mean", scale=2.0, offset=1.0))
    assert low(scan) == 0.5
    assert mean(scan) == pytest.approx((2.0 + 0.5 + 3.0) / 3 * 2.0 + 1.0)
    beyond = input_reader(InputSource(topic="/s", type="sensor_msgs/LaserScan",
                                      field="ranges[40]"))
    assert math.isnan(beyond(scan))  # an index past the array is a fault, not a crash


def test_an_odometry_pose_gives_bearing_distance_and_heading() -> None:
    odometry = message_class("nav_msgs/Odometry")()
    odometry.pose.pose.position.x, odometry.pose.pose.position.y = 1.0, 1.0
    odometry.pose.pose.orientation.z = math.sin(math.radians(90) / 2)  # facing +y
    odometry.pose.pose.orientation.w = math.cos(math.radians(90) / 2)

    def read(pose: str, target: tuple[float, float] | None = None) -> float:
        return input_reader(InputSource(topic="/odom", type="nav_msgs/Odometry", pose=pose,
                                        target=target))(odometry)

    assert read("heading") == pytest.approx(90.0)
    assert read("bearing", (2.0, 1.0)) == pytest.approx(-90.0)  # to the right
    assert read("bearing", (0.0, 2.0)) == pytest.approx(45.0)
    assert read("distance", (4.0, 5.0)) == pytest.approx(5.0)


def test_commands_scale_into_their_field_and_stop_zeroes_every_field() -> None:
    topic = CommandTopic(topic="/cmd_vel", type="geometry_msgs/Twist", field="angular.z",
                         scale=0.5, fixed={"linear.x": 0.2})
    writer = CommandWriter(topic, {"right": -1.0, "left": 1.0},
                           message_class("geometry_msgs/Twist"))
    twist = writer.command(0.8)
    assert (twist.angular.z, twist.linear.x) == (0.4, 0.2)
    stop = writer.stop()
    assert (stop.angular.z, stop.linear.x) == (0.0, 0.0)
    named = CommandWriter(CommandTopic(topic="/cmd", type="std_msgs/String"),
                          {"right": -1.0, "ahead": 0.0, "left": 1.0},
                          message_class("std_msgs/String"))
    assert named.command(0.6).data == "left" and named.stop().data == "stop"
    assert nearest_command({"a": -1.0, "b": 1.0}, 0.0) == "a"  # a tie takes the first
