"""Run callbacks: the parts of a run that act between generations.

A :class:`RunCallback` is part of the run itself: model selection
(:class:`~flctool.learners.selection.ModelSelection`), the budget
(:class:`~flctool.learners.budget.Budget`), the confirmation of the returned controller and
its comparison with baselines. It sees each generation's trials before the generation's
metrics are made, may run episodes of its own (counted in the run's usage), may end the run,
and keeps state that every checkpoint holds -- so :func:`~flctool.learners.loop.train` reads
as advance, evaluate, report, and a resumed run continues bit for bit.

The learner builds its run callbacks, so they cannot import it: each says what it reads of
the run as a protocol of its own (``SelectionRun``, ``ConfirmedRun``, ...), which
:class:`~flctool.learners.base.Learner` satisfies, and is a ``RunCallback`` of that protocol.
"""

from __future__ import annotations

from typing import Any, Generic, TypeVar

from flctool.learners.metrics import GenerationResult

#: What a run callback reads of the learner. Contravariant: a callback that needs less of
#: the run than a Learner offers is a callback of a Learner.
RunT = TypeVar("RunT", contravariant=True)


class RunCallback(Generic[RunT]):
    """Part of a run (see the module docstring). The learner builds its own from its
    ``learning:`` section (:attr:`~flctool.learners.base.Learner.run_callbacks`)."""

    #: Why the run should end now ("target", "episodes", ...); None to go on.
    stop_reason: str | None = None

    def on_trials(self, learner: RunT, result: GenerationResult) -> None:
        """After the trials of generation ``learner.generation`` (``result``)."""

    def on_finish(self, learner: RunT) -> None:
        """The run ends after this generation (all its generations done, or stopped)."""

    def state_dict(self) -> dict[str, Any]:
        """This callback's part of the checkpoint (JSON-compatible)."""
        return {}
