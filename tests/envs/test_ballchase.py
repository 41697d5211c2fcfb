"""The ballchase simulator: determinism, batched == one at a time, outcomes, config errors."""

from __future__ import annotations

import numpy as np
import pytest

from flctool import compile_behaviour, load_behaviour, parse_behaviour
from flctool.behaviour.environment import DEFAULT_MOTION, DEFAULT_NOISE, BallchaseSimConfig
from flctool.envs import check_env, make_env
from flctool.envs.ballchase import BallchaseSim
from flctool.errors import SpecError
from flctool.rollout import evaluate

from ..conftest import BEHAVIOURS

HANDMADE = BEHAVIOURS / "ballchase-handmade.yaml"


def _with_environment(env_yaml: str, rules: bool = True) -> str:
    text = HANDMADE.read_text()
    head = text[: text.index("environment:")]
    if not rules:
        head = head[: head.index("rules:")] + "rules: []\n" + head[head.index("learning:"):]
    return head + env_yaml


def _trajectory(env: BallchaseSim, seed: int, actions: np.ndarray) -> list[np.ndarray]:
    states = [env.reset_one(seed)]
    for a in actions:
        obs, _, terminated, truncated = env.step_one(float(a))
        states.append(np.concatenate([obs, env.x, env.y, env.heading]))
        if terminated or truncated:
            break
    return states


def test_passes_the_adapter_checker() -> None:
    behaviour = load_behaviour(HANDMADE)
    check_env(lambda: make_env(behaviour, 5), batch_size=5)
    check_env(make_env(behaviour), batch_size=3)  # one instance, reset between runs


def test_same_seed_same_trajectory_bit_for_bit() -> None:
    behaviour = load_behaviour(HANDMADE)
    actions = np.random.default_rng(3).uniform(-1, 1, 200)
    first = _trajectory(make_env(behaviour), 11, actions)
    second = _trajectory(make_env(behaviour), 11, actions)
    assert len(first) == len(second) > 1
    assert all(np.array_equal(a, b) for a, b in zip(first, second, strict=True))
    other = _trajectory(make_env(behaviour), 12, actions)
    assert not np.array_equal(first[0], other[0])


@pytest.mark.parametrize("action", ["crisp", "nearest"])
def test_batched_equals_one_at_a_time(action: str) -> None:
    behaviour = parse_behaviour(_with_environment(
        f"environment: {{adapter: ballchase-sim, action: {action}}}\n"))
    controller = compile_behaviour(behaviour)
    consequents = np.random.default_rng(0).integers(0, 5, size=(4, controller.n_rules))
    consequents[0] = controller.consequents  # one that succeeds, three random ones
    seeds = np.arange(40, dtype=np.int64)
    batch_env, one_env = make_env(behaviour, 40), make_env(behaviour)
    for table in consequents:
        together = evaluate(controller, batch_env, seeds, table)
        for i, seed in enumerate(seeds):
            alone = evaluate(controller, one_env, [seed], table)
            assert alone.returns[0] == together.returns[i]
            assert alone.lengths[0] == together.lengths[i]
            assert alone.fitness[0] == together.fitness[i]
    # and the batch's final poses equal the single episodes' (the pose is where bits drift)
    for seed in (0, 7, 39):
        evaluate(controller, one_env, [seed], consequents[1])
        evaluate(controller, batch_env, seeds, consequents[1])
        for key, value in one_env.trace_state().items():
            assert value[0] == batch_env.trace_state()[key][seed], key


@pytest.mark.slow
def test_one_at_a_time_gives_the_batched_bits_over_many_random_states() -> None:
    # One dynamics (envs/pitch.py's _advance and _sense) runs on floats for reset_one and
    # step_one and on arrays for reset and step: over many random starts and actions, noise
    # on, the learners' path and the evaluation path give the same bits at every step.
    behaviour = load_behaviour(HANDMADE)
    count = 300
    rng = np.random.default_rng(5)
    seeds = rng.integers(0, 2**62, count, dtype=np.int64)
    batch = make_env(behaviour, count)
    actions = rng.uniform(-1.5, 1.5, (batch.max_steps, count))
    history = [batch.reset(seeds)[0]]
    outcomes, poses = [], []
    for row in actions:
        step = batch.step(row)
        history.append(step.observations.copy())
        outcomes.append((step.rewards.copy(), step.terminated.copy(), step.truncated.copy()))
        poses.append({k: v.copy() for k, v in batch.trace_state().items()})
        if (step.terminated | step.truncated).all():
            break
    single = make_env(behaviour)
    steps = 0
    for b, seed in enumerate(seeds.tolist()):
        assert np.array_equal(single.reset_one(seed), history[0][b])
        for t, (rewards, terminated, truncated) in enumerate(outcomes):
            obs, reward, term, trunc = single.step_one(float(actions[t, b]))
            steps += 1
            assert np.array_equal(obs, history[t + 1][b]), (seed, t)
            assert (reward, term, trunc) == (rewards[b], terminated[b], truncated[b]), (seed, t)
            for key, value in single.trace_state().items():
                assert value[0] == poses[t][key][b], (seed, t, key)
            if term or trunc:
                break
        assert single.success()[0] == batch.success()[b]
    assert steps > 10 * count  # the episodes ran, not just their starts


def test_finished_episode_is_unchanged() -> None:
    env = make_env(load_behaviour(HANDMADE), 2)
    env.reset(np.array([1, 2]))
    step = env.step(np.array([1.0, -1.0]))
    for _ in range(env.max_steps):
        step = env.step(np.array([1.0, -1.0]))  # turning on the spot loses the ball
        if (step.terminated | step.truncated).all():
            break
    frozen = (step.observations.copy(), env.trace_state())
    again = env.step(np.array([0.0, 0.0]))
    assert np.array_equal(again.observations, frozen[0])
    assert not again.rewards.any()
    for key, value in env.trace_state().items():
        assert np.array_equal(value, frozen[1][key])


def test_outcomes_and_rewards() -> None:
    behaviour = load_behaviour(HANDMADE)
    controller = compile_behaviour(behaviour)
    env = make_env(behaviour, 200)
    result = evaluate(controller, env, np.arange(200))
    assert set(np.unique(result.returns)) <= {-1.0, 0.0, 1.0}
    assert np.array_equal(result.success, result.returns == 1.0)
    assert result.success.mean() > 0.9
    # turning on the spot forever keeps neither the ball in view nor scores
    spinning = evaluate(controller, env, np.arange(50), np.full(controller.n_rules, 4))
    assert not spinning.success.any()
    assert (spinning.returns == -1).all()


def test_fitness_prefers_faster_success() -> None:
    env = make_env(load_behaviour(HANDMADE))
    fitness = env.episode_fitness(np.array([1.0, 1.0, 0.0, -1.0, -1.0]),
                                  np.array([10, 100, 200, 150, 5]),
                                  np.array([True, True, False, False, False]))
    assert fitness[0] > fitness[1] > 1.0 > fitness[2] > fitness[3] > fitness[4] >= 0.0


def test_observations_follow_the_behaviour_inputs() -> None:
    behaviour = load_behaviour(HANDMADE)
    env = make_env(behaviour)
    assert env.observation_names == ("ball_size", "pan")
    obs = env.reset_one(4)
    assert 0.0 <= obs[0] <= 1.0 and -90.0 <= obs[1] <= 90.0
    config = behaviour.environment
    assert isinstance(config, BallchaseSimConfig)
    swapped = BallchaseSim(config, dict(behaviour.output.commands), ("pan", "ball_size"))
    assert np.array_equal(swapped.reset_one(4), obs[::-1])
    pan_only = BallchaseSim(config, dict(behaviour.output.commands), ("pan",))
    assert np.array_equal(pan_only.reset_one(4), obs[1:])


def test_action_nearest_executes_one_command() -> None:
    behaviour = parse_behaviour(_with_environment(
        "environment:\n  adapter: ballchase-sim\n  action: nearest\n"
        "  sensor_noise: {ball_size: 0, pan: 0}\n"
        "  noise:\n" + "".join(
            f"    {n}: {{forward: 0, sideways: 0, rotation: 0}}\n"
            for n in ("turn_right", "forward_right", "forward", "forward_left", "turn_left"))))
    env = make_env(behaviour)
    env.reset_one(0)
    heading = float(env.heading[0])
    env.step_one(0.8)  # nearest is turn_left: 15 deg, no noise
    assert float(env.heading[0]) - heading == pytest.approx(np.radians(15.0))


BAD_ENVIRONMENTS = [
    ("environment: {adapter: ballchase-simulator}\n", "environment.adapter",
     "Did you mean 'ballchase-sim'"),
    ("environment:\n  adapter: ballchase-sim\n  noise:\n"
     "    forward: {forward: 8, sideways: 5, rotation: -1}\n", "environment.noise.forward",
     "greater than or equal to 0"),
    ("environment:\n  adapter: ballchase-sim\n  pitch: {length: 1000, width: 800}\n",
     "environment.pitch", "too small for the robot"),
    ("environment:\n  adapter: ballchase-sim\n  sensor_noise: {pan: -2}\n",
     "environment.sensor_noise.pan", "greater than or equal to 0"),
    ("environment:\n  adapter: ballchase-sim\n  goal: {distance: 500}\n", "environment.goal",
     "below the nearest start distance"),
    ("environment:\n  adapter: ballchase-sim\n  start: {bearing: 120}\n", "environment.start",
     "beyond the neck range"),
    ("environment:\n  adapter: ballchase-sim\n  motion:\n"
     "    forwrd: {forward: 70, sideways: 0, rotation: 0}\n", "environment.motion.forwrd",
     "'forwrd' is not an output command. Did you mean 'forward'"),
    ("environment:\n  adapter: ballchase-sim\n  noise:\n"
     "    turn_lft: {forward: 1, sideways: 1, rotation: 1}\n", "environment.noise.turn_lft",
     "Did you mean 'turn_left'"),
]


@pytest.mark.parametrize(("env_yaml", "path", "message"), BAD_ENVIRONMENTS)
def test_bad_environment_is_a_located_error(env_yaml: str, path: str, message: str) -> None:
    with pytest.raises(SpecError) as caught:
        parse_behaviour(_with_environment(env_yaml), "chase.yaml")
    text = str(caught.value)
    assert f": {path}" in text and message in text, text
    assert "chase.yaml:" in text  # located by line


def test_command_without_motion_names_the_field() -> None:
    # caught when the file is validated, not only when a run starts
    text = _with_environment("environment: {adapter: ballchase-sim}\n", rules=False)
    with pytest.raises(SpecError, match=r"b.yaml:\d+:1: environment\.motion: output command "
                                        r"'kick' has no motion"):
        parse_behaviour(text.replace("    turn_left: 1.0\n", "    turn_left: 1.0\n    kick: 2.0\n"),
                        "b.yaml")


def test_command_without_noise_names_the_field() -> None:
    text = _with_environment("environment:\n  adapter: ballchase-sim\n  motion:\n"
                             "    kick: {forward: 90, sideways: 0, rotation: 0}\n", rules=False)
    with pytest.raises(SpecError, match=r"b.yaml:\d+:\d+: environment\.noise: no noise for "
                                        r"command kick"):
        parse_behaviour(text.replace("    turn_left: 1.0\n", "    turn_left: 1.0\n    kick: 2.0\n"),
                        "b.yaml")


def test_unknown_observation_names_the_input() -> None:
    text = _with_environment("environment: {adapter: ballchase-sim}\n", rules=False)
    with pytest.raises(SpecError, match=r"b.yaml:\d+:3: inputs\.tilt: the ballchase simulator "
                                        r"has no observation 'tilt'"):
        parse_behaviour(text.replace("  pan:\n", "  tilt:\n"), "b.yaml")


def test_partial_motion_table_extends_the_defaults() -> None:
    behaviour = parse_behaviour(_with_environment(
        "environment:\n  adapter: ballchase-sim\n  motion:\n"
        "    forward: {forward: 80, sideways: 0, rotation: 0}\n"
        "  noise:\n    turn_left: {forward: 0, sideways: 0, rotation: 0}\n"))
    config = behaviour.environment
    assert isinstance(config, BallchaseSimConfig)
    assert config.motion["forward"].forward == 80
    assert config.motion["turn_left"] == DEFAULT_MOTION["turn_left"]  # kept, not replaced
    assert config.noise["turn_left"].rotation == 0
    assert config.noise["forward"] == DEFAULT_NOISE["forward"]
    assert set(config.motion) == set(DEFAULT_MOTION)


def test_misspelt_command_is_located_by_line() -> None:
    text = _with_environment("environment:\n  adapter: ballchase-sim\n  motion:\n"
                             "    forwrd: {forward: 70, sideways: 0, rotation: 0}\n")
    line = text.splitlines().index("    forwrd: {forward: 70, sideways: 0, rotation: 0}") + 1
    with pytest.raises(SpecError, match=rf"b.yaml:{line}:\d+: environment\.motion\.forwrd"):
        parse_behaviour(text, "b.yaml")


def test_episodes_are_those_of_the_first_release() -> None:
    # Figures recorded with the simulator before it became a preset of the pitch world: the
    # same seeds must keep giving the same episodes, to the last bit.
    behaviour = load_behaviour(HANDMADE)
    controller = compile_behaviour(behaviour)
    env = make_env(behaviour)
    result = evaluate(controller, env, np.arange(200))
    assert (int(result.lengths.sum()), float(result.fitness.sum())) == (4164, 379.18)
    table = np.array([4, 3, 2, 1, 1, 0, 0, 0, 0, 4, 3, 4, 2, 3, 4])
    result = evaluate(controller, make_env(behaviour, 200), np.arange(200), table)
    assert (int(result.lengths.sum()), float(result.fitness.sum()),
            int(result.success.sum())) == (1552, 13.3475, 5)
    evaluate(controller, env, [3])
    assert (float(env.x[0]), float(env.y[0]), float(env.heading[0])) == (
        336.40049678082136, -593.7193542029227, 1.2884405221715665)
