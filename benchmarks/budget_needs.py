"""How many training episodes does a pitch task need, and does it grow with its rules?

For each pitch task of the task suite (its file's settings but the number of generations)
and each of ``--generations``, the file's learner runs on ``--seeds`` training seeds; each
run's ``best.yaml`` is evaluated on ``--episodes`` held-out episodes (drawn as ``flctool
evaluate --seed 0`` draws them) beside the task's hand-made controller. Printed per task:
its rules to learn M and commands K, the median held-out success at each budget (training
episodes = generations x population x trials), and the fewest training episodes whose
median reaches 95 % of the hand-made success ("need"). A budget rule sized from the problem
(say, growing with M log K) would show as a "need" that grows with M.

    nice -n 10 python benchmarks/budget_needs.py                  # every pitch task
    python benchmarks/budget_needs.py --tasks ballchase,dribble --generations 10,30 --seeds 2
"""

from __future__ import annotations

import argparse
import json
import statistics
import tempfile
import time
from pathlib import Path
from typing import Any

from task_suite import ROOT, TASKS, held_out

from flctool import load_behaviour

PITCH = [t for t in TASKS if not t.gym and t.handmade is not None
         and t.name not in ("defend", "shoot", "striker")]  # a goal to reach, one behaviour


def run_one(file: Path, seed: int, generations: int, episodes: int) -> dict[str, Any]:
    from flctool.runs import BEST_FILE
    from flctool.training import start_run

    with tempfile.TemporaryDirectory() as tmp:
        started = time.process_time()
        training = start_run(file, {"seed": seed, "generations": generations},
                             Path(tmp) / "run")
        summary = training.train()
        cpu = time.process_time() - started
        figures = held_out(summary.path / BEST_FILE, episodes)
    usage = summary.to_dict()["usage"]
    return {"seed": seed, "generations": generations, "success": figures["success"],
            "training_episodes": usage["training_episodes"], "episodes": usage["episodes"],
            "cpu_seconds": cpu, "status": summary.status}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--tasks", default=",".join(t.name for t in PITCH))
    parser.add_argument("--generations", default="10,20,30,60,120")
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--first-seed", type=int, default=600)
    parser.add_argument("--episodes", type=int, default=500)
    parser.add_argument("--json", type=Path, default=Path("budget_needs.json"))
    args = parser.parse_args()
    wanted = args.tasks.split(",")
    budgets = [int(g) for g in args.generations.split(",")]
    seeds = range(args.first_seed, args.first_seed + args.seeds)
    print(f"seeds {seeds.start}-{seeds.stop - 1}, best.yaml on {args.episodes} held-out "
          f"episodes; median success at each budget of training episodes")
    results: list[dict[str, Any]] = []
    for task in [t for t in PITCH if t.name in wanted]:
        behaviour = load_behaviour(ROOT / task.file)
        learning = behaviour.learning
        per_generation = learning.population * learning.trials
        reference = held_out(ROOT / str(task.handmade), args.episodes)["success"]
        rows = [run_one(ROOT / task.file, seed, g, args.episodes)
                for g in budgets for seed in seeds]
        medians = {g * per_generation: statistics.median(r["success"] for r in rows
                                                         if r["generations"] == g)
                   for g in budgets}
        need = next((e for e, m in sorted(medians.items()) if m >= 0.95 * reference), None)
        entry = {"task": task.name, "rules": len(behaviour.missing_rules()),
                 "commands": len(behaviour.output.commands), "reference": reference,
                 "medians": medians, "need": need, "runs": rows,
                 "cpu_seconds": sum(r["cpu_seconds"] for r in rows)}
        results.append(entry)
        cells = "  ".join(f"{e}: {m:.3f}" for e, m in medians.items())
        print(f"{task.name:17} M={entry['rules']:3d} K={entry['commands']}  hand-made "
              f"{reference:.3f}  {cells}  need {need if need is not None else '> most'}",
              flush=True)
    args.json.write_text(json.dumps({"seeds": list(seeds), "episodes": args.episodes,
                                     "tasks": results}, indent=2) + "\n")
    print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
