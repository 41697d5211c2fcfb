"""A conformance checker for environment adapters, in the spirit of Gymnasium's ``check_env``.

Tests run it on every registered adapter; authors of a new adapter run it on theirs. It checks
the :class:`~flctool.envs.base.BatchEnv` contract: shapes and dtypes, that every episode ends
within ``max_steps``, that a finished episode stays unchanged, that the same seeds give the
same trajectories bit for bit, and that B episodes stepped together equal each stepped alone.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from flctool.envs.base import BatchEnv, FloatArray
from flctool.errors import EnvError

Trajectory = tuple[FloatArray, FloatArray, NDArray[np.bool_], NDArray[np.bool_]]


def _fail(message: str) -> EnvError:
    return EnvError(f"adapter check failed: {message}",
                    hint="see the BatchEnv contract in flctool/envs/base.py")


def _run(env: BatchEnv, seeds: NDArray[np.int64], actions: FloatArray) -> Trajectory:
    """Step every episode to its end; returns observations (T+1, B, N), rewards (T, B),
    terminated and truncated (T, B)."""
    batch = seeds.shape[0]
    obs, info = env.reset(seeds)
    if not isinstance(info, dict):
        raise _fail(f"reset must return a dict as info, got {type(info).__name__}")
    n = len(env.observation_names)
    if obs.shape != (batch, n) or obs.dtype != np.float64:
        raise _fail(f"reset returned observations of shape {obs.shape} and dtype {obs.dtype}; "
                    f"expected ({batch}, {n}) float64")
    observations, rewards, terminated, truncated = [obs], [], [], []
    done = np.zeros(batch, dtype=bool)
    for t in range(env.max_steps + 1):
        step = env.step(actions[t % actions.shape[0]])
        for name, array, dtype in (("rewards", step.rewards, np.float64),
                                   ("terminated", step.terminated, np.bool_),
                                   ("truncated", step.truncated, np.bool_)):
            if array.shape != (batch,) or array.dtype != dtype:
                raise _fail(f"step returned {name} of shape {array.shape} and dtype "
                            f"{array.dtype}; expected ({batch},) {np.dtype(dtype)}")
        if step.observations.shape != (batch, n):
            raise _fail(f"step returned observations of shape {step.observations.shape}")
        if not (np.isfinite(step.observations).all() and np.isfinite(step.rewards).all()):
            raise _fail("step returned a non-finite observation or reward")
        if done.any():
            if not np.array_equal(step.observations[done], observations[-1][done]):
                raise _fail("stepping a finished episode changed its observation")
            if np.any(step.rewards[done] != 0):
                raise _fail("stepping a finished episode gave a non-zero reward")
            if not (step.terminated | step.truncated)[done].all():
                raise _fail("a finished episode lost its terminated/truncated flag")
        observations.append(step.observations)
        rewards.append(step.rewards)
        terminated.append(step.terminated)
        truncated.append(step.truncated)
        done = step.terminated | step.truncated
        if done.all():
            break
    else:
        raise _fail(f"episodes did not end within max_steps = {env.max_steps} steps")
    success = env.success()
    if success.shape != (batch,) or success.dtype != np.bool_:
        raise _fail(f"success() returned shape {success.shape} and dtype {success.dtype}")
    if (success & ~np.array(terminated).any(axis=0)).any():
        raise _fail("an episode counts as a success but never terminated")
    lengths = (~np.vstack([np.zeros((1, batch), dtype=bool),
                           np.array(terminated) | np.array(truncated)])[:-1]).sum(axis=0)
    fitness = env.episode_fitness(np.array(rewards).sum(axis=0), lengths, success)
    if fitness.shape != (batch,) or not np.isfinite(fitness).all():
        raise _fail(f"episode_fitness returned shape {fitness.shape} or non-finite values")
    return np.array(observations), np.array(rewards), np.array(terminated), np.array(truncated)


def _same(a: Trajectory, b: Trajectory) -> bool:
    return all(x.shape == y.shape and np.array_equal(x, y) for x, y in zip(a, b, strict=True))


def check_env(env: BatchEnv | Callable[[], BatchEnv], batch_size: int = 4,
              seed: int = 0) -> None:
    """Check an adapter (or a zero-argument factory of fresh adapters) against the protocol.

    Raises :class:`EnvError` naming the first broken rule; returns None when all hold. Every
    adapter a factory made is closed when the check ends, however it ends; one given is
    left open, for its opener to close.
    """
    if isinstance(env, BatchEnv):
        instance = env

        def make() -> BatchEnv:
            return instance  # one adapter, reset for every run: reset must start afresh
    else:
        make = env
    fresh = not isinstance(env, BatchEnv)  # a factory: each call makes a new adapter
    opened: list[BatchEnv] = []

    def make_one() -> BatchEnv:
        made = make()
        opened.append(made)
        return made

    def release(used: BatchEnv) -> None:
        # A robot serves one client at a time: a fresh adapter is closed as soon as its run
        # is over, so that the next one is served.
        if fresh and used in opened:
            opened.remove(used)
            used.close()

    try:
        _check(make_one, release, batch_size, seed)
    finally:
        if fresh:
            for left in {id(e): e for e in opened}.values():
                if isinstance(left, BatchEnv):
                    left.close()


def _check(make: Callable[[], BatchEnv], release: Callable[[BatchEnv], None],
           batch_size: int, seed: int) -> None:
    first = make()
    if not isinstance(first, BatchEnv):
        raise _fail(f"{type(first).__name__} is not a BatchEnv")
    names = first.observation_names
    if not (isinstance(names, tuple) and all(isinstance(n, str) for n in names) and names):
        raise _fail("observation_names must be a non-empty tuple of str")
    if not (isinstance(first.max_steps, int) and first.max_steps >= 1):
        raise _fail("max_steps must be an int >= 1")
    low, high = getattr(first, "action_bounds", (-1.0, 1.0))
    if not low <= high:
        raise _fail(f"action_bounds ({low}, {high}) must be (low, high) with low <= high")
    rng = np.random.default_rng(seed)
    seeds = rng.integers(0, 2**31, size=batch_size, dtype=np.int64)
    actions = rng.uniform(low, high, size=(first.max_steps + 1, batch_size))
    together = _run(first, seeds, actions)
    release(first)
    again = make()
    same = _same(together, _run(again, seeds, actions))
    release(again)
    if not same:
        raise _fail("the same seeds and actions gave different trajectories")
    alone = make()
    for b in range(batch_size):
        one = _run(alone, seeds[b : b + 1], actions[:, b : b + 1])
        steps = one[1].shape[0]
        parts = (together[0][: steps + 1, b : b + 1], together[1][:steps, b : b + 1],
                 together[2][:steps, b : b + 1], together[3][:steps, b : b + 1])
        if not _same(one, parts):
            raise _fail(f"episode {b} stepped alone differs from the same episode stepped in a "
                        f"batch of {batch_size}: episode b must use only seeds[b]'s randomness")
    release(alone)
