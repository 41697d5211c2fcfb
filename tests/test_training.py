"""Starting and resuming runs from Python: what ``flctool learn`` decides, without the CLI."""

from __future__ import annotations

from pathlib import Path

import pytest

from flctool import SpecError, load_behaviour
from flctool.behaviour.overrides import Override
from flctool.cli.app import command_line_overrides
from flctool.errors import RunDirError
from flctool.training import resume_run, start_run

from .conftest import BEHAVIOURS

BALLCHASE = BEHAVIOURS / "ballchase.yaml"
TINY = {"population": 4, "seed": 2}


def test_command_line_assignments_read_values_as_yaml_and_say_where_they_were_given() -> None:
    overrides = command_line_overrides(["q.temperature=0.2", "common_starts=true",
                                        "name=[oops", "empty="], {"seed": ("--seed", 3),
                                                                  "population": ("-p", None)})
    assert {o.key: o.value for o in overrides} == {
        "q.temperature": 0.2, "common_starts": True, "name": "[oops", "empty": "", "seed": 3}
    assert overrides[0].where == "command line (--set q.temperature)"
    assert overrides[-1].where == "command line (--seed)"
    with pytest.raises(SpecError, match="'nonsense' is not key=value"):
        command_line_overrides(["nonsense"])


@pytest.mark.slow
def test_a_run_started_and_resumed_equals_one_run_straight(tmp_path: Path) -> None:
    training = start_run(BALLCHASE, {**TINY, "generations": 2}, tmp_path / "parts")
    assert not training.resumed and training.done == 0
    assert training.train().generations == 2
    resumed = resume_run(tmp_path / "parts", generations=3)
    assert resumed.resumed and resumed.done == 2
    assert resumed.run.behaviour.learning.generations == 3
    assert resumed.train().status == "finished"
    straight = start_run(load_behaviour(BALLCHASE), {**TINY, "generations": 3},
                         tmp_path / "straight")
    straight.train()
    # the same controller (read from two files: equal whatever file each came from)
    assert load_behaviour(tmp_path / "parts" / "best.yaml") == load_behaviour(
        tmp_path / "straight" / "best.yaml")


def test_a_resumed_run_continues_only_as_recorded(tmp_path: Path) -> None:
    start_run(BALLCHASE, {**TINY, "generations": 1}, tmp_path / "run").train()
    with pytest.raises(RunDirError, match=r"differ from it at: learning\.q\.alpha"):
        resume_run(tmp_path / "run", overrides={"q.alpha": 0.3})
    with pytest.raises(SpecError, match="budget is given on its own"):
        resume_run(tmp_path / "run", overrides={"generations": 5})
    with pytest.raises(SpecError) as caught:
        resume_run(tmp_path / "run", generations=Override("generations", "many", "my script"))
    assert caught.value.problems[0].location() == "my script"
    # the same behaviour and overrides, with a new budget, are fine
    training = resume_run(tmp_path / "run", BALLCHASE, TINY, generations=2)
    try:
        assert training.run.behaviour.learning.generations == 2
    finally:
        training.close()


def test_an_environment_that_does_not_fit_leaves_no_run_directory(tmp_path: Path) -> None:
    cartpole = BEHAVIOURS / "cartpole.yaml"
    with pytest.raises(SpecError) as caught:
        start_run(cartpole, {"environment.observations.pole_angle": 9}, tmp_path / "r")
    assert caught.value.problems[0].location() == (
        "overrides (environment.observations.pole_angle)")
    assert not (tmp_path / "r").exists()
