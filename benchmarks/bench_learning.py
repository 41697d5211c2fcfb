"""How long learning takes: the paper's protocol on ballchase, per learner.

    python benchmarks/bench_learning.py [--repeats 5] [--json FILE]

Three figures per learner (population 10, 30 generations, one trial each = 300 trials of up
to 200 steps): the training loop alone (``flctool.learners.train``), training into a run
directory (checkpoints, metrics, best.yaml: ``Run.train``), and the whole command
``python -m flctool learn behaviours/ballchase.yaml`` including interpreter start-up. Best
of ``--repeats`` runs each. A script, never a timed test.
"""

from __future__ import annotations

import argparse
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
LEARNERS = ("pitt", "hybrid", "fuzzy_q")


def measure(learner: str, repeats: int) -> dict[str, Any]:
    behaviour = resolve_behaviour(load_behaviour(BALLCHASE), {"learner": learner})
    steps = 0

    def loop_only() -> None:
        nonlocal steps
        steps = sum(m.steps for m in train(make_learner(behaviour)))

    loop = best_seconds(loop_only, repeats)
    with tempfile.TemporaryDirectory() as tmp:
        runs = iter(range(repeats))
        recorded = best_seconds(
            lambda: create_run(behaviour, Path(tmp) / f"run{next(runs)}").train(), repeats)
        command = float("inf")
        for i in range(repeats):
            start = time.perf_counter()
            subprocess.run([sys.executable, "-m", "flctool", "learn", str(BALLCHASE),
                            "--learner", learner, "--out", str(Path(tmp) / f"cli{i}"),
                            "--json"], check=True, stdout=subprocess.DEVNULL, cwd=tmp)
            command = min(command, time.perf_counter() - start)
    return {"learner": learner, "steps": steps, "loop_seconds": loop,
            "steps_per_second": steps / loop, "run_dir_seconds": recorded,
            "command_seconds": command}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--json", type=Path, default=None)
    args = parser.parse_args()
    results = [measure(learner, args.repeats) for learner in LEARNERS]
    print("ballchase, paper protocol (300 trials); best of", args.repeats)
    print(f"{'learner':8} {'steps':>6} {'loop s':>7} {'steps/s':>8} {'run dir s':>9} "
          f"{'command s':>9}")
    for r in results:
        print(f"{r['learner']:8} {r['steps']:6d} {r['loop_seconds']:7.3f} "
              f"{r['steps_per_second']:8.0f} {r['run_dir_seconds']:9.3f} "
              f"{r['command_seconds']:9.3f}")
    if args.json is not None:
        write_json(args.json, {"machine": machine(), "results": results})


if __name__ == "__main__":
    main()
