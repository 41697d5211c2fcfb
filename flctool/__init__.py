"""flctool: learned fuzzy logic controllers for reactive robot behaviours.

The public API::

    behaviour = flctool.load_behaviour("behaviours/ballchase-handmade.yaml")
    controller = flctool.compile_behaviour(behaviour)
    controller.output(states)   # (B, N) -> (B,), eq. 1-3

The names below are loaded on first use (PEP 562 module ``__getattr__``), so that
``import flctool`` -- and with it ``flctool --version`` -- does not pay for numpy, numba and
pydantic until something needs them.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

__version__ = "0.1.0"

if TYPE_CHECKING:
    from flctool.compile import Controller, compile_behaviour
    from flctool.errors import (
        EnvError,
        ExportError,
        FlcError,
        InferenceError,
        LearnError,
        LinkError,
        NotDeployableError,
        SpecError,
    )
    from flctool.spec import (
        Behaviour,
        behaviour_to_yaml,
        load_behaviour,
        parse_behaviour,
    )
    from flctool.spec.rules import with_rules

# public name -> the module that defines it
_LAZY = {
    "Behaviour": "flctool.spec",
    "Controller": "flctool.compile",
    "EnvError": "flctool.errors",
    "ExportError": "flctool.errors",
    "FlcError": "flctool.errors",
    "InferenceError": "flctool.errors",
    "LearnError": "flctool.errors",
    "LinkError": "flctool.errors",
    "SpecError": "flctool.errors",
    "behaviour_to_yaml": "flctool.spec",
    "compile_behaviour": "flctool.compile",
    "load_behaviour": "flctool.spec",
    "parse_behaviour": "flctool.spec",
    "with_rules": "flctool.spec.rules",
    "NotDeployableError": "flctool.errors",
}

__all__ = [
    "Behaviour",
    "Controller",
    "EnvError",
    "ExportError",
    "FlcError",
    "InferenceError",
    "LearnError",
    "LinkError",
    "NotDeployableError",
    "SpecError",
    "__version__",
    "behaviour_to_yaml",
    "compile_behaviour",
    "load_behaviour",
    "parse_behaviour",
    "with_rules",
]


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'flctool' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value  # later lookups skip this function
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
