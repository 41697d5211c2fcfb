"""Did the run learn anything? Its controller against baselines, on the same episodes.

When a run ends, :class:`BaselineCheck` compares the confirmed controller
(:mod:`flctool.learners.confirmation`) with controllers that need no learning: every
constant command (all learned rules fire command k), :data:`RANDOM_TABLES` random rule
tables, and any hand-made rule tables given (``flctool learn --baseline FILE``). All run on
the confirmation's own episodes, so each comparison is paired, episode by episode.

Racing keeps it cheap: every baseline runs the first :data:`SCREEN_EPISODES` confirmation
episodes; the one with the best mean there runs the rest. The run's controller has
**learned** if the 95 % t interval of its mean fitness difference to that strongest baseline,
over all the confirmation episodes, lies above zero. (Picking the strongest baseline on the
first episodes favours the baseline a little, so a verdict of learned is, if anything,
conservative.) Otherwise the run ends with status ``not_learned`` and a message that says
what to try. Every baseline episode counts in the run's usage (``baseline_episodes``).

**Settling an undecided comparison.** A controller that leads the strongest baseline, but
not clearly, may be better or lucky; 50 episodes of a task whose best controllers fail most
of them cannot tell (shoot: every run scoring 0.33-0.38 held out against 0.2-0.3 for walking
straight at the goal, 4 of 10 ended ``not_learned``). So while the difference is positive
and its interval still reaches zero, both run on as many fresh episodes again (the
confirmation's seed draw continued, so still disjoint from every other), at most
:data:`SETTLING_ROUNDS` times and only within ``stop.episodes``; the verdict is the paired
difference over all of them. Looking up to three times instead of once raises the chance of
calling a controller that is no better "learned" from 2.5 % to at most 7.5 %. A controller
that trails, or one clearly better, is decided at once.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np
from numpy.typing import NDArray

from flctool.envs.base import BatchEnv
from flctool.learners.confirmation import confirmation_seeds
from flctool.learners.metrics import IntArray, Usage
from flctool.learners.run_callback import RunCallback
from flctool.learners.trial import SparseRules, run_trial
from flctool.rollout import Estimate, mean_interval

if TYPE_CHECKING:
    from flctool.compile.controller import Controller
    from flctool.learners.confirmation import Confirmation

#: Random rule tables among the baselines.
RANDOM_TABLES = 3
#: The most times an undecided comparison doubles its episodes (the module docstring).
SETTLING_ROUNDS = 2
#: Confirmation episodes every baseline runs before the strongest one runs the rest.
SCREEN_EPISODES = 10
#: Index of the random tables' child in the run's SeedSequence (after ga, env, explore,
#: validation and confirmation).
_BASELINE_STREAM = 5


@dataclass(frozen=True)
class Verdict:
    """The comparison at the end of a run."""

    learned: bool
    baseline: str  # the strongest baseline's name
    difference: Estimate  # mean fitness of the run's controller minus the baseline's, paired
    baseline_fitness: float  # the strongest baseline's mean fitness on those episodes
    screened: dict[str, float]  # every baseline's mean fitness on the screening episodes

    def record(self) -> dict[str, Any]:
        return {"learned": self.learned, "baseline": self.baseline,
                "difference": self.difference.to_dict(),
                "baseline_fitness": self.baseline_fitness, "screened": dict(self.screened)}

    def to_dict(self) -> dict[str, Any]:
        d = self.difference
        return {**self.record(), "exact": [d.value, d.low, d.high, d.n]}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Verdict:
        value, low, high, n = data["exact"]
        return cls(bool(data["learned"]), str(data["baseline"]),
                   Estimate(float(value), float(low), float(high), int(n)),
                   float(data["baseline_fitness"]),
                   {str(k): float(v) for k, v in dict(data["screened"]).items()})


#: What to try when a run did not learn: more budget, another learner, fewer rules.
# (extend.most keeps a sized budget's extension and trials; --generations would replace them)
_BUDGET = "give it more budget (--set extend.most=200, --set trials=3, --set population=20)"
_COARSER = "or use coarser sets (fewer rules to learn)"


def _other_learners(learner: str) -> str:
    """Another learner to try: the credit learner first, which on the task suite matched or
    beat the others everywhere and alone learned where one trial says little (shoot)."""
    if learner == "credit":
        return f"try another learner (--learner hybrid or fuzzy_q), {_COARSER}"
    return ("try the credit learner (--learner credit: it pools every episode's outcome rule by "
            f"rule, for tasks where one trial says little), {_COARSER}")


def not_learned_message(verdict: Mapping[str, Any], commands: Sequence[str],
                        learner: str = "hybrid") -> str:
    """What a user reads when a run did not learn: the verdict (``Verdict.record()``, as
    run.json holds it) and what to try, which depends on the baseline that was as good (and
    on the run's ``learner``, for which other one to try).

    - A **constant command** as good as the learned controller often means the task as
      written does not need its rules (docs/environments.md: the striker's ``always
      approach`` scores 0.950 held out, its hand-made arbiter 0.936), so that is said first.
    - A **random table** as good means the trials did not tell controllers apart: a success
      or failure per trial is a noisy measure (shoot: 0.25 against 0.37 success is not
      resolved by 40 validation episodes), so measuring each on more episodes comes first.
    - A **hand-made controller** (``--baseline``) as good: start from it (``--init``).
    """
    name = str(verdict.get("baseline"))
    difference = verdict.get("difference") or {}
    high = difference.get("high")
    does = "does better" if isinstance(high, (int, float)) and high < 0 else "does as well"
    head = (f"the learned controller is not clearly better than the baseline '{name}' (mean "
            f"fitness {_number(verdict.get('baseline_fitness'))}; difference "
            f"{difference_text(difference)} over the same {difference.get('n')} episodes)")
    others = _other_learners(learner)
    if name in {f"always {command}" for command in commands}:
        advice = (f"a controller that always commands '{name.removeprefix('always ')}' "
                  f"{does}: if that is good enough, the task as written may not need these "
                  f"rules (check its outcomes and starts); to learn more, {_BUDGET}, {others}")
    elif name.startswith("random table "):
        advice = (f"a random rule table {does}, so the trials did not tell controllers apart: "
                  "measure each on more episodes (--set trials=3, --set "
                  f"selection.episodes=100), {others}")
    else:
        advice = (f"your controller '{name}' {does}: start from it (--init with that file) "
                  f"and {_BUDGET}, {others}")
    return f"{head}\n  try: {advice}"


def difference_text(difference: Mapping[str, Any]) -> str:
    """A verdict's difference as run.json holds it: ``value [low, high]``."""
    return (f"{_number(difference.get('value'))} [{_number(difference.get('low'))}, "
            f"{_number(difference.get('high'))}]")


def _number(value: object) -> str:
    return f"{value:.3f}" if isinstance(value, (int, float)) else "-"


def baseline_episodes(n_commands: int, given: int, confirmed: int) -> int:
    """The episodes the comparison with baselines takes after a confirmation of
    ``confirmed`` episodes, with ``given`` hand-made tables: every baseline on the screening
    episodes, the strongest on the rest."""
    screen = min(SCREEN_EPISODES, confirmed)
    return (n_commands + RANDOM_TABLES + given) * screen + confirmed - screen


def settling_episodes(confirmed: int) -> int:
    """The most episodes settling an undecided comparison of ``confirmed`` episodes may
    add: both controllers, every round doubling the paired episodes."""
    return 2 * confirmed * ((1 << SETTLING_ROUNDS) - 1)


class ComparedRun(Protocol):
    """What the comparison with baselines reads of the run it is part of (a
    :class:`~flctool.learners.base.Learner` is one)."""

    @property
    def controller(self) -> Controller: ...

    @property
    def rules(self) -> SparseRules: ...

    @property
    def env(self) -> BatchEnv: ...

    def keep_fixed(self, population: IntArray) -> IntArray: ...

    def rules_for(self, genes: NDArray[np.float64] | None) -> SparseRules: ...


class BaselineCheck(RunCallback[ComparedRun]):
    """Compares the run's confirmed controller with baselines when the run ends (see the
    module docstring). ``given`` are hand-made rule tables: (name, consequents (M,))."""

    def __init__(self, confirmation: Confirmation, usage: Usage, run_seed: int,
                 given: list[tuple[str, IntArray]] | None = None) -> None:
        self.confirmation = confirmation
        self.usage = usage
        self.run_seed = run_seed
        self.given = list(given or [])
        self.verdict: Verdict | None = None

    def episodes_needed(self, n_commands: int, confirmed: int) -> int:
        """The episodes the comparison takes after a confirmation of ``confirmed`` episodes
        (:func:`baseline_episodes`)."""
        return baseline_episodes(n_commands, len(self.given), confirmed)

    def on_finish(self, learner: ComparedRun) -> None:
        final = self.confirmation.final
        self.verdict = None
        if final is None or len(final.episode_fitness) < 2:
            return  # nothing confirmed (confirmation off, or no budget left): no verdict
        learned = np.array(final.episode_fitness, dtype=np.float64)
        baselines = self.baselines(learner)
        confirmed = learned.shape[0]
        limit = self.confirmation.episode_limit
        while limit is not None and confirmed >= 2 and (
                self.usage.episodes + self.episodes_needed(learner.controller.n_commands,
                                                           confirmed) > limit):
            confirmed -= 1  # the budget leaves room for a comparison on fewer episodes
        if confirmed < 2:
            return  # stop.episodes leaves no room for a comparison: no verdict
        learned = learned[:confirmed]
        seeds = self.confirmation.seeds[:confirmed]
        screen = min(SCREEN_EPISODES, confirmed)
        screened = {name: self._fitness(learner, genes, seeds[:screen])
                    for name, genes in baselines}
        means = {name: float(values.mean()) for name, values in screened.items()}
        strongest = max(means, key=lambda name: means[name])  # ties: the first listed
        genes = dict(baselines)[strongest]
        rest = self._fitness(learner, genes, seeds[screen:])
        baseline = np.concatenate([screened[strongest], rest])
        paired = learned - baseline
        difference = mean_interval(paired)
        for _ in range(SETTLING_ROUNDS):
            count = paired.shape[0]
            if not difference.low <= 0.0 < difference.value or (
                    limit is not None and self.usage.episodes + 2 * count > limit):
                break
            fresh = confirmation_seeds(self.run_seed, 2 * count)[count:]
            ahead = self._fitness(learner, final.consequents, fresh,
                                  learner.rules_for(final.sets))
            behind = self._fitness(learner, genes, fresh)
            baseline = np.concatenate([baseline, behind])
            paired = np.concatenate([paired, ahead - behind])
            difference = mean_interval(paired)
        self.verdict = Verdict(bool(difference.low > 0.0), strongest, difference,
                               float(baseline.mean()), means)

    def baselines(self, learner: ComparedRun) -> list[tuple[str, IntArray]]:
        """The baselines, in order: each constant command, the random tables, the given
        tables; rules the file gives are as given in all of them."""
        controller = learner.controller
        n_rules, n_commands = controller.n_rules, controller.n_commands
        tables: list[tuple[str, IntArray]] = [
            (f"always {name}", np.full(n_rules, k, dtype=np.intp))
            for k, name in enumerate(controller.command_names)]
        rng = np.random.default_rng(np.random.SeedSequence(self.run_seed,
                                                           spawn_key=(_BASELINE_STREAM,)))
        tables += [(f"random table {i + 1}",
                    rng.integers(n_commands, size=n_rules).astype(np.intp))
                   for i in range(RANDOM_TABLES)]
        tables += [(name, np.asarray(genes, dtype=np.intp)) for name, genes in self.given]
        return [(name, learner.keep_fixed(genes[None, :].copy())[0]) for name, genes in tables]

    def _fitness(self, learner: ComparedRun, genes: IntArray, seeds: NDArray[np.int64],
                 rules: SparseRules | None = None) -> NDArray[np.float64]:
        """Fitness per episode of the controller ``genes`` on ``seeds`` (with ``rules``, the
        file's by default), counted in usage."""
        env, consequents = learner.env, genes.tolist()
        rules = learner.rules if rules is None else rules
        trials = [run_trial(env, rules, int(seed), consequents) for seed in seeds]
        lengths = np.array([t.length for t in trials], dtype=np.int64)
        self.usage.baseline_episodes += len(trials)
        self.usage.baseline_steps += int(lengths.sum())
        fitness: NDArray[np.float64] = env.episode_fitness(
            np.array([t.ret for t in trials], dtype=np.float64), lengths,
            np.array([t.success for t in trials], dtype=np.bool_))
        return fitness

    def state_dict(self) -> dict[str, Any]:
        return {"baselines": {"given": [[name, genes.tolist()] for name, genes in self.given],
                              "verdict": None if self.verdict is None
                              else self.verdict.to_dict()}}

    def restore(self, given: list[tuple[str, IntArray]], verdict: Verdict | None) -> None:
        """Restore what :meth:`state_dict` saved, as the checkpoint reader checked it."""
        self.given, self.verdict = list(given), verdict

    def record(self) -> dict[str, Any] | None:
        return None if self.verdict is None else self.verdict.record()
