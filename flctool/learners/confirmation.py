"""The figure a run reports: its controller confirmed on fresh episodes.

Model selection picks the best of many candidates on the same validation episodes, so the
winner's validated mean is optimistic (the best of 25 noisy means is high by luck). When a
run ends, :class:`Confirmation` runs the controller it returns on
``selection.confirmation`` episodes that took no part in training, selection or ``flctool
evaluate`` -- seeds in [2^31, 2^32) (the table of ranges is in :mod:`flctool.rollout`), fixed
for the run -- and that is the figure run.json, the summary and ``best.yaml`` lead with: the
mean fitness (its 95 % t interval clipped to the fitness's possible range), the success rate
(Wilson interval) and the mean return.

``stop.target`` is checked on a confirmation too: when the selected controller's validated
figure reaches the target, it is confirmed, and the run stops only if the confirmation
reaches it as well (:meth:`Confirmation.reaches`). Every confirmation is recorded and its
episodes count in the run's usage and budget.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np
from numpy.typing import NDArray

from flctool.behaviour.learning import TargetConfig
from flctool.envs.base import BatchEnv
from flctool.learners.metrics import FloatArray, GenerationResult, IntArray, Usage
from flctool.learners.run_callback import RunCallback
from flctool.learners.trial import SparseRules, run_trial
from flctool.rollout import (
    CONFIRMATION_SEED_LOW,
    T975,
    TRAIN_SEED_LOW,
    Estimate,
    clip_estimate,
    distinct_run_seeds,
    mean_interval,
    wilson_interval,
)

if TYPE_CHECKING:
    from flctool.learners.selection import Candidate, ModelSelection

#: Index of the confirmation seeds' child in the run's SeedSequence (after ga, env, explore
#: and validation).
_CONFIRMATION_STREAM = 4


def confirmation_seeds(run_seed: int, episodes: int) -> NDArray[np.int64]:
    """The run's ``episodes`` distinct confirmation seeds (E,), in [2^31, 2^32): the same for
    the whole run (a resumed run confirms on the same episodes), and a prefix of a longer
    draw."""
    return distinct_run_seeds(run_seed, _CONFIRMATION_STREAM, CONFIRMATION_SEED_LOW,
                              TRAIN_SEED_LOW, episodes)


@dataclass(frozen=True)
class Confirmed:
    """One controller's confirmation."""

    consequents: IntArray  # (M,)
    generation: int  # the generation the controller comes from
    individual: int
    after: int  # the generation after which it was confirmed
    fitness: Estimate  # mean fitness, interval clipped to the possible range
    success: Estimate  # success rate, Wilson interval
    mean_return: Estimate
    episode_fitness: tuple[float, ...] = ()  # per episode, in seed order (for comparisons)
    sets: FloatArray | None = None  # its set genome (G,) when the run learns the sets

    def is_of(self, consequents: Any, sets: Any = None) -> bool:
        """Whether this confirms the controller ``consequents (M,)`` with ``sets (G,)``."""
        if not np.array_equal(self.consequents, consequents):
            return False
        if self.sets is None or sets is None:
            return self.sets is None and sets is None
        return bool(np.array_equal(self.sets, sets))

    def value_in(self, unit: str) -> float:
        """The confirmed figure in ``unit``: ``fitness``, ``success`` or ``return``."""
        return {"fitness": self.fitness, "success": self.success,
                "return": self.mean_return}[unit].value

    def record(self) -> dict[str, Any]:
        """What run.json and the summary show."""
        return {"generation": self.generation, "individual": self.individual,
                "after": self.after, "episodes": self.fitness.n,
                "mean_fitness": self.fitness.to_dict(),
                "success_rate": self.success.to_dict(),
                "mean_return": self.mean_return.to_dict()}

    def to_dict(self) -> dict[str, Any]:
        return {**self.record(), "consequents": self.consequents.tolist(),
                "exact": [_exact(e) for e in (self.fitness, self.success, self.mean_return)],
                "episode_fitness": list(self.episode_fitness),
                **({} if self.sets is None else {"sets": self.sets.tolist()})}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Confirmed:
        fitness, success, mean_return = (Estimate(float(v), float(lo), float(hi), int(n))
                                         for v, lo, hi, n in data["exact"])
        return cls(np.array(data["consequents"], dtype=np.intp), int(data["generation"]),
                   int(data["individual"]), int(data["after"]), fitness, success,
                   mean_return, tuple(float(v) for v in data.get("episode_fitness", ())),
                   None if data.get("sets") is None else np.array(data["sets"],
                                                                  dtype=np.float64))


def fitness_interval(fitness: FloatArray, success: NDArray[np.bool_],
                     bounds: tuple[float, float]) -> Estimate:
    """The mean fitness (E,) of confirmation episodes, with a 95 % interval that allows for
    outcomes too rare to have shown: the mean is ``p mu_s + (1 - p) mu_f`` (success rate
    ``p``, mean fitness of successes and of the other episodes), so the interval combines the
    Wilson interval of ``p`` with t intervals of the two means -- the fitness range's bound
    standing in for a group no episode fell into. (A plain t interval over 50 episodes that
    all succeeded is narrow, and missed the held-out figure in 6 of 30 ballchase runs.)"""
    values = np.asarray(fitness, dtype=np.float64)
    n = int(values.shape[0])
    plain = clip_estimate(mean_interval(values), bounds)
    won = np.asarray(success, dtype=bool)
    k = int(won.sum())
    low_bound, high_bound = bounds
    if n < 2 or not (np.isfinite(low_bound) and np.isfinite(high_bound)):
        return plain
    rate = wilson_interval(k, n)

    def group(part: FloatArray) -> tuple[float, float]:
        if part.shape[0] < 2:  # no (or one) episode: anything the range allows
            return (low_bound if part.shape[0] == 0 else min(low_bound, float(part[0])),
                    high_bound if part.shape[0] == 0 else max(high_bound, float(part[0])))
        # the t quantile of the nearest tabulated degrees of freedom below (a little wider,
        # and no scipy to import for a group of, say, 47 episodes)
        dof = max(d for d in T975 if d <= part.shape[0] - 1)
        half = T975[dof] * float(part.std(ddof=1)) / math.sqrt(part.shape[0])
        mean = float(part.mean())
        return mean - half, mean + half

    s_low, s_high = group(values[won])
    f_low, f_high = group(values[~won])
    # the mean is monotone in p for fixed group means: take the worse end of each
    lows = [p * s_low + (1 - p) * f_low for p in (rate.low, rate.high)]
    highs = [p * s_high + (1 - p) * f_high for p in (rate.low, rate.high)]
    low = min(min(lows), plain.low)
    high = max(max(highs), plain.high)
    return Estimate(plain.value, max(low, low_bound), min(high, high_bound), n)


def _exact(estimate: Estimate) -> list[float | int]:
    # repr-exact through JSON (NaN is written as NaN and read back as nan)
    return [estimate.value, estimate.low, estimate.high, estimate.n]


class ConfirmedRun(Protocol):
    """What confirmation reads of the run it is part of (a
    :class:`~flctool.learners.base.Learner` is one)."""

    @property
    def generation(self) -> int: ...

    @property
    def env(self) -> BatchEnv: ...

    @property
    def selection(self) -> ModelSelection: ...

    def selected(self) -> tuple[int, int, IntArray, float, Candidate | None]: ...

    def selected_sets(self) -> FloatArray | None: ...

    def rules_for(self, genes: FloatArray | None) -> SparseRules: ...


class Confirmation(RunCallback[ConfirmedRun]):
    """Confirms the run's controller on fresh episodes when the run ends (see the module
    docstring); ``episodes`` 0 turns it off. ``episode_limit`` is ``stop.episodes``: a
    confirmation takes only what is left of it."""

    def __init__(self, episodes: int, run_seed: int, usage: Usage,
                 episode_limit: int | None = None) -> None:
        #: The episodes that follow a confirmation of n episodes (the comparison with the
        #: baselines): a confirmation leaves room for them within ``episode_limit``.
        self.after: Callable[[int], int] = lambda n: 0
        self.episodes = episodes
        self.usage = usage
        self.episode_limit = episode_limit
        self.seeds = confirmation_seeds(run_seed, episodes)
        self.confirmed: list[Confirmed] = []  # every confirmation, in order

    @property
    def final(self) -> Confirmed | None:
        """The confirmation of the controller the run returns (once the run has ended)."""
        return self.confirmed[-1] if self.confirmed else None

    def on_finish(self, learner: ConfirmedRun) -> None:
        generation, individual, consequents, _, _ = learner.selected()
        sets = learner.selected_sets()
        if self.final is None or not self.final.is_of(consequents, sets):
            self.confirm(learner, consequents, generation, individual, sets)

    def on_trials(self, learner: ConfirmedRun, result: GenerationResult) -> None:
        del learner, result  # confirmations run when the run ends, or when a target asks

    def reaches(self, learner: ConfirmedRun, target: TargetConfig) -> bool:
        """Whether the selected controller reaches ``target``: its validated figure first
        (no episodes), then a confirmation of it (once per controller)."""
        best = learner.selection.best
        if best is None or best.validation_in(target.unit) < target.value:
            return False
        final = self.final
        if final is None or not final.is_of(best.consequents, best.sets):
            final = self.confirm(learner, best.consequents, best.generation, best.individual,
                                 best.sets)
        return final is not None and final.value_in(target.unit) >= target.value

    def confirm(self, learner: ConfirmedRun, consequents: IntArray, generation: int,
                individual: int, sets: FloatArray | None = None) -> Confirmed | None:
        """Run ``consequents (M,)`` (with the set genome ``sets``, if the run learns the sets)
        on the confirmation episodes the budget leaves (None if it leaves none, or
        confirmation is off) and record the result."""
        count = self.episodes
        limit = self.episode_limit
        while limit is not None and count > 0 and (
                self.usage.episodes + count + self.after(count) > limit):
            count -= 1
        if count <= 0:
            return None
        env, genes, rules = learner.env, consequents.tolist(), learner.rules_for(sets)
        trials = [run_trial(env, rules, int(seed), genes) for seed in self.seeds[:count]]
        lengths = np.array([t.length for t in trials], dtype=np.int64)
        returns = np.array([t.ret for t in trials], dtype=np.float64)
        success = np.array([t.success for t in trials], dtype=np.bool_)
        fitness = env.episode_fitness(returns, lengths, success)
        self.usage.confirmation_episodes += count
        self.usage.confirmation_steps += int(lengths.sum())
        confirmed = Confirmed(np.array(consequents, dtype=np.intp), generation, individual,
                              learner.generation,
                              fitness_interval(fitness, success, env.fitness_range),
                              wilson_interval(int(success.sum()), count),
                              mean_interval(returns), tuple(fitness.tolist()),
                              None if sets is None else np.array(sets, dtype=np.float64))
        self.confirmed.append(confirmed)
        return confirmed

    def state_dict(self) -> dict[str, Any]:
        return {"confirmations": [c.to_dict() for c in self.confirmed]}

    def restore(self, confirmations: list[Confirmed]) -> None:
        self.confirmed = list(confirmations)

    def record(self) -> dict[str, Any]:
        """What run.json shows: the scheme, and every confirmation (the last is the run's)."""
        return {"episodes": self.episodes,
                "seeds": f"{self.episodes} fixed seeds in [2^31, 2^32) drawn from the run's "
                         "seed",
                "confirmed": [c.record() for c in self.confirmed]}
