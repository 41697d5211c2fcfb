"""Writing behaviours back out gives the same behaviour, bit for bit."""

from __future__ import annotations

import json

import numpy as np
import pytest

from flctool import compile_behaviour
from flctool.behaviour import (
    behaviour_from_data,
    behaviour_to_data,
    behaviour_to_yaml,
    parse_behaviour,
)

from ..compile.reference import random_behaviour_data
from ..conftest import ROOT


@pytest.mark.slow
def test_yaml_and_json_round_trip_exactly() -> None:
    rng = np.random.default_rng(5)
    for _ in range(30):
        behaviour = behaviour_from_data(random_behaviour_data(rng))
        text = behaviour_to_yaml(behaviour, header="made by a test\nsecond line")
        assert text.startswith("# made by a test\n# second line\n")
        again = parse_behaviour(text)
        assert again == behaviour
        from_json = behaviour_from_data(json.loads(json.dumps(behaviour_to_data(behaviour))))
        assert from_json == behaviour
        states = rng.uniform(-20, 20, size=(100, len(behaviour.inputs)))
        np.testing.assert_array_equal(compile_behaviour(again).output(states),
                                      compile_behaviour(behaviour).output(states))


def test_rules_are_written_one_per_line(minimal_text: str) -> None:
    text = behaviour_to_yaml(parse_behaviour(minimal_text))
    assert "- {if: {x: low}, then: up}" in text
    assert "low: [0.0, 0.0, 2.0, 6.0]" in text


def test_defaults_can_be_left_out(minimal_text: str) -> None:
    behaviour = parse_behaviour(minimal_text)
    assert "learning:" in behaviour_to_yaml(behaviour)
    lean = behaviour_to_yaml(behaviour, defaults=False)
    assert "learning:" not in lean and "description" not in lean
    assert parse_behaviour(lean) == behaviour


def test_a_long_rule_table_is_written_in_blocks_with_the_same_bytes(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """Rules are dumped a block at a time (bounded memory); the file is byte for byte what
    one call of the dumper writes."""
    import yaml

    from flctool.behaviour import dump, load_behaviour

    behaviour = load_behaviour(ROOT / "behaviours" / "ballchase-handmade.yaml")
    data = dump.behaviour_to_data(behaviour)
    whole = yaml.dump(dump._styled(data), Dumper=dump._Dumper, sort_keys=False,
                      allow_unicode=True, width=100)
    monkeypatch.setattr(dump, "_RULES_AT_ONCE", 4)  # 15 rules: four blocks
    assert dump.data_to_yaml(data, "a header") == "# a header\n" + whole


def test_activation_is_written_only_when_it_is_the_product(minimal_text: str) -> None:
    # min is the paper's eq. 2, left implicit as files leave it; product round-trips
    plain = parse_behaviour(minimal_text)
    assert plain.activation == "min"
    assert "activation" not in behaviour_to_yaml(plain)
    product = parse_behaviour(minimal_text + "activation: product\n")
    text = behaviour_to_yaml(product)
    assert "activation: product\n" in text
    assert parse_behaviour(text) == product


_PITCH_WORLD = """\
flctool: 1
name: intercept
inputs:
  pan:
    range: [-90.0, 90.0]
    sets:
      right: [-90.0, -90.0, -20.0, 0.0]
      ahead: [-20.0, 0.0, 0.0, 20.0]
      left: [0.0, 20.0, 90.0, 90.0]
  drift:
    range: [-60.0, 60.0]
    sets:
      right: [-60.0, -60.0, -3.0, 3.0]
      left: [-3.0, 3.0, 60.0, 60.0]
output:
  name: turn
  commands: {turn_right: -1.0, forward: 0.0, turn_left: 1.0}
rules: []
environment:
  adapter: pitch
  max_steps: 300
  ball: {friction: 0.02}
  start:
    robot: {x: [-1500, -1000], y: [-400, 400], heading: [-20, 20]}
    ball: {distance: [900, 1300], bearing: 30}
    ball_velocity: BALL_VELOCITY
  opponents:
    - {x: [1950, 1950], y: [-150, 150], behaviour: track, speed: 5, radius: 120}
  points:
    spot: {x: 2100, y: 300}
  channels:
    drift: {velocity: [ball, y], noise: 3}
    aim: {bearing: [ball, spot]}
    gap: {distance: [ball, opponent]}
    side: {offset: [ball, goal, robot]}
    behind: {angle: [robot, ball, goal]}
  rewards:
    - {channel: side, scale: -0.000001, abs: true}
  outcomes:
    - {when: ball_reached, reward: 1, success: true, held: 2}
    - {all: [{when: threshold, channel: gap, max: 170}, {when: ball_off_pitch}], reward: -1}
    - {any: [{when: ball_off_pitch}, {when: off_pitch}], reward: -1}
"""


@pytest.mark.parametrize("velocity", ["{speed: [20, 40], direction: [-120, 120]}",
                                      "{speed: [70, 90], towards: own_goal, spread: 300}",
                                      "{speed: [70, 90], towards: own_goal}"])
def test_a_pitch_world_with_every_kind_of_option_reads_back_from_its_written_out_copy(
        velocity: str) -> None:
    """``flctool learn`` writes the behaviour out and reads it back: an optional key whose
    default is written where it does not apply (a ball rolling in a ``direction`` with the
    ``spread`` of ``towards``) made a valid file fail to learn."""
    behaviour = parse_behaviour(_PITCH_WORLD.replace("BALL_VELOCITY", velocity))
    assert parse_behaviour(behaviour_to_yaml(behaviour)) == behaviour
    assert parse_behaviour(behaviour_to_yaml(behaviour, defaults=False)) == behaviour
