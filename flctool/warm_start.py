"""Warm start (``flctool learn ROBOT.yaml --init runs/sim``): begin a run from a controller
learned elsewhere -- in simulation, say -- since robot time is what is scarce (the paper: 30
generations in simulation, then 20 on the robot).

Rules and commands are matched by name: a rule of the new behaviour matches the source's rule
with the same set of each input (inputs and sets named alike), a command the source's command
of the same name. Then

* the first generation is seeded around the source controller: individual 0 is the source's
  consequent on every matched rule (a uniformly drawn command where no rule or command
  matches), each other individual that controller with every gene redrawn uniformly with
  probability ``learning.mutation`` -- all from the run's seed;
* the q table (hybrid, fuzzy_q), when the source is a run directory that has one, starts from
  the source's last checkpoint: each matched (rule, command) keeps its q value, the rest 0.

The learner takes them through :meth:`~flctool.learners.base.Learner.start_from` before its
first generation, so the first checkpoint holds what the run started from and ``--resume``
continues it as any run.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from flctool.behaviour.models import Behaviour
from flctool.behaviour.rule_order import rule_grid
from flctool.errors import LearnError
from flctool.learners.base import Learner

#: Mixed with the run's seed for the warm start's own draws (the GA's stream is left as is).
_STREAM = 0x5EED_1417
#: How far a first generation strays from the controller it starts around, for a learner
#: without a mutation rate of its own (credit): the paper's p_m. Its tables need to differ
#: for the first episodes to credit anything.
_AROUND = 0.1


@dataclass(frozen=True)
class WarmStart:
    """What a warm start carried over."""

    source: str
    rules_matched: int
    rules: int
    q_values: int  # (rule, command) q values carried over; 0 without a q table

    def describe(self) -> str:
        q = f", {self.q_values} q values" if self.q_values else ""
        return (f"warm start from {self.source}: {self.rules_matched} of {self.rules} rules "
                f"matched{q}")


def rule_map(target: Behaviour, source: Behaviour) -> list[int | None]:
    """For each rule of ``target`` (in rule order) the source's rule with the same sets, by
    name, or None."""
    if set(target.inputs) != set(source.inputs):
        return [None] * _rules(target)
    source_names = list(source.inputs)
    source_sets = [list(v.sets) for v in source.inputs.values()]
    source_shape = [len(s) for s in source_sets]
    index = {combo: m for m, combo in enumerate(rule_grid(source_shape))}
    target_sets = [list(v.sets) for v in target.inputs.values()]
    mapped: list[int | None] = []
    for combo in rule_grid([len(s) for s in target_sets]):
        named = dict(zip(target.inputs, (target_sets[i][j] for i, j in enumerate(combo)),
                         strict=True))
        try:
            at = tuple(source_sets[i].index(named[name]) for i, name in enumerate(source_names))
        except ValueError:  # a set the source does not have
            mapped.append(None)
            continue
        mapped.append(index[at])
    return mapped


def _rules(behaviour: Behaviour) -> int:
    return int(np.prod([len(v.sets) for v in behaviour.inputs.values()]))


def command_map(target: Behaviour, source: Behaviour) -> list[int | None]:
    """For each command of ``target`` the source's command of the same name, or None."""
    names = list(source.output.commands)
    return [names.index(c) if c in names else None for c in target.output.commands]


def seeded_population(genes: NDArray[np.intp], known: NDArray[np.bool_], size: int,
                      n_commands: int, rate: float, rng: np.random.Generator) -> NDArray[np.intp]:
    """``size`` individuals (size, M) around ``genes (M,)``: genes not ``known`` drawn
    uniformly in every individual; individual 0 the controller itself, each other one with
    every gene redrawn with probability ``rate``."""
    count = genes.shape[0]
    population = np.repeat(genes[None, :], size, axis=0)
    population[:, ~known] = rng.integers(0, n_commands, size=(size, int((~known).sum())))
    if size > 1:
        redraw = rng.random((size - 1, count)) < rate
        population[1:][redraw] = rng.integers(0, n_commands, size=int(redraw.sum()))
    result: NDArray[np.intp] = population.astype(np.intp)
    return result


def warm_start(learner: Learner, behaviour: Behaviour, source: Behaviour, label: str,
               strengths: NDArray[np.float64] | None = None,
               strengths_of: Behaviour | None = None) -> WarmStart:
    """Start ``learner`` (before its first generation) around the deployable ``source``
    controller, with the q values of ``strengths (M', K')`` (of ``strengths_of``, the
    behaviour of the run they come from; default ``source``) where rules and commands match.
    """
    from flctool.compile.rules import rule_consequents

    consequents = rule_consequents(source)
    if consequents is None:
        raise LearnError(f"{label} is not a deployable controller: some rules have no command",
                         hint="start from a learned controller (a run directory or its "
                         "best.yaml)")
    rules = rule_map(behaviour, source)
    commands = command_map(behaviour, source)
    back = {j: k for k, j in enumerate(commands) if j is not None}  # source -> target command
    genes = np.zeros(len(rules), dtype=np.intp)
    known = np.zeros(len(rules), dtype=bool)
    for m, at in enumerate(rules):
        if at is not None and consequents[at] in back:
            genes[m], known[m] = back[consequents[at]], True
    if not known.any():
        raise LearnError(f"no rule of {label} matches one of this behaviour's",
                         hint="start from a controller with the same inputs, sets and "
                         "commands (named alike)")
    config = learner.config
    rng = np.random.default_rng(np.random.SeedSequence([config.seed, _STREAM]))
    # fuzzy_q's one controller is its q table's greedy one: it starts from the table alone
    takes_population = learner.name != "fuzzy_q"
    population = seeded_population(genes, known, config.population, len(commands),
                                   float(getattr(config, "mutation", _AROUND)), rng)
    table = None
    carried = 0
    if strengths is not None and getattr(learner, "fuzzy_q", None) is not None:
        of = strengths_of or source
        q_rules = rule_map(behaviour, of)
        q_commands = command_map(behaviour, of)
        table = np.zeros((len(rules), len(commands)))
        for m, at in enumerate(q_rules):
            for k, j in enumerate(q_commands):
                if at is not None and j is not None:
                    table[m, k] = strengths[at, j]
                    carried += 1
    if not takes_population and table is None:
        raise LearnError(f"the fuzzy_q learner starts from a q table, and {label} has none",
                         hint="start from a run directory of a hybrid or fuzzy_q run")
    learner.start_from(population if takes_population else None, table)
    return WarmStart(label, int(known.sum()), len(rules), carried)


def warm_start_from_path(learner: Learner, behaviour: Behaviour, path: Path) -> WarmStart:
    """:func:`warm_start` from a run directory (its best.yaml and last q table) or a
    controller file."""
    from flctool.behaviour import load_behaviour, require_deployable
    from flctool.runs import open_run

    if path.is_dir():
        run = open_run(path)
        best = path / "best.yaml"
        if not best.is_file():
            raise LearnError(f"{path} has no best.yaml yet", hint="start from a finished run")
        source = load_behaviour(best)
        strengths = None
        generations = run.checkpoint_generations()
        if generations:
            state = run.checkpoint(generations[-1])
            if state.get("q") is not None:
                strengths = np.asarray(state["q"], dtype=np.float64)
        return warm_start(learner, behaviour, source, str(path), strengths, run.behaviour)
    source = load_behaviour(path)
    require_deployable(source, str(path))
    return warm_start(learner, behaviour, source, str(path))
