"""What a run spends, and the budget that ends it: episodes, steps, seconds, a target.

:class:`Usage` counts every episode and environment step a run spends, training and
selection apart; :class:`Budget` is the run callback that ends a run when the next generation
would break ``learning.stop`` or once a controller reaches ``stop.target``. Budgets count
training and selection episodes alike and are checked between generations, from counts saved
in every checkpoint, so that a run stopped by ``episodes``, ``steps`` or ``target`` is as
reproducible as one that runs all its generations; only ``seconds`` depends on the machine.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from flctool.learners.callbacks import RunCallback
from flctool.spec.learning import StopConfig

if TYPE_CHECKING:
    from flctool.learners.base import GenerationResult, Learner
    from flctool.learners.checkpoint import SelectionState
    from flctool.learners.selection import ModelSelection


@dataclass
class Usage:
    """Episodes and environment steps spent, for training and for selection."""

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


class Budget(RunCallback):
    """Ends the run on ``learning.stop`` (see the module docstring): after a generation,
    ``target`` if the selected controller reached it, else the first budget the next
    generation -- its trials, its leader's validation and the final selection -- would break.
    """

    def __init__(self, stop: StopConfig, selection: ModelSelection, usage: Usage) -> None:
        self.stop = stop
        self.selection = selection
        self.usage = usage
        self.stop_reason: str | None = None  # "target", "episodes", "steps" or "seconds"

    def on_trials(self, learner: Learner, result: GenerationResult) -> None:
        del result
        if self.reached_target():
            self.stop_reason = "target"
        elif learner.generation + 1 < learner.config.generations:
            self.stop_reason = self.exhausted(learner.episodes_per_generation(),
                                              learner.elapsed)

    def reached_target(self) -> bool:
        target = self.stop.target
        best = self.selection.best
        return target is not None and best is not None and best.validation_value() >= target

    def exhausted(self, generation_episodes: int, elapsed: float) -> str | None:
        """Which budget the next generation (``generation_episodes`` training episodes, and
        the most selection may spend after it) would break, if any."""
        stop, usage = self.stop, self.usage
        upcoming = generation_episodes + self.selection.most_episodes_after_generation()
        if stop.episodes is not None and usage.episodes + upcoming > stop.episodes:
            return "episodes"
        if stop.steps is not None and usage.episodes > 0:
            per_episode = usage.steps / usage.episodes
            if usage.steps + upcoming * per_episode > stop.steps:
                return "steps"
        if stop.seconds is not None and elapsed >= stop.seconds:
            return "seconds"
        return None

    def fits(self, episodes: int) -> bool:
        """Whether ``episodes`` more stay within ``stop.episodes``."""
        limit = self.stop.episodes
        return limit is None or self.usage.episodes + episodes <= limit

    # -- checkpoints: part of the run's selection record (its format predates this class)
    def state_dict(self) -> dict[str, Any]:
        return {"usage": self.usage.to_dict(), "stop_reason": self.stop_reason}

    def restore(self, state: SelectionState) -> None:
        for name, value in state.usage.to_dict().items():
            setattr(self.usage, name, value)
        self.stop_reason = state.stop_reason
