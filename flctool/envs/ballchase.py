"""The ballchase simulator of paper Sec. IV: a legged robot walks to a ball its head tracks.

World frame: the pitch is centred on the origin, x along its length, angles counter-clockwise
(positive = to the left, as in ROS). The ball does not move. The robot's head camera sits at
the neck, ``robot.neck_offset`` ahead of the body centre, and always pans towards the ball.

One step = one walking command (``step_period`` seconds): the robot turns by the command's
rotation, then moves forward and sideways along its new heading; each component is the
command's mean plus Gaussian noise (the paper's "statistical model measured from real robot
motion"). Observations, in the behaviour's input order:

* ``ball_size`` -- apparent ball diameter as a fraction of the image width, pinhole camera:
  ``min(1, touch / d)`` with ``d`` the camera-to-ball distance and
  ``touch = diameter / (2 tan(fov / 2))`` the distance at which the ball fills the image;
  times ``(1 + sensor_noise.ball_size * z)``, clipped to [0, 1].
* ``pan`` -- the head pan angle in degrees = bearing of the ball from the camera, plus
  ``sensor_noise.pan * z``, clipped to the neck range.

Outcomes (delayed reward, as in the paper): reached (camera within ``goal.distance`` of the
ball and ``|pan| <= goal.bearing``) -> terminated, success, reward +1; lost (true pan beyond the
neck range, or the robot's centre off the pitch) -> terminated, reward -1; ``max_steps`` steps
-> truncated; reward 0 otherwise.

Randomness: episode ``b`` draws its start and *all* its noise from
``numpy.random.default_rng(seeds[b])`` at reset, so batched and one-at-a-time runs agree bit
for bit. Two code paths compute the same arithmetic: plain Python floats for B = 1 (a few
microseconds per step, for learners running trials one after another) and numpy arrays for
larger B. Both take sin, cos and atan2 from libm through :mod:`math`, because numpy's SIMD
versions may differ from libm in the last bit.
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from flctool.envs.base import BatchEnv, BoolArray, FloatArray, Step
from flctool.errors import EnvError, Problem, SpecError
from flctool.spec.environment import BALLCHASE_OBSERVATIONS, BallchaseSimConfig
from flctool.spec.models import Behaviour

OBSERVATIONS = BALLCHASE_OBSERVATIONS
_RAD = math.pi / 180.0
_DEG = 180.0 / math.pi
# Standard normals drawn per step: motion forward, sideways, rotation; sensor size, pan.
_NOISE_COLUMNS = 5


def _map1(fn: Callable[[float], float], x: FloatArray) -> FloatArray:
    return np.fromiter(map(fn, x.tolist()), dtype=np.float64, count=x.shape[0])


def _cos(x: FloatArray) -> FloatArray:
    return _map1(math.cos, x)


def _sin(x: FloatArray) -> FloatArray:
    return _map1(math.sin, x)


def _atan2(y: FloatArray, x: FloatArray) -> FloatArray:
    return np.fromiter(map(math.atan2, y.tolist(), x.tolist()), dtype=np.float64,
                       count=y.shape[0])


class BallchaseSim(BatchEnv):
    """B ballchase episodes; observations are the behaviour's inputs (ball_size and/or pan).

    Build it with :func:`flctool.envs.make_env` or :meth:`from_behaviour`.
    """

    def __init__(self, config: BallchaseSimConfig, commands: dict[str, float],
                 observation_names: tuple[str, ...] = OBSERVATIONS) -> None:
        _check_fit(config, commands, observation_names)
        self.config = config
        self.observation_names = observation_names
        self.max_steps = config.max_steps
        self._columns = [OBSERVATIONS.index(name) for name in observation_names]
        order = sorted(commands, key=lambda name: commands[name])
        self.command_order = tuple(order)  # commands by increasing singleton
        self._values = np.array([commands[n] for n in order], dtype=np.float64)
        self._mean = np.array([[config.motion[n].forward, config.motion[n].sideways,
                                config.motion[n].rotation * _RAD] for n in order])
        self._std = np.array([[config.noise[n].forward, config.noise[n].sideways,
                               config.noise[n].rotation * _RAD] for n in order])
        self.action_bounds = (float(self._values[0]), float(self._values[-1]))
        # Python lists for the scalar path
        self._values_list: list[float] = self._values.tolist()
        self._mean_list: list[list[float]] = self._mean.tolist()
        self._std_list: list[list[float]] = self._std.tolist()
        # Constants of the scalar path, looked up once rather than through the config every step
        # (the same values, so the same arithmetic).
        # A vote's output is a singleton, so it executes as the nearest command does.
        self.votes = config.action == "vote"
        self._nearest = config.action in ("nearest", "vote") or len(order) == 1
        self._offset = config.robot.neck_offset
        self._size_noise = config.sensor_noise.ball_size
        self._pan_noise = config.sensor_noise.pan
        self._neck = config.robot.neck_range
        self._neck_rad = config.robot.neck_range * _RAD
        self._goal_distance = config.goal.distance
        self._goal_bearing_rad = config.goal.bearing * _RAD
        robot = config.robot
        self._touch = config.ball.diameter / (2.0 * math.tan(robot.camera_fov * _RAD / 2.0))
        self._half = (config.pitch.length / 2.0, config.pitch.width / 2.0)
        self._scalar = False
        self._started = False
        self._reset_arrays(1)

    @classmethod
    def from_behaviour(cls, behaviour: Behaviour, batch_size: int = 1) -> BallchaseSim:
        del batch_size  # B is the number of seeds given to reset
        config = behaviour.environment
        if not isinstance(config, BallchaseSimConfig):
            raise EnvError("the ballchase simulator needs 'environment: {adapter: ballchase-sim}'")
        return cls(config, dict(behaviour.output.commands), behaviour.input_names)

    # -- reset -----------------------------------------------------------------------------
    def _reset_arrays(self, batch: int) -> None:
        shape = (batch,)
        self.x: FloatArray = np.zeros(shape)
        self.y: FloatArray = np.zeros(shape)
        self.heading: FloatArray = np.zeros(shape)  # rad, unwrapped
        self.ball_x: FloatArray = np.zeros(shape)
        self.ball_y: FloatArray = np.zeros(shape)
        self.t: NDArray[np.int64] = np.zeros(shape, dtype=np.int64)
        self.terminated: BoolArray = np.ones(shape, dtype=bool)
        self.truncated: BoolArray = np.zeros(shape, dtype=bool)
        self.reached: BoolArray = np.zeros(shape, dtype=bool)
        self.obs: FloatArray = np.zeros((batch, len(self.observation_names)))
        # (B, max_steps + 1, 5): row 0 senses the start, row t the result of step t
        self.noise: FloatArray = np.zeros((batch, self.max_steps + 1, _NOISE_COLUMNS))

    def reset(self, seeds: NDArray[np.int64]) -> tuple[FloatArray, dict[str, Any]]:
        """Start one episode per seed: (B,) -> observations (B, N), info {}."""
        seeds = np.asarray(seeds, dtype=np.int64).reshape(-1)
        batch = seeds.shape[0]
        if batch < 1:
            raise EnvError("reset needs at least one seed")
        if batch == 1:
            return self.reset_one(int(seeds[0]))[None, :], {}
        self._scalar = False
        self._started = True
        cfg = self.config
        uniforms = np.empty((batch, 5))
        self._reset_arrays(batch)
        for b, seed in enumerate(seeds.tolist()):
            rng = np.random.default_rng(seed)
            uniforms[b] = rng.random(5)
            self.noise[b] = rng.standard_normal((self.max_steps + 1, _NOISE_COLUMNS))
        low, high = cfg.start.distance
        distance = low + (high - low) * uniforms[:, 0]
        bearing = (2.0 * uniforms[:, 1] - 1.0) * cfg.start.bearing * _RAD
        heading = (2.0 * uniforms[:, 2] - 1.0) * math.pi
        cos_h, sin_h = _cos(heading), _sin(heading)
        offset = cfg.robot.neck_offset
        # Ball relative to the body centre; the robot is then placed uniformly where both it
        # and the ball are on the pitch (the config validator guarantees there is room).
        rel_x = offset * cos_h + distance * _cos(heading + bearing)
        rel_y = offset * sin_h + distance * _sin(heading + bearing)
        ball_r, robot_r = cfg.ball.diameter / 2.0, cfg.robot.radius
        for axis, rel, u in ((0, rel_x, uniforms[:, 3]), (1, rel_y, uniforms[:, 4])):
            half = self._half[axis]
            lo = np.maximum(-half + robot_r, -half + ball_r - rel)
            hi = np.minimum(half - robot_r, half - ball_r - rel)
            pos = lo + u * (hi - lo)
            if axis == 0:
                self.x, self.ball_x = pos, pos + rel
            else:
                self.y, self.ball_y = pos, pos + rel
        self.heading = heading
        self.terminated[:] = False
        size, pan, _, _ = self._sense(cos_h, sin_h, self.noise[:, 0, 3], self.noise[:, 0, 4])
        self.obs = self._stack(size, pan)
        return self.obs.copy(), {}

    # -- the vectorised path -------------------------------------------------------------
    def _sense(self, cos_h: FloatArray, sin_h: FloatArray, z_size: FloatArray,
               z_pan: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """Observed size and pan, true camera-to-ball distance and pan (rad), all (B,)."""
        cfg = self.config
        offset = cfg.robot.neck_offset
        dx = self.ball_x - (self.x + offset * cos_h)
        dy = self.ball_y - (self.y + offset * sin_h)
        u = dx * cos_h + dy * sin_h
        v = dy * cos_h - dx * sin_h
        distance = np.sqrt(dx * dx + dy * dy)
        pan = _atan2(v, u)
        size = np.minimum(1.0, self._touch / np.maximum(distance, 1e-9))
        size = np.clip(size * (1.0 + cfg.sensor_noise.ball_size * z_size), 0.0, 1.0)
        neck = cfg.robot.neck_range
        seen = np.clip(pan * _DEG + cfg.sensor_noise.pan * z_pan, -neck, neck)
        return size, seen, distance, pan

    def _stack(self, size: FloatArray, pan: FloatArray) -> FloatArray:
        both = (size, pan)
        return np.stack([both[c] for c in self._columns], axis=1)

    def _motion(self, actions: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Mean and std (B, 3) of the commanded displacement for crisp outputs (B,)."""
        values = self._values
        a = np.clip(actions, values[0], values[-1])
        if self._nearest:
            k = np.argmin(np.abs(a[:, None] - values[None, :]), axis=1)
            return self._mean[k], self._std[k]
        j = np.clip(np.searchsorted(values, a, side="right") - 1, 0, values.shape[0] - 2)
        gap = values[j + 1] - values[j]
        w = np.where(gap > 0, (a - values[j]) / np.where(gap > 0, gap, 1.0), 0.0)[:, None]
        mean = (1.0 - w) * self._mean[j] + w * self._mean[j + 1]
        std = (1.0 - w) * self._std[j] + w * self._std[j + 1]
        return mean, std

    def step(self, actions: FloatArray) -> Step:
        """Apply crisp outputs ``actions (B,)``; finished episodes stay as they are."""
        actions = np.asarray(actions, dtype=np.float64).reshape(-1)
        if not self._started:
            raise EnvError("step before reset", hint="call reset(seeds) first")
        if actions.shape[0] != self.x.shape[0]:
            raise EnvError(f"step got {actions.shape[0]} actions for {self.x.shape[0]} episodes")
        if self._scalar:
            obs, reward, terminated, truncated = self.step_one(float(actions[0]))
            return Step(obs[None, :], np.array([reward]), np.array([terminated]),
                        np.array([truncated]))
        if np.isnan(actions).any():
            raise EnvError("an action is NaN", hint="check the controller's output")
        cfg = self.config
        active = ~(self.terminated | self.truncated)
        rows = np.minimum(self.t + 1, self.max_steps)
        z = self.noise[np.arange(self.x.shape[0]), rows]  # (B, 5)
        mean, std = self._motion(actions)
        move = mean + std * z[:, :3]
        heading = self.heading + move[:, 2]
        cos_h, sin_h = _cos(heading), _sin(heading)
        x = self.x + move[:, 0] * cos_h - move[:, 1] * sin_h
        y = self.y + move[:, 0] * sin_h + move[:, 1] * cos_h
        self.x = np.where(active, x, self.x)
        self.y = np.where(active, y, self.y)
        self.heading = np.where(active, heading, self.heading)
        size, pan, distance, true_pan = self._sense(cos_h, sin_h, z[:, 3], z[:, 4])
        reached = active & (distance <= cfg.goal.distance) & (
            np.abs(true_pan) <= cfg.goal.bearing * _RAD)
        off_pitch = (np.abs(self.x) > self._half[0]) | (np.abs(self.y) > self._half[1])
        lost = active & ~reached & (
            (np.abs(true_pan) > cfg.robot.neck_range * _RAD) | off_pitch)
        self.t = self.t + active
        self.obs = np.where(active[:, None], self._stack(size, pan), self.obs)
        self.reached |= reached
        self.terminated |= reached | lost
        self.truncated |= active & ~(reached | lost) & (self.t >= self.max_steps)
        rewards = reached.astype(np.float64) - lost.astype(np.float64)
        return Step(self.obs.copy(), rewards, self.terminated.copy(), self.truncated.copy())

    # -- the scalar path (B = 1), the same arithmetic on Python floats -----------------------
    def reset_one(self, seed: int) -> FloatArray:
        """Start a single episode; the same start as :meth:`reset` with ``[seed]``."""
        cfg = self.config
        rng = np.random.default_rng(seed)
        u_distance, u_bearing, u_heading, u_x, u_y = rng.random(5).tolist()
        noise = rng.standard_normal((self.max_steps + 1, _NOISE_COLUMNS))
        self._snoise: list[float] = noise.ravel().tolist()
        low, high = cfg.start.distance
        distance = low + (high - low) * u_distance
        bearing = (2.0 * u_bearing - 1.0) * cfg.start.bearing * _RAD
        heading = (2.0 * u_heading - 1.0) * math.pi
        cos_h, sin_h = math.cos(heading), math.sin(heading)
        offset = cfg.robot.neck_offset
        rel_x = offset * cos_h + distance * math.cos(heading + bearing)
        rel_y = offset * sin_h + distance * math.sin(heading + bearing)
        ball_r, robot_r = cfg.ball.diameter / 2.0, cfg.robot.radius
        half_x, half_y = self._half
        lo = max(-half_x + robot_r, -half_x + ball_r - rel_x)
        hi = min(half_x - robot_r, half_x - ball_r - rel_x)
        x = lo + u_x * (hi - lo)
        lo = max(-half_y + robot_r, -half_y + ball_r - rel_y)
        hi = min(half_y - robot_r, half_y - ball_r - rel_y)
        y = lo + u_y * (hi - lo)
        self._sx, self._sy, self._sh = x, y, heading
        self._sbx, self._sby = x + rel_x, y + rel_y
        self._st = 0
        self._sdone = False
        self._scalar = True
        if self.x.shape[0] != 1:
            self._reset_arrays(1)
        self.ball_x[0], self.ball_y[0] = self._sbx, self._sby
        self.noise = noise[None]
        self._store_scalar(False, False, False)
        self._started = True
        size, seen, _, _ = self._sense_one(x, y, cos_h, sin_h, self._snoise[3], self._snoise[4])
        obs: FloatArray = self.obs[0]
        both = (size, seen)
        for i, c in enumerate(self._columns):
            obs[i] = both[c]
        return np.array(obs)

    def _sense_one(self, x: float, y: float, cos_h: float, sin_h: float, z_size: float,
                   z_pan: float) -> tuple[float, float, float, float]:
        """:meth:`_sense` for one episode on floats."""
        offset = self._offset
        dx = self._sbx - (x + offset * cos_h)
        dy = self._sby - (y + offset * sin_h)
        pan = math.atan2(dy * cos_h - dx * sin_h, dx * cos_h + dy * sin_h)
        distance = math.sqrt(dx * dx + dy * dy)
        size = min(1.0, self._touch / max(distance, 1e-9))
        size = min(max(size * (1.0 + self._size_noise * z_size), 0.0), 1.0)
        neck = self._neck
        seen = min(max(pan * _DEG + self._pan_noise * z_pan, -neck), neck)
        return size, seen, distance, pan

    def _store_scalar(self, terminated: bool, truncated: bool, reached: bool) -> None:
        self.x[0], self.y[0], self.heading[0] = self._sx, self._sy, self._sh
        self.t[0] = self._st
        self.terminated[0], self.truncated[0], self.reached[0] = terminated, truncated, reached

    def step_one(self, action: float) -> tuple[FloatArray, float, bool, bool]:
        """Step the episode started by :meth:`reset_one` (the fast path: a few microseconds)."""
        if not self._scalar:
            return super().step_one(action)
        if self._sdone:
            return self.obs[0].copy(), 0.0, bool(self.terminated[0]), bool(self.truncated[0])
        if action != action:
            raise EnvError("the action is NaN", hint="check the controller's output")
        values = self._values_list
        count = len(values)
        a = min(max(action, values[0]), values[-1])
        if self._nearest:
            k = min(range(count), key=lambda i: abs(a - values[i]))
            mean, std = self._mean_list[k], self._std_list[k]
            mf, ms, mr = mean
            sf, ss, sr = std
        else:
            j = min(max(bisect.bisect_right(values, a) - 1, 0), count - 2)
            gap = values[j + 1] - values[j]
            w = (a - values[j]) / gap if gap > 0 else 0.0
            m0, m1 = self._mean_list[j], self._mean_list[j + 1]
            s0, s1 = self._std_list[j], self._std_list[j + 1]
            mf = (1.0 - w) * m0[0] + w * m1[0]
            ms = (1.0 - w) * m0[1] + w * m1[1]
            mr = (1.0 - w) * m0[2] + w * m1[2]
            sf = (1.0 - w) * s0[0] + w * s1[0]
            ss = (1.0 - w) * s0[1] + w * s1[1]
            sr = (1.0 - w) * s0[2] + w * s1[2]
        row = _NOISE_COLUMNS * min(self._st + 1, self.max_steps)
        zf, zs, zr, zsize, zpan = self._snoise[row : row + _NOISE_COLUMNS]
        forward, sideways = mf + sf * zf, ms + ss * zs
        heading = self._sh + (mr + sr * zr)
        cos_h, sin_h = math.cos(heading), math.sin(heading)
        x = self._sx + forward * cos_h - sideways * sin_h
        y = self._sy + forward * sin_h + sideways * cos_h
        self._sx, self._sy, self._sh = x, y, heading
        size, seen, distance, pan = self._sense_one(x, y, cos_h, sin_h, zsize, zpan)
        reached = distance <= self._goal_distance and abs(pan) <= self._goal_bearing_rad
        lost = not reached and (abs(pan) > self._neck_rad or abs(x) > self._half[0]
                                or abs(y) > self._half[1])
        self._st += 1
        truncated = not (reached or lost) and self._st >= self.max_steps
        self._sdone = reached or lost or truncated
        both = (size, seen)
        obs: FloatArray = self.obs[0]
        for i, c in enumerate(self._columns):
            obs[i] = both[c]
        self._store_scalar(reached or lost, truncated, reached)
        return obs.copy(), (1.0 if reached else -1.0 if lost else 0.0), reached or lost, truncated

    # -- outcome ---------------------------------------------------------------------------
    def success(self) -> BoolArray:
        """(B,) whether each episode has reached the ball."""
        return np.array(self.reached)

    def episode_fitness(self, returns: FloatArray, lengths: NDArray[np.int64],
                        success: BoolArray) -> FloatArray:
        """Trial fitness for the GA, (B,) each; faster success scores higher.

        reached in L steps: ``2 - L / max_steps`` in [1, 2); timed out: 0.5; lost after
        L steps: ``0.5 * L / max_steps`` in [0, 0.5) -- keeping the ball in view longer is
        better than losing it at once, and any success beats every failure.
        """
        fraction = np.asarray(lengths, dtype=np.float64) / self.max_steps
        lost = np.asarray(returns, dtype=np.float64) < 0
        failure = np.where(lost, 0.5 * fraction, 0.5)
        return np.where(np.asarray(success, dtype=bool), 2.0 - fraction, failure)

    def trace_state(self) -> dict[str, FloatArray]:
        """Robot pose (mm, deg in [-180, 180)) and ball position, each (B,)."""
        heading = np.remainder(self.heading * _DEG + 180.0, 360.0) - 180.0
        return {"robot_x": self.x.copy(), "robot_y": self.y.copy(), "robot_heading": heading,
                "ball_x": self.ball_x.copy(), "ball_y": self.ball_y.copy()}


def _check_fit(config: BallchaseSimConfig, commands: dict[str, float],
               observation_names: tuple[str, ...]) -> None:
    """The behaviour's inputs and commands must be ones the simulator knows."""
    problems = config.fit_problems(observation_names, tuple(commands))
    if len(set(observation_names)) != len(observation_names):
        problems.append(Problem(("inputs",), "an observation is read by two inputs"))
    if problems:
        raise SpecError(problems)
