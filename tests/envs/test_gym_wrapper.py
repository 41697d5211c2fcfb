"""The ballchase simulator behind gymnasium.Env passes Gymnasium's own checker."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from flctool import load_behaviour
from flctool.envs import make_env
from flctool.envs.gym_wrapper import BallchaseGymEnv

from ..conftest import BEHAVIOURS


def test_passes_gymnasiums_check_env() -> None:
    env = BallchaseGymEnv(load_behaviour(BEHAVIOURS / "ballchase.yaml"))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # e.g. "no spec": not made through gymnasium.make
        check_env(env, skip_render_check=True)


def test_seed_is_the_simulators_episode_seed() -> None:
    behaviour = load_behaviour(BEHAVIOURS / "ballchase.yaml")
    env = BallchaseGymEnv(behaviour)
    obs, _ = env.reset(seed=9)
    assert np.array_equal(obs, make_env(behaviour).reset_one(9))
    assert env.observation_space.contains(obs)
    obs, reward, _, _, info = env.step(np.array([0.5], dtype=np.float32))
    assert isinstance(reward, float)
    assert env.observation_space.contains(obs) and info == {}


@pytest.mark.slow
def test_every_shipped_pitch_behaviour_is_registered_and_passes_check_env() -> None:
    import gymnasium as gym

    from flctool.envs.gym_wrapper import shipped_pitch_behaviours

    names = shipped_pitch_behaviours()
    assert {"dribble", "face-goal", "return-home", "avoid-obstacle", "defend", "shoot",
            "approach", "striker"} <= set(names)
    for name in names:
        for env_id in (f"flctool/{name}-v0", f"flctool/{name}-discrete-v0"):
            env = gym.make(env_id)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                check_env(env.unwrapped, skip_render_check=True)
            # random actions until the episode ends: observations stay normalised
            obs, _ = env.reset(seed=3)
            env.action_space.seed(3)
            for _ in range(env.unwrapped.sim.max_steps):
                obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
                assert env.observation_space.contains(obs) and np.isfinite(reward)
                if terminated or truncated:
                    assert isinstance(info["success"], bool)
                    break
            else:
                raise AssertionError(f"{env_id}: the episode did not end")
            env.close()


def test_any_pitch_file_by_the_generic_id() -> None:
    import gymnasium as gym

    import flctool.envs.gym_wrapper  # noqa: F401 - registers the ids

    behaviour = load_behaviour(BEHAVIOURS / "dribble.yaml")
    env = gym.make("flctool/PitchDiscrete-v0", behaviour=behaviour)
    assert env.action_space.n == 5
    obs, _ = env.reset(seed=9)
    raw = make_env(behaviour).reset_one(9)
    low, high = (np.array([v.range[i] for v in behaviour.inputs.values()]) for i in (0, 1))
    assert np.allclose(obs, 2 * (np.clip(raw, low, high) - low) / (high - low) - 1)
    # action 0 runs the command of the smallest singleton: turn_right, about -15 deg
    before = float(env.unwrapped.sim.heading[0])
    env.step(0)
    assert np.degrees(float(env.unwrapped.sim.heading[0]) - before) < -8.0
