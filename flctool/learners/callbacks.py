"""Callbacks of the training loop: progress, run-directory records, early stop.

A callback watches a run from outside: it sees the learner at the start, every generation's
metrics, and the end; returning False from :meth:`Callback.on_generation` stops training
after that generation. The parts of the run itself (model selection, the budget) are run
callbacks (:mod:`flctool.learners.run_callback`).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import TYPE_CHECKING

from flctool.learners.metrics import GenerationMetrics

if TYPE_CHECKING:
    from flctool.learners.base import Learner


class Callback:
    """Base class: override any of the three hooks."""

    learner: Learner | None = None

    def on_start(self, learner: Learner) -> None:
        """Called once before the first generation (of this session: also on resume)."""
        self.learner = learner

    def on_generation(self, metrics: GenerationMetrics) -> bool:
        """Called after each generation; return False to stop training early."""
        del metrics
        return True

    def on_end(self) -> None:
        """Called once when training ends: finished, stopped early, or on an error or Ctrl-C
        (then also if :meth:`on_start` raised, so :attr:`learner` may still be None)."""


class CallbackList(Callback):
    """Several callbacks as one; training stops if any of them asks to."""

    def __init__(self, callbacks: Iterable[Callback]) -> None:
        self.callbacks = list(callbacks)

    def on_start(self, learner: Learner) -> None:
        super().on_start(learner)
        for callback in self.callbacks:
            callback.on_start(learner)

    def on_generation(self, metrics: GenerationMetrics) -> bool:
        answers = [callback.on_generation(metrics) for callback in self.callbacks]
        return all(answers)

    def on_end(self) -> None:
        # Every callback ends even if one fails (a run directory must not stay "running"
        # because a progress bar raised); the first failure is raised after all have run.
        failure: BaseException | None = None
        for callback in self.callbacks:
            try:
                callback.on_end()
            except BaseException as error:  # re-raised below, after the others ended
                failure = failure or error
        if failure is not None:
            raise failure


class FunctionCallback(Callback):
    """Calls ``function(metrics)`` every generation (progress bars, logging)."""

    def __init__(self, function: Callable[[GenerationMetrics], object]) -> None:
        self.function = function

    def on_generation(self, metrics: GenerationMetrics) -> bool:
        self.function(metrics)
        return True


class StopAtFitness(Callback):
    """Stops training once a generation's mean (or best) fitness reaches ``target``."""

    def __init__(self, target: float, statistic: str = "mean") -> None:
        if statistic not in ("mean", "best"):
            raise ValueError("statistic must be 'mean' or 'best'")
        self.target = target
        self.statistic = statistic

    def on_generation(self, metrics: GenerationMetrics) -> bool:
        value = metrics.mean if self.statistic == "mean" else metrics.best
        return value < self.target
