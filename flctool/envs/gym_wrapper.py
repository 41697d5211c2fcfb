"""The ballchase simulator as a ``gymnasium.Env``, for other reinforcement-learning libraries.

    env = BallchaseGymEnv(flctool.load_behaviour("behaviours/ballchase.yaml"))
    obs, info = env.reset(seed=0)         # obs: float64 (N,), the behaviour's inputs
    obs, reward, terminated, truncated, info = env.step(np.array([0.5], dtype=np.float32))

The action is the crisp output ``a`` (a Box of one component spanning the commands'
singletons). It passes ``gymnasium.utils.env_checker.check_env``. Needs the optional
gymnasium package (``pip install 'flctool[gym]'``).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from flctool.envs.ballchase import BallchaseSim
from flctool.envs.base import FloatArray
from flctool.errors import MissingDependencyError
from flctool.spec.models import Behaviour

try:
    import gymnasium as gym
except ImportError:
    raise MissingDependencyError("gymnasium", "gym", "the Gymnasium wrapper") from None


class BallchaseGymEnv(gym.Env[FloatArray, NDArray[np.float32]]):
    """One ballchase episode at a time behind Gymnasium's ``Env`` API."""

    metadata: dict[str, Any] = {"render_modes": []}  # noqa: RUF012 (Gymnasium's convention)

    def __init__(self, behaviour: Behaviour) -> None:
        super().__init__()
        self.sim = BallchaseSim.from_behaviour(behaviour)
        neck = self.sim.config.robot.neck_range
        bounds = {"ball_size": (0.0, 1.0), "pan": (-neck, neck)}
        low = np.array([bounds[n][0] for n in self.sim.observation_names])
        high = np.array([bounds[n][1] for n in self.sim.observation_names])
        self.observation_space = gym.spaces.Box(low, high, dtype=np.float64)
        a_low, a_high = self.sim.action_bounds
        self.action_space = gym.spaces.Box(a_low, a_high, shape=(1,), dtype=np.float32)

    def reset(self, *, seed: int | None = None,
              options: dict[str, Any] | None = None) -> tuple[FloatArray, dict[str, Any]]:
        super().reset(seed=seed)
        # An explicit seed is the simulator's episode seed, so seed s here is episode s there.
        episode = seed if seed is not None else int(self.np_random.integers(2**62))
        return self.sim.reset_one(episode), {}

    def step(self, action: Any) -> tuple[FloatArray, float, bool, bool, dict[str, Any]]:
        a = float(np.asarray(action, dtype=np.float64).reshape(-1)[0])
        obs, reward, terminated, truncated = self.sim.step_one(a)
        return obs, reward, terminated, truncated, {}
