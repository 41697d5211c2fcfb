"""``flctool evaluate``: run a deployable controller for many episodes and summarise."""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.markup import escape
from rich.table import Table

from flctool.atomic import write_text_atomic
from flctool.cli.app import app, console, user_errors
from flctool.cli.locate import located_in
from flctool.compile import compile_behaviour
from flctool.envs import make_env
from flctool.errors import FlcError, Problem, SpecError
from flctool.rollout import Estimate, EvaluationResult, evaluate, evaluation_seeds, trace_episode
from flctool.spec import Behaviour, load_behaviour


def _deployable(behaviour: Behaviour, file: str) -> None:
    missing = behaviour.missing_rules()
    if missing:
        first = ", ".join(f"{name}={value}" for name, value
                          in zip(behaviour.input_names, missing[0], strict=True))
        raise SpecError([Problem(
            ("rules",), f"{len(missing)} of {behaviour.rule_count} rules are missing, so "
            f"this controller cannot run (first missing: {first})",
            "learn them (flctool learn) or complete the rule table", file=file)], file)


def _row(label: str, estimate: Estimate, percent: bool = False) -> tuple[str, str, str, str]:
    def fmt(x: float) -> str:
        if x != x:  # NaN: no samples, or no interval from a single one
            return "-"
        return f"{100 * x:.1f} %" if percent else f"{x:.3f}"
    interval = "-" if estimate.low != estimate.low else \
        f"[{fmt(estimate.low)}, {fmt(estimate.high)}]"
    return label, fmt(estimate.value), interval, str(estimate.n)


def _table(name: str, result: EvaluationResult) -> Table:
    table = Table(title=f"{name}: {result.episodes} episodes", title_justify="left")
    table.add_column("statistic")
    table.add_column("value", justify="right")
    table.add_column("95 % CI", justify="right")
    table.add_column("n", justify="right")
    table.add_row(*_row("success rate (Wilson)", result.success_rate, percent=True))
    table.add_row(*_row("steps to success", result.steps_to_success))
    table.add_row(*_row("mean fitness", result.mean_fitness))
    table.add_row(*_row("mean return", result.mean_return))
    return table


def _csv(rows: list[dict[str, Any]]) -> str:
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=list(rows[0]), lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    return buffer.getvalue()


@app.command("evaluate")
def evaluate_command(
    file: Annotated[Path, typer.Argument(exists=True, dir_okay=False, readable=True,
                                         help="A deployable behaviour file (all rules given).")],
    episodes: Annotated[int, typer.Option(min=1, help="Evaluation episodes, run in lock-step.")]
    = 1000,
    seed: Annotated[int, typer.Option(min=0, help="Seed of the episodes' seeds.")] = 0,
    json_output: Annotated[bool, typer.Option("--json", help="Print JSON for scripts.")] = False,
    trace: Annotated[Path | None, typer.Option(
        dir_okay=False, help="Write the first episode's trajectory to this CSV file.")] = None,
) -> None:
    """Run a controller in its environment: success rate, steps to success and fitness, each
    with a 95 % confidence interval."""
    with user_errors():
        behaviour = load_behaviour(file)
        _deployable(behaviour, str(file))
        controller = compile_behaviour(behaviour)
        seeds = evaluation_seeds(seed, episodes)
        with located_in(file):  # an adapter's complaint about the file, at its line
            env = make_env(behaviour, episodes)
        try:
            result = evaluate(controller, env, seeds)
        finally:
            env.close()
        if trace is not None:
            single = make_env(behaviour, 1)
            try:
                rows = trace_episode(controller, single, int(seeds[0]))
            finally:
                single.close()
            try:
                write_text_atomic(trace, _csv(rows))
            except OSError as error:
                raise FlcError(f"cannot write the trace {trace}: {error.strerror}",
                               hint="check the directory exists and is writable") from None
    if json_output:
        typer.echo(json.dumps({"behaviour": behaviour.name, "file": str(file), "seed": seed,
                               **result.summary()}, indent=2))
        return
    console.print(_table(behaviour.name, result))
    if trace is not None:
        console.print(f"trace of episode seed {int(seeds[0])} written to {escape(str(trace))}")
