"""What a run spends, and the budget that ends it: episodes, steps, seconds, a target.

:class:`~flctool.learners.metrics.Usage` counts every episode and environment step a run
spends, training and selection apart; :class:`Budget` is the run callback that ends a run
when the next generation would break ``learning.stop`` or once the selected controller's
confirmation reaches ``stop.target`` (:mod:`flctool.learners.confirmation`). Budgets count
training and selection episodes alike and are checked between generations, from counts saved
in every checkpoint, so that a run stopped by ``episodes``, ``steps`` or ``target`` is as
reproducible as one that runs all its generations; only ``seconds`` depends on the machine.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import fields
from typing import TYPE_CHECKING, Any, Protocol

from flctool.behaviour.learning import LearningConfig, StopConfig
from flctool.learners.confirmation import ConfirmedRun
from flctool.learners.metrics import GenerationResult, IntArray, Usage
from flctool.learners.run_callback import RunCallback

if TYPE_CHECKING:
    from flctool.behaviour.models import Behaviour
    from flctool.compile.controller import Controller
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


class PlannedRun(Protocol):
    """What :func:`describe_budget` reads of a run before it starts."""

    @property
    def config(self) -> LearningConfig: ...

    @property
    def behaviour(self) -> Behaviour: ...

    @property
    def controller(self) -> Controller: ...

    @property
    def fixed_rules(self) -> IntArray: ...

    @property
    def confirmation(self) -> Confirmation: ...

    def episodes_at_end(self) -> int: ...


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
        elif learner.generation + 1 < learner.config.generations:
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


def describe_budget(learner: PlannedRun) -> str:
    """What the run will spend and why, in one line for ``flctool learn`` to say: its
    training episodes (generations x population x trials, from the file or the defaults, the
    paper's protocol), for how many rules and commands, and what selection, confirmation
    and the comparison with baselines add."""
    from flctool.behaviour.located import source_of

    config = learner.config
    source_map = source_of(learner.behaviour)
    given = [key for key in ("generations", "population", "trials")
             if source_map.mark(("learning", key)) is not None
             or ("learning", key) in source_map.overrides]
    source = ("the paper's protocol: the file sets none of generations, population, trials"
              if not given else f"{', '.join(given)} as given, the rest the paper's protocol")
    free = learner.controller.n_rules - len(learner.fixed_rules)
    training = config.generations * config.population * config.trials
    confirming = learner.confirmation.episodes
    end = learner.episodes_at_end()
    selection = config.selection
    validation = (f"selection validates candidates on {selection.episodes} episodes each"
                  if selection.candidates else "no selection")
    stop = config.stop
    limit = f"; at most {stop.episodes} episodes in all (stop.episodes)" \
        if stop.episodes is not None else ""
    generations = f"{config.generations} generation{'s' if config.generations != 1 else ''}"
    return (f"budget: {generations} x {config.population} individuals x "
            f"{config.trials} trial{'s' if config.trials != 1 else ''} = {training} training "
            f"episodes ({source}) for {free} rules to learn x "
            f"{learner.controller.n_commands} commands; {validation}; the returned controller "
            f"is confirmed on {confirming} fresh episodes and compared with baselines "
            f"({end - confirming} episodes){limit}")
