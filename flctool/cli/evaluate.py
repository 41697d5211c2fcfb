"""``flctool evaluate``: run a deployable controller for many episodes and summarise.

Episodes run in lock-step in chunks of at most :data:`CHUNK_EPISODES`, so memory follows the
chunk, not ``--episodes``; every episode depends on its own seed only, so the chunking does not
change a result (tests check it).
"""

from __future__ import annotations

import csv
import io
import json
import re
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
from flctool.cli.progress import Progress, compiling
from flctool.cli.spec_commands import ControllerArgument

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import NDArray
    from rich.table import Table

    from flctool.compile import Controller
    from flctool.envs import BatchEnv
    from flctool.rollout import Estimate, EvaluationResult
    from flctool.spec import Behaviour

#: Most episodes stepped together; the peak memory of an evaluation follows this, not
#: --episodes.
CHUNK_EPISODES = 1024
#: Episodes of the first chunk, and the seconds later chunks are sized to take (so that a
#: slow environment still shows progress).
FIRST_CHUNK, CHUNK_SECONDS = 64, 2.0
#: Most episodes one --seeds list may name.
MAX_LISTED_SEEDS = 10_000_000
#: Training episodes use seeds from 2^32 up (flctool.learners.base.TRAIN_SEED_LOW).
TRAINING_SEEDS_FROM = 2**32

_SEED_ITEM = re.compile(r"^\s*(\d+)\s*(?:-\s*(\d+)\s*)?$")


def parse_seeds(text: str) -> list[int]:
    """``"1,2,5-9"`` -> ``[1, 2, 5, 6, 7, 8, 9]``: comma-separated seeds and inclusive
    ranges, in the order given; a seed named twice is an error (it would count twice)."""
    seeds: list[int] = []
    for item in text.split(","):
        match = _SEED_ITEM.match(item)
        if match is None:
            raise ValueError(f"'{item.strip()}' is not a seed or a range like 5-9 "
                                     "(seeds are integers >= 0)")
        low = int(match.group(1))
        high = int(match.group(2)) if match.group(2) is not None else low
        if high < low:
            raise ValueError(f"the range {low}-{high} is empty; write it low-high")
        if len(seeds) + high - low + 1 > MAX_LISTED_SEEDS:
            raise ValueError(f"more than {MAX_LISTED_SEEDS:,} seeds")
        seeds.extend(range(low, high + 1))
    if max(seeds) >= 2**63:
        raise ValueError("seeds must be below 2^63")
    if len(set(seeds)) != len(seeds):
        twice = sorted({s for s in seeds if seeds.count(s) > 1})[:5] if len(seeds) < 10_000 \
            else []
        raise ValueError("a seed is named twice" +
                                 (f" ({', '.join(map(str, twice))})" if twice else ""))
    return seeds


def _row(label: str, estimate: Estimate, percent: bool = False) -> tuple[str, str, str, str]:
    def fmt(x: float) -> str:
        if x != x:  # NaN: no samples, or no interval from a single one
            return "-"
        return f"{100 * x:.1f} %" if percent else f"{x:.3f}"
    interval = "-" if estimate.low != estimate.low else \
        f"[{fmt(estimate.low)}, {fmt(estimate.high)}]"
    return label, fmt(estimate.value), interval, str(estimate.n)


def defines_success(behaviour: Behaviour) -> bool:
    """Whether the behaviour's environment has a notion of success (``success: never``
    says it has none)."""
    return getattr(behaviour.environment, "success", "terminated") != "never"


def _table(name: str, result: EvaluationResult, success: bool) -> Table:
    from rich.table import Table

    table = Table(title=f"{name}: {result.episodes} episodes", title_justify="left")
    table.add_column("statistic")
    table.add_column("value", justify="right")
    table.add_column("95 % CI", justify="right")
    table.add_column("n", justify="right")
    if success:
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
    import numpy as np

    from flctool.cli.locate import located_in
    from flctool.compile import compile_behaviour
    from flctool.envs import make_env
    from flctool.rollout import evaluation_seeds, trace_episode

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
        episode_seeds = (np.array(listed, dtype=np.int64) if listed is not None else
                         evaluation_seeds(0 if seed is None else seed,
                                          1000 if episodes is None else episodes))
        if listed is not None and max(listed) >= TRAINING_SEEDS_FROM:
            err_console.print(f"[yellow]warning:[/] seeds from {TRAINING_SEEDS_FROM} up are "
                              "the range training episodes use; these are not held out",
                              highlight=False)
        with located_in(source):  # an adapter's complaint about the file, at its line
            env = make_env(behaviour, min(len(episode_seeds), CHUNK_EPISODES))
        try:
            result = evaluate_in_chunks(controller, env, episode_seeds,
                                        show_progress=not json_output,
                                        success=defines_success(behaviour))
        finally:
            env.close()
        if trace is not None:
            single = make_env(behaviour, 1)
            try:
                rows = trace_episode(controller, single, int(episode_seeds[0]))
            finally:
                single.close()
            write_output(trace, _csv(rows), "trace", force=force)
    success = defines_success(behaviour)
    if json_output:
        summary = result.summary()
        if not success:
            del summary["success_rate"], summary["steps_to_success"]
        typer.echo(json.dumps({"behaviour": behaviour.name, "file": str(source),
                               "seed": None if listed is not None else (seed or 0),
                               **summary, "seeds": result.seeds.tolist()}, indent=2))
        return
    console.print(_table(behaviour.name, result, success))
    if trace is not None:
        console.print(f"trace of episode seed {int(episode_seeds[0])} written to "
                      f"{escape(str(trace))}")


def evaluate_in_chunks(controller: Controller, env: BatchEnv, seeds: NDArray[np.int64], *,
                       show_progress: bool = True, success: bool = True,
                       chunk: int = CHUNK_EPISODES) -> EvaluationResult:
    """:func:`flctool.rollout.evaluate` of ``seeds (E,)``, at most ``chunk`` episodes at a
    time: the same outcomes, with memory that does not grow with E.

    The first chunk is small; later ones are sized to take about :data:`CHUNK_SECONDS` each
    (up to ``chunk``), so a slow environment still reports progress every few seconds while
    a fast one runs in large lock-step batches.
    """
    import time

    import numpy as np

    from flctool.rollout import EvaluationResult, evaluate

    parts: list[EvaluationResult] = []
    total = int(seeds.shape[0])
    with compiling():  # load (or, on a machine's first run, compile) the kernels
        controller.output(controller.ranges[:, 0][None, :])
    size = min(FIRST_CHUNK, chunk)
    done = 0
    with Progress("episodes", total, terminal=show_progress) as progress:
        while done < total:
            started = time.monotonic()
            parts.append(evaluate(controller, env, seeds[done:done + size]))
            seconds = max(time.monotonic() - started, 1e-6)
            done += parts[-1].episodes
            size = max(1, min(chunk, int(parts[-1].episodes * CHUNK_SECONDS / seconds)))
            if success:
                rate = sum(int(p.success.sum()) for p in parts) / done
                progress.update(done, success=f"{100 * rate:.1f} %")
            else:
                progress.update(done)
    if len(parts) == 1:
        return parts[0]
    return EvaluationResult(*(np.concatenate([getattr(p, name) for p in parts])
                              for name in ("seeds", "returns", "lengths", "success",
                                           "fitness")))
