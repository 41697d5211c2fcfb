"""Rule-base scaling: the cost of a step follows the rules that fire, not M.

    python benchmarks/bench_scaling.py [--json PATH] [--quick] [--sweep]

For M = 15 (the ballchase controller, 3 x 5 sets) and M = 625, 15,625, 117,649 (4 x 5,
6 x 5 and 6 x 7 overlapping trapezoids), measures per state: batched inference
(``output`` on a batch), one-state inference (``output_one``) and a fuzzy-Q step's
rule work (``active_rules`` and their phi_m = alpha_m / sum(alpha), eq. 8), each also per
fired rule, and the peak memory numpy allocates during the batched call next to what a
dense (B, M) activation array would take. Then, for rule bases around the switch between
the two batched walks (every rule for a block of states; each state's fired rules), both
walks side by side with the one ``output`` takes (goal: within 25 % of the cheaper walk, so
that crossing the switch costs no jump), and issue 16's cliff: two inputs of 6 sets
(M = 36) against 5 sets (M = 25), 89 against 26 ns per state when the switch was at 32 rules
(goal: at most 36 / 25 = 1.44x, the cost growing no faster than M). Times are CPU time, the
least of several repeats. Writes JSON (default: bench_scaling.json beside this script).

``--sweep`` measures instead every rule base the kernels' choice decides (N <= 8 inputs of
L <= 9 sets, M <= MAX_RULES): ``output`` against the naive kernel
(``benchmarks/naive_kernel.py``) at every batch size in ``SWEEP_BATCHES`` (goal: at least 1x
everywhere; the two measured in turn, so that the machine's load falls on both alike), and
at 1,000 states both batched walks beside the one ``output`` takes (goal: within 25 % of
the cheaper), with the worst of each.
"""

from __future__ import annotations

import argparse
import itertools
import time
import tracemalloc
from pathlib import Path
from typing import Any

import common
import numpy as np
from naive_kernel import naive_output

import flctool
from flctool import Controller
from flctool.behaviour import behaviour_from_data
from flctool.behaviour.checks import MAX_RULES
from flctool.compile import controller as controller_module
from flctool.compile import kernels

GOAL_PER_ACTIVE_RULE = 5.0  # largest M at most 5x the smallest, per fired rule
GOAL_CLIFF = 36 / 25  # M = 36 against M = 25 (2 inputs): no faster than M grows
GOAL_WALK_CHOICE = 1.25  # output's walk against the cheaper of the two
# Rule bases around the switch between the walks, by number of inputs: N x L sets.
AROUND_SWITCH = {2: (5, 6, 8, 12, 16, 20, 24), 3: (3, 4, 5, 6, 7), 4: (3, 4, 5)}
# --sweep: every batch size where a walk changes (state by state up to 8 or 16 states, the
# tiny bases' loop up to 64) on both sides, and a large batch.
SWEEP_BATCHES = (1, 2, 4, 8, 9, 16, 17, 32, 64, 65, 1000)
GOAL_VS_NAIVE = 1.0


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


def walk_ns(controller: Controller, states: np.ndarray, dense: bool, repeats: int) -> float:
    """CPU ns per state of the batched kernel on one walk (every rule, or the fired rules)."""
    layout = controller._layout
    if dense:  # keep the grid the default layout leaves out
        layout = kernels.keep_grid(layout, controller.rule_grid)
    tables = np.array(controller.consequents, dtype=np.intp)[None, :]
    out = np.empty(len(states))
    infer = kernels.entry("infer")
    seconds = common.best_seconds(lambda: infer(states, layout.floats, layout.ints, tables,
                                                out, 0, len(states), dense), repeats)
    return seconds / len(states) * 1e9


def around_switch(batch: int, repeats: int) -> list[dict[str, Any]]:
    rows = []
    for n_inputs, sizes in AROUND_SWITCH.items():
        for n_sets in sizes:
            controller = overlapping_controller(n_inputs, n_sets, seed=n_inputs * 10 + n_sets)
            states = common.uniform_states(controller, batch, seed=2)
            controller.output(states[:100])
            every = walk_ns(controller, states, True, repeats)
            fired = walk_ns(controller, states, False, repeats)
            output = common.best_seconds(lambda c=controller, s=states: c.output(s),
                                         repeats) / batch * 1e9
            rows.append({"inputs": n_inputs, "sets": n_sets, "rules": controller.n_rules,
                         "walks_every_rule": controller._layout.dense,
                         "every_rule_ns": every, "fired_rules_ns": fired,
                         "output_ns": output, "over_cheaper": output / min(every, fired)})
            print(f"N = {n_inputs}, L = {n_sets:>2}, M = {controller.n_rules:>4}: every rule "
                  f"{every:6.1f}, fired rules {fired:6.1f}, output {output:6.1f} ns/state "
                  f"({'every rule' if controller._layout.dense else 'fired rules'})",
                  flush=True)
    return rows


def crossings(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Where output's walk changes as M grows (per N): cost and M just past over just before."""
    found = []
    for before, after in itertools.pairwise(rows):
        if before["inputs"] == after["inputs"] and (before["walks_every_rule"]
                                                    != after["walks_every_rule"]):
            found.append({"inputs": before["inputs"], "rules_before": before["rules"],
                          "rules_after": after["rules"],
                          "cost_ratio": after["output_ns"] / before["output_ns"],
                          "rules_ratio": after["rules"] / before["rules"]})
    return found


def cpu_per_call(run: Any, repeats: int, at_least: float = 0.02) -> float:
    """CPU seconds of one call, the least of ``repeats`` loops of at least ``at_least`` s."""
    best = float("inf")
    for _ in range(repeats):
        calls = 0
        started = time.process_time()
        while True:
            run()
            calls += 1
            spent = time.process_time() - started
            if spent >= at_least:
                break
        best = min(best, spent / calls)
    return best


def paired_per_call(first: Any, second: Any, repeats: int) -> tuple[float, float]:
    """:func:`cpu_per_call` of two calls measured in turn (first, second, first, ...), the
    least of ``repeats`` loops each: a change in the machine's load falls on both alike."""
    best = [float("inf"), float("inf")]
    for _ in range(repeats):
        for index, run in enumerate((first, second)):
            best[index] = min(best[index], cpu_per_call(run, 1))
    return best[0], best[1]


def sweep(repeats: int, only: set[tuple[int, int]] | None = None) -> dict[str, Any]:
    """output against the naive kernel at every N <= 8, L <= 9 (M <= MAX_RULES) and batch of
    SWEEP_BATCHES, and the walk output takes at 1,000 states against both walks."""
    rows = []
    for n_inputs in range(1, 9):
        for n_sets in range(2, 10):
            if n_sets ** n_inputs > MAX_RULES or (only and (n_inputs, n_sets) not in only):
                continue
            controller = overlapping_controller(n_inputs, n_sets, seed=n_inputs * 10 + n_sets)
            naive = naive_output(controller)
            for batch in SWEEP_BATCHES:
                states = common.uniform_states(controller, batch, seed=2)
                ours = controller.output(states)
                np.testing.assert_array_equal(ours, naive(states))  # the same bits
                flctool_s, naive_s = paired_per_call(
                    lambda c=controller, s=states: c.output(s),
                    lambda s=states, f=naive: f(s), repeats)
                row = {"inputs": n_inputs, "sets": n_sets, "rules": controller.n_rules,
                       "batch": batch, "walks_every_rule": controller._layout.dense,
                       "output_ns": flctool_s / batch * 1e9,
                       "naive_ns": naive_s / batch * 1e9, "vs_naive": naive_s / flctool_s}
                if batch == max(SWEEP_BATCHES):
                    # the every-rule walk is left out where its (B, M) grid would be too big
                    every = (walk_ns(controller, states, True, repeats)
                             if controller.n_rules * n_inputs <= 4_000_000 else None)
                    fired = walk_ns(controller, states, False, repeats)
                    cheaper = fired if every is None else min(every, fired)
                    chosen = every if controller._layout.dense and every is not None else fired
                    row.update({"every_rule_ns": every, "fired_rules_ns": fired,
                                "over_cheaper": chosen / cheaper})
                rows.append(row)
            worst = min(r["vs_naive"] for r in rows if r["rules"] == controller.n_rules
                        and r["inputs"] == n_inputs)
            by_batch = " ".join(f"{r['batch']}:{r['vs_naive']:.2f}" for r in rows
                                if r["rules"] == controller.n_rules
                                and r["inputs"] == n_inputs)
            print(f"N = {n_inputs}, L = {n_sets}, M = {controller.n_rules:>7,} "
                  f"({'every rule' if controller._layout.dense else 'fired rules'}"
                  f"{', a few states interleaved' if controller._layout.ints[4] else ''}): "
                  f"worst {worst:.2f}x the naive kernel ({by_batch})", flush=True)
    worst_row = min(rows, key=lambda r: r["vs_naive"])
    choice = [r for r in rows if "over_cheaper" in r]
    worst_choice = max(r["over_cheaper"] for r in choice)
    print(f"\nworst against the naive kernel: {worst_row['vs_naive']:.2f}x at N = "
          f"{worst_row['inputs']}, L = {worst_row['sets']}, B = {worst_row['batch']} (goal >= "
          f"{GOAL_VS_NAIVE:g}x): {'met' if worst_row['vs_naive'] >= GOAL_VS_NAIVE else 'MISSED'}")
    print(f"output's walk against the cheaper at 1,000 states (<= {GOAL_WALK_CHOICE}x): "
          f"{worst_choice:.2f}: {'met' if worst_choice <= GOAL_WALK_CHOICE else 'MISSED'}")
    return {"rows": rows, "worst_vs_naive": worst_row, "worst_walk_choice": worst_choice}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--json", type=Path, default=Path(__file__).with_suffix(".json"),
                        help="where to write the results")
    parser.add_argument("--quick", action="store_true", help="fewer states and repeats")
    parser.add_argument("--sweep", action="store_true",
                        help="every N <= 8, L <= 9 against the naive kernel instead")
    parser.add_argument("--only", metavar="NxL,...",
                        help="--sweep: only these rule bases (inputs x sets), e.g. 8x2,6x2")
    args = parser.parse_args()
    controller_module.set_inference("kernels")  # the compiled walks are measured here
    if args.sweep:
        only = ({tuple(int(v) for v in shape.split("x")) for shape in args.only.split(",")}
                if args.only else None)
        result = sweep(3 if args.quick else 5, only)  # type: ignore[arg-type]
        common.write_json(args.json.with_name(args.json.stem + "_sweep.json"), {
            "benchmark": "bench_scaling --sweep", "when": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
            "machine": common.machine(), "timing": "CPU time, least of the repeats",
            "batches": SWEEP_BATCHES, **result})
        return
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

    print("\nAround the switch between the batched walks (CPU ns per state):")
    switch = around_switch(batch, repeats)
    found = crossings(switch)
    worst_choice = max(row["over_cheaper"] for row in switch)
    by_shape = {(row["inputs"], row["sets"]): row for row in switch}
    cliff = by_shape[2, 6]["output_ns"] / by_shape[2, 5]["output_ns"]
    for crossing in found:
        print(f"N = {crossing['inputs']}: M = {crossing['rules_before']} -> "
              f"{crossing['rules_after']} ({crossing['rules_ratio']:.1f}x the rules) crosses "
              f"the switch: {crossing['cost_ratio']:.2f}x the cost per state")
    print(f"M = 36 over M = 25 (2 inputs; <= {GOAL_CLIFF:.2f}): {cliff:.2f}: "
          f"{'met' if cliff <= GOAL_CLIFF else 'MISSED'}")
    print(f"output's walk against the cheaper (<= {GOAL_WALK_CHOICE}x): {worst_choice:.2f}: "
          f"{'met' if worst_choice <= GOAL_WALK_CHOICE else 'MISSED'}")

    common.write_json(args.json, {
        "benchmark": "bench_scaling", "when": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        "machine": common.machine(), "quick": args.quick, "repeats": repeats, "rows": rows,
        "largest_over_smallest_per_fired_rule": ratios,
        "goal_per_fired_rule": GOAL_PER_ACTIVE_RULE,
        "timing": "CPU time, least of the repeats",
        "around_switch": switch, "switch_crossings": found,
        "goals": {"m36_over_m25": {"value": cliff, "goal": GOAL_CLIFF},
                  "walk_choice": {"value": worst_choice, "goal": GOAL_WALK_CHOICE}},
    })
    print(f"\nwrote {args.json.name}")


if __name__ == "__main__":
    main()
