"""``flctool experiment``: every learner on every seed, statistics and a report."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated

import typer

from flctool.cli.app import (
    app,
    command_line_overrides,
    console,
    escape,
    example,
    user_errors,
)
from flctool.cli.progress import Progress


@app.command(epilog=example(
    "flctool experiment behaviours/ballchase.yaml --seeds 30 --workers 2",
    "flctool experiment behaviours/ballchase.yaml --learners pitt,hybrid -o experiments/x"))
def experiment(
    file: Annotated[Path, typer.Argument(help="The behaviour file (YAML).")],
    learners: Annotated[str, typer.Option(
        help="Comma-separated learners to compare.")] = "pitt,hybrid,fuzzy_q",
    seeds: Annotated[int, typer.Option(min=1, help="Runs per learner, seeds 0..N-1.")] = 30,
    workers: Annotated[int | None, typer.Option(
        min=1, help="Parallel runs (local: default 1; ray: default every CPU Ray has).")]
    = None,
    executor: Annotated[str, typer.Option(help="Where runs execute: local or ray.")] = "local",
    address: Annotated[str | None, typer.Option(
        help="HOST:PORT of a running Ray cluster (with --executor ray).")] = None,
    set_: Annotated[list[str] | None, typer.Option(
        "--set", help="Override a setting for every run that reads it, e.g. --set "
        "environment.max_steps=100 (repeatable; keys as under 'learning:').")] = None,
    heldout: Annotated[int, typer.Option(
        min=1, help="Held-out episodes each run's best.yaml is tested on.")] = 500,
    level: Annotated[float | None, typer.Option(
        help="Mean fitness whose first crossing is reported (default: half way from the "
        "first to the last generation's median).")] = None,
    out: Annotated[Path | None, typer.Option(
        "--out", "-o", help="Experiment directory (default: experiments/<name>); an existing "
        "one with the same plan is continued.")] = None,
    as_json: Annotated[bool, typer.Option(
        "--json", help="Print the summary as JSON instead of text (progress stays on "
        "stderr).")]
    = False,
) -> None:
    """Run the paper's experiment: every learner on every seed, then report the spread across
    seeds, held-out success, rank tests and whether the paper's claims hold.

    Writes report.md and summary.json; 'flctool plot' on the directory draws the figures.
    """
    from flctool.experiment import (
        ExperimentPlan,
        make_executor,
        parse_learners,
        prepare_experiment,
        read_experiment_behaviour,
        write_report,
    )
    from flctool.experiment.runner import JobOutcome

    with user_errors():
        names = parse_learners(learners)
        overrides = command_line_overrides(set_ or [])
        runner = make_executor(executor, workers, address)
        behaviour = read_experiment_behaviour(file, names, overrides)
        plan = ExperimentPlan(behaviour.name, names, seeds, heldout_episodes=heldout,
                              overrides={o.key: o.value for o in overrides})
        folder = out if out is not None else Path("experiments") / behaviour.name
        study = prepare_experiment(behaviour, plan, folder)
        with Progress("runs", len(names) * seeds, terminal=not as_json) as progress:

            def done(outcome: JobOutcome) -> None:
                state = "done before" if outcome.skipped else "held-out success"
                progress.update(progress.done + 1, last=f"{outcome.learner} seed "
                                f"{outcome.seed}: {state} {outcome.heldout_success:.3f}")

            study.run(runner, done)
        summary = write_report(study, level)
    if as_json:
        print(json.dumps(summary, indent=2))
        return
    console.print(f"[green]finished[/] {len(names) * seeds} runs in {escape(str(folder))}")
    for claim in summary["claims"]:
        console.print(f"  {escape(claim['claim'])}: [bold]{escape(claim['verdict'])}[/]")
    for name in names:
        entry = summary["learners"][name]["heldout_success"]
        # the spread across seeds, not a confidence interval: said in words, not brackets
        console.print(f"  {name}: held-out success median {entry['median']:.3f}, "
                      f"interquartile range {entry['q25']:.3f} to {entry['q75']:.3f} "
                      f"across {seeds} seeds")
    console.print(f"report: {escape(str(folder / 'report.md'))}; figures: flctool plot "
                  f"{escape(str(folder))}")
