"""Shared fixtures: paths to the shipped behaviours and a small valid behaviour text."""

from __future__ import annotations

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
