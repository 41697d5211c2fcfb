"""Every shipped behaviour file loads, points editors at the schema, and compiles."""

from __future__ import annotations

from pathlib import Path

import pytest

from flctool import compile_behaviour, load_behaviour

from .conftest import BEHAVIOURS

SHIPPED = sorted(BEHAVIOURS.glob("*.yaml"))


def test_there_are_shipped_behaviours() -> None:
    assert {"ballchase.yaml", "ballchase-handmade.yaml"} <= {p.name for p in SHIPPED}


@pytest.mark.parametrize("path", SHIPPED, ids=[p.name for p in SHIPPED])
def test_shipped_behaviour(path: Path) -> None:
    first_line = path.read_text().splitlines()[0]
    assert first_line == "# yaml-language-server: $schema=../schemas/behaviour.schema.json"
    controller = compile_behaviour(load_behaviour(path))
    assert controller.n_rules >= 1


def test_ballchase_pair_share_their_partitions() -> None:
    learned = load_behaviour(BEHAVIOURS / "ballchase.yaml")
    handmade = load_behaviour(BEHAVIOURS / "ballchase-handmade.yaml")
    assert learned.inputs == handmade.inputs
    assert learned.output == handmade.output
    assert not learned.rules and handmade.is_deployable
    robot = load_behaviour(BEHAVIOURS / "ballchase-robot.yaml")
    assert robot.inputs == learned.inputs and robot.output == learned.output
    assert robot.learning.generations == 20  # the paper's real-robot protocol
