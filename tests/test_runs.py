"""Run directories: files, checkpoints, resume bit for bit, reading controllers back."""

from __future__ import annotations

import csv
import json
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from flctool import compile_behaviour, load_behaviour
from flctool.behaviour import Behaviour
from flctool.errors import RunDirError, SpecError
from flctool.learners import Callback, GenerationMetrics
from flctool.runs import (
    BEST_FILE,
    ENDED,
    METRICS_FILE,
    STRENGTHS_FILE,
    create_run,
    default_run_dir,
    open_run,
    resolve_behaviour,
)

from .conftest import BEHAVIOURS


def ballchase(**learning: object) -> Behaviour:
    return resolve_behaviour(load_behaviour(BEHAVIOURS / "ballchase.yaml"),
                             {"generations": 5, "population": 6, **learning})


class StopAfter(Callback):
    def __init__(self, generation: int) -> None:
        self.generation = generation

    def on_generation(self, metrics: GenerationMetrics) -> bool:
        return metrics.generation < self.generation


def rows(path: Path) -> list[dict[str, str]]:
    with path.open(encoding="utf-8") as handle:
        return list(csv.DictReader(handle))


def without_wall_time(path: Path) -> list[dict[str, str]]:
    return [{k: v for k, v in row.items() if k != "wall_time"} for row in rows(path)]


def test_a_run_writes_every_record(tmp_path: Path) -> None:
    behaviour = ballchase(seed=7)
    run = create_run(behaviour, tmp_path / "run")
    assert load_behaviour(run.path / "behaviour.yaml") == behaviour
    summary = run.train()
    assert summary.status == "finished" and summary.generations == 5
    metrics = rows(run.path / METRICS_FILE)
    assert [int(r["generation"]) for r in metrics] == list(range(5))
    assert list(metrics[0]) == ["generation", "mean", "std", "best", "min", "episodes",
                                "steps", "wall_time", "selection_episodes", "selection_steps",
                                "validated", "confirmation_episodes", "confirmation_steps"]
    assert all(int(r["episodes"]) == 6 for r in metrics)
    strengths = rows(run.path / STRENGTHS_FILE)
    assert len(strengths) == 5 * 15 * 5 and strengths[0]["command"] == "turn_right"
    assert run.checkpoint_generations() == list(range(5))
    checkpoint = run.checkpoint(4)
    assert {"population", "fitness", "q", "traces", "rng", "metrics"} <= set(checkpoint)
    assert set(checkpoint["rng"]) == {"ga", "env", "explore"}
    q = np.array([float(r["q"]) for r in strengths[-75:]]).reshape(15, 5)
    np.testing.assert_array_equal(q, np.array(checkpoint["q"]))
    info = json.loads((run.path / "run.json").read_text())
    assert summary.best is not None
    assert info["status"] == "finished" and info["best"] == summary.best.to_dict()


def test_best_yaml_is_the_deployable_best_validated_candidate(tmp_path: Path) -> None:
    run = create_run(ballchase(), tmp_path / "run")
    run.train()
    best = load_behaviour(run.path / BEST_FILE)
    assert best.is_deployable
    assert (run.path / BEST_FILE).read_text().startswith("# Learned by flctool")
    behaviour, provenance = open_run(run.path).behaviour_for()
    assert behaviour == best
    selection = json.loads((run.path / "run.json").read_text())["selection"]
    # the best of the race's last round, where every finalist met the most episodes
    finalists = [c["validation"] for c in selection["validated"]
                 if c["validation"]["n"] == selection["race"]["rounds"][-1]["episodes"]]
    assert provenance["validation"]["value"] == max(v["value"] for v in finalists)
    assert selection["best"]["validation"] == provenance["validation"]
    state = run.checkpoint(provenance["generation"])
    consequents = compile_behaviour(best).consequents
    assert consequents is not None
    assert consequents.tolist() == state["population"][provenance["individual"]]


def test_without_selection_best_yaml_is_the_best_of_the_last_generation(
        tmp_path: Path) -> None:
    behaviour = resolve_behaviour(ballchase(), {"selection.candidates": 0})
    run = create_run(behaviour, tmp_path / "run")
    run.train()
    behaviour, provenance = open_run(run.path).behaviour_for()
    state = run.checkpoint(4)
    confirmation = provenance.pop("confirmation")
    assert provenance == {"learner": "hybrid", "seed": 0, "generation": 4,
                          "individual": int(np.argmax(state["fitness"])),
                          "fitness": max(state["fitness"])}
    # without selection the figure read is still a fresh one
    assert confirmation["generation"] == 4 and confirmation["episodes"] == 50
    assert all(int(r["selection_episodes"]) == 0 for r in rows(run.path / METRICS_FILE))


def test_behaviour_for_picks_any_generation_and_individual(tmp_path: Path) -> None:
    run = create_run(ballchase(learner="pitt"), tmp_path / "run")
    run.train()
    assert not (run.path / STRENGTHS_FILE).exists()
    behaviour, provenance = run.behaviour_for(generation=1, individual=3)
    assert provenance["generation"] == 1 and provenance["individual"] == 3
    assert provenance["fitness"] == run.checkpoint(1)["fitness"][3]
    assert compile_behaviour(behaviour).consequents.tolist() == (  # type: ignore[union-attr]
        run.checkpoint(1)["population"][3])
    assert run.behaviour_for(generation=-1)[1]["generation"] == 4
    with pytest.raises(RunDirError, match=r"no generation 9.*0\.\.4"):
        run.behaviour_for(generation=9)
    with pytest.raises(RunDirError, match=r"individuals 0\.\.5, not 6"):
        run.behaviour_for(individual=6)


@pytest.mark.parametrize("learner", ["pitt", "fuzzy_q", "hybrid"])
@pytest.mark.slow
def test_resume_ends_where_an_uninterrupted_run_ends(tmp_path: Path, learner: str) -> None:
    behaviour = ballchase(learner=learner, seed=3, generations=6)
    whole = create_run(behaviour, tmp_path / "a" / "run")
    whole.train()
    part = create_run(behaviour, tmp_path / "b" / "run")
    assert part.train([StopAfter(2)]).status == "stopped"
    # as if killed during generation 3: its checkpoint never appeared, rows half written
    with (part.path / METRICS_FILE).open("a") as handle:
        handle.write("3,0.5,0.1,")
    resumed = open_run(part.path).train()
    assert resumed.status == "finished" and resumed.generations == 6
    assert without_wall_time(part.path / METRICS_FILE) == without_wall_time(
        whole.path / METRICS_FILE)
    assert (part.path / BEST_FILE).read_text() == (whole.path / BEST_FILE).read_text()
    if learner != "pitt":
        assert rows(part.path / STRENGTHS_FILE) == rows(whole.path / STRENGTHS_FILE)
    a, b = part.checkpoint(5), whole.checkpoint(5)
    for state in (a, b):
        state.pop("elapsed"), state["metrics"].pop("wall_time")
    assert a == b


#: What versions with one flat ``learning:`` model wrote for the keys a learner does not read.
EARLIER_DEFAULTS = {"crossover": 0.2, "mutation": 0.1, "pitt_crossover": "uniform",
                    "elites": 1, "common_starts": False,
                    "q": {"alpha": 0.1, "gamma": 0.9, "lambda": 0.7, "temperature": 0.15,
                          "initial": 0.0},
                    "exploration": {"policy": "boltzmann", "epsilon": 0.1, "decay": 1.0,
                                    "minimum": 0.0}}


def as_an_earlier_version_wrote_it(path: Path) -> None:
    """Rewrite the behaviour file ``path`` with every learning key of every learner."""
    text = path.read_text(encoding="utf-8")
    header = "".join(line + "\n" for line in text.splitlines() if line.startswith("#"))
    data = yaml.safe_load(text)
    data["learning"] = {**EARLIER_DEFAULTS, **data["learning"]}
    path.write_text(header + yaml.safe_dump(data, sort_keys=False), encoding="utf-8")


@pytest.mark.parametrize("learner", ["pitt", "fuzzy_q", "hybrid"])
@pytest.mark.slow
def test_a_run_an_earlier_version_recorded_still_resumes(tmp_path: Path, learner: str) -> None:
    behaviour = ballchase(learner=learner, seed=3, generations=4)
    whole = create_run(behaviour, tmp_path / "a" / "run")
    whole.train()
    part = create_run(behaviour, tmp_path / "b" / "run")
    part.train([StopAfter(1)])
    for name in ("behaviour.yaml", BEST_FILE):
        as_an_earlier_version_wrote_it(part.path / name)
        assert "pitt_crossover" in (part.path / name).read_text()
    assert load_behaviour(part.path / BEST_FILE).learning.learner == learner
    reopened = open_run(part.path)
    assert reopened.behaviour == behaviour
    assert reopened.train().status in ENDED
    assert without_wall_time(part.path / METRICS_FILE) == without_wall_time(
        whole.path / METRICS_FILE)
    assert (part.path / BEST_FILE).read_text() == (whole.path / BEST_FILE).read_text()


@pytest.mark.slow
def test_resume_can_extend_a_finished_run(tmp_path: Path) -> None:
    run = create_run(ballchase(generations=3), tmp_path / "run")
    run.train()
    again = open_run(run.path)
    again.extend(5)
    assert load_behaviour(run.path / "behaviour.yaml").learning.generations == 5
    assert again.train().generations == 5
    with pytest.raises(RunDirError, match="would not add any"):
        again.extend(4)


def test_run_directory_errors(tmp_path: Path) -> None:
    (tmp_path / "full").mkdir()
    (tmp_path / "full" / "x").write_text("x")
    with pytest.raises(RunDirError, match="not empty"):
        create_run(ballchase(), tmp_path / "full")
    with pytest.raises(RunDirError, match="no such run directory"):
        open_run(tmp_path / "missing")
    with pytest.raises(RunDirError, match="not a run directory"):
        open_run(tmp_path / "full")
    run = create_run(ballchase(), tmp_path / "empty")
    with pytest.raises(RunDirError, match="no finished generation"):
        run.behaviour_for()
    handmade = load_behaviour(BEHAVIOURS / "ballchase-handmade.yaml")
    no_env = handmade.model_copy(update={"environment": None})
    with pytest.raises(RunDirError, match="no 'environment' section"):
        create_run(no_env, tmp_path / "noenv")


def test_default_run_dir_names_the_run(tmp_path: Path) -> None:
    path = default_run_dir(ballchase(seed=4, learner="pitt"), tmp_path)
    assert path.parent == tmp_path and path.name.startswith("ballchase-pitt-seed4-")
    path.mkdir()
    assert default_run_dir(ballchase(seed=4, learner="pitt"), tmp_path) != path


def test_overrides_are_validated_like_the_file() -> None:
    behaviour = ballchase()
    changed = resolve_behaviour(behaviour, {"q.temperature": 0.2,
                                            "environment.max_steps": 50})
    assert changed.learning.q.temperature == 0.2
    assert changed.environment is not None and changed.environment.max_steps == 50
    assert resolve_behaviour(behaviour, {"q.lambda": 0.3}).learning.q.lambda_ == 0.3
    with pytest.raises(SpecError, match=r"learning\.q\.gamma"):
        resolve_behaviour(behaviour, {"q.gamma": 1.5})
    with pytest.raises(SpecError, match=r"learning\.seed.*not a section"):
        resolve_behaviour(behaviour, {"seed.x": 1})
    with pytest.raises(SpecError, match="unknown key 'temprature'"):
        resolve_behaviour(behaviour, {"q.temprature": 1})


class Crash(Callback):
    def __init__(self, generation: int, error: BaseException) -> None:
        self.generation, self.error = generation, error

    def on_generation(self, metrics: GenerationMetrics) -> bool:
        if metrics.generation == self.generation:
            raise self.error
        return True


@pytest.mark.parametrize("error", [RuntimeError("boom"), KeyboardInterrupt()])
def test_a_crashed_or_interrupted_run_is_recorded_as_stopped(tmp_path: Path,
                                                             error: BaseException) -> None:
    run = create_run(ballchase(learner="pitt"), tmp_path / "run")
    with pytest.raises(type(error)):
        run.train([Crash(2, error)])
    info = json.loads((run.path / "run.json").read_text())
    assert info["status"] == "stopped" and info["best"]["generation"] == 2
    assert open_run(run.path).train().status == "finished"


def test_a_stop_between_checkpoint_and_best_yaml_still_names_the_checkpoint_s_best(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # Ctrl-C may land after a generation's checkpoint is written but before best.yaml is:
    # the run must still describe its last checkpoint, as an uninterrupted run would.
    from flctool import runs

    real_append = runs._append
    calls = {"n": 0}

    def interrupted_append(root: Path, path: Path, text: str) -> None:
        calls["n"] += 1
        if calls["n"] == 3:  # generation 2's metrics row, right after its checkpoint
            raise KeyboardInterrupt
        real_append(root, path, text)

    monkeypatch.setattr(runs, "_append", interrupted_append)
    run = create_run(ballchase(learner="pitt"), tmp_path / "run")
    with pytest.raises(KeyboardInterrupt):
        run.train()
    monkeypatch.setattr(runs, "_append", real_append)
    info = json.loads((run.path / "run.json").read_text())
    assert info["status"] == "stopped"
    _, provenance = open_run(run.path).behaviour_for()
    assert provenance["generation"] == 2 and info["best"] == provenance
    assert f"generation {provenance['generation']}," in (run.path / "best.yaml").read_text()


def write_checkpoint(run_path: Path, generation: int, data: object) -> Path:
    path = run_path / "checkpoints" / f"gen-{generation:05d}.json"
    path.write_text(json.dumps(data))
    return path


@pytest.mark.parametrize(("damage", "message"), [
    (lambda state: [state], "the checkpoint holds a JSON list, not an object"),
    (lambda state: {k: v for k, v in state.items() if k != "metrics"},
     "the checkpoint has no 'metrics'"),
    (lambda state: {**state, "metrics": {"generation": 2}}, "the checkpoint is damaged"),
    (lambda state: {**state, "generation": 1}, "the checkpoint is of generation 1, not 2"),
    (lambda state: {**state, "population": [[9] * 15] * 6},
     r"its population holds command indices 9\.\.9, outside 0\.\.4"),
    (lambda state: {**state, "q": [[0.0]]}, r"'q' table has shape \(1, 1\)"),
    (lambda state: {**state, "traces": []}, r"'traces' table has shape \(0,\)"),
    (lambda state: {**state, "rng": {}}, "no state of the random generator"),
])
@pytest.mark.slow
def test_a_damaged_checkpoint_names_its_file_and_how_to_get_past_it(
        tmp_path: Path, damage: Callable[[dict[str, Any]], object], message: str) -> None:
    run = create_run(ballchase(generations=3), tmp_path / "run")
    run.train([StopAfter(2)])
    path = write_checkpoint(run.path, 2, damage(run.checkpoint(2)))
    with pytest.raises(RunDirError, match=message) as caught:
        open_run(run.path).train()
    assert str(caught.value).startswith(f"{path}: ")
    assert caught.value.hint == f"delete {path} to resume from generation 1"
    path.unlink()
    assert open_run(run.path).train().status == "finished"


def test_a_damaged_earlier_checkpoint_says_to_delete_the_later_ones_too(
        tmp_path: Path) -> None:
    run = create_run(ballchase(generations=3), tmp_path / "run")
    run.train()
    path = write_checkpoint(run.path, 0, {"learner": "hybrid"})
    with pytest.raises(RunDirError, match=r"gen-00000\.json: the checkpoint has no "
                                          r"'generation', 'elapsed'") as caught:
        run.metrics()
    assert caught.value.hint == (f"delete {path} and the checkpoints after it to start the "
                                 "run again from generation 0")
    with pytest.raises(RunDirError, match="gen-00000"):
        run.behaviour_for(generation=0)


@pytest.mark.parametrize(("damage", "message"), [
    (lambda state: {**state, "selection": {**state["selection"], "best": {
        **state["selection"]["best"], "consequents": [7] * 15}}},
     "selection record holds a controller that is not one of this behaviour"),
    (lambda state: {**state, "fitness": [1e400] * len(state["fitness"])},
     "its 'fitness' holds NaN or infinity"),
    (lambda state: {**state, "population": [[2**70] * 15] * len(state["population"])},
     "its 'population' is not a table of whole numbers"),
])
def test_every_reader_of_a_run_refuses_a_damaged_checkpoint_alike(
        tmp_path: Path, damage: Callable[[dict[str, Any]], object], message: str) -> None:
    # One validation (flctool.learners.checkpoint) behind the summary, the best controller
    # and the resume: each names the file and the same problem.
    run = create_run(ballchase(generations=3), tmp_path / "run")
    run.train([StopAfter(1)])
    path = write_checkpoint(run.path, 1, damage(run.checkpoint(1)))
    for read in (lambda: open_run(run.path).behaviour_for(), lambda: open_run(run.path).train()):
        with pytest.raises(RunDirError, match=message) as caught:
            read()
        assert str(caught.value).startswith(f"{path}: ")


def test_a_resume_needs_the_q_table_of_a_learner_with_strengths(tmp_path: Path) -> None:
    run = create_run(ballchase(generations=3), tmp_path / "run")  # hybrid keeps a q table
    run.train([StopAfter(1)])
    state = run.checkpoint(1)
    path = write_checkpoint(run.path, 1, {k: v for k, v in state.items() if k != "q"})
    assert open_run(run.path).behaviour_for()[1]["generation"] == 1  # needs no q table
    with pytest.raises(RunDirError, match=r"the checkpoint has no 'q' table of shape "
                                          r"\(rules, commands\) = \(15, 5\)") as caught:
        open_run(run.path).train()
    assert str(caught.value).startswith(f"{path}: ")


def test_a_damaged_earlier_q_table_is_found_when_the_tables_are_rebuilt(
        tmp_path: Path) -> None:
    run = create_run(ballchase(generations=3), tmp_path / "run")
    run.train([StopAfter(1)])
    path = write_checkpoint(run.path, 0, {**run.checkpoint(0), "q": [[0.0]]})
    with pytest.raises(RunDirError, match=r"gen-00000\.json: the checkpoint is damaged: its "
                                          r"'q' table has shape \(1, 1\), not \(rules, "
                                          r"commands\) = \(15, 5\)"):
        open_run(run.path).train()
    assert json.loads((run.path / "run.json").read_text())["status"] == "stopped"
    assert path.exists()


def test_bookkeeping_snapshots_best_and_syncs_only_at_intervals_and_the_end(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # The policy of RunRecorder: a checkpoint every generation; best.yaml, run.json and an
    # fsync at most every SNAPSHOT_SECONDS and at the end; the end state is the same.
    import os

    from flctool import runs

    every = create_run(ballchase(learner="pitt", seed=3), tmp_path / "every")
    monkeypatch.setattr(runs, "SNAPSHOT_SECONDS", 0.0)
    every.train()
    synced: list[int] = []
    real_fsync = os.fsync
    monkeypatch.setattr(os, "fsync", lambda fd: synced.append(fd) or real_fsync(fd))
    monkeypatch.setattr(runs, "SNAPSHOT_SECONDS", 1e9)
    written: list[Path] = []
    real_best = runs.RunRecorder._write_best

    def counting_best(recorder: runs.RunRecorder, *args: Any) -> None:
        written.append(recorder.run.path)
        real_best(recorder, *args)

    monkeypatch.setattr(runs.RunRecorder, "_write_best", counting_best)
    rarely = create_run(ballchase(learner="pitt", seed=3), tmp_path / "rarely")
    rarely.train()
    assert rarely.checkpoint_generations() == list(range(5))
    assert len(written) == 1  # at the end, not after each of the 5 generations
    # behaviour.yaml at creation; at the end the last checkpoint, best.yaml and run.json
    assert len(synced) == 4
    for name in (BEST_FILE, METRICS_FILE, "run.json"):
        expected = (every.path / name).read_text().replace("every", "rarely")
        if name == METRICS_FILE:
            assert without_wall_time(rarely.path / name) == without_wall_time(every.path / name)
        else:
            assert (rarely.path / name).read_text() == expected


def test_a_run_stopped_between_snapshots_keeps_every_generation(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from flctool import runs

    monkeypatch.setattr(runs, "SNAPSHOT_SECONDS", 1e9)
    run = create_run(ballchase(learner="hybrid"), tmp_path / "run")

    class Crash(Callback):
        def on_generation(self, metrics: GenerationMetrics) -> bool:
            if metrics.generation == 2:
                raise KeyboardInterrupt
            return True

    with pytest.raises(KeyboardInterrupt):
        run.train([Crash()])
    assert run.checkpoint_generations() == [0, 1, 2]
    assert [int(r["generation"]) for r in rows(run.path / METRICS_FILE)] == [0, 1, 2]
    _, provenance = open_run(run.path).behaviour_for()
    assert f"generation {provenance['generation']}," in (run.path / BEST_FILE).read_text()


# -- hostile run directories -----------------------------------------------------------------
def _stopped_run(tmp_path: Path, generations: int = 2) -> Path:
    """A pitt run stopped after ``generations`` generations (of 5)."""
    run = create_run(ballchase(learner="pitt"), tmp_path / "run")
    run.train([StopAfter(generations - 1)])
    return run.path


def test_a_resume_while_the_run_trains_is_refused(tmp_path: Path) -> None:
    path = _stopped_run(tmp_path)
    training = open_run(path)
    with training.lock():
        assert json.loads((path / "run.json").read_text())["status"] == "stopped"
        with pytest.raises(RunDirError, match=r"being trained by another flctool process "
                           r"\(pid \d+\)"):
            open_run(path).train()
        with pytest.raises(RunDirError, match="being trained"):
            open_run(path).extend(9)
    assert open_run(path).train().status == "finished"  # once the lock is free


def test_a_run_json_left_running_reads_as_stopped_without_the_lock(tmp_path: Path) -> None:
    path = _stopped_run(tmp_path)
    info = json.loads((path / "run.json").read_text())
    (path / "run.json").write_text(json.dumps({**info, "status": "running"}))
    run = open_run(path)
    assert run.info()["status"] == "stopped"
    with run.lock():
        assert run.info()["status"] == "running"


@pytest.mark.parametrize("planted", ["metrics.csv", "best.yaml", "run.json", "checkpoints",
                                     "checkpoints/gen-00002.json"])
def test_a_link_planted_in_a_run_is_never_written_through(tmp_path: Path,
                                                          planted: str) -> None:
    path = _stopped_run(tmp_path)
    outside = tmp_path / "outside"
    outside.mkdir()
    victim = outside / "victim.txt"
    victim.write_text("precious\n")
    link = path / planted
    if planted == "checkpoints":
        for child in link.iterdir():
            (outside / child.name).write_bytes(child.read_bytes())
        for child in list(link.iterdir()):
            child.unlink()
        link.rmdir()
        link.symlink_to(outside, target_is_directory=True)
    else:
        link.unlink(missing_ok=True)
        link.symlink_to(victim)
    before = {p.name: p.read_bytes() for p in outside.iterdir()}
    with pytest.raises(RunDirError, match="symbolic link"):
        open_run(path).train()
    assert {p.name: p.read_bytes() for p in outside.iterdir()} == before


@pytest.mark.parametrize(("code", "hint"), [
    (28, "free some disk space, then continue with flctool learn --resume"),  # ENOSPC
    (13, "writable"),  # EACCES
    (30, "writable"),  # EROFS
])
def test_a_failing_disk_is_one_clear_error_and_the_run_is_not_left_running(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, code: int, hint: str) -> None:
    import os

    from flctool import runs

    path = _stopped_run(tmp_path)
    real = runs.write_text_atomic

    def failing(target: Path, text: str, **options: Any) -> None:
        if Path(target).parent.name == "checkpoints":
            raise OSError(code, os.strerror(code), str(target))
        real(target, text, **options)

    monkeypatch.setattr(runs, "write_text_atomic", failing)
    with pytest.raises(RunDirError) as info:
        open_run(path).train()
    assert os.strerror(code) in str(info.value) and hint in info.value.hint
    assert info.value.__cause__ is None
    assert json.loads((path / "run.json").read_text())["status"] == "stopped"
    monkeypatch.undo()
    assert open_run(path).train().generations == 5  # nothing lost: resume continues


def test_run_json_is_rewritten_in_place_when_no_copy_fits(tmp_path: Path,
                                                         monkeypatch: pytest.MonkeyPatch) -> None:
    from flctool import runs

    path = _stopped_run(tmp_path)

    def full(target: Path, text: str, **options: Any) -> None:
        raise OSError(28, "No space left on device", str(target))

    monkeypatch.setattr(runs, "write_text_atomic", full)
    run = open_run(path)
    run.write_info("stopped", {"fitness": 1.0})
    assert json.loads((path / "run.json").read_text())["best"] == {"fitness": 1.0}
    with pytest.raises(RunDirError, match="No space left on device"):
        run.write_info("running", None)


def test_stale_temporary_files_of_a_killed_writer_are_removed(tmp_path: Path) -> None:
    path = _stopped_run(tmp_path)
    stale = [path / ".metrics.csv.deadbeef.tmp",
             path / "checkpoints" / ".gen-00002.json.0123abcd.tmp"]
    for file in stale:
        file.write_text("half a file")
    keep = path / "notes.tmp"
    keep.write_text("mine")
    open_run(path).train()
    assert not any(file.exists() for file in stale) and keep.exists()


def _tamper(path: Path, change: Callable[[dict[str, Any]], Any]) -> None:
    checkpoint = path / "checkpoints" / "gen-00001.json"
    state = json.loads(checkpoint.read_text())
    result = change(state)
    checkpoint.write_text(result if isinstance(result, str) else json.dumps(state))


@pytest.mark.parametrize(("change", "message"), [
    (lambda s: s.update(fitness=[math.nan, *s["fitness"][1:]]),
     "its 'fitness' holds NaN or infinity"),
    (lambda s: s.update(fitness=[math.inf, *s["fitness"][1:]]),
     "its 'fitness' holds NaN or infinity"),
    (lambda s: s.update(elapsed=math.inf), "its 'elapsed' is not a finite number"),
    (lambda s: json.dumps({**s, "elapsed": "[" * 100_000 + "]" * 100_000}).replace(
        '"' + "[" * 100_000, "[" * 100_000).replace("]" * 100_000 + '"', "]" * 100_000),
     "nested too deep"),
    (lambda s: s["rng"]["ga"]["state"].update(state=10 ** 200),
     "integer outside [0, 2^128)"),
    (lambda s: s.update(population=s["population"] * 20_000, fitness=s["fitness"] * 20_000),
     "holds 120,000 individuals, more than the run's population of 6"),
])
@pytest.mark.slow
def test_a_tampered_checkpoint_is_refused_clearly(tmp_path: Path, change: Any,
                                                  message: str) -> None:
    path = _stopped_run(tmp_path)
    _tamper(path, change)
    with pytest.raises(RunDirError) as info:
        open_run(path).train()
    assert "gen-00001.json" in str(info.value) and message in str(info.value)
    assert "delete" in info.value.hint
