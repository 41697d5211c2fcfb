"""Fuzzy Q-learning (paper Sec. III, eq. 4-9) and the ``fuzzy_q`` learner built on it.

Every rule m has one strength q_m^k per command k (eq. 4). In a state S with normalised
activations phi_m = alpha_m(S) / sum(alpha) and chosen commands k_m of the firing rules:

- eq. 5: ``Q(S, a) = sum_m phi_m q_m^{k_m}``
- eq. 6: ``dQ = r + gamma * max Q(S', .) - Q(S, a)``, with ``max Q(S', .) = sum_m phi_m(S')
  max_k q_m^k`` (each rule's best strength, weighted by the next state's activations); a
  terminal step has no next state, so ``dQ = r - Q(S, a)``. A truncated step (time limit)
  does bootstrap.
- eq. 7-9, read as in Glorennec & Jouffe's fuzzy Q-learning: a *replacing* eligibility trace
  per (rule, command), ``e(m, k) <- phi_m(S_t)`` for the chosen k of each firing rule and
  ``e <- lambda * gamma * e`` for every other pair, then ``q += alpha * dQ * e`` for all
  pairs. (Read literally, eq. 9 multiplies the trace by the *current* activation, which makes
  it inert; with ``lambda = 0`` both readings are eq. 7 exactly.) Traces start at zero in
  every trial and are not cut after exploratory choices (Peng's rather than Watkins' Q(lambda));
  traces that have decayed below :data:`TRACE_FLOOR` are dropped, which changes q by less than
  ``alpha * |dQ| * 1e-12``.

The q table lives in a flat Python list (index ``m * K + k``) because the per-step work
touches a handful of entries, where plain floats beat numpy calls.
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from flctool.behaviour.learning import FuzzyQConfig, QConfig
from flctool.behaviour.models import Behaviour
from flctool.envs.base import BatchEnv
from flctool.errors import LearnError
from flctool.learners.base import GenerationResult, Learner
from flctool.learners.checkpoint import damaged
from flctool.learners.extension import HELD_ATTEMPTS
from flctool.learners.ga import GeneticAlgorithm
from flctool.learners.set_genes import SetOperators, initial_set_genes
from flctool.learners.trial import Chooser, add_in_order, run_trial

FloatArray = NDArray[np.float64]

TRACE_FLOOR = 1e-12
_BLOCK = 1024  # uniforms drawn per refill of an exploration stream
#: How a fuzzy_q run that could not learn by exploring is told (docs/learning.md, "Why fuzzy_q
#: misses Acrobot"): it has had no reward signal when every training episode of this many
#: generations scored the same, below what its greedy controllers validate; its Boltzmann
#: exploration has locked in when its greedy controller has not changed for this many
#: generations while a rule's strengths differ (median) by at least :data:`LOCKED_RATIO`
#: temperatures, where the docs' rule of thumb wants about one: a command that far below the
#: strongest is tried with probability below e^-10, so it keeps the strength it had when last
#: tried.
LOCKED_GENERATIONS = 5
LOCKED_RATIO = 10.0


class FuzzyQ:
    """A q table (M, K) with replacing eligibility traces, learning by eq. 5-9."""

    def __init__(self, q: FloatArray, alpha: float, gamma: float, lambda_: float) -> None:
        self.n_rules, self.n_commands = (int(n) for n in q.shape)
        self.q: list[float] = [float(v) for v in np.asarray(q, dtype=np.float64).ravel()]
        self.alpha = alpha
        self.gamma = gamma
        self.decay = lambda_ * gamma
        self.trace: dict[int, float] = {}  # m * K + k -> e(m, k); absent means 0

    def table(self) -> FloatArray:
        """The q table as an (M, K) array (a copy)."""
        return np.array(self.q, dtype=np.float64).reshape(self.n_rules, self.n_commands)

    def traces(self) -> FloatArray:
        """The eligibility traces as an (M, K) array (a copy)."""
        e = np.zeros(self.n_rules * self.n_commands)
        for index, value in self.trace.items():
            e[index] = value
        return e.reshape(self.n_rules, self.n_commands)

    def load(self, q: FloatArray, traces: FloatArray) -> None:
        self.q = [float(v) for v in np.asarray(q, dtype=np.float64).ravel()]
        flat = np.asarray(traces, dtype=np.float64).ravel()
        self.trace = {int(i): float(flat[i]) for i in np.flatnonzero(flat)}

    def state_dict(self) -> dict[str, Any]:
        """The q table and traces as JSON-compatible lists (checkpoints)."""
        return {"q": self.table().tolist(), "traces": self.traces().tolist()}

    def load_state_dict(self, state: dict[str, Any]) -> None:
        self.load(np.array(state["q"], dtype=np.float64),
                  np.array(state["traces"], dtype=np.float64))

    def reset_traces(self) -> None:
        self.trace.clear()

    def value(self, rules: list[int], phi: list[float], commands: list[int]) -> float:
        """Q(S, a) of eq. 5 for the firing rules, their phi and chosen commands."""
        q, width = self.q, self.n_commands
        return add_in_order(p * q[m * width + k]
                            for m, p, k in zip(rules, phi, commands, strict=True))

    def greedy_value(self, rules: list[int], phi: list[float]) -> float:
        """max_a Q(S, a) of eq. 6: each firing rule's best q, weighted by phi."""
        q, width = self.q, self.n_commands
        return add_in_order(p * max(q[m * width : m * width + width])
                            for m, p in zip(rules, phi, strict=True))

    def learn(self, rules: list[int], phi: list[float], commands: list[int], reward: float,
              next_rules: list[int], next_phi: list[float], terminal: bool) -> float:
        """One step of eq. 6-9; returns the TD error dQ."""
        q, width, trace = self.q, self.n_commands, self.trace
        target = reward if terminal else reward + self.gamma * self.greedy_value(next_rules,
                                                                                 next_phi)
        delta = target - self.value(rules, phi, commands)  # eq. 6
        decay = self.decay
        if decay > 0.0:  # eq. 8, "otherwise" branch
            for index in list(trace):
                e = trace[index] * decay
                if e < TRACE_FLOOR:
                    del trace[index]
                else:
                    trace[index] = e
        else:
            trace.clear()
        for m, p, k in zip(rules, phi, commands, strict=True):  # eq. 8, replacing
            trace[m * width + k] = p
        step = self.alpha * delta
        for index, e in trace.items():  # eq. 7 and 9
            q[index] += step * e
        return delta


class UniformStream:
    """Uniform [0, 1) numbers from a generator, drawn in blocks (one numpy call per block)."""

    def __init__(self, rng: np.random.Generator) -> None:
        self.rng = rng
        self._block: list[float] = []
        self._next = 0

    def __call__(self) -> float:
        if self._next == len(self._block):
            self._block = self.rng.random(_BLOCK).tolist()
            self._next = 0
        value = self._block[self._next]
        self._next += 1
        return value


class BoltzmannChooser:
    """Each firing rule picks command k with probability ``exp(q_m^k / T) / sum_j ...``."""

    def __init__(self, fuzzy_q: FuzzyQ, temperature: float, uniform: UniformStream) -> None:
        self.fuzzy_q = fuzzy_q
        self.temperature = temperature
        self.uniform = uniform

    def choose(self, rules: list[int]) -> list[int]:
        q, width = self.fuzzy_q.q, self.fuzzy_q.n_commands
        choices = []
        for m in rules:
            row = q[m * width : m * width + width]
            top = max(row)
            weights = [math.exp((v - top) / self.temperature) for v in row]
            threshold = self.uniform() * add_in_order(weights)
            k, cumulative = 0, weights[0]
            while cumulative <= threshold and k < width - 1:
                k += 1
                cumulative += weights[k]
            choices.append(k)
        return choices


class HeldChooser:
    """Another chooser, except that each rule keeps the command it drew for ``hold`` of its
    firings, or with ``hold=None`` for a heavy-tailed number of them: n or more with
    probability 1/n (temporally-extended exploration, after Dabney, Ostrovski & Barreto's
    ez-greedy, whose zeta-distributed durations have the same tail). One per episode.

    A fresh draw every step makes an exploring episode a random walk around the greedy
    controller, which a task needing one command kept up for a while (Acrobot's swing)
    hardly ever sees done; a held draw plays it out (docs/learning.md, "How long a rule
    holds an explored command").
    """

    def __init__(self, chooser: Chooser, hold: int | None, uniform: UniformStream) -> None:
        self.chooser = chooser
        self.hold = hold
        self.uniform = uniform
        self.command: dict[int, int] = {}
        self.left: dict[int, int] = {}  # firings each rule keeps its command for

    def choose(self, rules: list[int]) -> list[int]:
        left, command = self.left, self.command
        fresh = [m for m in rules if not left.get(m)]
        if fresh:
            for m, k in zip(fresh, self.chooser.choose(fresh), strict=True):
                command[m] = k
                left[m] = self.hold or int(1.0 / (1.0 - self.uniform()))
        for m in rules:
            left[m] -= 1
        return [command[m] for m in rules]


class FixedChooser:
    """Another chooser, except that rules the file gives always fire their given command
    (they are never explored)."""

    def __init__(self, chooser: BoltzmannChooser | EpsilonGreedyChooser,
                 fixed: dict[int, int]) -> None:
        self.chooser = chooser
        self.fixed = fixed

    def choose(self, rules: list[int]) -> list[int]:
        choices = self.chooser.choose(rules)
        fixed = self.fixed
        return [fixed.get(m, k) for m, k in zip(rules, choices, strict=True)]


class EpsilonGreedyChooser:
    """Each firing rule explores (a uniform command) with probability epsilon, otherwise takes
    its strongest command (ties broken uniformly)."""

    def __init__(self, fuzzy_q: FuzzyQ, epsilon: float, uniform: UniformStream) -> None:
        self.fuzzy_q = fuzzy_q
        self.epsilon = epsilon
        self.uniform = uniform

    def choose(self, rules: list[int]) -> list[int]:
        q, width = self.fuzzy_q.q, self.fuzzy_q.n_commands
        choices = []
        for m in rules:
            if self.uniform() < self.epsilon:
                choices.append(min(int(self.uniform() * width), width - 1))
                continue
            row = q[m * width : m * width + width]
            top = max(row)
            best = [k for k, v in enumerate(row) if v == top]
            pick = best[0] if len(best) == 1 else best[min(int(self.uniform() * len(best)),
                                                               len(best) - 1)]
            choices.append(pick)
        return choices


def new_fuzzy_q(config: QConfig, n_rules: int, n_commands: int) -> FuzzyQ:
    """A q table (M, K) filled with ``q.initial``, learning with ``q``'s alpha, gamma and
    lambda (``config`` is ``learning.q``)."""
    return FuzzyQ(np.full((n_rules, n_commands), config.initial), config.alpha, config.gamma,
                  config.lambda_)


def boltzmann_greediness(table: FloatArray, temperature: float,
                         initial: float) -> tuple[float, float] | None:
    """How greedy Boltzmann exploration at ``temperature`` is over the rules whose strengths
    have moved from ``initial`` (None if none has): the mean probability that such a rule picks
    its strongest command, and the median difference between its strongest and weakest
    command's strength (what the docs' rule of thumb sets the temperature to)."""
    moved = table[np.any(table != initial, axis=1)]
    if moved.shape[0] == 0:
        return None
    weights = np.exp((moved - moved.max(axis=1, keepdims=True)) / temperature)
    share = float(np.mean(1.0 / weights.sum(axis=1)))  # the strongest command's weight is 1
    gap = float(np.median(moved.max(axis=1) - moved.min(axis=1)))
    return share, gap


def locked_text(record: dict[str, Any]) -> str:
    """What ``flctool learn`` says of a run whose exploration locked in (its
    :meth:`FuzzyQLearner.exploration_record`)."""
    gap = record["strength_gap"]
    return (f"the greedy controller has not changed since generation {record['greedy_since']}, "
            f"and a rule's strengths differ by {gap:.3g} (median) against a temperature of "
            f"{record['level']:g}, so rules pick their strongest command "
            f"{record['greedy_share']:.1%} of the time on average and the commands rarely "
            "tried keep the strengths they had when last tried. If the controller falls short, "
            f"raise learning.q.temperature towards {gap:.2g} (with more generations), or try "
            "--learner credit")


def unrewarded_text(record: dict[str, Any]) -> str:
    """What ``flctool learn`` says of a run whose training episodes have all scored the same
    for :data:`LOCKED_GENERATIONS` generations (its :meth:`FuzzyQLearner.exploration_record`)."""
    since = ("in the whole run" if record["varied_at"] < 0
             else f"since generation {record['varied_at'] + 1}")
    hold = record.get("hold")
    per_step = hold == 1 or (hold == "auto" and record.get("held_from") is None)
    exploring = "exploring one step at a time" if per_step else "exploring"
    held = ("learning.exploration.hold: zeta (each rule keeps a drawn command for a while), "
            if per_step else "")
    return (f"every training episode {since} scored the same (fitness {record['fitness']:g}): "
            f"{exploring} never reached what the reward pays for, so the strengths have "
            "nothing to tell the commands apart by, and best.yaml is the greedy controller "
            f"that validated best. Try {held}--learner credit or hybrid (they try whole rule "
            "tables, whose episodes differ), or a reward that pays for progress")


def held_text(record: dict[str, Any]) -> str | None:
    """What ``flctool learn`` says of a run that ``exploration.hold: auto`` began to hold the
    draws of (its :meth:`FuzzyQLearner.exploration_record`), if it did."""
    if record.get("held_from") is None:
        return None
    start = record["held_from"]
    return ("exploring one step at a time, every training episode of the "
            f"{LOCKED_GENERATIONS} or more generations before generation {start} scored the "
            "same, below what the greedy controllers validate (no reward signal), so from "
            f"generation {start} each rule held the commands it drew for a while, its "
            "strengths started afresh, in fresh attempts while they fit "
            "(learning.exploration.hold: auto)")


def exploration_advice(record: dict[str, Any]) -> tuple[str, str] | None:
    """What ``flctool learn`` tells a run by its exploration record, as (what happened, the
    text), if anything: no reward signal first, since it explains a lock-in too."""
    if record.get("unrewarded"):
        return "no reward signal", unrewarded_text(record)
    if record.get("locked"):
        return "exploration locked in", locked_text(record)
    return None


def greedy_consequents(table: FloatArray) -> NDArray[np.intp]:
    """Each rule's strongest command (M,), ties to the lowest index: the learned controller."""
    consequents: NDArray[np.intp] = np.argmax(table, axis=1).astype(np.intp)
    return consequents


class FuzzyQLearner(Learner):
    """Pure fuzzy Q-learning: one controller, each rule's command drawn by exploration and
    held for ``exploration.hold`` of its firings (:class:`HeldChooser`; every step under the
    paper's protocol). Under ``auto``, a run that begins to hold starts its strengths afresh,
    and again in each fresh attempt after (:meth:`advance`).

    A generation is ``population x trials`` episodes, so a generation costs what the GAs'
    does; ``common_starts`` does not apply. After each generation the exploration parameter
    (Boltzmann temperature ``q.temperature`` or ``exploration.epsilon``) is multiplied by
    ``exploration.decay``, down to ``exploration.minimum``. The learned controller is the
    greedy one (each rule's strongest command); its fitness in the run records is the
    generation's mean episode fitness, measured while exploring, so the hall of fame ranks
    the greedy controllers by recency and model selection validates them. Rules the file
    gives always fire their given command: they are never explored.

    With ``learning.sets`` the q table is paired with an outer search over the sets, because
    q values belong to rules, not to positions: a generation is ``population`` set genomes,
    each acting in ``trials`` exploring episodes that all teach the one shared q table; a
    set genome's fitness is the mean of its episodes, and between generations the genomes
    are bred by the genetic learners' GA (one elite, crossover probability 0.2, the set
    operators of :mod:`flctool.learners.set_genes`). The learned controller is the greedy one
    with the generation's best set genome. A generation costs what it does without sets.
    """

    name: ClassVar[str] = "fuzzy_q"
    config: FuzzyQConfig
    rank_by: ClassVar[str] = "recency"  # exploring fitness says little of the greedy one
    fuzzy_q: FuzzyQ

    def __init__(self, behaviour: Behaviour, env: BatchEnv) -> None:
        super().__init__(behaviour, env)
        self.fuzzy_q = self.fresh_strengths()
        self.fixed = dict(zip(self.fixed_rules.tolist(), self.fixed_commands.tolist(),
                              strict=True))
        self.population = self.greedy()
        #: The generation whose q table first gave the current greedy controller.
        self.greedy_since = 0
        #: The last generation whose training episodes did not all score what every earlier
        #: one scored (-1: none has yet).
        self.varied_at = -1
        #: The generation from which ``exploration.hold: auto`` holds the draws (None: not yet).
        self.held_from: int | None = None
        # Learning the sets too: a GA over set genomes whose every trial is a fuzzy
        # Q-learning episode (see the class docstring).
        self.set_operators: SetOperators | None = None
        self.set_population: FloatArray | None = None
        self.set_fitness: FloatArray | None = None
        sets = self.config.sets
        if self.codec is not None and sets is not None:
            self.set_operators = SetOperators(self.codec.slices, sets.mutation, sets.sigma)
            self.set_population = initial_set_genes(self.rngs["ga"], self.config.population,
                                                    self.codec.size, sets.sigma)
            self.set_fitness = np.zeros(self.config.population)
            self.set_genes = self.set_population[:1].copy()

    def start_from(self, population: NDArray[np.intp] | None = None,
                   strengths: FloatArray | None = None) -> None:
        """A warm start from a q table (see :meth:`Learner.start_from`); fuzzy_q's one
        controller is the table's greedy one, so it takes no population."""
        if population is not None:
            raise LearnError("the fuzzy_q learner starts from a q table, not a population",
                             hint="give strengths: its greedy controller is the first")
        super().start_from(None, strengths)
        self.population = self.greedy()

    def fresh_strengths(self) -> FuzzyQ:
        """A q table for this run's rules and commands, every strength at ``q.initial``."""
        return new_fuzzy_q(self.config.q, self.controller.n_rules, self.controller.n_commands)

    def greedy(self) -> NDArray[np.intp]:
        """The greedy controller (1, M): each rule's strongest command, given rules as given."""
        return self.keep_fixed(greedy_consequents(self.fuzzy_q.table())[None, :])

    def exploration(self, generation: int) -> float:
        """The temperature or epsilon used in ``generation``."""
        explore = self.config.exploration
        start = (self.config.q.temperature if explore.policy == "boltzmann"
                 else explore.epsilon)
        return max(explore.minimum, start * explore.decay ** generation)

    def evaluate(self, generation: int) -> GenerationResult:
        episodes = self.config.population * self.config.trials
        seeds = self.episode_seeds(episodes, 1, common=False)[:, 0].tolist()
        uniform = UniformStream(np.random.default_rng(
            int(self.rngs["explore"].integers(2**63))))
        level = self.exploration(generation)
        policy = self.config.exploration.policy
        chooser: BoltzmannChooser | EpsilonGreedyChooser | FixedChooser
        if policy == "boltzmann" and level > 0.0:
            chooser = BoltzmannChooser(self.fuzzy_q, level, uniform)
        else:  # epsilon-greedy; a temperature decayed to zero is plain greedy
            epsilon = min(level, 1.0) if policy == "epsilon_greedy" else 0.0
            chooser = EpsilonGreedyChooser(self.fuzzy_q, epsilon, uniform)
        if self.fixed:
            chooser = FixedChooser(chooser, self.fixed)
        hold = self.hold_now()
        returns = np.empty(episodes)
        lengths = np.empty(episodes, dtype=np.int64)
        success = np.empty(episodes, dtype=np.bool_)
        trials = self.config.trials
        for i, seed in enumerate(seeds):
            # with learned sets, set genome i // trials acts in its trials
            rules = (self.rules if self.set_population is None
                     else self.rules_for(self.set_population[i // trials]))
            # a fresh draw every step needs no holding (and draws as it always has)
            episode_chooser = chooser if hold == 1 else HeldChooser(chooser, hold, uniform)
            trial = run_trial(self.env, rules, seed, None, chooser=episode_chooser,
                              td=self.fuzzy_q)
            returns[i], lengths[i], success[i] = trial.ret, trial.length, trial.success
        fitness = self.env.episode_fitness(returns, lengths, success)
        if fitness.max() > fitness.min() or (generation > 0 and fitness[0] != self.fitness[0]):
            self.varied_at = generation
        greedy = self.greedy()
        if not np.array_equal(greedy, self.population):
            self.greedy_since = generation
        self.population = greedy
        self.fitness = np.array([float(np.mean(fitness))])
        if self.set_population is not None:
            self.set_fitness = fitness.reshape(-1, trials).mean(axis=1)
            best = int(np.argmax(self.set_fitness))
            self.set_genes = self.set_population[best : best + 1].copy()
        return GenerationResult(fitness, episodes, int(lengths.sum()))

    def hold_now(self) -> int | None:
        """How many firings a drawn command is held for in the next generation (None: a
        heavy-tailed number, see :class:`HeldChooser`)."""
        hold = self.config.hold
        if hold == "auto":
            return 1 if self.held_from is None else None
        return None if hold == "zeta" else hold

    def unrewarded(self) -> bool:
        """Whether every training episode of the last :data:`LOCKED_GENERATIONS` generations
        or more scored the same, below what the greedy controllers validate. Episodes that
        all score the same say nothing of the commands -- unless they all score as well as
        the greedy controllers validate (CartPole balanced for all 500 steps)."""
        best = self.selection.best
        return (self.generation - self.varied_at >= LOCKED_GENERATIONS and best is not None
                and best.validation_value() > float(self.fitness[0]))

    def advance(self) -> None:
        """Under ``exploration.hold: auto``, hold the draws from now on, with the strengths
        started afresh from ``q.initial`` and room for :data:`HELD_ATTEMPTS` fresh attempts,
        if the run has had no reward signal; start the strengths afresh when a held run
        begins a fresh attempt; breed the set genomes, if the run learns the sets. The
        exploration schedule follows the generation number."""
        if self.config.hold == "auto" and self.held_from is None and self.unrewarded():
            # Exploring one step at a time has not reached what the reward pays for; commands
            # held for a while may (the GAs' restarts answer a stalled search alike). The
            # strengths start afresh: they have all fallen alike, and the first commands held
            # to the goal would rise so far above the rest that exploration locked in at once.
            self.held_from = self.generation + 1
            self.fuzzy_q = self.fresh_strengths()
            # a fresh attempt, with the generations of one, and room for more after it: each
            # ends on a good controller by luck about half the time (HELD_ATTEMPTS)
            self.extension.open_attempts(self.held_from, HELD_ATTEMPTS)
            self.extension.begin_attempt(self.held_from)
        elif self.held_from is not None and self.extension.begins_attempt(self.generation + 1):
            # the attempt ended without a better selected controller: start afresh, holding
            self.fuzzy_q = self.fresh_strengths()
        if self.set_population is None or self.set_fitness is None:
            return
        # The GA of the genetic learners on set genomes alone (no consequents to breed).
        none = np.zeros((self.set_population.shape[0], 0), dtype=np.intp)
        _, genes = GeneticAlgorithm(SET_CROSSOVER, SET_ELITES).breed_genomes(
            self.rngs["ga"], none, self.set_fitness, _unchanged, _unchanged_child,
            self.set_population, self.set_operators)
        assert genes is not None
        self.set_population = genes

    def exploration_record(self) -> dict[str, Any]:
        """What run.json shows of the exploration (:data:`LOCKED_GENERATIONS`): its policy,
        level in the last generation and hold, the generation it began to hold at, the
        generation the greedy controller last changed at, the last one whose training episodes
        scored differently and whether the run has had no reward signal since, and, under
        Boltzmann exploration, how greedy it has become and whether it has locked in."""
        policy = self.config.exploration.policy
        level = self.exploration(max(self.generation, 0))
        record: dict[str, Any] = {
            "policy": policy, "level": level, "hold": self.config.hold,
            "held_from": self.held_from, "greedy_since": self.greedy_since,
            "varied_at": self.varied_at, "fitness": float(self.fitness[0]),
            "unrewarded": self.unrewarded(), "locked": False}
        if policy != "boltzmann" or level <= 0.0:
            return record
        greediness = boltzmann_greediness(self.fuzzy_q.table(), level, self.config.q.initial)
        if greediness is None:
            return record
        share, gap = greediness
        unchanged = self.generation - self.greedy_since
        record.update(greedy_share=share, strength_gap=gap,
                      locked=unchanged >= LOCKED_GENERATIONS and gap >= LOCKED_RATIO * level)
        return record

    def selection_record(self) -> dict[str, Any]:
        return {**super().selection_record(), "exploration": self.exploration_record()}

    def extra_state(self) -> dict[str, Any]:
        state = {**super().extra_state(), "greedy_since": self.greedy_since,
                 "varied_at": self.varied_at, "held_from": self.held_from}
        if self.set_population is not None and self.set_fitness is not None:
            state["set_population"] = self.set_population.tolist()
            state["set_fitness"] = self.set_fitness.tolist()
        return state

    def load_extra_state(self, state: dict[str, Any]) -> None:
        super().load_extra_state(state)
        # a checkpoint of a version that kept neither count: count from the resumed generation
        self.greedy_since = self._generation_in(state, "greedy_since", self.generation, -1)
        self.varied_at = self._generation_in(state, "varied_at", self.generation, -1)
        held_from = state.get("held_from")  # absent from older checkpoints: not yet held
        self.held_from = (None if held_from is None
                          else self._generation_in(state, "held_from", None, 1, 1))
        if self.held_from is not None:
            self.extension.open_attempts(self.held_from, HELD_ATTEMPTS)
        if self.set_population is None:
            return
        shape = self.set_population.shape
        try:
            genes = np.array(state["set_population"], dtype=np.float64)
            fitness = np.array(state["set_fitness"], dtype=np.float64)
        except (KeyError, TypeError, ValueError) as exc:
            raise damaged(f"has no readable set population ({exc!r})") from None
        if genes.shape != shape or fitness.shape != shape[:1] or not (
                np.isfinite(genes).all() and np.isfinite(fitness).all()) or (
                genes.size and not (genes.min() >= -1.0 and genes.max() <= 1.0)):
            raise damaged(f"is damaged: its set population is not {shape[0]} x {shape[1]} "
                          "genes in [-1, 1] with a finite fitness each")
        self.set_population, self.set_fitness = genes, fitness

    def _generation_in(self, state: dict[str, Any], key: str, default: int | None,
                       lowest: int, past: int = 0) -> int:
        """``state[key]`` (``default`` if absent), checked to be a generation from ``lowest``
        to ``past`` after the checkpoint's."""
        value = state.get(key, default)
        if isinstance(value, bool) or not isinstance(value, int) or not (
                lowest <= value <= self.generation + past):
            raise damaged(f"is damaged: its {key} is not a generation of the run")
        return value


#: The set genomes' GA under fuzzy_q (paper Sec. IV's crossover probability and one elite).
SET_CROSSOVER = 0.2
SET_ELITES = 1


def _unchanged(rng: np.random.Generator, a: NDArray[np.intp], b: NDArray[np.intp],
               ) -> NDArray[np.intp]:
    return a


def _unchanged_child(rng: np.random.Generator, child: NDArray[np.intp]) -> NDArray[np.intp]:
    return child
