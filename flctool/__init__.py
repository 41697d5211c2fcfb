"""flctool: learned fuzzy logic controllers for reactive robot behaviours.

The public API::

    behaviour = flctool.load_behaviour("behaviours/ballchase-handmade.yaml")
    controller = flctool.compile_behaviour(behaviour)
    controller.output(states)   # (B, N) -> (B,), eq. 1-3
    flctool.start_run(behaviour, {"seed": 3}, out="runs/first").train()
    flctool.evaluate_behaviour(flctool.load_behaviour("runs/first/best.yaml")).rows()

Every exception flctool raises on purpose is a :class:`FlcError` (:mod:`flctool.errors`, all
exported here).

The names below are loaded on first use (PEP 562 module ``__getattr__``), so that
``import flctool`` -- and with it ``flctool --version`` -- does not pay for numpy, numba and
pydantic until something needs them.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from flctool.lazy import lazy_attributes
from flctool.version import __version__

if TYPE_CHECKING:
    from flctool.compile import Controller, compile_behaviour
    from flctool.errors import (
        EnvError,
        ExportError,
        FlcError,
        InferenceError,
        LearnError,
        LinkError,
        MissingDependencyError,
        NotDeployableError,
        PluginWarning,
        Problem,
        ProtocolError,
        RunDirError,
        SpecError,
        UnknownNameError,
    )
    from flctool.evaluation import evaluate_behaviour
    from flctool.spec import (
        Behaviour,
        behaviour_to_yaml,
        load_behaviour,
        parse_behaviour,
    )
    from flctool.spec.rules import with_rules
    from flctool.training import resume_run, start_run

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
    "MissingDependencyError": "flctool.errors",
    "NotDeployableError": "flctool.errors",
    "PluginWarning": "flctool.errors",
    "Problem": "flctool.errors",
    "ProtocolError": "flctool.errors",
    "RunDirError": "flctool.errors",
    "SpecError": "flctool.errors",
    "UnknownNameError": "flctool.errors",
    "behaviour_to_yaml": "flctool.spec",
    "compile_behaviour": "flctool.compile",
    "evaluate_behaviour": "flctool.evaluation",
    "load_behaviour": "flctool.spec",
    "parse_behaviour": "flctool.spec",
    "resume_run": "flctool.training",
    "start_run": "flctool.training",
    "with_rules": "flctool.spec.rules",
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
    "MissingDependencyError",
    "NotDeployableError",
    "PluginWarning",
    "Problem",
    "ProtocolError",
    "RunDirError",
    "SpecError",
    "UnknownNameError",
    "__version__",
    "behaviour_to_yaml",
    "compile_behaviour",
    "evaluate_behaviour",
    "load_behaviour",
    "parse_behaviour",
    "resume_run",
    "start_run",
    "with_rules",
]


__getattr__ = lazy_attributes(__name__, _LAZY)


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
