"""What learning measured on known tasks, so ``flctool show`` can say what similar problems
needed.

Every row copies a row of docs/learning.md's "Measured" section, all on training seeds
100-109 with each file's defaults, each run's ``best.yaml`` on 1,000 held-out episodes in the
pitch world or 100 on Gymnasium tasks: ballchase, face-goal(-fine), return-home(-fine) and
dribble from the racing comparison on the task suite (with the race, the default now); the
others from the task suite table (``python benchmarks/task_suite.py``, measured before the
race) and Pendulum's paragraph. A task's size is its rules to learn (M) and commands (K);
its training episodes are its file's generations x population x trials. Selection,
confirmation and the comparison with baselines come on top (``flctool validate`` states them
for a file). Change a row only with the measurement in docs/learning.md that it copies.
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
    training: int  # training episodes a run (generations x population x trials)
    result: str  # held out over the seeds: median, worst, and the reference

    def line(self) -> str:
        return (f"{self.name}: {self.rules} rules x {self.commands} commands, {self.learner}, "
                f"{self.training:,} training episodes: {self.result}")


#: docs/learning.md, "Measured" (see the module docstring), seeds 100-109.
MEASURED = (
    MeasuredTask("ballchase", 15, 5, "hybrid", 300,
                 "success median 0.980, worst 0.922 (hand-made 1.000)"),
    MeasuredTask("face-goal", 5, 3, "hybrid", 300,
                 "success median 1.000, worst 0.907 (hand-made 1.000)"),
    MeasuredTask("face-goal-fine", 7, 3, "hybrid", 300,
                 "success median 1.000, worst 1.000 (hand-made 1.000)"),
    MeasuredTask("return-home", 15, 5, "hybrid", 500,
                 "success median 1.000, worst 0.968 (hand-made 1.000)"),
    MeasuredTask("return-home-fine", 21, 5, "hybrid", 500,
                 "success median 0.994, worst 0.865 (hand-made 1.000)"),
    MeasuredTask("dribble", 25, 5, "hybrid", 600,
                 "success median 0.981, worst 0.958 (hand-made 0.920)"),
    MeasuredTask("avoid-obstacle", 40, 5, "hybrid", 1500,
                 "success median 0.963, worst 0.828 (hand-made 0.953)"),
    MeasuredTask("cartpole", 81, 2, "fuzzy_q", 300,
                 "return median 500.0, worst 499.7; 10 of 10 seeds reach 475"),
    MeasuredTask("cartpole-vote", 81, 2, "hybrid", 300,
                 "return median 490.0, worst 393.7; 8 of 10 seeds reach 475"),
    MeasuredTask("acrobot", 9, 3, "hybrid", 300,
                 "return median -90.6, worst -111.3; 8 of 10 seeds reach -100"),
    MeasuredTask("acrobot-fuzzy-q", 9, 3, "fuzzy_q", 300,
                 "return median -122.6, worst -200.2; 2 of 10 seeds reach -100"),
    MeasuredTask("mountaincar", 15, 3, "hybrid", 1000,
                 "return median -108.0, worst -120.4; 9 of 10 seeds reach -110"),
    MeasuredTask("pendulum", 45, 5, "fuzzy_q", 3000,
                 "return median -184.7, worst -222.1; 8 of 10 seeds reach -200"),
)


def similar_tasks(rules: int, commands: int, count: int = 3) -> list[MeasuredTask]:
    """The ``count`` measured tasks nearest in size to ``rules`` x ``commands``: nearest in
    log M, then log K (a task twice as large is as far as one half as large)."""
    def distance(task: MeasuredTask) -> tuple[float, float]:
        return (abs(math.log(max(rules, 1) / task.rules)),
                abs(math.log(max(commands, 1) / task.commands)))

    return sorted(MEASURED, key=distance)[:count]
