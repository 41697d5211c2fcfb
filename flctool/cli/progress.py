"""Saying what a long command is doing, on stderr (stdout stays the command's result).

- On a terminal: a rich progress bar.
- Otherwise (a log file, a pipe, CI): one plain line every :data:`LOG_EVERY` seconds and one
  at the end, so a log shows that the work moves and how far it got.
- While numba compiles the inference kernels on a machine's first run (several seconds),
  :func:`compiling` prints a status line.
"""

from __future__ import annotations

import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from types import TracebackType
from typing import Any

from flctool.cli.app import err_console, escape

#: Seconds between two plain progress lines when stderr is not a terminal.
LOG_EVERY = 5.0
#: A first inference slower than this is (almost surely) numba compiling: say so.
COMPILE_NOTICE_AFTER = 1.0

_compiled = {"done": False}


def on_terminal() -> bool:
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError):
        return False


class Progress:
    """Progress of ``total`` steps of ``what`` (e.g. "generation", "episode").

    ``update(done, **fields)`` sets how many are done and the fields shown after the count
    (e.g. best=0.912); ``total=`` changes the total (a run that extends itself).
    Disabled, it prints nothing; with ``terminal=False`` it prints plain
    lines even on a terminal (no bar).
    """

    def __init__(self, what: str, total: int, done: int = 0, enabled: bool = True,
                 terminal: bool = True, log_every: float = LOG_EVERY) -> None:
        self.what = what
        self.total = total
        self.done = done
        self.enabled = enabled
        self.terminal = terminal
        self.fields: dict[str, str] = {}
        self._log_every = log_every
        self._start = time.monotonic()
        self._last_line = self._start
        self._bar: Any = None
        self._task: Any = None
        self._printed: tuple[int, str] | None = None  # the count and fields last printed

    def __enter__(self) -> Progress:
        if self.enabled and self.terminal and on_terminal():
            from rich.progress import (
                BarColumn,
                MofNCompleteColumn,
                TextColumn,
                TimeElapsedColumn,
            )
            from rich.progress import Progress as RichProgress

            self._bar = RichProgress(
                TextColumn("[bold]{task.description}"), BarColumn(), MofNCompleteColumn(),
                TextColumn("{task.fields[text]}"), TimeElapsedColumn(),
                console=err_console.get(), transient=False)
            self._task = self._bar.add_task(escape(self.what), total=self.total,
                                            completed=self.done, text="")
            self._bar.__enter__()
        return self

    def update(self, done: int, total: int | None = None, **fields: str) -> None:
        self.done = done
        self.total = self.total if total is None else total
        self.fields.update(fields)
        if not self.enabled:
            return
        if self._bar is not None:
            self._bar.update(self._task, completed=done, total=self.total,
                             text=escape(self._text()))
            return
        now = time.monotonic()
        if now - self._last_line >= self._log_every:
            self._last_line = now
            self._line()

    def __exit__(self, kind: type[BaseException] | None, error: BaseException | None,
                 traceback: TracebackType | None) -> None:
        if self._bar is not None:
            self._bar.__exit__(kind, error, traceback)
        elif self.enabled and kind is None and self._last_line != self._start \
                and self._printed != (self.done, self._text()):
            self._line()  # the end, after periodic lines (shorter work: the result says it)

    def _text(self) -> str:
        return "  ".join(f"{name} {value}" for name, value in self.fields.items())

    def _line(self) -> None:
        elapsed = time.monotonic() - self._start
        text = self._text()
        self._printed = (self.done, text)
        err_console.print(f"{escape(self.what)} {self.done}/{self.total}"
                          f"{'  ' + escape(text) if text else ''}  ({elapsed:.0f} s)",
                          highlight=False)


@contextmanager
def compiling(enabled: bool = True) -> Iterator[None]:
    """Around the first use of the compiled kernels in this process. On a terminal, a status
    line if that takes more than :data:`COMPILE_NOTICE_AFTER` seconds; in a log, a line after
    it if numba compiled (a machine's first run), with how long it took. (In a log, a line
    only because loading was slow would depend on the machine's load.)"""
    if _compiled["done"] or not enabled:
        yield
        return
    terminal = on_terminal()
    timer: threading.Timer | None = None
    if terminal:
        timer = threading.Timer(COMPILE_NOTICE_AFTER, err_console.print, args=(
            "[dim]preparing the inference kernels (numba compiles them on a machine's first "
            "run and caches them for the next)...[/]",), kwargs={"highlight": False})
        timer.daemon = True
        timer.start()
    start = time.monotonic()
    try:
        yield
    finally:
        if timer is not None:
            timer.cancel()
        _compiled["done"] = True
    if not terminal and _numba_compiled():
        err_console.print(f"compiled the inference kernels in {time.monotonic() - start:.1f} s "
                          "(numba, first run on this machine; cached for the next runs)",
                          highlight=False)


def _numba_compiled() -> bool:
    """Whether any inference kernel was compiled in this process (not loaded from numba's
    cache)."""
    kernels = sys.modules.get("flctool.compile.kernels")
    return kernels is not None and any(
        getattr(getattr(value, "stats", None), "cache_misses", None)
        for value in vars(kernels).values())
