"""The adapter checker: a conforming adapter passes, and each way of breaking the BatchEnv
contract is caught with a message naming it."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from numpy.typing import NDArray

from flctool.envs import BatchEnv, check_env
from flctool.envs.base import BoolArray, FloatArray, Step
from flctool.errors import EnvError


class Drift(BatchEnv):
    """A tiny conforming adapter: x starts where the episode's seed puts it and moves by the
    action; |x| >= 3 ends the episode (x >= 3 a success), ``max_steps`` truncates it."""

    observation_names = ("x",)
    max_steps = 12
    action_bounds = (-1.0, 1.0)

    def __init__(self) -> None:
        self.closed = 0
        self.x = np.zeros(0)
        self.t = np.zeros(0, dtype=np.int64)
        self.terminated = np.zeros(0, dtype=bool)
        self.truncated = np.zeros(0, dtype=bool)

    def start(self, seeds: NDArray[np.int64]) -> FloatArray:
        return np.array([np.random.default_rng(int(s)).uniform(-2, 2) for s in seeds])

    def reset(self, seeds: NDArray[np.int64]) -> tuple[FloatArray, dict[str, Any]]:
        self.x = self.start(seeds)
        self.t = np.zeros(len(seeds), dtype=np.int64)
        self.terminated = np.zeros(len(seeds), dtype=bool)
        self.truncated = np.zeros(len(seeds), dtype=bool)
        return self.x[:, None].copy(), {}

    def live(self) -> BoolArray:
        return ~(self.terminated | self.truncated)

    def step(self, actions: FloatArray) -> Step:
        live = self.live()
        self.x = np.where(live, self.x + actions, self.x)
        self.t += live
        ended = live & (np.abs(self.x) >= 3)
        self.terminated |= ended
        self.truncated |= live & ~ended & (self.t >= self.max_steps)
        rewards = np.where(ended, np.sign(self.x), 0.0)
        return Step(self.x[:, None].copy(), rewards, self.terminated.copy(),
                    self.truncated.copy())

    def success(self) -> BoolArray:
        return self.terminated & (self.x >= 3)

    def close(self) -> None:
        self.closed += 1


class WrongShape(Drift):
    def reset(self, seeds: NDArray[np.int64]) -> tuple[FloatArray, dict[str, Any]]:
        observations, info = super().reset(seeds)
        return np.hstack([observations, observations]), info


class UnseededReset(Drift):
    """Draws its starts from its own generator instead of the seeds."""

    rng = np.random.default_rng(0)

    def start(self, seeds: NDArray[np.int64]) -> FloatArray:
        return self.rng.uniform(-2, 2, size=len(seeds))


class BatchCoupled(Drift):
    """Episode b's start depends on the batch (one generator for all), not only seeds[b]."""

    def start(self, seeds: NDArray[np.int64]) -> FloatArray:
        return np.random.default_rng(int(seeds[0])).uniform(-2, 2, size=len(seeds))


class NeverTruncates(Drift):
    max_steps = 3

    def step(self, actions: FloatArray) -> Step:
        out = super().step(np.zeros_like(actions))
        self.truncated[:] = False
        return Step(out.observations, out.rewards, self.terminated.copy(),
                    self.truncated.copy())


class FinishedKeepsMoving(Drift):
    def step(self, actions: FloatArray) -> Step:
        out = super().step(actions)
        self.x = self.x + 0.1 * ~self.live()
        return Step(self.x[:, None].copy(), out.rewards, out.terminated, out.truncated)


class RewardsFinished(Drift):
    def step(self, actions: FloatArray) -> Step:
        out = super().step(actions)
        return Step(out.observations, out.rewards + ~self.live(), out.terminated,
                    out.truncated)


class NaNObservation(Drift):
    def step(self, actions: FloatArray) -> Step:
        out = super().step(actions)
        return Step(np.full_like(out.observations, np.nan), out.rewards, out.terminated,
                    out.truncated)


class IntegerRewards(Drift):
    def step(self, actions: FloatArray) -> Step:
        out = super().step(actions)
        return Step(out.observations, out.rewards.astype(np.int64), out.terminated,
                    out.truncated)  # type: ignore[arg-type]


class SuccessWithoutEnd(Drift):
    def success(self) -> BoolArray:
        return np.ones_like(self.terminated)


def test_a_conforming_adapter_passes_and_is_closed() -> None:
    made: list[Drift] = []

    def make() -> Drift:
        made.append(Drift())
        return made[-1]

    check_env(make, batch_size=5, seed=3)
    assert len(made) == 3 and all(env.closed == 1 for env in made)
    single = Drift()
    check_env(single)  # one instance, reset for every run
    assert single.closed == 0  # given, not opened, by the check: its opener closes it


@pytest.mark.parametrize(("adapter", "message"), [
    (WrongShape, r"reset returned observations of shape \(4, 2\).*expected \(4, 1\)"),
    (UnseededReset, "the same seeds and actions gave different trajectories"),
    (BatchCoupled, "episode 1 stepped alone differs from the same episode stepped in a batch"),
    (NeverTruncates, "episodes did not end within max_steps = 3 steps"),
    (FinishedKeepsMoving, "stepping a finished episode changed its observation"),
    (RewardsFinished, "stepping a finished episode gave a non-zero reward"),
    (NaNObservation, "step returned a non-finite observation or reward"),
    (IntegerRewards, r"step returned rewards of shape \(4,\) and dtype int64"),
    (SuccessWithoutEnd, "an episode counts as a success but never terminated"),
])
def test_a_broken_adapter_is_caught_and_still_closed(adapter: type[Drift],
                                                     message: str) -> None:
    made: list[Drift] = []

    def make() -> Drift:
        made.append(adapter())
        return made[-1]

    with pytest.raises(EnvError, match=f"adapter check failed: {message}"):
        check_env(make)
    assert made and all(env.closed == 1 for env in made)


def test_what_is_not_an_adapter_is_named() -> None:
    with pytest.raises(EnvError, match="list is not a BatchEnv"):
        check_env(lambda: [])  # type: ignore[arg-type, return-value]

    class Unnamed(Drift):
        observation_names = ()

    with pytest.raises(EnvError, match="observation_names must be a non-empty tuple"):
        check_env(Unnamed)

    class Backwards(Drift):
        action_bounds = (1.0, -1.0)

    with pytest.raises(EnvError, match=r"action_bounds \(1.0, -1.0\)"):
        check_env(Backwards)
