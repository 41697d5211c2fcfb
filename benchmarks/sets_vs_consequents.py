"""Learning the consequents only, or the consequents and the fuzzy sets, at equal budgets.

For each task (a shipped behaviour file) and each training seed, ``flctool learn`` runs twice
with the file's own settings: as the file is (consequents only), and with ``learning.sets``
added (mode ``partition`` for inputs whose sets are a strong partition, ``lateral`` for the
others, every other setting of the section at its default). Both runs have the same
population, generations and trials, so the same training episodes; validation episodes are
counted too (every episode a run used is in its usage). Each run's ``best.yaml`` is then
evaluated on ``--episodes`` held-out episodes (seeds below 2^31, as ``flctool evaluate --seed
0`` draws them; training and selection never use them).

Reported per task and variant: the median and the worst seed of the held-out score (mean
return for Gymnasium tasks, success rate for the pitch and ballchase tasks), the episodes
used, CPU seconds, and the two-sided Mann-Whitney U p-value of sets against consequents only.
The JSON file is rewritten after every run (with the machine and the start time), so a long
benchmark that is stopped keeps every run it finished.

    nice -n 10 python benchmarks/sets_vs_consequents.py --seeds 10 --json sets_vs_consequents.json
    python benchmarks/sets_vs_consequents.py --tasks ballchase,pendulum --seeds 3
    python benchmarks/sets_vs_consequents.py --tasks ballchase-misscaled --seeds 10 --bound 2
    python benchmarks/sets_vs_consequents.py --tasks mountaincar-misscaled --seeds 10 --bound 2 \
        --variants sets --json misscaled-bound2.json
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path
from typing import Any

from common import machine, train_and_evaluate, write_json
from scipy.stats import mannwhitneyu

from flctool import load_behaviour
from flctool.behaviour.models import Behaviour
from flctool.behaviour.overrides import resolve_behaviour
from flctool.behaviour.set_learning import strong_partition_problems

ROOT = Path(__file__).resolve().parents[1]
#: task -> (behaviour file under the repository, score: "return" (mean return) or "success"
#: (success rate)). The shipped files first; then files written for this benchmark whose hand
#: partitions are badly scaled (benchmarks/tasks/), where learning the sets has work to do.
TASKS = {"ballchase": ("behaviours/ballchase.yaml", "success"),
         "avoid-obstacle": ("behaviours/avoid-obstacle.yaml", "success"),
         "cartpole": ("behaviours/cartpole.yaml", "return"),
         "mountaincar": ("behaviours/mountaincar.yaml", "return"),
         "acrobot": ("behaviours/acrobot.yaml", "return"),
         "pendulum": ("behaviours/pendulum.yaml", "return"),
         "ballchase-misscaled": ("benchmarks/tasks/ballchase-misscaled.yaml", "success"),
         "mountaincar-misscaled": ("benchmarks/tasks/mountaincar-misscaled.yaml", "return")}
#: the tasks run when --tasks is not given
DEFAULT_TASKS = "ballchase,avoid-obstacle,cartpole,mountaincar,acrobot,pendulum"


def sets_section(behaviour: Behaviour, bound: float | None = None) -> dict[str, Any]:
    """``learning.sets`` for every input: partition where the file's sets are a strong
    partition, lateral elsewhere (a rule that needs no tuning per file); ``bound`` if given,
    else the section's default."""
    inputs = {name: {"mode": "partition" if not strong_partition_problems(name, variable)
                     else "lateral"} for name, variable in behaviour.inputs.items()}
    return {"inputs": inputs, **({} if bound is None else {"bound": bound})}


def run_one(task: str, seed: int, with_sets: bool, episodes: int, workdir: Path,
            bound: float | None = None) -> dict[str, Any]:
    file, score = TASKS[task]
    behaviour = load_behaviour(ROOT / file)
    overrides: dict[str, Any] = {"seed": seed}
    if with_sets:
        overrides["sets"] = sets_section(behaviour, bound)
    behaviour = resolve_behaviour(behaviour, overrides)
    trained = train_and_evaluate(
        behaviour, workdir / f"{task}-{seed}-{'sets' if with_sets else 'cons'}", episodes)
    result = trained.result
    value = (float(result.mean_return.value) if score == "return"
             else float(result.success_rate.value))
    return {"task": task, "seed": seed, "sets": with_sets, "score": value,
            "mean_return": float(result.mean_return.value),
            "success_rate": float(result.success_rate.value), **trained.counts(),
            "train_cpu_seconds": trained.train_cpu_seconds}


def summarise(rows: list[dict[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for variant, flag in (("consequents", False), ("sets", True)):
        scores = [r["score"] for r in rows if r["sets"] is flag]
        if not scores:
            continue
        used = [r["episodes"] for r in rows if r["sets"] is flag]
        cpu = [r["train_cpu_seconds"] for r in rows if r["sets"] is flag]
        out[variant] = {"median": statistics.median(scores), "worst": min(scores),
                        "seeds": len(scores), "median_episodes": statistics.median(used),
                        "median_cpu_seconds": statistics.median(cpu)}
    a = [r["score"] for r in rows if r["sets"]]
    b = [r["score"] for r in rows if not r["sets"]]
    out["mann_whitney_p"] = (float(mannwhitneyu(a, b, alternative="two-sided").pvalue)
                             if a and b and len(set(a + b)) > 1 else 1.0)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--tasks", default=DEFAULT_TASKS, help=(
        f"comma-separated, of {', '.join(TASKS)}"))
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--episodes", type=int, default=100)
    parser.add_argument("--variants", default="consequents,sets", help=(
        "which runs to make: consequents (the file as it is), sets (with learning.sets)"))
    parser.add_argument("--first-seed", type=int, default=0)
    parser.add_argument("--bound", type=float, default=None, help=(
        "learning.sets.bound of the sets arm (default: the section's)"))
    parser.add_argument("--json", type=Path, default=Path("sets_vs_consequents.json"))
    args = parser.parse_args()
    results: list[dict[str, Any]] = []
    summary: dict[str, Any] = {}
    record = {"started": time.strftime("%Y-%m-%dT%H:%M:%S%z"), "machine": machine(),
              "episodes": args.episodes, "seeds": args.seeds, "first_seed": args.first_seed,
              "bound": args.bound, "summary": summary, "runs": results}
    with tempfile.TemporaryDirectory() as tmp:
        for task in args.tasks.split(","):
            rows: list[dict[str, Any]] = []
            for seed in range(args.first_seed, args.first_seed + args.seeds):
                for with_sets in [v == "sets" for v in args.variants.split(",")]:
                    row = run_one(task, seed, with_sets, args.episodes, Path(tmp), args.bound)
                    rows.append(row)
                    results.append(row)
                    summary[task] = summarise(rows)
                    write_json(args.json, record)
                    print(f"{task:15} seed {seed:2d} {'sets' if with_sets else 'cons':4} "
                          f"score {row['score']:9.3f} episodes {row['episodes']:6d} "
                          f"cpu {row['train_cpu_seconds']:6.1f} s", flush=True)
            s = summary[task]
            print(f"{task}: " + " | ".join(
                f"{v} median {s[v]['median']:.3f} worst {s[v]['worst']:.3f}"
                for v in ("consequents", "sets") if v in s)
                + f" | Mann-Whitney p {s['mann_whitney_p']:.3g}", flush=True)
    print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
