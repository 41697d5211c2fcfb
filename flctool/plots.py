"""Figures of a run, as in the paper: learning curves (Fig. 5-6, 9-10), the strengths of one
rule over time (Fig. 7) and a chase's trajectory (Fig. 8, 11).

matplotlib is an optional extra (``pip install 'flctool[plot]'``); it is imported only here,
with the Agg backend, so plotting works on a robot's headless computer too.
"""

from __future__ import annotations

import csv
import io
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from flctool.atomic import write_bytes_atomic
from flctool.errors import MissingDependencyError, Problem, RunDirError, SpecError
from flctool.runs import Run

FloatArray = NDArray[np.float64]


def _pyplot() -> Any:
    try:
        import matplotlib
    except ImportError:
        raise MissingDependencyError("matplotlib", "plot", "Plotting") from None
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _save(figure: Any, path: Path) -> None:
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=120, bbox_inches="tight")
    _pyplot().close(figure)
    write_bytes_atomic(path, buffer.getvalue())


def _label(run: Run) -> str:
    return f"{run.path.name} ({run.learner}, seed {run.seed})"


def plot_fitness(runs: Sequence[Run], path: Path) -> None:
    """Mean fitness per generation with a +-1 std band and the best individual (dashed), one
    colour per run: the paper's Fig. 5-6 (and a comparison when several runs are given)."""
    plt = _pyplot()
    figure, axes = plt.subplots(figsize=(7, 4))
    for run in runs:
        metrics = run.metrics()
        if not metrics:
            raise RunDirError(f"{run.path}: the run has no finished generation to plot",
                              hint="let it run at least one generation")
        generation = np.array([m.generation for m in metrics])
        mean = np.array([m.mean for m in metrics])
        std = np.array([m.std for m in metrics])
        line = axes.plot(generation, mean, label=f"{_label(run)}: mean")[0]
        axes.fill_between(generation, mean - std, mean + std, color=line.get_color(), alpha=0.2)
        axes.plot(generation, [m.best for m in metrics], "--", color=line.get_color(),
                  label=f"{_label(run)}: best")
    axes.set_xlabel("generation")
    axes.set_ylabel("fitness")
    axes.set_title(f"{runs[0].behaviour.name}: fitness per generation (band: ±1 std)")
    axes.legend(fontsize="small")
    axes.grid(alpha=0.3)
    _save(figure, path)


def strength_history(run: Run) -> tuple[NDArray[np.int64], FloatArray]:
    """The q table after each recorded generation: generations (G,) and q (G, M, K)."""
    generations = run.checkpoint_generations()
    tables = [run.checkpoint(g).get("q") for g in generations]
    if not generations or any(t is None for t in tables):
        raise RunDirError(f"{run.path}: the {run.learner} learner keeps no rule strengths",
                          hint="strengths are learned by the hybrid and fuzzy_q learners")
    return np.array(generations), np.array(tables, dtype=np.float64)


def most_contested_rule(q: FloatArray) -> int:
    """The rule whose strengths moved most over the run (largest summed variance over time):
    a sensible default for the paper's Fig. 7."""
    return int(np.argmax(q.var(axis=0).sum(axis=1)))


def plot_strengths(run: Run, path: Path, rule: int | None = None) -> int:
    """The strength q_m^k of every command k of one rule m over the generations (Fig. 7).

    ``rule`` is 0-based in the documented rule order; by default the most contested rule.
    Returns the rule plotted.
    """
    generations, q = strength_history(run)
    rule = most_contested_rule(q) if rule is None else rule
    if not 0 <= rule < q.shape[1]:
        raise RunDirError(f"rule {rule} does not exist: the behaviour has rules "
                          f"0..{q.shape[1] - 1}",
                          hint="rules are numbered from 0, last input varying fastest")
    behaviour = run.behaviour
    antecedent = " AND ".join(f"{name} is {set_name}" for name, set_name
                              in zip(behaviour.input_names, behaviour.antecedents()[rule],
                                     strict=True))
    plt = _pyplot()
    figure, axes = plt.subplots(figsize=(7, 4))
    for k, command in enumerate(behaviour.output.commands):
        axes.plot(generations, q[:, rule, k], marker=".", label=command)
    axes.set_xlabel("generation")
    axes.set_ylabel("strength q")
    axes.set_title(f"rule {rule}: IF {antecedent}", fontsize="medium")
    axes.legend(fontsize="small")
    axes.grid(alpha=0.3)
    _save(figure, path)
    return rule


def read_trace(path: Path) -> dict[str, FloatArray]:
    """The numeric columns of a trace CSV written by ``flctool evaluate --trace``."""
    try:
        with path.open(encoding="utf-8", newline="") as handle:
            rows = list(csv.DictReader(handle))
    except OSError as exc:
        raise SpecError([Problem((), f"cannot read the trace: {exc.strerror}", file=str(path))],
                        str(path)) from None
    needed = ("robot_x", "robot_y", "ball_x", "ball_y")
    missing = [c for c in needed if not rows or c not in rows[0]]
    if missing:
        raise SpecError([Problem((), f"not a ballchase trace: no column(s) {', '.join(missing)}",
                                 "write one with flctool evaluate FILE --trace trace.csv",
                                 file=str(path), line=1)], str(path))
    try:
        return {c: np.array([float(row[c]) for row in rows]) for c in needed}
    except ValueError as exc:
        raise SpecError([Problem((), f"a position is not a number ({exc})", file=str(path))],
                        str(path)) from None


def plot_trajectory(trace: dict[str, FloatArray], path: Path, title: str) -> None:
    """The robot's path to the ball, seen from above (the paper's Fig. 8)."""
    plt = _pyplot()
    figure, axes = plt.subplots(figsize=(6, 5))
    axes.plot(trace["robot_x"], trace["robot_y"], "-", marker=".", markersize=3,
              label="robot")
    axes.plot(trace["robot_x"][:1], trace["robot_y"][:1], "s", color="black", label="start")
    axes.plot(trace["ball_x"][-1:], trace["ball_y"][-1:], "o", color="tab:orange",
              markersize=10, label="ball")
    axes.set_aspect("equal", adjustable="datalim")
    axes.set_xlabel("x (mm)")
    axes.set_ylabel("y (mm)")
    axes.set_title(title)
    axes.legend(fontsize="small")
    axes.grid(alpha=0.3)
    _save(figure, path)
