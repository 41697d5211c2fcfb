"""Without the ros2 extra, ROS 2 commands say how to install it."""

from __future__ import annotations

import sys

import pytest

from flctool.errors import MissingDependencyError
from flctool.ros2 import import_rclpy


def test_a_missing_rclpy_gives_the_install_hint(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "rclpy", None)  # import rclpy now raises ImportError
    with pytest.raises(MissingDependencyError) as caught:
        import_rclpy()
    assert caught.value.hint == "pip install 'flctool[ros2]'"
    assert "ROS 2 needs the optional package 'ros-rclpy'" in str(caught.value)
