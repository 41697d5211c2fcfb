"""The behaviour every plugin entry owes flctool, run for each entry (built-in or installed).

``test_plugins.py`` checks that the entries are well formed; here each one is used:

- a learner is reproducible from its seed and resumes where an uninterrupted run ends;
- an environment adapter passes the protocol checker (``check_env``);
- an exporter writes the handmade controller, and every format that reads back gives the
  same controller.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from flctool import compile_behaviour, load_behaviour
from flctool.behaviour import Behaviour, behaviour_from_data, behaviour_to_data
from flctool.envs import check_env, make_env
from flctool.envs.robot_server import RobotServer
from flctool.export import EXPORTERS, IMPORTERS
from flctool.learners import Callback, GenerationMetrics
from flctool.plugins import BUILTIN, Plugin, plugins
from flctool.runs import ENDED, create_run, open_run, resolve_behaviour

from .conftest import BEHAVIOURS
from .ros2_support import robot_behaviour, sim_robot

HANDMADE = load_behaviour(BEHAVIOURS / "ballchase-handmade.yaml")

#: A behaviour file for each built-in adapter. A new built-in adapter must add one here.
ADAPTER_BEHAVIOURS = {
    "ballchase-sim": "ballchase.yaml",
    "pitch": "dribble.yaml",
    "gymnasium": "cartpole.yaml",
    "robot-link": "ballchase-robot.yaml",
    "ros2": "ballchase-ros2.yaml",
}


class StopAfter(Callback):
    def __init__(self, generation: int) -> None:
        self.generation = generation

    def on_generation(self, metrics: GenerationMetrics) -> bool:
        return metrics.generation < self.generation


def small_run(learner: str) -> Behaviour:
    return resolve_behaviour(load_behaviour(BEHAVIOURS / "ballchase.yaml"), {
        "learner": learner, "seed": 5, "generations": 3, "population": 4,
        "selection.candidates": 2, "selection.episodes": 3})


def records(path: Path) -> tuple[str, str]:
    """metrics.csv without its wall-time column, and best.yaml (whose header names the run
    directory: the runs compared share a name)."""
    lines = (path / "metrics.csv").read_text(encoding="utf-8").splitlines()
    header = lines[0].split(",")
    keep = [i for i, name in enumerate(header) if name != "wall_time"]
    metrics = "\n".join(",".join(row.split(",")[i] for i in keep) for row in lines)
    return metrics, (path / "best.yaml").read_text(encoding="utf-8")


@pytest.mark.parametrize("plugin", plugins("learner"), ids=lambda p: p.name)
@pytest.mark.slow
def test_every_learner_is_reproducible_and_resumes_exactly(plugin: Plugin,
                                                           tmp_path: Path) -> None:
    behaviour = small_run(plugin.name)
    first = create_run(behaviour, tmp_path / "first" / "run")
    assert first.train().status in ENDED
    second = create_run(behaviour, tmp_path / "second" / "run")
    second.train()
    assert records(second.path) == records(first.path)

    cut = create_run(behaviour, tmp_path / "cut" / "run")
    assert cut.train([StopAfter(0)]).status == "stopped"
    assert open_run(cut.path).train().status == first.summary().status
    assert records(cut.path) == records(first.path)


@contextlib.contextmanager
def adapter_behaviour(name: str) -> Iterator[Behaviour]:
    """The contract behaviour of the built-in adapter ``name``; for the robot link, pointed
    at the reference robot side on a free port, served for the duration."""
    behaviour = load_behaviour(BEHAVIOURS / ADAPTER_BEHAVIOURS[name])
    if name == "ros2":
        with sim_robot("/contract"):
            yield robot_behaviour("/contract", startup_timeout=10.0, step_timeout=5.0)
        return
    if name != "robot-link":
        yield behaviour
        return
    robot = RobotServer.from_behaviour(HANDMADE, port=0, idle_timeout=10.0)
    thread = robot.serve_in_background()
    try:
        data = behaviour_to_data(behaviour)
        data["environment"].update(port=robot.port, connect_timeout=5.0, reset_timeout=5.0,
                                   step_timeout=5.0)
        yield behaviour_from_data(data)
    finally:
        robot.close()
        thread.join(timeout=5)


def test_every_builtin_adapter_has_a_contract_behaviour() -> None:
    assert set(ADAPTER_BEHAVIOURS) == {plugin.name for plugin in BUILTIN["environment"]}


@pytest.mark.parametrize("plugin", BUILTIN["environment"], ids=lambda p: p.name)
@pytest.mark.slow
def test_every_builtin_adapter_passes_the_checker(plugin: Plugin) -> None:
    if plugin.name == "gymnasium":
        pytest.importorskip("gymnasium")
    with adapter_behaviour(plugin.name) as behaviour:
        assert behaviour.environment is not None
        assert behaviour.environment.adapter == plugin.name
        # a ROS 2 robot runs one episode at a time
        batch = 1 if plugin.name == "ros2" else 3
        check_env(lambda: make_env(behaviour, batch_size=batch), batch_size=batch, seed=11)


@pytest.mark.parametrize("plugin", plugins("exporter"), ids=lambda p: p.name)
def test_every_exporter_writes_the_controller_and_reads_back_the_same(
        plugin: Plugin, tmp_path: Path) -> None:
    exporter = EXPORTERS.get(plugin.name)()
    suffix = plugin.suffixes[0] if plugin.suffixes else ""
    written = exporter.to_file(HANDMADE, tmp_path / f"handmade{suffix}")
    assert written and all(path.stat().st_size > 0 for path in written)
    if plugin.name not in IMPORTERS:
        return
    back = IMPORTERS.get(plugin.name)().from_file(written[0])
    states = np.random.default_rng(0).uniform(
        [spec.range[0] for spec in HANDMADE.inputs.values()],
        [spec.range[1] for spec in HANDMADE.inputs.values()], size=(500, len(HANDMADE.inputs)))
    expected = compile_behaviour(HANDMADE).output(states)
    assert np.array_equal(compile_behaviour(back).output(states), expected)
