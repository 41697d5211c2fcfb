"""``flctool learn`` as a user runs it, including a run killed with SIGKILL and resumed."""

from __future__ import annotations

import csv
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from typer.testing import CliRunner

from flctool import load_behaviour
from flctool.behaviour import behaviour_from_data, behaviour_to_data, behaviour_to_yaml
from flctool.cli import app
from flctool.envs.robot_server import RobotServer

from ..conftest import BEHAVIOURS, ROOT, restore_sigint

runner = CliRunner()
BALLCHASE = str(BEHAVIOURS / "ballchase.yaml")


def metrics_without_wall_time(run: Path) -> list[dict[str, str]]:
    with (run / "metrics.csv").open(encoding="utf-8") as handle:
        return [{k: v for k, v in row.items() if k != "wall_time"}
                for row in csv.DictReader(handle)]


def test_learn_writes_a_run_and_a_json_summary(tmp_path: Path) -> None:
    out = tmp_path / "run"
    result = runner.invoke(app, ["learn", BALLCHASE, "--generations", "3", "--seed", "5",
                                 "--learner", "pitt", "--population", "4", "--out", str(out),
                                 "--set", "pitt_crossover=one_point", "--json"])
    summary = json.loads(result.stdout)
    # three generations of four controllers learn nothing a random table does not do
    assert summary["status"] == "not_learned" and result.exit_code == 3, result.output
    assert summary["learner"] == "pitt" and summary["seed"] == 5
    assert summary["generations"] == 3
    assert summary["last"]["episodes"] == 4
    resolved = load_behaviour(out / "behaviour.yaml")
    assert resolved.learning.seed == 5 and resolved.learning.pitt_crossover == "one_point"
    assert load_behaviour(out / "best.yaml").is_deployable


@pytest.mark.slow
def test_learn_reports_progress_and_the_best_controller(tmp_path: Path) -> None:
    out = tmp_path / "run"
    result = runner.invoke(app, ["learn", BALLCHASE, "-g", "2", "-o", str(out)])
    assert result.exit_code == 0, result.output
    assert "finished hybrid (seed 0): 2 generations" in result.stdout
    assert "best.yaml" in result.stdout


@pytest.mark.parametrize(("options", "field"), [
    (["--set", "crossover=1.5"], "learning.crossover"),
    (["--set", "mutation=-0.1"], "learning.mutation"),
    (["--population", "1"], "learning.population"),
    (["--set", "q.temperature=0"], "learning.q.temperature"),
    (["--set", "q.gamma=1.2"], "learning.q.gamma"),
    (["--set", "q.alpha=0"], "learning.q.alpha"),
    (["--learner", "hybird"], "learning.learner"),
    (["--learner", "fuzzy_q", "--set", "exploration.epsilon=2"], "learning.exploration.epsilon"),
    (["--set", "exploration.epsilon=0.2"],  # the section the override made is placed at it
     "command line (--set exploration.epsilon): learning.exploration: 'exploration' is read "
     "by the fuzzy_q learner only; remove it or set learner: fuzzy_q"),
    (["--learner", "fuzzy_q", "--set", "crossover=0.3"], "learning.crossover: 'crossover' is "
     "read by the pitt and hybrid learners, not by fuzzy_q"),
    (["--set", "q.temprature=0.2"], "learning.q.temprature"),
    (["--set", "nonsense"], "--set"),
])
def test_bad_hyperparameters_name_the_field(tmp_path: Path, options: list[str],
                                            field: str) -> None:
    result = runner.invoke(app, ["learn", BALLCHASE, "--out", str(tmp_path / "r"), *options])
    assert result.exit_code == 1
    assert field in " ".join(result.stderr.split())  # as printed, without the line wrapping
    assert "Traceback" not in result.output
    assert not (tmp_path / "r").exists()


def test_learner_error_suggests_the_closest_name(tmp_path: Path) -> None:
    result = runner.invoke(app, ["learn", BALLCHASE, "--learner", "hybird"])
    assert "Did you mean 'hybrid'?" in result.stderr


def test_learner_help_and_errors_list_the_plugins_learners(tmp_path: Path) -> None:
    from flctool.plugins import names

    listed = ", ".join(names("learner"))
    assert listed in runner.invoke(app, ["learn", "--help"]).stdout
    result = runner.invoke(app, ["learn", BALLCHASE, "--learner", "hybird"])
    assert f"use one of: {listed}" in " ".join(result.stderr.split())


def test_switching_learner_drops_the_files_keys_for_the_other_learner(tmp_path: Path) -> None:
    text = (BEHAVIOURS / "ballchase.yaml").read_text().replace(
        "  learner: hybrid\n", "  learner: pitt\n  pitt_crossover: one_point\n  mutation: 0.2\n")
    (tmp_path / "pitt.yaml").write_text(text)
    out = tmp_path / "run"
    result = runner.invoke(app, ["learn", str(tmp_path / "pitt.yaml"), "--learner", "fuzzy_q",
                                 "-g", "1", "-p", "2", "--set", "selection.candidates=0",
                                 "--out", str(out)])
    assert result.exit_code in (0, 3), result.output  # 3: one generation learns little
    learning = load_behaviour(out / "behaviour.yaml").learning
    assert learning.learner == "fuzzy_q"
    assert "pitt_crossover" not in (out / "behaviour.yaml").read_text()


@pytest.mark.slow
def test_resume_refuses_changed_hyperparameters(tmp_path: Path) -> None:
    out = tmp_path / "run"
    assert runner.invoke(app, ["learn", BALLCHASE, "-g", "2", "-o", str(out)]).exit_code == 0
    result = runner.invoke(app, ["learn", "--resume", str(out), "--set", "q.alpha=0.3"])
    assert result.exit_code == 1 and "learning.q.alpha" in result.stderr
    result = runner.invoke(app, ["learn", "--resume", str(out), "--out", str(tmp_path / "x")])
    assert result.exit_code == 1 and "--out" in result.stderr
    result = runner.invoke(app, ["learn", BALLCHASE, "--resume", str(out), "-g", "3",
                                 "--json"])
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout)["generations"] == 3


def test_learn_needs_a_file_or_a_run(tmp_path: Path) -> None:
    result = runner.invoke(app, ["learn"])
    assert result.exit_code == 1 and "--resume" in result.stderr
    result = runner.invoke(app, ["learn", "--resume", str(tmp_path / "nothing")])
    assert result.exit_code == 1 and "no such run directory" in result.stderr


@pytest.mark.slow
def test_a_run_killed_mid_generation_resumes_bit_for_bit(tmp_path: Path) -> None:
    generations = "150"
    options = ["--generations", generations, "--seed", "11", "--json"]
    killed = tmp_path / "killed" / "run"
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    process = subprocess.Popen(
        [sys.executable, "-m", "flctool", "learn", BALLCHASE, *options, "--out", str(killed)],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)
    second = killed / "checkpoints" / "gen-00001.json"
    deadline = time.monotonic() + 60
    while not second.exists() and process.poll() is None and time.monotonic() < deadline:
        time.sleep(0.002)
    process.send_signal(signal.SIGKILL)
    process.wait()
    done = len(list((killed / "checkpoints").glob("gen-*.json")))
    assert 2 <= done < int(generations), "the kill must land in the middle of the run"

    result = runner.invoke(app, ["learn", "--resume", str(killed), "--json"])
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout)["status"] == "finished"

    whole = tmp_path / "whole" / "run"
    result = runner.invoke(app, ["learn", BALLCHASE, *options, "--out", str(whole)])
    assert result.exit_code == 0, result.output
    assert metrics_without_wall_time(killed) == metrics_without_wall_time(whole)
    assert (killed / "best.yaml").read_text() == (whole / "best.yaml").read_text()
    assert (killed / "strengths.csv").read_text() == (whole / "strengths.csv").read_text()


def test_a_behaviour_without_environment_leaves_no_run_directory(tmp_path: Path) -> None:
    text = Path(BALLCHASE).read_text(encoding="utf-8")
    stripped = text.replace("environment:\n  adapter: ballchase-sim\n", "")
    assert stripped != text
    file = tmp_path / "noenv.yaml"
    file.write_text(stripped, encoding="utf-8")
    result = runner.invoke(app, ["learn", str(file), "--out", str(tmp_path / "r")])
    assert result.exit_code == 1 and "no 'environment' section" in result.stderr
    assert not (tmp_path / "r").exists()


@pytest.mark.parametrize("key", ["generations", "learning.generations"])
@pytest.mark.slow
def test_resume_takes_the_new_budget_from_set_as_from_generations(tmp_path: Path,
                                                                  key: str) -> None:
    out = tmp_path / "run"
    assert runner.invoke(app, ["learn", BALLCHASE, "-g", "2", "-p", "4", "-o",
                               str(out)]).exit_code == 0
    result = runner.invoke(app, ["learn", "--resume", str(out), "--set", f"{key}=3",
                                 "--json"])
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout)["generations"] == 3
    assert load_behaviour(out / "behaviour.yaml").learning.generations == 3
    result = runner.invoke(app, ["learn", "--resume", str(out), "--set", f"{key}=5",
                                 "-g", "4"])
    assert result.exit_code == 1 and "ask for different budgets" in result.stderr
    result = runner.invoke(app, ["learn", "--resume", str(out), "--set", f"{key}=many"])
    assert result.exit_code == 1
    assert f"--set {key}" in result.stderr and "learning.generations" in result.stderr


def test_a_failed_run_directory_closes_the_environment_it_opened(tmp_path: Path) -> None:
    server = RobotServer.from_behaviour(load_behaviour(BALLCHASE), idle_timeout=5.0)
    thread = server.serve_in_background(once=True)
    try:
        data = behaviour_to_data(load_behaviour(BALLCHASE))
        data["environment"] = {"adapter": "robot-link", "port": server.port,
                               "connect_timeout": 5, "retries": 0}
        file = tmp_path / "link.yaml"
        file.write_text(behaviour_to_yaml(behaviour_from_data(data)), encoding="utf-8")
        (tmp_path / "full").mkdir()
        (tmp_path / "full" / "x").write_text("x")
        result = runner.invoke(app, ["learn", str(file), "--out", str(tmp_path / "full")])
        assert result.exit_code == 1 and "is not empty" in result.stderr
        thread.join(timeout=5)  # --once: it ends when learn disconnects
        assert not thread.is_alive()
        assert server.connections == 1 and server.stops == ["the client sent stop (close)"]
    finally:
        server.close()
        thread.join(timeout=5)


CARTPOLE = BEHAVIOURS / "cartpole.yaml"


def test_an_environment_error_points_at_the_line_of_the_file(tmp_path: Path) -> None:
    file = tmp_path / "cartpole.yaml"
    file.write_text(CARTPOLE.read_text(encoding="utf-8").replace("id: CartPole-v1",
                                                                 "id: CartPol-v1"))
    line = next(n for n, text in enumerate(file.read_text().splitlines(), 1)
                if "CartPol-v1" in text)
    result = runner.invoke(app, ["learn", str(file), "--out", str(tmp_path / "r")])
    assert result.exit_code == 1
    message = " ".join(result.stderr.split())  # as printed, without the line wrapping
    assert f"{file}:{line}:3: environment.id: Gymnasium cannot make 'CartPol-v1'" in message
    assert message.count("Did you mean") == 1 and "Did you mean 'CartPole-v1'?" in message
    assert not (tmp_path / "r").exists()
    result = runner.invoke(app, ["learn", str(CARTPOLE), "--out", str(tmp_path / "r"),
                                 "--set", "environment.observations.pole_angle=9"])
    assert result.exit_code == 1
    assert ("command line (--set environment.observations.pole_angle): "
            "environment.observations.pole_angle: index 9 is out of range") in (
        " ".join(result.stderr.split()))


@pytest.mark.slow
def test_ctrl_c_leaves_the_run_stopped_and_resumable(tmp_path: Path) -> None:
    run = tmp_path / "run"
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    process = subprocess.Popen(
        [sys.executable, "-m", "flctool", "learn", BALLCHASE, "-g", "100000", "-p", "4",
         "--json", "--out", str(run)],
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=env, text=True,
        preexec_fn=restore_sigint)
    try:
        first = run / "checkpoints" / "gen-00000.json"
        deadline = time.monotonic() + 60
        while not first.exists() and process.poll() is None and time.monotonic() < deadline:
            time.sleep(0.01)
        process.send_signal(signal.SIGINT)
        _, stderr = process.communicate(timeout=60)
        assert process.returncode == 130, stderr
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
    message = " ".join(stderr.split())
    # the run directory is named at the start, the exact resume command at the end
    assert f"in the run directory {run}" in message
    assert f"continue it with: flctool learn --resume {run}" in message
    assert "Traceback" not in stderr
    info = json.loads((run / "run.json").read_text())
    assert info["status"] == "stopped" and info["best"] is not None
    result = runner.invoke(app, ["learn", "--resume", str(run), "-g",
                                 str(info["best"]["generation"] + 2), "--json"])
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout)["status"] == "finished"


@pytest.mark.slow
def test_learn_loads_neither_scipy_nor_numba(tmp_path: Path) -> None:
    """A learning run needs neither: selection's intervals take the t quantile from a table
    and validation runs the training loop's inference (each would add tenths of a second)."""
    probe = ("import runpy, sys\n"
             "sys.argv = ['flctool', *sys.argv[1:]]\n"
             "try:\n"
             "    runpy.run_module('flctool', run_name='__main__')\n"
             "finally:\n"
             "    print(sorted({m.split('.')[0] for m in sys.modules} & {'scipy', 'numba'}),\n"
             "          file=sys.stderr)\n")
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    result = subprocess.run(
        [sys.executable, "-c", probe, "learn", BALLCHASE, "--generations", "2", "--out",
         str(tmp_path / "run"), "--json"],
        capture_output=True, text=True, env=env, check=False)
    assert result.returncode == 0, result.stderr
    assert result.stderr.strip().splitlines()[-1] == "[]"


ACROBOT_FUZZY_Q = ROOT / "benchmarks" / "tasks" / "acrobot-fuzzy-q.yaml"


@pytest.mark.slow
@pytest.mark.parametrize(("seed", "told"), [
    # at temperature 1 the greedy table stops changing at generation 25 while a rule's
    # strengths differ by about 30
    (610, ["exploration locked in: the greedy controller has not changed since generation 25",
           "raise learning.q.temperature towards 30 (with more generations)"]),
    # no exploring episode ever reaches the goal: every one times out at -500
    (611, ["no reward signal: every training episode in the whole run scored the same "
           "(fitness -500)", "exploring one step at a time never reached",
           "Try learning.exploration.hold: zeta"]),
])
def test_a_fuzzy_q_run_that_could_not_learn_by_exploring_is_told_what_to_try(
        tmp_path: Path, seed: int, told: list[str]) -> None:
    """acrobot-fuzzy-q exploring one step at a time (docs/learning.md, "Why fuzzy_q misses
    Acrobot")."""
    out = tmp_path / "run"
    result = runner.invoke(app, ["learn", str(ACROBOT_FUZZY_Q), "--seed", str(seed),
                                 "-o", str(out), "--set", "exploration.hold=1"])
    assert result.exit_code == 0, result.output
    text = " ".join(result.stdout.split())
    for sentence in told:
        assert sentence in text
    record = json.loads((out / "run.json").read_text())["selection"]["exploration"]
    assert record["locked"] == (seed == 610) and record["unrewarded"] == (seed == 611)
    assert record["hold"] == 1


@pytest.mark.slow
def test_held_exploration_finds_the_reward_that_exploring_one_step_at_a_time_missed(
        tmp_path: Path) -> None:
    """acrobot-fuzzy-q seed 611 with ``exploration.hold: auto`` (docs/learning.md, "How long a
    rule holds an explored command"): no episode reached the goal exploring one step at a
    time, so the run held its draws, and its training episodes reached the goal."""
    out = tmp_path / "run"
    result = runner.invoke(app, ["learn", str(ACROBOT_FUZZY_Q), "--seed", "611",
                                 "-o", str(out)])
    assert result.exit_code == 0, result.output
    run = json.loads((out / "run.json").read_text())
    record = run["selection"]["exploration"]
    assert record["hold"] == "auto" and not record["unrewarded"]
    metrics = (out / "metrics.csv").read_text().splitlines()
    last_generation = int(metrics[-1].split(",")[0])
    assert 5 <= record["held_from"] < record["varied_at"] == last_generation
    # a fresh attempt began where the draws began to be held, with room for three
    extension = run["selection"]["extension"]
    assert extension["attempts"][:2] == [0, record["held_from"]]
    assert extension["most"] == record["held_from"] + 3 * 30
    assert "no reward signal:" not in result.stdout  # the warning's label
    assert (f"so from generation {record['held_from']} each rule held the commands it drew"
            in " ".join(result.stdout.split()))
    assert max(float(line.split(",")[3]) for line in metrics[1:]) > -500  # the goal reached


@pytest.mark.slow
def test_a_fuzzy_q_run_whose_episodes_all_balance_to_the_end_is_not_told_anything(
        tmp_path: Path) -> None:
    """CartPole, seed 901: every training episode of its last generations scores the full 500,
    as its greedy controllers do -- the same score, but no lack of signal."""
    out = tmp_path / "run"
    result = runner.invoke(app, ["learn", str(BEHAVIOURS / "cartpole.yaml"), "--seed", "901",
                                 "-o", str(out), "--set", "exploration.hold=1"])
    assert result.exit_code == 0, result.output
    record = json.loads((out / "run.json").read_text())["selection"]["exploration"]
    assert record["fitness"] == 500.0 and record["varied_at"] <= 25
    assert not record["unrewarded"] and not record["locked"]
    assert "no reward signal" not in result.stdout and "locked in" not in result.stdout
