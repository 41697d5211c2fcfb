"""How much CPU learning takes, how much of it is the run directory, and memory: issue 16.

    nice -n 10 python benchmarks/bench_learning.py [--repeats 5] [--seeds 30] [--workers 2]
                                                   [--json FILE]

Every time is CPU time, the least of ``--repeats`` (the least disturbed by the other
processes of a shared machine): ``time.process_time`` in this process, and for commands and
pool workers ``getrusage(RUSAGE_CHILDREN)`` (user + system) of the children.

1. The paper's protocol on ballchase (population 10, 30 generations, one trial each = 300
   trials of up to 200 steps), per learner: the training loop alone
   (``flctool.learners.train``), training into a run directory (``Run.train``: checkpoints,
   metrics, strengths, best.yaml, run.json), run in turn, and the share of the run that is
   bookkeeping: the median over the pairs of (run directory - loop) / run directory (goal
   <= 15 %), and the whole command ``python -m flctool learn behaviours/ballchase.yaml`` with
   its start-up (the bare interpreter, then importing what the command imports). Goal: the
   whole command <= 0.4 s.
2. ``--seeds`` seeds x 3 learners through a process pool of ``--workers`` (spawn start, so
   the workers' imports are counted), with the loop alone and writing run directories: the
   CPU of the parent and every worker, and the runs per minute that gives on 2 cores
   (runs / (CPU / 2) x 60: two cores kept busy). Goal: >= 300 with run directories. The
   wall time is printed too; on a shared machine it says more about the others' load.
3. Peak resident memory of the real commands, each the only child of a fresh interpreter
   (``getrusage(RUSAGE_CHILDREN).ru_maxrss``). Goal: ``flctool learn`` at most 150 MB.
4. Would lock-step help? A learned controller's validation episodes (the run's 20 fixed
   seeds) one after another, as learning runs them (``run_trial``), against the same
   episodes stepped together by the batched simulator with the same per-state inference for
   the episodes still running: CPU of each, and the mean and longest episode (lock-step
   steps every episode until the longest ends).

Prints the tables and writes JSON (default: bench_learning.json beside the script). A
script, never a timed test.
"""

from __future__ import annotations

import argparse
import multiprocessing
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np
from common import ROOT, best_seconds, machine, write_json

from flctool import compile_behaviour, load_behaviour
from flctool.envs import make_env
from flctool.learners import make_learner, train
from flctool.learners.selection import validation_seeds
from flctool.learners.trial import SparseRules, run_trial
from flctool.runs import create_run, resolve_behaviour

BALLCHASE = ROOT / "behaviours" / "ballchase.yaml"
HANDMADE = ROOT / "behaviours" / "ballchase-handmade.yaml"
LEARNERS = ("pitt", "hybrid", "fuzzy_q")
GOAL_BOOKKEEPING = 0.15  # share of a run's CPU
GOAL_COMMAND_SECONDS = 0.4  # flctool learn, the whole command
GOAL_RUNS_PER_MINUTE = 300.0  # with run directories, on 2 cores
GOAL_MEGABYTES = 150.0

# What `flctool learn` imports before it trains (the learners and the simulator are
# registered by name and imported on first use).
IMPORTS = ("import flctool.cli, flctool.cli.learn, flctool.runs, flctool.envs.ballchase, "
           "flctool.learners.genetic, flctool.learners.fuzzy_q")
# Runs the command in this interpreter and reports afterwards which heavy libraries it
# imported (learning needs none of them; each costs tenths of a second).
HEAVY = ("numba", "scipy", "skfuzzy", "matplotlib")
IMPORT_PROBE = ("import atexit, runpy, sys\n"
                f"heavy = {HEAVY!r}\n"
                "atexit.register(lambda: print(' '.join(m for m in heavy if m in sys.modules) "
                "or '-', file=sys.stderr))\n"
                "sys.argv = ['flctool', *sys.argv[1:]]\n"
                "runpy.run_module('flctool', run_name='__main__')\n")
# Runs one command as its only child and prints the child's peak resident set in kB.
RSS_PROBE = ("import resource, subprocess, sys\n"
             "subprocess.run(sys.argv[1:], check=True, stdout=subprocess.DEVNULL)\n"
             "print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)\n")


def children_cpu() -> float:
    """User + system CPU seconds of every child reaped so far."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def cpu(command: list[str], cwd: Path) -> float:
    """CPU seconds of one command run as a child."""
    before = children_cpu()
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                   cwd=cwd)
    return children_cpu() - before


def learn_command(learner: str, out: Path) -> list[str]:
    return ["-m", "flctool", "learn", str(BALLCHASE), "--learner", learner, "--out", str(out),
            "--json"]


# -- 1. the paper's protocol, one run --------------------------------------------------------
def startup(repeats: int, tmp: Path) -> dict[str, float]:
    """Seconds of a bare interpreter and of importing what ``flctool learn`` imports."""
    interpreter = min(cpu([sys.executable, "-c", "pass"], tmp) for _ in range(repeats))
    imports = min(cpu([sys.executable, "-c", IMPORTS], tmp) for _ in range(repeats))
    return {"interpreter_seconds": interpreter, "import_seconds": imports - interpreter,
            "startup_seconds": imports}


def measure(learner: str, repeats: int, tmp: Path, startup_seconds: float) -> dict[str, Any]:
    behaviour = resolve_behaviour(load_behaviour(BALLCHASE), {"learner": learner})
    steps = 0

    def loop_only() -> None:
        nonlocal steps
        steps = sum(m.steps for m in train(make_learner(behaviour)))

    # The loop alone and with the run directory in turn, so that both meet the same load;
    # the share is the median of the pairs' shares (one disturbed run cannot move it).
    loops: list[float] = []
    recordings: list[float] = []
    for i in range(repeats):
        loops.append(best_seconds(loop_only, 1))
        recordings.append(best_seconds(
            lambda i=i: create_run(behaviour, tmp / f"{learner}-run{i}").train(), 1))
    loop, recorded = min(loops), min(recordings)
    share = statistics.median(max(0.0, r - lo) / r for lo, r in zip(loops, recordings,
                                                                     strict=True))
    command = min(cpu([sys.executable, *learn_command(learner, tmp / f"{learner}-cli{i}")],
                      tmp) for i in range(repeats))
    probe = subprocess.run([sys.executable, "-c", IMPORT_PROBE,
                            *learn_command(learner, tmp / f"{learner}-probe")[2:]],
                           check=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                           text=True, cwd=tmp)
    return {"learner": learner, "steps": steps, "loop_seconds": loop,
            "steps_per_second": steps / loop, "run_dir_seconds": recorded,
            "bookkeeping_share": share,
            "command_seconds": command, "command_after_startup_seconds":
            command - startup_seconds,
            "command_imports": probe.stderr.strip().splitlines()[-1]}


# -- 2. many seeds through a process pool ----------------------------------------------------
def train_one(task: tuple[str, int, str | None]) -> dict[str, Any]:
    """One run of the protocol in a pool worker: (learner, seed, run directory or None)."""
    learner, seed, out = task
    behaviour = resolve_behaviour(load_behaviour(BALLCHASE), {"learner": learner, "seed": seed})
    start = time.process_time()
    if out is None:
        history = train(make_learner(behaviour))
        best = max(m.best for m in history)
    else:
        summary = create_run(behaviour, Path(out)).train()
        best = float(summary.to_dict()["best"]["fitness"])
    return {"learner": learner, "seed": seed, "seconds": time.process_time() - start,
            "best": best}


def pool(seeds: int, workers: int, tmp: Path | None) -> dict[str, Any]:
    """``seeds`` x 3 runs through ``workers`` spawned processes, from creating the pool (the
    workers' start-up counts) to the last worker's exit: CPU of the parent and the workers,
    and wall time."""
    tasks = [(learner, seed, None if tmp is None else str(tmp / f"{learner}-seed{seed}"))
             for seed in range(seeds) for learner in LEARNERS]
    context = multiprocessing.get_context("spawn")
    start, parent, children = time.perf_counter(), time.process_time(), children_cpu()
    workers_pool = context.Pool(workers)
    results = list(workers_pool.imap_unordered(train_one, tasks))
    workers_pool.close()
    workers_pool.join()  # reaped: their CPU is in RUSAGE_CHILDREN
    total = time.perf_counter() - start
    used = time.process_time() - parent + children_cpu() - children
    seconds = [r["seconds"] for r in results]
    return {"runs": len(results), "workers": workers, "run_dirs": tmp is not None,
            "cpu_seconds": used, "runs_per_minute_on_2_cores": len(results) / (used / 2) * 60,
            "wall_seconds": total, "runs_per_minute_wall": len(results) / total * 60,
            "mean_run_cpu_seconds": statistics.fmean(seconds),
            "max_run_cpu_seconds": max(seconds),
            "per_learner_mean_cpu_seconds": {
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


# -- 4. lock-step --------------------------------------------------------------------------
def lockstep(repeats: int) -> dict[str, Any]:
    """A controller's 20 validation episodes one at a time (``run_trial``) and in lock-step
    (one batched simulator, the same per-state inference for the episodes still running)."""
    behaviour = load_behaviour(HANDMADE)
    controller = compile_behaviour(behaviour)
    assert controller.consequents is not None
    consequents = controller.consequents.tolist()
    rules = SparseRules(controller)
    seeds = validation_seeds(0, 20)
    single = make_env(behaviour)
    batch = make_env(behaviour, len(seeds))
    alone: list[int] = []
    together = np.zeros(len(seeds), dtype=np.int64)

    def one_at_a_time() -> None:
        alone[:] = [run_trial(single, rules, int(seed), consequents).length for seed in seeds]

    def lock_step() -> None:
        observations, _ = batch.reset(seeds)
        actions = np.zeros(len(seeds))
        running = np.ones(len(seeds), dtype=bool)
        together[:] = 0
        while running.any():
            for b in np.flatnonzero(running).tolist():
                active, alphas, _ = rules.activations(observations[b].tolist())
                actions[b] = rules.output(alphas, [consequents[m] for m in active])
            together[:] += running
            out = batch.step(actions)
            observations, running = out.observations, ~(out.terminated | out.truncated)

    single_seconds = best_seconds(one_at_a_time, repeats)
    lock_seconds = best_seconds(lock_step, repeats)
    if alone != together.tolist():
        raise SystemExit("lock-step ran other episodes than one at a time")
    return {"episodes": len(seeds), "one_at_a_time_seconds": single_seconds,
            "lock_step_seconds": lock_seconds, "lock_step_over_one_at_a_time":
            lock_seconds / single_seconds, "mean_length": statistics.fmean(alone),
            "longest": max(alone)}


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
        lock = lockstep(args.repeats)

    print(f"1. ballchase, paper protocol (population 10, 30 generations, 1 trial = 300 "
          f"trials); CPU seconds, least of {args.repeats}")
    print(f"{'learner':8} {'steps':>6} {'loop s':>7} {'steps/s':>8} {'run dir s':>9} "
          f"{'bookkeeping':>11} {'command s':>9} {'- start-up':>10} {'heavy imports':>13}")
    for r in results:
        print(f"{r['learner']:8} {r['steps']:6d} {r['loop_seconds']:7.3f} "
              f"{r['steps_per_second']:8.0f} {r['run_dir_seconds']:9.3f} "
              f"{r['bookkeeping_share']:10.0%} {r['command_seconds']:9.3f} "
              f"{r['command_after_startup_seconds']:10.3f} "
              f"{r['command_imports']:>13}")
    print(f"start-up of the command: {start['startup_seconds']:.3f} s CPU = interpreter "
          f"{start['interpreter_seconds']:.3f} s + imports {start['import_seconds']:.3f} s")

    print(f"\n2. {args.seeds} seeds x {len(LEARNERS)} learners, pool of {args.workers} "
          f"spawned workers")
    print(f"{'run dirs':8} {'runs':>5} {'CPU s':>7} {'runs/min on 2 cores':>19} {'wall s':>7} "
          f"{'runs/min wall':>13}  mean CPU per learner")
    for p in pools:
        per = ", ".join(f"{k} {v:.3f}" for k, v in p["per_learner_mean_cpu_seconds"].items())
        print(f"{'yes' if p['run_dirs'] else 'no':8} {p['runs']:5d} {p['cpu_seconds']:7.2f} "
              f"{p['runs_per_minute_on_2_cores']:19.0f} {p['wall_seconds']:7.2f} "
              f"{p['runs_per_minute_wall']:13.0f}  {per}")

    print("\n3. peak resident memory")
    for m in peaks:
        print(f"{m['peak_rss_mb']:7.1f} MB  {m['command']}")

    print(f"\n4. {lock['episodes']} validation episodes of the hand-made ballchase controller:"
          f" one at a time {lock['one_at_a_time_seconds']:.4f} s CPU, in lock-step "
          f"{lock['lock_step_seconds']:.4f} s ({lock['lock_step_over_one_at_a_time']:.2f}x);"
          f" episodes of {lock['mean_length']:.1f} steps on average, the longest "
          f"{lock['longest']}")

    learn_mb = peaks[0]["peak_rss_mb"]
    bookkeeping = max(r["bookkeeping_share"] for r in results)
    command = max(r["command_seconds"] for r in results)
    per_minute = pools[1]["runs_per_minute_on_2_cores"]
    goals = {
        "bookkeeping_share": (bookkeeping, "<=", GOAL_BOOKKEEPING),
        "learn_command_cpu_seconds": (command, "<=", GOAL_COMMAND_SECONDS),
        "runs_per_minute_with_run_dirs_on_2_cores": (per_minute, ">=", GOAL_RUNS_PER_MINUTE),
        "learn_peak_mb": (learn_mb, "<=", GOAL_MEGABYTES),
    }
    print()
    met = {}
    for name, (value, sense, goal) in goals.items():
        met[name] = value >= goal if sense == ">=" else value <= goal
        print(f"goal {name}: {value:,.3f} {sense} {goal:g} (worst learner where per learner): "
              f"{'met' if met[name] else 'MISSED'}")
    write_json(args.json, {"machine": machine(), "repeats": args.repeats, "startup": start,
                           "timing": "CPU time, least of the repeats",
                           "protocol": results, "pool": pools, "memory": peaks, "lock_step": lock,
                           "goals": {name: {"value": value, "sense": sense, "goal": goal,
                                            "met": met[name]}
                                     for name, (value, sense, goal) in goals.items()}})
    print(f"wrote {args.json.name}")


if __name__ == "__main__":
    main()
