"""The behaviour an experiment compares its learners on.

``learning:`` is one model per learner (:mod:`flctool.behaviour.learning`), so a behaviour file on
its own may carry only its learner's keys. An experiment runs one file with several learners,
so there its ``learning:`` may also carry the keys of every learner it compares (say
``exploration`` for the fuzzy_q runs and ``pitt_crossover`` for the pitt runs), and each run's
behaviour keeps exactly the keys its learner reads. A ``--set`` applies to every compared
learner that reads its key. A key that no compared learner reads stays an error, placed in the
file or at the override, naming the learners that read it.
"""

from __future__ import annotations

import copy
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from flctool.behaviour import Behaviour, behaviour_from_data, behaviour_to_data
from flctool.behaviour.dump import data_to_yaml
from flctool.behaviour.learning import DEFAULT_LEARNER
from flctool.behaviour.load import read_behaviour_text
from flctool.behaviour.located import source_of
from flctool.behaviour.overrides import Override, Overrides, apply_overrides, as_overrides
from flctool.behaviour.sections import (
    EARLIER_RECORD_KEYS,
    keep_keys_read_by,
    learners_text,
    readers_of,
)
from flctool.behaviour.yaml_source import SourceMap, read_yaml
from flctool.errors import Problem, SpecError

#: Keys the experiment decides for each run.
DECIDED_KEYS = {("learning", "learner"): "--learners", ("learning", "seed"): "--seeds"}


@dataclass(frozen=True, eq=False)
class ExperimentBehaviour:
    """A behaviour file (with its overrides) read for the learners an experiment compares.

    ``own`` is the file as its own learner reads it; ``extra`` the keys of ``learning:`` that
    only other compared learners read (as data, defaults filled in); ``behaviours`` each
    compared learner's behaviour, validated, with the file's seed. Two are equal when every
    compared learner's behaviour is: what the runs start from.
    """

    own: Behaviour
    extra: Mapping[str, Any]
    behaviours: Mapping[str, Behaviour]

    @property
    def name(self) -> str:
        return self.own.name

    @property
    def learners(self) -> tuple[str, ...]:
        return tuple(self.behaviours)

    def of(self, learner: str) -> Behaviour:
        """The behaviour the runs of ``learner`` start from."""
        return self.behaviours[learner]

    def to_yaml(self, header: str = "") -> str:
        """The file as the experiment keeps it: the own learner's behaviour with every value
        written, its ``learning:`` followed by the extra keys. Without extra keys it is
        exactly the behaviour's file, so directories of earlier versions compare equal."""
        data = behaviour_to_data(self.own)
        data["learning"].update(self.extra)
        return data_to_yaml(data, header)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, ExperimentBehaviour):
            return NotImplemented
        return dict(self.behaviours) == dict(other.behaviours)


def read_experiment_behaviour(file: str | Path, learners: Sequence[str],
                              overrides: Overrides | None = None) -> ExperimentBehaviour:
    """Read the behaviour file ``file`` for an experiment comparing ``learners``, with
    ``overrides`` applied (as :func:`flctool.behaviour.overrides.resolve_behaviour` reads them).
    :class:`SpecError` lists every problem, each placed in the file or at its override."""
    data, source = read_yaml(read_behaviour_text(file), str(file))
    return experiment_behaviour(data, source, learners, overrides)


def share_behaviour(behaviour: Behaviour, learners: Sequence[str]) -> ExperimentBehaviour:
    """A validated behaviour (carrying its own learner's keys only) for an experiment
    comparing ``learners``."""
    return experiment_behaviour(behaviour_to_data(behaviour), source_of(behaviour), learners)


def experiment_behaviour(data: Any, source: SourceMap, learners: Sequence[str],
                         overrides: Overrides | None = None) -> ExperimentBehaviour:
    """Behaviour data (as read from ``source``) for an experiment comparing ``learners``:
    see :func:`read_experiment_behaviour`."""
    given = as_overrides(overrides)
    problems = _override_problems(given, learners)
    if problems:
        raise SpecError(problems, source.file)
    data = copy.deepcopy(data)
    if isinstance(data, dict):
        source = source.with_overrides(apply_overrides(data, given))
    learning = data.get("learning", {}) if isinstance(data, dict) else None
    if not isinstance(learning, dict):
        behaviour_from_data(data, source)  # not a behaviour's shape: raises, saying why
        raise SpecError([source.problem(("learning",), "'learning' is not a section",
                                        "write its keys under it")], source.file)
    own = learning.get("learner", DEFAULT_LEARNER)
    own_section, extra, problems = _split(learning, own, learners, source)

    def validated(section: dict[str, Any]) -> Behaviour | None:
        try:
            return behaviour_from_data({**data, "learning": section}, source)
        except SpecError as error:
            problems.extend(error.problems)
            return None

    own_behaviour = validated(own_section)
    by_learner = {learner: validated(keep_keys_read_by({**learning, "learner": learner},
                                                       learner))
                  for learner in learners}
    if problems:
        unique = list(dict.fromkeys(problems))  # the learners share most keys: said once
        raise SpecError(sorted(unique, key=lambda p: (p.line or 0, p.column or 0)),
                        source.file)
    assert own_behaviour is not None  # validated, or a problem was recorded
    behaviours = {learner: b for learner, b in by_learner.items() if b is not None}
    written = {key: behaviour_to_data(behaviours[_first_reader(key, learners)])["learning"][key]
               for key in extra}
    return ExperimentBehaviour(own_behaviour, written, behaviours)


def _split(learning: dict[str, Any], own: Any, learners: Sequence[str], source: SourceMap,
           ) -> tuple[dict[str, Any], dict[str, Any], list[Problem]]:
    """``learning`` as (the own learner's section, the keys only other compared learners
    read, problems with keys that only learners not compared read)."""
    # A section recorded by an earlier flctool holds every key of every learner: the keys of
    # learners not compared were written by flctool, not by someone, so they go unremarked.
    recorded = learning.keys() >= EARLIER_RECORD_KEYS
    own_section: dict[str, Any] = {}
    extra: dict[str, Any] = {}
    problems: list[Problem] = []
    for key, value in learning.items():
        readers = readers_of(key)
        if key == "learner" or not readers or own in readers:
            own_section[key] = value  # its learner's, or unknown: validation judges it
        elif any(learner in readers for learner in learners):
            extra[key] = value
        elif not recorded:
            problems.append(source.problem(
                ("learning", key), f"'{key}' is read by {learners_text(readers)}, which "
                "this experiment does not compare",
                f"remove it, or add {' or '.join(readers)} to --learners"))
    return own_section, extra, problems


def _override_problems(overrides: list[Override], learners: Sequence[str]) -> list[Problem]:
    """Overrides the experiment refuses: of the learner or seed, which it decides for each
    run, and of a learning key no compared learner reads."""
    problems: list[Problem] = []
    for override in overrides:
        key, path, label = override.key, override.path, override.where
        if path in DECIDED_KEYS:
            problems.append(Problem(path, f"'{key}' is decided by the experiment for each "
                                    "run", f"use {DECIDED_KEYS[path]}", file=label))
            continue
        if path[0] != "learning" or len(path) < 2:
            continue
        readers = readers_of(path[1])
        if readers and not any(learner in readers for learner in learners):
            problems.append(Problem(path, f"'{path[1]}' is read by {learners_text(readers)}, "
                                    "none of which this experiment compares",
                                    f"leave it out, or add {' or '.join(readers)} to --learners",
                                    file=label))
    return problems


def _first_reader(key: str, learners: Sequence[str]) -> str:
    readers = readers_of(key)
    return next(learner for learner in learners if learner in readers)
