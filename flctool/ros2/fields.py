"""Numbers out of ROS 2 messages and commands into them, by the field paths of
:mod:`flctool.behaviour.ros2_messages`.

The readers and writers work on any object with the message's attributes -- rclpy messages, and
the messages rosbags deserializes from a bag -- so replay and fit-sim read bags with the same
code the live adapter reads topics with. Message classes are imported from the packages of the
closed message table only.
"""

from __future__ import annotations

import importlib
import math
from collections.abc import Callable
from typing import Any

from flctool.behaviour.ros2 import CommandTopic, InputSource, OutcomeRule, Qos
from flctool.behaviour.ros2_messages import MESSAGES, POSES, SERVICES, FieldPath, parse_path
from flctool.errors import MissingDependencyError

#: The status texts of an episode status topic.
STATUSES = ("running", "success", "failure", "timeout")

Reader = Callable[[Any], float]


def message_class(type_name: str, kind: str = "msg") -> Any:
    """The rclpy class of a message (or service) type of the closed table."""
    if type_name not in (MESSAGES if kind == "msg" else SERVICES):
        raise ValueError(f"{type_name} is not a supported {kind} type")
    package, _, name = type_name.partition("/")
    try:
        module = importlib.import_module(f"{package}.{kind}")
    except ImportError:
        raise MissingDependencyError(f"ros-{package.replace('_', '-')}", "ros2",
                                     f"the ROS 2 type {type_name}") from None
    return getattr(module, name)


def _walk(message: Any, names: tuple[str, ...]) -> Any:
    for name in names:
        message = getattr(message, name)
    return message


def read_path(message: Any, path: FieldPath, reduce: str | None = None) -> float:
    """The number at ``path``; NaN when an index lies beyond the array or a slice has no
    finite value (the caller's watchdog treats NaN as a fault)."""
    value = _walk(message, path.names)
    if path.start is None:
        return float(value)
    values = list(value)
    if path.stop is None:
        return float(values[path.start]) if path.start < len(values) else math.nan
    part = [float(v) for v in values[path.start:path.stop] if math.isfinite(float(v))]
    if not part:
        return math.nan
    if reduce == "min":
        return min(part)
    if reduce == "max":
        return max(part)
    return math.fsum(part) / len(part)


def yaw(quaternion: Any) -> float:
    """The rotation about z of a quaternion, in radians."""
    x, y, z, w = (float(quaternion.x), float(quaternion.y), float(quaternion.z),
                  float(quaternion.w))
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def pose_of(message: Any, type_name: str) -> tuple[float, float, float]:
    """(x, y, heading in radians) of a pose-carrying message."""
    x_path, y_path, heading_path = POSES[type_name]
    x = float(_walk(message, parse_path(x_path).names))
    y = float(_walk(message, parse_path(y_path).names))
    heading = _walk(message, parse_path(heading_path).names)
    return x, y, float(heading) if isinstance(heading, (int, float)) else yaw(heading)


def wrap_degrees(angle: float) -> float:
    """An angle in degrees, in [-180, 180)."""
    return (angle + 180.0) % 360.0 - 180.0


def input_reader(source: InputSource) -> Reader:
    """message -> the input's value (after scale and offset)."""
    scale, offset = source.scale, source.offset
    if source.pose is None:
        path, reduce = source.path, source.reduce
        return lambda message: read_path(message, path, reduce) * scale + offset
    kind, target, type_name = source.pose, source.target, source.type

    def from_pose(message: Any) -> float:
        x, y, heading = pose_of(message, type_name)
        if kind == "x":
            value = x
        elif kind == "y":
            value = y
        elif kind == "heading":
            value = wrap_degrees(math.degrees(heading))
        else:
            assert target is not None  # the model requires it
            dx, dy = target[0] - x, target[1] - y
            value = math.hypot(dx, dy) if kind == "distance" else wrap_degrees(
                math.degrees(math.atan2(dy, dx) - heading))
        return value * scale + offset
    return from_pose


def value_problem(name: str, value: float, source: InputSource) -> str | None:
    """Why an input's value is a fault (NaN, infinite, outside ``valid``), or None."""
    if not math.isfinite(value):
        return f"input {name} is {value} (from {source.topic})"
    if source.valid is not None and not source.valid[0] <= value <= source.valid[1]:
        return (f"input {name} = {value:g} is outside its valid range "
                f"[{source.valid[0]:g}, {source.valid[1]:g}] (from {source.topic})")
    return None


def outcome(rules: list[OutcomeRule], values: dict[str, float]) -> OutcomeRule | None:
    """The first rule that holds for these input values, or None."""
    for rule in rules:
        value = values[rule.input]
        if (rule.min is None or value >= rule.min) and (rule.max is None or value <= rule.max):
            return rule
    return None


def _set(message: Any, path: str, value: float) -> None:
    names = parse_path(path).names
    holder = _walk(message, names[:-1])
    current = getattr(holder, names[-1])
    setattr(holder, names[-1], type(current)(value))


def nearest_command(commands: dict[str, float], action: float) -> str:
    """The name of the command whose singleton is nearest ``action`` (the first on a tie)."""
    return min(commands, key=lambda name: abs(commands[name] - action))


class CommandWriter:
    """Builds the command messages of a :class:`CommandTopic`: a crisp output, or stop."""

    def __init__(self, topic: CommandTopic, commands: dict[str, float],
                 factory: Callable[[], Any]) -> None:
        self.topic = topic
        self.commands = dict(commands)
        self.factory = factory

    def command(self, action: float) -> Any:
        message = self.factory()
        if self.topic.type == "std_msgs/String":
            message.data = nearest_command(self.commands, action)
            return message
        assert self.topic.field is not None  # the model requires it for numeric types
        for path, value in self.topic.fixed.items():
            _set(message, path, value)
        _set(message, self.topic.field, action * self.topic.scale + self.topic.offset)
        return message

    def stop(self) -> Any:
        """The safe command: every numeric field 0 (a fresh message), or the stop text."""
        message = self.factory()
        if self.topic.type == "std_msgs/String":
            message.data = self.topic.stop
        return message


def qos_profile(qos: Qos) -> Any:
    """The rclpy QoSProfile of a topic's qos section."""
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

    return QoSProfile(
        history=HistoryPolicy.KEEP_LAST, depth=qos.depth,
        reliability=ReliabilityPolicy.RELIABLE if qos.reliability == "reliable"
        else ReliabilityPolicy.BEST_EFFORT,
        durability=DurabilityPolicy.VOLATILE if qos.durability == "volatile"
        else DurabilityPolicy.TRANSIENT_LOCAL)
