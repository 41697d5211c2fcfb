"""How long a run learns: ``generations``, and past them while the run still improves.

The paper's 30 generations suit ballchase; a larger problem needs more, and how many depends
on the task more than on its size (docs/learning.md, "How long a run learns"). So a run
whose file says nothing of its budget (``learning.extend``, set by default) runs its
``generations`` and then goes on while it improves: an **attempt** ends once the run's
selected controller -- the best validated one, the controller it would return -- has not
improved for ``extend.patience`` generations. A noisy validation can still set a new best by
luck; the patience bounds what such luck costs.

Some seeds lock in: the population settles on a poor controller early and nothing after
improves on it (approach, seed 706: 0.33 success where most seeds reach 0.8). More
generations of the same population do not help, a fresh one does. So where the learner can
start afresh (the genetic learners), the room left up to ``extend.most`` goes to **fresh
attempts**: a new random population (and, for the hybrid, a new q table), ``generations``
long and extended the same way while it improves on the run's best. The hall of fame and
its validations are the run's, so the run returns the best controller of all its attempts;
a run at ``extend.most`` ends. fuzzy_q starts afresh only once it holds its draws (no reward
signal); from then its room goes to fresh attempts too, with room for :data:`HELD_ATTEMPTS`
of them (:meth:`Extension.open_attempts`).

:class:`Extension` is the run callback that keeps this count. It runs after model selection
(which validates each generation's leader) and before the budget, which reads the planned
generations from it; its state is part of every checkpoint, so a resumed run ends where an
uninterrupted one would. A learner whose evidence only accumulates (``credit``) does not
stop early: with ``extend`` it runs all of ``extend.most``. A run without ``extend``
(``protocol: paper``, or ``generations`` given) has exactly its generations, as before.
"""

from __future__ import annotations

import math
from typing import Any, Protocol

from flctool.behaviour.learning import ExtendConfig
from flctool.learners.metrics import FloatArray, GenerationResult
from flctool.learners.run_callback import RunCallback
from flctool.learners.selection import ModelSelection

#: Generations per unit of M log2 K (rules to learn x bits to choose a command) at most,
#: and the problem size one unit stands for: ``extend.most`` when unset.
_PER_UNIT, _UNIT = 30, 30.0


#: Fresh attempts a fuzzy_q run has room for once ``exploration.hold: auto`` holds its draws:
#: an attempt at held exploration ended on a controller at Acrobot's threshold about half the
#: time, and selection returned it whenever one did (docs/learning.md, "Fresh attempts once a
#: run holds"), so three give a run about seven chances in eight.
HELD_ATTEMPTS = 3


def most_generations(rules: int, commands: int, least: int) -> int:
    """``extend.most`` when unset: 30 generations for every 30 units of M log2 K (a problem's
    rules to learn M times the bits of a choice among K commands), and at least twice the
    run's ``generations``: room to grow with the problem, a bound on what patience costs."""
    size = max(rules, 1) * math.log2(max(commands, 2))
    return max(2 * least, _PER_UNIT * math.ceil(size / _UNIT))


def held_most(most: int, least: int, attempts: int) -> int:
    """The most generations a run may have once :meth:`Extension.open_attempts` opens
    ``attempts`` fresh attempts, where ``most`` and ``least`` were its room and generations:
    they open no later than the last generation a fresh attempt fits in."""
    return max(most, most - least + attempts * least)


class ExtendedRun(Protocol):
    """What the extension reads of the run (a :class:`~flctool.learners.base.Learner`)."""

    @property
    def generation(self) -> int: ...

    @property
    def fitness(self) -> FloatArray: ...

    @property
    def selection(self) -> ModelSelection: ...


class Extension(RunCallback[ExtendedRun]):
    """The generations a run has (see the module docstring): ``least`` (the file's
    ``generations``), and with ``config`` (``learning.extend``) more while the selected
    controller improves, up to ``most``."""

    def __init__(self, config: ExtendConfig | None, least: int, most: int,
                 attempts: bool = False, to_most: bool = False) -> None:
        self.config = config
        self.least = least
        self.most = max(most, least)
        #: Whether the learner can start afresh, so the room left goes to fresh attempts.
        self.attempts = attempts
        #: Whether the run has all of ``most`` (a learner whose evidence only accumulates).
        self.to_most = to_most
        self.best_seen = -math.inf  # the selected controller's validated figure
        self.improved_at = -1  # the generation after which it last improved
        self.starts = [0]  # the generation each attempt began at

    @property
    def enabled(self) -> bool:
        return self.config is not None

    def on_trials(self, learner: ExtendedRun, result: GenerationResult) -> None:
        del result
        best = learner.selection.best
        # without selection, the best training fitness is the figure (as restarts read it)
        figure = best.validation_value() if best is not None else float(learner.fitness.max())
        if figure > self.best_seen:
            self.best_seen, self.improved_at = figure, learner.generation
        following = learner.generation + 1
        if (self.config is not None and self.attempts and following >= self.planned()
                and following + self.least <= self.most):
            self.starts.append(following)  # this attempt ends; a fresh one fits

    def open_attempts(self, start: int, attempts: int) -> None:
        """From ``start`` on, the room goes to fresh attempts, and unless ``extend.most``
        bounds the run there is room for ``attempts`` of them: for a learner that starts
        afresh part-way (fuzzy_q, once it holds its draws: :func:`held_most`). Nothing opens
        where not one fresh attempt fits in the run's room."""
        if self.config is None or start + self.least > self.most:
            return
        self.attempts = True
        if self.config.most is None:
            self.most = max(self.most, start + attempts * self.least)

    def begin_attempt(self, generation: int) -> None:
        """Count ``generation`` as the first of a fresh attempt, if one fits: for a learner
        that starts afresh of its own accord (fuzzy_q's strengths, once it holds its draws)."""
        if (self.config is not None and generation > self.starts[-1]
                and generation + self.least <= self.most):
            self.starts.append(generation)

    def begins_attempt(self, generation: int) -> bool:
        """Whether ``generation`` is the first of a fresh attempt (not the run's first)."""
        return generation > 0 and generation in self.starts

    def planned(self) -> int:
        """The generations the run has, as things stand: ``least``, or with ``extend``
        until ``patience`` generations without improvement, within ``[least, most]``;
        ``most`` for a learner that runs to it."""
        if self.config is None:
            return self.least
        if self.to_most:
            return self.most
        start = self.starts[-1]
        return min(self.most, max(start + self.least, self.improved_at + 1 + self.config.patience))

    def state_dict(self) -> dict[str, Any]:
        if self.config is None:
            return {}
        return {"extension": {"best_seen": self.best_seen, "improved_at": self.improved_at,
                              "starts": list(self.starts)}}

    def restore(self, record: dict[str, Any] | None) -> None:
        """Restore what :meth:`state_dict` saved (None: a checkpoint of a run without an
        extension, which then ends at its generations, as it would have)."""
        if record is None:
            self.config = None
            return
        self.best_seen = float(record["best_seen"])
        self.improved_at = int(record["improved_at"])
        self.starts = list(record["starts"])

    def record(self) -> dict[str, Any] | None:
        """What run.json shows: the generation each attempt began at, and the bound."""
        if self.config is None:
            return None
        return {"attempts": list(self.starts), "most": self.most,
                "patience": self.config.patience}
