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

# The figures are drawn into a staging folder inside their destination, then moved there
# together: an existing file is replaced only with --force (checked before any is moved), and
# an interrupted plot leaves no half-written figure. What to draw is flctool.plots' decision.
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
    from flctool import plots

    with user_errors():
        destination = out or plots.default_folder(sources)
        with _staging(destination, force) as stage:
            drawn = plots.plot_sources(sources, stage, rule)
            for paths, note in drawn:
                _written.extend((str(destination / path.name), note) for path in paths)
    for path, note in _written:
        say(f"wrote {path}{note}")


@contextmanager
def _staging(destination: Path, force: bool) -> Iterator[Path]:
    """Draw into a hidden folder inside ``destination``, then move every figure into it:
    all of them, or (when one exists and not ``force``) none."""
    make_parent(destination / "x", "figures")
    stage = destination / f".flctool-plot-{secrets.token_hex(4)}"
    stage.mkdir()
    _written.clear()
    try:
        yield stage
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
        shutil.rmtree(stage, ignore_errors=True)
