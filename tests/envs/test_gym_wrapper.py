"""The ballchase simulator behind gymnasium.Env passes Gymnasium's own checker."""

from __future__ import annotations

import warnings

import numpy as np
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
