"""``flctool plot``: the paper's figures from run directories or a trace."""

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
        exists=True, help="Run directories (learning curves; several are overlaid), or one "
        "trace CSV from 'flctool evaluate --trace'.")],
    out: Annotated[Path, typer.Option(
        "--out", "-o", help="Folder for the PNG files (default: the first run directory, or "
        "beside the trace).")] = Path(),
    rule: Annotated[int | None, typer.Option(
        help="Rule whose strengths to plot (0-based, last input fastest; default: the rule "
        "whose strengths moved most).")] = None,
) -> None:
    """Plot learning curves (paper Fig. 5-6), one rule's strengths (Fig. 7) or a trajectory
    (Fig. 8) as PNG files."""
    from flctool import plots
    from flctool.runs import open_run

    with user_errors():
        if len(sources) == 1 and sources[0].is_file():
            trace = sources[0]
            target = _folder(out, trace.parent) / f"{trace.stem}.png"
            plots.plot_trajectory(plots.read_trace(trace), target, f"trajectory: {trace.name}")
            console.print(f"wrote {escape(str(target))}")
            return
        if any(s.is_file() for s in sources):
            raise FlcError("give run directories, or a single trace CSV",
                           hint="plot traces one at a time")
        runs = [open_run(s) for s in sources]
        # the checkpoints say whether the learner kept rule strengths (hybrid, fuzzy_q)
        strengths = len(runs) == 1 and "q" in (runs[0].last_checkpoint() or {})
        if rule is not None and not strengths:
            raise FlcError("--rule picks the rule of one run whose learner keeps strengths "
                           "(hybrid, fuzzy_q)", hint="plot that run on its own")
        folder = _folder(out, runs[0].path)
        plots.plot_fitness(runs, folder / "fitness.png")
        console.print(f"wrote {escape(str(folder / 'fitness.png'))}")
        if strengths:
            plotted = plots.plot_strengths(runs[0], folder / "strengths.png", rule)
            console.print(f"wrote {escape(str(folder / 'strengths.png'))} (rule {plotted})")


def _folder(out: Path, default: Path) -> Path:
    folder = default if out == Path() else out
    folder.mkdir(parents=True, exist_ok=True)
    return folder
