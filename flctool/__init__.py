"""flctool: learned fuzzy logic controllers for reactive robot behaviours.

The public API::

    behaviour = flctool.load_behaviour("behaviours/ballchase-handmade.yaml")
    controller = flctool.compile_behaviour(behaviour)
    controller.output(states)   # (B, N) -> (B,), eq. 1-3
"""

__version__ = "0.1.0"

from flctool.compile import Controller, compile_behaviour, with_rules
from flctool.errors import (
    EnvError,
    ExportError,
    FlcError,
    InferenceError,
    LearnError,
    LinkError,
    SpecError,
)
from flctool.spec import (
    Behaviour,
    behaviour_to_yaml,
    load_behaviour,
    parse_behaviour,
)

__all__ = [
    "Behaviour",
    "Controller",
    "EnvError",
    "ExportError",
    "FlcError",
    "InferenceError",
    "LearnError",
    "LinkError",
    "SpecError",
    "__version__",
    "behaviour_to_yaml",
    "compile_behaviour",
    "load_behaviour",
    "parse_behaviour",
    "with_rules",
]
