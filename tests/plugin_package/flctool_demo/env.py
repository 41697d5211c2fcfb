"""The line world: one input x in [0, 10]; the crisp output moves x by that much."""

from typing import Any

import numpy as np

from flctool.envs.base import BatchEnv, Step


class LineEnv(BatchEnv):
    observation_names = ("x",)
    action_bounds = (-1.0, 1.0)

    def __init__(self, max_steps: int, goal: float, batch_size: int) -> None:
        self.max_steps, self.goal = max_steps, goal
        self.x = np.zeros(batch_size)

    @classmethod
    def from_behaviour(cls, behaviour: Any, batch_size: int = 1) -> "LineEnv":
        config = behaviour.environment
        return cls(config.max_steps, config.goal, batch_size)

    def reset(self, seeds: Any) -> Any:
        self.x = np.array([2.0 + 6.0 * np.random.default_rng(int(s)).random() for s in seeds])
        self.t = np.zeros(len(seeds), dtype=np.int64)
        self.reached = np.zeros(len(seeds), dtype=bool)
        self.ended = np.zeros(len(seeds), dtype=bool)
        self.timed_out = np.zeros(len(seeds), dtype=bool)
        return self.x[:, None].copy(), {}

    def step(self, actions: Any) -> Step:
        live = ~(self.ended | self.timed_out)
        self.x = np.where(live, self.x + actions, self.x)
        self.t = self.t + live
        success = live & (self.x >= self.goal)
        failure = live & (self.x <= 1.0)
        self.reached |= success
        self.ended |= success | failure
        self.timed_out |= live & ~self.ended & (self.t >= self.max_steps)
        rewards = np.where(success, 1.0, np.where(failure, -1.0, 0.0))
        return Step(self.x[:, None].copy(), rewards, self.ended.copy(), self.timed_out.copy())

    def success(self) -> Any:
        return self.reached.copy()
