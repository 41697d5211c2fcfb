"""Scaffolding: even overlapping partitions, valid files, clear errors for bad declarations."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from flctool import compile_behaviour, parse_behaviour
from flctool.behaviour.checks import uncovered_gap
from flctool.behaviour.environment import GymnasiumConfig
from flctool.behaviour.scaffold import (
    MAX_SETS,
    even_partition,
    parse_command,
    parse_input,
    parse_sensor,
    scaffold_behaviour,
)
from flctool.errors import FlcError

WALK = [parse_command(c) for c in ("turn_right:-1", "forward:0", "turn_left:1")]


@pytest.mark.parametrize("count", range(1, MAX_SETS + 1))
@pytest.mark.parametrize(("low", "high"), [(0.0, 1.0), (-90.0, 90.0), (-3.3, 7.1)])
def test_even_partition_covers_the_range_with_shoulders(count: int, low: float,
                                                        high: float) -> None:
    sets = even_partition(low, high, count)
    assert len(sets) == count
    assert sets[0][:2] == (low, low) and sets[-1][2:] == (high, high)  # shoulders
    for quad in sets:
        assert list(quad) == sorted(quad) and low <= quad[0] and quad[3] <= high
    for left, right in itertools.pairwise(sets):
        assert right[0] == left[2] and right[1] == left[3]  # neighbours overlap, cross at 0.5
    widths = [quad[2] - quad[1] for quad in sets]
    assert np.allclose(widths, widths[0])  # evenly spaced plateaus


def test_scaffold_is_a_valid_file_with_the_declared_sets() -> None:
    text = scaffold_behaviour("chase", [parse_input("ball_size:0:1:3"),
                                        parse_input("pan:-90:90:far_r,r,ahead,l,far_l")],
                              WALK, adapter="pitch")
    behaviour = parse_behaviour(text)
    assert behaviour.name == "chase" and behaviour.rule_count == 15 and not behaviour.rules
    assert list(behaviour.inputs["pan"].sets) == ["far_r", "r", "ahead", "l", "far_l"]
    assert behaviour.inputs["ball_size"].sets["medium"] == (0.2, 0.4, 0.6, 0.8)
    assert dict(behaviour.output.commands) == {"turn_right": -1.0, "forward": 0.0,
                                               "turn_left": 1.0}
    assert behaviour.environment is not None and behaviour.environment.adapter == "pitch"
    for variable in behaviour.inputs.values():
        assert uncovered_gap(variable) is None
    compile_behaviour(behaviour)


def test_sensor_maps_an_input_to_a_channel() -> None:
    text = scaffold_behaviour("aim", [parse_input("target:-180:180:5")], WALK, adapter="pitch",
                              sensors=dict([parse_sensor("target:goal_bearing")]))
    behaviour = parse_behaviour(text)
    assert behaviour.environment is not None
    assert behaviour.environment.sensors == {"target": "goal_bearing"}  # type: ignore[union-attr]


@pytest.mark.parametrize(("inputs", "sensors", "placed"), [
    (["obstacle_bearing:-180:180:3", "obstacle_distance:0:3000:2"], {}, "obstacles"),
    (["opponent_bearing:-180:180:5"], {}, "opponents"),
    (["threat:0:3000:3"], {"threat": "opponent_distance"}, "opponents"),
])
def test_inputs_that_read_an_obstacle_or_opponent_get_one_to_edit(
        inputs: list[str], sensors: dict[str, str], placed: str) -> None:
    """The pitch world has no obstacle or opponent unless the file places one, so a new
    file whose inputs read them places one (it would not validate otherwise)."""
    text = scaffold_behaviour("evade", [parse_input(i) for i in inputs], WALK,
                              adapter="pitch", sensors=sensors)
    environment = parse_behaviour(text).environment
    assert len(getattr(environment, placed)) == 1
    assert "# a " in text.split(f"  {placed}:")[0].splitlines()[-1]  # says to edit it
    other = {"obstacles", "opponents"} - {placed}
    assert not getattr(environment, other.pop())


def test_gymnasium_actions_follow_the_action_space() -> None:
    """A Box action space takes the crisp output itself: no mapping to delete by hand."""
    text = scaffold_behaviour("car", [parse_input("position:-1.2:0.6:3")],
                              [parse_command("left:-1"), parse_command("right:1")],
                              adapter="gymnasium:MountainCarContinuous-v0")
    assert "actions:" not in text and "Box action space" in text
    environment = parse_behaviour(text).environment
    assert isinstance(environment, GymnasiumConfig) and not environment.actions
    with pytest.raises(FlcError, match="'CartPole-v1' has 2 actions, fewer than the 3"):
        scaffold_behaviour("cart", [parse_input("angle:-0.2:0.2:3")],
                           [parse_command(c) for c in ("l:0", "m:1", "r:2")],
                           adapter="gymnasium:CartPole-v1")
    with pytest.raises(FlcError, match="Gymnasium cannot make 'CartPol-v1'"):
        scaffold_behaviour("cart", [parse_input("angle:-0.2:0.2:3")], WALK,
                           adapter="gymnasium:CartPol-v1")


def test_gymnasium_and_no_environment() -> None:
    text = scaffold_behaviour("cart", [parse_input("angle:-0.2:0.2:3")],
                              [parse_command("left:0"), parse_command("right:1")],
                              adapter="gymnasium:CartPole-v1")
    assert "id: CartPole-v1" in text and "angle: 0" in text and "right: 1" in text
    assert parse_behaviour(scaffold_behaviour("bare", [parse_input("x:0:1:2")], WALK)
                           ).environment is None


@pytest.mark.parametrize(("make", "message"), [
    (lambda: parse_input("pan:-90:90"), "must be NAME:LO:HI:SETS"),
    (lambda: parse_input("pan:90:-90:3"), "LO 90 must be below HI -90"),
    (lambda: parse_input("pan:a:90:3"), "LO 'a' in 'pan:a:90:3' is not a number"),
    (lambda: parse_input("pan:0:nan:3"), "must be a finite number"),
    (lambda: parse_input("pan:0:1:0"), "give 1 to 9"),
    (lambda: parse_input("pan:0:1:a,a"), "given twice"),
    (lambda: parse_input("2pan:0:1:2"), "is not a valid name"),
    (lambda: parse_command("left"), "must be NAME:VALUE"),
    (lambda: parse_command("left:x"), "is not a number"),
    (lambda: parse_sensor("target"), "must be INPUT:CHANNEL"),
    (lambda: scaffold_behaviour("b", [], WALK), "at least one input"),
    (lambda: scaffold_behaviour("b", [parse_input("x:0:1:2")], WALK[:1]), "two commands"),
    (lambda: scaffold_behaviour("b", [parse_input("x:0:1:2"), parse_input("x:0:2:2")], WALK),
     "input 'x' is declared twice"),
    (lambda: scaffold_behaviour("b", [parse_input("pn:0:1:2")], WALK, adapter="pitch"),
     "no channel 'pn'. Did you mean 'pan'?"),
    (lambda: scaffold_behaviour("b", [parse_input("pan:0:1:2")],
                                [parse_command("kick:1"), parse_command("forward:0")],
                                adapter="pitch"), "no default motion for command 'kick'"),
    (lambda: scaffold_behaviour("b", [parse_input("pan:0:1:2")], WALK, adapter="mujoco"),
     "unknown environment 'mujoco'"),
    (lambda: scaffold_behaviour("b", [parse_input("pan:0:1:2")], WALK,
                                sensors={"pan": "goal_bearing"}), "add --env pitch"),
])
def test_bad_declarations_are_clear_errors(make: object, message: str) -> None:
    with pytest.raises(FlcError, match=None) as caught:
        make()  # type: ignore[operator]
    assert message in str(caught.value)
