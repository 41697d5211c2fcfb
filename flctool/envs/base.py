"""The environment adapter protocol: Gymnasium-shaped, batched first.

A :class:`BatchEnv` runs B independent episodes in lock-step as numpy arrays -- a population,
or a thousand evaluation episodes, in one call. :class:`SingleEnv` is the one-episode form with
Gymnasium's signatures (``reset(seed) -> obs, info``; ``step(action) -> obs, reward,
terminated, truncated, info``).

The action is the controller's crisp output ``a`` of eq. 3, one float per episode: the adapter
decides how ``a`` drives its world (blend the commands' motions, take the nearest command,
map to a Gymnasium action). Observations are ordered like the behaviour's inputs.

Episode ``b`` draws all its randomness from ``seeds[b]`` alone, so stepping B episodes
together gives exactly what stepping each on its own gives. Once an episode has ended, further
steps leave it unchanged (reward 0, flags still set): callers step until all are done.

Whoever opens an environment closes it (on a robot link, closing sends ``stop``): a function
given one uses it and leaves it open; one that builds its own closes it. An environment is a
context manager, as Gymnasium's are::

    with make_env(behaviour, batch_size=100) as env:
        result = evaluate(controller, env, seeds)
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray
from typing_extensions import Self

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


@dataclass
class Step:
    """What one batched step returns; each array has one entry per episode."""

    observations: FloatArray  # (B, N)
    rewards: FloatArray  # (B,)
    terminated: BoolArray  # (B,) ended by the task: reached the goal, or failed
    truncated: BoolArray  # (B,) ended by the time limit
    info: dict[str, Any] = field(default_factory=dict)


class BatchEnv(ABC):
    """B episodes at once. Subclasses implement :meth:`reset` and :meth:`step`."""

    #: Names of the observation components, in the order of the behaviour's inputs.
    observation_names: tuple[str, ...]
    #: Steps after which an episode is truncated.
    max_steps: int
    #: The most episodes the adapter runs at once (a real robot: 1); None for any number.
    #: Callers with more seeds run them in chunks of this size.
    max_batch: int | None = None
    #: [low, high] of the crisp output ``a`` the adapter expects (the commands' singletons).
    action_bounds: tuple[float, float]
    #: Whether the controller acts by vote (the action mode ``vote``): each command's firing
    #: rules sum their activations and the strongest command's singleton is ``a``, in place
    #: of eq. 3's weighted average (see docs/learning.md).
    votes: bool = False
    #: Whether an episode is a function of its seed and the actions alone, replayed exactly
    #: (a simulator; never a robot): learning then reuses a validation episode's outcome for
    #: a controller that would act the same in it, instead of running it again.
    replayable: bool = False
    #: The lowest and highest fitness :meth:`episode_fitness` can give (unbounded by
    #: default): confidence intervals of a mean fitness are clipped to it, and a
    #: ``stop.target`` outside it is refused.
    fitness_range: tuple[float, float] = (-math.inf, math.inf)

    @abstractmethod
    def reset(self, seeds: NDArray[np.int64]) -> tuple[FloatArray, dict[str, Any]]:
        """Start one episode per seed; returns observations (B, N) and info."""

    @abstractmethod
    def step(self, actions: FloatArray) -> Step:
        """Apply the crisp outputs ``actions (B,)`` to every episode."""

    @abstractmethod
    def success(self) -> BoolArray:
        """(B,) whether each current episode has ended in success so far."""

    def episode_fitness(self, returns: FloatArray, lengths: NDArray[np.int64],
                        success: BoolArray) -> FloatArray:
        """The GA's fitness of finished trials; by default the undiscounted return."""
        del lengths, success
        return np.asarray(returns, dtype=np.float64)

    def reset_one(self, seed: int) -> FloatArray:
        """Start a single episode (B = 1); returns its observation (N,).

        The fast path for learners that run trials one after another; adapters may override
        it (and :meth:`step_one`) to skip building arrays, with identical results.
        """
        obs, _ = self.reset(np.array([seed], dtype=np.int64))
        first: FloatArray = obs[0]
        return first

    def step_one(self, action: float) -> tuple[FloatArray, float, bool, bool]:
        """Step the episode started by :meth:`reset_one`: (obs (N,), reward, terminated,
        truncated)."""
        out = self.step(np.array([action], dtype=np.float64))
        return (out.observations[0], float(out.rewards[0]), bool(out.terminated[0]),
                bool(out.truncated[0]))

    def trace_state(self) -> dict[str, FloatArray]:
        """Extra per-episode state for trajectory traces: column name -> (B,); default none."""
        return {}

    def close(self) -> None:  # noqa: B027 - an optional hook, not every adapter holds resources
        """Release resources (sockets, subprocesses); the default holds none. Closing twice
        is harmless."""

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()


class SingleEnv:
    """One episode with Gymnasium's signatures, over any :class:`BatchEnv` of size 1."""

    def __init__(self, batch: BatchEnv) -> None:
        self.batch = batch
        self.observation_names = batch.observation_names

    def reset(self, seed: int) -> tuple[FloatArray, dict[str, Any]]:
        obs, info = self.batch.reset(np.array([seed], dtype=np.int64))
        return obs[0], info

    def step(self, action: float) -> tuple[FloatArray, float, bool, bool, dict[str, Any]]:
        out = self.batch.step(np.array([action], dtype=np.float64))
        return (out.observations[0], float(out.rewards[0]), bool(out.terminated[0]),
                bool(out.truncated[0]), out.info)
