"""Figures of a run or an experiment, as in the paper, each written as PNG and SVG.

* learning curves (Fig. 5-6, 9-10): a run's mean fitness with the range of its generation's
  trials and its population std; an experiment's median and inter-quartile range across seeds
  per learner. Bands are made of measured values (min..max, quartiles), never mean +- std, so
  they stay inside the range fitness can take.
* the strengths of one rule over the trials (Fig. 7);
* a controller: its trajectory in the simulator on the pitch outline (Fig. 8, 11), each
  input's membership functions, the rule table as a grid, and for two inputs the control
  surface (the output over the input plane).

matplotlib is an optional extra (``pip install 'flctool[plot]'``); it is imported only here,
with the Agg backend, so plotting works on a robot's headless computer too.
"""

from __future__ import annotations

import csv
import io
import itertools
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from flctool.atomic import write_bytes_atomic
from flctool.behaviour import Behaviour
from flctool.behaviour.fuzzy import FuzzySet
from flctool.behaviour.shapes import set_row
from flctool.errors import FlcError, MissingDependencyError, Problem, RunDirError, SpecError
from flctool.inputs import no_such_file
from flctool.membership import memberships
from flctool.runs import Run

FloatArray = NDArray[np.float64]
FORMATS = ("png", "svg")


def _pyplot() -> Any:
    try:
        import matplotlib
    except ImportError:
        raise MissingDependencyError("matplotlib", "plot", "Plotting") from None
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    # Text stays text in SVG (small files, searchable); PNG metadata carries no date, so the
    # same figure gives the same bytes.
    matplotlib.rcParams.update({"svg.fonttype": "none", "svg.hashsalt": "flctool"})
    return plt


def _save(figure: Any, path: Path) -> list[Path]:
    """Write ``figure`` as ``path`` with the suffixes .png and .svg; returns both paths."""
    written = []
    for suffix in FORMATS:
        buffer = io.BytesIO()
        figure.savefig(buffer, format=suffix, dpi=110, bbox_inches="tight",
                       metadata={"Software": None} if suffix == "png" else {"Date": None})
        data = _palette_png(buffer.getvalue()) if suffix == "png" else buffer.getvalue()
        target = path.with_suffix(f".{suffix}")
        write_bytes_atomic(target, data)
        written.append(target)
    _pyplot().close(figure)
    return written


def _palette_png(data: bytes) -> bytes:
    """The PNG with a 256-colour palette: line plots look the same at a quarter of the size.
    (Pillow comes with matplotlib.)"""
    from PIL import Image

    image = Image.open(io.BytesIO(data)).convert("RGBA")
    buffer = io.BytesIO()
    image.quantize(colors=256, method=Image.Quantize.FASTOCTREE).save(
        buffer, format="PNG", optimize=True)
    return buffer.getvalue()


def _label(run: Run) -> str:
    return f"{run.learner}, seed {run.seed}"


def _episodes(run: Run) -> tuple[FloatArray, list[Any]]:
    metrics = run.metrics()
    if not metrics:
        raise RunDirError(f"{run.path}: the run has no finished generation to plot",
                          hint="let it run at least one generation")
    return np.cumsum([m.episodes for m in metrics]).astype(np.float64), metrics


def plot_fitness(runs: Sequence[Run], path: Path) -> list[Path]:
    """Learning curves of runs (the paper's Fig. 5-6): top, each generation's mean fitness
    with a band from its worst to its best trial and the best dashed; bottom, the
    population's std. One colour per run, over training episodes."""
    plt = _pyplot()
    figure, (top, bottom) = plt.subplots(2, 1, figsize=(7, 5.5), sharex=True,
                                         height_ratios=(2, 1))
    for run in runs:
        episodes, metrics = _episodes(run)
        mean = np.array([m.mean for m in metrics])
        line = top.plot(episodes, mean, label=f"{_label(run)}: mean")[0]
        top.fill_between(episodes, [m.min for m in metrics], [m.best for m in metrics],
                         color=line.get_color(), alpha=0.15, linewidth=0)
        top.plot(episodes, [m.best for m in metrics], "--", color=line.get_color(),
                 linewidth=1, label=f"{_label(run)}: best")
        bottom.plot(episodes, [m.std for m in metrics], color=line.get_color())
    top.set_ylabel("trial fitness")
    top.set_title(f"{runs[0].behaviour.name}: fitness per generation "
                  "(band: worst to best trial)", fontsize="medium")
    top.legend(fontsize="small")
    bottom.set_ylabel("std of trial fitness")
    bottom.set_xlabel("training episodes (trials)")
    for axes in (top, bottom):
        axes.grid(alpha=0.3)
    return _save(figure, path)


def strength_history(run: Run) -> tuple[NDArray[np.int64], FloatArray]:
    """The q table after each recorded generation: generations (G,) and q (G, M, K)."""
    generations = run.checkpoint_generations()
    tables = [run.checkpoint(g).get("q") for g in generations]
    if not generations or any(t is None for t in tables):
        raise RunDirError(f"{run.path}: the {run.learner} learner keeps no rule strengths",
                          hint="strengths are learned by the hybrid and fuzzy_q learners")
    return np.array(generations), np.array(tables, dtype=np.float64)


def most_contested_rule(q: FloatArray) -> int:
    """The rule whose strengths moved most over the run (largest summed variance over time):
    a sensible default for the paper's Fig. 7."""
    return int(np.argmax(q.var(axis=0).sum(axis=1)))


def rule_text(behaviour: Behaviour, rule: int) -> str:
    return " AND ".join(f"{name} is {set_name}" for name, set_name
                        in zip(behaviour.input_names, behaviour.antecedents()[rule],
                               strict=True))


def plot_strengths(run: Run, path: Path, rule: int | None = None) -> int:
    """The strength q_m^k of every command k of one rule m after each generation, over the
    trials (Fig. 7). ``rule`` is 0-based in the documented rule order; by default the most
    contested rule. Returns the rule plotted."""
    generations, q = strength_history(run)
    rule = most_contested_rule(q) if rule is None else rule
    if not 0 <= rule < q.shape[1]:
        raise RunDirError(f"rule {rule} does not exist: the behaviour has rules "
                          f"0..{q.shape[1] - 1}",
                          hint="rules are numbered from 0, last input varying fastest")
    episodes, _ = _episodes(run)
    episodes = episodes[: len(generations)]
    behaviour = run.behaviour
    plt = _pyplot()
    figure, axes = plt.subplots(figsize=(7, 4))
    for k, command in enumerate(behaviour.output.commands):
        axes.plot(episodes, q[:, rule, k], marker=".", label=command)
    axes.set_xlabel("training episodes (trials)")
    axes.set_ylabel("strength q (expected discounted reward)")
    axes.set_title(f"{_label(run)}: rule {rule}: IF {rule_text(behaviour, rule)}",
                   fontsize="medium")
    axes.legend(fontsize="small", title="THEN")
    axes.grid(alpha=0.3)
    _save(figure, path)
    return rule


# -- experiments ----------------------------------------------------------------------------
def plot_experiment_learning(summary: dict[str, Any], path: Path) -> list[Path]:
    """Per learner, the median across seeds of each generation's mean fitness (top) and
    population std (bottom) with the inter-quartile range, over training episodes: the
    paper's Fig. 5-6 over many seeds."""
    plt = _pyplot()
    figure, (top, bottom) = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    for name in summary["plan"]["learners"]:
        curve = summary["curves"][name]
        episodes = np.array(curve["episodes"])
        for axes, key in ((top, "mean"), (bottom, "std")):
            band = curve[key]
            line = axes.plot(episodes, band["median"], label=name)[0]
            axes.fill_between(episodes, band["q25"], band["q75"], color=line.get_color(),
                              alpha=0.2, linewidth=0)
    seeds = summary["plan"]["seeds"]
    top.set_title(f"{summary['behaviour']}: {seeds} seeds per learner "
                  "(line: median, band: 25-75 %)", fontsize="medium")
    top.set_ylabel("mean fitness of a generation")
    bottom.set_ylabel("std of trial fitness")
    bottom.set_xlabel("training episodes (trials)")
    top.legend(fontsize="small")
    for axes in (top, bottom):
        axes.grid(alpha=0.3)
    return _save(figure, path)


def plot_heldout(summary: dict[str, Any], path: Path) -> list[Path]:
    """Held-out success rate of every run's best.yaml, one column of points per learner with
    its quartiles."""
    plt = _pyplot()
    learners = summary["plan"]["learners"]
    figure, axes = plt.subplots(figsize=(1.6 + 1.4 * len(learners), 4))
    for i, name in enumerate(learners):
        entry = summary["learners"][name]["heldout_success"]
        values = np.array(entry["values"], dtype=np.float64)
        # a deterministic spread so that equal rates stay visible
        offsets = (np.arange(len(values)) % 7 - 3) * 0.04
        axes.plot(i + offsets, values, "o", alpha=0.6, markersize=4)
        axes.plot([i - 0.3, i + 0.3], [entry["median"]] * 2, color="black")
        axes.fill_between([i - 0.3, i + 0.3], entry["q25"], entry["q75"], color="grey",
                          alpha=0.25, linewidth=0)
    axes.set_xticks(range(len(learners)), learners)
    axes.set_ylim(-0.02, 1.02)
    episodes = summary["plan"]["heldout_episodes"]
    axes.set_ylabel(f"held-out success rate ({episodes} episodes)")
    axes.set_title("best.yaml of each run (bar: median, grey: 25-75 %)", fontsize="medium")
    axes.grid(alpha=0.3, axis="y")
    return _save(figure, path)


# -- a controller -----------------------------------------------------------------------
def _axis_label(behaviour: Behaviour, name: str) -> str:
    unit = behaviour.inputs[name].unit
    return f"{name} ({unit})" if unit else name


def _set_curve(value: FuzzySet, low: float, high: float) -> tuple[np.ndarray, np.ndarray]:
    """Where to draw a set: a trapezoid is linear between its corners, so it is drawn through
    them; another shape through 400 points of the range."""
    code, row = set_row(value)
    xs = (np.clip(np.array(row, dtype=np.float64), low, high) if code == 0
          else np.linspace(low, high, 400))
    return xs, memberships(xs, np.array([row], dtype=np.float64), [code])[:, 0]


def plot_memberships(behaviour: Behaviour, path: Path,
                     before: Behaviour | None = None) -> list[Path]:
    """Each input's fuzzy sets (paper Fig. 1): membership over the input's range; with
    ``before`` (the file a run learned the sets of) its sets dashed beneath, in the same
    colours, so each set's movement shows."""
    plt = _pyplot()
    names = behaviour.input_names
    figure, axes_list = plt.subplots(len(names), 1, figsize=(7, 2.2 * len(names)),
                                     squeeze=False)
    moved = 0
    for axes, name in zip(axes_list[:, 0], names, strict=True):
        variable = behaviour.inputs[name]
        low, high = variable.range
        old = before.inputs.get(name) if before is not None else None
        for set_name, quad in variable.sets.items():
            xs, ys = _set_curve(quad, low, high)
            line, = axes.plot(xs, ys, label=set_name)
            was = old.sets.get(set_name) if old is not None else None
            if was is not None and was != quad:
                moved += 1
                axes.plot(*_set_curve(was, low, high), linestyle="--", linewidth=0.9,
                          color=line.get_color(), alpha=0.6)
        axes.set_xlim(low, high)
        axes.set_ylim(-0.05, 1.1)
        axes.set_xlabel(_axis_label(behaviour, name))
        axes.set_ylabel("membership")
        axes.legend(fontsize="x-small", ncol=min(5, len(variable.sets)), loc="upper center",
                    bbox_to_anchor=(0.5, 1.3), frameon=False)
        axes.grid(alpha=0.3)
    # a run that learned the sets may still return the file's (its first individual has them)
    note = ("" if before is None else " (dashed: before learning)" if moved
            else " (learned: no set moved from the file's)")
    figure.suptitle(f"{behaviour.name}: fuzzy sets of each input{note}", y=1.0)
    figure.tight_layout()
    return _save(figure, path)


def _rule_grid(behaviour: Behaviour) -> tuple[list[str], list[str], list[list[str]]]:
    """Row labels, column labels (the last input's sets) and the command of each cell."""
    names = behaviour.input_names
    by_antecedent = {tuple(rule.if_[n] for n in names): rule.then for rule in behaviour.rules}
    columns = list(behaviour.inputs[names[-1]].sets)
    leading = [list(behaviour.inputs[n].sets) for n in names[:-1]]
    rows = [tuple(r) for r in itertools.product(*leading)] if leading else [()]
    cells = [[by_antecedent.get((*row, column), "") for column in columns] for row in rows]
    labels = [", ".join(f"{n}={s}" for n, s in zip(names[:-1], row, strict=True)) or "any"
              for row in rows]
    return labels, columns, cells


def plot_rule_table(behaviour: Behaviour, path: Path) -> list[Path]:
    """The rule table as a grid: rows are the sets of all inputs but the last, columns the
    last input's sets (the rule order of eq. 1 reads row by row); each cell names its command,
    coloured by the command's singleton value."""
    plt = _pyplot()
    labels, columns, cells = _rule_grid(behaviour)
    commands = behaviour.output.commands
    values = np.array([[commands[c] if c else np.nan for c in row] for row in cells])
    figure, axes = plt.subplots(figsize=(1.5 + 1.3 * len(columns), 1.2 + 0.5 * len(labels)))
    low, high = min(commands.values()), max(commands.values())
    image = axes.imshow(np.ma.masked_invalid(values), cmap="coolwarm", vmin=low,
                        vmax=high if high > low else low + 1, aspect="auto")
    for r, row in enumerate(cells):
        for c, command in enumerate(row):
            axes.text(c, r, command or "(none)", ha="center", va="center", fontsize="small")
    names = behaviour.input_names
    axes.set_xticks(range(len(columns)), columns, fontsize="small")
    axes.set_yticks(range(len(labels)), labels, fontsize="small")
    axes.set_xlabel(names[-1])
    if len(names) > 1:
        axes.set_ylabel(", ".join(names[:-1]))
    unit = f" ({behaviour.output.unit})" if behaviour.output.unit else ""
    figure.colorbar(image, ax=axes, label=f"{behaviour.output.name}{unit}")
    axes.set_title(f"{behaviour.name}: rule table", fontsize="medium")
    return _save(figure, path)


def plot_surface(behaviour: Behaviour, path: Path, resolution: int = 121) -> list[Path]:
    """The control surface of a two-input controller: its crisp output (eq. 3) over a
    ``resolution x resolution`` grid of the input plane."""
    from flctool.compile import compile_behaviour

    names = behaviour.input_names
    if len(names) != 2:
        raise FlcError(f"a control surface needs two inputs; {behaviour.name} has "
                       f"{len(names)}", hint="plot its rule table and membership functions")
    controller = compile_behaviour(behaviour)
    (x_low, x_high), (y_low, y_high) = controller.ranges.tolist()
    xs = np.linspace(x_low, x_high, resolution)
    ys = np.linspace(y_low, y_high, resolution)
    grid_x, grid_y = np.meshgrid(xs, ys)
    states = np.column_stack([grid_x.ravel(), grid_y.ravel()])
    output = controller.output(states).reshape(grid_x.shape)
    plt = _pyplot()
    figure, axes = plt.subplots(figsize=(6, 4.5))
    mesh = axes.pcolormesh(grid_x, grid_y, output, cmap="coolwarm", shading="auto",
                           rasterized=True)
    unit = f" ({behaviour.output.unit})" if behaviour.output.unit else ""
    figure.colorbar(mesh, ax=axes, label=f"{behaviour.output.name}{unit}")
    axes.set_xlabel(_axis_label(behaviour, names[0]))
    axes.set_ylabel(_axis_label(behaviour, names[1]))
    axes.set_title(f"{behaviour.name}: control surface", fontsize="medium")
    return _save(figure, path)


# -- trajectories (Fig. 8) ------------------------------------------------------------------
_TRACE_COLUMNS = ("robot_x", "robot_y", "ball_x", "ball_y")
_OPTIONAL_COLUMNS = ("robot_heading", "reward", "terminated", "truncated")


def read_trace(path: Path) -> dict[str, FloatArray]:
    """The numeric columns of a trace CSV written by ``flctool evaluate --trace``: positions
    (mm), and where present heading (deg), reward and the end flags (the final row, which
    has none, reads as NaN)."""
    try:
        with path.open(encoding="utf-8", newline="") as handle:
            rows = list(csv.DictReader(handle))
    except OSError as exc:
        raise SpecError([Problem((), f"cannot read the trace: {exc.strerror}", file=str(path))],
                        str(path)) from None
    missing = [c for c in _TRACE_COLUMNS if not rows or c not in rows[0]]
    if missing:
        raise SpecError([Problem((), f"not a ballchase trace: no column(s) {', '.join(missing)}",
                                 "write one with flctool evaluate FILE --trace trace.csv",
                                 file=str(path), line=1)], str(path))

    def number(text: str) -> float:
        flags = {"True": 1.0, "False": 0.0, "": float("nan")}
        return flags[text] if text in flags else float(text)

    present = [c for c in _OPTIONAL_COLUMNS if c in rows[0]]
    try:
        return {c: np.array([number(row[c]) for row in rows])
                for c in (*_TRACE_COLUMNS, *present)}
    except ValueError as exc:
        raise SpecError([Problem((), f"a value is not a number ({exc})", file=str(path))],
                        str(path)) from None


def trace_columns(rows: list[dict[str, Any]]) -> dict[str, FloatArray]:
    """Rows of :func:`flctool.rollout.trace_episode` as the columns :func:`read_trace` gives."""
    def number(value: Any) -> float:
        return float("nan") if value == "" else float(value)

    present = [c for c in (*_TRACE_COLUMNS, *_OPTIONAL_COLUMNS) if c in rows[0]]
    return {c: np.array([number(row[c]) for row in rows]) for c in present}


def outcome(trace: dict[str, FloatArray]) -> str:
    """How the traced episode ended: reached the ball, lost it, or timed out."""
    reward = trace.get("reward")
    if reward is None or len(reward) < 2:
        return "outcome not recorded"
    steps = len(reward) - 1  # the last row is the final state
    if reward[-2] > 0:
        return f"reached the ball in {steps} steps"
    if reward[-2] < 0:
        return f"lost the ball after {steps} steps"
    return f"timed out after {steps} steps"


def plot_trajectory(trace: dict[str, FloatArray], path: Path, title: str,
                    pitch: tuple[float, float] | None = None) -> list[Path]:
    """The robot's path to the ball seen from above (the paper's Fig. 8): start, heading
    arrows along the way, the ball, the outcome, and the pitch outline (``pitch`` = length,
    width in mm, centred on the origin) when known."""
    plt = _pyplot()
    figure, axes = plt.subplots(figsize=(7, 5))
    if pitch is not None:
        length, width = pitch
        axes.add_patch(plt.Rectangle((-length / 2, -width / 2), length, width, fill=False,
                                     edgecolor="green", linewidth=1.5, label="pitch"))
        axes.plot([0, 0], [-width / 2, width / 2], color="green", linewidth=0.8)
    x, y = trace["robot_x"], trace["robot_y"]
    axes.plot(x, y, "-", color="tab:blue", linewidth=1.2, label="robot centre")
    if "robot_heading" in trace:
        every = max(1, len(x) // 10)
        heading = np.radians(trace["robot_heading"][::every])
        # arrows of a fixed length in mm, a few per path
        span = max(float(np.ptp(x)), float(np.ptp(y)), *(pitch or (0.0,)))
        size = 0.04 * span if span > 0 else 1.0
        axes.quiver(x[::every], y[::every], size * np.cos(heading), size * np.sin(heading),
                    angles="xy", scale_units="xy", scale=1, color="tab:blue", width=0.004,
                    alpha=0.8, label="heading")
    axes.plot(x[:1], y[:1], "s", color="black", markersize=7, label="start")
    axes.plot(x[-1:], y[-1:], "x", color="tab:red", markersize=9, mew=2,
              label=f"end: {outcome(trace)}")
    axes.plot(trace["ball_x"][-1:], trace["ball_y"][-1:], "o", color="tab:orange",
              markersize=10, label="ball")
    axes.set_aspect("equal", adjustable="datalim")
    axes.set_xlabel("x along the pitch (mm)")
    axes.set_ylabel("y across the pitch (mm)")
    axes.set_title(title, fontsize="medium")
    axes.legend(fontsize="small", loc="upper left", bbox_to_anchor=(1.01, 1.0))
    axes.grid(alpha=0.3)
    return _save(figure, path)


def trace_controller(behaviour: Behaviour, seed: int) -> dict[str, FloatArray] | None:
    """One episode of a deployable controller as trajectory columns; None when the
    environment records no robot and ball positions (only the ballchase simulator does)."""
    from flctool.compile import compile_behaviour
    from flctool.envs import make_env
    from flctool.rollout import trace_episode

    with make_env(behaviour, 1) as env:
        rows = trace_episode(compile_behaviour(behaviour), env, seed)
    columns = trace_columns(rows)
    return columns if all(c in columns for c in _TRACE_COLUMNS) else None


def pitch_of(behaviour: Behaviour) -> tuple[float, float] | None:
    """(length, width) of the behaviour's pitch in mm, if its environment has one."""
    pitch = getattr(behaviour.environment, "pitch", None)
    if pitch is None:
        return None
    return float(pitch.length), float(pitch.width)


def plot_controller(behaviour: Behaviour, folder: Path, seed: int, title: str,
                    before: Behaviour | None = None) -> list[Path]:
    """Every figure of a deployable controller into ``folder``: memberships (over
    ``before``'s when its sets were learned), rule table, control surface (two inputs) and
    trajectory (environments with a robot and a ball)."""
    written = plot_memberships(behaviour, folder / "memberships.png", before)
    written += plot_rule_table(behaviour, folder / "rules.png")
    if len(behaviour.input_names) == 2:
        written += plot_surface(behaviour, folder / "surface.png")
    trace = trace_controller(behaviour, seed)
    if trace is None:
        return written
    written += plot_trajectory(trace, folder / "trajectory.png",
                               f"{title}: episode seed {seed}", pitch_of(behaviour))
    return written


# -- deciding what to draw from what was given ------------------------------------------------
#: One drawn figure: its files (PNG and SVG) and a note for the person (e.g. which rule).
Drawn = tuple[list[Path], str]


def default_folder(sources: Sequence[Path]) -> Path:
    """Where the figures of ``sources`` go unless told: the folder of a trace, else the
    experiment or first run directory. A source that does not exist is an error."""
    _check_exist(sources)
    return sources[0].parent if sources[0].is_file() else sources[0]


def _check_exist(sources: Sequence[Path]) -> None:
    if not sources:
        raise FlcError("nothing to plot", hint="give an experiment, run directories, or one "
                       "trace CSV")
    for source in sources:
        if not source.exists():
            raise no_such_file(source, "experiment, run directory or trace CSV")


def plot_sources(sources: Sequence[Path], folder: Path, rule: int | None = None
                 ) -> list[Drawn]:
    """Draw into ``folder`` every figure ``sources`` call for: one trace CSV (its
    trajectory); one experiment directory (learning curves, held-out success, one rule's
    strengths, the best controller); or run directories (their learning curves overlaid and,
    for one run, its strengths and best controller). ``rule`` picks the rule whose strengths
    are drawn (default: the one whose strengths moved most)."""
    from flctool.experiment import is_experiment
    from flctool.runs import open_run

    _check_exist(sources)
    if len(sources) == 1 and sources[0].is_file():
        trace = sources[0]
        return [(plot_trajectory(read_trace(trace), folder / f"{trace.stem}.png",
                                 f"trajectory: {trace.name}"), "")]
    if any(s.is_file() for s in sources):
        raise FlcError("give run directories, or a single trace CSV",
                       hint="plot traces one at a time")
    if any(is_experiment(s) for s in sources):
        if len(sources) > 1:
            raise FlcError("give one experiment directory at a time",
                           hint="plot each experiment on its own")
        return _plot_experiment(sources[0], folder, rule)
    runs = [open_run(s) for s in sources]
    # the checkpoints say whether the learner kept rule strengths (hybrid, fuzzy_q)
    strengths = len(runs) == 1 and "q" in (runs[0].last_checkpoint() or {})
    if rule is not None and not strengths:
        raise FlcError("--rule picks the rule of one run whose learner keeps strengths "
                       "(hybrid, fuzzy_q)", hint="plot that run on its own")
    drawn: list[Drawn] = [(plot_fitness(runs, folder / "fitness.png"), "")]
    if strengths:
        drawn.append(_strengths(runs[0], folder, rule))
    if len(runs) == 1 and (runs[0].path / "best.yaml").is_file():
        run = runs[0]
        learned_sets = getattr(run.behaviour.learning, "sets", None) is not None
        drawn.append(_best(run.path / "best.yaml", folder, f"{run.path.name} best.yaml",
                           run.behaviour if learned_sets else None))
    return drawn


def _strengths(run: Run, folder: Path, rule: int | None) -> Drawn:
    plotted = plot_strengths(run, folder / "strengths.png", rule)
    return [folder / "strengths.png", folder / "strengths.svg"], f" (rule {plotted})"


def _best(best: Path, folder: Path, title: str, before: Behaviour | None = None) -> Drawn:
    from flctool.behaviour import load_behaviour
    from flctool.rollout import evaluation_seeds

    # the first episode of 'flctool evaluate --episodes 1': never a training start
    seed = int(evaluation_seeds(0, 1)[0])
    return plot_controller(load_behaviour(best), folder, seed, title, before), ""


def _plot_experiment(path: Path, folder: Path, rule: int | None) -> list[Drawn]:
    from flctool.experiment import open_experiment, read_summary
    from flctool.runs import open_run

    experiment = open_experiment(path)
    summary = read_summary(path)
    drawn: list[Drawn] = [
        (plot_experiment_learning(summary, folder / "learning.png"), ""),
        (plot_heldout(summary, folder / "heldout.png"), "")]
    # Fig. 7 from the first seed of a learner that keeps strengths (the hybrid first)
    keeping = [n for n in ("hybrid", "fuzzy_q") if n in experiment.plan.learners]
    if keeping:
        drawn.append(_strengths(open_run(experiment.runs_dir / f"{keeping[0]}-seed0"),
                                folder, rule))
    elif rule is not None:
        raise FlcError("--rule needs a learner that keeps strengths (hybrid, fuzzy_q)",
                       hint="leave out --rule")
    best = summary["best_run"]
    name = f"{best['learner']}-seed{best['seed']}"
    drawn.append(_best(experiment.runs_dir / name / "best.yaml", folder,
                       f"best controller ({name}, held-out success "
                       f"{best['success_rate']:.3f})"))
    return drawn
