"""The ``environment: {adapter: ros2}`` section: a robot that runs ROS 2 (docs/ros2.md).

Each behaviour input reads one number from a topic (a message type and a field path, or a pose
turned into a bearing, distance or heading); the crisp output (eq. 3) is published on a command
topic; the episode starts by a reset topic or service and ends by a status topic, outcome rules
over the inputs, or ``max_steps``. Message types and field paths are checked against the
definitions of :mod:`flctool.behaviour.ros2_messages` when the file is loaded -- no ROS needed.
"""

from __future__ import annotations

import re
from typing import Annotated, Any, Literal

from pydantic import AfterValidator, Field, field_validator, model_validator

from flctool.behaviour.base import Name, Section
from flctool.behaviour.environment import AdapterConfig
from flctool.behaviour.ros2_messages import (
    POSES,
    REDUCTIONS,
    SERVICES,
    FieldPath,
    message_problem,
    normal_type,
    numeric_problem,
    parse_path,
)
from flctool.errors import Problem
from flctool.registry import did_you_mean

_NAME = re.compile(r"^~?/?[A-Za-z_][A-Za-z0-9_]*(/[A-Za-z_][A-Za-z0-9_]*)*$")


def _ros_name(name: str) -> str:
    if not _NAME.match(name) or "//" in name or len(name) > 200:
        raise ValueError(f"'{name}' is not a ROS 2 topic or service name: write e.g. '/scan' "
                         "or '/robot1/cmd_vel' (letters, digits and _ between slashes)")
    return name


RosName = Annotated[str, AfterValidator(_ros_name)]


def _message_type(name: str) -> str:
    problem = message_problem(name)
    if problem:
        raise ValueError(problem)
    return normal_type(name)


MessageType = Annotated[str, AfterValidator(_message_type)]


class Qos(Section):
    """A topic's quality of service; every key defaults to the ROS 2 default profile."""

    reliability: Literal["reliable", "best_effort"] = Field("reliable", description=(
        "best_effort for sensor streams published that way (a reliable subscription does not "
        "match a best-effort publisher)"))
    durability: Literal["volatile", "transient_local"] = "volatile"
    depth: int = Field(10, ge=1, le=1000, description="messages kept (history keep_last)")


class Topic(Section):
    topic: RosName = Field(description="the topic's name, e.g. /scan")
    type: MessageType = Field(description="message type, e.g. sensor_msgs/LaserScan")
    qos: Qos = Field(default_factory=Qos, description="quality of service; ROS 2 defaults")


def _shorthand(value: Any) -> Any:
    """``"TOPIC TYPE [FIELD] [REDUCTION]"`` as the object form."""
    if not isinstance(value, str):
        return value
    parts = value.split()
    if not 2 <= len(parts) <= 4:
        raise ValueError(f"'{value}': write 'TOPIC TYPE [FIELD] [min|max|mean]', e.g. "
                         "'/scan sensor_msgs/LaserScan ranges[0:90] min'")
    data: dict[str, Any] = {"topic": parts[0], "type": parts[1]}
    if len(parts) > 2:
        data["field"] = parts[2]
    if len(parts) > 3:
        data["reduce"] = parts[3]
    return data


class InputSource(Topic):
    """Where one behaviour input comes from: one number of the latest message on a topic.

    ``field`` names it (``.data``, ``ranges[0:90]`` with ``reduce``), or ``pose`` derives it
    from a pose-carrying message (Odometry, PoseStamped, Pose, Pose2D). Then
    ``value * scale + offset``.
    """

    field: str | None = Field(None, description=(
        "field path to a number, e.g. .data, angular.z, ranges[3], ranges[0:90]; default "
        ".data"))
    reduce: Literal["min", "max", "mean"] | None = Field(None, description=(
        "one number from a slice: the minimum, maximum or mean of its finite values"))
    pose: Literal["bearing", "distance", "heading", "x", "y"] | None = Field(None, description=(
        "from the message's pose: bearing (deg, positive to the left) or distance (the "
        "message's units) of target, heading (deg, yaw), or x / y"))
    target: tuple[float, float] | None = Field(None, description=(
        "[x, y] of the point a bearing or distance is to, in the pose's frame"))
    scale: float = Field(1.0, description="multiplies the value; not 0")
    offset: float = Field(0.0, description="added last: value * scale + offset")
    valid: tuple[float, float] | None = Field(None, description=(
        "[low, high]: a value outside is a fault (the robot is stopped); default any finite "
        "value (values beyond the input's range are clipped to it as usual)"))

    @model_validator(mode="before")
    @classmethod
    def _expand_shorthand(cls, value: Any) -> Any:
        return _shorthand(value)

    @model_validator(mode="after")
    def _readable(self) -> InputSource:
        if self.scale == 0:
            raise ValueError("scale 0 makes the input a constant; use a non-zero scale")
        if self.valid is not None and self.valid[0] > self.valid[1]:
            raise ValueError("valid must be [low, high] with low <= high")
        if self.pose is not None:
            if self.type not in POSES:
                raise ValueError(f"pose: {self.type} carries no pose; use one of "
                                 f"{', '.join(POSES)}")
            if self.field is not None or self.reduce is not None:
                raise ValueError("give either pose or field (and reduce), not both")
            if (self.pose in ("bearing", "distance")) != (self.target is not None):
                raise ValueError("pose bearing and distance need target: [x, y]; the others "
                                 "take none")
            return self
        if self.target is not None:
            raise ValueError("target applies to pose: bearing or distance only")
        path = self.path
        problem = numeric_problem(self.type, path)
        if problem:
            raise ValueError(f"field {problem}")
        if path.is_slice != (self.reduce is not None):
            raise ValueError(f"a slice needs reduce: {' | '.join(REDUCTIONS)}; an index or a "
                             "field takes none" if path.is_slice else
                             "reduce applies to a slice, e.g. ranges[0:90]")
        return self

    @property
    def path(self) -> FieldPath:
        """The parsed field path (``.data`` when none is given)."""
        return parse_path(self.field or ".data")


class CommandTopic(Topic):
    """Where the crisp output goes: one numeric field of a message, ``a * scale + offset``
    (the other fields 0, or ``fixed``), or -- for ``std_msgs/String`` -- the name of the
    command whose singleton is nearest ``a``."""

    field: str | None = Field(None, description=(
        "field path of the number, e.g. angular.z for geometry_msgs/Twist; none for "
        "std_msgs/String"))
    scale: float = Field(1.0, description="published value = a * scale + offset")
    offset: float = 0.0
    fixed: dict[str, float] = Field(default_factory=dict, description=(
        "other numeric fields set while running, e.g. {linear.x: 0.2}; the stop command "
        "sets them to 0"))
    stop: str = Field("stop", min_length=1, max_length=200, description=(
        "std_msgs/String only: the text published to stop"))

    @model_validator(mode="after")
    def _writable(self) -> CommandTopic:
        if self.type == "std_msgs/String":
            if self.field is not None or self.fixed:
                raise ValueError("a std_msgs/String command carries the command's name: it "
                                 "takes no field or fixed")
            return self
        if self.field is None:
            raise ValueError(f"name the field the output goes to, e.g. field: angular.z "
                             f"(for {self.type})")
        for text in (self.field, *self.fixed):
            path = parse_path(text)
            problem = numeric_problem(self.type, path)
            if problem is None and path.start is not None:
                problem = f"'{path}': a command field cannot be an array element"
            if problem:
                raise ValueError(f"{'field' if text == self.field else 'fixed'} {problem}")
        if self.field in self.fixed:
            raise ValueError(f"'{self.field}' is the output's field; it cannot also be fixed")
        return self


#: Message types a reset topic may carry: the seed, or nothing.
RESET_TYPES = ("std_msgs/Int64", "std_msgs/UInt64", "std_msgs/Int32", "std_msgs/UInt32",
               "std_msgs/Empty")


class Reset(Section):
    """How an episode is started: a message on a ``topic`` (the seed as an integer message,
    or ``std_msgs/Empty``), or a call to a ``service`` (``std_srvs/Empty`` or ``Trigger``)."""

    topic: RosName | None = Field(None, description="a reset topic, e.g. /reset")
    service: RosName | None = Field(None, description="a reset service, e.g. /reset_world")
    type: str = Field(description=f"topic: one of {', '.join(RESET_TYPES)}; service: one of "
                      f"{', '.join(SERVICES)}")
    qos: Qos = Field(default_factory=Qos, description="the topic's quality of service")

    @model_validator(mode="after")
    def _one_way(self) -> Reset:
        if (self.topic is None) == (self.service is None):
            raise ValueError("give either topic or service")
        kind = normal_type(self.type)
        allowed = RESET_TYPES if self.topic is not None else SERVICES
        if kind not in allowed:
            raise ValueError(f"a reset {'topic' if self.topic else 'service'} cannot be of type "
                             f"'{self.type}'.{did_you_mean(kind, allowed)} Use one of "
                             f"{', '.join(allowed)}")
        object.__setattr__(self, "type", kind)
        return self


class StatusTopic(Topic):
    """The robot's word on the episode, a std_msgs/String: running, success, failure or
    timeout."""

    @field_validator("type")
    @classmethod
    def _string(cls, kind: str) -> str:
        if kind != "std_msgs/String":
            raise ValueError("the status topic is a std_msgs/String (running, success, "
                             "failure, timeout)")
        return kind


class RewardTopic(Topic):
    field: str | None = Field(None, description="field path of the reward; default .data")

    @model_validator(mode="after")
    def _numeric(self) -> RewardTopic:
        problem = numeric_problem(self.type, parse_path(self.field or ".data"))
        if problem:
            raise ValueError(f"field {problem}")
        return self


class OutcomeRule(Section):
    """Ends the episode when a mapped input (its value after scale and offset) reaches a
    threshold; the first rule that holds wins."""

    input: Name = Field(description="a behaviour input")
    min: float | None = Field(None, description="holds when the input >= min")
    max: float | None = Field(None, description="holds when the input <= max")
    reward: float = Field(0.0, description="given at the step the episode ends")
    success: bool = False

    @model_validator(mode="after")
    def _bound(self) -> OutcomeRule:
        if self.min is None and self.max is None:
            raise ValueError("an outcome rule needs min and/or max")
        return self


class Episode(Section):
    """How an episode starts and ends on the robot."""

    max_steps: int = Field(200, ge=1, le=1_000_000, description=(
        "control steps before the episode is truncated"))
    reset: Reset | None = Field(None, description=(
        "how to start an episode: {topic, type} publishes the seed (or Empty), {service, "
        "type} calls std_srvs/Empty or Trigger; none: an episode starts when every input "
        "has a fresh message"))
    status: StatusTopic | None = Field(None, description=(
        "the robot's episode status: running, success, failure or timeout"))
    reward: RewardTopic | None = Field(None, description=(
        "a reward topic: each step's reward is the sum of the values received during it"))
    outcomes: list[OutcomeRule] = Field(default_factory=list, max_length=32, description=(
        "rules over the inputs that end the episode (checked after the status)"))
    fitness: Literal["return", "timed"] = Field("return", description=(
        "the GA's trial fitness: the undiscounted return, or timed (as the pitch world: "
        "success after L steps 2 - L/max_steps, else 0.5 L/max_steps)"))


class Ros2Config(AdapterConfig):
    """A robot that runs ROS 2 (docs/ros2.md)."""

    adapter: Literal["ros2"]
    inputs: dict[Name, InputSource] = Field(description=(
        "behaviour input -> its source: 'TOPIC TYPE [FIELD] [REDUCTION]' or {topic, type, "
        "field, reduce, pose, target, scale, offset, valid, qos}"))
    command: CommandTopic = Field(description="where the crisp output is published")
    episode: Episode = Field(default_factory=Episode)
    rate: float = Field(4.0, gt=0, le=1000, description=(
        "control rate in Hz: a command per period (the paper's robot: 4 Hz)"))
    sync: Literal["rate", "lockstep"] = Field("rate", description=(
        "rate: each step lasts one period and reads the latest inputs; lockstep: each step "
        "waits for a fresh message on every input (a simulator that steps per command)"))
    stale_after: float | None = Field(None, gt=0, description=(
        "s; an input older than this is a fault (default: 3 control periods)"))
    startup_timeout: float = Field(10.0, gt=0, description=(
        "s to find every topic's publishers and subscribers"))
    reset_timeout: float = Field(60.0, gt=0, description=(
        "s for a reset to be answered by fresh inputs (a person may place the robot)"))
    step_timeout: float = Field(2.0, gt=0, description=(
        "s a lockstep step waits for fresh inputs"))
    node: Name = Field("flctool", description="the node's name")
    namespace: str = Field("", max_length=200, description="the node's namespace, e.g. /robot1")

    @field_validator("namespace")
    @classmethod
    def _namespace(cls, namespace: str) -> str:
        if namespace and not _NAME.match(namespace):
            raise ValueError(f"'{namespace}' is not a namespace: write e.g. /robot1")
        return namespace

    @property
    def period(self) -> float:
        return 1.0 / self.rate

    @property
    def stale_bound(self) -> float:
        """s after which an input is stale."""
        return self.stale_after if self.stale_after is not None else 3.0 * self.period

    def fit_problems(self, inputs: tuple[str, ...], commands: tuple[str, ...]) -> list[Problem]:
        """Every behaviour input mapped, nothing else; outcome rules over inputs."""
        del commands
        problems = [Problem(("environment", "inputs"), f"input '{name}' has no source",
                            f"add '{name}: TOPIC TYPE FIELD' to environment.inputs")
                    for name in inputs if name not in self.inputs]
        problems += [Problem(("environment", "inputs", name), f"'{name}' is not an input."
                             f"{did_you_mean(name, inputs)}", "map behaviour inputs only")
                     for name in self.inputs if name not in inputs]
        problems += [Problem(("environment", "episode", "outcomes", i, "input"),
                             f"'{rule.input}' is not an input.{did_you_mean(rule.input, inputs)}",
                             f"use one of {', '.join(inputs)}")
                     for i, rule in enumerate(self.episode.outcomes) if rule.input not in inputs]
        return problems
