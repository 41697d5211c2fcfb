"""The behaviour file as pydantic models (paper Sec. II).

A behaviour declares N inputs, each partitioned into L_i fuzzy sets given as trapezoid
quadruples ``(pa, pb, pc, pd)``; one output with K singleton commands; and optionally the rule
consequents. The inputs, the output and the rules are the models of :mod:`flctool.behaviour.fuzzy`;
the checks that relate fields to each other (coverage, rule references) live in
:mod:`flctool.behaviour.checks`, and :func:`find_problems` runs them when a behaviour is
validated.
"""

from __future__ import annotations

import math
from typing import Any, Literal

from pydantic import (
    Field,
    PrivateAttr,
    SerializeAsAny,
    ValidationInfo,
    field_validator,
    model_validator,
)

from flctool.behaviour.base import BehaviourName, Name, Section
from flctool.behaviour.checks import check_input, check_rules, limit_problems
from flctool.behaviour.environment import AdapterConfig, default_gymnasium_ranges
from flctool.behaviour.fuzzy import InputVariable, Output, Rule
from flctool.behaviour.learning import DEFAULT_LEARNER, HybridConfig, LearningConfig
from flctool.behaviour.magnitudes import magnitude_problems
from flctool.behaviour.rule_order import rule_grid
from flctool.behaviour.sections import CHOSEN, section_for_learner
from flctool.behaviour.set_learning import set_learning_problems
from flctool.behaviour.yaml_source import SourceRef
from flctool.errors import NotDeployableError, Problem
from flctool.plugins import blamed

FORMAT_VERSION = 1


class Behaviour(Section):
    """A whole behaviour file. Build it with :func:`flctool.load_behaviour`."""

    flctool: int = Field(strict=True, description=(
        f"file format version; this flctool writes {FORMAT_VERSION}"))
    name: BehaviourName = Field(description=(
        "letters, digits, _ and -; formats that need an identifier write - as _"))
    description: str = ""
    inputs: dict[Name, InputVariable] = Field(min_length=1, description=(
        "input name -> variable; file order is the order of the state vector"))
    output: Output
    rules: list[Rule] = Field(default_factory=list, description=(
        "rule consequents; empty or partial for a behaviour still to be learned"))
    activation: Literal["min", "product"] = Field("min", description=(
        "how a rule combines its memberships into its activation: min, the paper's "
        "(eq. 2), or product, their product in input order (docs/behaviour-files.md)"))
    # Typed by the base every plugin's model extends; each is validated by the model of the
    # plugin it names (flctool.behaviour.sections) and dumped with all of that model's fields.
    learning: SerializeAsAny[LearningConfig] = Field(HybridConfig(), description=(
        "the learner and its hyperparameters; without 'learner:' the section is the "
        f"{DEFAULT_LEARNER} learner's"))
    environment: SerializeAsAny[AdapterConfig] | None = None
    #: Where each field was written (read by :mod:`flctool.behaviour.located`); not part of
    #: the value, set once by the loader (:func:`flctool.behaviour.located.attach_source`).
    _source: SourceRef = PrivateAttr(default_factory=SourceRef)

    def __setattr__(self, name: str, value: Any) -> None:
        if name == "_source":  # the fields are frozen by pydantic; the source map is too
            raise TypeError("a validated behaviour cannot be changed; its source map is "
                            "set when it is loaded")
        super().__setattr__(name, value)

    @field_validator("flctool")
    @classmethod
    def _supported_version(cls, version: int) -> int:
        if version > FORMAT_VERSION:
            raise ValueError(
                f"this file uses format version {version}, but this flctool reads version "
                f"{FORMAT_VERSION} only; upgrade flctool (pip install --upgrade flctool)")
        if version < 1:
            raise ValueError(f"format version must be {FORMAT_VERSION}, got {version}")
        return version

    @field_validator("learning", "environment", mode="before")
    @classmethod
    def _read_by_the_named_plugin(cls, value: Any, info: ValidationInfo) -> Any:
        if value is None and info.field_name == "environment":
            return None
        return CHOSEN[str(info.field_name)].validate(value, info)

    @model_validator(mode="before")
    @classmethod
    def _default_ranges(cls, data: Any) -> Any:
        # a gymnasium input may leave out its range: the observation space's bounds
        return default_gymnasium_ranges(data)

    @model_validator(mode="before")
    @classmethod
    def _name_the_learner(cls, data: Any) -> Any:
        # 'learner' chooses the model of the section, so a section without it is given the
        # default's name before the union looks for it
        learning = data.get("learning") if isinstance(data, dict) else None
        if isinstance(learning, dict):
            data = {**data, "learning": section_for_learner(learning)}
        return data

    @model_validator(mode="after")
    def _consistent(self, info: ValidationInfo) -> Behaviour:
        problems = find_problems(self)
        context: Any = info.context
        if isinstance(context, dict) and "problems" in context:
            context["problems"].extend(problems)  # the loader locates and reports them all
        elif problems:
            raise ValueError("; ".join(f"{p.path}: {p.message}" for p in problems))
        return self

    # -- derived facts -------------------------------------------------------------------
    @property
    def input_names(self) -> tuple[str, ...]:
        return tuple(self.inputs)

    @property
    def rule_count(self) -> int:
        """M = prod(L_i), the size of the full rule grid."""
        return math.prod(len(v.sets) for v in self.inputs.values())

    def antecedents(self) -> list[tuple[str, ...]]:
        """Every rule's set names in rule order (eq. 1, :mod:`flctool.behaviour.rule_order`)."""
        sets = [tuple(v.sets) for v in self.inputs.values()]
        return [tuple(sets[i][j] for i, j in enumerate(rule))
                for rule in rule_grid([len(s) for s in sets])]

    def missing_rules(self) -> list[tuple[str, ...]]:
        """Antecedents that have no rule yet; empty for a deployable controller."""
        given = {tuple(r.if_[n] for n in self.input_names) for r in self.rules}
        return [a for a in self.antecedents() if a not in given]

    @property
    def is_deployable(self) -> bool:
        return len(self.rules) == self.rule_count and not self.missing_rules()

    @property
    def acts_by_vote(self) -> bool:
        """Whether the behaviour acts by vote (``environment.action: vote``): the command
        whose firing rules' activations sum highest runs, not eq. 3's output."""
        return getattr(self.environment, "action", "crisp") == "vote"


def find_problems(behaviour: Behaviour) -> list[Problem]:
    """What relates the fields of ``behaviour`` badly (the checks of
    :mod:`flctool.behaviour.checks`, the adapter's and the set learning's), run once, when it
    is validated."""
    problems = limit_problems([len(v.sets) for v in behaviour.inputs.values()],
                              behaviour.learning.population, behaviour.learning.trials,
                              behaviour.learning.generations,
                              getattr(behaviour.environment, "max_steps", None))
    sets_problems = [p for name, variable in behaviour.inputs.items()
                     for p in check_input(name, variable)]
    problems += sets_problems
    if behaviour.output.name in behaviour.inputs:
        problems.append(Problem(("output", "name"), f"the output is named '{behaviour.output.name}'"
                                ", like an input", "give the output a name of its own"))
    problems += check_rules({name: tuple(v.sets) for name, v in behaviour.inputs.items()},
                            behaviour.output.commands, enumerate(behaviour.rules))
    environment = behaviour.environment
    if isinstance(environment, AdapterConfig):
        with blamed("environment", environment.adapter):
            problems += magnitude_problems(environment)
            problems += environment.fit_problems(behaviour.input_names,
                                                 tuple(behaviour.output.commands))
    if not sets_problems:  # learning the sets starts from valid ones
        problems += set_learning_problems(getattr(behaviour.learning, "sets", None),
                                          behaviour.inputs)
    return problems


#: How many missing rules a :class:`NotDeployableError` lists.
LISTED_MISSING = 10


def require_deployable(behaviour: Behaviour, file: str | None = None) -> None:
    """Raise :class:`NotDeployableError`, listing the missing rules, unless ``behaviour``
    gives all M consequents of eq. 1 (``file`` names where it came from)."""
    missing = behaviour.missing_rules()
    if not missing:
        return
    names = behaviour.input_names
    listed = [" AND ".join(f"{n} IS {s}" for n, s in zip(names, sets, strict=True))
              for sets in missing[:LISTED_MISSING]]
    more = len(missing) - len(listed)
    text = "".join(f"\n  IF {rule}" for rule in listed)
    if more:
        text += f"\n  ... and {more} more"
    where = f"{file}: " if file else ""
    raise NotDeployableError(
        f"{where}behaviour '{behaviour.name}' is not deployable: {len(missing)} of "
        f"{behaviour.rule_count} rules have no consequent:{text}",
        hint="learn them (flctool learn) and use the run directory, or add the rules")
