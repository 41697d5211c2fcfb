"""A loaded behaviour keeps where its fields were written, so any layer raises located
errors; the source map changes neither equality nor pickling."""

from __future__ import annotations

import pickle
from pathlib import Path

import pytest

from flctool import SpecError, load_behaviour
from flctool.behaviour import Behaviour, behaviour_from_data, behaviour_to_data, parse_behaviour
from flctool.behaviour.located import locate, locate_error, located, source_of
from flctool.behaviour.overrides import Override, resolve_behaviour
from flctool.envs import BatchEnv, make_env
from flctool.envs.robot_server import RobotServer
from flctool.errors import Problem
from flctool.learners import LEARNERS, make_learner
from flctool.learners.genetic import PittLearner

from ..conftest import BEHAVIOURS

CARTPOLE = BEHAVIOURS / "cartpole.yaml"
BALLCHASE = BEHAVIOURS / "ballchase.yaml"


def _line_of(file: Path, text: str) -> int:
    return next(n for n, line in enumerate(file.read_text().splitlines(), 1) if text in line)


def test_an_adapters_complaint_is_located_in_the_file(tmp_path: Path) -> None:
    file = tmp_path / "cartpole.yaml"
    file.write_text(CARTPOLE.read_text(encoding="utf-8").replace("id: CartPole-v1",
                                                                 "id: CartPol-v1"))
    behaviour = load_behaviour(file)  # valid as a file: the id is checked by the adapter
    with pytest.raises(SpecError) as caught:
        make_env(behaviour, 1)
    problem = caught.value.problems[0]
    assert (problem.file, problem.line, problem.column) == (str(file),
                                                            _line_of(file, "CartPol-v1"), 3)
    assert problem.path == ("environment", "id") and caught.value.file == str(file)


def test_an_overridden_field_is_placed_where_the_override_was_given() -> None:
    behaviour = resolve_behaviour(load_behaviour(CARTPOLE), [
        Override("environment.observations.pole_angle", 9, "my script")])
    with pytest.raises(SpecError) as caught:
        make_env(behaviour, 1)
    assert caught.value.problems[0].location() == "my script"
    assert "index 9 is out of range" in caught.value.problems[0].message
    # a field not overridden stays at its line in the file
    problem = locate(behaviour, ("environment", "id"), "x")
    assert (problem.file, problem.line) == (str(CARTPOLE), _line_of(CARTPOLE, "id:"))


def test_locate_and_located_place_only_unplaced_problems() -> None:
    behaviour = parse_behaviour(CARTPOLE.read_text(encoding="utf-8"), "cart.yaml")
    placed = Problem(("name",), "already placed", file="elsewhere.yaml", line=9)
    error = SpecError([Problem(("learning", "seed"), "bad", "fix it"), placed])
    located_error = locate_error(behaviour, error)
    assert located_error.problems[1] is placed
    assert located_error.problems[0].file == "cart.yaml"
    assert located_error.problems[0].line is not None
    assert located_error.problems[0].hint == "fix it"
    whole = SpecError([placed])
    assert locate_error(behaviour, whole) is whole
    with pytest.raises(SpecError) as caught, located(behaviour):
        raise error
    assert caught.value.problems[0].file == "cart.yaml"
    with pytest.raises(ValueError, match="other"), located(behaviour):
        raise ValueError("other")


def test_a_behaviour_built_in_python_has_no_file() -> None:
    behaviour = behaviour_from_data(behaviour_to_data(load_behaviour(CARTPOLE)))
    assert locate(behaviour, ("environment", "id"), "x").line is None


def test_the_source_map_changes_neither_equality_nor_pickling() -> None:
    from_file = load_behaviour(CARTPOLE)
    from_text = parse_behaviour(CARTPOLE.read_text(encoding="utf-8"), "other.yaml")
    from_data = behaviour_from_data(behaviour_to_data(from_file))
    assert from_file == from_text == from_data
    copy = pickle.loads(pickle.dumps(from_file))
    assert copy == from_file
    assert source_of(copy).file == str(CARTPOLE) and source_of(copy).marks
    assert source_of(from_file.model_copy()).file == str(CARTPOLE)
    with pytest.raises(TypeError):
        from_file.inputs["x"] = from_file.inputs["cart_position"]  # type: ignore[index]
    with pytest.raises(TypeError, match="cannot be changed"):
        from_file._source = source_of(from_data)  # type: ignore[assignment]


class _Refusing(PittLearner):
    """A learner whose own checks refuse the behaviour, naming a field only."""

    def __init__(self, behaviour: Behaviour, env: BatchEnv) -> None:
        raise SpecError([Problem(("learning", "population"), "too many for this learner")])


def test_a_learners_complaint_is_located_and_the_env_built_for_it_closed() -> None:
    server = RobotServer.from_behaviour(load_behaviour(BALLCHASE), idle_timeout=5.0)
    thread = server.serve_in_background(once=True)
    saved = LEARNERS._entries["pitt"]
    try:
        behaviour = resolve_behaviour(load_behaviour(BALLCHASE), {
            "learner": "pitt", "environment": {"adapter": "robot-link", "port": server.port,
                                               "connect_timeout": 5, "retries": 0}})
        LEARNERS._entries["pitt"] = _Refusing
        with pytest.raises(SpecError) as caught:
            make_learner(behaviour)
        problem = caught.value.problems[0]
        # the file gives no population: the problem is placed at its section
        assert (problem.file, problem.line) == (str(BALLCHASE), _line_of(BALLCHASE, "learning:"))
        thread.join(timeout=5)  # --once: it ends when the client disconnects
        assert server.stops == ["the client sent stop (close)"]
    finally:
        LEARNERS._entries["pitt"] = saved
        server.close()
        thread.join(timeout=5)
