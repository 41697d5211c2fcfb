"""How close fit-sim's tables can come from N logged steps: per table entry, the error of the
fitted mean and standard deviation over many independent sessions, at 1,000 steps and more.

    nice -n 10 python benchmarks/fit_sim_accuracy.py [--sessions 100]

The robot is the simulator of tests/ros2/test_bags.py (non-default motion and noise tables,
``action: nearest``), driven by a uniformly random command each step. Its poses are read in
process and each step's displacement goes through fit-sim's own ``step_displacement``: over
ROS 2 the values travel as float64, so a bag gives the same samples. The estimators are the
sample mean and the sample standard deviation (n - 1), whose standard errors are
``std / sqrt(n)`` and about ``std / sqrt(2 n)``; with ~200 steps per command from 1,000
steps a standard deviation is known to ~5 % (one standard error) only. Prints, per entry,
the 95th percentile of |error| as a percentage of the true value, at each session length.
A script, never a timed test.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

from flctool.behaviour import behaviour_from_data, behaviour_to_data, load_behaviour
from flctool.envs import make_env
from flctool.ros2.bags import step_displacement

BALLCHASE = Path(__file__).resolve().parents[1] / "behaviours" / "ballchase.yaml"
KEYS = ("forward", "sideways", "rotation")
#: tests/ros2/test_bags.py's robot: faster, drifting, noisier, one-sided turns.
MOTION = {"turn_right": {"forward": 12.0, "sideways": -3.0, "rotation": -20.0},
          "forward_right": {"forward": 70.0, "sideways": -6.0, "rotation": -9.0},
          "forward": {"forward": 85.0, "sideways": 4.0, "rotation": 1.5},
          "forward_left": {"forward": 65.0, "sideways": 5.0, "rotation": 11.0},
          "turn_left": {"forward": 8.0, "sideways": 2.0, "rotation": 18.0}}
NOISE = {"turn_right": {"forward": 5.0, "sideways": 3.0, "rotation": 2.5},
         "forward_right": {"forward": 10.0, "sideways": 6.0, "rotation": 2.0},
         "forward": {"forward": 12.0, "sideways": 7.0, "rotation": 1.0},
         "forward_left": {"forward": 9.0, "sideways": 5.0, "rotation": 2.0},
         "turn_left": {"forward": 4.0, "sideways": 2.0, "rotation": 3.0}}


def session(env: object, commands: dict[str, float], steps: int, first_seed: int,
            rng: np.random.Generator) -> dict[str, list[tuple[float, float, float]]]:
    """Each command's step displacements over ``steps`` random-command steps."""
    names = list(commands)
    samples: dict[str, list[tuple[float, float, float]]] = {name: [] for name in names}
    done, seed = True, first_seed
    for _ in range(steps):
        if done:
            env.reset_one(seed)  # type: ignore[attr-defined]
            seed += 1
        before = _pose(env)
        name = names[int(rng.integers(len(names)))]
        _, _, terminated, truncated = env.step_one(commands[name])  # type: ignore[attr-defined]
        samples[name].append(step_displacement(before, _pose(env), 1.0))
        done = terminated or truncated
    return samples


def _pose(env: object) -> tuple[float, float, float]:
    state = env.trace_state()  # type: ignore[attr-defined]
    return (float(state["robot_x"][0]), float(state["robot_y"][0]),
            math.radians(float(state["robot_heading"][0])))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--sessions", type=int, default=100)
    parser.add_argument("--lengths", type=int, nargs="+", default=[1000, 10000])
    args = parser.parse_args()
    data = behaviour_to_data(load_behaviour(BALLCHASE))
    data["environment"].update(action="nearest", motion=MOTION, noise=NOISE)
    behaviour = behaviour_from_data(data)
    commands = dict(behaviour.output.commands)
    env = make_env(behaviour)
    rng = np.random.default_rng(0)
    errors: dict[int, dict[tuple[str, str, str], list[float]]] = {}
    for length in args.lengths:
        table: dict[tuple[str, str, str], list[float]] = {}
        for k in range(args.sessions):
            samples = session(env, commands, length, k * length, rng)
            for name, rows in samples.items():
                values = np.array(rows)
                for i, key in enumerate(KEYS):
                    for what, fitted, true in (
                            ("mean", values[:, i].mean(), MOTION[name][key]),
                            ("std", values[:, i].std(ddof=1), NOISE[name][key])):
                        table.setdefault((name, key, what), []).append(
                            100 * abs(fitted - true) / abs(true))
        errors[length] = table
    heads = " ".join(f"{n:>7}" for n in args.lengths)
    print(f"95th percentile of |error| in % of the true value, {args.sessions} sessions "
          "per length")
    print(f"{'command':14} {'entry':9} {'table':5} {'true':>6}  {heads}")
    for (name, key, what) in errors[args.lengths[0]]:
        true = (MOTION if what == "mean" else NOISE)[name][key]
        row = " ".join(f"{np.percentile(errors[n][(name, key, what)], 95):7.1f}"
                       for n in args.lengths)
        print(f"{name:14} {key:9} {what:5} {true:6g}  {row}")


if __name__ == "__main__":
    main()
