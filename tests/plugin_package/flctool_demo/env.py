"""The line world: one input x in [0, 10]; the crisp output moves x by that much. An episode
succeeds at the goal, fails at x <= 1 and is truncated after max_steps."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from flctool.envs.base import BatchEnv, BoolArray, FloatArray, Step


class LineEnv(BatchEnv):
    observation_names = ("x",)
    action_bounds = (-1.0, 1.0)
    replayable = True  # an episode depends on its seed and the actions only

    def __init__(self, max_steps: int, goal: float, batch_size: int = 1) -> None:
        self.max_steps, self.goal = max_steps, goal
        self._start(np.zeros(batch_size, dtype=np.int64))

    @classmethod
    def from_behaviour(cls, behaviour: Any, batch_size: int = 1) -> LineEnv:
        config = behaviour.environment  # a LineConfig: validated when the file was loaded
        return cls(config.max_steps, config.goal, batch_size)

    def _start(self, seeds: NDArray[np.int64]) -> None:
        # episode b draws its start from seeds[b] alone
        self.x = np.array([2.0 + 6.0 * np.random.default_rng(int(s)).random() for s in seeds])
        self.t = np.zeros(len(seeds), dtype=np.int64)
        self.reached = np.zeros(len(seeds), dtype=bool)
        self.ended = np.zeros(len(seeds), dtype=bool)
        self.timed_out = np.zeros(len(seeds), dtype=bool)

    def reset(self, seeds: NDArray[np.int64]) -> tuple[FloatArray, dict[str, Any]]:
        self._start(seeds)
        return self.x[:, None].copy(), {}

    def step(self, actions: FloatArray) -> Step:
        live = ~(self.ended | self.timed_out)  # ended episodes stay as they are
        self.x = np.where(live, self.x + actions, self.x)
        self.t = self.t + live
        success = live & (self.x >= self.goal)
        failure = live & (self.x <= 1.0)
        self.reached |= success
        self.ended |= success | failure
        self.timed_out |= live & ~self.ended & (self.t >= self.max_steps)
        rewards = np.where(success, 1.0, np.where(failure, -1.0, 0.0))
        return Step(self.x[:, None].copy(), rewards, self.ended.copy(), self.timed_out.copy())

    def success(self) -> BoolArray:
        return self.reached.copy()
