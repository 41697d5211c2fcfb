"""How long learning takes and how much memory it holds: issue 6's learning goals.

    python benchmarks/bench_learning.py [--repeats 5] [--seeds 30] [--workers 2] [--json FILE]

1. The paper's protocol on ballchase (population 10, 30 generations, one trial each = 300
   trials of up to 200 steps), per learner: the training loop alone
   (``flctool.learners.train``), training into a run directory (checkpoints, metrics,
   best.yaml: ``Run.train``), and the whole command ``python -m flctool learn
   behaviours/ballchase.yaml``, with how much of it is start-up (the bare interpreter, then
   importing what the command imports). Best of ``--repeats`` each. Goal: under 0.3 s after
   start-up.
2. ``--seeds`` seeds x 3 learners through a process pool of ``--workers`` (spawn start, so
   the workers' imports are counted), once with the loop alone and once writing run
   directories. Goal: 30 x 3 in under 15 s on 2 cores.
3. Peak resident memory of the real commands, each the only child of a fresh interpreter
   (``getrusage(RUSAGE_CHILDREN).ru_maxrss``). Goal: ``flctool learn`` at most 150 MB.

Prints the tables and writes JSON (default: bench_learning.json beside the script). A
script, never a timed test.
"""

from __future__ import annotations

import argparse
import multiprocessing
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from common import ROOT, best_seconds, machine, write_json

from flctool import load_behaviour
from flctool.learners import make_learner, train
from flctool.runs import create_run, resolve_behaviour

BALLCHASE = ROOT / "behaviours" / "ballchase.yaml"
HANDMADE = ROOT / "behaviours" / "ballchase-handmade.yaml"
LEARNERS = ("pitt", "hybrid", "fuzzy_q")
GOAL_SECONDS = 0.3
GOAL_POOL_SECONDS = 15.0
GOAL_MEGABYTES = 150.0

# What `flctool learn` imports before it trains (the learners and the simulator are
# registered by name and imported on first use).
IMPORTS = ("import flctool.cli, flctool.runs, flctool.envs.ballchase, flctool.learners.pitt, "
           "flctool.learners.hybrid, flctool.learners.fuzzy_q")
# Runs the command in this interpreter and reports afterwards whether it imported numba.
NUMBA_PROBE = ("import atexit, runpy, sys\n"
               "atexit.register(lambda: print('numba' in sys.modules, file=sys.stderr))\n"
               "sys.argv = ['flctool', *sys.argv[1:]]\n"
               "runpy.run_module('flctool', run_name='__main__')\n")
# Runs one command as its only child and prints the child's peak resident set in kB.
RSS_PROBE = ("import resource, subprocess, sys\n"
             "subprocess.run(sys.argv[1:], check=True, stdout=subprocess.DEVNULL)\n"
             "print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)\n")


def wall(command: list[str], cwd: Path) -> float:
    start = time.perf_counter()
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL, cwd=cwd)
    return time.perf_counter() - start


def learn_command(learner: str, out: Path) -> list[str]:
    return ["-m", "flctool", "learn", str(BALLCHASE), "--learner", learner, "--out", str(out),
            "--json"]


# -- 1. the paper's protocol, one run --------------------------------------------------------
def startup(repeats: int, tmp: Path) -> dict[str, float]:
    """Seconds of a bare interpreter and of importing what ``flctool learn`` imports."""
    interpreter = min(wall([sys.executable, "-c", "pass"], tmp) for _ in range(repeats))
    imports = min(wall([sys.executable, "-c", IMPORTS], tmp) for _ in range(repeats))
    return {"interpreter_seconds": interpreter, "import_seconds": imports - interpreter,
            "startup_seconds": imports}


def measure(learner: str, repeats: int, tmp: Path, startup_seconds: float) -> dict[str, Any]:
    behaviour = resolve_behaviour(load_behaviour(BALLCHASE), {"learner": learner})
    steps = 0

    def loop_only() -> None:
        nonlocal steps
        steps = sum(m.steps for m in train(make_learner(behaviour)))

    loop = best_seconds(loop_only, repeats)
    runs = iter(range(repeats))
    recorded = best_seconds(
        lambda: create_run(behaviour, tmp / f"{learner}-run{next(runs)}").train(), repeats)
    command = min(wall([sys.executable, *learn_command(learner, tmp / f"{learner}-cli{i}")],
                       tmp) for i in range(repeats))
    probe = subprocess.run([sys.executable, "-c", NUMBA_PROBE,
                            *learn_command(learner, tmp / f"{learner}-probe")[2:]],
                           check=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                           text=True, cwd=tmp)
    return {"learner": learner, "steps": steps, "loop_seconds": loop,
            "steps_per_second": steps / loop, "run_dir_seconds": recorded,
            "command_seconds": command, "command_after_startup_seconds":
            command - startup_seconds,
            "command_imports_numba": probe.stderr.strip().splitlines()[-1] == "True"}


# -- 2. many seeds through a process pool ----------------------------------------------------
def train_one(task: tuple[str, int, str | None]) -> dict[str, Any]:
    """One run of the protocol in a pool worker: (learner, seed, run directory or None)."""
    learner, seed, out = task
    behaviour = resolve_behaviour(load_behaviour(BALLCHASE), {"learner": learner, "seed": seed})
    start = time.perf_counter()
    if out is None:
        history = train(make_learner(behaviour))
        best = max(m.best for m in history)
    else:
        summary = create_run(behaviour, Path(out)).train()
        best = float(summary.best["fitness"])
    return {"learner": learner, "seed": seed, "seconds": time.perf_counter() - start,
            "best": best}


def pool(seeds: int, workers: int, tmp: Path | None) -> dict[str, Any]:
    """Wall time of ``seeds`` x 3 runs through ``workers`` spawned processes, from creating
    the pool (the workers' start-up counts) to the last result."""
    tasks = [(learner, seed, None if tmp is None else str(tmp / f"{learner}-seed{seed}"))
             for seed in range(seeds) for learner in LEARNERS]
    context = multiprocessing.get_context("spawn")
    start = time.perf_counter()
    with context.Pool(workers) as workers_pool:
        results = list(workers_pool.imap_unordered(train_one, tasks))
    total = time.perf_counter() - start
    seconds = [r["seconds"] for r in results]
    return {"runs": len(results), "workers": workers, "run_dirs": tmp is not None,
            "wall_seconds": total, "wall_per_run_seconds": total / len(results),
            "mean_run_seconds": statistics.fmean(seconds), "max_run_seconds": max(seconds),
            "per_learner_mean_seconds": {
                learner: statistics.fmean(r["seconds"] for r in results
                                          if r["learner"] == learner) for learner in LEARNERS}}


# -- 3. peak memory ---------------------------------------------------------------------------
def peak_megabytes(arguments: list[str], tmp: Path) -> float:
    out = subprocess.run([sys.executable, "-c", RSS_PROBE, sys.executable, *arguments],
                         check=True, capture_output=True, text=True, cwd=tmp)
    return int(out.stdout.strip()) / 1024.0  # ru_maxrss is in kB on Linux


def memory(tmp: Path) -> list[dict[str, Any]]:
    commands = {
        "flctool learn behaviours/ballchase.yaml":
            ["-m", "flctool", "learn", str(BALLCHASE), "--out", str(tmp / "mem-learn"),
             "--json"],
        "flctool evaluate behaviours/ballchase-handmade.yaml --episodes 1000":
            ["-m", "flctool", "evaluate", str(HANDMADE), "--episodes", "1000", "--json"],
        "python -c 'import numba' (for scale)": ["-c", "import numba"],
        "python -c 'import flctool.cli' (for scale)": ["-c", "import flctool.cli"],
    }
    return [{"command": name, "peak_rss_mb": peak_megabytes(arguments, tmp)}
            for name, arguments in commands.items()]


# -- report -----------------------------------------------------------------------------------
def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--seeds", type=int, default=30)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--json", type=Path, default=Path(__file__).with_suffix(".json"))
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as name:
        tmp = Path(name)
        start = startup(args.repeats, tmp)
        results = [measure(learner, args.repeats, tmp, start["startup_seconds"])
                   for learner in LEARNERS]
        pools = [pool(args.seeds, args.workers, None),
                 pool(args.seeds, args.workers, tmp / "pool")]
        peaks = memory(tmp)

    print(f"1. ballchase, paper protocol (population 10, 30 generations, 1 trial = 300 "
          f"trials); best of {args.repeats}")
    print(f"{'learner':8} {'steps':>6} {'loop s':>7} {'steps/s':>8} {'run dir s':>9} "
          f"{'command s':>9} {'- start-up':>10} {'numba':>6}")
    for r in results:
        print(f"{r['learner']:8} {r['steps']:6d} {r['loop_seconds']:7.3f} "
              f"{r['steps_per_second']:8.0f} {r['run_dir_seconds']:9.3f} "
              f"{r['command_seconds']:9.3f} {r['command_after_startup_seconds']:10.3f} "
              f"{'yes' if r['command_imports_numba'] else 'no':>6}")
    print(f"start-up of the command: {start['startup_seconds']:.3f} s = interpreter "
          f"{start['interpreter_seconds']:.3f} s + imports {start['import_seconds']:.3f} s")

    print(f"\n2. {args.seeds} seeds x {len(LEARNERS)} learners, pool of {args.workers} "
          f"spawned workers")
    print(f"{'run dirs':8} {'runs':>5} {'wall s':>7} {'wall/run s':>10} {'mean run s':>10} "
          f"{'max run s':>9}  mean per learner")
    for p in pools:
        per = ", ".join(f"{k} {v:.3f}" for k, v in p["per_learner_mean_seconds"].items())
        print(f"{'yes' if p['run_dirs'] else 'no':8} {p['runs']:5d} {p['wall_seconds']:7.2f} "
              f"{p['wall_per_run_seconds']:10.3f} {p['mean_run_seconds']:10.3f} "
              f"{p['max_run_seconds']:9.3f}  {per}")

    print("\n3. peak resident memory")
    for m in peaks:
        print(f"{m['peak_rss_mb']:7.1f} MB  {m['command']}")

    learn_mb = peaks[0]["peak_rss_mb"]
    goals = {
        "protocol_loop_under_0.3s": all(r["loop_seconds"] < GOAL_SECONDS for r in results),
        "protocol_run_dir_under_0.3s": all(r["run_dir_seconds"] < GOAL_SECONDS
                                           for r in results),
        "pool_under_15s": pools[0]["wall_seconds"] < GOAL_POOL_SECONDS,
        "pool_with_run_dirs_under_15s": pools[1]["wall_seconds"] < GOAL_POOL_SECONDS,
        "learn_peak_at_most_150mb": learn_mb <= GOAL_MEGABYTES,
    }
    print("\ngoals: " + ", ".join(f"{k} {'met' if v else 'MISSED'}" for k, v in goals.items()))
    write_json(args.json, {"machine": machine(), "repeats": args.repeats, "startup": start,
                           "protocol": results, "pool": pools, "memory": peaks,
                           "goals": goals})
    print(f"wrote {args.json.name}")


if __name__ == "__main__":
    main()
