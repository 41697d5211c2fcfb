"""The pitch world: a legged robot, a ball, goals, obstacles and opponents on a football pitch.

World frame: the pitch is centred on the origin, x along its length towards the target goal,
angles counter-clockwise (positive = to the left, as in ROS). The robot's head camera sits
``robot.neck_offset`` ahead of the body centre and always pans towards the ball.

One step, in this order (docs/environments.md gives every formula):

1. the walking command: the robot turns by the command's rotation, then moves forward and
   sideways along its new heading; each component is the command's mean plus its standard
   deviation times a standard normal (the paper's "statistical model measured from real robot
   motion");
2. moving obstacles advance and bounce off the pitch's edges; opponents act on the ball's
   position (stand, track it along y, chase it), then move the robot out of their bodies
   (contact: the robot cannot walk through them);
3. the ball rolls (velocity decays by ``ball.friction``); if the robot's body (then an
   opponent's) touches it, it is pushed out of the body and takes ``ball.kick`` times that
   body's step as its velocity; at the pitch's edge it stops, unless it crosses a goal line
   inside the goal mouth;
4. the sensors read the new state (each channel with its own noise);
5. the outcomes are tested in file order; the first that holds (for its ``held`` steps) ends
   the episode; per-step rewards are added.

Two engines behind one adapter: :class:`_OneEpisode` runs one episode on Python floats (a few
microseconds per step, for learners running trials one after another), :class:`_Batch` runs B
episodes on numpy arrays and masks the finished ones. Both run the dynamics of
:mod:`flctool.envs.pitch_dynamics`, written once, and agree bit for bit.

Randomness: episode ``b`` draws its start and *all* its noise from
``numpy.random.default_rng(seeds[b])`` at reset: 5 uniforms (robot and ball placement), a
(max_steps + 1, 3 + C) table of standard normals (motion forward, sideways, rotation; then one
column per noisy channel: ball_size and pan always, then the other built-in channels read, in
:data:`PITCH_CHANNELS` order, then the derived channels read, in file order), then 3 uniforms
per obstacle, 2 per opponent, and 2 for the ball's start velocity if it has one -- so
ballchase's draws are the first two of these.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from flctool.behaviour.environment import PITCH_CHANNELS, Motion, MotionNoise, PitchConfig
from flctool.behaviour.models import Behaviour
from flctool.envs.base import BatchEnv, BoolArray, FloatArray, Step
from flctool.envs.pitch_drive import CommandDrive, Drive
from flctool.envs.pitch_dynamics import (
    ARRAYS,
    FLOATS,
    STATE_FIELDS,
    ConditionTest,
    Groups,
    Mask,
    Ops,
    State,
    V,
    advance,
    condition_test,
    noise_kind,
    observe,
    point,
    sense,
)
from flctool.envs.pitch_world import OutcomeRule, World, world_from_config
from flctool.errors import EnvError, SpecError

__all__ = ["OutcomeRule", "PitchSim", "World", "world_from_config"]

_RAD = math.pi / 180.0
_DEG = 180.0 / math.pi
_MOTION_COLUMNS = 3
_UNIFORMS = 5  # robot and ball placement; then 3 per obstacle, 2 per opponent, 2 for a launch


class _Rules:
    """The outcomes and per-step rewards, applied after each step by either engine."""

    def __init__(self, world: World) -> None:
        self.world = world
        self.tests: list[ConditionTest[Any]] = [condition_test(world, rule.test)
                                                for rule in world.outcomes]
        self.held = [rule.held for rule in world.outcomes]
        self.rewards = [0.0] + [r.reward for r in world.outcomes]
        self.successes = [False] + [r.success for r in world.outcomes]

    def _holds(self, ops: Ops[V], index: int, s: State[V], true: dict[str, V]) -> Mask:
        raw = self.tests[index](ops, s, true)
        if self.held[index] == 1:
            return raw
        s.held[index] = ops.where(raw, s.held[index] + 1.0, 0.0)
        return s.held[index] >= self.held[index]

    def outcome(self, ops: Ops[V], s: State[V], true: dict[str, V]) -> Any:
        """Index + 1 of the first declared outcome that holds, 0 for none."""
        if ops is FLOATS:  # one episode: stop at the first that holds
            for index in range(len(self.tests)):
                if self._holds(ops, index, s, true):
                    return index + 1
            return 0
        holds = [self._holds(ops, index, s, true) for index in range(len(self.tests))]
        code: Any = 0
        for index in range(len(holds) - 1, -1, -1):  # the first that holds is set last
            code = np.where(holds[index], index + 1, code)
        return code

    def shaping(self, true: dict[str, V]) -> V | float:
        """The per-step rewards: sum of scale times each channel's true value."""
        total: V | float = 0.0
        for channel, scale, absolute in self.world.rewards:
            value = true[channel]
            total = total + scale * (abs(value) if absolute else value)
        return total


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
                 extra_channels: tuple[str, ...] = (), drive: Drive | None = None) -> None:
        self.world = world
        self.votes = votes
        self.channels = channels
        self.observation_names = observation_names or channels
        self.max_steps = world.max_steps
        self.drive: Drive = drive or CommandDrive(commands, motion, noise, world.nearest)
        self.command_order = self.drive.order
        self.action_bounds = (float(self.drive.values[0]), float(self.drive.values[-1]))
        derived = {d.name: d for d in world.derived}
        # the observations, then what only a composition's parts read
        read = (*channels, *(c for c in dict.fromkeys(extra_channels) if c not in channels))
        self.n_observations = len(channels)
        noisy = ["ball_size", "pan"] + [c for c in PITCH_CHANNELS[2:] if c in read] + [
            d.name for d in world.derived if d.name in read]
        column = {c: _MOTION_COLUMNS + i for i, c in enumerate(noisy)}
        self.columns = _MOTION_COLUMNS + len(noisy)
        self.observers = [(c, noise_kind(c, derived), world.noise[c], column[c]) for c in read]
        self.rules = _Rules(world)
        needed = set(read).union(*(rule.test.channels() for rule in world.outcomes),
                                     (channel for channel, _, _ in world.rewards))
        self.derived = tuple(d for d in world.derived if d.name in needed)
        self.needed = Groups.of(frozenset(needed), world)
        self._engine: _OneEpisode | _Batch | None = None

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
        world = world_from_config(config)
        if config.compose:
            from flctool.envs.pitch_compose import composed_drive

            drive, extra = composed_drive(behaviour, config, channels)
            return cls(world, dict(behaviour.output.commands), config.motion, config.noise,
                       channels, behaviour.input_names, config.action == "vote",
                       extra_channels=extra, drive=drive)
        return cls(world, dict(behaviour.output.commands), config.motion, config.noise,
                   channels, behaviour.input_names, config.action == "vote")

    # -- the poses, from whichever engine ran last -------------------------------------------
    def _pose(self, name: str) -> FloatArray:
        if self._engine is None:
            raise EnvError("no episode yet", hint="call reset(seeds) first")
        return np.array(getattr(self._engine.state, name), dtype=np.float64).reshape(-1)

    x = property(lambda self: self._pose("x"), doc="(B,) robot x, mm")
    y = property(lambda self: self._pose("y"), doc="(B,) robot y, mm")
    heading = property(lambda self: self._pose("heading"), doc="(B,) rad, unwrapped")
    ball_x = property(lambda self: self._pose("ball_x"), doc="(B,) mm")
    ball_y = property(lambda self: self._pose("ball_y"), doc="(B,) mm")

    # -- what both engines share: the start, the draws, the readings -------------------------
    def start(self, ops: Ops[V], u: Sequence[Any], obstacle_u: Sequence[Any],
              extra_u: Sequence[Any]) -> State[V]:
        """Place the robot, ball, obstacles and opponents from uniforms ``u`` (5),
        ``obstacle_u`` (3 per obstacle) and ``extra_u`` (2 per opponent, then 2 for the ball's
        velocity)."""
        w = self.world
        heading: Any = (2.0 * u[2] - 1.0) * w.heading_half
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
        opponents = []
        for i, opponent in enumerate(w.opponents):
            ox_lo, ox_hi, oy_lo, oy_hi = opponent.box
            ux, uy = extra_u[2 * i : 2 * i + 2]
            opponents.append([ox_lo + ux * (ox_hi - ox_lo), oy_lo + uy * (oy_hi - oy_lo),
                              zero, zero])
        s = State(x, y, heading, ball_x, ball_y, zero, zero, obstacles, zero, zero != 0.0,
                  zero, zero, opponents, [zero for _ in w.outcomes])
        if w.launch is not None:
            self._launch(ops, s, extra_u[2 * len(w.opponents):])
        return s

    def _launch(self, ops: Ops[V], s: State[V], u: Sequence[Any]) -> None:
        """The ball's start velocity from two uniforms: speed, then direction or aim."""
        launch = self.world.launch
        assert launch is not None
        speed = launch.speed[0] + u[0] * (launch.speed[1] - launch.speed[0])
        if launch.direction is not None:
            low, high = launch.direction
            angle = low + u[1] * (high - low) + 0.0 * s.x
        else:
            tx, ty = point(self.world, s, launch.towards)
            ty = ty + (2.0 * u[1] - 1.0) * launch.spread
            angle = ops.atan2(ty - s.ball_y, tx - s.ball_x)
        s.ball_vx, s.ball_vy = speed * ops.cos(angle), speed * ops.sin(angle)

    def draw(self, seed: int) -> tuple[list[float], list[float], list[float], FloatArray]:
        """Episode ``seed``'s randomness: placement uniforms, obstacle uniforms, opponent and
        launch uniforms, the normals (max_steps + 1, columns) -- row 0 senses the start, row t
        the result of step t."""
        rng = np.random.default_rng(seed)
        w = self.world
        u = rng.random(_UNIFORMS).tolist()
        noise = rng.standard_normal((self.max_steps + 1, self.columns))
        obstacle_u = rng.random(3 * len(w.obstacles)).tolist()
        extra = 2 * len(w.opponents) + (2 if w.launch is not None else 0)
        extra_u = rng.random(extra).tolist() if extra else []
        return u, obstacle_u, extra_u, noise

    def read(self, ops: Ops[V], s: State[V], cos_h: V, sin_h: V, z: Any,
             ) -> tuple[list[V], dict[str, V]]:
        """Readings of the behaviour's channels (N floats, or N arrays (B,)) from the noise
        row ``z`` ((columns,) or (B, columns)), and the true channel values."""
        true = sense(ops, self.world, s, cos_h, sin_h, self.needed, self.derived)
        w = self.world
        if ops is FLOATS:
            return [observe(ops, w, true[c], kind, std, z[col])
                    for c, kind, std, col in self.observers], true
        return [observe(ops, w, true[c], kind, std, z[:, col])
                for c, kind, std, col in self.observers], true

    # -- the protocol ------------------------------------------------------------------------
    def reset(self, seeds: NDArray[np.int64]) -> tuple[FloatArray, dict[str, Any]]:
        """Start one episode per seed: (B,) -> observations (B, N), info {}."""
        seeds = np.asarray(seeds, dtype=np.int64).reshape(-1)
        if seeds.shape[0] < 1:
            raise EnvError("reset needs at least one seed")
        if seeds.shape[0] == 1:
            return self.reset_one(int(seeds[0]))[None, :], {}
        engine = _Batch(self, seeds)
        self._engine = engine
        return engine.obs.copy(), {}

    def step(self, actions: FloatArray) -> Step:
        """Apply crisp outputs ``actions (B,)``; finished episodes stay as they are."""
        actions = np.asarray(actions, dtype=np.float64).reshape(-1)
        engine = self._engine
        if engine is None:
            raise EnvError("step before reset", hint="call reset(seeds) first")
        batch = engine.batch_size
        if actions.shape[0] != batch:
            raise EnvError(f"step got {actions.shape[0]} actions for {batch} episodes")
        if isinstance(engine, _OneEpisode):
            obs, reward, terminated, truncated = engine.step(float(actions[0]))
            return Step(obs[None, :], np.array([reward]), np.array([terminated]),
                        np.array([truncated]))
        return engine.step(actions)

    def reset_one(self, seed: int) -> FloatArray:
        """Start a single episode; the same start as :meth:`reset` with ``[seed]``."""
        engine = _OneEpisode(self, seed)
        self._engine = engine
        return np.array(engine.obs)

    def step_one(self, action: float) -> tuple[FloatArray, float, bool, bool]:
        """Step the episode started by :meth:`reset_one` (the fast path)."""
        if not isinstance(self._engine, _OneEpisode):
            return super().step_one(action)
        return self._engine.step(action)

    def success(self) -> BoolArray:
        """(B,) whether each episode has ended in a success outcome."""
        if self._engine is None:
            raise EnvError("no episode yet", hint="call reset(seeds) first")
        return self._engine.success()

    #: What :meth:`episode_fitness` can give: 0 (a failure at once) to 2 (success at once).
    fitness_range = (0.0, 2.0)

    def episode_fitness(self, returns: FloatArray, lengths: NDArray[np.int64],
                        success: BoolArray) -> FloatArray:
        """Trial fitness for the GA, (B,) each: :func:`timed_fitness`."""
        del returns
        return timed_fitness(lengths, success, self.max_steps)

    def trace_state(self) -> dict[str, FloatArray]:
        """Robot pose (mm, deg in [-180, 180)) and ball position, each (B,)."""
        heading = np.remainder(self.heading * _DEG + 180.0, 360.0) - 180.0
        return {"robot_x": self.x, "robot_y": self.y, "robot_heading": heading,
                "ball_x": self.ball_x, "ball_y": self.ball_y}


class _OneEpisode:
    """One episode on Python floats: the learners' fast path."""

    batch_size = 1

    def __init__(self, sim: PitchSim, seed: int) -> None:
        self.sim = sim
        u, obstacle_u, extra_u, noise = sim.draw(seed)
        self.noise: list[float] = noise.ravel().tolist()
        self.state: State[float] = sim.start(FLOATS, u, obstacle_u, extra_u)
        self.t = 0
        self.terminated = self.truncated = self.succeeded = False
        s = self.state
        values, _ = sim.read(FLOATS, s, math.cos(s.heading), math.sin(s.heading),
                             self.noise[: sim.columns])
        self.readings = values
        self.obs: FloatArray = np.array(values[: sim.n_observations], dtype=np.float64)

    def step(self, action: float) -> tuple[FloatArray, float, bool, bool]:
        if self.terminated or self.truncated:
            return np.array(self.obs), 0.0, self.terminated, self.truncated
        if action != action:
            raise EnvError("the action is NaN", hint="check the controller's output")
        sim, world = self.sim, self.sim.world
        mean, std = sim.drive.one(action, self.readings)
        columns = sim.columns
        row = columns * min(self.t + 1, sim.max_steps)
        z = self.noise[row : row + columns]
        s = self.state
        cos_h, sin_h = advance(FLOATS, world, s, mean, std, z)
        readings, true = sim.read(FLOATS, s, cos_h, sin_h, z)
        code = sim.rules.outcome(FLOATS, s, true)
        self.t += 1
        timeout = code == 0 and self.t >= sim.max_steps
        self.succeeded = sim.rules.successes[code] or (timeout and world.timeout_success)
        reward = sim.rules.rewards[code] + (world.timeout_reward if timeout else 0.0)
        if world.rewards:
            reward = reward + float(sim.rules.shaping(true))
        self.terminated, self.truncated = code > 0, timeout
        self.readings = readings
        # returned, kept, never mutated
        self.obs = obs = np.array(readings[: sim.n_observations], dtype=np.float64)
        return obs, reward, code > 0, timeout

    def success(self) -> BoolArray:
        return np.array([self.succeeded])


class _Batch:
    """B episodes on numpy arrays; finished episodes keep their state."""

    def __init__(self, sim: PitchSim, seeds: NDArray[np.int64]) -> None:
        self.sim = sim
        batch = self.batch_size = seeds.shape[0]
        w = sim.world
        extra = 2 * len(w.opponents) + (2 if w.launch is not None else 0)
        uniforms = np.empty((batch, _UNIFORMS))
        obstacle_u = np.empty((batch, 3 * len(w.obstacles)))
        extra_u = np.empty((batch, extra))
        self.noise = np.empty((batch, sim.max_steps + 1, sim.columns))
        for b, seed in enumerate(seeds.tolist()):
            uniforms[b], obstacle_u[b], extra_u[b], self.noise[b] = sim.draw(seed)
        self.state: State[FloatArray] = sim.start(ARRAYS, list(uniforms.T), list(obstacle_u.T),
                                                  list(extra_u.T))
        self.t = np.zeros(batch, dtype=np.int64)
        self.terminated = np.zeros(batch, dtype=bool)
        self.truncated = np.zeros(batch, dtype=bool)
        self.reached = np.zeros(batch, dtype=bool)
        s = self.state
        values, _ = sim.read(ARRAYS, s, ARRAYS.cos(s.heading), ARRAYS.sin(s.heading),
                             self.noise[:, 0])
        self.readings = values
        self.obs = _stack(values[: sim.n_observations], batch)

    def step(self, actions: FloatArray) -> Step:
        if np.isnan(actions).any():
            raise EnvError("an action is NaN", hint="check the controller's output")
        sim, world, batch = self.sim, self.sim.world, self.batch_size
        active = ~(self.terminated | self.truncated)
        rows = np.minimum(self.t + 1, sim.max_steps)
        z = self.noise[np.arange(batch), rows]  # (B, columns)
        mean, std = sim.drive.batch(actions, self.readings)
        before = self.state
        s = before.copy()
        cos_h, sin_h = advance(ARRAYS, world, s, mean, std, [z[:, 0], z[:, 1], z[:, 2]])
        values, true = sim.read(ARRAYS, s, cos_h, sin_h, z)
        code = np.where(active, sim.rules.outcome(ARRAYS, s, true), 0)
        # finished episodes keep their state
        for name in STATE_FIELDS:
            setattr(s, name, np.where(active, getattr(s, name), getattr(before, name)))
        for new_list, old_list in ((s.obstacles, before.obstacles),
                                   (s.opponents, before.opponents)):
            for new, old in zip(new_list, old_list, strict=True):
                new[:] = [np.where(active, a, b) for a, b in zip(new, old, strict=True)]
        s.held = [np.where(active, a, b) for a, b in zip(s.held, before.held, strict=True)]
        self.state = s
        self.t = self.t + active
        if sim.drive.reads:
            self.readings = [np.where(active, new, old)
                             for new, old in zip(values, self.readings, strict=True)]
        self.obs = np.where(active[:, None], _stack(values[: sim.n_observations], batch),
                            self.obs)
        ended = code > 0
        timeout = active & ~ended & (self.t >= sim.max_steps)
        success = np.asarray(sim.rules.successes)[code] & ended
        success |= timeout & world.timeout_success
        rewards = np.asarray(sim.rules.rewards)[code] + np.where(timeout, world.timeout_reward,
                                                                 0.0)
        if world.rewards:
            rewards = rewards + np.where(active, sim.rules.shaping(true), 0.0)
        self.reached |= success
        self.terminated |= ended
        self.truncated |= timeout
        return Step(self.obs.copy(), rewards, self.terminated.copy(), self.truncated.copy())

    def success(self) -> BoolArray:
        return np.array(self.reached)


def _stack(columns: list[FloatArray], batch: int) -> FloatArray:
    return np.stack(columns, axis=1) if columns else np.zeros((batch, 0))


def timed_fitness(lengths: NDArray[np.int64], success: BoolArray, max_steps: int) -> FloatArray:
    """Trial fitness where faster success scores higher, (B,) each (also the ros2 adapter's
    ``fitness: timed``).

    success after L steps: ``2 - L / max_steps`` in [1, 2]; any other ending after L
    steps: ``0.5 * L / max_steps`` in [0, 0.5] (a time-out gives 0.5) -- lasting longer
    before a failure is better than failing at once, and any success beats every failure.
    """
    fraction = np.asarray(lengths, dtype=np.float64) / max_steps
    result: FloatArray = np.where(np.asarray(success, dtype=bool), 2.0 - fraction,
                                  0.5 * fraction)
    return result
