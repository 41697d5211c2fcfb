"""Simulator throughput: one episode at a time (B = 1) against 1000 in lock-step, CPU time.

    python benchmarks/bench_sim.py [--episodes 1000]

Two worlds: ballchase (a preset of the pitch world) and the pitch world of
``behaviours/dribble-handmade.yaml`` (a ball that rolls when pushed, four more channels'
arithmetic, six outcomes). The policy is a cheap proportional chase (turn towards the pan
angle) so that the figures are the simulator's own cost; the last lines add the handmade
controller's inference through ``flctool.rollout.evaluate``. Times are process CPU time
(the machine may be shared). A script, never a timed test.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from flctool import compile_behaviour, load_behaviour
from flctool.envs import make_env
from flctool.rollout import evaluate

BEHAVIOURS = Path(__file__).resolve().parents[1] / "behaviours"
HANDMADE = BEHAVIOURS / "ballchase-handmade.yaml"
WORLDS = [HANDMADE, BEHAVIOURS / "dribble-handmade.yaml"]  # both read pan as input 1 or 0


def _pan(path: Path) -> int:
    return list(load_behaviour(path).inputs).index("pan")


def one_at_a_time(path: Path, episodes: int) -> tuple[int, float, float]:
    """Steps, seconds stepping, seconds resetting."""
    env = make_env(load_behaviour(path), 1)
    pan = _pan(path)
    steps = 0
    resetting = 0.0
    start = time.process_time()
    for seed in range(episodes):
        before = time.process_time()
        obs = env.reset_one(seed)
        resetting += time.process_time() - before
        while True:
            obs, _, terminated, truncated = env.step_one(max(-1.0, min(1.0, obs[pan] / 60.0)))
            steps += 1
            if terminated or truncated:
                break
    return steps, time.process_time() - start - resetting, resetting


def batched(path: Path, episodes: int) -> tuple[int, float, float]:
    env = make_env(load_behaviour(path), episodes)
    pan = _pan(path)
    steps = 0
    start = time.process_time()
    obs, _ = env.reset(np.arange(episodes, dtype=np.int64))
    resetting = time.process_time() - start
    start = time.process_time()
    done = np.zeros(episodes, dtype=bool)
    while not done.all():
        steps += int((~done).sum())
        step = env.step(np.clip(obs[:, pan] / 60.0, -1.0, 1.0))
        obs, done = step.observations, step.terminated | step.truncated
    return steps, time.process_time() - start, resetting


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=1000)
    episodes = parser.parse_args().episodes
    for path in WORLDS:
        _simulator(path, episodes)
    _with_inference(episodes)


def _simulator(path: Path, episodes: int) -> None:
    one_steps, one_time, one_reset = one_at_a_time(path, episodes)
    batch_steps, batch_time, batch_reset = batched(path, episodes)
    assert one_steps == batch_steps  # the same episodes, bit for bit
    print(f"simulator, {path.name}, {episodes} episodes, {one_steps} steps")
    print(f"  one at a time (B=1, step_one): {one_steps / one_time:12,.0f} steps/s "
          f"({1e6 * one_time / one_steps:.2f} us/step, {1e6 * one_reset / episodes:.1f} "
          "us/reset)")
    print(f"  batched (B={episodes}):{'':10}{batch_steps / batch_time:12,.0f} steps/s "
          f"({1e6 * batch_time / batch_steps:.2f} us/step, {1e6 * batch_reset / episodes:.1f} "
          "us/reset)")
    print(f"  batched / one at a time, steps: {one_time / batch_time:.1f} x; with resets: "
          f"{(one_time + one_reset) / (batch_time + batch_reset):.1f} x")


def _with_inference(episodes: int) -> None:
    behaviour = load_behaviour(HANDMADE)
    controller = compile_behaviour(behaviour)
    seeds = np.arange(episodes, dtype=np.int64)
    single = make_env(behaviour, 1)
    start = time.process_time()
    lengths = [int(evaluate(controller, single, [s]).lengths[0]) for s in seeds]
    loop_time = time.process_time() - start
    start = time.process_time()
    result = evaluate(controller, make_env(behaviour, episodes), seeds)
    lock_time = time.process_time() - start
    assert lengths == result.lengths.tolist()
    print(f"rollout.evaluate with the handmade controller, {int(result.lengths.sum())} steps")
    print(f"  {episodes} x evaluate(B=1): {loop_time:.3f} s;  evaluate(B={episodes}): "
          f"{lock_time:.3f} s;  ratio {loop_time / lock_time:.1f} x")


if __name__ == "__main__":
    main()
