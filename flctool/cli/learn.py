"""``flctool learn``: train a behaviour's rules into a run directory, or resume one."""

from __future__ import annotations

import json
import shlex
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from flctool.cli.app import (
    app,
    console,
    err_console,
    escape,
    example,
    report_interrupted,
    user_errors,
)
from flctool.cli.progress import Progress
from flctool.errors import Problem, RunDirError, SpecError
from flctool.plugins import names

if TYPE_CHECKING:
    from flctool.learners import Learner
    from flctool.runs import Run, RunSummary
    from flctool.spec import Behaviour


def parse_assignments(assignments: list[str]) -> dict[str, Any]:
    """``["q.temperature=0.2", "common_starts=true"]`` -> a mapping; values read as YAML."""
    import yaml

    overrides: dict[str, Any] = {}
    for text in assignments:
        key, sep, value = text.partition("=")
        key = key.strip()
        if not sep or not key:
            raise SpecError([Problem(("--set",), f"'{text}' is not key=value",
                                     "write e.g. --set q.temperature=0.2", file="command line")],
                            "command line")
        try:
            overrides[key] = yaml.safe_load(value) if value.strip() else ""
        except yaml.YAMLError:  # not YAML: the text itself
            overrides[key] = value
    return overrides


def set_keys(assignments: list[str]) -> list[str]:
    """The keys of ``--set key=value`` assignments, as given."""
    return [text.partition("=")[0].strip() for text in assignments]


_GENERATIONS_KEYS = ("generations", "learning.generations")


def _resume_generations(run: Run, generations: int | None,
                        overrides: dict[str, Any]) -> int | None:
    """The new generation budget of a resumed run: ``-g``, or ``--set generations=N`` (taken
    out of ``overrides``, which must otherwise match the run)."""
    from flctool.runs import resolve_behaviour

    for key in _GENERATIONS_KEYS:
        if key not in overrides:
            continue
        value = overrides.pop(key)
        # Validated like the file's own field (an int >= 1), named as the user wrote it.
        budget = resolve_behaviour(run.behaviour, {"generations": value},
                                   f"--set {key}").learning.generations
        if generations is not None and generations != budget:
            raise RunDirError(f"--generations {generations} and --set {key}={value} ask for "
                              "different budgets", hint="give the new total once")
        generations = budget
    return generations


def _differences(a: Any, b: Any, path: str = "") -> list[str]:
    if isinstance(a, dict) and isinstance(b, dict):
        found: list[str] = []
        for key in sorted(set(a) | set(b), key=str):
            found += _differences(a.get(key), b.get(key), f"{path}.{key}" if path else str(key))
        return found
    return [] if a == b else [path or "(top level)"]


def _check_same_run(run: Run, requested: Behaviour) -> None:
    from flctool.spec import behaviour_to_data

    recorded = behaviour_to_data(run.behaviour)
    wanted = behaviour_to_data(requested)
    for data in (recorded, wanted):
        data.get("learning", {}).pop("generations", None)
    changed = _differences(recorded, wanted)
    if changed:
        raise RunDirError(f"--resume continues the run recorded in {run.path}, but the file "
                          f"and options given differ from it at: {', '.join(changed)}",
                          hint="leave them out (only --generations may change), or start a "
                          "new run with --out")


@app.command(epilog=example(
    "flctool learn behaviours/ballchase.yaml -o runs/first",
    "flctool learn behaviours/ballchase.yaml --learner pitt --seed 3 --set mutation=0.2",
    "flctool learn --resume runs/first --generations 60"))
def learn(
    file: Annotated[Path | None, typer.Argument(
        help="The behaviour file (YAML); optional with --resume.")] = None,
    learner: Annotated[str | None, typer.Option(
        "--learner", "-l", help=f"{', '.join(names('learner'))} (default: the file's).")]
    = None,
    seed: Annotated[int | None, typer.Option("--seed", "-s", help="Random seed.")] = None,
    generations: Annotated[int | None, typer.Option(
        "--generations", "-g", help="Generations to run (with --resume: the new total).")]
    = None,
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
    as_json: Annotated[bool, typer.Option(
        "--json", help="Print a JSON summary instead of text (progress stays on stderr).")]
    = False,
) -> None:
    """Learn the rule consequents of a behaviour (Pitt GA, fuzzy Q-learning or the hybrid).

    Writes a run directory with metrics, checkpoints and best.yaml, the learned controller.
    """
    from flctool.cli.locate import located_in
    from flctool.learners import make_learner
    from flctool.runs import BEHAVIOUR_FILE, create_run, open_run, resolve_behaviour
    from flctool.spec import load_behaviour

    with user_errors():
        overrides = parse_assignments(set_ or [])
        for key, value in (("learner", learner), ("seed", seed), ("population", population)):
            if value is not None:
                overrides[key] = value
        if resume is not None:
            if out is not None:
                raise RunDirError("--resume continues in its own directory; --out is for new "
                                  "runs", hint="leave out --out")
            run = open_run(resume)
            generations = _resume_generations(run, generations, overrides)
            if file is not None or overrides:
                base = load_behaviour(file) if file is not None else run.behaviour
                _check_same_run(run, resolve_behaviour(base, overrides))
            if generations is not None and generations != run.behaviour.learning.generations:
                run.extend(generations)
            source, overridden = run.path / BEHAVIOUR_FILE, []
            behaviour = run.behaviour
        else:
            if file is None:
                raise RunDirError("give a behaviour file to learn, or --resume a run directory",
                                  hint="flctool learn behaviours/ballchase.yaml")
            if generations is not None:
                overrides["generations"] = generations
            behaviour = resolve_behaviour(load_behaviour(file), overrides,
                                          f"{file} with command-line options")
            source, overridden = file, set_keys(set_ or [])
        # The environment is built before any directory is made, so that its errors (located
        # in the file they are about) leave nothing behind.
        with located_in(source, overridden):
            learner_ = make_learner(behaviour)
        if resume is None:
            try:
                run = create_run(behaviour, out)
            except BaseException:
                learner_.env.close()  # Run.train closes it from here on (a robot gets stop)
                raise
        done = len(run.checkpoint_generations())
        err_console.print(f"{'resuming' if resume is not None else 'learning'} "
                          f"{behaviour.learning.learner} (seed {behaviour.learning.seed}) "
                          f"from generation {done} in the run directory "
                          f"{escape(str(run.path))}", highlight=False)
        try:
            summary = _train(run, learner_, show_progress=not as_json)
        except KeyboardInterrupt:
            report_interrupted(f"the run in {run.path} stopped at its last checkpoint; "
                               f"continue it with: {resume_command(run.path)}")
            raise typer.Exit(130) from None
    if as_json:
        print(json.dumps(summary.to_dict(), indent=2))
    else:
        _report(summary)


def resume_command(path: Path) -> str:
    """The command line that continues the run in ``path``, ready to paste."""
    return f"flctool learn --resume {shlex.quote(str(path))}"


def _train(run: Run, learner: Learner, show_progress: bool) -> RunSummary:
    from flctool.learners import FunctionCallback, GenerationMetrics

    config = run.behaviour.learning
    done = len(run.checkpoint_generations())
    with Progress(f"{config.learner} generation", config.generations, done,
                  terminal=show_progress) as progress:

        def advance(metrics: GenerationMetrics) -> None:
            validated = ("-" if metrics.validated != metrics.validated
                         else f"{metrics.validated:.3f}")
            progress.update(metrics.generation + 1, **{"validated best": validated,
                                                       "training mean": f"{metrics.mean:.3f}"})

        return run.train([FunctionCallback(advance)], learner=learner)


def _report(summary: RunSummary) -> None:
    best = summary.best
    console.print(f"[green]{summary.status}[/] {summary.learner} (seed {summary.seed}): "
                  f"{summary.generations} generations in {escape(str(summary.path))}")
    if summary.last is not None:
        last = summary.last
        console.print(f"last generation: mean fitness {last.mean:.3f} (std {last.std:.3f}), "
                      f"best {last.best:.3f}; {last.wall_time:.2f} s of training")
    usage = summary.usage
    if usage:
        console.print(f"used {usage['training_episodes']} training episodes "
                      f"({usage['training_steps']} steps) and {usage['selection_episodes']} "
                      f"selection episodes ({usage['selection_steps']} steps)")
    if best:
        validation = best.get("validation")
        score = (f"validated mean fitness {validation['value']:.3f} [{validation['low']:.3f}, "
                 f"{validation['high']:.3f}] over {validation['n']} episodes"
                 if validation and validation.get("low") is not None
                 else f"fitness {best['fitness']:.3f} in training")
        console.print(f"best controller: generation {best['generation']}, individual "
                      f"{best['individual']}, {score} -> "
                      f"{escape(str(summary.path / 'best.yaml'))}")
        console.print(f"next: flctool evaluate {escape(str(summary.path / 'best.yaml'))}")
