"""Starting and resuming runs: everything ``flctool learn`` decides, for Python users too.

    training = start_run("behaviours/ballchase.yaml", {"seed": 3}, out="runs/first")
    summary = training.train()                  # to learning.generations, checkpointed

    training = resume_run("runs/first", generations=60)   # continue to 60 generations
    summary = training.train()

The learner (and with it the environment) is built before a new run directory is made, so a
behaviour whose environment does not fit leaves nothing behind; its errors are located in the
file (or at the override, :class:`~flctool.behaviour.overrides.Override`) they are about. A resumed
run continues only as it was recorded: overrides that differ from the run are refused; its
generation budget is the one thing it may change, given by itself (``generations``).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from flctool.behaviour import Behaviour, behaviour_to_data, load_behaviour
from flctool.behaviour.overrides import (
    Override,
    Overrides,
    as_overrides,
    gives,
    resolve_behaviour,
)
from flctool.compile import compile_behaviour
from flctool.errors import Problem, RunDirError, SpecError
from flctool.learners import Callback, Learner, make_learner
from flctool.runs import Run, RunSummary, create_run, open_run


@dataclass
class Training:
    """A run ready to train: its directory and the learner built for it, whose environment
    this object opened and closes (after :meth:`train`, or on :meth:`close`; as a context
    manager, when the block ends)."""

    run: Run
    learner: Learner
    #: Whether the run continues from a checkpoint (:func:`resume_run`).
    resumed: bool

    @property
    def done(self) -> int:
        """Generations the run has completed so far."""
        return len(self.run.checkpoint_generations())

    def train(self, callbacks: Iterable[Callback] = ()) -> RunSummary:
        """Train to the run's generation budget (see :meth:`Run.train`); the environment is
        closed when training ends, however it ends."""
        try:
            return self.run.train(callbacks, learner=self.learner)
        finally:
            self.close()

    def close(self) -> None:
        """Close the environment (a robot is sent ``stop``); closing twice is harmless."""
        self.learner.env.close()

    def __enter__(self) -> Training:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()


def start_run(behaviour: Behaviour | str | Path, overrides: Overrides | None = None,
              out: str | Path | None = None, *,
              baselines: Iterable[str | Path] = ()) -> Training:
    """A new run of ``behaviour`` (a behaviour or its file) with ``overrides`` applied (see
    :func:`~flctool.behaviour.overrides.resolve_behaviour`), in ``out`` or a new folder under
    ``runs/``. ``baselines`` are files of hand-made controllers of the same rule grid that
    the run's controller must beat (:mod:`flctool.learners.baselines`)."""
    if not isinstance(behaviour, Behaviour):
        behaviour = load_behaviour(behaviour)
    given = as_overrides(overrides)
    if given:
        behaviour = resolve_behaviour(behaviour, given)
    tables = [baseline_table(behaviour, path) for path in baselines]
    learner = make_learner(behaviour)
    learner.baseline_check.given = tables
    try:
        run = create_run(behaviour, Path(out) if out is not None else None)
    except BaseException:
        learner.env.close()  # Training closes it from here on (a robot gets stop)
        raise
    return Training(run, learner, resumed=False)


def baseline_table(behaviour: Behaviour, path: str | Path) -> tuple[str, NDArray[np.intp]]:
    """The hand-made controller in ``path`` as a baseline of ``behaviour``: (its file name,
    its consequents (M,)); it must have the same inputs, sets and commands and give every
    rule."""
    other = load_behaviour(path)
    if _rule_grid(other) != _rule_grid(behaviour):
        raise SpecError([Problem(("inputs",), "a baseline must have the rule grid of the "
                                 f"behaviour it is compared with ({behaviour.name}): the same "
                                 "inputs, sets and commands, in the same order",
                                 "give a controller of this behaviour, e.g. a best.yaml of "
                                 "it or a hand-written one", file=str(path))], str(path))
    consequents = compile_behaviour(other).consequents
    if consequents is None:
        raise SpecError([Problem(("rules",), f"a baseline gives every rule; this one leaves "
                                 f"{other.rule_count - len(other.rules)} to learn",
                                 "write the missing rules", file=str(path))], str(path))
    return Path(path).name, consequents.astype(np.intp)


def _rule_grid(behaviour: Behaviour) -> tuple[object, ...]:
    return (tuple((name, tuple(v.sets)) for name, v in behaviour.inputs.items()),
            tuple(behaviour.output.commands))


def resume_run(path: str | Path, behaviour: Behaviour | str | Path | None = None,
               overrides: Overrides | None = None,
               generations: int | Override | None = None) -> Training:
    """The run in ``path``, to continue from its last checkpoint.

    ``generations`` raises the run's generation budget (an :class:`Override` of
    ``generations`` says where it was given, for its errors). ``behaviour`` and
    ``overrides``, when given, must describe the run as it was recorded: a resumed run
    continues bit for bit, or not at all. The budget is not one of the overrides.
    """
    run = open_run(path)
    given = as_overrides(overrides)
    for override in given:
        if override.path == ("learning", "generations"):
            raise SpecError([Problem(override.path, "a resumed run's generation budget is "
                                     "given on its own, not among the overrides",
                                     "give it as the new budget (generations)",
                                     file=override.where)], override.where)
    budget = new_budget(run, generations)
    if behaviour is not None or given:
        if behaviour is None:
            base = run.behaviour
        elif isinstance(behaviour, Behaviour):
            base = behaviour
        else:
            base = load_behaviour(behaviour)
        check_same_run(run, resolve_behaviour(base, given))
    if budget is not None and budget != run.behaviour.learning.generations:
        run.extend(budget)
    return Training(run, make_learner(run.behaviour), resumed=True)


def new_budget(run: Run, generations: int | Override | None) -> int | None:
    """The generation budget ``generations`` asks of a resumed ``run``, validated like the
    file's own field (an int >= 1) and placed where it was given; None keeps the recorded
    one."""
    if generations is None:
        return None
    budget = generations if isinstance(generations, Override) else Override(
        "generations", generations, "the new generation budget")
    return resolve_behaviour(run.behaviour, [budget]).learning.generations


def check_same_run(run: Run, requested: Behaviour) -> None:
    """Refuse to resume ``run`` as ``requested`` when the two differ anywhere but in the
    generation budget; the error lists the fields that differ."""
    recorded = behaviour_to_data(run.behaviour)
    wanted = behaviour_to_data(requested)
    # the budget is the run's: its generations, and its extend and trials unless the file
    # writes them (a file without a budget gets them sized, docs/learning.md)
    budget = ["generations", *(key for key in ("extend", "trials") if not gives(requested, key))]
    for data in (recorded, wanted):
        for key in budget:
            data.get("learning", {}).pop(key, None)
    changed = _differences(recorded, wanted)
    if changed:
        raise RunDirError(f"--resume continues the run recorded in {run.path}, but the file "
                          f"and options given differ from it at: {', '.join(changed)}",
                          hint="leave them out (only --generations may change), or start a "
                          "new run with --out")


def _differences(a: Any, b: Any, path: str = "") -> list[str]:
    if isinstance(a, dict) and isinstance(b, dict):
        found: list[str] = []
        for key in sorted(set(a) | set(b), key=str):
            found += _differences(a.get(key), b.get(key), f"{path}.{key}" if path else str(key))
        return found
    return [] if a == b else [path or "(top level)"]
