"""Experiment directories: plans, jobs, held-out tests, and resuming a killed experiment."""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import Any

import pytest

from flctool import load_behaviour
from flctool.errors import RunDirError
from flctool.experiment import (
    Experiment,
    ExperimentPlan,
    open_experiment,
    parse_learners,
    write_report,
)
from flctool.experiment.executors import LocalExecutor
from flctool.experiment.runner import HELDOUT_FILE, JobOutcome, prepare_experiment, run_job
from flctool.rollout import evaluation_seeds
from flctool.runs import ENDED, open_run

from .helpers import tiny_experiment

Finished = tuple[Experiment, list[JobOutcome], dict[str, Any]]


@pytest.fixture(scope="module")
def finished(tmp_path_factory: pytest.TempPathFactory) -> Finished:
    """The tiny experiment run to its end once for this module: the experiment, its jobs'
    outcomes and its report."""
    experiment = tiny_experiment(tmp_path_factory.mktemp("finished") / "exp")
    outcomes = experiment.run(LocalExecutor(1))
    return experiment, outcomes, write_report(experiment)


@pytest.mark.slow
def test_every_learner_on_every_seed(finished: Finished) -> None:
    experiment, outcomes, _ = finished
    assert [(o.learner, o.seed) for o in outcomes] == [
        (learner, seed) for learner in ("pitt", "hybrid", "fuzzy_q") for seed in (0, 1)]
    assert not any(o.skipped for o in outcomes)
    for learner, seed, directory in experiment.run_dirs():
        run = open_run(directory)
        assert (run.learner, run.seed) == (learner, seed)
        assert run.info()["status"] in ENDED
        assert len(run.metrics()) == 3
        heldout = json.loads((directory / HELDOUT_FILE).read_text())
        assert heldout["episodes"] == 20
        assert heldout["successes"] == round(heldout["success_rate"] * 20)


@pytest.mark.slow
def test_heldout_episodes_are_the_ones_flctool_evaluate_runs(tmp_path: Path) -> None:
    from flctool.compile import compile_behaviour
    from flctool.envs import make_env
    from flctool.rollout import evaluate

    experiment = tiny_experiment(tmp_path / "exp", seeds=1, learners=("hybrid",))
    experiment.run(LocalExecutor(1))
    directory = experiment.runs_dir / "hybrid-seed0"
    best = load_behaviour(directory / "best.yaml")
    result = evaluate(compile_behaviour(best), make_env(best, 20), evaluation_seeds(0, 20))
    heldout = json.loads((directory / HELDOUT_FILE).read_text())
    assert heldout["successes"] == int(result.success.sum())
    assert heldout["steps"] == int(result.lengths.sum())
    # never a training seed: training starts at 2**32
    assert evaluation_seeds(0, 20).max() < 2**32


@pytest.mark.slow
def test_a_killed_experiment_continues_without_redoing_finished_runs(
        tmp_path: Path, finished: Finished) -> None:
    whole, _, expected = finished
    shutil.copytree(whole.path, tmp_path / "killed")
    killed = open_experiment(tmp_path / "killed")
    # As a kill leaves it: one run stopped after its first generation, one run trained but
    # not yet tested, the rest finished.
    stopped = killed.runs_dir / "hybrid-seed1"
    for name in ("gen-00001.json", "gen-00002.json"):
        (stopped / "checkpoints" / name).unlink()
    info = json.loads((stopped / "run.json").read_text())
    (stopped / "run.json").write_text(json.dumps({**info, "status": "stopped"}))
    (killed.runs_dir / "pitt-seed0" / HELDOUT_FILE).unlink()
    finished = killed.runs_dir / "fuzzy_q-seed0" / "checkpoints" / "gen-00002.json"
    stamp = finished.stat().st_mtime_ns

    seen: list[JobOutcome] = []
    reopened = open_experiment(tmp_path / "killed")
    reopened.run(LocalExecutor(1), seen.append)
    redone = {(o.learner, o.seed) for o in seen if not o.skipped}
    assert redone == {("hybrid", 1), ("pitt", 0)}
    assert finished.stat().st_mtime_ns == stamp
    assert len(open_run(stopped).metrics()) == 3
    assert write_report(reopened) == expected


def test_the_same_plan_continues_and_another_is_refused(tmp_path: Path) -> None:
    experiment = tiny_experiment(tmp_path / "exp")
    again = tiny_experiment(tmp_path / "exp")
    assert again.plan == experiment.plan
    with pytest.raises(RunDirError, match=r"different plan.*seeds"):
        tiny_experiment(tmp_path / "exp", seeds=3)
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "file.txt").write_text("x")
    with pytest.raises(RunDirError, match="not an experiment directory"):
        tiny_experiment(tmp_path / "other")
    with pytest.raises(RunDirError, match=r"no experiment\.json"):
        open_experiment(tmp_path)


def test_plan_round_trips() -> None:
    plan = ExperimentPlan("b", ("pitt", "hybrid"), 4, 100, 3, {"generations": 5})
    assert ExperimentPlan.from_dict(json.loads(json.dumps(plan.to_dict()))) == plan


def test_learner_lists() -> None:
    assert parse_learners(" pitt, hybrid ") == ("pitt", "hybrid")
    with pytest.raises(RunDirError, match=r"unknown learner.*pit"):
        parse_learners("pit,hybrid")
    with pytest.raises(RunDirError, match="twice"):
        parse_learners("pitt,pitt")
    with pytest.raises(RunDirError, match="no learner"):
        parse_learners(",")


def test_run_job_reads_a_finished_job_back(tmp_path: Path) -> None:
    experiment = tiny_experiment(tmp_path / "exp", seeds=1, learners=("pitt",))
    job = experiment.jobs()[0]
    first = run_job(job, tmp_path / "run")
    second = run_job(job, tmp_path / "run")
    assert not first.skipped and second.skipped
    assert first.heldout_success == second.heldout_success


def test_a_damaged_heldout_file_names_itself(tmp_path: Path) -> None:
    experiment = tiny_experiment(tmp_path / "exp", seeds=1, learners=("pitt",))
    experiment.run(LocalExecutor(1))
    (experiment.runs_dir / "pitt-seed0" / HELDOUT_FILE).write_text("{")
    with pytest.raises(RunDirError, match=r"heldout\.json cannot be read") as info:
        experiment.run(LocalExecutor(1))
    assert "delete" in info.value.hint


def test_prepare_refuses_an_unwritable_place(tmp_path: Path) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("x")
    experiment = tiny_experiment(tmp_path / "exp", seeds=1)
    with pytest.raises(RunDirError, match="not an experiment directory"):
        prepare_experiment(experiment.behaviour, experiment.plan, blocker)


@pytest.mark.slow
def test_a_run_killed_while_being_created_starts_over(tmp_path: Path) -> None:
    experiment = tiny_experiment(tmp_path / "exp", seeds=1, learners=("pitt",))
    job = experiment.jobs()[0]
    directory = experiment.runs_dir / job.name
    (directory / "checkpoints").mkdir(parents=True)  # what create_run makes first
    (directory / ".behaviour.yaml.0123abcd.tmp").write_text("half")
    assert not run_job(job, directory).skipped
    assert open_run(directory).info()["status"] == "finished"


@pytest.mark.slow
def test_a_killed_command_continues_where_it_stopped(tmp_path: Path) -> None:
    """SIGKILL the command mid-way (no chance to clean up), then run it again."""
    import os
    import signal
    import subprocess
    import sys
    import time

    from ..conftest import BEHAVIOURS

    out = tmp_path / "killed"
    command = [sys.executable, "-m", "flctool", "experiment", str(BEHAVIOURS / "ballchase.yaml"),
               "--seeds", "3", "--learners", "hybrid,pitt", "--set", "generations=12",
               "--set", "population=4", "--heldout", "20", "--json", "--out", str(out)]
    process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 120
        while len(list(out.glob("runs/*/heldout.json"))) < 2:
            assert process.poll() is None, "the experiment ended before it could be killed"
            assert time.monotonic() < deadline
            time.sleep(0.05)
        os.kill(process.pid, signal.SIGKILL)
    finally:
        process.wait()
    finished = {p.parent.name: p.stat().st_mtime_ns for p in out.glob("runs/*/heldout.json")}
    assert 2 <= len(finished) < 6
    result = subprocess.run(command, capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    # finished runs were read back, not redone
    for name, stamp in finished.items():
        assert (out / "runs" / name / "heldout.json").stat().st_mtime_ns == stamp
    whole = prepare_experiment(open_experiment(out).behaviour, open_experiment(out).plan,
                               tmp_path / "whole")
    whole.run(LocalExecutor(1))
    write_report(whole)
    assert (out / "report.md").read_text() == (whole.path / "report.md").read_text()


def test_a_second_process_on_the_same_experiment_is_refused(tmp_path: Path) -> None:
    """Like a run, an experiment is run by one process at a time: the second would run the
    same unfinished jobs."""
    from flctool.dirlock import DirectoryLock
    from flctool.experiment.runner import LOCK_FILE

    experiment = tiny_experiment(tmp_path / "exp")
    holder = DirectoryLock(experiment.path / LOCK_FILE)
    assert holder.acquire()  # another process, as flock sees it: another open file
    try:
        with pytest.raises(RunDirError, match=r"being run by another flctool process "
                           r"\(pid \d+\)") as info:
            experiment.run(LocalExecutor(1))
        assert "run the same command again" in info.value.hint
        assert not (experiment.path / "runs").exists()  # nothing was started
    finally:
        holder.release()


def test_an_experiment_lock_planted_as_a_link_is_refused(tmp_path: Path) -> None:
    from flctool.experiment.runner import LOCK_FILE

    experiment = tiny_experiment(tmp_path / "exp")
    victim = tmp_path / "victim.txt"
    victim.write_text("precious\n")
    (experiment.path / LOCK_FILE).symlink_to(victim)
    with pytest.raises(RunDirError, match="cannot lock"):
        experiment.run(LocalExecutor(1))
    assert victim.read_text() == "precious\n"
