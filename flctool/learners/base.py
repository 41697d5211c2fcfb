"""The learner base: what every learner is, and the run it keeps.

A learner keeps a population of controllers (chromosomes of M consequent indices, paper
Sec. IV; ``fuzzy_q`` keeps one, its greedy controller) with their fitness, and supplies two
steps: :meth:`Learner.evaluate` runs a generation's trials, :meth:`Learner.advance` makes the
next generation. :func:`~flctool.learners.loop.train` does the rest -- timing, metrics,
callbacks, stopping -- the same way for all of them.

Randomness: the run's seed feeds one ``SeedSequence`` that spawns three generators, ``ga``
(initialisation, selection, crossover, mutation), ``env`` (episode start seeds) and
``explore`` (fuzzy_q's choices). Their states are part of every checkpoint, so a resumed run
draws exactly what an uninterrupted one would. Training episodes use seeds of at least
:data:`TRAIN_SEED_LOW` = 2^32, so evaluating with seeds below it (``flctool evaluate`` counts
from 0) never replays a training start.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from functools import partial
from typing import Any, ClassVar, Protocol

import numpy as np
from numpy.typing import NDArray

from flctool.behaviour.learning import LearningConfig
from flctool.behaviour.models import Behaviour
from flctool.behaviour.rule_order import rule_index
from flctool.compile import compile_behaviour
from flctool.envs.base import BatchEnv
from flctool.errors import LearnError, Problem, SpecError
from flctool.learners.baselines import BaselineCheck
from flctool.learners.budget import Budget
from flctool.learners.checkpoint import STREAMS, Expected, read_checkpoint
from flctool.learners.confirmation import Confirmation
from flctool.learners.extension import Extension, most_generations
from flctool.learners.metrics import FloatArray as FloatArray
from flctool.learners.metrics import GenerationResult as GenerationResult
from flctool.learners.metrics import IntArray as IntArray
from flctool.learners.metrics import Usage
from flctool.learners.run_callback import RunCallback
from flctool.learners.selection import Candidate, ModelSelection
from flctool.learners.trial import SparseRules
from flctool.rollout import TRAIN_SEED_HIGH, TRAIN_SEED_LOW
from flctool.sets.codec import SetCodec


class RuleStrengths(Protocol):
    """What the template loop needs of a learner's rule strengths (eq. 4-9): the q table for
    metrics and plots, and its state for checkpoints. :class:`~flctool.learners.fuzzy_q.FuzzyQ`
    is one; the base class knows no learner."""

    def table(self) -> FloatArray: ...

    def state_dict(self) -> dict[str, Any]: ...

    def load_state_dict(self, state: dict[str, Any]) -> None: ...


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
    #: Whether the learner can start a fresh attempt (:meth:`advance` then draws a new
    #: population), so that an extended run spends its room on them
    #: (:mod:`~flctool.learners.extension`).
    fresh_attempts: ClassVar[bool] = False

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
        #: The set codec when the run learns the sets too (``learning.sets``), and each
        #: controller's set genome (P, G) beside ``population``; None otherwise.
        self.codec = SetCodec(behaviour) if learning.sets is not None else None
        self.set_genes: FloatArray | None = None
        self._set_rules: dict[bytes, SparseRules] = {}
        #: Episodes and steps the run has spent, training and selection apart.
        self.usage = Usage()
        config = self.config
        limit = config.stop.episodes
        self.confirmation = Confirmation(config.selection.confirmation, config.seed,
                                         self.usage, limit)
        #: The end-of-run comparison with baselines; hand-made tables go in its ``given``.
        self.baseline_check = BaselineCheck(self.confirmation, self.usage, config.seed)
        self.confirmation.after = partial(self.baseline_check.episodes_needed,
                                          self.controller.n_commands)
        # selection leaves room, within stop.episodes, for what the end of the run needs
        self.selection = ModelSelection(config.selection, config.seed, self.usage, limit,
                                        self.rank_by, reserve=self.episodes_at_end,
                                        race=config.race_episodes)
        #: How many generations the run has: ``generations``, extended while it improves.
        extend = config.extend
        most = (extend.most if extend is not None and extend.most is not None else
                most_generations(len(behaviour.missing_rules()), self.controller.n_commands,
                                 config.generations))
        self.extension = Extension(extend, config.generations, most, self.fresh_attempts,
                                   config.runs_to_most)
        self.budget = Budget(config.stop, self.selection, self.confirmation, self.usage,
                             reserve=self.episodes_at_end)
        check_target(behaviour, env)

    def episodes_at_end(self) -> int:
        """The episodes the end of the run takes after selection: the confirmation and the
        comparison with baselines."""
        confirming = self.confirmation.episodes
        if confirming < 2:
            return confirming
        return confirming + self.baseline_check.episodes_needed(self.controller.n_commands,
                                                                 confirming)

    @property
    def run_callbacks(self) -> list[RunCallback[Learner]]:
        """The parts of the run that act between generations, in order: model selection,
        the extension (how many generations the run has, from what selection chose), the
        budget (which looks at what selection chose, and may have it confirmed), the
        confirmation of the controller the run returns, and its comparison with baselines."""
        return [self.selection, self.extension, self.budget, self.confirmation,
                self.baseline_check]

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

    # -- learned sets ----------------------------------------------------------------------
    def rules_for(self, genes: FloatArray | None) -> SparseRules:
        """The rule base with the sets of the set genome ``genes (G,)`` (decoded and
        validated as a file is), or the file's sets for None."""
        if genes is None or self.codec is None:
            return self.rules
        key = np.asarray(genes, dtype=np.float64).tobytes()
        rules = self._set_rules.get(key)
        if rules is None:
            if len(self._set_rules) >= _SET_RULES_KEPT:
                self._set_rules.clear()
            rules = SparseRules.from_behaviour(self.codec.decode(np.asarray(genes).tolist()))
            self._set_rules[key] = rules
        return rules

    def rules_of(self, candidate: Candidate) -> SparseRules:
        """The rule base a candidate acts with: its own sets, if the run learns them."""
        return self.rules_for(candidate.sets)

    def population_rules(self) -> list[SparseRules]:
        """The rule base of each controller of the population (P,)."""
        if self.set_genes is None:
            return [self.rules] * self.population.shape[0]
        return [self.rules_for(genes) for genes in self.set_genes]

    def selected_sets(self) -> FloatArray | None:
        """The set genome (G,) of the controller :meth:`selected` returns (None: the file's
        sets)."""
        best = self.selection.best
        if best is not None:
            return best.sets
        if self.set_genes is None:
            return None
        return np.array(self.set_genes[int(np.argmax(self.fitness))])

    # -- shared helpers ------------------------------------------------------------------
    def keep_fixed(self, population: IntArray) -> IntArray:
        """``population (P, M)`` with the rules the file gives set to their commands (in
        place, and returned): given rules are fixed, never learned."""
        population[:, self.fixed_rules] = self.fixed_commands
        return population

    @property
    def finished(self) -> bool:
        """Whether the run has ended: all its generations done, or a budget or target met."""
        return self.stop_reason is not None or self.generation + 1 >= self.planned_generations()

    def planned_generations(self) -> int:
        """The generations the run has, as things stand (:mod:`~flctool.learners.extension`):
        ``generations``, or more while an extended run improves."""
        return self.extension.planned()

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
        found = [self.selection.candidate_for(
            self.population[i], None if self.set_genes is None else self.set_genes[i])
            for i in order]
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
            **({} if self.set_genes is None else {"set_genes": self.set_genes.tolist()}),
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
        record = {**self.selection.record(), "usage": self.usage.to_dict(),
                  "stop_reason": self.stop_reason,
                  "confirmation": self.confirmation.record(),
                  "baseline": self.baseline_check.record(),
                  "extension": self.extension.record()}
        genes = self.selected_sets()
        if self.codec is not None and genes is not None:
            record["sets"] = self.sets_record(genes)
        return record

    @property
    def learned(self) -> bool | None:
        """Whether the run's controller is clearly better than every baseline (None: the
        run has not ended, or had nothing confirmed to compare)."""
        verdict = self.baseline_check.verdict
        return None if verdict is None else verdict.learned

    def sets_record(self, genes: FloatArray) -> dict[str, Any]:
        """What run.json shows of the returned controller's learned sets: the interpretability
        measures of each learned input (coverage, neighbour overlap, each set's movement)."""
        from flctool.sets.measures import interpretability

        assert self.codec is not None
        learned = self.codec.decode(np.asarray(genes).tolist())
        return {"genes": np.asarray(genes).tolist(),
                "inputs": interpretability(self.behaviour, learned,
                                           [c.name for c in self.codec.inputs])}

    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Restore what :meth:`state_dict` saved; :class:`LearnError` (and the learner left
        as it was) if it is damaged or of another learner or behaviour (the checks are
        :func:`~flctool.learners.checkpoint.read_checkpoint`'s)."""
        controller = self.controller
        checkpoint = read_checkpoint(state, Expected(
            controller.n_rules, controller.n_commands, learner=self.name,
            max_population=self.config.population, strengths=self.uses_strengths,
            set_genes=0 if self.codec is None else self.codec.size))
        for name, generator in self.rngs.items():
            generator.bit_generator.state = checkpoint.rng[name]
        if checkpoint.selection is not None:  # None: a checkpoint of a run without one
            saved = checkpoint.selection
            self.selection.restore(saved.hall, saved.best, saved.finalized, saved.validated,
                                   saved.racing, saved.race)
            self.budget.restore(saved.usage, saved.stop_reason)
            self.extension.restore(saved.extension)
            self.confirmation.restore(checkpoint.selection.confirmations)
            self.baseline_check.restore(checkpoint.selection.baselines,
                                        checkpoint.selection.verdict)
        else:
            self.extension.restore(None)
        self.generation, self.elapsed = checkpoint.generation, checkpoint.elapsed
        self.population, self.fitness = checkpoint.population, checkpoint.fitness
        self.set_genes = checkpoint.set_genes
        self.load_extra_state(state)


def check_target(behaviour: Behaviour, env: BatchEnv) -> None:
    """A ``stop.target`` the run can reach: a fitness within the environment's possible
    range, a success rate only where the environment defines success; a located error
    otherwise."""
    target = behaviour.learning.stop.target_in_units()
    if target is None:
        return
    path = ("learning", "stop", "target")
    low, high = env.fitness_range
    if target.unit == "fitness" and not low <= target.value <= high:
        raise SpecError([Problem(path, f"a target mean fitness of {target.value:g} is outside "
                                 f"the fitness this environment can give, [{low:g}, {high:g}]",
                                 "give a fitness within it, or the target in the units you "
                                 "mean: {success: 0.95} or {return: 475}")])
    if target.unit == "success" and getattr(behaviour.environment, "success",
                                            "terminated") == "never":
        raise SpecError([Problem(path, "a success target, but the environment defines no "
                                 "success (success: never)",
                                 "give the target as {return: ...} or {fitness: ...}")])


#: Rule bases of set genomes kept decoded (a generation's and its elites' fit many times).
_SET_RULES_KEPT = 1024


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
