"""What learning measured on known tasks, so ``flctool show`` can say what similar problems
needed.

Every row copies a row of docs/learning.md's task suite table ("Measured"): training seeds
900-909, which took no part in any choice, each file learned with its own settings (the files
that give no budget size their own: ``learning.extend`` and two trials under the GAs), each
run's ``best.yaml`` on 1,000 held-out episodes in the pitch world or 100 on Gymnasium tasks.
A task's size is its rules to learn (M) and commands (K); its training episodes are the
median over the ten runs (a file without a budget: what its runs used; otherwise its
generations x population x trials).
Selection, confirmation and the comparison with baselines come on top (``flctool validate``
states them for a file). Change a row only with the measurement in docs/learning.md that it
copies.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class MeasuredTask:
    """One task as learned with its file's defaults, and what that gave."""

    name: str
    rules: int  # M: rules to learn
    commands: int  # K
    learner: str
    training: int  # training episodes a run used, median over the measured runs
    result: str  # held out over the seeds: median, worst, and the reference

    def line(self) -> str:
        return (f"{self.name}: {self.rules} rules x {self.commands} commands, {self.learner}, "
                f"{self.training:,} training episodes: {self.result}")


#: The training seeds of every row: docs/learning.md, "Measured".
SEEDS = "900-909"

#: docs/learning.md, "Measured" (see the module docstring), seeds :data:`SEEDS`.
MEASURED = (
    MeasuredTask("ballchase", 15, 5, "hybrid", 1200,
                 "success median 0.994, worst 0.970 (hand-made 1.000)"),
    MeasuredTask("face-goal", 5, 3, "hybrid", 1200,
                 "success median 1.000, worst 1.000 (hand-made 1.000)"),
    MeasuredTask("face-goal-fine", 7, 3, "hybrid", 1200,
                 "success median 1.000, worst 1.000 (hand-made 1.000)"),
    MeasuredTask("return-home", 15, 5, "hybrid", 790,
                 "success median 0.998, worst 0.974 (hand-made 1.000)"),
    MeasuredTask("return-home-fine", 21, 5, "hybrid", 950,
                 "success median 0.995, worst 0.984 (hand-made 1.000)"),
    MeasuredTask("dribble", 25, 5, "hybrid", 1200,
                 "success median 0.998, worst 0.972 (hand-made 0.920)"),
    MeasuredTask("defend", 15, 5, "hybrid", 1050,
                 "success median 1.000, worst 0.981 (hand-made 0.948)"),
    MeasuredTask("approach", 30, 5, "hybrid", 1640,
                 "success median 0.896, worst 0.815 (hand-made 0.893)"),
    MeasuredTask("avoid-obstacle", 40, 5, "hybrid", 1920,
                 "success median 0.992, worst 0.963 (hand-made 0.953)"),
    MeasuredTask("shoot", 54, 5, "credit", 15000,
                 "success median 0.363, worst 0.333 (hand-made 0.368)"),
    MeasuredTask("striker", 12, 2, "hybrid", 1200,
                 "success median 0.930, worst 0.914 (hand-made 0.936)"),
    MeasuredTask("cartpole", 81, 2, "fuzzy_q", 300,
                 "return median 500.0, worst 500.0; 10 of 10 seeds reach 475"),
    MeasuredTask("cartpole-vote", 81, 2, "hybrid", 1800,
                 "return median 499.9, worst 468.5; 9 of 10 seeds reach 475"),
    MeasuredTask("acrobot", 9, 3, "hybrid", 940,
                 "return median -90.5, worst -93.6; 10 of 10 seeds reach -100"),
    MeasuredTask("acrobot-fuzzy-q", 9, 3, "fuzzy_q", 300,
                 "return median -124.1, worst -433.6; 2 of 10 seeds reach -100"),
    MeasuredTask("mountaincar", 15, 3, "hybrid", 1000,
                 "return median -108.0, worst -118.3; 9 of 10 seeds reach -110"),
    MeasuredTask("pendulum", 45, 5, "fuzzy_q", 3000,
                 "return median -191.1, worst -197.7; 10 of 10 seeds reach -200"),
    # written after the defaults were fixed; nothing was tuned on them
    MeasuredTask("home-past-obstacle", 30, 5, "hybrid", 1800,
                 "success median 0.992, worst 0.984 (hand-made 0.718)"),
    MeasuredTask("intercept", 15, 5, "hybrid", 1200,
                 "success median 0.961, worst 0.936 (hand-made 0.942)"),
    MeasuredTask("dribble-past-obstacle", 54, 5, "hybrid", 2820,
                 "success median 0.439, worst 0.397 (hand-made 0.394)"),
    MeasuredTask("park", 15, 4, "hybrid", 680,
                 "success median 1.000, worst 0.939 (hand-made 1.000)"),
    MeasuredTask("mountaincar-continuous", 9, 3, "hybrid", 1140,
                 "return median 96.2, worst 93.9; 10 of 10 seeds reach 90"),
)


def similar_tasks(rules: int, commands: int, count: int = 3) -> list[MeasuredTask]:
    """The ``count`` measured tasks nearest in size to ``rules`` x ``commands``: nearest in
    log M, then log K (a task twice as large is as far as one half as large)."""
    def distance(task: MeasuredTask) -> tuple[float, float]:
        return (abs(math.log(max(rules, 1) / task.rules)),
                abs(math.log(max(commands, 1) / task.commands)))

    return sorted(MEASURED, key=distance)[:count]
