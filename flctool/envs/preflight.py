"""Everything ``flctool validate`` checks in a behaviour file, before any run.

Loading checks the file itself (:func:`flctool.behaviour.load_behaviour`). The environment adapter
checks the rest when it is built (a Gymnasium id that does not exist, an observation index
past the space, a singleton outside the action space, a command without an action), so it is
built here too, whenever building it has no effect outside this process and checks something
loading did not. A robot link is not built: connecting would talk to a robot; its checks run
when ``learn`` connects. A ``ros2`` section's topics, types and fields are checked by loading,
against the message definitions (flctool.behaviour.ros2_messages); building it would join the
graph. The simulators are not built either: everything building them checks is their
section's ``fit_problems``, which loading already ran, and building them would only cost the
import of numpy and the simulator (most of ``validate``'s time).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from flctool.behaviour import Behaviour, load_behaviour
from flctool.behaviour.checks import command_warnings
from flctool.behaviour.located import locate
from flctool.errors import MissingDependencyError, Problem

#: Adapters whose checks need the world outside the process (a robot on the network).
_NOT_BUILT = {"robot-link": "the robot-link adapter's checks run when learn connects to the "
                            "robot (validate does not connect)"}
#: Adapters whose construction checks nothing beyond their section's model and
#: ``fit_problems`` (both run by :func:`load_behaviour`), so validate need not build them.
_CHECKED_BY_LOADING = frozenset({"ballchase-sim", "pitch", "ros2"})


@dataclass(frozen=True)
class FileReport:
    """A valid file: its behaviour, warnings (located), and why the adapter was not checked
    (empty if it was, or if the file names no environment)."""

    behaviour: Behaviour
    warnings: list[Problem] = field(default_factory=list)
    adapter_note: str = ""


def validate_file(path: str | Path) -> FileReport:
    """Load ``path`` and run its adapter's checks; raises :class:`SpecError` with every
    problem located in the file."""
    path = Path(path)
    behaviour = load_behaviour(path)
    warnings = [locate(behaviour, w.path, w.message, w.hint)
                for w in command_warnings(behaviour.output.commands)]
    note = ""
    environment = behaviour.environment
    if environment is not None:
        note = _NOT_BUILT.get(environment.adapter, "")
        if not note and environment.adapter not in _CHECKED_BY_LOADING:
            try:
                check_adapter(behaviour)  # its errors are located in the file (make_env)
            except MissingDependencyError as error:
                note = f"the {environment.adapter} adapter's checks did not run: {error}"
    return FileReport(behaviour, warnings, note)


def check_adapter(behaviour: Behaviour) -> None:
    """Build the behaviour's adapter once and close it: raises what building raises."""
    from flctool.envs import make_env

    with make_env(behaviour, 1):
        pass

