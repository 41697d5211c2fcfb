"""``validate``, ``show`` and ``schema``: behaviour files and their JSON Schema."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from flctool.cli.app import (
    Force,
    app,
    console,
    controller_file,
    debug_enabled,
    escape,
    example,
    print_error,
    read_user_file,
    say,
    user_errors,
    write_output,
)
from flctool.errors import FlcError, Problem, SpecError, format_path

if TYPE_CHECKING:
    from rich.table import Table

    from flctool.behaviour import Behaviour
    from flctool.envs.preflight import FileReport

ControllerArgument = Annotated[Path, typer.Argument(
    metavar="CONTROLLER", help="A behaviour file (YAML), or a run directory (its best.yaml).")]
DEFAULT_SCHEMA = Path("schemas/behaviour.schema.json")


@app.command(epilog=example("flctool validate behaviours/*.yaml",
                            "flctool validate behaviours/*.yaml --json | jq '.files[].problems'"))
def validate(
    files: Annotated[list[Path], typer.Argument(
        metavar="FILE...", help="Behaviour files to check (a run directory: its best.yaml).")],
    as_json: Annotated[bool, typer.Option(
        "--json", help="Print every file's problems as JSON on stdout (docs/cli.md has the "
        "schema), for editors and CI.")] = False,
) -> None:
    """Check behaviour files and report every problem in each (exit 1 if any is invalid).

    Runs the environment adapter's checks too, when the adapter can be built here."""
    checked = [_check(path) for path in files]
    results = [result for result, _ in checked]
    if as_json:
        print(json.dumps({"format": VALIDATE_FORMAT,
                          "valid": all(r["valid"] for r in results), "files": results},
                         indent=2))
    else:
        for result, error in checked:
            _say(result, error)
    if not all(r["valid"] for r in results):
        raise typer.Exit(1)


#: The version of ``validate --json``'s output (docs/cli.md); raised when a field changes.
VALIDATE_FORMAT = 1


def _check(path: Path) -> tuple[dict[str, Any], FlcError | None]:
    """One file's result as data (valid or not, its problems, warnings and notes), and the
    error that made it invalid."""
    result: dict[str, Any] = {"file": str(path), "valid": False, "behaviour": None,
                              "deployable": None, "rules": None, "rules_to_learn": None,
                              "budget": None, "problems": [], "warnings": [], "notes": []}
    try:
        report = validate_file(controller_file(path))
    except FlcError as error:
        result["problems"] = [_problem(p) for p in error.problems] if isinstance(
            error, SpecError) else [{"file": str(path), "line": None, "column": None,
                                     "field": None, "message": str(error.args[0]),
                                     "fix": error.hint or None}]
        return result, error
    except Exception as error:  # a bug on one file must not stop the check of the others
        if debug_enabled():
            raise
        internal = FlcError(f"{path}: internal error while checking it: "
                            f"{type(error).__name__}: {error}",
                            hint="run with --debug for the traceback, and report it")
        result["problems"] = [{"file": str(path), "line": None, "column": None,
                               "field": None, "message": str(internal.args[0]),
                               "fix": internal.hint}]
        return result, internal
    behaviour = report.behaviour
    result.update(valid=True, behaviour=behaviour.name, deployable=behaviour.is_deployable,
                  rules=behaviour.rule_count, rules_to_learn=len(behaviour.missing_rules()),
                  budget=None if behaviour.is_deployable else _budget(behaviour),
                  warnings=[_problem(w) for w in report.warnings],
                  notes=[report.adapter_note] if report.adapter_note else [])
    return result, None


def _budget(behaviour: Behaviour) -> dict[str, Any]:
    """What learning the file would spend, and why (``validate --json``'s ``budget``)."""
    from flctool.learners.budget import plan_budget

    plan = plan_budget(behaviour)
    return {"most_episodes": plan.most, "training_episodes": plan.training,
            "selection_episodes_at_most": plan.selection,
            "confirmation_episodes": plan.confirmation,
            "baseline_episodes": plan.baselines, "statement": plan.lines(),
            "extend": None if plan.extension is None else {
                "most_generations": plan.extension[0], "patience": plan.extension[1]},
            "settings": {key: {"value": s.value, "from": s.source}
                         for key, s in plan.settings.items()}}


def _problem(problem: Problem) -> dict[str, Any]:
    """A located problem as ``validate --json`` gives it."""
    return {"file": problem.file, "line": problem.line, "column": problem.column,
            "field": format_path(problem.path) if problem.path else None,
            "message": problem.message, "fix": problem.hint or None}


def _say(result: dict[str, Any], error: FlcError | None) -> None:
    """One file's result as lines for a person (stderr for errors and warnings)."""
    if error is not None:
        print_error(error)
        return
    for warning in result["warnings"]:
        where = ":".join(str(result_part) for result_part in (
            warning["file"], warning["line"], warning["column"]) if result_part is not None)
        fix = f" (fix: {warning['fix']})" if warning["fix"] else ""
        say(f"{where}: {warning['field'] or '(top level)'}: {warning['message']}{fix}",
            "warning:", "yellow", err=True)
    for note in result["notes"]:
        say(f"{result['file']}: {note}", "note:", "yellow")
    state = ("deployable" if result["deployable"]
             else f"{result['rules_to_learn']} of {result['rules']} rules to learn")
    say(f"{result['file']}: {result['behaviour']} ({state})", "ok")
    if result["budget"] is not None:
        console.print(escape("\n".join(result["budget"]["statement"])), highlight=False)


def validate_file(path: Path) -> FileReport:
    """:func:`flctool.envs.preflight.validate_file`, imported when a file is checked."""
    from flctool.envs.preflight import validate_file as check

    return check(path)


@app.command(epilog=example("flctool show behaviours/ballchase-handmade.yaml",
                            "flctool show runs/first",
                            "flctool show runs/first --compare behaviours/pendulum.yaml"))
def show(
    file: ControllerArgument,
    compare: Annotated[Path | None, typer.Option(
        "--compare", metavar="FILE", help=(
            "List how far each set moved from this behaviour's (e.g. the file a run learned "
            "the sets of), with the partitions' coverage and neighbour overlap."))] = None,
) -> None:
    """Show a behaviour: its inputs and sets, M and K, and the rule table."""
    from rich.table import Table

    from flctool.behaviour import load_behaviour
    from flctool.behaviour.shapes import is_trapezoid

    with user_errors():
        shown = controller_file(file)
        behaviour = load_behaviour(shown)
        if compare is not None:
            _refuse_comparing_with_itself(file, shown, compare)
        reference = None if compare is None else load_behaviour(controller_file(compare))
        if reference is not None:
            console.print(_set_movements(reference, behaviour, compare or Path()))
            return
    console.print(f"[bold]{escape(behaviour.name)}[/]  {escape(behaviour.description)}")
    sets = Table(title="inputs", title_justify="left")
    for column in ("input", "range", "set", "pa", "pb", "pc", "pd"):
        sets.add_column(column, justify="right" if column.startswith("p") else "left")
    for name, variable in behaviour.inputs.items():
        unit = f" {variable.unit}" if variable.unit else ""
        span = f"[{variable.range[0]:g}, {variable.range[1]:g}]{unit}"
        for i, (set_name, quad) in enumerate(variable.sets.items()):
            # a set of another shape: its name, then its parameters (flctool.behaviour.shapes)
            cells = ([f"{v:g}" for v in quad] if is_trapezoid(quad) else
                     [f"{quad.kind} {' '.join(f'{v:g}' for v in quad.params)}", "", "", ""])
            sets.add_row(name if i == 0 else "", span if i == 0 else "", set_name,
                         *cells, end_section=i == len(variable.sets) - 1)
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
                     f"{missing} rules still to learn")
                  + ("; activation: product (a rule fires with the product of its "
                     "memberships)" if behaviour.activation == "product" else ""))
    if len(behaviour.inputs) == 2 and behaviour.rules:
        console.print(_rule_grid(behaviour))
    elif behaviour.rules:
        console.print(_rule_list(behaviour))
    if missing:
        console.print(escape(_similar(missing, k)), highlight=False)


def _similar(rules: int, commands: int) -> str:
    """What the measured tasks nearest in size needed (flctool.learners.measured)."""
    from flctool.learners.measured import SEEDS, similar_tasks

    return "\n".join([
        f"similar problems measured (docs/learning.md, seeds {SEEDS}, each file's defaults; "
        "selection, confirmation and baselines on top of the training episodes):",
        *(f"  {task.line()}" for task in similar_tasks(rules, commands))])


def _refuse_comparing_with_itself(file: Path, shown: Path, compare: Path) -> None:
    """A clear error when ``--compare`` names the controller shown (``runs/R --compare
    runs/R`` is best.yaml against itself): every movement would be 0, which reads as "learning
    moved no set" when nothing was compared."""
    if controller_file(compare).resolve() != shown.resolve():
        return
    from flctool.runs import BEHAVIOUR_FILE

    where = (f": for a run, {file / BEHAVIOUR_FILE} (the run's copy of it)" if file.is_dir()
             else "")
    raise FlcError(f"{compare} is the controller shown ({shown}), so there is nothing to "
                   "compare its sets with", hint=f"compare with the file the sets were learned "
                   f"from{where}")


def _set_movements(reference: Behaviour, behaviour: Behaviour, compare: Path) -> Table:
    """Each set's movement from ``reference``'s: a :class:`FlcError` if the two do not have
    the same inputs and sets (then they are not one behaviour before and after learning)."""
    from rich.table import Table

    from flctool.behaviour.shapes import is_trapezoid
    from flctool.sets.measures import movements, partition_measures, trapezoid_sets

    layout = {n: (v.range, tuple(v.sets)) for n, v in behaviour.inputs.items()}
    if layout != {n: (v.range, tuple(v.sets)) for n, v in reference.inputs.items()}:
        raise FlcError(
            f"{compare} has other inputs, ranges or set names than the behaviour shown, so "
            "its sets cannot be compared", hint="compare a learned behaviour with the file "
            "it was learned from")
    table = Table(title=f"sets moved from {escape(str(compare))}", title_justify="left")
    for column in ("input", "set", "before", "after", "moved", "of range"):
        table.add_column(column, justify="right" if column in ("moved", "of range") else "left")
    moved = movements(reference, behaviour)
    for name, variable in behaviour.inputs.items():
        rows = [m for m in moved if m.input == name]
        unit = f" {variable.unit}" if variable.unit else ""
        for i, m in enumerate(rows):
            table.add_row(name if i == 0 else "", m.set, _quad(m.before), _quad(m.after),
                          f"{m.largest:.4g}{unit}", f"{100 * m.fraction:.1f} %",
                          end_section=i == len(rows) - 1)
    measures = [(name, partition_measures(v.range, trapezoid_sets(v.sets)))
                for name, v in behaviour.inputs.items()
                if all(is_trapezoid(s) for s in v.sets.values())]
    table.caption = "; ".join(
        f"{name}: coverage {m['coverage']:.3g}, neighbour overlap "
        + (f"{m['least_overlap']:.3g}..{m['greatest_overlap']:.3g}"
           if m["least_overlap"] is not None else "-") for name, m in measures)
    return table


def _quad(quad: tuple[float, ...]) -> str:
    return "[" + ", ".join(f"{v:.4g}" for v in quad) + "]"


def _rule_list(behaviour: Behaviour) -> Table:
    from rich.table import Table

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
    from rich.table import Table

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


@app.command(epilog=example("flctool schema --check", "flctool schema --force"))
def schema(
    check: Annotated[bool, typer.Option(
        "--check", help="Fail (exit 1) if the file differs from the models.")] = False,
    path: Annotated[Path, typer.Option(
        "--output", "-o", "--path", help="The schema file.")] = DEFAULT_SCHEMA,
    force: Force = False,
) -> None:
    """Write the behaviour JSON Schema generated from the models (or check it is current)."""
    from flctool.behaviour.schema import behaviour_schema_text

    text = behaviour_schema_text()
    with user_errors():
        current = read_user_file(path, "schema") if path.is_file() else None
        if check:
            if current != text:
                raise FlcError(f"{path} is {'missing' if current is None else 'stale'}",
                               hint="run 'flctool schema --force' and commit the result")
            say(f"{path} is up to date", "ok")
            return
        if current == text:
            say(f"{path} is already up to date")
            return
        write_output(path, text, "schema", force=force)
    say(f"wrote {path}")
