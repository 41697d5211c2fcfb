"""Do the shipped Gymnasium behaviours solve their tasks with their own settings?

For each behaviour file and each of ``--seeds`` training seeds, ``flctool learn`` runs with the
file's settings (through the library, into a temporary run directory); its ``best.yaml`` is
then evaluated on ``--episodes`` held-out episodes, drawn as ``flctool evaluate --seed 0``
draws them (seeds below 2^31; training uses [2^32, 2^62), model selection [2^62, 2^63)).
Every episode a run used is counted: training and selection (validation) episodes alike.

Prints per seed the held-out mean return and the episodes used, and per file how many seeds
reach the task's threshold (CartPole-v1: 475, MountainCar-v0: -110).

    python benchmarks/gym_thresholds.py                       # both files, 10 seeds
    python benchmarks/gym_thresholds.py --files mountaincar --set learner=hybrid
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
THRESHOLDS = {"cartpole": 475.0, "mountaincar": -110.0, "pendulum": -200.0}


def run_one(name: str, seed: int, overrides: dict[str, Any], episodes: int,
            workdir: Path) -> dict[str, Any]:
    behaviour = resolve_behaviour(load_behaviour(ROOT / "behaviours" / f"{name}.yaml"),
                                  {**overrides, "seed": seed})
    trained = train_and_evaluate(behaviour, workdir / f"{name}-{seed}", episodes)
    summary = trained.summary
    return {"file": name, "seed": seed, "mean_return": float(trained.result.mean_return.value),
            "validated": (summary.to_dict()["best"].get("validation") or {}).get("value"),
            "generations": summary.generations, **trained.counts(),
            "stop_reason": (summary.selection or {}).get("stop_reason"),
            "train_cpu_seconds": trained.train_cpu_seconds}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--files", default="cartpole,mountaincar")
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--episodes", type=int, default=100)
    parser.add_argument("--set", dest="assignments", action="append", default=[],
                        help="override a learning hyperparameter, e.g. generations=80")
    parser.add_argument("--json", type=Path, default=Path("gym_thresholds.json"))
    args = parser.parse_args()
    overrides = {k: yaml.safe_load(v) for k, _, v in (a.partition("=") for a in
                                                       args.assignments)}
    results: list[dict[str, Any]] = []
    summary: dict[str, Any] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for name in args.files.split(","):
            threshold = THRESHOLDS[name]
            print(f"{name}.yaml: {args.seeds} seeds, best.yaml on {args.episodes} held-out "
                  f"episodes, threshold {threshold:g}; overrides {overrides or 'none'}")
            print(f"{'seed':>4} {'return':>8} {'validated':>9} {'gens':>5} {'training':>8} "
                  f"{'selection':>9} {'episodes':>8} {'cpu s':>6}  stop")
            rows = []
            for seed in range(args.seeds):
                r = run_one(name, seed, overrides, args.episodes, Path(tmp))
                rows.append(r)
                validated = "-" if r["validated"] is None else f"{r['validated']:.1f}"
                print(f"{seed:4d} {r['mean_return']:8.2f} {validated:>9} {r['generations']:5d} "
                      f"{r['training_episodes']:8d} {r['selection_episodes']:9d} "
                      f"{r['episodes']:8d} {r['train_cpu_seconds']:6.1f}  "
                      f"{r['stop_reason'] or 'generations'}", flush=True)
            solved = [r for r in rows if r["mean_return"] >= threshold]
            episodes = [r["episodes"] for r in rows]
            summary[name] = {"threshold": threshold, "solved": len(solved),
                             "seeds": len(rows),
                             "median_return": statistics.median(r["mean_return"] for r in rows),
                             "median_episodes": statistics.median(episodes),
                             "max_episodes": max(episodes)}
            s = summary[name]
            print(f"{name}: {s['solved']} of {s['seeds']} seeds reach {threshold:g}; median "
                  f"return {s['median_return']:.2f}; episodes used (all counted): median "
                  f"{s['median_episodes']:.0f}, max {s['max_episodes']}")
            results += rows
    args.json.write_text(json.dumps({"episodes": args.episodes, "overrides": overrides,
                                     "summary": summary, "runs": results}, indent=2) + "\n")
    print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
