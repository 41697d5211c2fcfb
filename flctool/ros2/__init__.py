"""ROS 2 for flctool: the graph a node lives in, reading and writing message fields, which
robot file's topics a controller uses (:mod:`~flctool.ros2.section`), the deployment node
and its watchdog, and bags (docs/ros2.md). The simulator served as a ROS 2 robot is an
environment's job: :mod:`flctool.envs.ros2_robot`.

Everything here needs the optional extra ``flctool[ros2]`` (rclpy and the message packages from
PyPI's ROS 2 wheels; rosbags and mcap for bags), imported only when used: :func:`import_rclpy`
turns a missing package into an install hint. The behaviour-file side
(:mod:`flctool.behaviour.ros2`) needs none of it.
"""

from __future__ import annotations

from types import ModuleType

from flctool.errors import MissingDependencyError


def import_rclpy() -> ModuleType:
    """rclpy, or :class:`MissingDependencyError` with the ``ros2`` extra's install hint."""
    try:
        import rclpy
    except ImportError:
        raise MissingDependencyError("ros-rclpy", "ros2", "ROS 2") from None
    module: ModuleType = rclpy  # typed even where rclpy is absent (mypy reads it as Any)
    return module
