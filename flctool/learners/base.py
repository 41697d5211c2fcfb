"""The learner protocol and the one training loop every learner runs.

A learner keeps a population of controllers (chromosomes of M consequent indices, paper
Sec. IV; ``fuzzy_q`` keeps one, its greedy controller) with their fitness, and supplies two
steps: :meth:`Learner.evaluate` runs a generation's trials, :meth:`Learner.advance` makes the
next generation. :func:`train` does the rest -- timing, metrics, callbacks, stopping -- the
same way for all of them.

Randomness: the run's seed feeds one ``SeedSequence`` that spawns three generators, ``ga``
(initialisation, selection, crossover, mutation), ``env`` (episode start seeds) and
``explore`` (fuzzy_q's choices). Their states are part of every checkpoint, so a resumed run
draws exactly what an uninterrupted one would. Training episodes use seeds of at least
:data:`TRAIN_SEED_LOW` = 2^32, so evaluating with seeds below it (``flctool evaluate`` counts
from 0) never replays a training start.
"""

from __future__ import annotations

import time
from abc import ABC, abstractmethod
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any, ClassVar, Protocol

import numpy as np
from numpy.typing import NDArray

from flctool.compile import compile_behaviour
from flctool.envs.base import BatchEnv
from flctool.errors import LearnError
from flctool.learners.budget import Budget, Usage
from flctool.learners.callbacks import Callback, CallbackList, RunCallback
from flctool.learners.checkpoint import STREAMS, Expected, read_checkpoint
from flctool.learners.metrics import GenerationMetrics
from flctool.learners.selection import Candidate, ModelSelection
from flctool.learners.trial import SparseRules
from flctool.rollout import TRAIN_SEED_HIGH, TRAIN_SEED_LOW
from flctool.spec.learning import LearningConfig
from flctool.spec.models import Behaviour
from flctool.spec.rule_order import rule_index


class RuleStrengths(Protocol):
    """What the template loop needs of a learner's rule strengths (eq. 4-9): the q table for
    metrics and plots, and its state for checkpoints. :class:`~flctool.learners.fuzzy_q.FuzzyQ`
    is one; the base class knows no learner."""

    def table(self) -> FloatArray: ...

    def state_dict(self) -> dict[str, Any]: ...

    def load_state_dict(self, state: dict[str, Any]) -> None: ...

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]



@dataclass(frozen=True)
class GenerationResult:
    """What :meth:`Learner.evaluate` measured."""

    fitness: FloatArray  # (P,) per individual, or (E,) per episode for fuzzy_q
    episodes: int
    steps: int


class Learner(ABC):
    """Base of every learner; subclasses supply :meth:`evaluate` and :meth:`advance`.

    Attributes: ``config``, the behaviour's ``learning:`` section, of the model the learner's
    plugin entry names (a subclass declares it: ``config: PittConfig``); ``population (P,
    M)`` command indices, ``fitness (P,)`` of the last evaluated generation, ``generation``
    (-1 before the first), ``elapsed`` seconds of training so far.
    """

    name: ClassVar[str]
    config: LearningConfig
    #: The rule strengths and their traces (eq. 4-9), for learners that keep them.
    fuzzy_q: RuleStrengths | None = None
    #: How the hall of fame ranks candidates (see :class:`ModelSelection`).
    rank_by: ClassVar[str] = "fitness"

    def __init__(self, behaviour: Behaviour, env: BatchEnv) -> None:
        self.behaviour = behaviour
        learning = behaviour.learning
        if learning.learner != self.name:
            raise LearnError(f"the {self.name} learner cannot learn a behaviour whose "
                             f"learning section is the {learning.learner} learner's",
                             hint=f"set learning.learner: {self.name}, or use make_learner")
        # The section's model is chosen by 'learner' among the plugins' models, so it is
        # the one this learner's entry names: the type a subclass declares for config.
        self.config = learning
        self.controller = compile_behaviour(behaviour)
        self.rules = SparseRules(self.controller)
        self.env = env
        children = np.random.SeedSequence(self.config.seed).spawn(len(STREAMS))
        self.rngs = {name: np.random.default_rng(seq) for name, seq in zip(STREAMS, children,
                                                                           strict=True)}
        self.generation = -1
        self.elapsed = 0.0
        self.population: IntArray = np.zeros((1, self.controller.n_rules), dtype=np.intp)
        self.fitness: FloatArray = np.zeros(1)
        self.fixed_rules, self.fixed_commands = fixed_consequents(behaviour)
        #: Episodes and steps the run has spent, training and selection apart.
        self.usage = Usage()
        self.selection = ModelSelection(self.config.selection, self.config.seed, self.usage,
                                        self.config.stop.episodes, self.rank_by)
        self.budget = Budget(self.config.stop, self.selection, self.usage)

    @property
    def run_callbacks(self) -> list[RunCallback]:
        """The parts of the run that act between generations, in order: model selection,
        then the budget (which looks at what selection chose)."""
        return [self.selection, self.budget]

    @property
    def stop_reason(self) -> str | None:
        """Why the run ended before its generations ("target", "episodes", ...), or None."""
        return next((c.stop_reason for c in self.run_callbacks if c.stop_reason), None)

    # -- what each learner supplies ----------------------------------------------------
    @abstractmethod
    def evaluate(self, generation: int) -> GenerationResult:
        """Run the trials of ``generation`` and set :attr:`fitness` (and, for fuzzy_q,
        :attr:`population`)."""

    @abstractmethod
    def advance(self) -> None:
        """Turn the evaluated generation into the next one (breed, decay exploration)."""

    @property
    def uses_strengths(self) -> bool:
        """Whether the learner keeps rule strengths (a q table): then :meth:`strengths` is set."""
        return self.fuzzy_q is not None

    def strengths(self) -> FloatArray | None:
        """The q table (M, K), for learners that keep one."""
        return None if self.fuzzy_q is None else self.fuzzy_q.table()

    def extra_state(self) -> dict[str, Any]:
        """Learner-specific checkpoint data (JSON-compatible): the q table and traces."""
        return {} if self.fuzzy_q is None else self.fuzzy_q.state_dict()

    def load_extra_state(self, state: dict[str, Any]) -> None:
        """Restore what :meth:`extra_state` saved."""
        if self.fuzzy_q is not None:
            self.fuzzy_q.load_state_dict(state)

    def start_from(self, population: IntArray | None = None,
                   strengths: FloatArray | None = None) -> None:
        """Start a fresh run from a given first generation ``population (P, M)`` and/or q
        table ``strengths (M, K)`` instead of random ones (a warm start, e.g. around a
        controller); traces start at zero, rules the file gives stay as given. Only before
        the first generation: the first checkpoint then holds what it became.
        """
        n_rules, n_commands = self.controller.n_rules, self.controller.n_commands
        if self.generation != -1:
            raise LearnError("a run starts from a given population or q table only before "
                             "its first generation", hint="start a new run")
        if population is not None:
            genes = np.asarray(population)
            if genes.shape != (self.config.population, n_rules) or genes.dtype.kind not in "iu":
                raise LearnError(f"a first generation must be {self.config.population} x "
                                 f"{n_rules} command indices, not {genes.shape} of "
                                 f"{genes.dtype}", hint="one row per individual")
            if genes.size and (genes.min() < 0 or genes.max() >= n_commands):
                raise LearnError(f"a first generation holds command indices outside "
                                 f"0..{n_commands - 1}")
            self.population = self.keep_fixed(genes.astype(np.intp))
        if strengths is not None:
            if self.fuzzy_q is None:
                raise LearnError(f"the {self.name} learner keeps no rule strengths to start "
                                 "from", hint="give a first generation only")
            table = np.asarray(strengths, dtype=np.float64)
            if table.shape != (n_rules, n_commands) or not np.isfinite(table).all():
                raise LearnError(f"a q table must be {n_rules} x {n_commands} finite numbers, "
                                 f"not {table.shape}")
            self.fuzzy_q.load_state_dict({"q": table.tolist(),
                                          "traces": np.zeros_like(table).tolist()})

    # -- shared helpers ------------------------------------------------------------------
    def keep_fixed(self, population: IntArray) -> IntArray:
        """``population (P, M)`` with the rules the file gives set to their commands (in
        place, and returned): given rules are fixed, never learned."""
        population[:, self.fixed_rules] = self.fixed_commands
        return population

    @property
    def finished(self) -> bool:
        """Whether the run has ended: all its generations done, or a budget or target met."""
        return self.stop_reason is not None or self.generation + 1 >= self.config.generations

    def episodes_per_generation(self) -> int:
        """The training episodes one generation runs."""
        return self.config.population * self.config.trials

    def selected(self) -> tuple[int, int, IntArray, float, Candidate | None]:
        """The controller the run returns: (generation, individual, consequents (M,),
        training fitness, its validated candidate or None).

        The best validated candidate; before any validation (or with selection off) the
        last evaluated generation's best individual by its training trials.
        """
        best = self.selection.best
        if best is not None:
            return best.generation, best.individual, best.consequents.copy(), best.fitness, best
        index, consequents, fitness = self.best()
        return self.generation, index, consequents, fitness, None

    def elite_count(self) -> int:
        """How many of a generation's best are its elites (at least 1); a GA's ``elites``."""
        return 1

    def elite_candidates(self) -> list[Candidate]:
        """The last generation's elites (at least its best) as hall-of-fame candidates."""
        count = self.elite_count() if self.population.shape[0] > 1 else 1
        order = np.argsort(-self.fitness, kind="stable")[:count]
        found = [self.selection.candidate_for(self.population[i]) for i in order]
        return [c for c in found if c is not None]

    def best(self) -> tuple[int, IntArray, float]:
        """The last evaluated generation's best individual: (index, consequents (M,), fitness).

        Ties go to the lower index (elites come first).
        """
        index = int(np.argmax(self.fitness))
        return index, self.population[index].copy(), float(self.fitness[index])

    def episode_seeds(self, individuals: int, trials: int, common: bool) -> NDArray[np.int64]:
        """Start seeds (individuals, trials) of one generation, from the ``env`` stream.

        With ``common``, every individual gets the same ``trials`` seeds (common random
        starts: fitness differences then come from the controllers, not the ball placement).
        """
        rng = self.rngs["env"]
        if common:
            row = rng.integers(TRAIN_SEED_LOW, TRAIN_SEED_HIGH, size=trials, dtype=np.int64)
            return np.tile(row, (individuals, 1))
        return rng.integers(TRAIN_SEED_LOW, TRAIN_SEED_HIGH, size=(individuals, trials),
                            dtype=np.int64)

    def state_dict(self) -> dict[str, Any]:
        """Everything needed to continue bit for bit after the last evaluated generation."""
        return {
            "learner": self.name,
            "generation": self.generation,
            "elapsed": self.elapsed,
            "population": self.population.tolist(),
            "fitness": self.fitness.tolist(),
            "rng": {name: rng.bit_generator.state for name, rng in self.rngs.items()},
            "selection": self.run_callbacks_state(),
            **self.extra_state(),
        }

    def run_callbacks_state(self) -> dict[str, Any]:
        """The run callbacks' states, as one record (a checkpoint's ``selection``)."""
        state: dict[str, Any] = {}
        for callback in self.run_callbacks:
            state.update(callback.state_dict())
        return state

    def selection_record(self) -> dict[str, Any]:
        """What run.json shows of selection and spending: the validated candidates, the
        best, the episodes and steps of training and of selection, why the run stopped."""
        return {**self.selection.record(), "usage": self.usage.to_dict(),
                "stop_reason": self.stop_reason}

    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Restore what :meth:`state_dict` saved; :class:`LearnError` (and the learner left
        as it was) if it is damaged or of another learner or behaviour (the checks are
        :func:`~flctool.learners.checkpoint.read_checkpoint`'s)."""
        controller = self.controller
        checkpoint = read_checkpoint(state, Expected(
            controller.n_rules, controller.n_commands, learner=self.name,
            max_population=self.config.population, strengths=self.uses_strengths))
        for name, generator in self.rngs.items():
            generator.bit_generator.state = checkpoint.rng[name]
        if checkpoint.selection is not None:  # None: a checkpoint of a run without one
            self.selection.restore(checkpoint.selection)
            self.budget.restore(checkpoint.selection)
        self.generation, self.elapsed = checkpoint.generation, checkpoint.elapsed
        self.population, self.fitness = checkpoint.population, checkpoint.fitness
        self.load_extra_state(state)


def fixed_consequents(behaviour: Behaviour) -> tuple[IntArray, IntArray]:
    """The rules the file gives: their grid indices (F,) and command indices (F,)."""
    names = behaviour.input_names
    sets = [tuple(variable.sets) for variable in behaviour.inputs.values()]
    shape = tuple(len(s) for s in sets)
    commands = tuple(behaviour.output.commands)
    rules, chosen = [], []
    for rule in behaviour.rules:
        index = [sets[i].index(rule.if_[name]) for i, name in enumerate(names)]
        rules.append(rule_index(index, shape))
        chosen.append(commands.index(rule.then))
    return np.array(rules, dtype=np.intp), np.array(chosen, dtype=np.intp)


def train(learner: Learner, callbacks: Iterable[Callback] = ()) -> list[GenerationMetrics]:
    """Run generations from the learner's current one until the run ends: at
    ``learning.generations``, or when a run callback (a ``learning.stop`` budget or target)
    ends it.

    A fresh learner starts at generation 0; one restored from a checkpoint continues after
    it. Each generation is advance (breed), evaluate (the trials), then the run callbacks
    (:attr:`Learner.run_callbacks`: model selection validates, the budget decides whether to
    stop; when the run ends, selection validates its remaining candidates), then the report:
    the generation's metrics to ``callbacks``. So the metrics -- and the checkpoint a run
    directory writes of them -- already hold the run's final choice. Returns this session's
    metrics, one per generation.
    """
    callback = CallbackList(callbacks)
    history: list[GenerationMetrics] = []
    usage = learner.usage
    # on_end runs however training ends -- finished, stopped early, an error or Ctrl-C -- so
    # that a run directory never claims to be running after its process has gone.
    try:
        callback.on_start(learner)
        started = time.perf_counter()
        before = learner.elapsed

        def clock() -> None:
            learner.elapsed = before + time.perf_counter() - started

        generation = learner.generation + 1
        while not learner.finished:
            selection_before = usage.selection_episodes, usage.selection_steps
            if generation > 0:
                learner.advance()
            result = learner.evaluate(generation)
            learner.generation = generation
            usage.training_episodes += result.episodes
            usage.training_steps += result.steps
            for part in learner.run_callbacks:
                part.on_trials(learner, result)
                clock()
            if learner.finished:
                for part in learner.run_callbacks:
                    part.on_finish(learner)
                clock()
            best = learner.selection.best
            metrics = GenerationMetrics.from_fitness(
                generation, result.fitness, result.episodes, result.steps, learner.elapsed,
                usage.selection_episodes - selection_before[0],
                usage.selection_steps - selection_before[1],
                best.validation_value() if best else float("nan"))
            history.append(metrics)
            generation += 1
            if not callback.on_generation(metrics):
                break
    finally:
        callback.on_end()
    return history
