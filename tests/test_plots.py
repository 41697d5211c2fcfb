"""The paper's figures from real run directories and traces."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from flctool import load_behaviour
from flctool.cli import app
from flctool.errors import FlcError, MissingDependencyError, RunDirError, SpecError
from flctool.plots import (
    default_folder,
    most_contested_rule,
    outcome,
    plot_controller,
    plot_fitness,
    plot_memberships,
    plot_rule_table,
    plot_sources,
    plot_strengths,
    plot_surface,
    plot_trajectory,
    read_trace,
    strength_history,
)
from flctool.runs import Run, create_run, resolve_behaviour

from .conftest import BEHAVIOURS

PNG = b"\x89PNG\r\n\x1a\n"
SVG = b"<svg"
runner = CliRunner()


def _run(tmp_path: Path, learner: str, name: str) -> Run:
    behaviour = resolve_behaviour(load_behaviour(BEHAVIOURS / "ballchase.yaml"),
                                  {"learner": learner, "generations": 3, "population": 4})
    run = create_run(behaviour, tmp_path / name)
    run.train()
    return run


@pytest.mark.slow
def test_fitness_and_strengths_of_a_run(tmp_path: Path) -> None:
    run = _run(tmp_path, "hybrid", "hybrid")
    written = plot_fitness([run], tmp_path / "fitness.png")
    assert written == [tmp_path / "fitness.png", tmp_path / "fitness.svg"]
    assert (tmp_path / "fitness.png").read_bytes().startswith(PNG)
    assert SVG in (tmp_path / "fitness.svg").read_bytes()
    generations, q = strength_history(run)
    assert generations.tolist() == [0, 1, 2] and q.shape == (3, 15, 5)
    plotted = plot_strengths(run, tmp_path / "strengths.png")
    assert plotted == most_contested_rule(q)
    assert (tmp_path / "strengths.png").read_bytes().startswith(PNG)
    with pytest.raises(RunDirError, match=r"rule 15 does not exist: .* rules 0\.\.14"):
        plot_strengths(run, tmp_path / "bad.png", rule=15)


def test_most_contested_rule_is_the_one_whose_strengths_moved() -> None:
    q = np.zeros((4, 3, 2))
    q[:, 2, 1] = [0.0, 0.5, 1.0, 0.2]
    q[:, 0, 0] = [0.1, 0.1, 0.1, 0.1]  # large but constant
    assert most_contested_rule(q) == 2


def test_pitt_keeps_no_strengths(tmp_path: Path) -> None:
    run = _run(tmp_path, "pitt", "pitt")
    with pytest.raises(RunDirError, match="the pitt learner keeps no rule strengths"):
        strength_history(run)


def test_trajectory_from_an_evaluate_trace(tmp_path: Path) -> None:
    trace = tmp_path / "trace.csv"
    result = runner.invoke(app, ["evaluate", str(BEHAVIOURS / "ballchase-handmade.yaml"),
                                 "--episodes", "1", "--trace", str(trace)])
    assert result.exit_code == 0, result.output
    columns = read_trace(trace)
    assert len(columns["robot_x"]) > 1
    assert "robot_heading" in columns and "reward" in columns
    assert outcome(columns).startswith(("reached the ball in", "lost the ball after",
                                        "timed out after"))
    plot_trajectory(columns, tmp_path / "trajectory.png", "chase", pitch=(4200.0, 2700.0))
    assert (tmp_path / "trajectory.png").read_bytes().startswith(PNG)
    svg = (tmp_path / "trajectory.svg").read_text()
    assert "x along the pitch (mm)" in svg and "pitch" in svg


def test_a_file_that_is_not_a_trace(tmp_path: Path) -> None:
    other = tmp_path / "states.csv"
    other.write_text("ball_size,pan\n0.1,2\n")
    with pytest.raises(SpecError, match="not a ballchase trace: no column"):
        read_trace(other)


def test_missing_matplotlib_gives_the_install_hint(tmp_path: Path,
                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    with pytest.raises(MissingDependencyError) as info:
        plot_trajectory({"robot_x": np.zeros(2), "robot_y": np.zeros(2),
                         "ball_x": np.zeros(2), "ball_y": np.zeros(2)}, tmp_path / "t.png", "t")
    assert info.value.hint == "pip install 'flctool[plot]'"
    assert not (tmp_path / "t.png").exists()


@pytest.mark.slow
def test_plot_command(tmp_path: Path) -> None:
    hybrid = _run(tmp_path, "hybrid", "hybrid")
    pitt = _run(tmp_path, "pitt", "pitt")
    result = runner.invoke(app, ["plot", str(hybrid.path), "--rule", "7"])
    assert result.exit_code == 0, result.output
    assert "(rule 7)" in result.output
    for name in ("fitness", "strengths", "memberships", "rules", "surface", "trajectory"):
        assert (hybrid.path / f"{name}.png").is_file(), name
        assert (hybrid.path / f"{name}.svg").is_file(), name
    out = tmp_path / "compare"
    result = runner.invoke(app, ["plot", str(hybrid.path), str(pitt.path), "-o", str(out)])
    assert result.exit_code == 0, result.output
    assert (out / "fitness.png").is_file() and not (out / "strengths.png").exists()
    result = runner.invoke(app, ["plot", str(pitt.path), "--rule", "3"])
    assert result.exit_code == 1
    assert "--rule picks the rule of one run" in result.output


@pytest.mark.slow
def test_plot_sources_decides_the_figures_from_python(tmp_path: Path) -> None:
    hybrid = _run(tmp_path, "hybrid", "hybrid")
    pitt = _run(tmp_path, "pitt", "pitt")
    assert default_folder([hybrid.path, pitt.path]) == hybrid.path
    one = tmp_path / "one"
    one.mkdir()
    drawn = plot_sources([hybrid.path], one, rule=2)
    assert drawn[0] == ([one / "fitness.png", one / "fitness.svg"], "")
    assert drawn[1] == ([one / "strengths.png", one / "strengths.svg"], " (rule 2)")
    assert {path.stem for paths, _ in drawn[2:] for path in paths} >= {
        "memberships", "rules", "surface", "trajectory"}
    assert all(path.is_file() for paths, _ in drawn for path in paths)
    both = tmp_path / "both"
    both.mkdir()
    assert [note for _, note in plot_sources([hybrid.path, pitt.path], both)] == [""]
    with pytest.raises(FlcError, match="--rule picks the rule of one run"):
        plot_sources([pitt.path], both, rule=3)
    with pytest.raises(FlcError, match="no such file or directory"):
        default_folder([tmp_path / "gone"])
    with pytest.raises(FlcError, match="give run directories, or a single trace CSV"):
        plot_sources([hybrid.path, hybrid.path / "best.yaml"], both)


@pytest.mark.slow
def test_the_fitness_band_stays_inside_the_possible_range(tmp_path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    run = _run(tmp_path, "pitt", "pitt")
    captured: list[object] = []
    original = plt.Axes.fill_between

    def spy(self: object, x: object, low: object, high: object, **kwargs: object) -> object:
        captured.append((np.asarray(low), np.asarray(high)))
        return original(self, x, low, high, **kwargs)

    plt.Axes.fill_between = spy  # type: ignore[method-assign]
    try:
        plot_fitness([run], tmp_path / "fitness.png")
    finally:
        plt.Axes.fill_between = original  # type: ignore[method-assign]
    (low, high), = captured
    # ballchase trial fitness lies in [0, 2); mean + std of a two-peaked population does not
    assert low.min() >= 0.0 and high.max() < 2.0
    metrics = run.metrics()
    assert high.tolist() == [m.best for m in metrics]
    assert low.tolist() == [m.min for m in metrics]


@pytest.mark.slow
def test_controller_figures(tmp_path: Path) -> None:
    handmade = load_behaviour(BEHAVIOURS / "ballchase-handmade.yaml")
    written = plot_controller(handmade, tmp_path, 7, "handmade")
    assert sorted(p.name for p in written) == sorted(
        f"{n}.{s}" for n in ("memberships", "rules", "surface", "trajectory")
        for s in ("png", "svg"))
    svg = (tmp_path / "rules.svg").read_text()
    for command in ("turn_left", "forward", "turn_right"):
        assert command in svg
    assert "pan (deg)" in (tmp_path / "surface.svg").read_text()


@pytest.mark.slow
def test_controllers_without_a_pitch_or_two_inputs(tmp_path: Path) -> None:
    cartpole = load_behaviour(BEHAVIOURS / "cartpole.yaml")
    plot_memberships(cartpole, tmp_path / "m.png")
    plot_rule_table(cartpole, tmp_path / "r.png")  # rules not learned: empty cells
    assert "(none)" in (tmp_path / "r.svg").read_text()
    with pytest.raises(FlcError, match="a control surface needs two inputs"):
        plot_surface(cartpole, tmp_path / "s.png")


@pytest.mark.slow
def test_plot_an_experiment(tmp_path: Path) -> None:
    from flctool.experiment import ExperimentPlan, make_executor, prepare_experiment, write_report

    behaviour = resolve_behaviour(load_behaviour(BEHAVIOURS / "ballchase.yaml"),
                                  {"generations": 3, "population": 4})
    plan = ExperimentPlan("ballchase", ("pitt", "hybrid"), 2, heldout_episodes=10)
    experiment = prepare_experiment(behaviour, plan, tmp_path / "exp")
    experiment.run(make_executor("local"))
    write_report(experiment)
    result = runner.invoke(app, ["plot", str(experiment.path), "--rule", "7"])
    assert result.exit_code == 0, result.output
    assert "strengths.png (rule 7)" in result.output
    for name in ("learning", "heldout", "strengths", "memberships", "rules", "surface",
                 "trajectory"):
        assert (experiment.path / f"{name}.png").read_bytes().startswith(PNG), name
    assert "training episodes (trials)" in (experiment.path / "learning.svg").read_text()
    both = runner.invoke(app, ["plot", str(experiment.path), str(experiment.path)])
    assert both.exit_code == 1 and "one experiment directory at a time" in both.output


@pytest.mark.slow
def test_a_run_that_learned_the_sets_draws_them_over_the_files(tmp_path: Path) -> None:
    behaviour = resolve_behaviour(load_behaviour(BEHAVIOURS / "ballchase.yaml"), {
        "generations": 2, "population": 4, "sets": {"mode": "partition"}})
    run = create_run(behaviour, tmp_path / "run")
    run.train()
    (tmp_path / "figures").mkdir()
    plot_sources([run.path], tmp_path / "figures")
    svg = (tmp_path / "figures" / "memberships.svg").read_text()
    assert "dashed: before learning" in svg
    # one dashed line per set that moved, in the learned set's colour
    learned = load_behaviour(run.path / "best.yaml")
    moved = sum(learned.inputs[n].sets[s] != q for n, v in behaviour.inputs.items()
                for s, q in v.sets.items())
    assert moved > 0 and svg.count("stroke-dasharray") >= moved


def test_learned_sets_that_did_not_move_are_said_so(tmp_path: Path) -> None:
    behaviour = load_behaviour(BEHAVIOURS / "ballchase.yaml")
    plot_memberships(behaviour, tmp_path / "same.png", before=behaviour)
    svg = (tmp_path / "same.svg").read_text()
    assert "no set moved" in svg and "dashed" not in svg
    assert "stroke-dasharray" not in svg
