"""flctool: learned fuzzy logic controllers for reactive robot behaviours.

The public API, the whole flow from a behaviour file to a deployed controller::

    behaviour = flctool.load_behaviour("behaviours/ballchase.yaml")
    controller = flctool.compile_behaviour(flctool.load_behaviour(
        "behaviours/ballchase-handmade.yaml"))
    controller.output(states)   # (B, N) -> (B,), eq. 1-3
    with flctool.make_env(behaviour, batch_size=8) as env: ...
    summary = flctool.start_run(behaviour, {"seed": 3}, out="runs/first").train()
    best = flctool.load_behaviour("runs/first/best.yaml")
    flctool.evaluate_behaviour(best, episodes=1000).rows()
    flctool.export_file(best, "ballchase.fll")
    flctool.import_behaviour("ballchase.fll")

Every exception flctool raises on purpose is a :class:`FlcError` (:mod:`flctool.errors`, all
exported here).

The names below are written once, as the imports under ``TYPE_CHECKING`` (what type checkers
and editors read), and loaded on first use (PEP 562 module ``__getattr__``,
:func:`flctool.lazy.public_imports`), so that ``import flctool`` -- and with it ``flctool
--version`` -- does not pay for numpy, numba and pydantic until something needs them.
"""

from __future__ import annotations

from functools import cache
from typing import TYPE_CHECKING, Any

from flctool.lazy import lazy_attributes, public_imports
from flctool.version import __version__ as __version__

# The public names, in the order of the flow; `X as X` re-exports X (PEP 484).
# isort: off
if TYPE_CHECKING:
    # read and change a behaviour
    from flctool.behaviour import (
        Behaviour as Behaviour, load_behaviour as load_behaviour,
        parse_behaviour as parse_behaviour, behaviour_to_yaml as behaviour_to_yaml,
    )
    from flctool.behaviour.overrides import (
        Override as Override, resolve_behaviour as resolve_behaviour,
    )
    from flctool.behaviour.rules import with_rules as with_rules

    # compile it; make its environment
    from flctool.compile import Controller as Controller, compile_behaviour as compile_behaviour
    from flctool.envs import BatchEnv as BatchEnv, make_env as make_env

    # learn its rules
    from flctool.training import (
        Training as Training, start_run as start_run, resume_run as resume_run,
    )
    from flctool.runs import RunSummary as RunSummary, open_run as open_run
    from flctool.learners import Learner as Learner, make_learner as make_learner, train as train

    # evaluate, export, import
    from flctool.evaluation import (
        Evaluation as Evaluation, evaluate_behaviour as evaluate_behaviour,
    )
    from flctool.export import (
        ExportOptions as ExportOptions, export_text as export_text, export_file as export_file,
        import_behaviour as import_behaviour,
    )

    # what goes wrong
    from flctool.errors import (
        FlcError as FlcError, Problem as Problem, SpecError as SpecError,
        InputFileError as InputFileError,
        NotDeployableError as NotDeployableError, EnvError as EnvError, LinkError as LinkError,
        ProtocolError as ProtocolError, LearnError as LearnError, RunDirError as RunDirError,
        InferenceError as InferenceError, ExportError as ExportError,
        ImportRefusals as ImportRefusals,
        MissingDependencyError as MissingDependencyError, UnknownNameError as UnknownNameError,
        PluginError as PluginError, PluginWarning as PluginWarning,
    )
# isort: on


def __getattr__(name: str) -> Any:
    if name == "__all__":  # for `from flctool import *`: the names above, read on demand
        return ["__version__", *_homes()]
    return _load(name)


def __dir__() -> list[str]:
    return sorted(set(globals()) | {"__all__", *_homes()})


@cache
def _homes() -> dict[str, str]:
    """Public name -> its module: the imports written under TYPE_CHECKING above, read (not
    run) when a name is first asked for, so that ``import flctool`` stays cheap."""
    return public_imports(__file__)


def _load(name: str) -> Any:
    return lazy_attributes(__name__, _homes())(name)
