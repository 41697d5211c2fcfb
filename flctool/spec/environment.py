"""The ``environment:`` section: one config model per adapter, chosen by ``adapter``.

Lengths are in millimetres, angles in degrees (positive = counter-clockwise = to the left, as
in ROS), times in steps. docs/environments.md gives the rationale of every default.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import AfterValidator, Field, ValidationInfo, field_validator

from flctool.errors import Problem
from flctool.registry import did_you_mean
from flctool.spec.base import Name, Section

#: What the ballchase simulator observes; a behaviour's inputs are named after these.
BALLCHASE_OBSERVATIONS = ("ball_size", "pan")


class Pitch(Section):
    """The field the robot walks on, centred on the origin, length along x."""

    length: float = Field(4200.0, gt=0, description="mm along x (four-legged league: 4200)")
    width: float = Field(2700.0, gt=0, description="mm along y (four-legged league: 2700)")


class Robot(Section):
    """Geometry of an AIBO-class legged robot with a panning head camera."""

    radius: float = Field(150.0, gt=0, description=(
        "mm; the robot's centre keeps this far inside the pitch at the start"))
    neck_offset: float = Field(100.0, ge=0, description=(
        "mm from the body centre forward to the neck, where the head camera pans"))
    neck_range: float = Field(90.0, gt=0, le=180, description=(
        "deg; the head pans within +-neck_range, beyond it the ball is lost"))
    camera_fov: float = Field(56.9, gt=0, lt=180, description=(
        "deg, horizontal field of view of the camera (AIBO ERS-7: 56.9)"))


class Ball(Section):
    diameter: float = Field(80.0, gt=0, description="mm")


def _interval(bounds: tuple[float, float]) -> tuple[float, float]:
    low, high = bounds
    if not 0 < low <= high:
        raise ValueError(f"[{low:g}, {high:g}] must be [low, high] with 0 < low <= high")
    return bounds


class Start(Section):
    """Where an episode starts: the ball in front of the robot, its head already on it."""

    distance: Annotated[tuple[float, float], AfterValidator(_interval)] = Field(
        (400.0, 2000.0), description="mm, camera to ball centre, drawn uniformly")
    bearing: float = Field(60.0, ge=0, le=180, description=(
        "deg; the ball's bearing from the camera is drawn uniformly in +-bearing"))


class Goal(Section):
    """When the ball counts as reached: close, and the robot facing it."""

    distance: float = Field(120.0, gt=0, description="mm, camera to ball centre")
    bearing: float = Field(20.0, gt=0, le=180, description="deg, |pan| at most this")


class SensorNoise(Section):
    """Standard deviations of the observation noise (Gaussian, per step)."""

    ball_size: float = Field(0.02, ge=0, description="relative: size * (1 + std * z)")
    pan: float = Field(2.0, ge=0, description="deg")


class Motion(Section):
    """A displacement in the robot's frame per step (mean or standard deviation)."""

    forward: float = Field(description="mm along the heading")
    sideways: float = Field(description="mm to the left")
    rotation: float = Field(description="deg, positive = turn left")


class MotionNoise(Motion):
    forward: float = Field(ge=0, description="mm, standard deviation")
    sideways: float = Field(ge=0, description="mm, standard deviation")
    rotation: float = Field(ge=0, description="deg, standard deviation")


def _motion(forward: float, sideways: float, rotation: float) -> Motion:
    return Motion(forward=forward, sideways=sideways, rotation=rotation)


def _noise(forward: float, sideways: float, rotation: float) -> MotionNoise:
    return MotionNoise(forward=forward, sideways=sideways, rotation=rotation)


# Step period 0.25 s. An AIBO-class robot walks straight at about 240 mm/s, arcs at about
# 200 mm/s while turning 30 deg/s, and turns on the spot at about 60 deg/s, with a little
# forward creep; the deviations are about 10-20 % of the means plus slip in every direction.
DEFAULT_MOTION: dict[str, Motion] = {
    "turn_right": _motion(5.0, 0.0, -15.0),
    "forward_right": _motion(50.0, 0.0, -7.5),
    "forward": _motion(60.0, 0.0, 0.0),
    "forward_left": _motion(50.0, 0.0, 7.5),
    "turn_left": _motion(5.0, 0.0, 15.0),
}
DEFAULT_NOISE: dict[str, MotionNoise] = {
    "turn_right": _noise(4.0, 4.0, 2.0),
    "forward_right": _noise(8.0, 5.0, 1.5),
    "forward": _noise(8.0, 5.0, 1.5),
    "forward_left": _noise(8.0, 5.0, 1.5),
    "turn_left": _noise(4.0, 4.0, 2.0),
}


def _extend_defaults(table: Any, defaults: dict[str, Any]) -> Any:
    """A command table as written, over the defaults: entries given replace or add to them."""
    if not isinstance(table, dict):
        return table  # pydantic reports the wrong type
    return {**defaults, **table}


def command_table_problems(motion: dict[str, Motion], noise: dict[str, MotionNoise],
                           commands: tuple[str, ...]) -> list[Problem]:
    """Output commands without a motion, and table entries that name no command (a typo)."""
    problems = [
        Problem(("environment", "motion"), f"output command '{name}' has no motion",
                f"add '{name}: {{forward: mm, sideways: mm, rotation: deg}}' to "
                "environment.motion and its standard deviations to environment.noise "
                f"(the table has: {', '.join(motion)})")
        for name in commands if name not in motion]
    missing = [name for name in commands if name in motion and name not in noise]
    if missing:
        problems.append(Problem(
            ("environment", "noise"),
            f"no noise for command{'s' if len(missing) > 1 else ''} {', '.join(missing)}",
            f"add e.g. '{missing[0]}: {{forward: 0, sideways: 0, rotation: 0}}' to "
            "environment.noise for a noiseless command"))
    # Entries the defaults bring are harmless when unused; one the file adds that names no
    # output command is almost always a misspelt command, which would otherwise be ignored.
    for table_name, table in (("motion", motion), ("noise", noise)):
        problems += [
            Problem(("environment", table_name, name),
                    f"'{name}' is not an output command.{did_you_mean(name, commands)}",
                    f"name one of the output commands: {', '.join(commands)}")
            for name in table if name not in commands and name not in DEFAULT_MOTION]
    return problems


class BallchaseSimConfig(Section):
    """The ballchase simulator of paper Sec. IV (see docs/environments.md)."""

    adapter: Literal["ballchase-sim"]
    max_steps: int = Field(200, ge=1, description="steps before an episode is truncated")
    step_period: float = Field(0.25, gt=0, description=(
        "s per step; documents the units of the motion table (a step is one command)"))
    action: Literal["crisp", "nearest", "vote"] = Field("crisp", description=(
        "crisp: blend the two commands around the output a (piecewise linear over the "
        "sorted singletons); nearest: execute the command whose singleton is nearest a; "
        "vote: each command's firing rules sum their activations, the strongest command "
        "runs"))
    robot: Robot = Robot()
    ball: Ball = Ball()
    start: Start = Start()
    goal: Goal = Goal()
    pitch: Pitch = Pitch()
    sensor_noise: SensorNoise = SensorNoise()
    motion: dict[Name, Motion] = Field(default_factory=lambda: dict(DEFAULT_MOTION), description=(
        "command name -> mean displacement per step; every output command needs one. Extends "
        "the default table (turn_right, forward_right, forward, forward_left, turn_left): "
        "an entry given replaces the default of that name or adds a command"))
    noise: dict[Name, MotionNoise] = Field(
        default_factory=lambda: dict(DEFAULT_NOISE), validate_default=True, description=(
            "command name -> standard deviation of the displacement per step; every output "
            "command needs one. Extends the default table like motion"))

    @field_validator("motion", mode="before")
    @classmethod
    def _motion_over_defaults(cls, motion: Any) -> Any:
        return _extend_defaults(motion, DEFAULT_MOTION)

    @field_validator("noise", mode="before")
    @classmethod
    def _noise_over_defaults(cls, noise: Any) -> Any:
        return _extend_defaults(noise, DEFAULT_NOISE)

    @field_validator("start")
    @classmethod
    def _start_within_neck(cls, start: Start, info: ValidationInfo) -> Start:
        robot = info.data.get("robot")
        if robot is not None and start.bearing > robot.neck_range:
            raise ValueError(f"start bearing {start.bearing:g} deg is beyond the neck range "
                             f"+-{robot.neck_range:g} deg: every episode would start lost")
        return start

    @field_validator("goal")
    @classmethod
    def _goal_before_start(cls, goal: Goal, info: ValidationInfo) -> Goal:
        start = info.data.get("start")
        if start is not None and goal.distance >= start.distance[0]:
            raise ValueError(f"goal distance {goal.distance:g} mm must be below the nearest "
                             f"start distance {start.distance[0]:g} mm, or episodes start "
                             "at the goal")
        return goal

    @field_validator("pitch")
    @classmethod
    def _room_to_start(cls, pitch: Pitch, info: ValidationInfo) -> Pitch:
        robot, ball, start = (info.data.get(k) for k in ("robot", "ball", "start"))
        if robot is None or ball is None or start is None:
            return pitch
        # The farthest start must fit with the robot and the ball both on the pitch, in
        # any direction: see BallchaseSim's start placement.
        need = max(start.distance[1] + robot.neck_offset + robot.radius + ball.diameter / 2,
                   2 * robot.radius)
        short = min(pitch.length, pitch.width)
        if short < need:
            raise ValueError(
                f"the pitch ({pitch.length:g} x {pitch.width:g} mm) is too small for the robot: "
                f"length and width must each be at least start.distance max + "
                f"robot.neck_offset + robot.radius + ball.diameter/2 (and 2 robot.radius) = "
                f"{need:g} mm")
        return pitch

    def fit_problems(self, inputs: tuple[str, ...], commands: tuple[str, ...]) -> list[Problem]:
        """What keeps this simulator from running a behaviour with these inputs and commands.

        Checked when a file is validated, so `flctool validate` catches it before a run.
        """
        problems = [
            Problem(("inputs", name), f"the ballchase simulator has no observation '{name}'",
                    "name the inputs after its observations: "
                    + ", ".join(BALLCHASE_OBSERVATIONS))
            for name in inputs if name not in BALLCHASE_OBSERVATIONS]
        return problems + command_table_problems(self.motion, self.noise, commands)


class GymnasiumConfig(Section):
    """Any Gymnasium environment with a Box observation and a Discrete or Box action space."""

    adapter: Literal["gymnasium"]
    id: str = Field(description="a registered Gymnasium id, e.g. CartPole-v1")
    max_steps: int | None = Field(None, ge=1, description=(
        "steps before truncation; default: the environment's own time limit"))
    observations: dict[Name, int] = Field(default_factory=dict, description=(
        "behaviour input name -> index of the observation component it reads; "
        "default: the inputs in order read components 0, 1, ..."))
    actions: dict[Name, int] = Field(default_factory=dict, description=(
        "Discrete action spaces: command name -> action index; the crisp output executes "
        "the action of the command with the nearest singleton. Box action spaces: leave "
        "empty, the crisp output is the action"))
    action: Literal["nearest", "vote"] = Field("nearest", description=(
        "nearest: the command whose singleton is nearest the crisp output (eq. 3) runs; "
        "vote: each command's firing rules sum their activations and the strongest command "
        "runs (no dead zone between opposite commands)"))
    success: Literal["terminated", "truncated", "never"] = Field("terminated", description=(
        "which episode end counts as success: terminated (reached a goal, e.g. "
        "MountainCar), truncated (survived to the time limit, e.g. CartPole), or never"))
    options: dict[str, float | int | str | bool] = Field(default_factory=dict, description=(
        "keyword arguments for gymnasium.make"))

    @field_validator("observations", "actions")
    @classmethod
    def _non_negative(cls, mapping: dict[str, int]) -> dict[str, int]:
        for name, index in mapping.items():
            if index < 0:
                raise ValueError(f"'{name}': index {index} must be >= 0")
        return mapping


class RobotLinkConfig(Section):
    """A real robot, or its bridge, over TCP (protocol: docs/robot-link.md).

    The robot side owns the episode: its observations, commands and ``max_steps`` are checked
    against the behaviour in the handshake, when the link connects.
    """

    adapter: Literal["robot-link"]
    host: str = Field("127.0.0.1", min_length=1, description=(
        "host name or IP address of the robot or its bridge"))
    port: int = Field(ge=1, le=65535, description=(
        "TCP port the robot's bridge listens on (flctool serve prints its port)"))
    connect_timeout: float = Field(5.0, gt=0, description=(
        "s to open the connection and receive the handshake reply"))
    reset_timeout: float = Field(60.0, gt=0, description=(
        "s to wait for the reply to reset: a real robot may need a person to place it and "
        "the ball"))
    step_timeout: float = Field(2.0, gt=0, description=(
        "s to wait for the reply to each step (and to stop); longer means a fault: the "
        "robot is sent stop and the run ends"))
    retries: int = Field(2, ge=0, le=100, description=(
        "further connection attempts after a refused or timed-out connect; steps are never "
        "retried (a step moves the robot)"))
    retry_delay: float = Field(1.0, ge=0, description="s between connection attempts")


EnvironmentConfig = Annotated[
    BallchaseSimConfig | GymnasiumConfig | RobotLinkConfig,
    Field(discriminator="adapter"),
]
ADAPTER_NAMES = ("ballchase-sim", "gymnasium", "robot-link")
