"""Overrides: changes to a behaviour's ``learning:`` or ``environment:`` section, each carrying
where it was given, validated like the file itself.

    resolve_behaviour(behaviour, {"seed": 3, "q.alpha": 0.2})        # given "in overrides"
    resolve_behaviour(behaviour, [Override("seed", 3, "my sweep (seed)")])

An error about an overridden field is placed where the override was given (its
:attr:`Override.origin`: ``overrides (q.alpha)`` by default; the command line says
``command line (--set q.alpha)``), any other at its line in the behaviour's file.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

from flctool.behaviour.dump import behaviour_to_data
from flctool.behaviour.load import behaviour_from_data
from flctool.behaviour.located import source_of
from flctool.behaviour.models import Behaviour
from flctool.behaviour.sections import keep_keys_read_by, section_model
from flctool.errors import PathPart, Problem, SpecError


def override_path(key: str) -> tuple[str, ...]:
    """The field path an override key names: ``q.alpha`` is ``learning.q.alpha``; keys may
    also start with ``learning.`` or ``environment.``."""
    path = tuple(key.split("."))
    return path if path[0] in ("learning", "environment") else ("learning", *path)


@dataclass(frozen=True)
class Override:
    """One override: a dotted ``key`` under ``learning:`` (``seed``, ``q.temperature``) or
    starting with ``learning.`` / ``environment.``, its ``value``, and where it was given."""

    key: str
    value: Any
    #: Where it was given, as errors name it; by default ``overrides (KEY)``.
    origin: str = ""

    @property
    def path(self) -> tuple[str, ...]:
        """The field it sets (:func:`override_path`)."""
        return override_path(self.key)

    @property
    def where(self) -> str:
        """Where it was given: its origin, or ``overrides (KEY)``."""
        return self.origin or f"overrides ({self.key})"


#: Overrides as a library call takes them: a mapping key -> value, or :class:`Override`\\ s.
Overrides = Mapping[str, Any] | Iterable[Override]


def as_overrides(overrides: Overrides | None) -> list[Override]:
    """``overrides`` as a list of :class:`Override` (a mapping's given "in overrides")."""
    if overrides is None:
        return []
    if isinstance(overrides, Mapping):
        return [Override(key, value) for key, value in overrides.items()]
    return list(overrides)


def resolve_behaviour(behaviour: Behaviour, overrides: Overrides) -> Behaviour:
    """The behaviour with ``overrides`` applied and validated like the file itself.

    Errors name the field, e.g. ``learning.crossover``; one about an overridden field is
    placed where the override was given, any other at its line in the behaviour's file.
    Overriding ``learner`` drops the keys of the behaviour's learner that the new one does
    not read; keys the overrides give must be the new learner's.
    """
    given = as_overrides(overrides)
    data = behaviour_to_data(behaviour)
    learning = data["learning"]
    # the trials of the budget a file without one gets (with the default extend; a file
    # flctool wrote out carries both, so they are read by value, as extend is)
    config = behaviour.learning
    sized = _extended_by_default(behaviour)
    sized_trials = sized and config.trials == config.sized_trials
    learner = next((o.value for o in given if o.path == ("learning", "learner")), None)
    if isinstance(learner, str):  # switching learner: the old one's keys were not for it
        learning = data["learning"] = keep_keys_read_by(learning, learner)
        model = section_model("learning", {"learner": learner})
        # a key at the old learner's default was not chosen for it: the new one's default
        # (credit draws 100 tables a generation where the GAs breed 10 individuals)
        for key, field in type(config).model_fields.items():
            new = getattr(model, "model_fields", {}).get(key)
            if (key in learning and new is not None and learning[key] == field.default
                    and new.default != field.default and _plain(field.default)):
                del learning[key]
        if sized_trials and "trials" in learning:  # the new learner's sized trials
            learning["trials"] = getattr(model, "sized_trials", 1)
    if _gives_the_budget(given) and sized:
        # a budget given now is exact: `extend` came because the file gave none (or is the
        # default a written-out file carries), and so did sized trials; an `extend` of the
        # file's own is kept
        learning.pop("extend", None)
        if sized_trials:
            learning.pop("trials", None)
    places = apply_overrides(data, given)
    return behaviour_from_data(data, source_of(behaviour).with_overrides(places))


def _plain(value: object) -> bool:
    """Whether a default is a number or word as a file writes it (not a section)."""
    return isinstance(value, (int, float, str, bool))


def _gives_the_budget(overrides: list[Override]) -> bool:
    """Whether the overrides give ``generations`` or ``protocol``, and not ``extend``."""
    paths = [o.path[:2] for o in overrides]
    return (("learning", "generations") in paths or ("learning", "protocol") in paths) \
        and ("learning", "extend") not in paths


def _extended_by_default(behaviour: Behaviour) -> bool:
    """Whether the behaviour's ``extend`` is the one a file without a budget gets (all its
    keys the defaults; a file flctool wrote out carries it so)."""
    from flctool.behaviour.learning import ExtendConfig

    return behaviour.learning.extend == ExtendConfig()


def gives(behaviour: Behaviour, key: str) -> bool:
    """Whether the behaviour's file writes ``learning.<key>``, or an override gave it (not
    a default, nor what the sized budget of a file without one set)."""
    source = source_of(behaviour)
    return source.mark(("learning", key)) is not None or any(
        tuple(path[:2]) == ("learning", key) for path in source.overrides)


def apply_overrides(data: dict[str, Any], overrides: Overrides,
                    ) -> dict[tuple[PathPart, ...], str]:
    """Set each override in ``data`` (a behaviour as data, changed in place); returns where
    each overridden field was given, for :meth:`SourceMap.with_overrides
    <flctool.behaviour.yaml_source.SourceMap.with_overrides>` (see :func:`resolve_behaviour`)."""
    given: dict[tuple[PathPart, ...], str] = {}
    for override in as_overrides(overrides):
        path = list(override.path)
        node = data
        for depth, part in enumerate(path[:-1]):
            child = node.setdefault(part, {})
            if not isinstance(child, dict):
                raise SpecError([Problem(
                    tuple(path[: depth + 1]), f"'{'.'.join(path[: depth + 1])}' is a value, "
                    f"not a section, so '{override.key}' cannot be set", "set the value itself",
                    file=override.where)], override.where)
            node = child
        node[path[-1]] = override.value
        given[tuple(path)] = override.where
    return given
