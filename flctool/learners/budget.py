"""What a run spends, and the budget that ends it: episodes, steps, seconds, a target.

:class:`~flctool.learners.metrics.Usage` counts every episode and environment step a run
spends, training and selection apart; :class:`Budget` is the run callback that ends a run
when the next generation would break ``learning.stop`` or once the selected controller's
confirmation reaches ``stop.target`` (:mod:`flctool.learners.confirmation`). Budgets count
training and selection episodes alike and are checked between generations, from counts saved
in every checkpoint, so that a run stopped by ``episodes``, ``steps`` or ``target`` is as
reproducible as one that runs all its generations; only ``seconds`` depends on the machine.

Before a run starts, :func:`plan_budget` says what it will spend and why: each number with
where it came from (``flctool validate`` and ``flctool learn`` print it).
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass, fields
from typing import TYPE_CHECKING, Any, Protocol

from flctool.behaviour.learning import (
    FuzzyQConfig,
    GeneticConfig,
    LearningConfig,
    StopConfig,
)
from flctool.learners.baselines import (
    SETTLING_ROUNDS,
    baseline_episodes,
    settling_episodes,
)
from flctool.learners.confirmation import ConfirmedRun
from flctool.learners.metrics import GenerationResult, Usage
from flctool.learners.run_callback import RunCallback

if TYPE_CHECKING:
    from flctool.behaviour.models import Behaviour
    from flctool.learners.confirmation import Confirmation
    from flctool.learners.selection import ModelSelection


class BudgetedRun(ConfirmedRun, Protocol):
    """What the budget reads of the run it is part of (a
    :class:`~flctool.learners.base.Learner` is one); a target is checked by confirming."""

    @property
    def config(self) -> LearningConfig: ...

    @property
    def elapsed(self) -> float: ...

    def episodes_per_generation(self) -> int: ...

    def planned_generations(self) -> int: ...


class Budget(RunCallback[BudgetedRun]):
    """Ends the run on ``learning.stop`` (see the module docstring): after a generation,
    ``target`` if the selected controller's confirmation reached it, else the first budget
    the next generation -- its trials, its leader's validation, the final selection and the
    confirmation -- would break.
    """

    def __init__(self, stop: StopConfig, selection: ModelSelection,
                 confirmation: Confirmation, usage: Usage,
                 reserve: Callable[[], int] = lambda: 0) -> None:
        self.stop = stop
        self.reserve = reserve  # episodes the end of the run needs after selection
        self.target = stop.target_in_units()
        self.selection = selection
        self.confirmation = confirmation
        self.usage = usage
        self.stop_reason: str | None = None  # "target", "episodes", "steps" or "seconds"

    def on_trials(self, learner: BudgetedRun, result: GenerationResult) -> None:
        del result
        if self.target is not None and self.confirmation.reaches(learner, self.target):
            self.stop_reason = "target"
        elif learner.generation + 1 < learner.planned_generations():
            self.stop_reason = self.exhausted(learner.episodes_per_generation(),
                                              learner.elapsed)

    def exhausted(self, generation_episodes: int, elapsed: float) -> str | None:
        """Which budget the next generation (``generation_episodes`` training episodes, and
        the most selection and confirmation may spend after it) would break, if any."""
        stop, usage = self.stop, self.usage
        upcoming = (generation_episodes + self.selection.most_episodes_after_generation()
                    + self.reserve())
        if stop.episodes is not None and usage.episodes + upcoming > stop.episodes:
            return "episodes"
        if stop.steps is not None and usage.episodes > 0:
            per_episode = usage.steps / usage.episodes
            if usage.steps + upcoming * per_episode > stop.steps:
                return "steps"
        if stop.seconds is not None and elapsed >= stop.seconds:
            return "seconds"
        return None

    # -- checkpoints: part of the run's selection record (its format predates this class)
    def state_dict(self) -> dict[str, Any]:
        return {"usage": self.usage.to_dict(), "stop_reason": self.stop_reason}

    def restore(self, usage: Usage, stop_reason: str | None) -> None:
        """Restore what :meth:`state_dict` saved, as the checkpoint reader checked it."""
        for counter in fields(Usage):
            setattr(self.usage, counter.name, getattr(usage, counter.name))
        self.stop_reason = stop_reason


@dataclass(frozen=True)
class Setting:
    """One setting of a run's budget: its key, value, and where the value came from."""

    key: str  # as the file writes it: "generations", "selection.episodes"
    value: int | None
    #: "the file's line 12", "--set trials" (a command-line override), "overrides (trials)"
    #: (one given in Python), "given" (a behaviour built in Python), or "default"
    source: str

    def text(self) -> str:
        return f"{self.key} {self.value} ({self.source})"


#: The settings a budget statement names, as field paths under ``learning``.
_SETTINGS = (("generations",), ("population",), ("trials",), ("selection", "candidates"),
             ("selection", "episodes"), ("selection", "race"), ("selection", "confirmation"),
             ("stop", "episodes"))


@dataclass(frozen=True)
class BudgetPlan:
    """What a run will spend, and why: :func:`plan_budget` makes it before the run starts
    (``flctool validate`` and ``flctool learn`` say it)."""

    settings: dict[str, Setting]
    rules: int  # rules to learn (M less the rules the file gives)
    commands: int  # K
    training: int  # generations x population x trials
    selection: int  # the most validation episodes selection and its race may spend
    confirmation: int
    baselines: int  # the comparison with baselines, after a full confirmation
    limit: int | None  # stop.episodes
    #: With ``learning.extend``: (the most generations, the patience); None: exactly
    #: ``generations``.
    extension: tuple[int, int] | None = None
    #: Whether an extended run's room goes to fresh attempts (the genetic learners).
    attempts: bool = False
    #: ``extend.most`` as given (None: it follows from the problem's size).
    most_given: int | None = None
    #: Whether the run has all of its most generations (LearningConfig.runs_to_most).
    to_most: bool = False
    #: fuzzy_q under ``exploration.hold: auto``: the most generations once the run holds its
    #: draws, with room for fresh attempts (None: not such a run).
    held_most: int | None = None

    @property
    def most(self) -> int:
        """The most episodes the run may spend in all (``stop.episodes`` if lower)."""
        total = self.training + self.selection + self.confirmation + self.baselines
        return total if self.limit is None else min(total, self.limit)

    def lines(self) -> list[str]:
        """The statement, first line a summary, the rest indented: every number and where
        it came from."""
        s = self.settings
        protocol = [s[key] for key in ("generations", "population", "trials")]
        # a sized budget's defaults (extend, two trials) are not the paper's protocol
        defaults = "the paper's protocol" if self.extension is None else "the defaults"
        source = (("the paper's protocol: " if self.extension is None else "")
                  + "the file gives none of them"
                  if all(x.source == "default" for x in protocol) else
                  ", ".join(f"{x.key} from {x.source}" for x in protocol
                            if x.source != "default") + f", the rest {defaults}")
        generations = _count(s["generations"].value, "generation")
        if self.extension is not None:
            most, patience = self.extension
            least = s["generations"].value
            if self.most_given is None:
                why = "from the problem's size unless extend.most is given"
            elif self.most_given == most:
                why = "from extend.most"
            else:
                why = f"since extend.most {self.most_given} is below generations"
            if self.to_most:
                generations = (f"{most} generations ({why}; its credit only grows with more "
                               "episodes, so the run has them all)")
            else:
                fresh = (f", then fresh attempts of {least} while they fit" if self.attempts
                         else "")
                held = ("" if self.held_most is None else
                        f"; if its exploration begins to hold (no reward signal), fresh "
                        f"attempts of {least} from there, up to {self.held_most}")
                generations = (f"{least} to {most} generations (on past {least} until "
                               f"{patience} pass without a better selected controller{fresh}; "
                               f"{most} {why}{held})")
        lines = [f"budget: at most {self.most:,} episodes: {self.training:,} training, up to "
                 f"{self.selection:,} selection, {self.confirmation} confirmation and "
                 f"{self.baselines} against baselines, for {self.rules} rules to learn x "
                 f"{self.commands} commands",
                 f"  training: {generations} x {s['population'].value} individuals x "
                 f"{_count(s['trials'].value, 'trial')} ({source})"]
        if s["selection.candidates"].value:
            race = s["selection.race"]
            raced = (f"; the best raced on to {race.value} episodes"
                     if (race.value or 0) > (s["selection.episodes"].value or 0)
                     else "; no race")
            lines.append(f"  selection: each generation's leader and the last "
                         f"{s['selection.candidates'].value} candidates on "
                         f"{s['selection.episodes'].value} validation episodes each{raced} "
                         f"({', '.join(s[k].text() for k in _SELECTION)})")
        else:
            lines.append(f"  selection: none ({s['selection.candidates'].text()})")
        lines.append(f"  confirmation: {s['selection.confirmation'].text()}; the comparison "
                     f"with baselines runs every constant command and random table on 10 of "
                     f"its episodes, the strongest on the rest, and while the learned "
                     f"controller leads it but not clearly, both on as many again (at most "
                     f"{SETTLING_ROUNDS} times)")
        if self.limit is not None:
            lines.append(f"  limit: {s['stop.episodes'].text()}")
        return lines


_SELECTION = ("selection.candidates", "selection.episodes", "selection.race")


def _count(number: int | None, noun: str) -> str:
    return f"{number} {noun}{'' if number == 1 else 's'}"


def plan_budget(behaviour: Behaviour, baselines: int = 0) -> BudgetPlan:
    """The budget a run of ``behaviour`` will use (``baselines``: hand-made tables given
    with ``--baseline``), each setting with where it came from: a line of the file, a
    ``--set``, or the default (the paper's protocol for generations, population, trials).

    Selection's figure is a bound: every generation's leader and the last candidates and
    elites validated (a run usually meets fewer distinct leaders), and the race
    (:func:`~flctool.learners.selection.race_cost`) over all of them."""
    from flctool.behaviour.located import source_of
    from flctool.learners.extension import HELD_ATTEMPTS, held_most, most_generations
    from flctool.learners.selection import race_cost

    config = behaviour.learning
    source_map = source_of(behaviour)

    def setting(path: tuple[str, ...]) -> Setting:
        section: Any = config
        for part in path[:-1]:
            section = getattr(section, part)
        value = getattr(section, path[-1])
        if path == ("selection", "race") and value is None:
            value = config.race_episodes  # unset: the learner's reading
        full = ("learning", *path)
        mark = source_map.mark(full)
        default = (config.default_race if path == ("selection", "race")
                   else type(section).model_fields[path[-1]].default)
        if path == ("trials",) and value == config.sized_trials:
            default = value  # what a file without a budget gets
        given = next((where for given, where in source_map.overrides.items()
                      if full[:len(given)] == given), None)
        if given is not None:  # "command line (--set trials)": the option says it
            inner = re.fullmatch(r"command line \((.*)\)", given)
            source = inner.group(1) if inner else given
        elif mark is not None:
            source = f"the file's line {mark[0]}"
        else:
            source = "default" if value == default else "given"
        return Setting(".".join(path), value, source)

    settings = {".".join(path): setting(path) for path in _SETTINGS}
    selection = config.selection
    rules, commands = len(behaviour.missing_rules()), len(behaviour.output.commands)
    extension = None
    generations = config.generations
    held = None
    if config.extend is not None:
        generations = config.extend.most or most_generations(rules, commands, generations)
        generations = max(generations, config.generations)
        extension = (generations, config.extend.patience)
        if (isinstance(config, FuzzyQConfig) and config.hold == "auto"
                and config.extend.most is None and not config.runs_to_most):
            # room a run gets once it holds its draws (FuzzyQLearner.advance)
            held = held_most(generations, config.generations, HELD_ATTEMPTS)
            generations = held
    validated = (generations + selection.candidates + int(getattr(config, "elites", 1))
                 if selection.candidates else 0)
    most_selection = validated * selection.episodes
    if config.race_episodes > selection.episodes:
        most_selection += race_cost(validated, selection.episodes, config.race_episodes)
    confirming = selection.confirmation
    return BudgetPlan(settings, rules, commands,
                      generations * config.population * config.trials, most_selection,
                      confirming,
                      baseline_episodes(commands, baselines, confirming)
                      + settling_episodes(confirming) if confirming >= 2 else 0,
                      config.stop.episodes, extension,
                      isinstance(config, GeneticConfig),
                      None if config.extend is None else config.extend.most,
                      config.runs_to_most, held)


def describe_budget(behaviour: Behaviour, baselines: int = 0) -> str:
    """:func:`plan_budget`'s statement, as ``flctool validate`` and ``learn`` print it."""
    return "\n".join(plan_budget(behaviour, baselines).lines())
