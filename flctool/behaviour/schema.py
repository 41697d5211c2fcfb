"""The JSON Schema of behaviour files, generated from the pydantic models.

It describes the built-in learners and adapters: ``learning:`` and ``environment:`` are each
the union of the built-ins' models, chosen by ``learner`` / ``adapter`` (the one place that
union is built, :mod:`flctool.behaviour.sections`). Installed plugins do not change it, so the
committed schema stays the same wherever it is checked; the two sections' descriptions say
how a plugin extends them (docs/plugins.md).
"""

from __future__ import annotations

import json
from typing import Annotated, Any, Union

from pydantic import Field, create_model
from pydantic.fields import FieldInfo

from flctool.behaviour.models import Behaviour
from flctool.behaviour.sections import CHOSEN
from flctool.plugins import BUILTIN

SCHEMA_ID = "https://flctool.dev/schemas/behaviour.schema.json"

#: What the schema says of a section chosen by name, after the field's own description.
PLUGINS_EXTEND = ("Installed plugins add {kind}s, each with a model of its own (see "
                  "docs/plugins.md); flctool validate checks their sections, this schema "
                  "describes the built-in ones.")


def _builtin_union(section: str) -> tuple[Any, FieldInfo]:
    """The field ``section`` of :class:`Behaviour`, typed as the union of the built-in
    plugins' models chosen by the section's key."""
    chosen = CHOSEN[section]
    models = tuple(plugin.config_model() for plugin in BUILTIN[chosen.kind])
    union: Any = Annotated[Union[models], Field(discriminator=chosen.key)]  # noqa: UP007
    field = Behaviour.model_fields[section]
    if field.default is None:
        union = union | None
    extend = PLUGINS_EXTEND.format(kind="learner" if chosen.kind == "learner" else "adapter")
    described = f"{field.description}. {extend}" if field.description else extend
    return union, Field(field.default, description=described)


def behaviour_schema() -> dict[str, Any]:
    fields: dict[str, Any] = {section: _builtin_union(section) for section in CHOSEN}
    described = create_model(  # the behaviour model as editors see it: built-in plugins
        "Behaviour", __base__=Behaviour, __doc__=Behaviour.__doc__, **fields)
    schema = described.model_json_schema(by_alias=True, mode="validation")
    return {"$schema": "https://json-schema.org/draft/2020-12/schema", "$id": SCHEMA_ID,
            **schema}


def behaviour_schema_text() -> str:
    """The schema as the committed file holds it (stable key order, trailing newline)."""
    return json.dumps(behaviour_schema(), indent=2, ensure_ascii=False) + "\n"
