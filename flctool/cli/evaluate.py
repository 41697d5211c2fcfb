"""``flctool evaluate``: run a deployable controller for many episodes and show the summary
that :mod:`flctool.evaluation` makes."""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from flctool.cli.app import (
    Force,
    app,
    check_output,
    console,
    err_console,
    escape,
    example,
    load_controller,
    usage_error,
    user_errors,
    write_output,
)
from flctool.cli.behaviour_commands import ControllerArgument
from flctool.cli.progress import Progress, compiling

if TYPE_CHECKING:
    from rich.table import Table

    from flctool.evaluation import Evaluation


def _table(evaluation: Evaluation) -> Table:
    from rich.table import Table

    table = Table(title=f"{evaluation.behaviour.name}: {evaluation.result.episodes} episodes",
                  title_justify="left")
    table.add_column("statistic")
    table.add_column("value", justify="right")
    table.add_column("95 % CI", justify="right")
    table.add_column("n", justify="right")
    for row in evaluation.rows():
        table.add_row(*row)
    return table


def _csv(rows: list[dict[str, Any]]) -> str:
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=list(rows[0]), lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    return buffer.getvalue()


@app.command("evaluate", epilog=example(
    "flctool evaluate runs/first",
    "flctool evaluate behaviours/ballchase-handmade.yaml --seed 3 --episodes 200 --json",
    "flctool evaluate runs/first --seeds 1,2,5-9 --trace first.csv"))
def evaluate_command(
    file: ControllerArgument,
    episodes: Annotated[int | None, typer.Option(
        min=1, help="Evaluation episodes (default 1000), their seeds drawn from --seed.")]
    = None,
    seed: Annotated[int | None, typer.Option(
        min=0, help="Draws the episodes' seeds (default 0): --episodes distinct seeds in "
        "[0, 2^31 - 1), never those of training (docs/cli.md).")] = None,
    seeds: Annotated[str | None, typer.Option(
        "--seeds", metavar="LIST", help="The episodes' own seeds instead, e.g. 1,2,5-9 "
        "(one episode each).")] = None,
    json_output: Annotated[bool, typer.Option("--json", help="Print JSON for scripts.")] = False,
    trace: Annotated[Path | None, typer.Option(
        help="Write the first episode's trajectory to this CSV file.")] = None,
    force: Force = False,
) -> None:
    """Run a controller in its environment: success rate, steps to success and fitness, each
    with a 95 % confidence interval. Success lines appear only when the environment defines
    success."""
    from flctool.compile import compile_behaviour
    from flctool.compile import controller as controller_module
    from flctool.envs import make_env
    from flctool.evaluation import (
        DEFAULT_EPISODES,
        batch_size,
        defines_success,
        evaluate_behaviour,
        parse_seeds,
    )
    from flctool.rollout import EVALUATION_SEED_HIGH, trace_episode

    listed: list[int] | None = None
    if seeds is not None:
        if episodes is not None or seed is not None:
            raise usage_error("give either --seeds, or --seed and --episodes")
        try:
            listed = parse_seeds(seeds)
        except ValueError as error:
            raise usage_error(str(error), "--seeds") from None
    with user_errors():
        behaviour, source = load_controller(file)
        if trace is not None:
            check_output(trace, "trace", force=force)
        controller = compile_behaviour(behaviour)
        if listed is not None and max(listed) >= EVALUATION_SEED_HIGH:
            err_console.print(f"[yellow]warning:[/] seeds from {EVALUATION_SEED_HIGH} up are "
                              "the ranges learning uses (confirmation, training, selection); "
                              "these are not held out",
                              highlight=False)
        # Inference starts in numpy; if the work grows enough to pay for the compiled kernels,
        # loading them (compiling, on a machine's first run) is announced.
        controller_module.kernel_loading = compiling
        total = len(listed) if listed is not None else (episodes or DEFAULT_EPISODES)
        success = defines_success(behaviour)
        # The environment first: its errors come before the progress bar.
        with (make_env(behaviour, batch_size(total)) as env,
              Progress("episodes", total, terminal=not json_output) as progress):

            def chunk_done(done: int, successes: int) -> None:
                if success:
                    progress.update(done, success=f"{100 * successes / done:.1f} %")
                else:
                    progress.update(done)

            evaluation = evaluate_behaviour(behaviour, listed, seed=seed, episodes=episodes,
                                            controller=controller, env=env,
                                            on_chunk=chunk_done)
        first_seed = int(evaluation.result.seeds[0])
        if trace is not None:
            with make_env(behaviour, 1) as single:
                rows = trace_episode(controller, single, first_seed)
            write_output(trace, _csv(rows), "trace", force=force)
    if json_output:
        typer.echo(json.dumps(evaluation.to_dict(str(source)), indent=2))
        return
    console.print(_table(evaluation))
    if trace is not None:
        console.print(f"trace of episode seed {first_seed} written to {escape(str(trace))}")
