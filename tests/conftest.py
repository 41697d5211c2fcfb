"""Shared fixtures: paths to the shipped behaviours and a small valid behaviour text."""

from __future__ import annotations

import signal
from collections.abc import Iterator
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
BEHAVIOURS = ROOT / "behaviours"

MINIMAL = """\
flctool: 1
name: mini
inputs:
  x:
    range: [0, 10]
    sets:
      low: [0, 0, 2, 6]
      high: [4, 8, 10, 10]
output:
  name: u
  commands: {down: -1, up: 1}
rules:
  - {if: {x: low}, then: up}
  - {if: {x: high}, then: down}
"""


@pytest.fixture
def minimal_text() -> str:
    return MINIMAL


@pytest.fixture
def handmade_path() -> Path:
    return BEHAVIOURS / "ballchase-handmade.yaml"


def restore_sigint() -> None:
    """``preexec_fn`` for a child process the test interrupts with SIGINT.

    A shell that starts a command in the background (as a CI runner may) makes it ignore
    SIGINT, and children inherit that; Python then installs no KeyboardInterrupt handler.
    With the default disposition back, the child handles Ctrl-C as it would for a user.
    """
    signal.signal(signal.SIGINT, signal.SIG_DFL)


@pytest.fixture
def ctrl_c_raises() -> Iterator[None]:
    """SIGINT raises KeyboardInterrupt in this process, whatever it inherited."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
