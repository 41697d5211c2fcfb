"""``flctool learn``: train a behaviour's rules into a run directory, or resume one."""

from __future__ import annotations

import json
import math
import shlex
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from flctool.cli.app import (
    app,
    command_line_overrides,
    console,
    err_console,
    escape,
    example,
    report_interrupted,
    user_errors,
)
from flctool.cli.progress import Progress
from flctool.errors import RunDirError
from flctool.plugins import names

if TYPE_CHECKING:
    from flctool.behaviour.overrides import Override
    from flctool.runs import RunSummary
    from flctool.training import Training


@app.command(epilog=example(
    "flctool learn behaviours/ballchase.yaml -o runs/first",
    "flctool learn behaviours/ballchase.yaml --learner pitt --seed 3 --set mutation=0.2",
    "flctool learn --resume runs/first --generations 60",
    "flctool learn behaviours/ballchase-ros2.yaml --init runs/first"))
def learn(
    file: Annotated[Path | None, typer.Argument(
        help="The behaviour file (YAML); optional with --resume.")] = None,
    learner: Annotated[str | None, typer.Option(
        "--learner", "-l", help=f"{', '.join(names('learner'))} (default: the file's).")]
    = None,
    seed: Annotated[int | None, typer.Option("--seed", "-s", help="Random seed.")] = None,
    generations: Annotated[int | None, typer.Option(
        "--generations", "-g", help=(
            "Generations to run, exactly: a file without a budget then has no extension and "
            "one trial (with --resume: the new total)."))] = None,
    population: Annotated[int | None, typer.Option(
        "--population", "-p", help="Individuals per generation.")] = None,
    out: Annotated[Path | None, typer.Option(
        "--out", "-o", help="Run directory (default: runs/<name>-<learner>-seed<S>-<time>).")]
    = None,
    resume: Annotated[Path | None, typer.Option(
        "--resume", help="Continue the run in this directory from its last checkpoint.")]
    = None,
    set_: Annotated[list[str] | None, typer.Option(
        "--set", help="Override a learning hyperparameter, e.g. --set q.temperature=0.2 "
        "(repeatable; keys as under 'learning:').")] = None,
    baseline: Annotated[list[Path] | None, typer.Option(
        "--baseline", help="A hand-made controller of the same rules that the learned one "
        "must beat (repeatable); constant commands and random tables are always compared.")]
    = None,
    as_json: Annotated[bool, typer.Option(
        "--json", help="Print a JSON summary instead of text (progress stays on stderr).")]
    = False,
    init: Annotated[Path | None, typer.Option(
        "--init", help="Start around this controller (a run directory or a behaviour file): "
        "the first generation seeded around it, q values carried over where rules match.")]
    = None,
) -> None:
    """Learn the rule consequents of a behaviour (Pitt GA, fuzzy Q-learning or the hybrid).

    Writes a run directory with metrics, checkpoints and best.yaml, the learned controller.
    """
    from flctool.training import resume_run, start_run

    with user_errors():
        overrides = command_line_overrides(set_ or [], {
            "learner": ("--learner", learner), "seed": ("--seed", seed),
            "population": ("--population", population)})
        if resume is not None:
            if baseline:
                raise RunDirError("--baseline is given when a run starts; a resumed run "
                                  "compares with the baselines it started with",
                                  hint="leave out --baseline")
            if init is not None:
                raise RunDirError("--init starts a new run; a resumed run continues from its "
                                  "checkpoint", hint="leave out --init")
            if out is not None:
                raise RunDirError("--resume continues in its own directory; --out is for new "
                                  "runs", hint="leave out --out")
            overrides, budget = _budget(overrides, generations)
            training = resume_run(resume, file, overrides, budget)
        else:
            if file is None:
                raise RunDirError("give a behaviour file to learn, or --resume a run directory",
                                  hint="flctool learn behaviours/ballchase.yaml")
            overrides += command_line_overrides([], {"generations": ("--generations",
                                                                     generations)})
            training = start_run(file, overrides, out, baselines=baseline or [])
            if init is not None:
                _warm_start(training, init)
        run, behaviour = training.run, training.run.behaviour
        err_console.print(f"{'resuming' if training.resumed else 'learning'} "
                          f"{behaviour.learning.learner} (seed {behaviour.learning.seed}) "
                          f"from generation {training.done} in the run directory "
                          f"{escape(str(run.path))}", highlight=False)
        from flctool.learners.budget import describe_budget

        err_console.print(escape(describe_budget(
            behaviour, len(training.learner.baseline_check.given))), highlight=False)
        try:
            summary = _train(training, show_progress=not as_json)
        except KeyboardInterrupt:
            report_interrupted(f"the run in {run.path} stopped at its last checkpoint; "
                               f"continue it with: {resume_command(run.path)}")
            raise typer.Exit(130) from None
    if as_json:
        print(json.dumps(summary.to_dict(), indent=2))
    else:
        _report(summary)
    if summary.status == "not_learned":  # flctool.runs.NOT_LEARNED (kept lazy)
        from flctool.learners.baselines import not_learned_message
        from flctool.runs import BASELINE_FILE  # loaded already: the run is one

        verdict = (summary.selection or {}).get("baseline") or {}
        message = not_learned_message(verdict, list(behaviour.output.commands),
                                      behaviour.learning.learner)
        err_console.print(f"[yellow]not learned:[/] {escape(message)}", highlight=False)
        baseline_file = run.path / BASELINE_FILE
        if baseline_file.is_file():
            err_console.print(f"  the baseline, to evaluate or deploy instead: "
                              f"{escape(str(baseline_file))}", highlight=False)
        raise typer.Exit(NOT_LEARNED_EXIT)


#: The exit code of a run that ended without learning (docs/cli.md).
NOT_LEARNED_EXIT = 3


def _warm_start(training: Training, init: Path) -> None:
    from flctool.warm_start import warm_start_from_path

    try:
        started = warm_start_from_path(training.learner, training.run.behaviour, init)
    except BaseException:
        training.close()  # the environment (a robot is sent stop)
        raise
    err_console.print(escape(started.describe()), highlight=False)


def _budget(overrides: list[Override], generations: int | None,
            ) -> tuple[list[Override], Override | None]:
    """A resumed run's new budget, from --generations or --set generations=N (which must
    agree), and the other overrides."""
    budgets = [o for o in overrides if o.path == ("learning", "generations")]
    budgets += command_line_overrides([], {"generations": ("--generations", generations)})
    if len({repr(o.value) for o in budgets}) > 1:
        given = " and ".join(o.where.removeprefix("command line ") for o in budgets)
        raise RunDirError(f"{given} ask for different budgets",
                          hint="give the new total once")
    return [o for o in overrides if o not in budgets], budgets[0] if budgets else None


def resume_command(path: Path) -> str:
    """The command line that continues the run in ``path``, ready to paste."""
    return f"flctool learn --resume {shlex.quote(str(path))}"


def _train(training: Training, show_progress: bool) -> RunSummary:
    from flctool.learners import Callback, GenerationMetrics

    config = training.run.behaviour.learning

    class Shown(Callback):
        """Each generation on the progress bar, whose total is the generations the run
        has as things stand (an extended run's grows while it improves)."""

        def on_generation(self, metrics: GenerationMetrics) -> bool:
            validated = ("-" if metrics.validated != metrics.validated
                         else f"{metrics.validated:.3f}")
            total = None if self.learner is None else self.learner.planned_generations()
            progress.update(metrics.generation + 1, total,
                            **{"validated best": validated,
                               "training mean": f"{metrics.mean:.3f}"})
            return True

    with Progress(f"{config.learner} generation", config.generations, training.done,
                  terminal=show_progress) as progress:
        return training.train([Shown()])


def _report(summary: RunSummary) -> None:
    from flctool.runs import confirmation_text

    best = summary.best
    console.print(f"[green]{summary.status}[/] {summary.learner} (seed {summary.seed}): "
                  f"{summary.generations} generations in {escape(str(summary.path))}")
    if summary.last is not None:
        last = summary.last
        console.print(f"last generation: mean fitness {last.mean:.3f} (std {last.std:.3f}), "
                      f"best {last.best:.3f}; {last.wall_time:.2f} s of training")
    usage = summary.usage
    if usage is not None:
        console.print(f"used {usage.training_episodes} training episodes "
                      f"({usage.training_steps} steps), {usage.selection_episodes} selection "
                      f"({usage.selection_steps} steps), {usage.confirmation_episodes} "
                      f"confirmation ({usage.confirmation_steps} steps) and "
                      f"{usage.baseline_episodes} baseline episodes "
                      f"({usage.baseline_steps} steps)")
    if best is not None:
        console.print(f"best controller: generation {best.generation}, individual "
                      f"{best.individual} -> {escape(str(summary.path / 'best.yaml'))}")
        confirmation = best.confirmation
        if confirmation:
            console.print(f"  confirmed on {confirmation['episodes']} fresh episodes: "
                          f"{confirmation_text(confirmation)}")
        validation = best.validation
        if validation is not None and not math.isnan(validation.low):
            console.print(f"  selection's figure (the best of the candidates on the same "
                          f"{validation.n} episodes, so optimistic): validated mean "
                          f"fitness {validation.value:.3f} [{validation.low:.3f}, "
                          f"{validation.high:.3f}]")
        elif not confirmation:
            console.print(f"  fitness {best.fitness:.3f} in training")
        verdict = (summary.selection or {}).get("baseline")
        if verdict and verdict.get("learned"):
            from flctool.learners.baselines import difference_text

            console.print(f"  learned: better than the strongest baseline, "
                          f"'{escape(str(verdict['baseline']))}', by "
                          f"{difference_text(verdict['difference'])} mean fitness on the same "
                          f"episodes")
        exploration = (summary.selection or {}).get("exploration")
        if exploration:
            from flctool.learners.fuzzy_q import exploration_advice, held_text

            held = held_text(exploration)
            if held is not None:
                console.print(f"  exploration held: {escape(held)}", highlight=False)
            advice = exploration_advice(exploration)
            if advice is not None:
                console.print(f"  [yellow]{advice[0]}:[/] {escape(advice[1])}", highlight=False)
        console.print(f"next: flctool evaluate {escape(str(summary.path / 'best.yaml'))}")
