"""The sections a plugin reads, resolved when a file is loaded.

``learning:`` is read by the model of the learner its ``learner`` names (the default learner's
if it names none), ``environment:`` by the model of the adapter its ``adapter`` names. The
behaviour model types them by their common base (:class:`LearningConfig`,
:class:`AdapterConfig`) and validates each one against the named plugin's own model, which
:func:`flctool.plugins.plugin` imports then, and only then (as Gymnasium's ``make()`` imports
an environment's entry). No union of every plugin's model is built to load a file; the JSON
Schema builds the built-ins' one (:mod:`flctool.behaviour.schema`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cache
from typing import Any

from pydantic import BaseModel, ValidationInfo
from pydantic_core import PydanticKnownError

from flctool.behaviour.environment import AdapterConfig
from flctool.behaviour.learning import DEFAULT_LEARNER, LearningConfig, learner_keys
from flctool.errors import PluginError
from flctool.plugins import Plugin, blamed, names, plugin, plugins


@dataclass(frozen=True)
class ChosenSection:
    """A section whose model a key of it chooses among the plugins of one kind."""

    #: The section's key in a behaviour file.
    section: str
    #: The plugin kind (flctool.plugins) that reads it.
    kind: str
    #: The key that names the plugin.
    key: str
    #: The model every plugin's model of this section extends.
    base: type[BaseModel]
    #: The plugin read when the section names none; None when naming one is required.
    default: str | None = None

    def chosen(self, section: Any) -> str | None:
        """The plugin name ``section`` (as data) chooses, if it is a name at all."""
        if not isinstance(section, Mapping):
            return None
        name = section.get(self.key, self.default)
        return name if isinstance(name, str) else None

    def model(self, name: str) -> type[BaseModel] | None:
        """The model of the plugin ``name``; None if no plugin of this kind has that name.
        Raises :class:`PluginError`, naming the plugin, if its model cannot read the
        section."""
        found = plugin(self.kind, name)
        if found is None:
            return None
        model = self.checked(found)
        if isinstance(model, str):
            package = found.target.partition(":")[0].split(".")[0]
            raise PluginError(
                f"the {self.kind} plugin '{name}' ({found.target}) cannot read "
                f"'{self.section}:': {model}", hint="a fault of the plugin, not of the file: "
                f"report it to the authors of its package ({package}), or uninstall it")
        return model

    def checked(self, found: Plugin) -> type[BaseModel] | str:
        """The model of ``found``'s section, or why it cannot be one: it must import, extend
        :attr:`base` and declare ``key: Literal[name]``."""
        return _checked_model(self, found)

    def validate(self, value: Any, info: ValidationInfo) -> Any:
        """A field validator: ``value`` validated by the model of the plugin it names.

        Errors are placed in the section as the named model's own (``learning.keep``); a
        section naming no plugin, or an unknown one, and one that is no mapping, get the
        errors pydantic gives a discriminated union, which the loader words
        (:mod:`flctool.behaviour.load`).
        """
        if isinstance(value, self.base):  # a section built in Python: its named model's?
            model = self.model(getattr(value, self.key))
            if model is not None and isinstance(value, model):
                return value
            value = value.model_dump(by_alias=True, exclude_unset=True)
        if not isinstance(value, Mapping):
            raise PydanticKnownError("model_attributes_type")
        if self.key not in value and self.default is None:
            raise PydanticKnownError("union_tag_not_found", {"discriminator": repr(self.key)})
        name = value.get(self.key, self.default)
        model = self.model(name) if isinstance(name, str) else None
        if model is None:
            raise PydanticKnownError("union_tag_invalid", {
                "discriminator": repr(self.key), "tag": str(name),
                "expected_tags": ", ".join(repr(known) for known in names(self.kind))})
        with blamed(self.kind, name):  # the model's own validators are the plugin's code
            return model.model_validate(value, context=info.context)


LEARNING = ChosenSection("learning", "learner", "learner", LearningConfig, DEFAULT_LEARNER)
ENVIRONMENT = ChosenSection("environment", "environment", "adapter", AdapterConfig)
#: The sections chosen by name, by their key in a behaviour file.
CHOSEN = {chosen.section: chosen for chosen in (LEARNING, ENVIRONMENT)}


@cache
def _checked_model(chosen: ChosenSection, found: Plugin) -> type[BaseModel] | str:
    try:
        model = found.config_model()
    except Exception as error:  # a third party's config that does not import or is no model
        return f"its config cannot be used ({type(error).__name__}: {error})"
    if not issubclass(model, chosen.base):
        return f"its config must extend {chosen.base.__module__}.{chosen.base.__qualname__}"
    field = model.model_fields.get(chosen.key)
    if field is None or getattr(field.annotation, "__args__", None) != (found.name,):
        return f"its config must declare {chosen.key}: Literal['{found.name}']"
    return model


def section_model(section: str, value: Any) -> type[BaseModel] | None:
    """The model that reads ``value`` as the section ``section`` of a file: the named
    plugin's for a section chosen by name (None if it names no known plugin)."""
    chosen = CHOSEN[section]
    name = chosen.chosen(value)
    return None if name is None else chosen.model(name)


def readers_of(key: str) -> tuple[str, ...]:
    """The learners (built-in and installed) whose ``learning:`` reads ``key``; a plugin whose
    model cannot be used reads none (naming it in a file reports why)."""
    models = ((found.name, LEARNING.checked(found)) for found in plugins("learner"))
    return tuple(name for name, model in models
                 if not isinstance(model, str) and key in learner_keys(model))


def foreign_key_message(key: str, learner: str) -> str | None:
    """Why ``key`` may not appear in the ``learning:`` of ``learner``, when another learner
    reads it; None for a key no learner reads (a typo, reported as unknown)."""
    readers = readers_of(key)
    if not readers or learner in readers:
        return None
    if len(readers) == 1:
        return (f"'{key}' is read by {learners_text(readers)}; remove it or set "
                f"learner: {readers[0]}")
    return (f"'{key}' is read by {learners_text(readers)}, not by {learner}; remove it or "
            "set learner to one of them")


def learners_text(names: Sequence[str]) -> str:
    """``the pitt learner only``, or ``the pitt and hybrid learners``: who reads a key."""
    if len(names) == 1:
        return f"the {names[0]} learner only"
    return f"the {', '.join(names[:-1])} and {names[-1]} learners"


#: The keys of the one flat ``learning:`` model of earlier versions, which wrote every one of
#: them into each behaviour they recorded (a run's behaviour.yaml and best.yaml).
EARLIER_RECORD_KEYS = frozenset((
    "learner", "seed", "population", "generations", "crossover", "mutation", "pitt_crossover",
    "elites", "trials", "common_starts", "q", "exploration"))


def section_for_learner(learning: Mapping[str, Any]) -> dict[str, Any]:
    """A ``learning:`` section (as data) ready to validate: named its learner, the default
    if it names none, and, if an earlier version recorded it, without the keys its learner
    never read. A section someone wrote keeps every key, so that a stray key is reported."""
    section = {"learner": DEFAULT_LEARNER, **learning}
    learner = section["learner"]
    if section.keys() >= EARLIER_RECORD_KEYS and isinstance(learner, str):
        return keep_keys_read_by(section, learner)
    return section


def keep_keys_read_by(learning: Mapping[str, Any], learner: str) -> dict[str, Any]:
    """``learning`` (a section as data) for ``learner``: the keys it does not read left out.

    For a section written for another learner, e.g. when an override switches the learner
    or a run directory of an older flctool recorded every key for every learner. A learner
    nobody knows keeps every key, so that validation reports the name.
    """
    model = LEARNING.model(learner)
    if model is None:
        return dict(learning)
    keys = learner_keys(model)
    return {key: value for key, value in learning.items() if key in keys}
