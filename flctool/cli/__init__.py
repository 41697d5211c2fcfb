"""The ``flctool`` command line. The commands are registered in :mod:`flctool.cli.app`.

Ctrl-C is one line and exit code 130 wherever it lands: inside a command the app handles it
(:class:`flctool.cli.app.FlctoolGroup`); while the command line is still being imported, the
hook installed here does, before anything else is imported.
"""

from __future__ import annotations

import os
import sys
from types import TracebackType

_previous_hook = sys.excepthook


def _interrupt_hook(kind: type[BaseException], value: BaseException,
                    traceback: TracebackType | None) -> None:
    if issubclass(kind, KeyboardInterrupt):
        try:
            sys.stderr.write("interrupted\n")
            sys.stderr.flush()
        finally:
            os._exit(130)
    _previous_hook(kind, value, traceback)


sys.excepthook = _interrupt_hook

from flctool.cli.app import app  # noqa: E402 - after the hook, so start-up is covered

__all__ = ["app", "run"]


def run() -> None:
    """The console script ``flctool``."""
    app()
