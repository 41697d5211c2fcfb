"""The graph a node lives in: waits on conditions, and a graph left open does not abort the
interpreter at exit."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from ..ros2_support import require_ros2, ros_environment


@pytest.mark.slow
def test_a_graph_left_open_is_closed_at_exit_without_aborting() -> None:
    require_ros2()
    script = ("from flctool.ros2.graph import RosGraph\n"
              "graph = RosGraph('left_open')\n"
              "assert graph.wait(lambda: True, 0.1) and not graph.wait(lambda: False, 0.1)\n"
              "print('left open')\n")
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                            timeout=60, env={**os.environ, **ros_environment()}, check=False)
    assert result.returncode == 0, result.stderr
    assert result.stdout == "left open\n" and "terminate called" not in result.stderr
