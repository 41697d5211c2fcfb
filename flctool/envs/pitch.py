"""The pitch world: a legged robot, a ball, goals and obstacles on a football pitch.

World frame: the pitch is centred on the origin, x along its length towards the target goal,
angles counter-clockwise (positive = to the left, as in ROS). The robot's head camera sits
``robot.neck_offset`` ahead of the body centre and always pans towards the ball.

One step, in this order (docs/environments.md gives every formula):

1. the walking command: the robot turns by the command's rotation, then moves forward and
   sideways along its new heading; each component is the command's mean plus its standard
   deviation times a standard normal (the paper's "statistical model measured from real robot
   motion");
2. moving obstacles advance and bounce off the pitch's edges;
3. the ball rolls (velocity decays by ``ball.friction``); if the robot's body touches it, it is
   pushed out of the body and takes ``ball.kick`` times the robot's step as its velocity; at
   the pitch's edge it stops, unless it crosses a goal line inside the goal mouth;
4. the sensors read the new state (each channel with its own noise);
5. the outcomes are tested in file order; the first that holds ends the episode.

One coding, two paths. :func:`_advance` and :func:`_sense` are written once against an
:class:`_Ops` namespace: :data:`_FLOATS` runs them on Python floats for B = 1 (a few
microseconds per step, for learners running trials one after another), :data:`_ARRAYS` on numpy
arrays of B episodes. Only the bookkeeping differs (finished episodes are masked in the batch).
Both take sin, cos and atan2 from libm through :mod:`math`, because numpy's SIMD versions may
differ from libm in the last bit, so the two paths agree bit for bit.

Randomness: episode ``b`` draws its start and *all* its noise from
``numpy.random.default_rng(seeds[b])`` at reset: 5 uniforms (robot and ball placement), a
(max_steps + 1, 3 + C) table of standard normals (motion forward, sideways, rotation; then one
column per noisy channel: ball_size and pan always, then the other channels read, in
:data:`PITCH_CHANNELS` order), then 3 uniforms per obstacle -- so ballchase's draws are the
first two of these.
"""

from __future__ import annotations

import bisect
import math
import operator
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from flctool.envs.base import BatchEnv, BoolArray, FloatArray, Step
from flctool.errors import EnvError, SpecError
from flctool.spec.environment import (
    PITCH_CHANNELS,
    RELATIVE_CHANNELS,
    Motion,
    MotionNoise,
    PitchConfig,
)
from flctool.spec.models import Behaviour

_RAD = math.pi / 180.0
_DEG = 180.0 / math.pi
_MOTION_COLUMNS = 3
_UNIFORMS = 5  # robot and ball placement; then 3 per obstacle


# -- the two arithmetic namespaces --------------------------------------------------------------
def _map1(fn: Callable[[float], float], x: FloatArray) -> FloatArray:
    return np.fromiter(map(fn, x.tolist()), dtype=np.float64, count=x.shape[0])


def _atan2_array(y: FloatArray, x: FloatArray) -> FloatArray:
    return np.fromiter(map(math.atan2, y.tolist(), x.tolist()), dtype=np.float64,
                       count=y.shape[0])


@dataclass(frozen=True)
class _Ops:
    """The operations :func:`_advance` and :func:`_sense` use beyond + - * / and comparisons."""

    cos: Callable[[Any], Any]
    sin: Callable[[Any], Any]
    atan2: Callable[[Any, Any], Any]
    sqrt: Callable[[Any], Any]
    minimum: Callable[[Any, Any], Any]
    maximum: Callable[[Any, Any], Any]
    where: Callable[[Any, Any, Any], Any]  # where(condition, if true, if false)
    but_not: Callable[[Any, Any], Any]  # a and not b
    both: Callable[[Any, Any], Any] = operator.and_  # on bools or bool arrays
    either: Callable[[Any, Any], Any] = operator.or_


_FLOATS = _Ops(
    cos=math.cos, sin=math.sin, atan2=math.atan2, sqrt=math.sqrt, minimum=min, maximum=max,
    where=lambda c, a, b: a if c else b, but_not=lambda a, b: a and not b)
_ARRAYS = _Ops(
    cos=lambda x: _map1(math.cos, x), sin=lambda x: _map1(math.sin, x), atan2=_atan2_array,
    sqrt=np.sqrt, minimum=np.minimum, maximum=np.maximum, where=np.where,
    but_not=lambda a, b: a & ~b)


def _clip(ops: _Ops, x: Any, low: float, high: float) -> Any:
    return ops.minimum(ops.maximum(x, low), high)


def _wrap(ops: _Ops, angle: Any) -> Any:
    """Radians -> (-pi, pi]: the same atan2 both paths use."""
    return ops.atan2(ops.sin(angle), ops.cos(angle))


# -- the world, resolved into plain numbers --------------------------------------------------
@dataclass(frozen=True)
class OutcomeRule:
    """One declared outcome, its parameters resolved (angles in radians)."""

    kind: str
    reward: float
    success: bool
    distance: float = 0.0
    bearing: float = 0.0
    facing_goal: float | None = None
    channel: str = ""
    low: float = -math.inf
    high: float = math.inf


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


def world_from_config(config: PitchConfig) -> World:
    robot, ball, pitch, start = config.robot, config.ball, config.pitch, config.start
    rules, timeout = [], None
    for outcome in config.outcomes:
        if outcome.when == "timeout":
            timeout = timeout or outcome
            continue
        rules.append(OutcomeRule(
            outcome.when, outcome.reward, outcome.success,
            distance=outcome.distance or 120.0, bearing=(outcome.bearing or 20.0) * _RAD,
            facing_goal=None if outcome.facing_goal is None else outcome.facing_goal * _RAD,
            channel=outcome.channel or "",
            low=-math.inf if outcome.min is None else outcome.min,
            high=math.inf if outcome.max is None else outcome.max))
    heading_lo, heading_hi = start.robot.heading
    bs = start.ball
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
        noise=config.sensor_noise.model_dump(), outcomes=tuple(rules),
        timeout_reward=timeout.reward if timeout else 0.0,
        timeout_success=timeout.success if timeout else False)


# -- the dynamics, written once -----------------------------------------------------------------
@dataclass
class _State:
    """One episode (floats) or B episodes (arrays, (B,) each; obstacles (B, K) as lists of
    (B,) columns)."""

    x: Any
    y: Any
    heading: Any  # rad, unwrapped
    ball_x: Any
    ball_y: Any
    ball_vx: Any
    ball_vy: Any
    obstacles: list[list[Any]]  # per obstacle [x, y, vx, vy]
    ball_in_goal: Any  # +1 target goal, -1 own goal, 0 neither
    ball_out: Any  # the ball left the pitch outside the goal mouths


def _advance(ops: _Ops, w: World, s: _State, mean: Sequence[Any], std: Sequence[Any],
             z: Sequence[Any]) -> tuple[Any, Any]:
    """Move the robot, the obstacles and the ball one step in place; returns cos, sin of the
    new heading. ``mean``, ``std``: the command's (forward, sideways, rotation rad);
    ``z``: the step's three motion normals."""
    forward = mean[0] + std[0] * z[0]
    sideways = mean[1] + std[1] * z[1]
    heading = s.heading + (mean[2] + std[2] * z[2])
    cos_h, sin_h = ops.cos(heading), ops.sin(heading)
    x = s.x + forward * cos_h - sideways * sin_h  # (s.x + a) - b: the order is part of the
    y = s.y + forward * sin_h + sideways * cos_h  # bits ballchase's seeds reproduce
    step_x, step_y = x - s.x, y - s.y
    s.x, s.y, s.heading = x, y, heading
    for (*_, radius, speed), ob in zip(w.obstacles, s.obstacles, strict=True):
        if speed > 0:
            ob[0] = ob[0] + ob[2]
            ob[1] = ob[1] + ob[3]
            # bounce: turn back a velocity that carries the obstacle further out
            ob[2] = ops.where(ops.both(abs(ob[0]) > w.half_x - radius, ob[0] * ob[2] > 0),
                              -ob[2], ob[2])
            ob[3] = ops.where(ops.both(abs(ob[1]) > w.half_y - radius, ob[1] * ob[3] > 0),
                              -ob[3], ob[3])
    if w.ball_movable:
        _roll_ball(ops, w, s, step_x, step_y)
    return cos_h, sin_h


def _roll_ball(ops: _Ops, w: World, s: _State, step_x: Any, step_y: Any) -> None:
    """Roll, push on contact with the robot's body (a circle), stop at an edge or go in."""
    rolling = s.ball_in_goal == 0  # a ball in a goal stays there
    keep = 1.0 - w.friction
    bx = ops.where(rolling, s.ball_x + s.ball_vx, s.ball_x)
    by = ops.where(rolling, s.ball_y + s.ball_vy, s.ball_y)
    vx, vy = s.ball_vx * keep, s.ball_vy * keep
    dx, dy = bx - s.x, by - s.y
    gap = ops.sqrt(dx * dx + dy * dy)
    reach = w.robot_radius + w.ball_radius
    touch = ops.both(rolling, gap < reach)
    scale = reach / ops.maximum(gap, 1e-9)
    bx = ops.where(touch, s.x + dx * scale, bx)
    by = ops.where(touch, s.y + dy * scale, by)
    vx = ops.where(touch, w.kick * step_x, vx)
    vy = ops.where(touch, w.kick * step_y, vy)
    crossed = ops.both(rolling, abs(bx) > w.half_x)
    in_mouth = abs(by) < w.goal_half_width
    s.ball_in_goal = ops.where(ops.both(crossed, in_mouth), ops.where(bx > 0, 1.0, -1.0),
                               s.ball_in_goal)
    hit_x = ops.but_not(crossed, in_mouth)
    hit_y = ops.both(rolling, abs(by) > w.half_y)
    s.ball_x = ops.where(hit_x, _clip(ops, bx, -w.half_x, w.half_x), bx)
    s.ball_y = ops.where(hit_y, _clip(ops, by, -w.half_y, w.half_y), by)
    s.ball_vx = ops.where(ops.either(hit_x, hit_y), 0.0, vx)
    s.ball_vy = ops.where(ops.either(hit_x, hit_y), 0.0, vy)
    s.ball_out = ops.either(s.ball_out, ops.either(hit_x, hit_y))


def _bearing(ops: _Ops, s: _State, cos_h: Any, sin_h: Any, tx: Any, ty: Any,
             ) -> tuple[Any, Any]:
    """Bearing (rad, relative to the heading) and distance (mm) of a point from the body."""
    dx, dy = tx - s.x, ty - s.y
    return (ops.atan2(dy * cos_h - dx * sin_h, dx * cos_h + dy * sin_h),
            ops.sqrt(dx * dx + dy * dy))


@dataclass(frozen=True)
class _Groups:
    """Which groups of channels a behaviour needs beyond the ball's (computed once)."""

    goal: bool
    home: bool
    obstacles: bool
    heading: bool

    @classmethod
    def of(cls, needed: frozenset[str], w: World) -> _Groups:
        return cls(goal=bool(needed & {"goal_bearing", "goal_distance"}),
                   home=bool(needed & {"home_bearing", "home_distance"}),
                   obstacles=bool(w.obstacles) and bool(
                       needed & {"obstacle_bearing", "obstacle_distance"}),
                   heading="heading" in needed)


def _sense(ops: _Ops, w: World, s: _State, cos_h: Any, sin_h: Any,
           needed: _Groups) -> dict[str, Any]:
    """The true (noise-free) value of every needed channel, plus 'ball_camera_distance' and
    'pan_rad' (which the outcomes use); ball_size is the noise-free pinhole size."""
    offset = w.neck_offset
    dx = s.ball_x - (s.x + offset * cos_h)
    dy = s.ball_y - (s.y + offset * sin_h)
    u = dx * cos_h + dy * sin_h
    v = dy * cos_h - dx * sin_h
    distance = ops.sqrt(dx * dx + dy * dy)
    pan = ops.atan2(v, u)
    true: dict[str, Any] = {"ball_camera_distance": distance, "pan_rad": pan,
                            "ball_size": ops.minimum(1.0, w.touch / ops.maximum(distance, 1e-9)),
                            "pan": pan * _DEG, "ball_distance": distance}
    if needed.goal:
        bearing, far = _bearing(ops, s, cos_h, sin_h, w.half_x, 0.0)
        true["goal_bearing"], true["goal_distance"] = bearing * _DEG, far
        true["goal_bearing_rad"] = bearing
    if needed.home:
        bearing, far = _bearing(ops, s, cos_h, sin_h, w.home[0], w.home[1])
        true["home_bearing"], true["home_distance"] = bearing * _DEG, far
    if needed.obstacles:
        nearest_bearing: Any = 0.0
        nearest: Any = math.inf
        for (*_, radius, _speed), ob in zip(w.obstacles, s.obstacles, strict=True):
            bearing, far = _bearing(ops, s, cos_h, sin_h, ob[0], ob[1])
            surface = far - w.robot_radius - radius
            closer = surface < nearest
            nearest_bearing = ops.where(closer, bearing, nearest_bearing)
            nearest = ops.where(closer, surface, nearest)
        true["obstacle_bearing"], true["obstacle_distance"] = nearest_bearing * _DEG, nearest
    if needed.heading:
        true["heading"] = _wrap(ops, s.heading) * _DEG
    true["x"], true["y"] = s.x, s.y
    true["ball_x"], true["ball_y"] = s.ball_x, s.ball_y
    return true


_SIZE, _PAN, _RELATIVE, _ANGLE, _PLAIN = range(5)  # how a channel's noise applies


def _noise_kind(channel: str) -> int:
    if channel in ("ball_size", "pan"):
        return _SIZE if channel == "ball_size" else _PAN
    if channel in RELATIVE_CHANNELS:
        return _RELATIVE
    return _ANGLE if channel.endswith("bearing") or channel == "heading" else _PLAIN


def _observe(ops: _Ops, w: World, value: Any, kind: int, std: float, z: Any) -> Any:
    """A channel's reading from its true ``value``: noise added, clipped to what the sensor
    can give (``kind`` from :func:`_noise_kind`)."""
    if kind == _SIZE:
        return _clip(ops, value * (1.0 + std * z), 0.0, 1.0)
    if kind == _PAN:
        return _clip(ops, value + std * z, -w.neck_range, w.neck_range)
    if kind == _RELATIVE:
        return ops.maximum(value * (1.0 + std * z), 0.0)
    if kind == _ANGLE:  # stays an angle in (-180, 180]
        return _wrap(ops, (value + std * z) * _RAD) * _DEG
    return value + std * z


OutcomeTest = Callable[[_Ops, _State, dict[str, Any]], Any]


def _outcome_test(w: World, rule: OutcomeRule) -> OutcomeTest:
    """Whether ``rule`` holds, as a function of the state and the true channel values."""
    kind = rule.kind
    if kind == "ball_reached":
        near, bearing, facing = rule.distance, rule.bearing, rule.facing_goal
        if facing is None:
            return lambda ops, s, t: ops.both(t["ball_camera_distance"] <= near,
                                              abs(t["pan_rad"]) <= bearing)
        return lambda ops, s, t: ops.both(
            ops.both(t["ball_camera_distance"] <= near, abs(t["pan_rad"]) <= bearing),
            abs(t["goal_bearing_rad"]) <= facing)
    if kind == "ball_lost":
        neck = w.neck_range * _RAD
        return lambda ops, s, t: abs(t["pan_rad"]) > neck
    if kind == "off_pitch":
        return lambda ops, s, t: ops.either(abs(s.x) > w.half_x, abs(s.y) > w.half_y)
    if kind == "ball_in_goal":
        return lambda ops, s, t: s.ball_in_goal > 0
    if kind == "ball_in_own_goal":
        return lambda ops, s, t: s.ball_in_goal < 0
    if kind == "ball_off_pitch":
        return lambda ops, s, t: s.ball_out
    if kind == "collision":
        return lambda ops, s, t: t["obstacle_distance"] <= 0.0
    channel, low, high = rule.channel, rule.low, rule.high  # a threshold on a true value
    return lambda ops, s, t: ops.both(t[channel] >= low, t[channel] <= high)


def _outcome(ops: _Ops, tests: Sequence[OutcomeTest], s: _State, true: dict[str, Any]) -> Any:
    """Index + 1 of the first declared outcome that holds, 0 for none."""
    if ops is _FLOATS:  # one episode: stop at the first that holds
        for index, test in enumerate(tests):
            if test(ops, s, true):
                return index + 1
        return 0
    code: Any = 0
    for index in range(len(tests) - 1, -1, -1):  # the first that holds is set last
        code = ops.where(tests[index](ops, s, true), index + 1, code)
    return code


# -- the adapter -------------------------------------------------------------------------------
class PitchSim(BatchEnv):
    """B pitch-world episodes; observations are the channels the behaviour's inputs read.

    Build it with :func:`flctool.envs.make_env` or :meth:`from_behaviour`. After a reset, the
    poses are readable as ``x``, ``y``, ``heading`` (rad, unwrapped), ``ball_x``, ``ball_y``,
    each (B,).
    """

    replayable = True  # all randomness comes from the seed (see _draw)

    def __init__(self, world: World, commands: dict[str, float], motion: dict[str, Motion],
                 noise: dict[str, MotionNoise], channels: tuple[str, ...],
                 observation_names: tuple[str, ...] | None = None, votes: bool = False,
                 ) -> None:
        self.world = world
        self.votes = votes
        self.channels = channels
        self.observation_names = observation_names or channels
        self.max_steps = world.max_steps
        order = sorted(commands, key=lambda name: commands[name])
        self.command_order = tuple(order)  # commands by increasing singleton
        self._values = np.array([commands[n] for n in order], dtype=np.float64)
        self.action_bounds = (float(self._values[0]), float(self._values[-1]))
        self._values_list: list[float] = self._values.tolist()
        # Columns of the motion table by increasing singleton, the last row repeated so that
        # "nearest" (weight 0 on the row above) blends like "crisp" without a special case.
        rows = [*order, order[-1]]
        self._mean = [[motion[n].forward for n in rows], [motion[n].sideways for n in rows],
                      [motion[n].rotation * _RAD for n in rows]]
        self._std = [[noise[n].forward for n in rows], [noise[n].sideways for n in rows],
                     [noise[n].rotation * _RAD for n in rows]]
        self._mean_arrays = [np.array(column) for column in self._mean]
        self._std_arrays = [np.array(column) for column in self._std]
        self._nearest = world.nearest or len(order) == 1
        noisy = ["ball_size", "pan"] + [c for c in PITCH_CHANNELS[2:] if c in channels]
        column = {c: _MOTION_COLUMNS + i for i, c in enumerate(noisy)}
        self._columns = _MOTION_COLUMNS + len(noisy)
        self._observers = [(c, _noise_kind(c), world.noise[c], column[c]) for c in channels]
        self._needed = _Groups.of(frozenset(channels) | {
            "goal_bearing" for r in world.outcomes if r.facing_goal is not None} | {
            r.channel for r in world.outcomes if r.kind == "threshold"} | {
            "obstacle_distance" for r in world.outcomes if r.kind == "collision"}, world)
        self._tests = [_outcome_test(world, rule) for rule in world.outcomes]
        self._rewards = [0.0] + [r.reward for r in world.outcomes]
        self._successes = [False] + [r.success for r in world.outcomes]
        self._scalar = False  # which path holds the episodes: _sstate (B = 1) or _state
        self._started = False

    @classmethod
    def from_behaviour(cls, behaviour: Behaviour, batch_size: int = 1) -> PitchSim:
        del batch_size  # B is the number of seeds given to reset
        config = behaviour.environment
        if not isinstance(config, PitchConfig):
            raise EnvError("the pitch world needs 'environment: {adapter: pitch}'")
        problems = config.fit_problems(behaviour.input_names, tuple(behaviour.output.commands))
        if problems:
            raise SpecError(problems)
        channels = tuple(config.channel_of(name) for name in behaviour.input_names)
        return cls(world_from_config(config), dict(behaviour.output.commands), config.motion,
                   config.noise, channels, behaviour.input_names, config.action == "vote")

    # -- the poses, from whichever path ran last ---------------------------------------------
    def _pose(self, name: str) -> FloatArray:
        if not self._started:
            raise EnvError("no episode yet", hint="call reset(seeds) first")
        if self._scalar:
            return np.array([getattr(self._sstate, name)], dtype=np.float64)
        return np.array(getattr(self._state, name), dtype=np.float64)

    x = property(lambda self: self._pose("x"), doc="(B,) robot x, mm")
    y = property(lambda self: self._pose("y"), doc="(B,) robot y, mm")
    heading = property(lambda self: self._pose("heading"), doc="(B,) rad, unwrapped")
    ball_x = property(lambda self: self._pose("ball_x"), doc="(B,) mm")
    ball_y = property(lambda self: self._pose("ball_y"), doc="(B,) mm")

    # -- start -------------------------------------------------------------------------------
    def _start(self, ops: _Ops, u: Sequence[Any], obstacle_u: Sequence[Any]) -> _State:
        """Place the robot, ball and obstacles from uniforms ``u`` (5) and ``obstacle_u``."""
        w = self.world
        heading = (2.0 * u[2] - 1.0) * w.heading_half
        if w.heading_mid != 0.0:
            heading = heading + w.heading_mid
        cos_h, sin_h = ops.cos(heading), ops.sin(heading)
        rx_lo, rx_hi, ry_lo, ry_hi = w.robot_box
        if w.ball_ahead:
            # The ball relative to the body centre; the robot is then placed uniformly in its
            # box where the ball is on the pitch too (the config guarantees there is room).
            low, high = w.start_distance
            distance = low + (high - low) * u[0]
            bearing = (2.0 * u[1] - 1.0) * w.start_bearing * _RAD
            rel_x = w.neck_offset * cos_h + distance * ops.cos(heading + bearing)
            rel_y = w.neck_offset * sin_h + distance * ops.sin(heading + bearing)
            lo = ops.maximum(rx_lo, -w.half_x + w.ball_radius - rel_x)
            hi = ops.minimum(rx_hi, w.half_x - w.ball_radius - rel_x)
            x = lo + u[3] * (hi - lo)
            lo = ops.maximum(ry_lo, -w.half_y + w.ball_radius - rel_y)
            hi = ops.minimum(ry_hi, w.half_y - w.ball_radius - rel_y)
            y = lo + u[4] * (hi - lo)
            ball_x, ball_y = x + rel_x, y + rel_y
        else:
            x = rx_lo + u[0] * (rx_hi - rx_lo)
            y = ry_lo + u[1] * (ry_hi - ry_lo)
            bx_lo, bx_hi, by_lo, by_hi = w.ball_box
            ball_x = bx_lo + u[3] * (bx_hi - bx_lo)
            ball_y = by_lo + u[4] * (by_hi - by_lo)
        obstacles = []
        for i, (ox_lo, ox_hi, oy_lo, oy_hi, _radius, speed) in enumerate(w.obstacles):
            ux, uy, ud = obstacle_u[3 * i : 3 * i + 3]
            direction = 2.0 * math.pi * ud
            obstacles.append([ox_lo + ux * (ox_hi - ox_lo), oy_lo + uy * (oy_hi - oy_lo),
                              speed * ops.cos(direction), speed * ops.sin(direction)])
        zero = 0.0 * x
        return _State(x, y, heading, ball_x, ball_y, zero, zero, obstacles, zero, zero != 0.0)

    def _draw(self, seed: int) -> tuple[list[float], list[float], FloatArray]:
        """Episode ``seed``'s randomness: placement uniforms, obstacle uniforms, the normals
        (max_steps + 1, columns) -- row 0 senses the start, row t the result of step t."""
        rng = np.random.default_rng(seed)
        u = rng.random(_UNIFORMS).tolist()
        noise = rng.standard_normal((self.max_steps + 1, self._columns))
        obstacle_u = rng.random(3 * len(self.world.obstacles)).tolist()
        return u, obstacle_u, noise

    def _read(self, ops: _Ops, s: _State, cos_h: Any, sin_h: Any, z: Any,
              ) -> tuple[list[Any], dict[str, Any]]:
        """Readings of the behaviour's channels (N floats, or N arrays (B,)) from the noise
        row ``z`` ((columns,) or (B, columns)), and the true channel values."""
        true = _sense(ops, self.world, s, cos_h, sin_h, self._needed)
        w = self.world
        if ops is _FLOATS:
            return [_observe(ops, w, true[c], kind, std, z[col])
                    for c, kind, std, col in self._observers], true
        return [_observe(ops, w, true[c], kind, std, z[:, col])
                for c, kind, std, col in self._observers], true

    # -- the batched path --------------------------------------------------------------------
    def reset(self, seeds: NDArray[np.int64]) -> tuple[FloatArray, dict[str, Any]]:
        """Start one episode per seed: (B,) -> observations (B, N), info {}."""
        seeds = np.asarray(seeds, dtype=np.int64).reshape(-1)
        batch = seeds.shape[0]
        if batch < 1:
            raise EnvError("reset needs at least one seed")
        if batch == 1:
            return self.reset_one(int(seeds[0]))[None, :], {}
        uniforms = np.empty((batch, _UNIFORMS))
        obstacle_u = np.empty((batch, 3 * len(self.world.obstacles)))
        self._noise = np.empty((batch, self.max_steps + 1, self._columns))
        for b, seed in enumerate(seeds.tolist()):
            uniforms[b], obstacle_u[b], self._noise[b] = self._draw(seed)
        self._state = self._start(_ARRAYS, list(uniforms.T), list(obstacle_u.T))
        self._t = np.zeros(batch, dtype=np.int64)
        self._terminated = np.zeros(batch, dtype=bool)
        self._truncated = np.zeros(batch, dtype=bool)
        self._reached = np.zeros(batch, dtype=bool)
        self._scalar = False
        self._started = True
        s = self._state
        values, _ = self._read(_ARRAYS, s, _ARRAYS.cos(s.heading), _ARRAYS.sin(s.heading),
                               self._noise[:, 0])
        self._obs = _stack(values, batch)
        return self._obs.copy(), {}

    def _motion(self, actions: FloatArray) -> tuple[list[FloatArray], list[FloatArray]]:
        """Mean and std columns (each (B,)) of the commanded displacement: the sorted
        singletons' motions blended piecewise linearly (or the nearest one's)."""
        values = self._values
        a = np.clip(actions, values[0], values[-1])
        if self._nearest:
            j = np.argmin(np.abs(a[:, None] - values[None, :]), axis=1)
            w = np.zeros_like(a)
        else:
            j = np.clip(np.searchsorted(values, a, side="right") - 1, 0, values.shape[0] - 2)
            gap = values[j + 1] - values[j]
            w = np.where(gap > 0, (a - values[j]) / np.where(gap > 0, gap, 1.0), 0.0)
        return _blend(self._mean_arrays, self._std_arrays, j, w)

    def step(self, actions: FloatArray) -> Step:
        """Apply crisp outputs ``actions (B,)``; finished episodes stay as they are."""
        actions = np.asarray(actions, dtype=np.float64).reshape(-1)
        if not self._started:
            raise EnvError("step before reset", hint="call reset(seeds) first")
        batch = 1 if self._scalar else self._t.shape[0]
        if actions.shape[0] != batch:
            raise EnvError(f"step got {actions.shape[0]} actions for {batch} episodes")
        if self._scalar:
            obs, reward, terminated, truncated = self.step_one(float(actions[0]))
            return Step(obs[None, :], np.array([reward]), np.array([terminated]),
                        np.array([truncated]))
        if np.isnan(actions).any():
            raise EnvError("an action is NaN", hint="check the controller's output")
        active = ~(self._terminated | self._truncated)
        rows = np.minimum(self._t + 1, self.max_steps)
        z = self._noise[np.arange(batch), rows]  # (B, columns)
        mean, std = self._motion(actions)
        before = self._state
        s = _State(before.x, before.y, before.heading, before.ball_x, before.ball_y,
                   before.ball_vx, before.ball_vy, [list(o) for o in before.obstacles],
                   before.ball_in_goal, before.ball_out)
        cos_h, sin_h = _advance(_ARRAYS, self.world, s, mean, std, [z[:, 0], z[:, 1], z[:, 2]])
        values, true = self._read(_ARRAYS, s, cos_h, sin_h, z)
        code = np.where(active, _outcome(_ARRAYS, self._tests, s, true), 0)
        # finished episodes keep their state
        for name in ("x", "y", "heading", "ball_x", "ball_y", "ball_vx", "ball_vy",
                     "ball_in_goal", "ball_out"):
            setattr(s, name, np.where(active, getattr(s, name), getattr(before, name)))
        s.obstacles = [[np.where(active, new, old) for new, old in zip(o, p, strict=True)]
                       for o, p in zip(s.obstacles, before.obstacles, strict=True)]
        self._state = s
        self._t = self._t + active
        self._obs = np.where(active[:, None], _stack(values, batch), self._obs)
        ended = code > 0
        timeout = active & ~ended & (self._t >= self.max_steps)
        success = np.asarray(self._successes)[code] & ended
        success |= timeout & self.world.timeout_success
        rewards = np.asarray(self._rewards)[code] + np.where(timeout, self.world.timeout_reward,
                                                             0.0)
        self._reached |= success
        self._terminated |= ended
        self._truncated |= timeout
        return Step(self._obs.copy(), rewards, self._terminated.copy(), self._truncated.copy())

    # -- the scalar path (B = 1): the same functions on Python floats ------------------------
    def reset_one(self, seed: int) -> FloatArray:
        """Start a single episode; the same start as :meth:`reset` with ``[seed]``."""
        u, obstacle_u, noise = self._draw(seed)
        self._snoise: list[float] = noise.ravel().tolist()
        self._sstate = self._start(_FLOATS, u, obstacle_u)
        self._st = 0
        self._sflags = (False, False, False)  # terminated, truncated, success
        self._scalar = True
        self._started = True
        s = self._sstate
        values, _ = self._read(_FLOATS, s, math.cos(s.heading), math.sin(s.heading),
                               self._snoise[: self._columns])
        self._sobs: FloatArray = np.array(values, dtype=np.float64)
        return np.array(self._sobs)

    def step_one(self, action: float) -> tuple[FloatArray, float, bool, bool]:
        """Step the episode started by :meth:`reset_one` (the fast path)."""
        if not self._scalar:
            return super().step_one(action)
        terminated, truncated, _ = self._sflags
        if terminated or truncated:
            return np.array(self._sobs), 0.0, terminated, truncated
        if action != action:
            raise EnvError("the action is NaN", hint="check the controller's output")
        values = self._values_list
        count = len(values)
        # a Python float: numpy scalars would make every operation below several times slower
        a = min(max(float(action), values[0]), values[-1])
        if self._nearest:
            j, w = min(range(count), key=lambda i: abs(a - values[i])), 0.0
        else:
            j = min(max(bisect.bisect_right(values, a) - 1, 0), count - 2)
            gap = values[j + 1] - values[j]
            w = (a - values[j]) / gap if gap > 0 else 0.0
        mean, std = _blend(self._mean, self._std, j, w)
        row = self._columns * min(self._st + 1, self.max_steps)
        z = self._snoise[row : row + self._columns]
        s = self._sstate
        cos_h, sin_h = _advance(_FLOATS, self.world, s, mean, std, z)
        readings, true = self._read(_FLOATS, s, cos_h, sin_h, z)
        code = _outcome(_FLOATS, self._tests, s, true)
        self._st += 1
        timeout = code == 0 and self._st >= self.max_steps
        success = self._successes[code] or (timeout and self.world.timeout_success)
        reward = self._rewards[code] + (self.world.timeout_reward if timeout else 0.0)
        self._sflags = (code > 0, timeout, success)
        self._sobs = obs = np.array(readings, dtype=np.float64)  # returned, kept, never mutated
        return obs, reward, code > 0, timeout

    # -- outcome -----------------------------------------------------------------------------
    def success(self) -> BoolArray:
        """(B,) whether each episode has ended in a success outcome."""
        if self._scalar:
            return np.array([self._sflags[2]])
        return np.array(self._reached)

    #: What :meth:`episode_fitness` can give: 0 (a failure at once) to 2 (success at once).
    fitness_range = (0.0, 2.0)

    def episode_fitness(self, returns: FloatArray, lengths: NDArray[np.int64],
                        success: BoolArray) -> FloatArray:
        """Trial fitness for the GA, (B,) each; faster success scores higher.

        success after L steps: ``2 - L / max_steps`` in [1, 2]; any other ending after L
        steps: ``0.5 * L / max_steps`` in [0, 0.5] (a time-out gives 0.5) -- lasting longer
        before a failure is better than failing at once, and any success beats every failure.
        """
        del returns
        fraction = np.asarray(lengths, dtype=np.float64) / self.max_steps
        return np.where(np.asarray(success, dtype=bool), 2.0 - fraction, 0.5 * fraction)

    def trace_state(self) -> dict[str, FloatArray]:
        """Robot pose (mm, deg in [-180, 180)) and ball position, each (B,)."""
        heading = np.remainder(self.heading * _DEG + 180.0, 360.0) - 180.0
        return {"robot_x": self.x, "robot_y": self.y, "robot_heading": heading,
                "ball_x": self.ball_x, "ball_y": self.ball_y}


def _stack(columns: list[FloatArray], batch: int) -> FloatArray:
    return np.stack(columns, axis=1) if columns else np.zeros((batch, 0))


def _blend(mean: Sequence[Any], std: Sequence[Any], j: Any, w: Any,
           ) -> tuple[list[Any], list[Any]]:
    """Rows j and j + 1 of the motion table's columns, weighted (1 - w, w): crisp blending;
    nearest passes w = 0, which gives row j exactly."""
    keep = 1.0 - w
    return ([keep * c[j] + w * c[j + 1] for c in mean], [keep * c[j] + w * c[j + 1] for c in std])
