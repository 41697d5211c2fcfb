"""One exception tree for flctool: every exception (and warning) a user can see is defined here
and exported from :mod:`flctool`.

Every message says what is wrong, where (file, line, field path) and how to fix it.
The library raises these; only the CLI turns them into exit codes and coloured text.

    FlcError
      SpecError            an input file (or a --set) is invalid: located problems
      InferenceError       inference asked something it cannot answer
      EnvError             an environment adapter could not be built or misbehaved
        LinkError          the connection to a robot failed
      LearnError           a learner could not start, resume or finish
      RunDirError          a run directory is missing, damaged or does not match
      ExportError          a controller cannot be written or read in a format
        ImportRefusals     several constructs keep one file out, listed together
      NotDeployableError   rules are missing where a complete controller is needed
      UnknownNameError     no learner, adapter or format of that name
      MissingDependencyError  an optional package is not installed
      PluginError          an installed plugin's own code failed (its package is at fault)
    ProtocolError (ValueError)   a robot-link line that is not a protocol message
    PluginWarning (UserWarning)  an installed plugin is skipped
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass

PathPart = str | int


def format_path(path: Sequence[PathPart]) -> str:
    """Render a field path as the user wrote it: ``inputs.pan.sets.left`` or ``rules[3].then``."""
    text = ""
    for part in path:
        if isinstance(part, int):
            text += f"[{part}]"
        else:
            text += f".{part}" if text else str(part)
    return text or "(top level)"


@dataclass(frozen=True)
class Problem:
    """One thing wrong with an input file, located as precisely as the file allows."""

    path: tuple[PathPart, ...]
    message: str
    hint: str = ""
    file: str | None = None
    line: int | None = None  # 1-based
    column: int | None = None  # 1-based

    def location(self) -> str:
        where = self.file or "<behaviour>"
        if self.line is not None:
            where += f":{self.line}"
            if self.column is not None:
                where += f":{self.column}"
        return where

    def __str__(self) -> str:
        text = f"{self.location()}: {format_path(self.path)}: {self.message}"
        if self.hint:
            text += f" (fix: {self.hint})"
        return text


class FlcError(Exception):
    """Base of every error flctool raises on purpose."""

    #: A short, imperative suggestion shown after the message.
    hint: str = ""

    def __init__(self, message: str, hint: str = "") -> None:
        super().__init__(message)
        if hint:
            self.hint = hint

    def __str__(self) -> str:
        text = super().__str__()
        return f"{text} (fix: {self.hint})" if self.hint else text


class SpecError(FlcError):
    """A behaviour file (or another input file) is invalid; carries every problem found."""

    def __init__(self, problems: Sequence[Problem], file: str | None = None) -> None:
        self.problems = list(problems)
        self.file = file
        count = len(self.problems)
        head = f"{file or 'behaviour'}: {count} problem{'s' if count != 1 else ''}"
        super().__init__(head + "".join(f"\n  {p}" for p in self.problems))

    def __str__(self) -> str:
        return str(self.args[0])


class InputFileError(SpecError):
    """A file the user named cannot be read as text: missing, a folder, unreadable, or not
    UTF-8 (then located at its first byte that is not). Worded by :mod:`flctool.inputs`,
    the same for every command."""

    @property
    def problem(self) -> Problem:
        return self.problems[0]

    def __str__(self) -> str:  # one line: the file (and place) and what is wrong
        problem = self.problem
        fix = f" (fix: {problem.hint})" if problem.hint else ""
        return f"{problem.location()}: {problem.message}{fix}"


class InferenceError(FlcError):
    """Inference was asked something it cannot answer (NaN input, wrong shape)."""


class EnvError(FlcError):
    """An environment adapter could not be built or misbehaved."""


class LinkError(EnvError):
    """The connection to a robot (or its bridge) failed or timed out."""


class LearnError(FlcError):
    """A learner could not start, resume or finish a run."""


class RunDirError(FlcError):
    """A run directory is missing, incomplete or does not match the request."""


class ExportError(FlcError):
    """A controller cannot be written in (or read from) the requested format."""


class ImportRefusals(ExportError):
    """Several constructs keep one file out: each is an :class:`ExportError` of its own
    (file, line, construct and fix), listed together so that one attempt shows them all."""

    def __init__(self, file: str, errors: list[ExportError]) -> None:
        self.errors = errors
        lines = sorted(errors, key=lambda e: line_of(str(e)))
        super().__init__(f"{file}: {len(errors)} constructs flctool cannot import"
                         + "".join(f"\n  {e}" for e in lines))


def line_of(message: str) -> int:
    """The line a located message names (``file:line:...``); 0 where it names none."""
    found = re.match(r".*?:(\d+):", message)
    return int(found.group(1)) if found else 0


class NotDeployableError(FlcError):
    """A behaviour lacks rule consequents where a complete controller is needed (running,
    evaluating or exporting it); raised by :func:`flctool.behaviour.require_deployable`."""


class UnknownNameError(FlcError):
    """A name was looked up that no one registered (a learner, an adapter, a format); the
    message says which names are known and the closest one."""


class ProtocolError(ValueError):
    """A line from a robot link that is not a message of the protocol (not JSON, not an
    object, no type). The robot link turns it into a :class:`LinkError` naming the robot."""


class PluginError(FlcError):
    """An installed plugin's own code failed (not the behaviour file): the message names the
    plugin and the package to report it to."""


class PluginWarning(UserWarning):
    """An installed plugin that cannot be used (it is skipped)."""


class MissingDependencyError(FlcError):
    """An optional dependency is not installed; the hint says which extra installs it."""

    def __init__(self, package: str, extra: str, purpose: str) -> None:
        self.package = package
        self.extra = extra
        super().__init__(
            f"{purpose} needs the optional package '{package}', which is not installed",
            hint=f"pip install 'flctool[{extra}]'",
        )
