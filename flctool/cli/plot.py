"""``flctool plot``: the paper's figures from run directories or a trace."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from flctool.cli.app import Force, app, check_output, console, escape, example, user_errors
from flctool.errors import FlcError


@app.command(epilog=example("flctool plot runs/first",
                            "flctool plot runs/hybrid runs/pitt -o figures",
                            "flctool plot chase.csv --force"))
def plot(
    sources: Annotated[list[Path], typer.Argument(
        metavar="SOURCE...", help="Run directories (learning curves; several are overlaid), "
        "or one trace CSV from 'flctool evaluate --trace'.")],
    out: Annotated[Path | None, typer.Option(
        "--out", "-o", help="Folder for the PNG files, created if missing (default: the first "
        "run directory, or the trace's folder).")] = None,
    rule: Annotated[int | None, typer.Option(
        help="Rule whose strengths to plot (0-based, last input fastest; default: the rule "
        "whose strengths moved most).")] = None,
    force: Force = False,
) -> None:
    """Plot learning curves, a rule's strengths or a trajectory as PNG files.

    The paper's figures: learning curves (Fig. 5-6), one rule's strengths (Fig. 7), a
    trajectory (Fig. 8)."""
    with user_errors():
        from flctool import plots
        from flctool.runs import open_run

        for source in sources:
            if not source.exists():
                raise FlcError(f"{source}: no such file or directory",
                               hint="give run directories, or one trace CSV")
        if len(sources) == 1 and sources[0].is_file():
            trace = sources[0]
            target = (out or trace.parent) / f"{trace.stem}.png"
            check_output(target, "plot", force=force)
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
        folder = out or runs[0].path
        targets = [folder / "fitness.png", *([folder / "strengths.png"] if strengths else [])]
        for target in targets:  # refuse before drawing anything
            check_output(target, "plot", force=force)
        plots.plot_fitness(runs, targets[0])
        console.print(f"wrote {escape(str(targets[0]))}")
        if strengths:
            plotted = plots.plot_strengths(runs[0], targets[1], rule)
            console.print(f"wrote {escape(str(targets[1]))} (rule {plotted})")
