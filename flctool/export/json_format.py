"""JSON: the behaviour file's content as JSON, valid against schemas/behaviour.schema.json."""

from __future__ import annotations

import json

from flctool.behaviour import Behaviour, behaviour_to_data, require_deployable
from flctool.export.base import Exporter


class JsonExporter(Exporter):
    """The same keys and order as the YAML file; JSON has no comments, so no provenance."""

    format = "json"

    def to_string(self, behaviour: Behaviour) -> str:
        require_deployable(behaviour)
        # json writes floats with repr: the shortest text that reads back to the same double.
        return json.dumps(behaviour_to_data(behaviour), indent=2, ensure_ascii=False) + "\n"
