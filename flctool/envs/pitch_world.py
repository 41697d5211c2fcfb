"""The pitch world resolved into plain numbers: what the dynamics (envs/pitch_dynamics.py)
need from a behaviour's ``environment:`` section, angles in radians where they are compared.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from flctool.behaviour.environment import PitchConfig
from flctool.behaviour.pitch_vocabulary import BallVelocity, Condition

_RAD = math.pi / 180.0


@dataclass(frozen=True)
class Test:
    """One condition resolved: a kind with its parameters, or ``all``/``any`` of others."""

    kind: str
    distance: float = 0.0
    bearing: float = 0.0  # rad
    facing_goal: float | None = None  # rad
    channel: str = ""
    low: float = -math.inf
    high: float = math.inf
    parts: tuple[Test, ...] = ()

    def channels(self) -> set[str]:
        """The true channel values this test reads."""
        own = {self.channel} if self.kind == "threshold" else set()
        if self.facing_goal is not None:
            own.add("goal_bearing")
        if self.kind == "collision":
            own.add("obstacle_distance")
        return own.union(*(part.channels() for part in self.parts))


@dataclass(frozen=True)
class OutcomeRule:
    """One declared outcome: its test, what it gives, and how many steps it must hold."""

    test: Test
    reward: float
    success: bool
    held: int = 1


@dataclass(frozen=True)
class Derived:
    """A derived channel: its kind and the points (or mover and component) it is taken of."""

    name: str
    kind: str  # bearing | distance | offset | angle | velocity
    points: tuple[str, ...]
    component: str = ""  # velocity: x | y | speed


@dataclass(frozen=True)
class OpponentSpec:
    box: tuple[float, float, float, float]  # x lo, x hi, y lo, y hi
    behaviour: str  # stand | track | chase
    speed: float
    radius: float


@dataclass(frozen=True)
class BallLaunch:
    """The ball's start velocity: speed interval and a direction interval (rad, world frame)
    or a point it is aimed at, jittered along y by +-spread."""

    speed: tuple[float, float]
    direction: tuple[float, float] | None
    towards: str
    spread: float


@dataclass(frozen=True)
class World:
    """Everything the dynamics need, as floats; built from a config by the adapter."""

    max_steps: int
    nearest: bool
    half_x: float
    half_y: float
    goal_half_width: float
    robot_radius: float
    neck_offset: float
    neck_range: float  # deg
    touch: float  # mm, camera-to-ball distance at which the ball fills the image
    ball_radius: float
    ball_movable: bool
    kick: float
    friction: float
    # start: the ball ahead of the camera (distance, bearing) or in a box
    ball_ahead: bool
    start_distance: tuple[float, float]
    start_bearing: float  # deg
    ball_box: tuple[float, float, float, float]  # x lo, x hi, y lo, y hi
    robot_box: tuple[float, float, float, float]
    heading_mid: float  # rad
    heading_half: float  # rad
    obstacles: tuple[tuple[float, float, float, float, float, float], ...]  # box, radius, speed
    home: tuple[float, float]
    noise: dict[str, float]  # channel -> std
    outcomes: tuple[OutcomeRule, ...]
    timeout_reward: float
    timeout_success: bool
    opponents: tuple[OpponentSpec, ...] = ()
    points: dict[str, tuple[float, float]] = field(default_factory=dict)  # fixed points
    derived: tuple[Derived, ...] = ()
    rewards: tuple[tuple[str, float, bool], ...] = ()  # channel, scale, abs
    launch: BallLaunch | None = None


def _test(condition: Condition) -> Test:
    if condition.all is not None or condition.any is not None:
        kind = "all" if condition.all is not None else "any"
        return Test(kind, parts=tuple(_test(c) for c in condition.all or condition.any or ()))
    return Test(
        condition.when or "", distance=condition.distance, bearing=condition.bearing * _RAD,
        facing_goal=None if condition.facing_goal is None else condition.facing_goal * _RAD,
        channel=condition.channel or "",
        low=-math.inf if condition.min is None else condition.min,
        high=math.inf if condition.max is None else condition.max)


def _launch(velocity: BallVelocity | None) -> BallLaunch | None:
    if velocity is None:
        return None
    direction = None if velocity.direction is None else (
        velocity.direction[0] * _RAD, velocity.direction[1] * _RAD)
    return BallLaunch(velocity.speed, direction, velocity.towards or "", velocity.spread)


def world_from_config(config: PitchConfig) -> World:
    robot, ball, pitch, start = config.robot, config.ball, config.pitch, config.start
    rules, timeout = [], None
    for outcome in config.outcomes:
        if outcome.when == "timeout":
            timeout = timeout or outcome
            continue
        rules.append(OutcomeRule(_test(outcome), outcome.reward, outcome.success, outcome.held))
    heading_lo, heading_hi = start.robot.heading
    bs = start.ball
    derived = tuple(
        Derived(name, channel.kind, channel.points,
                channel.velocity[1] if channel.velocity is not None else "")
        for name, channel in config.channels.items())
    noise = config.sensor_noise.model_dump()
    noise.update({name: channel.noise for name, channel in config.channels.items()})
    return World(
        max_steps=config.max_steps, nearest=config.action in ("nearest", "vote"),
        half_x=pitch.length / 2.0, half_y=pitch.width / 2.0,
        goal_half_width=pitch.goal_width / 2.0, robot_radius=robot.radius,
        neck_offset=robot.neck_offset, neck_range=robot.neck_range,
        touch=ball.diameter / (2.0 * math.tan(robot.camera_fov * _RAD / 2.0)),
        ball_radius=ball.diameter / 2.0, ball_movable=ball.movable, kick=ball.kick,
        friction=ball.friction, ball_ahead=bs.ahead,
        start_distance=bs.distance or (0.0, 0.0), start_bearing=bs.bearing or 0.0,
        ball_box=(*(bs.x or (0.0, 0.0)), *(bs.y or (0.0, 0.0))),
        robot_box=(*start.robot.x, *start.robot.y),
        heading_mid=(heading_lo + heading_hi) / 2.0 * _RAD,
        heading_half=(heading_hi - heading_lo) / 2.0 * _RAD,
        obstacles=tuple((*o.x, *o.y, o.radius, o.speed) for o in config.obstacles),
        home=(config.home.x, config.home.y),
        noise=noise, outcomes=tuple(rules),
        timeout_reward=timeout.reward if timeout else 0.0,
        timeout_success=timeout.success if timeout else False,
        opponents=tuple(OpponentSpec((*o.x, *o.y), o.behaviour, o.speed, o.radius)
                        for o in config.opponents),
        points={name: (p.x, p.y) for name, p in config.points.items()},
        derived=derived,
        rewards=tuple((r.channel, r.scale, r.abs) for r in config.rewards),
        launch=_launch(start.ball_velocity))
