"""YAML: the behaviour file itself, complete with all M rules, as flctool reads it."""

from __future__ import annotations

from flctool.behaviour import Behaviour, behaviour_to_yaml, require_deployable
from flctool.export.base import Exporter, header_lines


class YamlExporter(Exporter):
    """A deployable behaviour file; floats are written with repr, so it loads back exactly."""

    format = "yaml"

    def to_string(self, behaviour: Behaviour) -> str:
        require_deployable(behaviour)
        header = "\n".join(header_lines(behaviour, self.options.provenance))
        return behaviour_to_yaml(behaviour, header)
