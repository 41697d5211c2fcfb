"""The pitch world's coach vocabulary: derived channels, combined and held outcomes, per-step
rewards, a rolling start, opponents, start checks that know the heading -- and a located
error for each new key."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flctool.envs import check_env, make_env
from flctool.envs.pitch import PitchSim
from flctool.errors import SpecError

from .test_pitch import _behaviour, _run

FIXED = """  adapter: pitch
  ball: {{movable: {movable}}}
  start:
    robot: {{x: [-1000, -1000], y: [0, 0], heading: [{heading}, {heading}]}}
    ball: {{x: [0, 0], y: [500, 500]}}
  sensor_noise: {{own_goal_bearing: 0, ball_vx: 0}}
  points: {{spot: {{x: 1000, y: 0}}}}
  channels:
    guard: {{offset: [ball, own_goal, robot]}}
    between: {{angle: [ball, robot, own_goal]}}
    to_spot: {{bearing: [robot, spot]}}
    aim: {{bearing: [ball, goal]}}
    ball_to_goal: {{distance: [ball, goal]}}
    ball_speed: {{velocity: [ball, speed]}}
  outcomes: [{{when: timeout, success: true}}]
"""
CHANNELS = ("guard", "between", "to_spot", "aim", "ball_to_goal", "ball_speed",
            "own_goal_bearing", "ball_vx")


def _fixed(heading: float = 0.0, movable: str = "false") -> PitchSim:
    env = make_env(_behaviour(FIXED.format(heading=heading, movable=movable), CHANNELS))
    assert isinstance(env, PitchSim)
    return env


def test_derived_channels_read_the_geometry() -> None:
    obs = dict(zip(CHANNELS, _fixed().reset_one(0).tolist(), strict=True))
    # robot (-1000, 0), ball (0, 500), own goal (-2100, 0), target goal (2100, 0)
    ball_to_own = np.array([-2100.0, -500.0])
    robot_from_ball = np.array([-1000.0, -500.0])
    cross = ball_to_own[0] * robot_from_ball[1] - ball_to_own[1] * robot_from_ball[0]
    assert obs["guard"] == pytest.approx(cross / np.hypot(*ball_to_own))
    to_ball, to_goal = np.array([1000.0, 500.0]), np.array([-1100.0, 0.0])
    cosine = to_ball @ to_goal / (np.hypot(*to_ball) * np.hypot(*to_goal))
    assert obs["between"] == pytest.approx(math.degrees(math.acos(cosine)))
    assert obs["to_spot"] == pytest.approx(0.0)
    assert obs["aim"] == pytest.approx(math.degrees(math.atan2(-500.0, 2100.0)))
    assert obs["ball_to_goal"] == pytest.approx(math.hypot(2100.0, 500.0))
    assert obs["ball_speed"] == 0.0 and obs["ball_vx"] == 0.0
    assert obs["own_goal_bearing"] == pytest.approx(180.0)
    # bearings are relative to the robot's heading; the other quantities are not
    turned = dict(zip(CHANNELS, _fixed(heading=90.0).reset_one(0).tolist(), strict=True))
    assert turned["to_spot"] == pytest.approx(-90.0)
    assert turned["own_goal_bearing"] == pytest.approx(90.0)
    assert turned["guard"] == pytest.approx(obs["guard"])


def test_ball_velocity_channels_follow_a_rolling_ball() -> None:
    env = make_env(_behaviour("""  adapter: pitch
  ball: {friction: 0.1}
  start:
    robot: {x: [-1500, -1500], y: [-900, -900], heading: [0, 0]}
    ball: {x: [0, 0], y: [0, 0]}
    ball_velocity: {speed: [80, 80], towards: own_goal}
  sensor_noise: {ball_vx: 0, ball_vy: 0}
  outcomes:
    - {when: ball_in_own_goal, reward: -1}
    - {when: timeout, success: true}
""", ("ball_vx", "ball_vy")))
    obs = env.reset_one(0)
    assert obs.tolist() == pytest.approx([-80.0, 0.0])
    obs, *_ = env.step_one(0.0)
    assert obs[0] == pytest.approx(-72.0)  # rolled and lost a tenth of its speed


ROLLING = """  adapter: pitch
  max_steps: 150
  ball: {{friction: 0.02}}
  start:
    robot: {{x: [1500, 1500], y: [1000, 1000], heading: [0, 0]}}
    ball: {{x: [0, 0], y: [-100, 100]}}
    ball_velocity: {{speed: [70, 90], towards: own_goal, spread: 200}}
{extra}  outcomes:
    - {{when: ball_in_own_goal, reward: -1}}
    - {{when: ball_off_pitch, reward: -1}}
    - {{when: timeout, success: true}}
"""


def test_a_ball_rolling_at_the_own_goal_goes_in() -> None:
    env, reward, terminated, _, steps = _run(ROLLING.format(extra=""), 0.0)
    assert terminated and reward == -1.0 and not env.success()[0]
    assert env.ball_x[0] < -2100.0 and steps < 60


@pytest.mark.parametrize("behaviour", ["stand", "track"])
def test_a_keeper_on_the_line_stops_the_ball(behaviour: str) -> None:
    keeper = ("  opponents: [{x: [-1900, -1900], y: [-350, 350], behaviour: " + behaviour +
              ", speed: 60}]\n")
    if behaviour == "stand":  # standing in the middle of the goal
        keeper = keeper.replace("[-350, 350]", "[0, 0]").replace(", speed: 60", "")
    saved = sum(_run(ROLLING.format(extra=keeper), 0.0, seed=seed)[0].success()[0]
                for seed in range(20))
    assert saved >= 18  # the ball stops at the keeper and never goes in


def test_a_chaser_walks_to_the_ball_and_pushes_it() -> None:
    env = make_env(_behaviour("""  adapter: pitch
  start:
    robot: {x: [-1800, -1800], y: [1100, 1100], heading: [0, 0]}
    ball: {x: [0, 0], y: [0, 0]}
  opponents: [{x: [1000, 1000], y: [0, 0], behaviour: chase, speed: 50}]
  sensor_noise: {opponent_distance: 0}
  outcomes: [{when: timeout, success: true}]
""", ("opponent_distance",)))
    assert isinstance(env, PitchSim)
    env.reset_one(0)
    for _ in range(30):
        env.step_one(-1.0)
    assert env.ball_x[0] < 0.0  # pushed towards the own goal
    opponent = env._engine.state.opponents[0] if env._engine else None
    assert opponent is not None and opponent[0] < 1000.0


CONTACT = """  adapter: pitch
  max_steps: 60
  start:
    robot: {x: [-1000, -1000], y: [-250, 250], heading: [0, 0]}
    ball: {x: [1500, 1500], y: [900, 900]}
  opponents: [{x: [-400, -400], y: [0, 0], behaviour: stand, radius: 120}]
  outcomes: [{when: timeout, success: true}]
"""


def test_the_robot_cannot_walk_through_an_opponent() -> None:
    env = make_env(_behaviour(CONTACT))
    assert isinstance(env, PitchSim)
    passed = 0
    for seed in range(10):
        env.reset_one(seed)
        for _ in range(60):
            env.step_one(0.0)  # forward, at the opponent
            gap = math.hypot(env.x[0] + 400.0, env.y[0])
            assert gap >= 150.0 + 120.0 - 1e-9, seed  # the bodies touch at most
        passed += env.x[0] > -400.0  # slid round it
    assert passed > 0
    # head on and without motion noise, the robot is held at touching
    still = CONTACT.replace("y: [-250, 250]", "y: [0, 0]") + (
        "  noise: {forward: {forward: 0, sideways: 0, rotation: 0}}\n")
    env = make_env(_behaviour(still))
    assert isinstance(env, PitchSim)
    env.reset_one(0)
    for _ in range(30):
        env.step_one(0.0)
    assert (env.x[0], env.y[0]) == (pytest.approx(-400.0 - 270.0), 0.0)
    # a declared collision outcome ends the episode when the bodies touch
    collide = still.replace("outcomes: [", "outcomes: [{when: collision, reward: -1}, ")
    _, reward, terminated, _, steps = _run(collide, 0.0)
    assert (reward, terminated) == (-1.0, True) and steps == 6  # 330 mm at 60 mm a step


def test_contact_is_the_same_batched_and_one_at_a_time() -> None:
    behaviour = _behaviour(CONTACT.replace("stand, radius: 120", "chase, speed: 30"),
                           ("opponent_distance", "opponent_bearing", "pan"))
    actions = np.random.default_rng(3).uniform(-0.6, 0.6, (60, 8))
    batch = make_env(behaviour, 8)
    batch.reset(np.arange(8, dtype=np.int64))
    singles = [make_env(behaviour) for _ in range(8)]
    for b, env in enumerate(singles):
        env.reset_one(b)
    for t in range(60):
        step = batch.step(actions[t])
        for b, env in enumerate(singles):
            obs = env.step_one(float(actions[t, b]))[0]
            assert np.array_equal(obs, step.observations[b]), (t, b)
    assert isinstance(batch, PitchSim)
    assert np.array_equal(batch.x, np.array([e.x[0] for e in singles]))
    assert np.array_equal(batch.ball_x, np.array([e.ball_x[0] for e in singles]))


def test_all_any_and_held_outcomes() -> None:
    base = """  adapter: pitch
  max_steps: 30
  start:
    robot: {x: [-1000, -1000], y: [0, 0], heading: [0, 0]}
    ball: {x: [1500, 1500], y: [0, 0]}
  noise: {forward: {forward: 0, sideways: 0, rotation: 0}}
  outcomes:
"""
    # walking 60 mm a step from x = -1000: x >= -700 after 5 steps
    held = base + ("    - {all: [{when: threshold, channel: x, min: -700}, "
                   "{when: threshold, channel: y, max: 1}], held: 3, reward: 1, success: true}\n")
    _, reward, terminated, _, steps = _run(held, 0.0)
    assert (reward, terminated, steps) == (1.0, True, 7)
    either = base + ("    - {any: [{when: threshold, channel: x, min: -700}, "
                     "{when: off_pitch}], reward: 2, success: true}\n")
    assert _run(either, 0.0)[4] == 5
    never = base + ("    - {all: [{when: threshold, channel: x, min: -700}, "
                    "{when: off_pitch}], success: true}\n")
    assert _run(never, 0.0)[3]  # truncated: both never hold at once


def test_per_step_rewards_scale_a_channel() -> None:
    env_yaml = """  adapter: pitch
  max_steps: 4
  start:
    robot: {x: [-1000, -1000], y: [0, 0], heading: [0, 0]}
    ball: {x: [1500, 1500], y: [0, 0]}
  noise: {forward: {forward: 0, sideways: 0, rotation: 0}}
  rewards: [{channel: x, scale: 0.001}, {channel: y, scale: -1, abs: true}]
  outcomes: [{when: timeout, reward: 1, success: true}]
"""
    env = make_env(_behaviour(env_yaml))
    env.reset_one(0)
    rewards = [env.step_one(0.0)[1] for _ in range(4)]
    assert rewards[:3] == pytest.approx([-0.94, -0.88, -0.82])
    assert rewards[3] == pytest.approx(1.0 - 0.76)


EVERYTHING_NEW = """  adapter: pitch
  max_steps: 80
  ball: {friction: 0.05}
  start:
    robot: {x: [-1500, 0], y: [-800, 800], heading: [-90, 90]}
    ball: {x: [-500, 500], y: [-500, 500]}
    ball_velocity: {speed: [20, 60], direction: [150, 210]}
  opponents:
    - {x: [-1900, -1900], y: [-350, 350], behaviour: track, speed: 30}
    - {x: [500, 900], y: [-500, 500], behaviour: chase, speed: 20}
  channels:
    guard: {offset: [ball, own_goal, robot], noise: 20}
    between: {angle: [ball, robot, own_goal], noise: 3}
    keeper: {bearing: [robot, opponent], noise: 2}
    speed: {velocity: [robot, speed]}
  rewards: [{channel: guard, scale: -0.0001, abs: true}]
  outcomes:
    - {any: [{when: ball_in_own_goal}, {when: collision}], reward: -1}
    - {all: [{when: threshold, channel: between, min: 150}, {when: threshold, channel: ball_vx,
       max: 1}], held: 4, reward: 1, success: true}
    - {when: ball_off_pitch, reward: -1}
"""
ALL_INPUTS = ("guard", "between", "keeper", "speed", "opponent_bearing", "opponent_distance",
              "own_goal_bearing", "ball_vx", "ball_vy", "pan")


@pytest.mark.slow
def test_batched_equals_one_at_a_time_with_the_new_vocabulary() -> None:
    behaviour = _behaviour(EVERYTHING_NEW, ALL_INPUTS)
    check_env(lambda: make_env(behaviour, 4), batch_size=4)
    actions = np.random.default_rng(5).uniform(-1.2, 1.2, (80, 10))
    batch = make_env(behaviour, 10)
    obs, _ = batch.reset(np.arange(10, dtype=np.int64))
    singles = [make_env(behaviour) for _ in range(10)]
    assert all(np.array_equal(obs[b], env.reset_one(b)) for b, env in enumerate(singles))
    for t in range(80):
        step = batch.step(actions[t])
        for b, env in enumerate(singles):
            o, r, term, trunc = env.step_one(float(actions[t, b]))
            assert np.array_equal(o, step.observations[b]), (t, b)
            assert (r, term, trunc) == (step.rewards[b], step.terminated[b], step.truncated[b])
        if (step.terminated | step.truncated).all():
            break
    assert np.array_equal(batch.success(), np.array([e.success()[0] for e in singles]))


def test_start_checks_know_the_heading() -> None:
    # Near the own goal with the ball ahead and the robot facing up the pitch: the ball
    # always lands on the pitch, so this is allowed ...
    near_own_goal = """  adapter: pitch
  start:
    robot: {{x: [-1900, -1500], y: [-300, 300], heading: [{low}, {high}]}}
    ball: {{distance: [300, 1000], bearing: 30}}
"""
    env = make_env(_behaviour(near_own_goal.format(low=-30, high=30)))
    assert isinstance(env, PitchSim)
    for seed in range(50):
        env.reset_one(seed)
        assert -2100 < env.ball_x[0] < 2100 and -1900 <= env.x[0] <= -1500
    # ... but facing any way, a ball 1000 mm behind would be off the pitch
    with pytest.raises(SpecError) as caught:
        _behaviour(near_own_goal.format(low=-180, high=180))
    assert ": environment.start.robot.x:" in str(caught.value)
    assert "headings in [-180, 180]" in str(caught.value)


BAD = [
    ("  channels: {g: {offset: [ball, own_gaol, robot]}}\n", ("pan",),
     "environment.channels.g.offset", "unknown point 'own_gaol'. Did you mean 'own_goal'"),
    ("  channels: {g: {distance: [ball, goal], angle: [ball, robot, goal]}}\n", ("pan",),
     "environment.channels.g", "give exactly one of"),
    ("  channels: {g: {distance: [ball, ball]}}\n", ("pan",), "environment.channels.g.distance",
     "both 'ball'"),
    ("  channels: {pan: {distance: [ball, goal]}}\n", ("x",), "environment.channels.pan",
     "built-in channel"),
    ("  channels: {g: {bearing: [robot, opponent]}}\n", ("g",), "environment.channels.g.bearing",
     "there is none"),
    ("  channels: {g: {velocity: [ball, z]}}\n", ("pan",), "environment.channels.g.velocity[1]",
     "'x', 'y' or 'speed'"),
    ("  points: {goal: {x: 0, y: 0}}\n", ("pan",), "environment.points.goal",
     "built-in point"),
    ("  outcomes: [{all: [{when: threshold, channel: x, min: 0}, {when: off_pitch, min: 3}], "
     "success: true}]\n", ("pan",), "environment.outcomes[0].all[1]",
     "'min' does not apply to a 'off_pitch'"),
    ("  outcomes: [{any: [{when: threshold, channel: guardd, min: 0}], success: true}]\n"
     "  channels: {guard: {offset: [ball, own_goal, robot]}}\n", ("pan",),
     "environment.outcomes[0].any[0].channel", "Did you mean 'guard'"),
    ("  outcomes: [{when: ball_in_goal, all: [{when: off_pitch}], success: true}]\n", ("pan",),
     "environment.outcomes[0]", "exactly one of when, all, any"),
    ("  outcomes: [{when: ball_in_goal, success: true}, {when: timeout, held: 3}]\n", ("pan",),
     "environment.outcomes[1].held", "does not apply to a 'timeout'"),
    ("  outcomes: [{all: [{when: timeout}], success: true}]\n", ("pan",),
     "environment.outcomes[0].all[0]", "cannot be combined"),
    ("  outcomes: [{when: ball_reached, held: 0, success: true}]\n", ("pan",),
     "environment.outcomes[0].held", "greater than or equal to 1"),
    ("  rewards: [{channel: bal_x, scale: 1}]\n", ("pan",), "environment.rewards[0].channel",
     "Did you mean 'ball_x'"),
    ("  start:\n    ball_velocity: {speed: [10, 20], towards: mine}\n", ("pan",),
     "environment.start.ball_velocity.towards", "unknown point 'mine'"),
    ("  start:\n    ball_velocity: {speed: [10, 20]}\n", ("pan",),
     "environment.start.ball_velocity", "either towards"),
    ("  start:\n    ball_velocity: {speed: [20, 10], direction: [0, 0]}\n", ("pan",),
     "environment.start.ball_velocity.speed", "low <= high"),
    ("  ball: {movable: false}\n  start:\n    ball_velocity: {speed: [10, 20], direction: "
     "[0, 0]}\n", ("pan",), "environment.start.ball_velocity", "not movable"),
    ("  opponents: [{x: [2050, 2050], y: [0, 0]}]\n", ("pan",), "environment.opponents[0].x",
     "off the pitch"),
    ("  opponents: [{x: [0, 0], y: [0, 0], behaviour: dance}]\n", ("pan",),
     "environment.opponents[0].behaviour", "'stand', 'track' or 'chase'"),
    ("  outcomes: [{when: ball_in_goal, success: true}]\n", ("opponent_bearing",),
     "environment.opponents", "no opponents"),
    # the rest of the keys: each value a file can get wrong, at its own field
    ("  channels: {g: {angle: [ball, robot, ball]}}\n", ("pan",), "environment.channels.g.angle",
     "the three points must be different"),
    ("  channels: {g: {bearing: [ball, goal], noise: -1}}\n", ("pan",),
     "environment.channels.g.noise", "greater than or equal to 0"),
    ("  points: {spot: {x: 0}}\n", ("pan",), "environment.points.spot.y",
     "required field 'y' is missing"),
    ("  rewards: [{channel: ball_x}]\n", ("pan",), "environment.rewards[0].scale",
     "required field 'scale' is missing"),
    ("  rewards: [{channel: ball_x, scale: 1, abs: maybe}]\n", ("pan",),
     "environment.rewards[0].abs", "valid boolean"),
    ("  start:\n    ball_velocity: {speed: [10, 20], direction: [0, 10], spread: 100}\n",
     ("pan",), "environment.start.ball_velocity", "spread applies to towards"),
    ("  start:\n    ball_velocity: {speed: [10, 20], direction: [10, 0]}\n", ("pan",),
     "environment.start.ball_velocity.direction", "must be [low, high]"),
    ("  start:\n    ball_velocity: {speed: [10, 20], towards: goal, spread: -5}\n", ("pan",),
     "environment.start.ball_velocity.spread", "greater than or equal to 0"),
    ("  opponents: [{x: [0, 0], y: [0, 0], speed: 2000}]\n", ("pan",),
     "environment.opponents[0].speed", "less than or equal to 1000"),
    ("  opponents: [{x: [0, 0], y: [0, 0], radius: 0}]\n", ("pan",),
     "environment.opponents[0].radius", "greater than 0"),
    ("  opponents: [{x: [0, 0], y: [1400, 1400]}]\n", ("pan",), "environment.opponents[0].y",
     "off the pitch"),
    ("  opponents: [{x: [0, 0], y: [0, 0], behavior: track}]\n", ("pan",),
     "environment.opponents[0].behavior", "Did you mean 'behaviour'"),
    ("  outcomes: [{when: ball_reached, held: 2.5, success: true}]\n", ("pan",),
     "environment.outcomes[0].held", "valid integer"),
    ("  outcomes: [{any: [], success: true}]\n", ("pan",), "environment.outcomes[0].any",
     "'any' is empty"),
    ("  outcomes: [{all: [{all: [{all: [{all: [{all: [{when: off_pitch}]}]}]}]}], "
     "success: true}]\n", ("pan",), "environment.outcomes[0].all[0].all[0].all[0].all[0]",
     "nest deeper than 4 levels"),
    ("  outcomes: [{when: threshold, channel: x, success: true}]\n", ("pan",),
     "environment.outcomes[0]", "needs 'channel' and 'min' and/or 'max'"),
]


@pytest.mark.parametrize(("env_yaml", "inputs", "path", "message"), BAD)
def test_each_new_key_has_a_located_error(env_yaml: str, inputs: tuple[str, ...], path: str,
                                          message: str) -> None:
    with pytest.raises(SpecError) as caught:
        _behaviour("  adapter: pitch\n" + env_yaml, inputs)
    text = str(caught.value)
    assert f": {path}:" in text and message in text, text
    assert "p.yaml:" in text
