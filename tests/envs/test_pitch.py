"""The pitch world: one dynamics for both paths, ballchase as a preset, sensors, outcomes,
ball dynamics, and configuration errors."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flctool import compile_behaviour, load_behaviour, parse_behaviour
from flctool.envs import check_env, make_env
from flctool.envs.pitch import PitchSim
from flctool.errors import SpecError
from flctool.rollout import evaluate

from ..conftest import BEHAVIOURS

HEAD = """flctool: 1
name: probe
inputs:
{inputs}
output:
  name: turn
  commands: {{turn_right: -1.0, forward_right: -0.5, forward: 0.0, forward_left: 0.5,
             turn_left: 1.0}}
rules: []
environment:
"""
TWO_SETS = ("    range: [{lo}, {hi}]\n"
            "    sets: {{low: [{lo}, {lo}, {lo}, {hi}], high: [{lo}, {hi}, {hi}, {hi}]}}\n")
RANGES = {"ball_size": (0, 1), "pan": (-90, 90), "ball_distance": (0, 6000),
          "goal_bearing": (-180, 180), "goal_distance": (0, 6000),
          "obstacle_bearing": (-180, 180), "obstacle_distance": (0, 6000),
          "home_bearing": (-180, 180), "home_distance": (0, 6000), "heading": (-180, 180),
          "x": (-3000, 3000), "y": (-2000, 2000), "ball_x": (-3000, 3000),
          "ball_y": (-2000, 2000)}


def _behaviour(environment: str, inputs: tuple[str, ...] = ("pan",), file: str = "p.yaml"):
    text = HEAD.format(inputs="".join(
        f"  {name}:\n" + TWO_SETS.format(lo=RANGES.get(name, (0, 1))[0],
                                         hi=RANGES.get(name, (0, 1))[1]) for name in inputs))
    return parse_behaviour(text + environment, file)


EVERYTHING = """  adapter: pitch
  max_steps: 120
  ball: {kick: 1.5, friction: 0.2}
  start:
    robot: {x: [-1500, -500], y: [-500, 500], heading: [-60, 60]}
    ball: {x: [-300, 300], y: [-300, 300]}
  obstacles:
    - {x: [500, 1000], y: [-800, 800], radius: 120, speed: 25}
    - {x: [-1800, -1600], y: [800, 1000]}
  outcomes:
    - {when: ball_in_goal, reward: 1, success: true}
    - {when: collision, reward: -1}
    - {when: ball_off_pitch, reward: -0.5}
    - {when: off_pitch, reward: -1}
"""


def test_passes_the_adapter_checker() -> None:
    behaviour = _behaviour(EVERYTHING, tuple(RANGES))
    check_env(lambda: make_env(behaviour, 4), batch_size=4)
    check_env(make_env(behaviour), batch_size=3)


@pytest.mark.slow
def test_batched_equals_one_at_a_time_on_every_channel() -> None:
    # The two paths run the same functions on floats and on arrays; this checks it holds
    # for every channel, a rolling ball and moving obstacles, bit for bit.
    behaviour = _behaviour(EVERYTHING, tuple(RANGES))
    actions = np.random.default_rng(1).uniform(-1.2, 1.2, (120, 12))
    batch = make_env(behaviour, 12)
    obs, _ = batch.reset(np.arange(12, dtype=np.int64))
    singles = [make_env(behaviour) for _ in range(12)]
    single_obs = [env.reset_one(seed) for seed, env in enumerate(singles)]
    assert all(np.array_equal(obs[b], single_obs[b]) for b in range(12))
    moved = False
    for t in range(120):
        step = batch.step(actions[t])
        for b, env in enumerate(singles):
            o, r, term, trunc = env.step_one(float(actions[t, b]))
            assert np.array_equal(o, step.observations[b]), (t, b)
            assert (r, term, trunc) == (step.rewards[b], step.terminated[b], step.truncated[b])
            for key, value in env.trace_state().items():
                assert value[0] == batch.trace_state()[key][b], (t, b, key)
        moved |= bool(np.any(batch.ball_x != batch.ball_x[0]))
        if (step.terminated | step.truncated).all():
            break
    assert moved
    assert np.array_equal(batch.success(), np.array([e.success()[0] for e in singles]))


def test_ballchase_is_a_preset_of_the_pitch_world() -> None:
    # The pitch world declared like ballchase gives ballchase's episodes, bit for bit.
    chase = load_behaviour(BEHAVIOURS / "ballchase-handmade.yaml")
    text = (BEHAVIOURS / "ballchase-handmade.yaml").read_text()
    pitch = parse_behaviour(text[: text.index("environment:")] + """environment:
  adapter: pitch
  ball: {movable: false}
  start:
    robot: {x: [-1950, 1950], y: [-1200, 1200], heading: [-180, 180]}
    ball: {distance: [400, 2000], bearing: 60}
  outcomes:
    - {when: ball_reached, reward: 1, success: true}
    - {when: ball_lost, reward: -1}
    - {when: off_pitch, reward: -1}
""")
    controller = compile_behaviour(chase)
    seeds = np.arange(100)
    table = np.random.default_rng(2).integers(0, 5, controller.n_rules)
    for consequents in (None, table):
        a = evaluate(controller, make_env(chase, 100), seeds, consequents)
        b = evaluate(controller, make_env(pitch, 100), seeds, consequents)
        assert np.array_equal(a.lengths, b.lengths) and np.array_equal(a.fitness, b.fitness)
        assert np.array_equal(a.returns, b.returns)


def _start_state(environment: str, inputs: tuple[str, ...]) -> tuple[PitchSim, np.ndarray]:
    env = make_env(_behaviour(environment, inputs))
    assert isinstance(env, PitchSim)
    return env, env.reset_one(0)


def test_channels_read_the_geometry() -> None:
    exact = """  adapter: pitch
  home: {x: -1000, y: 0}
  start:
    robot: {x: [0, 0], y: [0, 0], heading: [90, 90]}
    ball: {x: [0, 0], y: [1000, 1000]}
  obstacles: [{x: [-500, -500], y: [0, 0], radius: 100}]
  sensor_noise: {ball_size: 0, pan: 0, ball_distance: 0, goal_bearing: 0, goal_distance: 0,
                 obstacle_bearing: 0, obstacle_distance: 0, home_bearing: 0, home_distance: 0,
                 heading: 0, x: 0, y: 0, ball_x: 0, ball_y: 0}
"""
    names = tuple(RANGES)
    _, obs = _start_state(exact, names)
    read = dict(zip(names, obs.tolist(), strict=True))
    # facing +y (left of the pitch), the ball straight ahead 1000 mm from the body centre
    assert read["pan"] == pytest.approx(0.0, abs=1e-9)
    assert read["ball_distance"] == pytest.approx(900.0)  # from the camera, 100 mm ahead
    assert read["goal_bearing"] == pytest.approx(-90.0)  # the target goal (+x) is right
    assert read["goal_distance"] == pytest.approx(2100.0)
    assert read["home_bearing"] == pytest.approx(90.0) and read["home_distance"] == 1000.0
    assert read["obstacle_bearing"] == pytest.approx(90.0)
    assert read["obstacle_distance"] == pytest.approx(500.0 - 150.0 - 100.0)  # surfaces
    assert read["heading"] == pytest.approx(90.0)
    assert (read["x"], read["y"]) == (0.0, 0.0)
    assert (read["ball_x"], read["ball_y"]) == (0.0, 1000.0)


@pytest.mark.slow
def test_sensors_map_inputs_to_channels_with_their_noise() -> None:
    env_yaml = """  adapter: pitch
  sensors: {where: goal_bearing}
  sensor_noise: {goal_bearing: 0}
  start: {robot: {x: [0, 0], y: [0, 0], heading: [30, 30]}}
"""
    _, obs = _start_state(env_yaml, ("where",))
    assert obs[0] == pytest.approx(-30.0)
    noisy = env_yaml.replace("goal_bearing: 0", "goal_bearing: 10")
    readings = [make_env(_behaviour(noisy, ("where",))).reset_one(s)[0] for s in range(400)]
    assert np.std(readings) == pytest.approx(10.0, rel=0.15)
    assert np.mean(readings) == pytest.approx(-30.0, abs=1.5)


def _run(environment: str, action: float, inputs: tuple[str, ...] = ("pan",), seed: int = 0,
         ) -> tuple[PitchSim, float, bool, bool, int]:
    env = make_env(_behaviour(environment, inputs))
    assert isinstance(env, PitchSim)
    env.reset_one(seed)
    for t in range(1, env.max_steps + 1):
        _, reward, terminated, truncated = env.step_one(action)
        if terminated or truncated:
            return env, reward, terminated, truncated, t
    raise AssertionError("the episode did not end")


STRAIGHT = """  adapter: pitch
  max_steps: {steps}
  start:
    robot: {{x: [-1000, -1000], y: [0, 0], heading: [0, 0]}}
    ball: {{x: [{ball}, {ball}], y: [0, 0]}}
  noise: {{forward: {{forward: 0, sideways: 0, rotation: 0}}}}
"""


def test_pushed_ball_rolls_into_the_goal() -> None:
    # walking straight at the ball pushes it; it rolls, slows, and is pushed again until in
    env_yaml = STRAIGHT.format(steps=150, ball=-500) + """  outcomes:
    - {when: ball_in_goal, reward: 1, success: true}
    - {when: off_pitch, reward: -1}
"""
    env, reward, terminated, _, steps = _run(env_yaml, 0.0)
    assert terminated and reward == 1.0 and env.success()[0]
    assert env.ball_x[0] > 2100.0 and steps < 70  # 3100 mm at 60 mm a step, helped by kicks


def test_ball_rolls_and_slows_after_a_kick() -> None:
    env = make_env(_behaviour(STRAIGHT.format(steps=50, ball=-780) + """\
  ball: {kick: 2, friction: 0.5}
  outcomes: [{when: timeout, success: true}]
""", ("pan",)))
    env.reset_one(0)
    positions = []
    for _ in range(4):
        env.step_one(0.0)
        positions.append(float(env.ball_x[0]))
    gaps = np.diff(positions)
    assert gaps[0] > 0 and all(np.diff(gaps) < 0)


def test_static_ball_never_moves() -> None:
    env_yaml = STRAIGHT.format(steps=40, ball=-500) + """  ball: {movable: false}
  outcomes:
    - {when: ball_in_goal, success: true}
"""
    env, _, _, truncated, steps = _run(env_yaml, 0.0)
    assert truncated and steps == 40 and env.ball_x[0] == -500.0


@pytest.mark.parametrize(("outcomes", "reward", "success"), [
    ("- {when: collision, reward: -1}\n    - {when: timeout, success: true}", -1.0, False),
    ("- {when: threshold, channel: x, min: 0, reward: 2, success: true}", 2.0, True),
    ("- {when: off_pitch, reward: -1}\n    - {when: timeout, reward: 0.5, success: true}",
     -1.0, False),
])
def test_outcomes_end_the_episode(outcomes: str, reward: float, success: bool) -> None:
    env_yaml = STRAIGHT.format(steps=120, ball=1500) + f"""  ball: {{movable: false}}
  obstacles: [{{x: [-200, -200], y: [0, 0]}}]
  outcomes:
    {outcomes}
"""
    env, got, terminated, truncated, _ = _run(env_yaml, 0.0, ("goal_bearing",))
    assert (got, terminated, truncated, bool(env.success()[0])) == (reward, True, False, success)


def test_declared_timeout_can_be_a_success() -> None:
    env_yaml = STRAIGHT.format(steps=10, ball=1500) + """  outcomes:
    - {when: off_pitch, reward: -1}
    - {when: timeout, reward: 0.5, success: true}
"""
    env, reward, terminated, truncated, steps = _run(env_yaml, 1.0, ("goal_bearing",))
    assert (reward, terminated, truncated, steps) == (0.5, False, True, 10)
    assert env.success()[0]
    fitness = env.episode_fitness(np.array([0.5]), np.array([10]), env.success())
    assert fitness[0] == 1.0  # success after all T steps


def test_ball_reached_facing_the_goal() -> None:
    facing = """  adapter: pitch
  start:
    robot: {{x: [0, 0], y: [0, 0], heading: [{h}, {h}]}}
    ball: {{distance: [110, 110], bearing: 0}}
  sensor_noise: {{pan: 0}}
  outcomes:
    - {{when: ball_reached, facing_goal: 20, reward: 1, success: true}}
"""
    env, reward, _, _, steps = _run(facing.format(h=0), 0.0)
    assert reward == 1.0 and steps == 1
    env, _, _, truncated, steps = _run(
        facing.format(h=60) + "  max_steps: 3\n", 0.0)
    assert truncated and not env.success()[0]


def test_moving_obstacles_stay_on_the_pitch() -> None:
    env = make_env(_behaviour("""  adapter: pitch
  max_steps: 400
  obstacles: [{x: [1800, 1900], y: [1000, 1100], speed: 80}]
  outcomes: [{when: timeout, success: true}]
""", ("obstacle_distance",)), 8)
    env.reset(np.arange(8, dtype=np.int64))
    assert isinstance(env, PitchSim)
    for _ in range(400):
        env.step(np.zeros(8))
        for ob in env._engine.state.obstacles:
            assert np.all(np.abs(ob[0]) <= 2100 + 80) and np.all(np.abs(ob[1]) <= 1350 + 80)


BAD = [
    ("  adapter: pitch\n", ("goal_bering",), "inputs.goal_bering",
     "no channel 'goal_bering'. Did you mean 'goal_bearing'"),
    ("  adapter: pitch\n  sensors: {where: goal_bearng}\n", ("where",),
     "environment.sensors.where", "Did you mean 'goal_bearing'"),
    ("  adapter: pitch\n  sensors: {nothere: pan}\n", ("pan",), "environment.sensors.nothere",
     "'nothere' is not an input"),
    ("  adapter: pitch\n", ("obstacle_distance",), "environment.obstacles",
     "no obstacles"),
    ("  adapter: pitch\n  outcomes: [{when: off_pitch, channel: x, min: 0, success: true}]\n",
     ("pan",), "environment.outcomes[0]", "'channel' does not apply to a 'off_pitch'"),
    ("  adapter: pitch\n  outcomes: [{when: threshold, channel: headng, max: 3}]\n", ("pan",),
     "environment.outcomes[0].channel", "Did you mean 'heading'"),
    ("  adapter: pitch\n  outcomes: [{when: off_pitch, reward: -1}]\n", ("pan",),
     "environment.outcomes", "no outcome is a success"),
    ("  adapter: pitch\n  motion: {fwd: {forward: 1, sideways: 0, rotation: 0}}\n", ("pan",),
     "environment.motion.fwd", "not an output command"),
    ("  adapter: pitch\n  start: {ball: {x: [0, 1]}}\n", ("pan",), "environment.start.ball",
     "give either x and y"),
    ("  adapter: pitch\n  start: {robot: {x: [5, 1]}}\n", ("pan",), "environment.start.robot.x",
     "low <= high"),
    ("  adapter: pitch\n  start: {robot: {x: [-3000, 0]}}\n", ("pan",),
     "environment.start.robot.x", "off the pitch"),
]


@pytest.mark.parametrize(("env_yaml", "inputs", "path", "message"), BAD)
def test_bad_world_is_a_located_error(env_yaml: str, inputs: tuple[str, ...], path: str,
                                      message: str) -> None:
    with pytest.raises(SpecError) as caught:
        _behaviour(env_yaml, inputs)
    text = str(caught.value)
    assert f": {path}:" in text and message in text, text
    assert "p.yaml:" in text


@pytest.mark.parametrize("name", ["face-goal", "return-home", "avoid-obstacle", "dribble"])
def test_shipped_pitch_behaviours_are_pitch_worlds(name: str) -> None:
    behaviour = load_behaviour(BEHAVIOURS / f"{name}.yaml")
    assert behaviour.environment is not None and behaviour.environment.adapter == "pitch"
    assert math.isfinite(float(make_env(behaviour).reset_one(0)[0]))


@pytest.mark.parametrize(("action", "votes"), [("crisp", False), ("nearest", False),
                                               ("vote", True)])
def test_action_modes(action: str, votes: bool) -> None:
    still = "{forward: 0, sideways: 0, rotation: 0}"
    env = make_env(_behaviour(f"  adapter: pitch\n  action: {action}\n"
                              f"  noise: {{forward: {still}, forward_left: {still}}}\n"))
    assert env.votes is votes
    env.reset_one(0)
    heading = float(env.heading[0])
    env.step_one(0.3)  # crisp blends forward and forward_left; the others run forward_left
    turned = math.degrees(float(env.heading[0]) - heading)
    expected = 0.6 * 7.5 if action == "crisp" else 7.5
    assert turned == pytest.approx(expected)
