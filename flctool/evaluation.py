"""Evaluating a deployable controller: what ``flctool evaluate`` reports, for Python users and
experiments too.

    evaluation = evaluate_behaviour(load_behaviour("runs/first/best.yaml"), seed=0,
                                    episodes=1000)
    evaluation.rows()        # the statistics as the command's table shows them
    evaluation.to_dict()     # and as its --json prints them

Episodes run in lock-step in chunks of at most :data:`CHUNK_EPISODES`, so memory follows the
chunk, not the number of episodes; every episode depends on its own seed only, so the
chunking does not change a result (tests check it).
"""

from __future__ import annotations

import math
import re
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from flctool.rollout import Estimate, EvaluationResult, evaluate, evaluation_seeds

if TYPE_CHECKING:
    from numpy.typing import NDArray

    from flctool.behaviour import Behaviour
    from flctool.compile import Controller
    from flctool.envs import BatchEnv

#: Most episodes stepped together; the peak memory of an evaluation follows this, not the
#: number of episodes.
CHUNK_EPISODES = 1024
#: Episodes of the first chunk, and the seconds later chunks are sized to take (so that a
#: slow environment still shows progress).
FIRST_CHUNK, CHUNK_SECONDS = 64, 2.0
#: Most episodes one list of seeds may name.
MAX_LISTED_SEEDS = 10_000_000
#: Episodes and the seed that draws their seeds when neither is given.
DEFAULT_EPISODES, DEFAULT_SEED = 1000, 0

#: Called after each chunk with the episodes done so far and how many of them succeeded.
ChunkDone = Callable[[int, int], None]

_SEED_ITEM = re.compile(r"^\s*(\d+)\s*(?:-\s*(\d+)\s*)?$")


def parse_seeds(text: str) -> list[int]:
    """``"1,2,5-9"`` -> ``[1, 2, 5, 6, 7, 8, 9]``: comma-separated seeds and inclusive
    ranges, in the order given; a seed named twice is an error (it would count twice).
    Raises ValueError saying what is wrong."""
    seeds: list[int] = []
    for item in text.split(","):
        match = _SEED_ITEM.match(item)
        if match is None:
            raise ValueError(f"'{item.strip()}' is not a seed or a range like 5-9 "
                             "(seeds are integers >= 0)")
        low = int(match.group(1))
        high = int(match.group(2)) if match.group(2) is not None else low
        if high < low:
            raise ValueError(f"the range {low}-{high} is empty; write it low-high")
        if len(seeds) + high - low + 1 > MAX_LISTED_SEEDS:
            raise ValueError(f"more than {MAX_LISTED_SEEDS:,} seeds")
        seeds.extend(range(low, high + 1))
    if max(seeds) >= 2**63:
        raise ValueError("seeds must be below 2^63")
    if len(set(seeds)) != len(seeds):
        twice = sorted({s for s in seeds if seeds.count(s) > 1})[:5] if len(seeds) < 10_000 \
            else []
        raise ValueError("a seed is named twice" +
                         (f" ({', '.join(map(str, twice))})" if twice else ""))
    return seeds


def defines_success(behaviour: Behaviour) -> bool:
    """Whether the behaviour's environment has a notion of success (``success: never``
    says it has none)."""
    return getattr(behaviour.environment, "success", "terminated") != "never"


def evaluate_in_chunks(controller: Controller, env: BatchEnv, seeds: NDArray[np.int64], *,
                       chunk: int = CHUNK_EPISODES,
                       on_chunk: ChunkDone | None = None) -> EvaluationResult:
    """:func:`flctool.rollout.evaluate` of ``seeds (E,)``, at most ``chunk`` episodes at a
    time: the same outcomes, with memory that does not grow with E.

    The first chunk is small; later ones are sized to take about :data:`CHUNK_SECONDS` each
    (up to ``chunk``), so a slow environment still reports progress (``on_chunk``) every
    few seconds while a fast one runs in large lock-step batches.
    """
    parts: list[EvaluationResult] = []
    total = int(seeds.shape[0])
    size = min(FIRST_CHUNK, chunk)
    done = successes = 0
    while done < total:
        started = time.monotonic()
        parts.append(evaluate(controller, env, seeds[done:done + size]))
        seconds = max(time.monotonic() - started, 1e-6)
        done += parts[-1].episodes
        successes += int(parts[-1].success.sum())
        size = max(1, min(chunk, int(parts[-1].episodes * CHUNK_SECONDS / seconds)))
        if on_chunk is not None:
            on_chunk(done, successes)
    if len(parts) == 1:
        return parts[0]
    return EvaluationResult(*(np.concatenate([getattr(p, name) for p in parts])
                              for name in ("seeds", "returns", "lengths", "success",
                                           "fitness")))


@dataclass(frozen=True)
class Evaluation:
    """A behaviour's evaluation: its per-episode outcomes and how they are summarised."""

    behaviour: Behaviour
    result: EvaluationResult
    #: The seed that drew the episodes' seeds; None when they were listed.
    seed: int | None

    @property
    def success(self) -> bool:
        """Whether success statistics apply (the environment defines success)."""
        return defines_success(self.behaviour)

    def rows(self) -> list[tuple[str, str, str, str]]:
        """The summary as a table shows it: (statistic, value, 95 % CI, n), numbers as
        text, ``-`` where there is none (no samples, or no interval from one)."""
        result = self.result
        rows = []
        if self.success:
            rows += [_row("success rate (Wilson)", result.success_rate, percent=True),
                     _row("steps to success", result.steps_to_success)]
        rows += [_row("mean fitness", result.mean_fitness),
                 _row("mean return", result.mean_return)]
        return rows

    def summary(self) -> dict[str, Any]:
        """Each statistic as ``{value, low, high, n}`` (None for NaN), without the success
        statistics when the environment defines no success."""
        summary = self.result.summary()
        if not self.success:
            del summary["success_rate"], summary["steps_to_success"]
        return summary

    def to_dict(self, file: str | None = None) -> dict[str, Any]:
        """What ``flctool evaluate --json`` prints: the behaviour, the file it was read from,
        the drawing seed, the :meth:`summary` and every episode's seed."""
        return {"behaviour": self.behaviour.name, "file": file, "seed": self.seed,
                **self.summary(), "seeds": self.result.seeds.tolist()}


def _row(label: str, estimate: Estimate, percent: bool = False) -> tuple[str, str, str, str]:
    def fmt(x: float) -> str:
        if math.isnan(x):
            return "-"
        return f"{100 * x:.1f} %" if percent else f"{x:.3f}"
    interval = "-" if math.isnan(estimate.low) else \
        f"[{fmt(estimate.low)}, {fmt(estimate.high)}]"
    return label, fmt(estimate.value), interval, str(estimate.n)


def episode_seeds(seeds: list[int] | None = None, seed: int | None = None,
                  episodes: int | None = None) -> NDArray[np.int64]:
    """The episodes' seeds: ``seeds`` as listed, or ``episodes`` (default 1000) distinct
    seeds drawn from ``seed`` (default 0) by :func:`flctool.rollout.evaluation_seeds`."""
    if seeds is not None:
        if seed is not None or episodes is not None:
            raise ValueError("give either seeds, or seed and episodes")
        return np.array(seeds, dtype=np.int64)
    return evaluation_seeds(DEFAULT_SEED if seed is None else seed,
                            DEFAULT_EPISODES if episodes is None else episodes)


def batch_size(episodes: int) -> int:
    """The batch an environment for an evaluation of ``episodes`` is built for."""
    return min(episodes, CHUNK_EPISODES)


def evaluate_behaviour(behaviour: Behaviour, seeds: list[int] | None = None, *,
                       seed: int | None = None, episodes: int | None = None,
                       controller: Controller | None = None, env: BatchEnv | None = None,
                       on_chunk: ChunkDone | None = None) -> Evaluation:
    """Run a deployable ``behaviour`` in its environment, one episode per seed (see
    :func:`episode_seeds`), in chunks (:func:`evaluate_in_chunks`). ``controller`` is the
    behaviour compiled and ``env`` its environment (built for :func:`batch_size`), if the
    caller has them already: a given environment is left open (its opener closes it), one
    built here is closed at the end."""
    from flctool.compile import compile_behaviour
    from flctool.envs import make_env

    drawn = episode_seeds(seeds, seed, episodes)
    if controller is None:
        controller = compile_behaviour(behaviour)
    if env is None:
        with make_env(behaviour, batch_size(len(drawn))) as built:
            result = evaluate_in_chunks(controller, built, drawn, on_chunk=on_chunk)
    else:
        result = evaluate_in_chunks(controller, env, drawn, on_chunk=on_chunk)
    return Evaluation(behaviour, result,
                      None if seeds is not None else (DEFAULT_SEED if seed is None else seed))
