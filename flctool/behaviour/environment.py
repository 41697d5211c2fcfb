"""The ``environment:`` section: one config model per adapter, chosen by ``adapter``.

Lengths are in millimetres, angles in degrees (positive = counter-clockwise = to the left, as
in ROS), times in steps. docs/environments.md gives the rationale of every default.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Annotated, Any, Literal

from pydantic import AfterValidator, Field, ValidationInfo, field_validator, model_validator

from flctool.behaviour.base import Name, Section
from flctool.behaviour.pitch_vocabulary import (
    BallVelocity,
    DerivedChannel,
    FixedPoint,
    Opponent,
    Outcome,
    StepReward,
    vocabulary_problems,
)
from flctool.errors import FlcError, PathPart, Problem
from flctool.registry import did_you_mean

#: What the ballchase simulator observes; a behaviour's inputs are named after these.
BALLCHASE_OBSERVATIONS = ("ball_size", "pan")

#: At most this many parts in one composition (``environment.compose`` of the pitch world).
MAX_PARTS = 8


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


class AdapterConfig(Section):
    """Base of every ``environment:`` section; its ``adapter`` names the plugin that reads it
    (flctool.plugins)."""

    adapter: str = Field(description="which adapter reads this section")

    def fit_problems(self, inputs: tuple[str, ...], commands: tuple[str, ...]) -> list[Problem]:
        """What does not fit between this environment and the behaviour's input and command
        names (an observation it does not have, a command it cannot execute); none unless the
        adapter says."""
        del inputs, commands
        return []


class BallchaseSimConfig(AdapterConfig):
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


ObservationIndex = Annotated[int, Field(ge=0)]


class ObservationFeature(Section):
    """One behaviour input computed from a Gymnasium observation vector.

    Exactly one source: a ``component``, an ``angle`` from a cosine and a sine component, or
    the ``difference`` of two components. Then, in this order, ``abs`` takes its absolute
    value and ``scale`` and ``offset`` map it linearly: ``value * scale + offset``.
    """

    component: ObservationIndex | None = Field(None, description=(
        "index of the observation component the input reads"))
    angle: tuple[ObservationIndex, ObservationIndex] | None = Field(None, description=(
        "[cos index, sin index]: the angle atan2(sin, cos) in radians, in [-pi, pi]; one "
        "input in place of two (e.g. Pendulum's [0, 1])"))
    difference: tuple[ObservationIndex, ObservationIndex] | None = Field(None, description=(
        "[i, j]: component i minus component j"))
    abs: bool = Field(False, description="take the absolute value (before scale and offset)")
    scale: float = Field(1.0, description=(
        "multiplies the value (after abs), e.g. 57.29578 for degrees from radians; not 0"))
    offset: float = Field(0.0, description="added last: value * scale + offset")

    @model_validator(mode="after")
    def _one_source(self) -> ObservationFeature:
        sources = [k for k in ("component", "angle", "difference") if getattr(self, k) is not None]
        if len(sources) != 1:
            raise ValueError("give exactly one of component, angle or difference (got "
                             f"{', '.join(sources) or 'none'})")
        if self.scale == 0:
            raise ValueError("scale 0 makes the input a constant; use a non-zero scale")
        return self

    @property
    def indices(self) -> tuple[int, ...]:
        """The observation components this feature reads."""
        if self.component is not None:
            return (self.component,)
        pair = self.angle if self.angle is not None else self.difference
        assert pair is not None
        return pair

    def value(self, observation: Sequence[float]) -> float:
        """The input's value for one observation vector ``(D,)``."""
        if self.component is not None:
            value = float(observation[self.component])
        elif self.angle is not None:
            value = math.atan2(float(observation[self.angle[1]]),
                               float(observation[self.angle[0]]))
        else:
            assert self.difference is not None
            value = float(observation[self.difference[0]]) - float(
                observation[self.difference[1]])
        if self.abs:
            value = abs(value)
        return value * self.scale + self.offset

    def bounds(self, low: Sequence[float], high: Sequence[float]) -> tuple[float, float]:
        """The interval of the value when each component i lies in [low[i], high[i]];
        infinite where the observation space is unbounded."""
        if self.component is not None:
            lo, hi = float(low[self.component]), float(high[self.component])
        elif self.angle is not None:
            lo, hi = -math.pi, math.pi
        else:
            assert self.difference is not None
            i, j = self.difference
            lo, hi = float(low[i]) - float(high[j]), float(high[i]) - float(low[j])
        if self.abs:
            lo, hi = (lo, hi) if lo >= 0 else (-hi, -lo) if hi <= 0 else (0.0, max(-lo, hi))
        lo, hi = lo * self.scale + self.offset, hi * self.scale + self.offset
        return (lo, hi) if lo <= hi else (hi, lo)


# -- the pitch world ---------------------------------------------------------------------------

#: The pitch world's sensor channels, in the order their noise columns are drawn. Angles are
#: bearings in degrees relative to the robot's heading (positive = to the left), distances mm.
PITCH_CHANNELS = (
    "ball_size", "pan", "ball_distance", "goal_bearing", "goal_distance", "obstacle_bearing",
    "obstacle_distance", "home_bearing", "home_distance", "heading", "x", "y", "ball_x",
    "ball_y", "own_goal_bearing", "own_goal_distance", "ball_vx", "ball_vy",
    "opponent_bearing", "opponent_distance")
#: Channels whose noise is relative (reading * (1 + std * z)); the others add std * z.
RELATIVE_CHANNELS = ("ball_size", "ball_distance", "goal_distance", "obstacle_distance",
                     "home_distance", "own_goal_distance", "opponent_distance")


def _box(bounds: tuple[float, float]) -> tuple[float, float]:
    low, high = bounds
    if low > high:
        raise ValueError(f"[{low:g}, {high:g}] must be [low, high] with low <= high")
    return bounds


Interval = Annotated[tuple[float, float], AfterValidator(_box)]


class Field2D(Pitch):
    """The pitch of the pitch world: goals centred on both short sides."""

    goal_width: float = Field(800.0, gt=0, description=(
        "mm, width of each goal mouth (four-legged league: 800); the target goal is at "
        "x = +length/2, the own goal at x = -length/2"))


class PitchBall(Ball):
    """The ball and how it moves when the robot pushes it (docs/environments.md)."""

    movable: bool = Field(True, description="false: the ball never moves")
    kick: float = Field(1.2, ge=0, le=5, description=(
        "on contact the ball takes this many times the robot's displacement of the step as "
        "its velocity (mm per step)"))
    friction: float = Field(0.25, ge=0, le=1, description=(
        "fraction of the ball's velocity lost per step while rolling"))


class RobotStart(Section):
    """The robot's start pose, each drawn uniformly."""

    x: Interval = Field((-1500.0, 1500.0), description="mm")
    y: Interval = Field((-1000.0, 1000.0), description="mm")
    heading: Interval = Field((-180.0, 180.0), description="deg, 0 = facing the target goal")


class BallStart(Section):
    """Where the ball starts: in a box on the pitch (x, y), or ahead of the robot's camera
    (distance, bearing) -- then the robot is placed anywhere the two fit, as in ballchase."""

    x: Interval | None = Field(None, description="mm; with y: uniform in this box")
    y: Interval | None = Field(None, description="mm")
    distance: Annotated[tuple[float, float], AfterValidator(_interval)] | None = Field(
        None, description="mm, camera to ball, uniform; with bearing")
    bearing: float | None = Field(None, ge=0, le=180, description=(
        "deg, the ball's bearing from the camera is uniform in +-bearing"))

    @property
    def ahead(self) -> bool:
        return self.distance is not None


def _ball_start(start: BallStart) -> BallStart:
    box = start.x is not None and start.y is not None and start.distance is None \
        and start.bearing is None
    ahead = start.x is None and start.y is None and start.distance is not None \
        and start.bearing is not None
    if not (box or ahead):
        raise ValueError("give either x and y (a box on the pitch) or distance and bearing "
                         "(ahead of the robot's camera)")
    return start


class PitchStart(Section):
    robot: RobotStart = RobotStart()
    ball: Annotated[BallStart, AfterValidator(_ball_start)] = BallStart(
        x=(-1000.0, 1000.0), y=(-800.0, 800.0))
    ball_velocity: BallVelocity | None = Field(None, description=(
        "the ball rolls from the start (default: it lies still)"))


class Obstacle(Section):
    """A round obstacle (a standing or walking robot), drawn uniformly in its box."""

    x: Interval = Field(description="mm")
    y: Interval = Field(description="mm")
    radius: float = Field(150.0, gt=0, description="mm")
    speed: float = Field(0.0, ge=0, description=(
        "mm per step in a direction drawn at the start; it bounces off the pitch's edges"))


class Home(Section):
    x: float = Field(-1500.0, description="mm")
    y: float = Field(0.0, description="mm")


class PitchSensorNoise(Section):
    """Standard deviations of each channel's Gaussian noise, per step."""

    ball_size: float = Field(0.02, ge=0, description="relative")
    pan: float = Field(2.0, ge=0, description="deg")
    ball_distance: float = Field(0.05, ge=0, description="relative")
    goal_bearing: float = Field(3.0, ge=0, description="deg")
    goal_distance: float = Field(0.05, ge=0, description="relative")
    obstacle_bearing: float = Field(3.0, ge=0, description="deg")
    obstacle_distance: float = Field(0.05, ge=0, description="relative")
    home_bearing: float = Field(5.0, ge=0, description="deg")
    home_distance: float = Field(0.05, ge=0, description="relative")
    heading: float = Field(5.0, ge=0, description="deg")
    x: float = Field(50.0, ge=0, description="mm")
    y: float = Field(50.0, ge=0, description="mm")
    ball_x: float = Field(50.0, ge=0, description="mm")
    ball_y: float = Field(50.0, ge=0, description="mm")
    own_goal_bearing: float = Field(3.0, ge=0, description="deg")
    own_goal_distance: float = Field(0.05, ge=0, description="relative")
    ball_vx: float = Field(10.0, ge=0, description="mm per step")
    ball_vy: float = Field(10.0, ge=0, description="mm per step")
    opponent_bearing: float = Field(3.0, ge=0, description="deg")
    opponent_distance: float = Field(0.05, ge=0, description="relative")


def _default_outcomes() -> list[Outcome]:
    return [Outcome(when="ball_reached", reward=1.0, success=True),
            Outcome(when="ball_lost", reward=-1.0), Outcome(when="off_pitch", reward=-1.0)]


class PitchConfig(AdapterConfig):
    """A football pitch with goals, a ball, the robot and obstacles (docs/environments.md)."""

    adapter: Literal["pitch"]
    max_steps: int = Field(200, ge=1, le=10_000, description=(
        "steps before an episode ends with the timeout outcome (at most 10,000: each "
        "episode draws its noise for every step at reset)"))
    step_period: float = Field(0.25, gt=0, description=(
        "s per step; documents the units of the motion table (a step is one command)"))
    action: Literal["crisp", "nearest", "vote"] = Field("crisp", description=(
        "crisp: blend the two commands around the output a; nearest: the nearest command; "
        "vote: each command's firing rules sum their activations, the strongest command runs"))
    robot: Robot = Robot()
    ball: PitchBall = PitchBall()
    pitch: Field2D = Field2D()
    home: Home = Home()
    start: PitchStart = PitchStart()
    obstacles: list[Obstacle] = Field(default_factory=list, max_length=16, description=(
        "round obstacles; the obstacle_* channels read the nearest one"))
    opponents: list[Opponent] = Field(default_factory=list, max_length=4, description=(
        "scripted players that move and block the ball; the opponent_* channels read the "
        "nearest one"))
    points: dict[Name, FixedPoint] = Field(default_factory=dict, max_length=16, description=(
        "named fixed points (mm) for derived channels, besides robot, ball, goal, own_goal, "
        "home and opponent"))
    channels: dict[Name, DerivedChannel] = Field(default_factory=dict, max_length=32,
                                                 description=(
        "derived channels: name -> one geometric quantity between points (bearing, "
        "distance, offset, angle, velocity)"))
    rewards: list[StepReward] = Field(default_factory=list, max_length=16, description=(
        "rewards given after every step: scale times a channel's true value"))
    compose: dict[Name, str | dict[str, Any]] = Field(
        default_factory=dict, max_length=MAX_PARTS, description=(
            "a composed behaviour: each output command -> the behaviour (file, relative to "
            "this one) that runs while the command is chosen; loading inlines the parts"))
    sensors: dict[Name, str] = Field(default_factory=dict, description=(
        "behaviour input name -> channel it reads; an input not listed reads the channel of "
        "its own name"))
    sensor_noise: PitchSensorNoise = PitchSensorNoise()
    outcomes: list[Outcome] = Field(default_factory=_default_outcomes, min_length=1,
                                    max_length=32, description=(
        "how episodes end, first that holds wins; time-out after max_steps is the 'timeout' "
        "outcome (reward 0, failure unless declared)"))
    motion: dict[Name, Motion] = Field(default_factory=lambda: dict(DEFAULT_MOTION), description=(
        "command name -> mean displacement per step; extends the default table"))
    noise: dict[Name, MotionNoise] = Field(
        default_factory=lambda: dict(DEFAULT_NOISE), description=(
            "command name -> standard deviation per step; extends the default table"))

    @field_validator("motion", mode="before")
    @classmethod
    def _motion_over_defaults(cls, motion: Any) -> Any:
        return _extend_defaults(motion, DEFAULT_MOTION)

    @field_validator("noise", mode="before")
    @classmethod
    def _noise_over_defaults(cls, noise: Any) -> Any:
        return _extend_defaults(noise, DEFAULT_NOISE)

    def channel_of(self, input_name: str) -> str:
        return self.sensors.get(input_name, input_name)

    @property
    def known_channels(self) -> tuple[str, ...]:
        """The built-in channels, then the derived ones in file order."""
        return (*PITCH_CHANNELS, *self.channels)

    def fit_problems(self, inputs: tuple[str, ...], commands: tuple[str, ...]) -> list[Problem]:
        """What keeps the pitch world from running a behaviour; checked by validate."""
        problems = []
        for name in inputs:
            channel = self.channel_of(name)
            if channel not in self.known_channels:
                where = ("environment", "sensors", name) if name in self.sensors else \
                    ("inputs", name)
                problems.append(Problem(
                    where, f"the pitch world has no channel '{channel}'."
                    f"{did_you_mean(channel, self.known_channels)}",
                    "name the input after a channel or map it in environment.sensors; the "
                    "channels: " + ", ".join(self.known_channels)))
        problems += [Problem(("environment", "sensors", name), f"'{name}' is not an input."
                             f"{did_you_mean(name, inputs)}", "map behaviour inputs only")
                     for name in self.sensors if name not in inputs]
        read = [self.channel_of(name) for name in inputs]
        if len(set(read)) != len(read):
            problems.append(Problem(("inputs",), "two inputs read the same channel",
                                    "give each input a channel of its own"))
        leaves = [leaf for i, outcome in enumerate(self.outcomes)
                  for _, leaf in outcome.leaves(("environment", "outcomes", i))]
        thresholds = [leaf.channel or "" for leaf in leaves] + [r.channel for r in self.rewards]
        uses_obstacles = any(c.startswith("obstacle_") for c in (*read, *thresholds)) or (
            any(leaf.when == "collision" for leaf in leaves) and not self.opponents)
        if uses_obstacles and not self.obstacles:
            problems.append(Problem(("environment", "obstacles"),
                                    "obstacle channels or a collision outcome, but no obstacles",
                                    "add e.g. 'obstacles: [{x: [-200, 200], y: [-200, 200]}]'"))
        if any(c.startswith("opponent_") for c in (*read, *thresholds)) and not self.opponents:
            problems.append(Problem(("environment", "opponents"),
                                    "opponent channels, but no opponents",
                                    "add e.g. 'opponents: [{x: [1900, 1900], y: [-300, 300], "
                                    "behaviour: track}]'"))
        problems += vocabulary_problems(self.points, self.channels, PITCH_CHANNELS,
                                        self.outcomes, self.rewards, self.start.ball_velocity,
                                        len(self.opponents))
        if self.compose:
            problems += self._compose_problems(commands)
        if self.start.ball_velocity is not None and not self.ball.movable:
            problems.append(Problem(("environment", "start", "ball_velocity"),
                                    "the ball is not movable (ball.movable: false)",
                                    "remove start.ball_velocity or let the ball move"))
        for i, outcome in enumerate(self.outcomes):
            if outcome.when == "timeout" and outcome.held != 1:
                problems.append(Problem(("environment", "outcomes", i, "held"),
                                        "'held' does not apply to a 'timeout' outcome",
                                        "remove it: a time-out happens once"))
        if not any(o.success for o in self.outcomes):
            problems.append(Problem(("environment", "outcomes"), "no outcome is a success",
                                    "mark the outcome the behaviour aims at with success: true"))
        return problems + self._start_problems() + command_table_problems(
            self.motion, self.noise, self.walked_commands(commands))

    def _compose_problems(self, commands: tuple[str, ...]) -> list[Problem]:
        """Each command names a part, each part is a command; the parts' commands walk."""
        where = ("environment", "compose")
        problems = [Problem((*where,), f"the command '{name}' has no part", "give every "
                            f"output command a behaviour: '{name}: {name}.yaml'")
                    for name in commands if name not in self.compose]
        problems += [Problem((*where, name), f"'{name}' is not an output command."
                             f"{did_you_mean(name, commands)}", "name one output command per "
                             "part") for name in self.compose if name not in commands]
        for name, part in self.compose.items():
            inputs = part.get("inputs") if isinstance(part, dict) else None
            part_env = part.get("environment") if isinstance(part, dict) else None
            sensors = part_env.get("sensors") if isinstance(part_env, dict) else None
            sensors = sensors if isinstance(sensors, dict) else {}
            for input_name in inputs if isinstance(inputs, dict) else ():
                channel = sensors.get(input_name, input_name)
                if channel not in self.known_channels:
                    problems.append(Problem(
                        (*where, name), f"the part's input '{input_name}' reads '{channel}', "
                        "which this world does not have", "declare it under "
                        "environment.channels here: the parts read the composing world"))
        return problems

    def walked_commands(self, commands: tuple[str, ...]) -> tuple[str, ...]:
        """The commands the robot executes: the output's, or for a composition its parts'."""
        if not self.compose:
            return commands
        walked: dict[str, None] = {}
        for part in self.compose.values():
            output = part.get("output") if isinstance(part, dict) else None
            table = output.get("commands") if isinstance(output, dict) else None
            walked.update(dict.fromkeys(table if isinstance(table, dict) else ()))
        return tuple(walked)

    def _start_problems(self) -> list[Problem]:
        """Start boxes that reach off the pitch, or leave no room for a ball ahead."""
        half = {"x": self.pitch.length / 2.0, "y": self.pitch.width / 2.0}
        boxes: list[tuple[tuple[PathPart, ...], str, tuple[float, float], float]] = []
        start = ("environment", "start")
        for axis in ("x", "y"):
            boxes.append(((*start, "robot", axis), "the robot", getattr(self.start.robot, axis),
                          self.robot.radius))
            ball_box = getattr(self.start.ball, axis)
            if ball_box is not None:
                boxes.append(((*start, "ball", axis), "the ball", ball_box,
                              self.ball.diameter / 2.0))
            for i, obstacle in enumerate(self.obstacles):
                boxes.append((("environment", "obstacles", i, axis), "the obstacle",
                              getattr(obstacle, axis), obstacle.radius))
            for i, opponent in enumerate(self.opponents):
                boxes.append((("environment", "opponents", i, axis), "the opponent",
                              getattr(opponent, axis), opponent.radius))
        problems = []
        for path, what, (low, high), radius in boxes:
            limit = half[str(path[-1])] - radius
            if low < -limit or high > limit:
                problems.append(Problem(path, f"[{low:g}, {high:g}] puts {what} off the pitch: "
                                        f"its centre must stay within +-{limit:g} mm",
                                        "shrink the interval or enlarge the pitch"))
        problems += self._ball_ahead_problems(half)
        return problems

    def _ball_ahead_problems(self, half: dict[str, float]) -> list[Problem]:
        """A robot box that leaves no room for the ball ahead, for the headings and bearings
        the start draws (the robot is placed where the drawn ball lands on the pitch)."""
        ball = self.start.ball
        if ball.distance is None or ball.bearing is None:
            return []
        heading = self.start.robot.heading
        directions = (heading[0] - ball.bearing, heading[1] + ball.bearing)
        offset = self.robot.neck_offset
        problems = []
        for axis, shift in (("x", 0.0), ("y", 90.0)):
            # the ball's offset from the body centre along the axis: the camera's, over the
            # headings, plus the ball's from the camera, over the directions and distances
            low_c, high_c = _cos_extent(heading[0] - shift, heading[1] - shift)
            low_d, high_d = _cos_extent(directions[0] - shift, directions[1] - shift)
            near, far = ball.distance
            most = offset * high_c + (far if high_d > 0 else near) * high_d
            least = offset * low_c + (far if low_d < 0 else near) * low_d
            room = half[axis] - self.ball.diameter / 2.0
            low, high = getattr(self.start.robot, axis)
            if low + most > room or high + least < -room:
                problems.append(Problem(
                    ("environment", "start", "robot", axis), f"no room for the ball ahead: "
                    f"with the robot in [{low:g}, {high:g}] and headings in [{heading[0]:g}, "
                    f"{heading[1]:g}] deg, a ball up to {far:g} mm ahead within +-"
                    f"{ball.bearing:g} deg can be off the pitch",
                    f"let the robot start where the ball ahead fits (the ball lies "
                    f"{least:g} to {most:g} mm from it along {axis}), narrow the headings, or "
                    "shorten start.ball.distance"))
        return problems


def _cos_extent(low: float, high: float) -> tuple[float, float]:
    """The least and greatest cosine over the angles [low, high] deg."""
    if high - low >= 360.0:
        return -1.0, 1.0
    values = [math.cos(math.radians(low)), math.cos(math.radians(high))]
    turns = math.floor(low / 360.0)
    greatest = 1.0 if any(low <= 360.0 * k <= high for k in (turns, turns + 1)) \
        else max(values)
    least = -1.0 if any(low <= 180.0 + 360.0 * k <= high for k in (turns - 1, turns, turns + 1)) \
        else min(values)
    return least, greatest


class GymnasiumConfig(AdapterConfig):
    """Any Gymnasium environment with a Box observation and a Discrete or Box action space."""

    adapter: Literal["gymnasium"]
    id: str = Field(description="a registered Gymnasium id, e.g. CartPole-v1")
    max_steps: int | None = Field(None, ge=1, description=(
        "steps before truncation; default: the environment's own time limit"))
    observations: dict[Name, ObservationIndex | ObservationFeature] = Field(
        default_factory=dict, description=(
            "behaviour input name -> the index of the observation component it reads, or a "
            "feature computed from the observation ({component | angle | difference, abs, "
            "scale, offset}); default: the inputs in order read components 0, 1, ..."))
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

    @field_validator("actions")
    @classmethod
    def _non_negative(cls, mapping: dict[str, int]) -> dict[str, int]:
        for name, index in mapping.items():
            if index < 0:
                raise ValueError(f"'{name}': index {index} must be >= 0")
        return mapping

    def features(self, inputs: tuple[str, ...]) -> dict[str, ObservationFeature]:
        """Input name -> its feature, for the inputs ``observations`` maps (all of them by
        default: the inputs in order read components 0, 1, ...)."""
        mapping = self.observations or {name: i for i, name in enumerate(inputs)}
        return {name: ObservationFeature(component=feature) if isinstance(feature, int)
                else feature for name, feature in mapping.items()}


def default_gymnasium_ranges(data: Any) -> Any:
    """Raw behaviour data with ``range`` filled in for gymnasium inputs that leave it out.

    The default is the interval the input's feature takes over the observation space's
    bounds (:meth:`ObservationFeature.bounds`), read from the environment, which is made once
    for it. An input whose interval is infinite, or whose environment cannot be made, keeps
    no range, and validation reports the missing range where it belongs. Runs before the
    models validate the file, so the sets are checked against the range as usual; the
    resolved behaviour (a run's ``behaviour.yaml``, exports) states the range.
    """
    if not isinstance(data, dict):
        return data
    environment, inputs = data.get("environment"), data.get("inputs")
    if not (isinstance(environment, dict) and environment.get("adapter") == "gymnasium"
            and isinstance(inputs, dict)):
        return data
    missing = [name for name, variable in inputs.items()
               if isinstance(variable, dict) and "range" not in variable]
    env_id = environment.get("id")
    # An id "module:Env" imports a module: reading a file never does that.
    if not missing or not isinstance(env_id, str) or ":" in env_id:
        return data
    try:
        config = GymnasiumConfig.model_validate(environment)
        features = config.features(tuple(str(name) for name in inputs))
        from flctool.behaviour.gym_registry import observation_space_bounds

        low, high = observation_space_bounds(config.id, config.options)
    except (ValueError, FlcError):  # reported where it belongs when the file is validated
        return data
    filled = dict(inputs)
    for name in missing:
        feature = features.get(str(name))
        if feature is None or max(feature.indices) >= len(low):
            continue
        lo, hi = feature.bounds(low, high)
        if math.isfinite(lo) and math.isfinite(hi) and lo < hi:
            filled[name] = {**inputs[name], "range": [lo, hi]}
    return {**data, "inputs": filled}


class RobotLinkConfig(AdapterConfig):
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
