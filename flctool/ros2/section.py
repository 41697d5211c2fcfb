"""Which ROS 2 section a controller runs with: its own ``environment: {adapter: ros2}``, or
that of a robot file (``--robot ROBOT.yaml``, for a controller learned in a simulator) --
checked against the controller either way, so that every input has a topic and nothing else
does. ``flctool run --ros2``, ``replay``, ``record``, ``fit-sim`` and ``export --format bundle
--robot`` choose it here, in one way.

Needs no rclpy: only the behaviour files are read.
"""

from __future__ import annotations

from pathlib import Path

from flctool.behaviour.located import locate_error
from flctool.behaviour.models import Behaviour
from flctool.behaviour.ros2 import Ros2Config
from flctool.errors import FlcError, SpecError


def ros2_section(behaviour: Behaviour, where: str, robot: Path | None = None,
                 own: Ros2Config | None = None,
                 inputs: tuple[str, ...] | None = None) -> tuple[Ros2Config, str]:
    """The ROS 2 section for ``behaviour`` (read from ``where``) and the file it came from:
    ``robot``'s when given, else ``own`` (a section found beside the controller, e.g. an
    export bundle's wiring), else the behaviour's own. A missing section, or one that does not
    map exactly what the deployment reads -- ``inputs``, by default the behaviour's inputs (a
    composition reads every channel of its arbiter and parts) -- is a located error."""
    from flctool.behaviour import load_behaviour

    read = behaviour.input_names if inputs is None else inputs
    config = own if own is not None else behaviour.environment
    holder = behaviour if own is None else None  # whose source map places a problem
    if robot is not None:
        holder = load_behaviour(robot)
        config, where = holder.environment, str(robot)
    if not isinstance(config, Ros2Config):
        if robot is not None:
            raise FlcError(f"{robot} has no 'environment: {{adapter: ros2, ...}}' section",
                           hint="see docs/ros2.md for the topics a robot file maps")
        raise FlcError(f"{where}'s environment is not a ROS 2 robot",
                       hint="name the robot's topics with --robot ROBOT.yaml (a behaviour "
                       "with environment: {adapter: ros2, ...} whose inputs are "
                       f"{', '.join(read)}, docs/ros2.md)")
    problems = config.fit_problems(read, tuple(behaviour.output.commands))
    if problems:
        error = SpecError(problems, where)
        raise error if holder is None else locate_error(holder, error)
    return config, where
