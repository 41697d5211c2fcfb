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

Then the validated candidates **race** (:meth:`ModelSelection.race`, successive halving by
thirds): on ``selection.episodes`` episodes a lucky candidate often validates above a better
one, so the best third run on three times the episodes, and so on up to ``selection.race``;
the winner of the last round is returned. Selection's episodes then go to the candidates
still in contention. While racing is on, a validated candidate stays in the hall until the
run ends, so that it can race; ``selection.race: 0`` is the selection of earlier versions,
bit for bit.

Seeds: training episodes use seeds in [2^32, 2^62) (drawn from the run's ``env`` stream),
``flctool evaluate`` uses seeds below 2^31 (drawn from its ``--seed``), and validation uses
the fixed seeds :func:`validation_seeds` draws in [2^62, 2^63) from the run's seed: the three
sets never meet. Every candidate meets the same validation episodes (common random numbers),
so their differences come from the controllers; a race's rounds take the next seeds of the
same draw.

Episodes already known: with a simulator (``env.replayable``: an episode is a function of
its seed and the actions) a validation episode is not run again for a candidate that gives
the same command as an earlier one to every rule that fired where that one acted: it would
act the same at every step, so the episode is the same, bit for bit, and its outcome is
reused: on ballchase, a sixth (fuzzy_q) to a third (pitt, hybrid) of validation episodes.
They still count as spent (budgets and ``usage`` are what running them would give), so
results are the same with a robot, a resumed run or no reuse at all.

Budgets (``stop``, :mod:`flctool.learners.budget`) count validation episodes as they count
training ones.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from flctool.behaviour.learning import SelectionConfig
from flctool.envs.base import BatchEnv
from flctool.learners.metrics import FloatArray, GenerationResult, IntArray, Usage
from flctool.learners.run_callback import RunCallback
from flctool.learners.trial import SparseRules, Trial, run_trial
from flctool.rollout import Estimate, clip_estimate, distinct_run_seeds, mean_interval

#: A rule base, or what gives each candidate's (its own sets when a run learns them).
RulesOf = SparseRules | Callable[["Candidate"], SparseRules]

VALIDATION_SEED_LOW = 2**62
VALIDATION_SEED_HIGH = 2**63 - 1
#: Index of the validation seeds' child in the run's SeedSequence (after ga, env, explore).
_VALIDATION_STREAM = 3
#: A race's rounds keep the best third of the candidates, on three times the episodes.
RACE_FACTOR = 3


def validation_seeds(run_seed: int, episodes: int) -> NDArray[np.int64]:
    """The run's ``episodes`` distinct validation seeds (E,), in [2^62, 2^63).

    Drawn from a child of the run's seed that the training streams do not use, and the same
    for the whole run, so no state needs saving: a resumed run validates on the same episodes.
    """
    return distinct_run_seeds(run_seed, _VALIDATION_STREAM, VALIDATION_SEED_LOW,
                              VALIDATION_SEED_HIGH, episodes)


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
    #: Its set genome (G,) when the run learns the sets too (``learning.sets``), else None.
    sets: FloatArray | None = None
    #: Its success rate and mean return on the validation episodes (None: not validated, or
    #: by a version that did not record them).
    validation_success: float | None = None
    validation_return: float | None = None
    #: Each validation episode's fitness, success and return, in seed order (empty: not
    #: validated, or by a version that did not record them): what a race extends.
    episode_fitness: list[float] = field(default_factory=list)
    episode_success: list[bool] = field(default_factory=list)
    episode_return: list[float] = field(default_factory=list)

    @property
    def fitness(self) -> float:
        """Mean training fitness over the generations it was evaluated in."""
        return self.fitness_sum / self.trials if self.trials else math.nan

    def key(self) -> bytes:
        return _key(self.consequents, self.sets)

    def validation_value(self) -> float:
        """The validated mean fitness; -inf before validation."""
        return -math.inf if self.validation is None else self.validation.value

    def mean_of(self, episodes: int) -> float:
        """The mean fitness over its first ``episodes`` validation episodes (a race compares
        candidates on the same episodes)."""
        return math.fsum(self.episode_fitness[:episodes]) / episodes

    def to_dict(self) -> dict[str, Any]:
        return {"consequents": self.consequents.tolist(), "generation": self.generation,
                "individual": self.individual, "fitness_sum": self.fitness_sum,
                "trials": self.trials, "validated_at": self.validated_at,
                "validation": None if self.validation is None else _estimate_dict(
                    self.validation),
                "validation_success": self.validation_success,
                "validation_return": self.validation_return,
                **({} if not self.episode_fitness else {
                    "episodes": [self.episode_fitness, self.episode_success,
                                 self.episode_return]}),
                **({} if self.sets is None else {"sets": self.sets.tolist()})}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Candidate:
        validation = data["validation"]
        success, mean_return = data.get("validation_success"), data.get("validation_return")
        fitness, won, returns = data.get("episodes") or ([], [], [])
        if not len(fitness) == len(won) == len(returns):
            raise ValueError("a candidate's validation episodes differ in length")
        return cls(np.array(data["consequents"], dtype=np.intp), int(data["generation"]),
                   int(data["individual"]), float(data["fitness_sum"]), int(data["trials"]),
                   None if validation is None else _estimate(validation),
                   int(data["validated_at"]),
                   None if data.get("sets") is None else np.array(data["sets"],
                                                                  dtype=np.float64),
                   None if success is None else float(success),
                   None if mean_return is None else float(mean_return),
                   [float(v) for v in fitness], [bool(v) for v in won],
                   [float(v) for v in returns])

    def validation_in(self, unit: str) -> float:
        """The validated figure in ``unit`` (``fitness``, ``success`` or ``return``); -inf
        if it was not measured."""
        value = {"fitness": None if self.validation is None else self.validation.value,
                 "success": self.validation_success, "return": self.validation_return}[unit]
        return -math.inf if value is None else value

    def record(self) -> dict[str, Any]:
        """What run.json shows of a candidate: where it came from, training and validation."""
        return {"generation": self.generation, "individual": self.individual,
                "training_fitness": self.fitness, "training_trials": self.trials,
                "validation": None if self.validation is None
                else self.validation.to_dict(),
                "validation_success": self.validation_success,
                "validation_return": self.validation_return}


def race_cost(candidates: int, first: int, last: int) -> int:
    """The most episodes a race of ``candidates`` validated on ``first`` episodes each costs
    when it takes its finalists to ``last`` (see :meth:`ModelSelection.race`)."""
    episodes, cost = first, 0
    while candidates > 1 and episodes < last:
        more = min(episodes * RACE_FACTOR, last)
        candidates = max(2, math.ceil(candidates / RACE_FACTOR))
        cost += candidates * (more - episodes)
        episodes = more
    return cost


def _key(consequents: IntArray, sets: FloatArray | None = None) -> bytes:
    key = np.asarray(consequents, dtype=np.int64).tobytes()
    return key if sets is None else key + np.asarray(sets, dtype=np.float64).tobytes()


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


class SelectionRun(Protocol):
    """What model selection reads of the run it is part of (a
    :class:`~flctool.learners.base.Learner` is one)."""

    @property
    def population(self) -> IntArray: ...

    @property
    def fitness(self) -> FloatArray: ...

    @property
    def set_genes(self) -> FloatArray | None: ...

    @property
    def generation(self) -> int: ...

    @property
    def env(self) -> BatchEnv: ...

    @property
    def stop_reason(self) -> str | None: ...

    def rules_of(self, candidate: Candidate) -> SparseRules: ...

    def elite_candidates(self) -> list[Candidate]: ...


class ModelSelection(RunCallback[SelectionRun]):
    """The run's hall of fame and its validation (see the module docstring): the run
    callback that decides which controller a run returns.

    ``rank_by`` is ``"fitness"`` (GAs: mean training fitness) or ``"recency"`` (fuzzy_q: the
    latest greedy controllers first, because its training fitness is measured while
    exploring and says little about the greedy controller). Validation episodes are added to
    ``usage``, and never taken beyond ``episode_limit`` (``stop.episodes``) less ``reserve()``,
    what the end of the run needs after selection (confirmation, baselines).
    """

    def __init__(self, config: SelectionConfig, run_seed: int, usage: Usage,
                 episode_limit: int | None = None, rank_by: str = "fitness",
                 reserve: Callable[[], int] = lambda: 0, race: int | None = None) -> None:
        self.config = config
        #: The episodes a race takes its finalists to: ``race``, else ``selection.race``,
        #: else none (a learner passes its reading of an unset key).
        self.race_to = race if race is not None else (config.race or 0)
        self.reserve = reserve  # episodes the end of the run needs after selection
        self.run_seed = run_seed
        self.usage = usage
        self.episode_limit = episode_limit
        self.rank_by = rank_by
        self.hall: dict[bytes, Candidate] = {}
        self.best: Candidate | None = None
        self.finalized = False
        self.validated: list[dict[str, Any]] = []  # every validation, in order
        #: Whether candidates race when the run ends (``selection.race``); a run started by
        #: a version without races continues without them (:meth:`restore`).
        self.racing = self.race_to > config.episodes
        self.rounds: list[dict[str, Any]] = []  # the last race's rounds (run.json)
        # a prefix of the longer draw: the first `episodes` seeds are the same either way
        self.seeds = validation_seeds(run_seed, max(config.episodes, self.race_to))
        # by validation seed and set genome (other sets: other episodes)
        self._known: dict[tuple[int, bytes], list[_KnownEpisode]] = {}

    @property
    def enabled(self) -> bool:
        return self.config.candidates > 0

    # -- as a run callback -------------------------------------------------------------------
    def on_trials(self, learner: SelectionRun, result: GenerationResult) -> None:
        """Offer the generation to the hall of fame, and validate its leader."""
        del result
        self.offer(learner.population, learner.fitness, learner.generation, learner.set_genes)
        self.validate_leader(learner.rules_of, learner.env, learner.generation)

    def on_finish(self, learner: SelectionRun) -> None:
        """Validate the remaining candidates, unless a target ended the run."""
        if learner.stop_reason != "target":
            self.finalize(learner.rules_of, learner.env, learner.generation,
                          learner.elite_candidates())

    def most_episodes_after_generation(self) -> int:
        """The most validation episodes one more generation may cost: its leader's and,
        if it is the last, every candidate's and the race's."""
        if not self.enabled:
            return 0
        episodes = (1 + self.config.candidates) * self.config.episodes
        if self.racing:
            validated = sum(1 for c in self.hall.values() if c.validation is not None)
            episodes += race_cost(validated + 1 + self.config.candidates,
                                  self.config.episodes, self.race_to)
        return episodes

    # -- the hall of fame ------------------------------------------------------------------
    def offer(self, population: IntArray, fitness: FloatArray, generation: int,
              sets: FloatArray | None = None) -> None:
        """Add a generation's controllers ``population (P, M)`` with their trial fitness
        ``(P,)`` (an individual met before adds to its mean), then keep the top candidates;
        ``sets (P, G)`` are their set genomes when the run learns the sets."""
        if not self.enabled:
            return
        self.finalized = False
        for individual, (consequents, value) in enumerate(zip(population, fitness,
                                                              strict=True)):
            genes = None if sets is None else np.array(sets[individual], dtype=np.float64)
            key = _key(consequents, genes)
            candidate = self.hall.get(key)
            if candidate is None:
                candidate = Candidate(np.array(consequents, dtype=np.intp), generation,
                                      individual, sets=genes)
                self.hall[key] = candidate
            candidate.generation, candidate.individual = generation, individual
            candidate.fitness_sum += float(value)
            candidate.trials += 1
        keep = {c.key() for c in self.ranked()[: self.config.candidates]}
        if self.best is not None:
            keep.add(self.best.key())
        if self.racing:  # every validated candidate races when the run ends
            keep.update(k for k, c in self.hall.items() if c.validation is not None)
        self.hall = {k: c for k, c in self.hall.items() if k in keep}

    def ranked(self) -> list[Candidate]:
        """The hall's candidates, best first (ties: first inserted)."""
        candidates = list(self.hall.values())
        if self.rank_by == "recency":
            return sorted(candidates, key=lambda c: -c.generation)
        return sorted(candidates, key=lambda c: -c.fitness)

    # -- validation ------------------------------------------------------------------------
    def validate(self, candidate: Candidate, rules: RulesOf, env: BatchEnv,
                 generation: int) -> None:
        """Run ``candidate`` on the validation episodes (``selection.episodes``), record the
        result, and make it the best if it validated highest so far.

        Episodes run one after another on the learner's batch-of-one ``env`` through the
        training loop's own inference (the same bits as the deployed controller, and no
        compiled kernels to load for a small job). ``rules`` is the rule base, or what gives
        a candidate's (its own sets, when the run learns them)."""
        self._validate_to(candidate, self.config.episodes, rules, env, generation)
        assert candidate.validation is not None
        if self.best is None or candidate.validation.value > self.best.validation_value():
            self.best = candidate

    def _validate_to(self, candidate: Candidate, episodes: int, rules: RulesOf,
                     env: BatchEnv, generation: int) -> None:
        """Run ``candidate`` on the validation episodes it has not met among the first
        ``episodes``, and make its validation the figure over all it has met."""
        if not isinstance(rules, SparseRules):
            rules = rules(candidate)
        seeds = self.seeds[len(candidate.episode_fitness):episodes]
        if not seeds.size:
            return
        consequents = candidate.consequents.tolist()
        if env.replayable:
            sets = b"" if candidate.sets is None else candidate.sets.tobytes()
            trials = [self._episode(env, rules, (seed, sets), consequents)
                      for seed in seeds.tolist()]
        else:
            trials = [run_trial(env, rules, int(seed), consequents) for seed in seeds]
        lengths = np.array([t.length for t in trials], dtype=np.int64)
        fitness = env.episode_fitness(np.array([t.ret for t in trials], dtype=np.float64),
                                      lengths, np.array([t.success for t in trials]))
        candidate.episode_fitness += [float(v) for v in fitness]
        candidate.episode_success += [bool(t.success) for t in trials]
        candidate.episode_return += [float(t.ret) for t in trials]
        all_fitness = np.array(candidate.episode_fitness, dtype=np.float64)
        candidate.validation = clip_estimate(mean_interval(all_fitness), env.fitness_range)
        candidate.validated_at = generation
        candidate.validation_success = float(np.mean(candidate.episode_success))
        candidate.validation_return = float(np.mean(candidate.episode_return))
        self.usage.selection_episodes += len(trials)
        self.usage.selection_steps += int(lengths.sum())
        self.validated.append(candidate.record())

    def _episode(self, env: BatchEnv, rules: SparseRules, episode_key: tuple[int, bytes],
                 consequents: list[int]) -> Trial:
        """Validation episode ``seed`` of the controller ``consequents (M,)`` (with the set
        genome of ``episode_key``, which is (seed, genome bytes)): an earlier candidate's if
        this one commands alike every rule that fired where that one acted (see the module
        docstring), else run and remembered."""
        seed = episode_key[0]
        known = self._known.setdefault(episode_key, [])
        for episode in known:
            if all(consequents[m] == k for m, k in zip(episode.rules, episode.commands,
                                                        strict=True)):
                return episode.trial
        acted: set[int] = set()
        trial = run_trial(env, rules, seed, consequents, acted=acted)
        order = tuple(sorted(acted))
        known.append(_KnownEpisode(order, tuple(consequents[m] for m in order), trial))
        return trial

    def validate_leader(self, rules: RulesOf, env: BatchEnv, generation: int) -> None:
        """Validate the hall's leader if it has not been (every generation)."""
        ranked = self.ranked()
        if ranked and ranked[0].validation is None and self.fits(1):
            self.validate(ranked[0], rules, env, generation)

    def finalize(self, rules: RulesOf, env: BatchEnv, generation: int,
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
        if self.racing:
            self.race(rules, env, generation)
        self.finalized = True

    def race(self, rules: RulesOf, env: BatchEnv, generation: int) -> None:
        """Race the validated candidates (successive halving, by thirds): rank them on their
        first ``selection.episodes`` validation episodes; the best third (at least two) run
        on :data:`RACE_FACTOR` times as many and are ranked on those; and so on until
        ``selection.race`` episodes. The winner of the last round becomes the best. Every
        candidate of a round is ranked on the same episodes; a round the budget cannot pay
        for is not run (the best of the last round run wins)."""
        episodes = self.config.episodes
        contenders = sorted((c for c in self.hall.values()
                             if len(c.episode_fitness) >= episodes),
                            key=lambda c: -c.mean_of(episodes))
        self.rounds = []
        while len(contenders) > 1 and episodes < self.race_to:
            episodes = min(episodes * RACE_FACTOR, self.race_to)
            survivors = contenders[:max(2, math.ceil(len(contenders) / RACE_FACTOR))]
            if not self.fits_episodes(sum(max(0, episodes - len(c.episode_fitness))
                                          for c in survivors)):
                break
            for candidate in survivors:
                self._validate_to(candidate, episodes, rules, env, generation)
            contenders = sorted(survivors, key=lambda c: -c.mean_of(episodes))
            self.rounds.append({"episodes": episodes, "candidates": [
                {"generation": c.generation, "individual": c.individual,
                 "mean_fitness": c.mean_of(episodes)} for c in contenders]})
            self.best = contenders[0]

    def candidate_for(self, consequents: IntArray,
                      sets: FloatArray | None = None) -> Candidate | None:
        return self.hall.get(_key(consequents, sets))

    def fits(self, validations: int) -> bool:
        """Whether ``validations`` more validations stay within the episode limit."""
        return self.fits_episodes(validations * self.config.episodes)

    def fits_episodes(self, episodes: int) -> bool:
        """Whether ``episodes`` more validation episodes stay within the episode limit."""
        limit = self.episode_limit
        return limit is None or self.usage.episodes + episodes + self.reserve() <= limit

    # -- checkpoints -----------------------------------------------------------------------
    def state_dict(self) -> dict[str, Any]:
        return {"hall": [c.to_dict() for c in self.hall.values()],
                "best": None if self.best is None else self.best.to_dict(),
                "finalized": self.finalized, "validated": self.validated,
                "racing": self.racing, "race": self.rounds}

    def restore(self, hall: list[Candidate], best: Candidate | None, finalized: bool,
                validated: list[dict[str, Any]], racing: bool = False,
                rounds: list[dict[str, Any]] | None = None) -> None:
        """Restore what :meth:`state_dict` saved, as :func:`~flctool.learners.checkpoint.
        read_checkpoint` validated it (its ``SelectionState``). A checkpoint of a version
        without races (``racing`` False) continues without them, bit for bit."""
        self.hall = {c.key(): c for c in hall}
        # the best is the same object as its hall entry, so later validations update both
        self.best = self.hall.get(best.key(), best) if best is not None else None
        self.finalized, self.validated = finalized, validated
        self.racing = racing and self.race_to > self.config.episodes
        self.rounds = list(rounds or [])

    def record(self) -> dict[str, Any]:
        """What run.json shows of selection: the validation scheme, every candidate validated
        (in order: where it came from, its training fitness, its validation mean and 95 %
        CI) and the best."""
        return {"candidates": self.config.candidates, "episodes": self.config.episodes,
                "seeds": f"{len(self.seeds)} fixed seeds in [2^62, 2^63) drawn from the "
                         "run's seed",
                "validated": self.validated,
                "race": {"episodes": self.race_to if self.racing else 0,
                         "rounds": self.rounds},
                "best": None if self.best is None else self.best.record()}
