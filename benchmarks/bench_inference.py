"""Inference speed of the ballchase controller: flctool against a naive numba kernel of
eq. 1-3 at every batch size, and against scikit-fuzzy, pyfuzzylite and simpful, in one run,
with every output checked equal to flctool's first (the naive kernel's bit for bit).

    nice -n 10 python benchmarks/bench_inference.py [--batch 1000000] [--json PATH] [--quick]

Every figure is CPU time (``time.process_time``), the least of several repetitions (the
least disturbed by other processes on a shared machine), except the two-thread speed-up,
which is wall time by nature (its CPU time is printed beside it). Prints, with ratios:

1. ns per state of ``Controller.output`` and of the naive kernel (benchmarks/naive_kernel.py)
   for batches of 1 to 10^6 states: goals, never slower than the naive kernel, and at least
   4x it on the largest batch;
2. ``output_one`` in µs per call against the naive kernel on one state: goal <= 0.6 µs;
3. ``output(..., threads=2)`` on the largest batch;
4. states per second (a batch) and µs per state (one state per call) of the other libraries.
   Libraries without array inference are timed one state at a time on a subset and their
   states/s extrapolated; the table says which. Needs the bench extra:
   pip install 'flctool[bench]'.

Writes JSON (default: bench_inference.json beside this script).
"""

from __future__ import annotations

import argparse
import contextlib
import io
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import common
import numpy as np
from naive_kernel import naive_arrays, naive_infer, naive_output

import flctool
from flctool.compile import kernels

TOLERANCE = 1e-9
GOALS = {"single_us": 0.6, "batched_vs_naive": 4.0, "every_size_vs_naive": 1.0,
         "vs_pyfuzzylite": 25.0, "vs_skfuzzy": 3000.0}
# Every size up to 8, then both sides of each switch between walks (16/17: state by state
# or blocks for two inputs; 64/65: one block or two), then powers of ten.
SIZES = (1, 2, 3, 4, 5, 6, 7, 8, 10, 12, 16, 17, 24, 32, 64, 65, 100, 1_000, 10_000,
         100_000, 1_000_000)
STATES_PER_TIMING = 200_000  # small batches are timed as many calls, this many states in all


def per_state_ns(output: Any, batches: list[np.ndarray], repeats: int) -> float:
    """Least CPU ns per state of ``output(batch)`` over every batch, of ``repeats`` passes."""
    def one_pass() -> None:
        for batch in batches:
            output(batch)
    states = sum(len(batch) for batch in batches)
    return common.best_seconds(one_pass, repeats) / states * 1e9


def against_naive(controller: flctool.Controller, largest: int, repeats: int,
                  quick: bool) -> list[dict[str, Any]]:
    """flctool's output and the naive kernel on the same batches, size by size."""
    naive = naive_output(controller)
    rows = []
    for size in (s for s in SIZES if s <= largest):
        calls = max(1, (STATES_PER_TIMING // (10 if quick else 1)) // size)
        batches = [common.uniform_states(controller, size, seed=k) for k in range(calls)]
        for batch in batches[:50]:
            if not np.array_equal(naive(batch), controller.output(batch)):
                raise SystemExit("the naive kernel disagrees with flctool")
        ours = per_state_ns(controller.output, batches, repeats)
        theirs = per_state_ns(naive, batches, repeats)
        rows.append({"batch": size, "calls": calls, "flctool_ns_per_state": ours,
                     "naive_ns_per_state": theirs, "ratio": theirs / ours})
        print(f"  B = {size:>9,}: flctool {ours:8.1f} ns/state, naive kernel {theirs:8.1f} "
              f"ns/state: {theirs / ours:5.2f}x", flush=True)
    return rows

# Start-up in a fresh interpreter: the time to import flctool (numba must not be imported
# by that), and the time of the first inference calls (numba compiling, or loading its cache).
_STARTUP = """
import sys, time
start = time.perf_counter()
import flctool, flctool.cli
imported = time.perf_counter()
assert "numba" not in sys.modules, "numba imported by import flctool"
controller = flctool.compile_behaviour(flctool.load_behaviour(sys.argv[1]))
compiled = time.perf_counter()
controller.output(controller.ranges.T.copy())
controller.output_one(controller.ranges[:, 0].copy())
controller.active_rules(controller.ranges[:, 0].copy())
first = time.perf_counter()
print(imported - start, first - compiled)
"""


def startup(cache_dir: str | None) -> tuple[float, float]:
    """(import seconds, first-inference seconds) in a new interpreter; with ``cache_dir`` numba
    caches there (empty: a cold compile), else in its default place."""
    env = dict(os.environ)
    if cache_dir is not None:
        env["NUMBA_CACHE_DIR"] = cache_dir
    result = subprocess.run([sys.executable, "-c", _STARTUP, str(common.BALLCHASE)], env=env,
                            capture_output=True, text=True, check=True)
    imported, first = result.stdout.split()
    return float(imported), float(first)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--batch", type=int, default=1_000_000, help="states in the batch")
    parser.add_argument("--json", type=Path, default=Path(__file__).with_suffix(".json"),
                        help="where to write the results")
    parser.add_argument("--quick", action="store_true", help="fewer states and repeats")
    args = parser.parse_args()
    repeats = 2 if args.quick else 5
    subset = {"pyfuzzylite": 2_000 if args.quick else 20_000,
              "simpful": 300 if args.quick else 2_000,
              "skfuzzy_batch": 300 if args.quick else 2_000,
              "skfuzzy_single": 30 if args.quick else 200,
              "flctool_single": 20_000 if args.quick else 200_000}

    behaviour = flctool.load_behaviour(common.BALLCHASE)
    controller = flctool.compile_behaviour(behaviour)
    states = common.uniform_states(controller, args.batch, seed=0)
    print(f"ballchase: {controller.n_inputs} inputs, {'x'.join(map(str, controller.shape))} "
          f"sets, {controller.n_rules} rules, {controller.n_commands} singletons; "
          f"batch of {args.batch:,} states")

    # -- start-up: import cost, numba compile (cold cache) and cache load (warm) -----------
    with tempfile.TemporaryDirectory() as cache:
        import_s, cold_s = startup(cache)
        _, warm_s = startup(cache)
    print(f"start-up: import flctool {import_s * 1e3:.0f} ms (numba not imported); first "
          f"inference {cold_s:.2f} s with an empty numba cache, {warm_s * 1e3:.0f} ms cached")

    # -- check every library against flctool before timing --------------------------------
    check = states[:300]
    expected = controller.output(check)
    skfuzzy_batch = common.skfuzzy_simulation(behaviour, controller)
    skfuzzy_one = common.skfuzzy_one(common.skfuzzy_simulation(behaviour, controller),
                                     behaviour)
    fuzzylite_one = common.fuzzylite_one(common.fuzzylite_engine(behaviour, controller))
    differences = {}
    with contextlib.redirect_stdout(io.StringIO()):  # simpful announces the model type
        simpful_one = common.simpful_one(common.simpful_system(behaviour, controller),
                                         behaviour)
        differences["flctool output_one"] = common.check_equal(
            "flctool output_one", [controller.output_one(s) for s in check], expected, 0.0)
        differences["scikit-fuzzy"] = common.check_equal(
            "scikit-fuzzy", common.skfuzzy_outputs(skfuzzy_batch, behaviour, check), expected,
            TOLERANCE)
        differences["scikit-fuzzy (one state)"] = common.check_equal(
            "scikit-fuzzy", [skfuzzy_one(s) for s in check[:30]], expected[:30], TOLERANCE)
        differences["pyfuzzylite"] = common.check_equal(
            "pyfuzzylite", [fuzzylite_one(s) for s in check], expected, TOLERANCE)
        differences["simpful"] = common.check_equal(
            "simpful", [simpful_one(s) for s in check], expected, TOLERANCE)
    print("outputs equal to flctool's: " + ", ".join(
        f"{name} (max |diff| {value:.1e})" for name, value in differences.items()))

    # -- 1. every batch size against the naive kernel ---------------------------------------
    print("\n1. Controller.output against a naive numba kernel (CPU ns per state, least of "
          f"{repeats}):")
    sizes = against_naive(controller, args.batch, repeats, args.quick)
    batched_vs_naive = sizes[-1]["ratio"]
    worst = min(sizes, key=lambda row: row["ratio"])

    # -- 2. one state per call ---------------------------------------------------------------
    one_states = list(states[:subset["flctool_single"]])
    one_call = common.per_call_seconds(controller.output_one, one_states, repeats)
    arrays = naive_arrays(controller)
    naive_rows = [s[None, :].copy() for s in one_states]
    naive_single = common.per_call_seconds(lambda row: naive_infer(row, *arrays), naive_rows,
                                           repeats)
    print(f"\n2. output_one: {one_call * 1e6:.3f} µs per call (CPU, least of {repeats}); the "
          f"naive kernel on one state {naive_single * 1e6:.3f} µs: "
          f"{naive_single / one_call:.2f}x")

    # -- 3. both cores -----------------------------------------------------------------------
    threaded_wall = common.best_wall_seconds(lambda: controller.output(states, threads=2),
                                             repeats)
    one_wall = common.best_wall_seconds(lambda: controller.output(states), repeats)
    threaded_cpu = common.best_seconds(lambda: controller.output(states, threads=2), repeats)
    identical = bool(np.array_equal(controller.output(states, threads=2),
                                    controller.output(states)))
    print(f"\n3. output(threads=2) on {args.batch:,} states: {one_wall / threaded_wall:.2f}x "
          f"faster in wall time ({threaded_wall * 1e9 / args.batch:.1f} ns/state against "
          f"{one_wall * 1e9 / args.batch:.1f}; CPU {threaded_cpu * 1e9 / args.batch:.1f} "
          f"ns/state), outputs identical: {identical}")
    if not identical:
        raise SystemExit("threads=2 changed the outputs")

    # -- 4. the other libraries --------------------------------------------------------------
    rows: list[dict[str, Any]] = []
    batched = common.best_seconds(lambda: controller.output(states), repeats)
    rows.append({"library": "flctool", "states_per_s": args.batch / batched,
                 "us_per_state": one_call * 1e6, "batched_how": f"batch of {args.batch:,}"})

    n = subset["skfuzzy_batch"]
    skfuzzy_batch = common.skfuzzy_simulation(behaviour, controller)  # new array shape
    seconds = common.best_seconds(
        lambda: common.skfuzzy_outputs(skfuzzy_batch, behaviour, states[:n]), 1)
    single = common.per_call_seconds(skfuzzy_one, list(states[:subset["skfuzzy_single"]]), 1)
    rows.append({"library": "scikit-fuzzy (control)", "states_per_s": n / seconds,
                 "us_per_state": single * 1e6,
                 "batched_how": f"array inputs, {n:,} states, extrapolated"})

    with contextlib.redirect_stdout(io.StringIO()):
        for name, infer in (("pyfuzzylite 7.1", fuzzylite_one), ("simpful", simpful_one)):
            key = name.split()[0]
            single = common.per_call_seconds(infer, list(states[:subset[key]]),
                                             max(1, repeats // 2))
            rows.append({"library": name, "states_per_s": 1 / single,
                         "us_per_state": single * 1e6,
                         "batched_how": f"no array inference: one state at a time over "
                                        f"{subset[key]:,} states, extrapolated"})

    ours = rows[0]
    for row in rows:
        row["batched_ratio"] = ours["states_per_s"] / row["states_per_s"]
        row["single_ratio"] = row["us_per_state"] / ours["us_per_state"]

    print()
    print(f"| {'library':<24} | {'states/s (batched)':>18} | {'µs/state (one)':>14} | "
          f"{'flctool is x faster':>19} | {'(one)':>8} | batched how")
    print(f"|{'-' * 26}|{'-' * 20}:|{'-' * 16}:|{'-' * 21}:|{'-' * 10}:|{'-' * 12}")
    for row in rows:
        print(f"| {row['library']:<24} | {row['states_per_s']:>18,.0f} | "
              f"{row['us_per_state']:>14,.2f} | {row['batched_ratio']:>19,.0f} | "
              f"{row['single_ratio']:>8,.0f} | {row['batched_how']}")

    by_name = {row["library"]: row for row in rows}
    goals = {
        "single_us": (one_call * 1e6, "<=", GOALS["single_us"]),
        "batched_vs_naive": (batched_vs_naive, ">=", GOALS["batched_vs_naive"]),
        "every_size_vs_naive": (worst["ratio"], ">=", GOALS["every_size_vs_naive"]),
        "vs_pyfuzzylite": (by_name["pyfuzzylite 7.1"]["batched_ratio"], ">=",
                           GOALS["vs_pyfuzzylite"]),
        "vs_skfuzzy": (by_name["scikit-fuzzy (control)"]["batched_ratio"], ">=",
                       GOALS["vs_skfuzzy"]),
    }
    print()
    met = {}
    for name, (value, sense, goal) in goals.items():
        met[name] = value >= goal if sense == ">=" else value <= goal
        where = f" (worst at B = {worst['batch']:,})" if name == "every_size_vs_naive" else ""
        print(f"goal {name}: {value:,.2f} {sense} {goal:,.1f}{where}: "
              f"{'met' if met[name] else 'MISSED'}")

    common.write_json(args.json, {
        "benchmark": "bench_inference", "behaviour": "behaviours/ballchase-handmade.yaml",
        "when": time.strftime("%Y-%m-%dT%H:%M:%S%z"), "machine": common.machine(),
        "batch": args.batch, "repeats": repeats, "quick": args.quick,
        "tolerance": TOLERANCE, "max_differences": differences,
        "small_batch": kernels.OWN_SMALL_BATCH_FEW_INPUTS if controller.n_inputs <= 2
        else kernels.OWN_SMALL_BATCH,
        "walks_every_rule": controller._layout.dense,
        "timing": "CPU time (time.process_time), least of the repeats",
        "against_naive": sizes,
        "output_one": {"us": one_call * 1e6, "naive_us": naive_single * 1e6,
                       "ratio": naive_single / one_call},
        "threads": {"threads": 2, "wall_speedup": one_wall / threaded_wall,
                    "cpu_ns_per_state": threaded_cpu * 1e9 / args.batch,
                    "identical": identical},
        "startup": {"import_flctool_s": import_s, "first_inference_cold_cache_s": cold_s,
                    "first_inference_warm_cache_s": warm_s},
        "rows": rows, "goals": {name: {"value": value, "sense": sense, "goal": goal,
                                       "met": met[name]}
                                for name, (value, sense, goal) in goals.items()},
    })
    print(f"\nwrote {args.json.name}")


if __name__ == "__main__":
    main()
