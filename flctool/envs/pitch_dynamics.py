"""The pitch world's dynamics, written once for one episode (Python floats) and for B
episodes (numpy arrays of shape (B,)).

Every function here takes an :class:`Ops` namespace and values of one type ``V``: ``float``
with :data:`FLOATS`, :data:`~flctool.envs.base.FloatArray` with :data:`ARRAYS` (mypy checks
each body for both). Both namespaces take sin, cos and atan2 from libm through :mod:`math`,
because numpy's SIMD versions may differ from libm in the last bit, so the two paths agree
bit for bit. The order of every operation is part of the bits the tests pin (ballchase's
seeds reproduce its first release).
"""

from __future__ import annotations

import math
import operator
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Generic, TypeVar

import numpy as np

from flctool.behaviour.environment import RELATIVE_CHANNELS
from flctool.envs.base import BoolArray, FloatArray
from flctool.envs.pitch_world import Derived, Test, World

_RAD = math.pi / 180.0
#: Bodies this close (mm) are in contact: the ``collision`` outcome's tolerance.
CONTACT_MM = 1e-6
_DEG = 180.0 / math.pi

#: A number per episode: a float for one, a (B,) array for B.
V = TypeVar("V", float, FloatArray)
#: A truth value per episode: a bool for one, a (B,) bool array for B.
Mask = bool | np.bool_ | BoolArray


def _map1(fn: Callable[[float], float], x: FloatArray) -> FloatArray:
    return np.fromiter(map(fn, x.tolist()), dtype=np.float64, count=x.shape[0])


def _atan2_array(y: FloatArray, x: FloatArray) -> FloatArray:
    return np.fromiter(map(math.atan2, y.tolist(), x.tolist()), dtype=np.float64,
                       count=y.shape[0])


@dataclass(frozen=True)
class Ops(Generic[V]):
    """The operations the dynamics use beyond + - * / and comparisons."""

    cos: Callable[[V], V]
    sin: Callable[[V], V]
    atan2: Callable[[V, V], V]
    sqrt: Callable[[V], V]
    minimum: Callable[[V | float, V | float], V]
    maximum: Callable[[V | float, V | float], V]
    where: Callable[[Mask, V | float, V | float], V]  # where(condition, if true, if false)
    but_not: Callable[[Mask, Mask], Mask]  # a and not b
    both: Callable[[Mask, Mask], Mask] = operator.and_
    either: Callable[[Mask, Mask], Mask] = operator.or_


FLOATS: Ops[float] = Ops(
    cos=math.cos, sin=math.sin, atan2=math.atan2, sqrt=math.sqrt, minimum=min, maximum=max,
    where=lambda c, a, b: a if c else b, but_not=lambda a, b: bool(a and not b))
ARRAYS: Ops[FloatArray] = Ops(
    cos=lambda x: _map1(math.cos, x), sin=lambda x: _map1(math.sin, x), atan2=_atan2_array,
    sqrt=np.sqrt, minimum=np.minimum, maximum=np.maximum, where=np.where,
    but_not=lambda a, b: np.logical_and(a, np.logical_not(b)))


def clip(ops: Ops[V], x: V, low: float, high: float) -> V:
    return ops.minimum(ops.maximum(x, low), high)


def wrap(ops: Ops[V], angle: V) -> V:
    """Radians -> (-pi, pi]: the same atan2 both paths use."""
    return ops.atan2(ops.sin(angle), ops.cos(angle))


@dataclass
class State(Generic[V]):
    """One episode (floats) or B episodes (arrays, (B,) each)."""

    x: V
    y: V
    heading: V  # rad, unwrapped
    ball_x: V
    ball_y: V
    ball_vx: V
    ball_vy: V
    obstacles: list[list[V]]  # per obstacle [x, y, vx, vy]
    ball_in_goal: V  # +1 target goal, -1 own goal, 0 neither
    ball_out: Mask  # the ball left the pitch outside the goal mouths
    step_x: V  # the robot's displacement in the last step
    step_y: V
    opponents: list[list[V]]  # per opponent [x, y, step x, step y]
    held: list[V]  # per outcome: consecutive steps its condition has held

    def copy(self) -> State[V]:
        return State(self.x, self.y, self.heading, self.ball_x, self.ball_y, self.ball_vx,
                     self.ball_vy, [list(o) for o in self.obstacles], self.ball_in_goal,
                     self.ball_out, self.step_x, self.step_y, [list(o) for o in self.opponents],
                     list(self.held))


#: The per-episode fields of :class:`State` (beyond the lists).
STATE_FIELDS = ("x", "y", "heading", "ball_x", "ball_y", "ball_vx", "ball_vy", "ball_in_goal",
                "ball_out", "step_x", "step_y")


def advance(ops: Ops[V], w: World, s: State[V], mean: Sequence[V | float],
            std: Sequence[V | float], z: Sequence[V | float]) -> tuple[V, V]:
    """Move the robot, the obstacles, the opponents and the ball one step in place; returns
    cos, sin of the new heading. ``mean``, ``std``: the command's (forward, sideways,
    rotation rad); ``z``: the step's three motion normals."""
    forward = mean[0] + std[0] * z[0]
    sideways = mean[1] + std[1] * z[1]
    heading = s.heading + (mean[2] + std[2] * z[2])
    cos_h, sin_h = ops.cos(heading), ops.sin(heading)
    x = s.x + forward * cos_h - sideways * sin_h  # (s.x + a) - b: the order is part of the
    y = s.y + forward * sin_h + sideways * cos_h  # bits ballchase's seeds reproduce
    step_x, step_y = x - s.x, y - s.y
    x_before, y_before = s.x, s.y
    s.x, s.y, s.heading = x, y, heading
    s.step_x, s.step_y = step_x, step_y
    for (*_, radius, speed), ob in zip(w.obstacles, s.obstacles, strict=True):
        if speed > 0:
            ob[0] = ob[0] + ob[2]
            ob[1] = ob[1] + ob[3]
            # bounce: turn back a velocity that carries the obstacle further out
            ob[2] = ops.where(ops.both(abs(ob[0]) > w.half_x - radius, ob[0] * ob[2] > 0),
                              -ob[2], ob[2])
            ob[3] = ops.where(ops.both(abs(ob[1]) > w.half_y - radius, ob[1] * ob[3] > 0),
                              -ob[3], ob[3])
    if w.opponents:
        _move_opponents(ops, w, s)
        blocked = _block_robot(ops, w, s, cos_h, sin_h)
        # the ball takes the robot's step as it happened, contact included
        step_x = ops.where(blocked, s.x - x_before, step_x)
        step_y = ops.where(blocked, s.y - y_before, step_y)
        s.step_x, s.step_y = step_x, step_y
    if w.ball_movable:
        _roll_ball(ops, w, s, step_x, step_y)
    return cos_h, sin_h


def _block_robot(ops: Ops[V], w: World, s: State[V], cos_h: V, sin_h: V) -> Mask:
    """Contact with the other players: the robot's body (a circle) cannot overlap an
    opponent's. After everyone has moved, each opponent in file order moves the robot out of
    its body along the line between their centres, to touching; the opponent does not yield.
    Centres that coincide move the robot straight back along its heading. Returns whether
    any opponent moved it."""
    blocked: Mask = s.x != s.x  # False, of the engine's type
    for spec, op in zip(w.opponents, s.opponents, strict=True):
        dx, dy = s.x - op[0], s.y - op[1]
        gap = ops.sqrt(dx * dx + dy * dy)
        reach = w.robot_radius + spec.radius
        apart = gap > 1e-9
        scale = reach / ops.maximum(gap, 1e-9)
        out_x = ops.where(apart, dx * scale, -reach * cos_h)
        out_y = ops.where(apart, dy * scale, -reach * sin_h)
        touch = gap < reach
        s.x = ops.where(touch, op[0] + out_x, s.x)
        s.y = ops.where(touch, op[1] + out_y, s.y)
        blocked = ops.either(blocked, touch)
    return blocked


def _move_opponents(ops: Ops[V], w: World, s: State[V]) -> None:
    """Each opponent acts on the ball's position before it rolls this step."""
    for spec, op in zip(w.opponents, s.opponents, strict=True):
        if spec.behaviour == "track":  # along its y interval towards the ball's y
            _, _, y_lo, y_hi = spec.box
            y = clip(ops, op[1] + clip(ops, s.ball_y - op[1], -spec.speed, spec.speed),
                     y_lo, y_hi)
            op[2], op[3] = 0.0 * op[0], y - op[1]
            op[1] = y
        elif spec.behaviour == "chase":  # straight at the ball
            dx, dy = s.ball_x - op[0], s.ball_y - op[1]
            gap = ops.sqrt(dx * dx + dy * dy)
            scale = ops.minimum(spec.speed, gap) / ops.maximum(gap, 1e-9)
            op[2], op[3] = dx * scale, dy * scale
            op[0], op[1] = op[0] + op[2], op[1] + op[3]


def _push(ops: Ops[V], w: World, rolling: Mask, bx: V, by: V, vx: V, vy: V, px: V, py: V,
          radius: float, step_x: V, step_y: V) -> tuple[V, V, V, V]:
    """The ball (bx, by, vx, vy) after contact with a body of ``radius`` at (px, py) that
    moved by (step_x, step_y): moved out to touching, velocity ``kick`` times the step."""
    dx, dy = bx - px, by - py
    gap = ops.sqrt(dx * dx + dy * dy)
    reach = radius + w.ball_radius
    touch = ops.both(rolling, gap < reach)
    scale = reach / ops.maximum(gap, 1e-9)
    return (ops.where(touch, px + dx * scale, bx), ops.where(touch, py + dy * scale, by),
            ops.where(touch, w.kick * step_x, vx), ops.where(touch, w.kick * step_y, vy))


def _roll_ball(ops: Ops[V], w: World, s: State[V], step_x: V, step_y: V) -> None:
    """Roll, push on contact with the robot's body (a circle) and the opponents', stop at an
    edge or go in."""
    rolling = s.ball_in_goal == 0  # a ball in a goal stays there
    keep = 1.0 - w.friction
    bx = ops.where(rolling, s.ball_x + s.ball_vx, s.ball_x)
    by = ops.where(rolling, s.ball_y + s.ball_vy, s.ball_y)
    vx, vy = s.ball_vx * keep, s.ball_vy * keep
    bx, by, vx, vy = _push(ops, w, rolling, bx, by, vx, vy, s.x, s.y, w.robot_radius,
                           step_x, step_y)
    for spec, op in zip(w.opponents, s.opponents, strict=True):
        bx, by, vx, vy = _push(ops, w, rolling, bx, by, vx, vy, op[0], op[1], spec.radius,
                               op[2], op[3])
    crossed = ops.both(rolling, abs(bx) > w.half_x)
    in_mouth = abs(by) < w.goal_half_width
    s.ball_in_goal = ops.where(ops.both(crossed, in_mouth), ops.where(bx > 0, 1.0, -1.0),
                               s.ball_in_goal)
    hit_x = ops.but_not(crossed, in_mouth)
    hit_y = ops.both(rolling, abs(by) > w.half_y)
    s.ball_x = ops.where(hit_x, clip(ops, bx, -w.half_x, w.half_x), bx)
    s.ball_y = ops.where(hit_y, clip(ops, by, -w.half_y, w.half_y), by)
    s.ball_vx = ops.where(ops.either(hit_x, hit_y), 0.0, vx)
    s.ball_vy = ops.where(ops.either(hit_x, hit_y), 0.0, vy)
    s.ball_out = ops.either(s.ball_out, ops.either(hit_x, hit_y))


def _bearing(ops: Ops[V], s: State[V], cos_h: V, sin_h: V, tx: V | float, ty: V | float,
             ) -> tuple[V, V]:
    """Bearing (rad, relative to the heading) and distance (mm) of a point from the body."""
    dx, dy = tx - s.x, ty - s.y
    return (ops.atan2(dy * cos_h - dx * sin_h, dx * cos_h + dy * sin_h),
            ops.sqrt(dx * dx + dy * dy))


@dataclass(frozen=True)
class Groups:
    """Which groups of channels a behaviour needs beyond the ball's (computed once)."""

    goal: bool
    home: bool
    obstacles: bool
    heading: bool
    own_goal: bool = False
    opponents: bool = False

    @classmethod
    def of(cls, needed: frozenset[str], w: World) -> Groups:
        return cls(goal=bool(needed & {"goal_bearing", "goal_distance"}),
                   home=bool(needed & {"home_bearing", "home_distance"}),
                   obstacles=bool(w.obstacles) and bool(
                       needed & {"obstacle_bearing", "obstacle_distance"}),
                   heading="heading" in needed,
                   own_goal=bool(needed & {"own_goal_bearing", "own_goal_distance"}),
                   opponents=bool(w.opponents) and bool(
                       needed & {"opponent_bearing", "opponent_distance", "obstacle_distance"}))


def sense(ops: Ops[V], w: World, s: State[V], cos_h: V, sin_h: V,
          needed: Groups, derived: Sequence[Derived] = ()) -> dict[str, V]:
    """The true (noise-free) value of every needed channel, plus 'ball_camera_distance',
    'pan_rad' and 'goal_bearing_rad' (which the outcomes use); ball_size is the noise-free
    pinhole size."""
    offset = w.neck_offset
    dx = s.ball_x - (s.x + offset * cos_h)
    dy = s.ball_y - (s.y + offset * sin_h)
    u = dx * cos_h + dy * sin_h
    v = dy * cos_h - dx * sin_h
    distance = ops.sqrt(dx * dx + dy * dy)
    pan = ops.atan2(v, u)
    true: dict[str, V] = {"ball_camera_distance": distance, "pan_rad": pan,
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
        nearest_bearing: V | float = 0.0
        nearest: V | float = math.inf
        for (*_, radius, _speed), ob in zip(w.obstacles, s.obstacles, strict=True):
            bearing, far = _bearing(ops, s, cos_h, sin_h, ob[0], ob[1])
            surface = far - w.robot_radius - radius
            closer = surface < nearest
            nearest_bearing = ops.where(closer, bearing, nearest_bearing)
            nearest = ops.where(closer, surface, nearest)
        true["obstacle_bearing"] = ops.where(True, nearest_bearing, 0.0) * _DEG
        true["obstacle_distance"] = ops.where(True, nearest, 0.0)
    if needed.heading:
        true["heading"] = wrap(ops, s.heading) * _DEG
    true["x"], true["y"] = s.x, s.y
    true["ball_x"], true["ball_y"] = s.ball_x, s.ball_y
    true["ball_vx"], true["ball_vy"] = s.ball_vx, s.ball_vy
    if needed.own_goal:
        bearing, far = _bearing(ops, s, cos_h, sin_h, -w.half_x, 0.0)
        true["own_goal_bearing"], true["own_goal_distance"] = bearing * _DEG, far
    if needed.opponents:
        _sense_opponents(ops, w, s, cos_h, sin_h, true)
    for channel in derived:
        true[channel.name] = _derived(ops, w, s, cos_h, sin_h, channel)
    return true


def _sense_opponents(ops: Ops[V], w: World, s: State[V], cos_h: V, sin_h: V,
                     true: dict[str, V]) -> None:
    """The nearest opponent by gap; ``obstacle_distance`` (collisions) counts them too."""
    nearest_bearing: V | float = 0.0
    nearest: V | float = math.inf
    for spec, op in zip(w.opponents, s.opponents, strict=True):
        bearing, far = _bearing(ops, s, cos_h, sin_h, op[0], op[1])
        surface = far - w.robot_radius - spec.radius
        closer = surface < nearest
        nearest_bearing = ops.where(closer, bearing, nearest_bearing)
        nearest = ops.where(closer, surface, nearest)
    true["opponent_bearing"] = ops.where(True, nearest_bearing, 0.0) * _DEG
    true["opponent_distance"] = ops.where(True, nearest, 0.0)
    if "obstacle_distance" in true:
        true["obstacle_distance"] = ops.minimum(true["obstacle_distance"], nearest)
    else:
        true["obstacle_distance"] = true["opponent_distance"]


def point(w: World, s: State[V], name: str) -> tuple[V | float, V | float]:
    if name == "robot":
        return s.x, s.y
    if name == "ball":
        return s.ball_x, s.ball_y
    if name == "goal":
        return w.half_x, 0.0
    if name == "own_goal":
        return -w.half_x, 0.0
    if name == "home":
        return w.home
    if name == "opponent":
        return s.opponents[0][0], s.opponents[0][1]
    return w.points[name]


def _derived(ops: Ops[V], w: World, s: State[V], cos_h: V, sin_h: V, channel: Derived) -> V:
    """A derived channel's true value (docs/environments.md, "Derived channels")."""
    zero = 0.0 * s.x  # makes a value of fixed points a value per episode
    if channel.kind == "velocity":
        mover = channel.points[0]
        vx, vy = ((s.step_x, s.step_y) if mover == "robot" else
                  (s.ball_vx, s.ball_vy) if mover == "ball" else
                  (s.opponents[0][2], s.opponents[0][3]))
        if channel.component == "speed":
            return ops.sqrt(vx * vx + vy * vy)
        return vx + zero if channel.component == "x" else vy + zero
    (ax, ay), (bx, by) = point(w, s, channel.points[0]), point(w, s, channel.points[1])
    if channel.kind == "bearing":  # the direction A -> B in the robot's frame
        dx, dy = bx - ax + zero, by - ay + zero
        return ops.atan2(dy * cos_h - dx * sin_h, dx * cos_h + dy * sin_h) * _DEG
    if channel.kind == "distance":
        dx, dy = bx - ax + zero, by - ay + zero
        return ops.sqrt(dx * dx + dy * dy)
    px, py = point(w, s, channel.points[2])
    if channel.kind == "offset":  # of P from the line A -> B, positive to its left
        lx, ly = bx - ax + zero, by - ay + zero
        length = ops.sqrt(lx * lx + ly * ly)
        return (lx * (py - ay) - ly * (px - ax)) / ops.maximum(length, 1e-9)
    # angle at B (the middle point) between A and P
    ux, uy = ax - bx + zero, ay - by + zero
    vx2, vy2 = px - bx + zero, py - by + zero
    return abs(ops.atan2(ux * vy2 - uy * vx2, ux * vx2 + uy * vy2)) * _DEG


SIZE, PAN, RELATIVE, ANGLE, PLAIN, DISTANCE, UNSIGNED_ANGLE = range(7)  # how noise applies


def noise_kind(channel: str, derived: dict[str, Derived]) -> int:
    if channel in ("ball_size", "pan"):
        return SIZE if channel == "ball_size" else PAN
    if channel in derived:
        kind = derived[channel].kind
        return {"bearing": ANGLE, "distance": DISTANCE, "angle": UNSIGNED_ANGLE}.get(kind, PLAIN)
    if channel in RELATIVE_CHANNELS:
        return RELATIVE
    return ANGLE if channel.endswith("bearing") or channel == "heading" else PLAIN


def observe(ops: Ops[V], w: World, value: V, kind: int, std: float, z: V | float) -> V:
    """A channel's reading from its true ``value``: noise added, clipped to what the sensor
    can give (``kind`` from :func:`noise_kind`)."""
    if kind == SIZE:
        return clip(ops, value * (1.0 + std * z), 0.0, 1.0)
    if kind == PAN:
        return clip(ops, value + std * z, -w.neck_range, w.neck_range)
    if kind == RELATIVE:
        return ops.maximum(value * (1.0 + std * z), 0.0)
    if kind == ANGLE:  # stays an angle in (-180, 180]
        return wrap(ops, (value + std * z) * _RAD) * _DEG
    if kind == DISTANCE:
        return ops.maximum(value + std * z, 0.0)
    if kind == UNSIGNED_ANGLE:
        return clip(ops, value + std * z, 0.0, 180.0)
    return value + std * z


ConditionTest = Callable[[Ops[V], State[V], dict[str, V]], Mask]


def condition_test(w: World, test: Test) -> ConditionTest[V]:
    """Whether ``test`` holds, as a function of the state and the true channel values."""
    kind = test.kind
    if kind in ("all", "any"):
        parts = [condition_test(w, part) for part in test.parts]
        if kind == "all":
            def every(ops: Any, s: Any, t: Any) -> Mask:
                held: Mask = True
                for part in parts:
                    held = ops.both(held, part(ops, s, t))
                return held
            return every

        def some(ops: Any, s: Any, t: Any) -> Mask:
            held: Mask = False
            for part in parts:
                held = ops.either(held, part(ops, s, t))
            return held
        return some
    if kind == "ball_reached":
        near, bearing, facing = test.distance, test.bearing, test.facing_goal
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
        # touching counts (within a micrometre): contact leaves an opponent exactly touching
        return lambda ops, s, t: t["obstacle_distance"] <= CONTACT_MM
    channel, low, high = test.channel, test.low, test.high  # a threshold on a true value
    return lambda ops, s, t: ops.both(t[channel] >= low, t[channel] <= high)
