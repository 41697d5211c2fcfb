"""Behaviour files: pydantic models, YAML loading with line numbers, and writing back."""

from flctool.behaviour.dump import behaviour_to_data, behaviour_to_yaml
from flctool.behaviour.fuzzy import InputVariable, Output, Rule
from flctool.behaviour.load import behaviour_from_data, load_behaviour, parse_behaviour
from flctool.behaviour.models import FORMAT_VERSION, Behaviour, require_deployable

__all__ = [
    "FORMAT_VERSION",
    "Behaviour",
    "InputVariable",
    "Output",
    "Rule",
    "behaviour_from_data",
    "behaviour_to_data",
    "behaviour_to_yaml",
    "load_behaviour",
    "parse_behaviour",
    "require_deployable",
]
