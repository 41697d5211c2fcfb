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

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from pydantic import BaseModel, ValidationInfo
from pydantic_core import PydanticKnownError

from flctool.behaviour.environment import AdapterConfig
from flctool.behaviour.learning import DEFAULT_LEARNER, LearningConfig
from flctool.plugins import blamed, names, plugin


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
        """The model of the plugin ``name``; None if no plugin of this kind has that name."""
        found = plugin(self.kind, name)
        return None if found is None else found.config_model()

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


def section_model(section: str, value: Any) -> type[BaseModel] | None:
    """The model that reads ``value`` as the section ``section`` of a file: the named
    plugin's for a section chosen by name (None if it names no known plugin)."""
    chosen = CHOSEN[section]
    name = chosen.chosen(value)
    return None if name is None else chosen.model(name)
