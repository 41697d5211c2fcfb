"""Model selection and budgets: which controller a run returns, and when a run stops.

One training trial is a noisy measure of a controller, so the individual with the best trial
is often a lucky one. A run therefore keeps **candidates** in a :class:`HallOfFame` -- the
distinct controllers with the best mean training fitness over all the trials they had (an
elite is tried again every generation, so its mean firms up), or, for ``fuzzy_q``, the greedy
controllers of the latest generations -- and runs them on **validation episodes**. The
controller returned (``best.yaml``) is the candidate with the best validated mean fitness.

When candidates are validated:

- after every generation, the hall's leader, if it has not been validated yet (so the score
  shown while training is a validated one, and ``stop.target`` can be checked);
- after the last generation, every candidate still unvalidated: the hall's top
  ``selection.candidates`` and the final population's elites.

Seeds: training episodes use seeds in [2^32, 2^62) (drawn from the run's ``env`` stream),
``flctool evaluate`` uses seeds below 2^31 (drawn from its ``--seed``), and validation uses
the fixed seeds :func:`validation_seeds` draws in [2^62, 2^63) from the run's seed: the three
sets never meet. Every candidate meets the same validation episodes (common random numbers),
so their differences come from the controllers.

Episodes already known: with a simulator (``env.replayable``: an episode is a function of
its seed and the actions) a validation episode is not run again for a candidate that gives
the same command as an earlier one to every rule that fired where that one acted: it would
act the same at every step, so the episode is the same, bit for bit, and its outcome is
reused: on ballchase, a sixth (fuzzy_q) to a third (pitt, hybrid) of validation episodes.
They still count as spent (budgets and ``usage`` are what running them would give), so
results are the same with a robot, a resumed run or no reuse at all.

Budgets (``stop``) count training and validation episodes alike and are checked between
generations, so that a run stopped by ``episodes`` or ``steps`` is as reproducible as one that
runs all its generations; only ``seconds`` depends on the machine.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from flctool.envs.base import BatchEnv
from flctool.learners.trial import SparseRules, Trial, run_trial
from flctool.rollout import Estimate, mean_interval
from flctool.spec.learning import SelectionConfig, StopConfig

if TYPE_CHECKING:
    from flctool.learners.checkpoint import SelectionState

IntArray = NDArray[np.intp]
FloatArray = NDArray[np.float64]

VALIDATION_SEED_LOW = 2**62
VALIDATION_SEED_HIGH = 2**63 - 1
#: Index of the validation seeds' child in the run's SeedSequence (after ga, env, explore).
_VALIDATION_STREAM = 3


def validation_seeds(run_seed: int, episodes: int) -> NDArray[np.int64]:
    """The run's ``episodes`` distinct validation seeds (E,), in [2^62, 2^63).

    Drawn from a child of the run's seed that the training streams do not use, and the same
    for the whole run, so no state needs saving: a resumed run validates on the same episodes.
    """
    sequence = np.random.SeedSequence(run_seed, spawn_key=(_VALIDATION_STREAM,))
    rng = np.random.default_rng(sequence)
    seeds: list[int] = []
    seen: set[int] = set()
    while len(seeds) < episodes:
        for value in rng.integers(VALIDATION_SEED_LOW, VALIDATION_SEED_HIGH,
                                  size=episodes - len(seeds), dtype=np.int64).tolist():
            if value not in seen:
                seen.add(value)
                seeds.append(value)
    return np.array(seeds, dtype=np.int64)


@dataclass
class Candidate:
    """One distinct controller of a run, with what training and validation said of it."""

    consequents: IntArray  # (M,)
    generation: int  # when it was last in the population
    individual: int  # its index in that generation
    fitness_sum: float = 0.0  # over its training trials
    trials: int = 0
    validation: Estimate | None = None  # mean fitness over the validation episodes
    validated_at: int = -1  # generation after which it was validated

    @property
    def fitness(self) -> float:
        """Mean training fitness over the generations it was evaluated in."""
        return self.fitness_sum / self.trials if self.trials else math.nan

    def key(self) -> bytes:
        return _key(self.consequents)

    def validation_value(self) -> float:
        """The validated mean fitness; -inf before validation."""
        return -math.inf if self.validation is None else self.validation.value

    def to_dict(self) -> dict[str, Any]:
        return {"consequents": self.consequents.tolist(), "generation": self.generation,
                "individual": self.individual, "fitness_sum": self.fitness_sum,
                "trials": self.trials, "validated_at": self.validated_at,
                "validation": None if self.validation is None else _estimate_dict(
                    self.validation)}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Candidate:
        validation = data["validation"]
        return cls(np.array(data["consequents"], dtype=np.intp), int(data["generation"]),
                   int(data["individual"]), float(data["fitness_sum"]), int(data["trials"]),
                   None if validation is None else _estimate(validation),
                   int(data["validated_at"]))

    def record(self) -> dict[str, Any]:
        """What run.json shows of a candidate: where it came from, training and validation."""
        return {"generation": self.generation, "individual": self.individual,
                "training_fitness": self.fitness, "training_trials": self.trials,
                "validation": None if self.validation is None
                else self.validation.to_dict()}


def _key(consequents: IntArray) -> bytes:
    return np.asarray(consequents, dtype=np.int64).tobytes()


def _estimate_dict(estimate: Estimate) -> list[float | int]:
    # repr-exact floats through JSON (NaN is written as NaN by json, read back as nan)
    return [estimate.value, estimate.low, estimate.high, estimate.n]


def _estimate(data: list[Any]) -> Estimate:
    value, low, high, n = data
    return Estimate(float(value), float(low), float(high), int(n))


@dataclass(frozen=True)
class _KnownEpisode:
    """A validation episode already run: the rules that fired in the states the controller
    acted on (increasing), the commands it gave them, and the outcome."""

    rules: tuple[int, ...]
    commands: tuple[int, ...]
    trial: Trial


@dataclass
class Usage:
    """Episodes and environment steps spent, for training and for validation."""

    training_episodes: int = 0
    training_steps: int = 0
    selection_episodes: int = 0
    selection_steps: int = 0

    @property
    def episodes(self) -> int:
        return self.training_episodes + self.selection_episodes

    @property
    def steps(self) -> int:
        return self.training_steps + self.selection_steps

    def to_dict(self) -> dict[str, int]:
        return {"training_episodes": self.training_episodes,
                "training_steps": self.training_steps,
                "selection_episodes": self.selection_episodes,
                "selection_steps": self.selection_steps}


@dataclass
class Selection:
    """The run's hall of fame, its validation, and its budget (see the module docstring).

    ``rank_by`` is ``"fitness"`` (GAs: mean training fitness) or ``"recency"`` (fuzzy_q: the
    latest greedy controllers first, because its training fitness is measured while
    exploring and says little about the greedy controller).
    """

    config: SelectionConfig
    stop: StopConfig
    run_seed: int
    rank_by: str = "fitness"
    hall: dict[bytes, Candidate] = field(default_factory=dict)
    best: Candidate | None = None
    usage: Usage = field(default_factory=Usage)
    stop_reason: str | None = None  # why the run ended early: "target", "episodes", ...
    finalized: bool = False
    validated: list[dict[str, Any]] = field(default_factory=list)  # every validation, in order

    def __post_init__(self) -> None:
        self.seeds = validation_seeds(self.run_seed, self.config.episodes)
        self._known: dict[int, list[_KnownEpisode]] = {}  # by validation seed

    @property
    def enabled(self) -> bool:
        return self.config.candidates > 0

    # -- the hall of fame ------------------------------------------------------------------
    def offer(self, population: IntArray, fitness: FloatArray, generation: int) -> None:
        """Add a generation's controllers ``population (P, M)`` with their trial fitness
        ``(P,)`` (an individual met before adds to its mean), then keep the top candidates."""
        if not self.enabled:
            return
        self.finalized = False
        for individual, (consequents, value) in enumerate(zip(population, fitness,
                                                              strict=True)):
            key = _key(consequents)
            candidate = self.hall.get(key)
            if candidate is None:
                candidate = Candidate(np.array(consequents, dtype=np.intp), generation,
                                      individual)
                self.hall[key] = candidate
            candidate.generation, candidate.individual = generation, individual
            candidate.fitness_sum += float(value)
            candidate.trials += 1
        keep = {c.key() for c in self.ranked()[: self.config.candidates]}
        if self.best is not None:
            keep.add(self.best.key())
        self.hall = {k: c for k, c in self.hall.items() if k in keep}

    def ranked(self) -> list[Candidate]:
        """The hall's candidates, best first (ties: first inserted)."""
        candidates = list(self.hall.values())
        if self.rank_by == "recency":
            return sorted(candidates, key=lambda c: -c.generation)
        return sorted(candidates, key=lambda c: -c.fitness)

    # -- validation ------------------------------------------------------------------------
    def validate(self, candidate: Candidate, rules: SparseRules, env: BatchEnv,
                 generation: int) -> None:
        """Run ``candidate`` on the validation episodes and record the result.

        Episodes run one after another on the learner's batch-of-one ``env`` through the
        training loop's own inference (the same bits as the deployed controller, and no
        compiled kernels to load for a small job)."""
        consequents = candidate.consequents.tolist()
        if env.replayable:
            trials = [self._episode(env, rules, seed, consequents)
                      for seed in self.seeds.tolist()]
        else:
            trials = [run_trial(env, rules, int(seed), consequents) for seed in self.seeds]
        lengths = np.array([t.length for t in trials], dtype=np.int64)
        fitness = env.episode_fitness(np.array([t.ret for t in trials], dtype=np.float64),
                                      lengths, np.array([t.success for t in trials]))
        candidate.validation = mean_interval(fitness)
        candidate.validated_at = generation
        self.usage.selection_episodes += len(trials)
        self.usage.selection_steps += int(lengths.sum())
        self.validated.append(candidate.record())
        if self.best is None or candidate.validation.value > self.best.validation_value():
            self.best = candidate

    def _episode(self, env: BatchEnv, rules: SparseRules, seed: int,
                 consequents: list[int]) -> Trial:
        """Validation episode ``seed`` of the controller ``consequents (M,)``: an earlier
        candidate's if this one commands alike every rule that fired where that one acted
        (see the module docstring), else run and remembered."""
        known = self._known.setdefault(seed, [])
        for episode in known:
            if all(consequents[m] == k for m, k in zip(episode.rules, episode.commands,
                                                        strict=True)):
                return episode.trial
        acted: set[int] = set()
        trial = run_trial(env, rules, seed, consequents, acted=acted)
        order = tuple(sorted(acted))
        known.append(_KnownEpisode(order, tuple(consequents[m] for m in order), trial))
        return trial

    def validate_leader(self, rules: SparseRules, env: BatchEnv, generation: int) -> None:
        """Validate the hall's leader if it has not been (every generation)."""
        ranked = self.ranked()
        if ranked and ranked[0].validation is None and self.fits(1):
            self.validate(ranked[0], rules, env, generation)

    def finalize(self, rules: SparseRules, env: BatchEnv, generation: int,
                 elites: list[Candidate]) -> None:
        """Validate the remaining candidates (the hall's top and ``elites``) the budget
        allows, best ranked first: the run is ending."""
        if not self.enabled or self.finalized:
            return
        pending: list[Candidate] = []
        for candidate in [*self.ranked()[: self.config.candidates], *elites]:
            if candidate.validation is None and all(candidate is not c for c in pending):
                pending.append(candidate)
        for candidate in pending:
            if not self.fits(1):
                break
            self.validate(candidate, rules, env, generation)
        self.finalized = True

    def candidate_for(self, consequents: IntArray) -> Candidate | None:
        return self.hall.get(_key(consequents))

    # -- budgets ---------------------------------------------------------------------------
    def fits(self, validations: int) -> bool:
        """Whether ``validations`` more validations stay within ``stop.episodes``."""
        limit = self.stop.episodes
        return limit is None or (self.usage.episodes + validations * self.config.episodes
                                 <= limit)

    def reached_target(self) -> bool:
        target = self.stop.target
        return target is not None and self.best is not None and (
            self.best.validation_value() >= target)

    def budget_exhausted(self, generation_episodes: int, elapsed: float) -> str | None:
        """Which budget would the next generation (``generation_episodes`` training episodes,
        its leader's validation, and the final validation of every candidate) break, if any.
        """
        stop = self.stop
        validations = (1 + self.config.candidates) if self.enabled else 0
        upcoming = generation_episodes + validations * self.config.episodes
        usage = self.usage
        if stop.episodes is not None and usage.episodes + upcoming > stop.episodes:
            return "episodes"
        if stop.steps is not None and usage.episodes > 0:
            per_episode = usage.steps / usage.episodes
            if usage.steps + upcoming * per_episode > stop.steps:
                return "steps"
        if stop.seconds is not None and elapsed >= stop.seconds:
            return "seconds"
        return None

    # -- checkpoints -----------------------------------------------------------------------
    def state_dict(self) -> dict[str, Any]:
        return {"hall": [c.to_dict() for c in self.hall.values()],
                "best": None if self.best is None else self.best.to_dict(),
                "usage": self.usage.to_dict(), "stop_reason": self.stop_reason,
                "finalized": self.finalized, "validated": self.validated}

    def restore(self, state: SelectionState | None) -> None:
        """Restore what :meth:`state_dict` saved, as :func:`~flctool.learners.checkpoint.
        read_checkpoint` validated it (None: a checkpoint of a run without selection)."""
        if state is None:
            return
        self.hall = {c.key(): c for c in state.hall}
        best = state.best
        # the best is the same object as its hall entry, so later validations update both
        self.best = self.hall.get(best.key(), best) if best is not None else None
        self.usage, self.stop_reason = state.usage, state.stop_reason
        self.finalized, self.validated = state.finalized, state.validated

    def record(self) -> dict[str, Any]:
        """What run.json shows: the validation scheme, every candidate validated (in order:
        where it came from, its training fitness, its validation mean and 95 % CI), the best,
        and the episodes and steps spent on training and on selection."""
        return {"candidates": self.config.candidates, "episodes": self.config.episodes,
                "seeds": f"{len(self.seeds)} fixed seeds in [2^62, 2^63) drawn from the "
                         "run's seed",
                "validated": self.validated,
                "best": None if self.best is None else self.best.record(),
                "usage": self.usage.to_dict(), "stop_reason": self.stop_reason}
