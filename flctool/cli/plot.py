"""``flctool plot``: the paper's figures from an experiment, run directories or a trace."""

from __future__ import annotations

import os
import secrets
import shutil
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Annotated

import typer

from flctool.cli.app import Force, app, example, make_parent, say, user_errors
from flctool.errors import FlcError

# The figures are drawn into a staging folder beside their destination, then moved there
# together: an existing file is replaced only with --force (checked before any is moved), and
# an interrupted plot leaves no half-written figure.
_staged: dict[str, Path | None] = {"stage": None}
_written: list[tuple[str, str]] = []


@app.command(epilog=example("flctool plot runs/first",
                            "flctool plot runs/hybrid runs/pitt -o figures",
                            "flctool plot experiments/ballchase --force",
                            "flctool plot chase.csv"))
def plot(
    sources: Annotated[list[Path], typer.Argument(
        metavar="SOURCE...", help="An experiment directory, run directories (learning "
        "curves; several are overlaid), or one trace CSV from 'flctool evaluate --trace'.")],
    out: Annotated[Path | None, typer.Option(
        "--out", "-o", help="Folder for the figures, created if missing (default: the "
        "experiment or first run directory, or the trace's folder).")] = None,
    rule: Annotated[int | None, typer.Option(
        help="Rule whose strengths to plot (0-based, last input fastest; default: the rule "
        "whose strengths moved most).")] = None,
    force: Force = False,
) -> None:
    """Plot learning curves, strengths, a trajectory and the controller as PNG and SVG files.

    The paper's figures: learning curves (Fig. 5-6), one rule's strengths over the trials
    (Fig. 7), the best controller's trajectory (Fig. 8); and the controller's fuzzy sets,
    rule table and control surface."""
    with user_errors():
        for source in sources:
            if not source.exists():
                raise FlcError(f"{source}: no such file or directory",
                               hint="give an experiment, run directories, or one trace CSV")
        destination = out or (sources[0].parent if sources[0].is_file() else sources[0])
        with _staging(destination, force):
            _plot(sources, out, rule)
    for path, note in _written:
        say(f"wrote {path}{note}")


def _plot(sources: list[Path], out: Path | None, rule: int | None) -> None:
    from flctool import plots
    from flctool.experiment import is_experiment
    from flctool.runs import open_run

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


def _plot_experiment(path: Path, out: Path | None, rule: int | None) -> None:
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
    stage = _staged["stage"]
    for path in paths:
        final = path if stage is None or path.parent != stage else stage.parent / path.name
        _written.append((str(final), note))


def _folder(out: Path | None, default: Path) -> Path:
    """Where the figures for ``out`` (else ``default``) are drawn: the staging folder."""
    del out, default  # the destination was decided when the staging folder was made
    stage = _staged["stage"]
    if stage is None:
        raise FlcError("internal error: figures drawn outside a staging folder")
    return stage


@contextmanager
def _staging(destination: Path, force: bool) -> Iterator[None]:
    """Draw into a hidden folder inside ``destination``, then move every figure into it:
    all of them, or (when one exists and not ``force``) none."""
    make_parent(destination / "x", "figures")
    stage = destination / f".flctool-plot-{secrets.token_hex(4)}"
    stage.mkdir()
    _staged["stage"] = stage
    _written.clear()
    try:
        yield
        drawn = sorted(stage.iterdir())
        existing = [destination / p.name for p in drawn if (destination / p.name).exists()]
        if existing and not force:
            _written.clear()
            names = ", ".join(str(p) for p in existing[:3])
            more = f" and {len(existing) - 3} more" if len(existing) > 3 else ""
            raise FlcError(f"the figure(s) {names}{more} already exist",
                           hint="pass --force to replace them, or choose another --out")
        for path in drawn:
            os.replace(path, destination / path.name)
    finally:
        _staged["stage"] = None
        shutil.rmtree(stage, ignore_errors=True)
