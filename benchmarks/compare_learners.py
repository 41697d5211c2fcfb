"""Pitt vs fuzzy_q vs the paper's hybrid on ballchase: held-out success and learning speed.

For each learner and each of ``--seeds`` training seeds, ``flctool learn`` is run (through
the library, into a temporary run directory) with the behaviour's protocol -- by default the
paper's: population 10, pc 0.2, pm 0.1, 30 generations, one trial per individual -- and the
behaviour's model selection (``learning.selection``). Its ``best.yaml`` is then evaluated on
``--episodes`` held-out episodes drawn as ``flctool evaluate --seed 0`` draws them (seeds
below 2^31; training uses seeds in [2^32, 2^62), selection in [2^62, 2^63), so none is
shared). Prints, per learner, the median, mean and worst held-out success over the seeds,
the area under the mean-fitness curve (sum over generations of the generation's mean
fitness), the episodes every run used -- training, selection, confirmation and baselines,
all counted -- the calibration (in how many runs the confirmation's interval contains the
held-out mean fitness) and the runs that ended ``not_learned``, and writes everything as
JSON.

    python benchmarks/compare_learners.py                     # 30 seeds, 1,000 episodes
    python benchmarks/compare_learners.py --set selection.candidates=0   # no selection
    python benchmarks/compare_learners.py --set trials=2 --set common_starts=true
"""

from __future__ import annotations

import argparse
import json
import statistics
import tempfile
from pathlib import Path
from typing import Any

import yaml
from common import train_and_evaluate

from flctool import load_behaviour
from flctool.runs import resolve_behaviour

ROOT = Path(__file__).resolve().parents[1]


def run_one(behaviour_path: Path, learner: str, seed: int, overrides: dict[str, Any],
            episodes: int, workdir: Path) -> dict[str, Any]:
    behaviour = resolve_behaviour(load_behaviour(behaviour_path),
                                  {**overrides, "learner": learner, "seed": seed})
    trained = train_and_evaluate(behaviour, workdir / f"{learner}-{seed}", episodes)
    summary, result = trained.summary, trained.result
    metrics = trained.run.metrics()
    return {"learner": learner, "seed": seed,
            "success": float(result.success_rate.value),
            "mean_return": float(result.mean_return.value),
            "auc": float(sum(m.mean for m in metrics)),
            "final_mean": metrics[-1].mean, "best_fitness": summary.to_dict()["best"]["fitness"],
            "validated": (summary.to_dict()["best"].get("validation") or {}).get("value"),
            "train_cpu_seconds": trained.train_cpu_seconds,
            # every episode the run used: training, selection, confirmation, baselines
            **trained.counts(),
            "status": summary.status,
            "confirmed_fitness": ((summary.to_dict()["best"].get("confirmation") or {})
                                  .get("mean_fitness") or {}),
            "heldout_fitness": float(result.mean_fitness.value)}


def calibrated(row: dict[str, Any]) -> bool:
    """Whether the run's confirmation interval contains its held-out mean fitness."""
    interval = row["confirmed_fitness"]
    return bool(interval) and interval["low"] <= row["heldout_fitness"] <= interval["high"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--behaviour", type=Path, default=ROOT / "behaviours/ballchase.yaml")
    parser.add_argument("--learners", default="pitt,hybrid,fuzzy_q")
    parser.add_argument("--seeds", type=int, default=30)
    parser.add_argument("--first-seed", type=int, default=0,
                        help="training seeds are first-seed .. first-seed + seeds - 1")
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
            for seed in range(args.first_seed, args.first_seed + args.seeds):
                results.append(run_one(args.behaviour, learner, seed, overrides,
                                       args.episodes, Path(tmp)))
    summary: dict[str, dict[str, Any]] = {}
    print(f"{args.behaviour.name}: {args.seeds} training seeds from {args.first_seed}, "
          f"best.yaml on {args.episodes} held-out episodes; overrides {overrides or 'none'}")
    print(f"{'learner':8} {'median':>7} {'mean':>7} {'worst':>7} {'(seed)':>6} {'AUC':>7} "
          f"{'cpu s':>6} {'training':>8} {'selection':>9} {'episodes':>8} {'calibrated':>9} "
          f"{'not_learned':>11}")
    for learner in learners:
        rows = [r for r in results if r["learner"] == learner]
        success = [r["success"] for r in rows]
        worst = min(rows, key=lambda r: r["success"])
        summary[learner] = {
            "median_success": statistics.median(success), "mean_success": statistics.mean(success),
            "worst_success": worst["success"], "worst_seed": worst["seed"],
            "mean_auc": statistics.mean(r["auc"] for r in rows),
            "mean_train_cpu_seconds": statistics.mean(r["train_cpu_seconds"] for r in rows),
            "mean_training_episodes": statistics.mean(r["training_episodes"] for r in rows),
            "mean_selection_episodes": statistics.mean(r["selection_episodes"] for r in rows),
            "mean_episodes": statistics.mean(r["episodes"] for r in rows),
            "calibrated": sum(calibrated(r) for r in rows),
            "not_learned": sum(r["status"] == "not_learned" for r in rows)}
        s = summary[learner]
        print(f"{learner:8} {s['median_success']:7.3f} {s['mean_success']:7.3f} "
              f"{s['worst_success']:7.3f} {s['worst_seed']:6d} {s['mean_auc']:7.2f} "
              f"{s['mean_train_cpu_seconds']:6.2f} {s['mean_training_episodes']:8.0f} "
              f"{s['mean_selection_episodes']:9.0f} {s['mean_episodes']:8.0f} "
              f"{s['calibrated']:4d}/{len(rows):<4d} {s['not_learned']:11d}")
    if "pitt" in summary and "hybrid" in summary:
        ratio = summary["hybrid"]["mean_auc"] / summary["pitt"]["mean_auc"]
        print(f"hybrid AUC / pitt AUC = {ratio:.3f}")
    args.json.write_text(json.dumps({"behaviour": str(args.behaviour.name),
                                     "seeds": args.seeds, "first_seed": args.first_seed,
                                     "episodes": args.episodes,
                                     "overrides": overrides, "summary": summary,
                                     "runs": results}, indent=2) + "\n")
    print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
