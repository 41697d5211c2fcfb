"""``validate``, ``show``, ``infer`` and ``schema``: behaviour files and plain inference."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape
from rich.table import Table

from flctool.cli.app import (
    app,
    console,
    debug_enabled,
    err_console,
    print_error,
    read_user_file,
    user_errors,
    write_user_file,
)
from flctool.compile import compile_behaviour
from flctool.envs.preflight import validate_file
from flctool.errors import FlcError
from flctool.spec import Behaviour, load_behaviour
from flctool.spec.schema import behaviour_schema_text
from flctool.tabular import read_states, write_table

ExistingFile = Annotated[Path, typer.Argument(exists=True, dir_okay=False, readable=True,
                                              help="A behaviour file (YAML).")]
DEFAULT_SCHEMA = Path("schemas/behaviour.schema.json")


@app.command()
def validate(
    files: Annotated[list[Path], typer.Argument(exists=True, dir_okay=False, readable=True,
                                                help="Behaviour files to check.")],
) -> None:
    """Check behaviour files and report every problem in each (exit 1 if any is invalid)."""
    failed = 0
    for path in files:
        try:
            report = validate_file(path)
        except FlcError as error:
            failed += 1
            print_error(error)
            continue
        except Exception as error:  # a bug on one file must not stop the check of the others
            if debug_enabled():
                raise
            failed += 1
            print_error(FlcError(f"{path}: internal error while checking it: "
                                 f"{type(error).__name__}: {error}",
                                 hint="run with --debug for the traceback, and report it"))
            continue
        behaviour = report.behaviour
        for warning in report.warnings:
            err_console.print(f"[yellow]warning:[/] {escape(str(warning))}", highlight=False)
        if report.adapter_note:
            console.print(f"[yellow]note:[/] {escape(str(path))}: {escape(report.adapter_note)}")
        state = ("deployable" if behaviour.is_deployable
                 else f"{len(behaviour.missing_rules())} of {behaviour.rule_count} rules to learn")
        console.print(f"[green]ok[/] {escape(str(path))}: {behaviour.name} ({state})")
    if failed:
        raise typer.Exit(1)


@app.command()
def show(file: ExistingFile) -> None:
    """Show a behaviour: its inputs and sets, M and K, and the rule table."""
    with user_errors():
        behaviour = load_behaviour(file)
    console.print(f"[bold]{escape(behaviour.name)}[/]  {escape(behaviour.description)}")
    sets = Table(title="inputs", title_justify="left")
    for column in ("input", "range", "set", "pa", "pb", "pc", "pd"):
        sets.add_column(column, justify="right" if column.startswith("p") else "left")
    for name, variable in behaviour.inputs.items():
        unit = f" {variable.unit}" if variable.unit else ""
        span = f"[{variable.range[0]:g}, {variable.range[1]:g}]{unit}"
        for i, (set_name, quad) in enumerate(variable.sets.items()):
            sets.add_row(name if i == 0 else "", span if i == 0 else "", set_name,
                         *(f"{v:g}" for v in quad), end_section=i == len(variable.sets) - 1)
    console.print(sets)
    commands = Table(title=f"output '{behaviour.output.name}'", title_justify="left")
    commands.add_column("command")
    commands.add_column("singleton", justify="right")
    for command, value in behaviour.output.commands.items():
        commands.add_row(command, f"{value:g}")
    console.print(commands)
    m, k = behaviour.rule_count, len(behaviour.output.commands)
    missing = len(behaviour.missing_rules())
    console.print(f"N = {len(behaviour.inputs)} inputs, M = {m} rules, K = {k} commands; "
                  + ("deployable (all rules given)" if not missing else
                     f"{missing} rules still to learn"))
    if len(behaviour.inputs) == 2 and behaviour.rules:
        console.print(_rule_grid(behaviour))
    elif behaviour.rules:
        console.print(_rule_list(behaviour))


def _rule_list(behaviour: Behaviour) -> Table:
    table = Table(title="rules, in rule order (last input varies fastest)",
                  title_justify="left")
    table.add_column("m", justify="right")
    for name in behaviour.input_names:
        table.add_column(name)
    table.add_column("then")
    then = {tuple(r.if_[n] for n in behaviour.input_names): r.then for r in behaviour.rules}
    for m, antecedent in enumerate(behaviour.antecedents()):
        table.add_row(str(m), *antecedent, then.get(antecedent, "[dim]?[/]"))
    return table


def _rule_grid(behaviour: Behaviour) -> Table:
    first, second = behaviour.input_names
    table = Table(title=f"rules: rows {first}, columns {second}", title_justify="left")
    table.add_column(f"{first} \\ {second}")
    for set_name in behaviour.inputs[second].sets:
        table.add_column(set_name, justify="center")
    then = {(r.if_[first], r.if_[second]): r.then for r in behaviour.rules}
    for row in behaviour.inputs[first].sets:
        table.add_row(row, *(then.get((row, col), "[dim]?[/]")
                             for col in behaviour.inputs[second].sets))
    return table


@app.command()
def infer(
    file: ExistingFile,
    input: Annotated[str, typer.Option(
        "--input", "-i", help="CSV of states with a header naming the inputs; - for stdin.")]
    = "-",
    output: Annotated[Path | None, typer.Option(
        "--output", "-o", help="Where to write the CSV (default: stdout).")] = None,
) -> None:
    """Run a deployable controller on states from CSV; adds the output column."""
    with user_errors():
        behaviour = load_behaviour(file)
        controller = compile_behaviour(behaviour)
        if input == "-":
            text, source = sys.stdin.read(), "<stdin>"
        else:
            text, source = read_user_file(Path(input), "states CSV"), input
        header, rows, states = read_states(text, controller.input_names, source)
        values = controller.output(states)
        result = write_table([*header, controller.output_name],
                             [[*row, repr(float(v))] for row, v in zip(rows, values, strict=True)])
        if output is None:
            sys.stdout.write(result)
        else:
            write_user_file(output, result, "output CSV")


@app.command()
def schema(
    check: Annotated[bool, typer.Option(
        "--check", help="Fail (exit 1) if the file differs from the models.")] = False,
    path: Annotated[Path, typer.Option(help="The schema file.")] = DEFAULT_SCHEMA,
) -> None:
    """Write the behaviour JSON Schema generated from the models (or check it is current)."""
    text = behaviour_schema_text()
    with user_errors():
        if check:
            current = read_user_file(path, "schema") if path.is_file() else None
            if current != text:
                raise FlcError(f"{path} is {'missing' if current is None else 'stale'}",
                               hint="run 'flctool schema' and commit the result")
            console.print(f"[green]ok[/] {escape(str(path))} is up to date")
            return
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
        except OSError as error:
            raise FlcError(f"cannot create the folder {path.parent}: {error.strerror}") from None
        write_user_file(path, text, "schema")
    console.print(f"wrote {escape(str(path))}")
