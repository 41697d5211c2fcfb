"""Pitt vs fuzzy_q vs the paper's hybrid on ballchase: held-out success and learning speed.

For each learner and each of ``--seeds`` training seeds, ``flctool learn`` is run (through
the library, into a temporary run directory) with the behaviour's protocol -- by default the
paper's: population 10, pc 0.2, pm 0.1, 30 generations, one trial per individual. Its
``best.yaml`` is then evaluated on ``--episodes`` held-out episodes (seeds 0..E-1; training
episodes use seeds >= 2^32, so none is shared). Prints, per learner, the median, mean and
worst held-out success over the seeds, and the area under the mean-fitness curve (sum over
generations of the generation's mean fitness), and writes everything as JSON.

    python benchmarks/compare_learners.py                     # 20 seeds, 1,000 episodes
    python benchmarks/compare_learners.py --set trials=2 --set common_starts=true
"""

from __future__ import annotations

import argparse
import json
import statistics
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from flctool import compile_behaviour, load_behaviour
from flctool.envs import make_env
from flctool.learners import TRAIN_SEED_LOW
from flctool.rollout import evaluate
from flctool.runs import BEST_FILE, create_run, resolve_behaviour

ROOT = Path(__file__).resolve().parents[1]


def run_one(behaviour_path: Path, learner: str, seed: int, overrides: dict[str, Any],
            episodes: int, workdir: Path) -> dict[str, Any]:
    behaviour = resolve_behaviour(load_behaviour(behaviour_path),
                                  {**overrides, "learner": learner, "seed": seed})
    run = create_run(behaviour, workdir / f"{learner}-{seed}")
    started = time.perf_counter()
    summary = run.train()
    train_seconds = time.perf_counter() - started
    metrics = run.metrics()
    best = load_behaviour(run.path / BEST_FILE)
    seeds = np.arange(episodes, dtype=np.int64)
    assert seeds.max() < TRAIN_SEED_LOW  # held out: training never uses these
    result = evaluate(compile_behaviour(best), make_env(best, episodes), seeds)
    return {"learner": learner, "seed": seed,
            "success": float(result.success_rate.value),
            "auc": float(sum(m.mean for m in metrics)),
            "final_mean": metrics[-1].mean, "best_fitness": summary.best["fitness"],
            "train_seconds": train_seconds,
            "episodes": int(sum(m.episodes for m in metrics)),
            "steps": int(sum(m.steps for m in metrics))}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--behaviour", type=Path, default=ROOT / "behaviours/ballchase.yaml")
    parser.add_argument("--learners", default="pitt,hybrid,fuzzy_q")
    parser.add_argument("--seeds", type=int, default=20)
    parser.add_argument("--episodes", type=int, default=1000)
    parser.add_argument("--set", dest="assignments", action="append", default=[],
                        help="override a learning hyperparameter, e.g. trials=2")
    parser.add_argument("--json", type=Path, default=Path("compare_learners.json"))
    args = parser.parse_args()
    overrides = {k: yaml.safe_load(v) for k, _, v in (a.partition("=") for a in
                                                       args.assignments)}
    learners = args.learners.split(",")
    results: list[dict[str, Any]] = []
    with tempfile.TemporaryDirectory() as tmp:
        for learner in learners:
            for seed in range(args.seeds):
                results.append(run_one(args.behaviour, learner, seed, overrides,
                                       args.episodes, Path(tmp)))
    summary: dict[str, dict[str, Any]] = {}
    print(f"{args.behaviour.name}: {args.seeds} training seeds, best.yaml on {args.episodes} "
          f"held-out episodes; overrides {overrides or 'none'}")
    print(f"{'learner':8} {'median':>7} {'mean':>7} {'worst':>7} {'(seed)':>6} {'AUC':>7} "
          f"{'train s':>8} {'episodes':>8}")
    for learner in learners:
        rows = [r for r in results if r["learner"] == learner]
        success = [r["success"] for r in rows]
        worst = min(rows, key=lambda r: r["success"])
        summary[learner] = {
            "median_success": statistics.median(success), "mean_success": statistics.mean(success),
            "worst_success": worst["success"], "worst_seed": worst["seed"],
            "mean_auc": statistics.mean(r["auc"] for r in rows),
            "mean_train_seconds": statistics.mean(r["train_seconds"] for r in rows),
            "mean_episodes": statistics.mean(r["episodes"] for r in rows)}
        s = summary[learner]
        print(f"{learner:8} {s['median_success']:7.3f} {s['mean_success']:7.3f} "
              f"{s['worst_success']:7.3f} {s['worst_seed']:6d} {s['mean_auc']:7.2f} "
              f"{s['mean_train_seconds']:8.3f} {s['mean_episodes']:8.0f}")
    if "pitt" in summary and "hybrid" in summary:
        ratio = summary["hybrid"]["mean_auc"] / summary["pitt"]["mean_auc"]
        print(f"hybrid AUC / pitt AUC = {ratio:.3f}")
    args.json.write_text(json.dumps({"behaviour": str(args.behaviour.name),
                                     "seeds": args.seeds, "episodes": args.episodes,
                                     "overrides": overrides, "summary": summary,
                                     "runs": results}, indent=2) + "\n")
    print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
