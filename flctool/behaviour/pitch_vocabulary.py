"""What a coach can say about the pitch world, as behaviour-file models: the points of the
pitch, channels derived from them, outcome conditions (combined with ``all``/``any`` and held
for a number of steps), per-step rewards, the ball's start velocity and scripted opponents.

The vocabulary is closed: a derived channel names one geometric quantity and the points it is
taken between; nothing in a file is evaluated as an expression. docs/environments.md draws
the geometry.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Annotated, Any, Literal

from pydantic import (
    AfterValidator,
    Field,
    SerializerFunctionWrapHandler,
    model_serializer,
    model_validator,
)
from typing_extensions import Self

from flctool.behaviour.base import Name, Section
from flctool.errors import PathPart, Problem
from flctool.registry import did_you_mean

#: Points every pitch world has. ``goal`` is the centre of the target goal's line
#: (x = +length/2, y = 0), ``own_goal`` the other one's; ``opponent`` is the first declared
#: opponent (there must be one); ``home`` is ``environment.home``. A file adds fixed points
#: under ``environment.points``.
BUILTIN_POINTS = ("robot", "ball", "goal", "own_goal", "home", "opponent")
#: What moves, for ``velocity`` channels: displacement per step, in mm, world frame.
MOVERS = ("robot", "ball", "opponent")
VELOCITY_COMPONENTS = ("x", "y", "speed")
#: The geometric quantities a derived channel may be (docs/environments.md).
DERIVED_KINDS = ("bearing", "distance", "offset", "angle", "velocity")
#: Outcome kinds that test the world (``timeout`` ends an episode without a test).
CONDITION_KINDS = ("ball_reached", "ball_in_goal", "ball_in_own_goal", "ball_off_pitch",
                   "threshold", "collision", "off_pitch", "ball_lost")
#: How deeply ``all``/``any`` may nest: enough for "(a and b) or c", bounded for hostile files.
MAX_CONDITION_DEPTH = 4
_REACH = ("distance", "bearing", "facing_goal")
_THRESHOLD = ("channel", "min", "max")


class FixedPoint(Section):
    x: float = Field(description="mm")
    y: float = Field(description="mm")


def _two(points: tuple[str, str]) -> tuple[str, str]:
    if points[0] == points[1]:
        raise ValueError(f"the two points are both '{points[0]}'; name two different points")
    return points


def _three(points: tuple[str, str, str]) -> tuple[str, str, str]:
    if len(set(points)) < 3:
        raise ValueError("the three points must be different")
    return points


Pair = Annotated[tuple[Name, Name], AfterValidator(_two)]
Triple = Annotated[tuple[Name, Name, Name], AfterValidator(_three)]


class DerivedChannel(Section):
    """A channel computed from the points of the pitch: exactly one of the quantities.

    Bearings are relative to the robot's heading (positive = to the left), like every
    bearing channel; the other quantities do not depend on the robot's heading.
    """

    bearing: Pair | None = Field(None, description=(
        "[A, B]: the direction from A to B, deg, relative to the robot's heading, in "
        "(-180, 180]; [robot, B] is B's bearing"))
    distance: Pair | None = Field(None, description="[A, B]: mm from A to B (centres)")
    offset: Triple | None = Field(None, description=(
        "[A, B, P]: signed distance of P from the line through A and B, mm, positive when P "
        "lies to the left looking from A to B"))
    angle: Triple | None = Field(None, description=(
        "[A, P, B]: the angle at P between the directions to A and to B, deg in [0, 180]; "
        "180 when P lies on the segment between them"))
    velocity: tuple[Literal["robot", "ball", "opponent"],
                    Literal["x", "y", "speed"]] | None = Field(None, description=(
        "[MOVER, COMPONENT]: the mover's displacement in the last step, mm per step, world "
        "frame (x towards the target goal)"))
    noise: float = Field(0.0, ge=0, description=(
        "deg or mm: standard deviation of Gaussian noise added to each reading (bearings "
        "wrap, angles and distances are clipped to their ranges)"))

    @model_validator(mode="after")
    def _exactly_one(self) -> Self:
        given = [kind for kind in DERIVED_KINDS if getattr(self, kind) is not None]
        if len(given) != 1:
            raise ValueError("give exactly one of " + ", ".join(DERIVED_KINDS) +
                             (f"; this gives {', '.join(given)}" if given else ""))
        return self

    @property
    def kind(self) -> str:
        return next(kind for kind in DERIVED_KINDS if getattr(self, kind) is not None)

    @property
    def points(self) -> tuple[str, ...]:
        if self.velocity is not None:
            return (self.velocity[0],)
        value: tuple[str, ...] = getattr(self, self.kind)
        return value


class Condition(Section):
    """A test of the world after a step: one kind (``when``), or ``all``/``any`` of others."""

    when: Literal["ball_reached", "ball_in_goal", "ball_in_own_goal", "ball_off_pitch",
                  "threshold", "collision", "off_pitch", "ball_lost", "timeout"] | None = Field(
        None, description="the event; see docs/environments.md")
    all: list[Condition] | None = Field(None, min_length=1, max_length=16, description=(
        "holds when every condition listed holds"))
    any: list[Condition] | None = Field(None, min_length=1, max_length=16, description=(
        "holds when at least one condition listed holds"))
    distance: float = Field(120.0, gt=0, description=(
        "ball_reached: mm from the camera to the ball"))
    bearing: float = Field(20.0, gt=0, le=180, description=(
        "ball_reached: the ball within +-bearing deg of the camera axis"))
    facing_goal: float | None = Field(None, gt=0, le=180, description=(
        "ball_reached: also the target goal within +-facing_goal deg of the heading"))
    channel: str | None = Field(None, description=(
        "threshold: the channel (its true, noise-free value), built in or derived"))
    min: float | None = Field(None, description="threshold: holds when channel >= min")
    max: float | None = Field(None, description="threshold: holds when channel <= max")

    @model_serializer(mode="wrap")
    def _only_what_applies(self, handler: SerializerFunctionWrapHandler) -> dict[str, Any]:
        # The defaults of ball_reached's keys would otherwise be written on every kind, and
        # a file written out must read back: keys that do not apply are errors.
        data: dict[str, Any] = handler(self)
        kind = self.when or ""
        for key in _REACH if kind != "ball_reached" else ():
            data.pop(key, None)
        for key in _THRESHOLD if kind != "threshold" else ():
            data.pop(key, None)
        return data

    def problems(self, path: tuple[PathPart, ...], depth: int = 1,
                 ) -> list[tuple[tuple[PathPart, ...], str]]:
        """Keys that do not belong to this kind, a missing one, or nesting too deep."""
        forms = [key for key in ("when", "all", "any") if getattr(self, key) is not None]
        if len(forms) != 1:
            return [(path, "give exactly one of when, all, any" +
                     (f" (this gives {', '.join(forms)})" if forms else ""))]
        if depth > MAX_CONDITION_DEPTH:
            return [(path, f"conditions nest deeper than {MAX_CONDITION_DEPTH} levels")]
        given = {key for key in (*_REACH, *_THRESHOLD) if key in self.model_fields_set}
        kind = self.when or forms[0]
        allowed = set(_REACH if kind == "ball_reached" else
                      _THRESHOLD if kind == "threshold" else ())
        extra = sorted(given - allowed)
        if extra:
            return [(path, f"'{extra[0]}' does not apply to a '{kind}' condition")]
        if kind == "threshold" and (self.channel is None or
                                    (self.min is None and self.max is None)):
            return [(path, "a threshold needs 'channel' and 'min' and/or 'max'")]
        if self.when == "timeout" and depth > 1:
            return [(path, "'timeout' ends an episode by itself; it cannot be combined")]
        found = []
        for key in ("all", "any"):
            for i, part in enumerate(getattr(self, key) or ()):
                found += part.problems((*path, key, i), depth + 1)
        return found

    def leaves(self, path: tuple[PathPart, ...]) -> Iterator[tuple[tuple[PathPart, ...],
                                                                   Condition]]:
        """Every single-kind condition inside this one, with its path."""
        if self.when is not None:
            yield path, self
        for key in ("all", "any"):
            for i, part in enumerate(getattr(self, key) or ()):
                yield from part.leaves((*path, key, i))


class Outcome(Condition):
    """One way an episode ends: the first outcome (in file order) that holds ends it."""

    reward: float = Field(0.0, description="given once, at the step the episode ends")
    success: bool = Field(False, description="whether this ending counts as success")
    held: int = Field(1, ge=1, le=10_000, description=(
        "the condition must hold after this many consecutive steps (1: at once)"))


class StepReward(Section):
    """A reward given after every step: ``scale`` times the channel's true value."""

    channel: str = Field(description="a channel, built in or derived")
    scale: float = Field(description=(
        "reward per unit of the channel per step; keep scale * value * max_steps below the "
        "outcomes' rewards, so that the outcome still decides"))
    abs: bool = Field(False, description="use the channel's absolute value")


class BallVelocity(Section):
    """The ball's velocity at the start: a speed, and a direction or a point it rolls at."""

    speed: Annotated[tuple[float, float], AfterValidator(lambda v: _ordered(v, 0.0))] = Field(
        description="mm per step, uniform in [low, high]")
    towards: Name | None = Field(None, description=(
        "a point the ball rolls at (e.g. own_goal); with spread"))
    spread: float = Field(0.0, ge=0, description=(
        "mm; the aim is uniform within +-spread of the point along y"))
    direction: Annotated[tuple[float, float], AfterValidator(lambda v: _ordered(v, -360.0))
                         ] | None = Field(None, description=(
        "deg, world frame (0 = towards the target goal), uniform in [low, high]"))

    @model_validator(mode="after")
    def _one_direction(self) -> Self:
        if (self.towards is None) == (self.direction is None):
            raise ValueError("give either towards (a point) or direction (deg)")
        if self.direction is not None and "spread" in self.model_fields_set:
            raise ValueError("spread applies to towards, not to direction")
        return self

    @model_serializer(mode="wrap")
    def _only_what_applies(self, handler: SerializerFunctionWrapHandler) -> dict[str, Any]:
        # A file written out must read back: spread's default is not written with a direction.
        data: dict[str, Any] = handler(self)
        if self.direction is not None:
            data.pop("spread", None)
        return data


def _ordered(bounds: tuple[float, float], floor: float) -> tuple[float, float]:
    low, high = bounds
    if not floor <= low <= high:
        raise ValueError(f"[{low:g}, {high:g}] must be [low, high] with {floor:g} <= low <= "
                         "high")
    return bounds


class Opponent(Section):
    """A scripted player: placed uniformly in its box, then acting by its behaviour."""

    x: Annotated[tuple[float, float], AfterValidator(lambda v: _ordered(v, -1e9))] = Field(
        description="mm")
    y: Annotated[tuple[float, float], AfterValidator(lambda v: _ordered(v, -1e9))] = Field(
        description="mm")
    behaviour: Literal["stand", "track", "chase"] = Field("stand", description=(
        "stand: stays; track: keeps its x and steps along y towards the ball's y, within its "
        "y interval (a goalkeeper); chase: walks straight at the ball"))
    speed: float = Field(40.0, ge=0, le=1000, description="mm per step at most")
    radius: float = Field(150.0, gt=0, description="mm; the ball bounces off this circle")


def vocabulary_problems(points: dict[str, FixedPoint], channels: dict[str, DerivedChannel],
                        builtin_channels: tuple[str, ...], outcomes: list[Outcome],
                        rewards: list[StepReward], velocity: BallVelocity | None,
                        opponents: int) -> list[Problem]:
    """Names that do not resolve: points, channels (derived ones included), and conditions
    that do not fit their kind; every problem at its field."""
    env: tuple[PathPart, ...] = ("environment",)
    problems = []
    known_points = (*BUILTIN_POINTS, *points)
    for name in points:
        if name in BUILTIN_POINTS:
            problems.append(Problem((*env, "points", name), f"'{name}' is a built-in point",
                                    "name the fixed point differently"))
    for name, channel in channels.items():
        path = (*env, "channels", name)
        if name in builtin_channels:
            problems.append(Problem(path, f"'{name}' is a built-in channel",
                                    "name the derived channel differently"))
        for point in channel.points:
            problems += _point_problems((*path, channel.kind), point, known_points, opponents)
    if velocity is not None and velocity.towards is not None:
        problems += _point_problems((*env, "start", "ball_velocity", "towards"),
                                    velocity.towards, known_points, opponents)
    known_channels = (*builtin_channels, *channels)
    for i, outcome in enumerate(outcomes):
        path = (*env, "outcomes", i)
        problems += [Problem(where, message, "see the outcome rules in docs/environments.md")
                     for where, message in outcome.problems(path)]
        for where, leaf in outcome.leaves(path):
            if leaf.channel is not None and leaf.channel not in known_channels:
                problems.append(_unknown_channel((*where, "channel"), leaf.channel,
                                                 known_channels))
    for i, reward in enumerate(rewards):
        if reward.channel not in known_channels:
            problems.append(_unknown_channel((*env, "rewards", i, "channel"), reward.channel,
                                             known_channels))
    return problems


def _point_problems(path: tuple[PathPart, ...], point: str, known: tuple[str, ...],
                    opponents: int) -> list[Problem]:
    if point not in known:
        return [Problem(path, f"unknown point '{point}'.{did_you_mean(point, known)}",
                        "the points: " + ", ".join(known) + " (add fixed points under "
                        "environment.points)")]
    if point == "opponent" and not opponents:
        return [Problem(path, "'opponent' names the first opponent, but there is none",
                        "add e.g. 'opponents: [{x: [1900, 1900], y: [-300, 300], "
                        "behaviour: track}]'")]
    return []


def _unknown_channel(path: tuple[PathPart, ...], channel: str,
                     known: tuple[str, ...]) -> Problem:
    return Problem(path, f"unknown channel '{channel}'.{did_you_mean(channel, known)}",
                   "the channels: " + ", ".join(known) + " (derive others under "
                   "environment.channels)")
