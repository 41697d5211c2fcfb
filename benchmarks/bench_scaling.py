"""Rule-base scaling: the cost of a step follows the rules that fire, not M.

    python benchmarks/bench_scaling.py [--json PATH] [--quick]

For M = 15 (the ballchase controller, 3 x 5 sets) and M = 625, 15,625, 117,649 (4 x 5,
6 x 5 and 6 x 7 overlapping trapezoids), measures per state: batched inference
(``output`` on a batch), one-state inference (``output_one``) and a fuzzy-Q step's
rule work (``active_rules`` and their phi_m = alpha_m / sum(alpha), eq. 8), each also per
fired rule, and the peak memory numpy allocates during the batched call next to what a
dense (B, M) activation array would take. Writes JSON (default: bench_scaling.json beside
this script).
"""

from __future__ import annotations

import argparse
import time
import tracemalloc
from pathlib import Path
from typing import Any

import common
import numpy as np

import flctool
from flctool import Controller
from flctool.spec import behaviour_from_data

GOAL_PER_ACTIVE_RULE = 5.0  # largest M at most 5x the smallest, per fired rule


def overlapping_controller(n_inputs: int, n_sets: int, seed: int) -> Controller:
    """N inputs on [0, 1], each with L trapezoids whose slopes overlap their neighbours'
    (so one or two sets of an input fire), and a random complete rule table."""
    step = 1.0 / (n_sets - 1)
    sets = {}
    for j in range(n_sets):
        peak = j * step
        quad = [peak - step, peak - 0.2 * step, peak + 0.2 * step, peak + step]
        if j == 0:
            quad[:2] = [0.0, 0.0]
        if j == n_sets - 1:
            quad[2:] = [1.0, 1.0]
        sets[f"s{j}"] = quad
    data = {"flctool": 1, "name": f"scaling_{n_inputs}x{n_sets}",
            "inputs": {f"x{i}": {"range": [0, 1], "sets": sets} for i in range(n_inputs)},
            "output": {"name": "u", "commands": {f"c{k}": k - 2.0 for k in range(5)}}}
    learning = flctool.compile_behaviour(behaviour_from_data(data))
    rng = np.random.default_rng(seed)
    return learning.with_consequents(rng.integers(0, 5, size=learning.n_rules))


def q_step(controller: Controller, state: np.ndarray) -> np.ndarray:
    """The rule work of one fuzzy-Q step: the fired rules and their phi (eq. 8)."""
    _, alpha = controller.active_rules(state)
    return alpha / alpha.sum()


def measure(name: str, controller: Controller, batch: int, singles: int,
            repeats: int) -> dict[str, Any]:
    states = common.uniform_states(controller, batch, seed=1)
    one_states = list(states[:singles])
    controller.output(states[:10])
    q_step(controller, states[0])
    controller.output_one(states[0])
    fired = np.mean([len(controller.active_rules(s)[0]) for s in states[:2000]])
    batched = common.best_seconds(lambda: controller.output(states), repeats) / batch
    one = common.per_call_seconds(controller.output_one, one_states, repeats)
    step = common.per_call_seconds(lambda s: q_step(controller, s), one_states, repeats)
    tracemalloc.start()
    controller.output(states)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    return {"controller": name, "inputs": controller.n_inputs,
            "sets": "x".join(map(str, controller.shape)), "rules": controller.n_rules,
            "mean_fired_rules": float(fired), "batch": batch,
            "batched_ns_per_state": batched * 1e9,
            "batched_ns_per_fired_rule": batched * 1e9 / fired,
            "one_us_per_state": one * 1e6, "one_us_per_fired_rule": one * 1e6 / fired,
            "q_step_us": step * 1e6, "q_step_us_per_fired_rule": step * 1e6 / fired,
            "peak_traced_bytes_batched": peak,
            "dense_activations_bytes": batch * controller.n_rules * 8}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--json", type=Path, default=Path(__file__).with_suffix(".json"),
                        help="where to write the results")
    parser.add_argument("--quick", action="store_true", help="fewer states and repeats")
    args = parser.parse_args()
    batch, singles, repeats = (20_000, 5_000, 2) if args.quick else (200_000, 50_000, 5)

    ballchase = flctool.compile_behaviour(flctool.load_behaviour(common.BALLCHASE))
    controllers = [("ballchase", ballchase)] + [
        (f"{n} inputs x {sets} sets", overlapping_controller(n, sets, seed=n * 10 + sets))
        for n, sets in ((4, 5), (6, 5), (6, 7))]
    rows = []
    for name, controller in controllers:
        rows.append(measure(name, controller, batch, singles, repeats))
        row = rows[-1]
        print(f"M = {row['rules']:>7,} ({name}): {row['mean_fired_rules']:.1f} rules fire "
              f"on average", flush=True)

    print()
    print("| M | N | fired (mean) | batched ns/state | ns/fired rule | output_one µs | "
          "µs/fired rule | Q step µs | µs/fired rule | peak numpy MB | dense (B, M) MB |")
    print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for row in rows:
        print(f"| {row['rules']:,} | {row['inputs']} | {row['mean_fired_rules']:.1f} | "
              f"{row['batched_ns_per_state']:.1f} | {row['batched_ns_per_fired_rule']:.2f} | "
              f"{row['one_us_per_state']:.2f} | {row['one_us_per_fired_rule']:.3f} | "
              f"{row['q_step_us']:.2f} | {row['q_step_us_per_fired_rule']:.3f} | "
              f"{row['peak_traced_bytes_batched'] / 1e6:.1f} | "
              f"{row['dense_activations_bytes'] / 1e6:,.0f} |")

    ratios = {}
    print()
    for key in ("batched_ns_per_fired_rule", "one_us_per_fired_rule",
                "q_step_us_per_fired_rule"):
        ratios[key] = rows[-1][key] / rows[0][key]
        verdict = "met" if ratios[key] <= GOAL_PER_ACTIVE_RULE else "MISSED"
        print(f"largest / smallest M, {key.replace('_', ' ')}: {ratios[key]:.2f} "
              f"(goal <= {GOAL_PER_ACTIVE_RULE:g}): {verdict}")

    common.write_json(args.json, {
        "benchmark": "bench_scaling", "when": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        "machine": common.machine(), "quick": args.quick, "repeats": repeats, "rows": rows,
        "largest_over_smallest_per_fired_rule": ratios,
        "goal_per_fired_rule": GOAL_PER_ACTIVE_RULE,
    })
    print(f"\nwrote {args.json.name}")


if __name__ == "__main__":
    main()
