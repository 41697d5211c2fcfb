"""flctool's learners against Stable-Baselines3 PPO and DQN, on the same tasks and protocol.

    pip install -e '.[rl-baselines]'    # torch and stable-baselines3: gigabytes, never in CI
    python benchmarks/vs_sb3.py sb3 --seeds 5 --json vs_sb3_sb3.json
    python benchmarks/vs_sb3.py flctool --seeds 5 --json vs_sb3_flctool.json
    python benchmarks/vs_sb3.py table vs_sb3_sb3.json vs_sb3_flctool.json
    python benchmarks/vs_sb3.py sb3 --tasks mountaincar --algos dqn --only-seeds 4 \
        --max-steps 400000 --max-cpu 300 --json part.json --merge benchmarks/vs_sb3.json

``--tasks``, ``--algos`` and ``--only-seeds`` run a part; ``--merge JSON`` (or ``merge JSON
PART...`` for a part already run) adds a part's runs to a combined file such as
``benchmarks/vs_sb3.json``, with its command line, replacing any run of the same task,
method and seed. Merging computes nothing: the records are the part's, as written.

Tasks (``TASKS``): CartPole-v1, Acrobot-v1 and MountainCar-v0 (Gymnasium), flctool's
ballchase simulator and one pitch-world behaviour (face_goal), each with a threshold on the
deterministic policy's mean over 100 held-out episodes: the return for the Gymnasium tasks
(475, -100, -110), the success rate for the two robot tasks (0.95).

**Protocol, the same for every method.** A method trains, and decides for itself when to stop;
what it spends deciding is counted apart ("stop" episodes, steps and CPU). Then its
deterministic policy is confirmed on 100 fresh held-out episodes (seeds drawn as ``flctool
evaluate --seed k`` draws them, never used in training or stopping); those are not counted as
spent by the method, they are the measurement.

- SB3 (PPO, DQN): rl-baselines3-zoo's hyperparameters (``ZOO_COMMIT``; the zoo's
  ``default`` entry, i.e. SB3's defaults, for the two robot tasks it does not know), on one
  torch thread. Every ``check`` training steps (1/50 of the zoo's budget) the deterministic
  policy plays 10 validation episodes; if their mean reaches the threshold, 100 fresh
  held-out episodes decide; reached -> solved, else training goes on, until the zoo's
  budget (capped by ``--max-steps``) or ``--max-cpu`` seconds are spent. Screening and
  confirmations count as stop episodes (a confirmation that fails is spent deciding).
- flctool: the behaviour file's learner and settings, with ``stop.target`` at the threshold
  for the Gymnasium tasks (its validation episodes are its stop episodes, with its
  confirmation and the end-of-run comparison with the baselines), then ``best.yaml`` on 100
  held-out episodes: one confirmation, no second chance.

CPU seconds are ``time.process_time`` of this process around training and stopping (SB3's
exclude importing torch, 7-15 s; flctool's exclude its imports, about 0.4 s). The robot
tasks are exposed to SB3 as a ``gymnasium.Env`` over flctool's simulator, with one discrete
action per command (the commands' singletons), as Gymnasium's own tasks are discrete.
Policy size: rules for flctool, trainable parameters of the policy network for SB3.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
#: rl-baselines3-zoo commit whose hyperparams/ppo.yml and hyperparams/dqn.yml are copied
#: below (zoo version 2.9.0a2, 23 April 2026).
ZOO_COMMIT = "22e3ff2450fd92033f7f032915e1f64894a09584"
HELD_OUT = 100
SCREEN = 10
CHECKS_PER_BUDGET = 50


@dataclass(frozen=True)
class Task:
    name: str
    behaviour: str  # flctool's file in behaviours/
    gym_id: str | None  # None: flctool's own simulator
    threshold: float
    metric: str  # "return" or "success"
    flctool_target: bool  # whether flctool's run stops at stop.target = threshold


TASKS = {
    "cartpole": Task("CartPole-v1", "cartpole", "CartPole-v1", 475.0, "return", True),
    "acrobot": Task("Acrobot-v1", "acrobot", "Acrobot-v1", -100.0, "return", True),
    "mountaincar": Task("MountainCar-v0", "mountaincar", "MountainCar-v0", -110.0, "return",
                        True),
    "ballchase": Task("ballchase", "ballchase", None, 0.95, "success", False),
    "face_goal": Task("face_goal (pitch)", "face-goal", None, 0.95, "success", False),
}

# rl-baselines3-zoo at ZOO_COMMIT: hyperparams/ppo.yml and hyperparams/dqn.yml, as written
# there ("lin_x": linear schedule from x to 0; "default": the file's default entry).
ZOO: dict[str, dict[str, dict[str, Any]]] = {
    "ppo": {
        "CartPole-v1": {"n_envs": 8, "n_timesteps": 1e5, "n_steps": 32, "batch_size": 256,
                        "gae_lambda": 0.8, "gamma": 0.98, "n_epochs": 20, "ent_coef": 0.0,
                        "learning_rate": "lin_0.001", "clip_range": "lin_0.2"},
        "Acrobot-v1": {"normalize": True, "n_envs": 16, "n_timesteps": 1e6, "n_steps": 256,
                       "gae_lambda": 0.94, "gamma": 0.99, "n_epochs": 4, "ent_coef": 0.0},
        "MountainCar-v0": {"normalize": True, "n_envs": 16, "n_timesteps": 1e6, "n_steps": 16,
                           "gae_lambda": 0.98, "gamma": 0.99, "n_epochs": 4, "ent_coef": 0.0},
        "default": {"n_timesteps": 1e6},
    },
    "dqn": {
        "CartPole-v1": {"n_timesteps": 5e4, "learning_rate": 2.3e-3, "batch_size": 64,
                        "buffer_size": 100000, "learning_starts": 1000, "gamma": 0.99,
                        "target_update_interval": 10, "train_freq": 256,
                        "gradient_steps": 128, "exploration_fraction": 0.16,
                        "exploration_final_eps": 0.04, "net_arch": [256, 256]},
        "Acrobot-v1": {"n_timesteps": 1e5, "learning_rate": 6.3e-4, "batch_size": 128,
                       "buffer_size": 50000, "learning_starts": 0, "gamma": 0.99,
                       "target_update_interval": 250, "train_freq": 4, "gradient_steps": -1,
                       "exploration_fraction": 0.12, "exploration_final_eps": 0.1,
                       "net_arch": [256, 256]},
        "MountainCar-v0": {"n_timesteps": 1.2e5, "learning_rate": 4e-3, "batch_size": 128,
                           "buffer_size": 10000, "learning_starts": 1000, "gamma": 0.98,
                           "target_update_interval": 600, "train_freq": 16,
                           "gradient_steps": 8, "exploration_fraction": 0.2,
                           "exploration_final_eps": 0.07, "net_arch": [256, 256]},
        "default": {"n_timesteps": 1e6},
    },
}


def held_out_seeds(k: int) -> list[int]:
    """The k-th set of 100 held-out episode seeds (``flctool evaluate --seed k``'s)."""
    from flctool.rollout import evaluation_seeds

    return [int(s) for s in evaluation_seeds(k, HELD_OUT)]


def screen_seeds() -> list[int]:
    # Validation seeds for deciding when to stop: above every held-out and training seed.
    return [2**62 + 7919 * i for i in range(SCREEN)]


def load(task: Task) -> Any:
    from flctool import load_behaviour

    return load_behaviour(ROOT / "behaviours" / f"{task.behaviour}.yaml")


def metric(task: Task, returns: list[float], successes: list[bool]) -> float:
    return statistics.fmean(returns if task.metric == "return" else map(float, successes))


# -- the SB3 side -----------------------------------------------------------------------------


def sim_env_class() -> Any:
    """A ``gymnasium.Env`` over flctool's simulator of a behaviour, one discrete action per
    command (its singleton is the crisp output)."""
    import gymnasium as gym

    from flctool.envs import make_env

    class SimEnv(gym.Env):  # type: ignore[misc, type-arg]
        def __init__(self, behaviour: Any) -> None:
            self.sim = make_env(behaviour, 1)
            ranges = np.array([v.range for v in behaviour.inputs.values()], dtype=np.float32)
            self.observation_space = gym.spaces.Box(ranges[:, 0], ranges[:, 1],
                                                    dtype=np.float32)
            self.commands = list(behaviour.output.commands.values())
            self.action_space = gym.spaces.Discrete(len(self.commands))
            self.success = False

        def reset(self, *, seed: int | None = None, options: Any = None) -> Any:
            super().reset(seed=seed)
            episode = seed if seed is not None else int(self.np_random.integers(2**32, 2**62))
            self.success = False
            return self.sim.reset_one(episode).astype(np.float32), {}

        def step(self, action: Any) -> Any:
            obs, reward, terminated, truncated = self.sim.step_one(self.commands[int(action)])
            if terminated or truncated:
                self.success = bool(self.sim.success()[0])
            return obs.astype(np.float32), reward, terminated, truncated, {
                "is_success": self.success}

    return SimEnv


def make_gym(task: Task) -> Any:
    import gymnasium as gym

    if task.gym_id is not None:
        return gym.make(task.gym_id)
    return sim_env_class()(load(task))


def schedule(value: Any) -> Any:
    if isinstance(value, str) and value.startswith("lin_"):
        start = float(value[4:])
        return lambda progress: progress * start
    return value


def sb3_play(task: Task, model: Any, normalizer: Any, seeds: list[int]) -> dict[str, Any]:
    """The deterministic policy on one episode per seed, stepped together (batched predict)."""
    envs = [make_gym(task) for _ in seeds]
    obs = np.stack([env.reset(seed=s)[0] for env, s in zip(envs, seeds, strict=True)])
    returns = [0.0] * len(seeds)
    steps = 0
    successes = [False] * len(seeds)
    running = list(range(len(seeds)))
    while running:
        batch = obs[running]
        if normalizer is not None:
            batch = normalizer.normalize_obs(batch)
        actions, _ = model.predict(batch, deterministic=True)
        still = []
        for index, action in zip(running, actions, strict=True):
            o, r, terminated, truncated, info = envs[index].step(action)
            obs[index] = o
            returns[index] += float(r)
            steps += 1
            if terminated or truncated:
                successes[index] = bool(info.get("is_success", False))
            else:
                still.append(index)
        running = still
    for env in envs:
        env.close()
    return {"returns": returns, "successes": successes, "steps": steps,
            "value": metric(task, returns, successes)}


def sb3_run(task: Task, algo: str, seed: int, max_steps: int, max_cpu: float) -> dict[str, Any]:
    import torch
    from stable_baselines3 import DQN, PPO
    from stable_baselines3.common.callbacks import BaseCallback
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.vec_env import VecNormalize

    from flctool.rollout import TRAIN_SEED_LOW

    torch.set_num_threads(1)
    table = ZOO[algo]
    entry = "default"
    if task.gym_id in table:
        entry = task.gym_id  # type: ignore[assignment]
    params = dict(table[entry])
    budget = int(min(params.pop("n_timesteps"), max_steps))
    n_envs = int(params.pop("n_envs", 1))
    normalize = bool(params.pop("normalize", False))
    net_arch = params.pop("net_arch", None)
    params = {k: schedule(v) for k, v in params.items()}
    if net_arch is not None:
        params["policy_kwargs"] = {"net_arch": net_arch}
    started = time.process_time()
    venv = make_vec_env(lambda: make_gym(task), n_envs=n_envs,
                        seed=TRAIN_SEED_LOW + 1000 * seed)
    if normalize:  # the zoo's normalize: true is VecNormalize with its defaults
        venv = VecNormalize(venv)
    cls = PPO if algo == "ppo" else DQN
    model = cls("MlpPolicy", venv, seed=seed, verbose=0, device="cpu", **params)
    check = max(1, budget // CHECKS_PER_BUDGET)
    record: dict[str, Any] = {"task": task.name, "method": f"SB3 {algo.upper()}", "seed": seed,
                              "zoo_entry": entry, "budget_steps": budget, "solved": False,
                              "stop_episodes": 0, "stop_steps": 0, "stop_cpu": 0.0,
                              "confirmations": 0, "train_episodes": 0}
    screening = screen_seeds()

    class Stopper(BaseCallback):  # type: ignore[misc]
        next_check = check

        def _on_step(self) -> bool:
            dones = self.locals.get("dones")
            if dones is not None:
                record["train_episodes"] += int(np.sum(dones))
            if time.process_time() - started - record["stop_cpu"] > max_cpu:
                record["stopped_by"] = "max_cpu"
                return False
            if self.num_timesteps < self.next_check:
                return True
            self.next_check += check
            begun = time.process_time()
            normalizer = venv if normalize else None
            try:
                screen = sb3_play(task, self.model, normalizer, screening)
                record["stop_episodes"] += SCREEN
                record["stop_steps"] += screen["steps"]
                if screen["value"] < task.threshold:
                    return True
                confirm = sb3_play(task, self.model, normalizer,
                                   held_out_seeds(record["confirmations"]))
                record["confirmations"] += 1
                record["held_out"] = confirm["value"]
                if confirm["value"] >= task.threshold:
                    record["solved"] = True
                    return False
                record["stop_episodes"] += HELD_OUT  # a failed confirmation was spent deciding
                record["stop_steps"] += confirm["steps"]
                return True
            finally:
                record["stop_cpu"] += time.process_time() - begun

    model.learn(total_timesteps=budget, callback=Stopper())
    record["train_steps"] = int(model.num_timesteps)
    if not record["solved"]:
        begun = time.process_time()
        final = sb3_play(task, model, venv if normalize else None,
                         held_out_seeds(record["confirmations"]))
        record["held_out"] = final["value"]
        record["final_cpu"] = time.process_time() - begun
        record.setdefault("stopped_by", "budget")
    record["cpu"] = time.process_time() - started - record.get("final_cpu", 0.0)
    record["train_cpu"] = record["cpu"] - record["stop_cpu"]
    record["policy_size"] = sum(p.numel() for p in model.policy.parameters())
    record["policy_unit"] = "parameters"
    venv.close()
    return record


# -- the flctool side -------------------------------------------------------------------------


def flctool_run(task: Task, seed: int) -> dict[str, Any]:
    from common import train_and_evaluate

    from flctool.runs import resolve_behaviour

    overrides: dict[str, Any] = {"seed": seed}
    if task.flctool_target:
        overrides["stop.target"] = task.threshold
    behaviour = resolve_behaviour(load(task), overrides)
    with tempfile.TemporaryDirectory() as tmp:
        trained = train_and_evaluate(behaviour, Path(tmp) / "run", HELD_OUT,
                                     seeds=held_out_seeds(0))
    summary, result = trained.summary, trained.result
    value = (float(result.mean_return.value) if task.metric == "return"
             else float(result.success_rate.value))
    usage = trained.usage
    return {"task": task.name, "method": f"flctool {behaviour.learning.learner}",
            "seed": seed, "solved": value >= task.threshold, "held_out": value,
            "train_steps": usage.training_steps, "train_episodes": usage.training_episodes,
            # spent deciding when to stop and what it learned: validation, confirmation and
            # the end-of-run comparison with the baselines (every episode the run used)
            "stop_steps": (usage.selection_steps + usage.confirmation_steps
                           + usage.baseline_steps),
            "stop_episodes": (usage.selection_episodes + usage.confirmation_episodes
                              + usage.baseline_episodes),
            "baseline_steps": usage.baseline_steps,
            "baseline_episodes": usage.baseline_episodes,
            "cpu": trained.train_cpu_seconds, "stopped_by": (summary.selection or {}).get(
                "stop_reason") or "generations",
            "policy_size": math.prod(len(v.sets) for v in behaviour.inputs.values()),
            "policy_unit": "rules"}


# -- the table --------------------------------------------------------------------------------


def table(records: list[dict[str, Any]]) -> str:
    lines = ["| task (threshold) | method | solved | train steps | train episodes | "
             "stop steps | stop episodes | CPU s | held-out score | policy size |",
             "| --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
    groups: dict[tuple[str, str], list[dict[str, Any]]] = {}
    for record in records:
        groups.setdefault((record["task"], record["method"]), []).append(record)
    thresholds = {t.name: t.threshold for t in TASKS.values()}
    order = [t.name for t in TASKS.values()]
    for (task, method), runs in sorted(groups.items(),
                                       key=lambda kv: (order.index(kv[0][0]), kv[0][1])):
        solved = [r for r in runs if r["solved"]]
        shown = solved or runs  # medians over the solving seeds, else over all

        def median(key: str, rows: list[dict[str, Any]] = shown) -> float:
            return statistics.median(float(r[key]) for r in rows)
        unit = runs[0]["policy_unit"]
        lines.append(
            f"| {task} ({thresholds[task]:g}) | {method} | {len(solved)}/{len(runs)} | "
            f"{median('train_steps'):,.0f} | {median('train_episodes'):,.0f} | "
            f"{median('stop_steps'):,.0f} | {median('stop_episodes'):,.0f} | "
            f"{median('cpu'):.1f} | "
            f"{median('held_out', runs):.3g} | {median('policy_size'):,.0f} {unit} |")
    return "\n".join(lines)


def write_results(args: argparse.Namespace, records: list[dict[str, Any]],
                  skipped: list[str]) -> None:
    args.json.write_text(json.dumps({
        "benchmark": "vs_sb3", "side": args.side, "zoo_commit": ZOO_COMMIT,
        "started": args.started, "when": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        "load_average": [round(x, 2) for x in os.getloadavg()], "argv": sys.argv[1:],
        "runs": records, "not_started": skipped}, indent=1) + "\n")


def merge(combined: Path, parts: list[Path], note: str | None = None) -> None:
    """Add each part file's runs to ``combined`` (``benchmarks/vs_sb3.json``'s layout: its
    ``parts`` list each process's command line, and its ``runs`` are the table's), replacing
    a run of the same task, method and seed and the entry of a part of the same file name."""
    data = json.loads(combined.read_text())
    for path in parts:
        part = json.loads(path.read_text())
        keys = {(r["task"], r["method"], r["seed"]) for r in part["runs"]}
        data["runs"] = [r for r in data["runs"]
                        if (r["task"], r["method"], r["seed"]) not in keys] + part["runs"]
        entry = {"file": path.name, "side": part["side"], "argv": part["argv"],
                 "when": part["when"], "runs": len(part["runs"]),
                 "not_started": part["not_started"], "in_the_table": True}
        for key in ("started", "load_average"):
            if key in part:
                entry[key] = part[key]
        if note:
            entry["note"] = note
        data["parts"] = [p for p in data["parts"] if p["file"] != path.name] + [entry]
    combined.write_text(json.dumps(data, indent=1) + "\n")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("side", choices=("sb3", "flctool", "table", "merge"))
    parser.add_argument("files", nargs="*", type=Path,
                        help="table: the JSON files to show; merge: the combined file, then "
                             "the part files to add to it")
    parser.add_argument("--tasks", default=",".join(TASKS))
    parser.add_argument("--algos", default="ppo,dqn")
    parser.add_argument("--seeds", type=int, default=5, help="seeds 0 to SEEDS - 1")
    parser.add_argument("--only-seeds", metavar="K,...",
                        help="these seeds instead of --seeds' (e.g. 4)")
    parser.add_argument("--max-steps", type=int, default=1_000_000,
                        help="SB3: at most this many training steps (the zoo's budget "
                             "otherwise)")
    parser.add_argument("--max-cpu", type=float, default=math.inf,
                        help="SB3: stop training after this many CPU seconds")
    parser.add_argument("--json", type=Path, default=Path("vs_sb3.json"))
    parser.add_argument("--until", metavar="HH:MM",
                        help="start no new run after this UTC time today (runs not started "
                             "are listed as skipped)")
    parser.add_argument("--merge", type=Path, metavar="JSON",
                        help="after each run, add this process's runs to this combined file")
    parser.add_argument("--note", help="merge: a note kept with the parts' entries")
    args = parser.parse_args()
    args.started = time.strftime("%Y-%m-%dT%H:%M:%S%z")
    if args.side == "table":
        records = [r for f in args.files for r in json.loads(f.read_text())["runs"]]
        print(table(records))
        return
    if args.side == "merge":
        if len(args.files) < 2:
            parser.error("merge: the combined file, then at least one part file")
        merge(args.files[0], args.files[1:], args.note)
        print(table(json.loads(args.files[0].read_text())["runs"]))
        return
    seeds = (range(args.seeds) if args.only_seeds is None
             else [int(k) for k in args.only_seeds.split(",")])
    deadline = math.inf
    if args.until:
        hours, minutes = (int(part) for part in args.until.split(":"))
        deadline = time.time() - time.time() % 86400 + 3600 * hours + 60 * minutes
    records: list[dict[str, Any]] = []
    skipped: list[str] = []
    for name in args.tasks.split(","):
        task = TASKS[name]
        for algo in args.algos.split(",") if args.side == "sb3" else ["file's learner"]:
            for seed in seeds:
                if time.time() > deadline:
                    skipped.append(f"{name} {algo} seed {seed}")
                    continue
                record = (sb3_run(task, algo, seed, args.max_steps, args.max_cpu)
                          if args.side == "sb3" else flctool_run(task, seed))
                records.append(record)
                print(json.dumps(record), flush=True)
                write_results(args, records, skipped)
                if args.merge:
                    merge(args.merge, [args.json], args.note)
    write_results(args, records, skipped)
    if args.merge:
        merge(args.merge, [args.json], args.note)
    if skipped:
        print(f"not started (past --until {args.until}): {', '.join(skipped)}")
    print(table(records))


if __name__ == "__main__":
    main()
