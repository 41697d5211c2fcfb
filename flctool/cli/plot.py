"""``flctool plot``: the paper's figures from an experiment, run directories or a trace."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape

from flctool.cli.app import app, console, user_errors
from flctool.errors import FlcError


@app.command()
def plot(
    sources: Annotated[list[Path], typer.Argument(
        exists=True, help="An experiment directory, run directories (learning curves; "
        "several are overlaid), or one trace CSV from 'flctool evaluate --trace'.")],
    out: Annotated[Path, typer.Option(
        "--out", "-o", help="Folder for the figures (default: the experiment or first run "
        "directory, or beside the trace).")] = Path(),
    rule: Annotated[int | None, typer.Option(
        help="Rule whose strengths to plot (0-based, last input fastest; default: the rule "
        "whose strengths moved most).")] = None,
) -> None:
    """Plot learning curves (paper Fig. 5-6), one rule's strengths over the trials (Fig. 7),
    the best controller's trajectory (Fig. 8), its fuzzy sets, rule table and control
    surface, as PNG and SVG files."""
    from flctool import plots
    from flctool.experiment import is_experiment
    from flctool.runs import open_run

    with user_errors():
        if len(sources) == 1 and sources[0].is_file():
            trace = sources[0]
            target = _folder(out, trace.parent) / f"{trace.stem}.png"
            _wrote(plots.plot_trajectory(plots.read_trace(trace), target,
                                         f"trajectory: {trace.name}"))
            return
        if any(s.is_file() for s in sources):
            raise FlcError("give run directories, or a single trace CSV",
                           hint="plot traces one at a time")
        if any(is_experiment(s) for s in sources):
            if len(sources) > 1:
                raise FlcError("give one experiment directory at a time",
                               hint="plot each experiment on its own")
            _plot_experiment(sources[0], out, rule)
            return
        runs = [open_run(s) for s in sources]
        # the checkpoints say whether the learner kept rule strengths (hybrid, fuzzy_q)
        strengths = len(runs) == 1 and "q" in (runs[0].last_checkpoint() or {})
        if rule is not None and not strengths:
            raise FlcError("--rule picks the rule of one run whose learner keeps strengths "
                           "(hybrid, fuzzy_q)", hint="plot that run on its own")
        folder = _folder(out, runs[0].path)
        _wrote(plots.plot_fitness(runs, folder / "fitness.png"))
        if strengths:
            plotted = plots.plot_strengths(runs[0], folder / "strengths.png", rule)
            _wrote([folder / "strengths.png", folder / "strengths.svg"], f" (rule {plotted})")
        if len(runs) == 1 and (runs[0].path / "best.yaml").is_file():
            _plot_best(runs[0].path / "best.yaml", folder, f"{runs[0].path.name} best.yaml")


def _plot_best(best: Path, folder: Path, title: str) -> None:
    from flctool import plots
    from flctool.rollout import evaluation_seeds
    from flctool.spec import load_behaviour

    # the first episode of 'flctool evaluate --episodes 1': never a training start
    seed = int(evaluation_seeds(0, 1)[0])
    _wrote(plots.plot_controller(load_behaviour(best), folder, seed, title))


def _plot_experiment(path: Path, out: Path, rule: int | None) -> None:
    from flctool import plots
    from flctool.experiment import open_experiment, read_summary
    from flctool.runs import open_run

    experiment = open_experiment(path)
    summary = read_summary(path)
    folder = _folder(out, path)
    _wrote(plots.plot_experiment_learning(summary, folder / "learning.png"))
    _wrote(plots.plot_heldout(summary, folder / "heldout.png"))
    # Fig. 7 from the first seed of a learner that keeps strengths (the hybrid first)
    keeping = [n for n in ("hybrid", "fuzzy_q") if n in experiment.plan.learners]
    if keeping:
        run = open_run(experiment.runs_dir / f"{keeping[0]}-seed0")
        plotted = plots.plot_strengths(run, folder / "strengths.png", rule)
        _wrote([folder / "strengths.png", folder / "strengths.svg"], f" (rule {plotted})")
    elif rule is not None:
        raise FlcError("--rule needs a learner that keeps strengths (hybrid, fuzzy_q)",
                       hint="leave out --rule")
    best = summary["best_run"]
    name = f"{best['learner']}-seed{best['seed']}"
    _plot_best(experiment.runs_dir / name / "best.yaml", folder,
               f"best controller ({name}, held-out success {best['success_rate']:.3f})")


def _wrote(paths: list[Path], note: str = "") -> None:
    for path in paths:
        console.print(f"wrote {escape(str(path))}{escape(note)}")


def _folder(out: Path, default: Path) -> Path:
    folder = default if out == Path() else out
    folder.mkdir(parents=True, exist_ok=True)
    return folder
