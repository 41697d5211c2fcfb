"""Logged data over real rclpy: sessions recorded as MCAP bags, replayed exactly, and the
simulator's motion and noise tables recovered from 1,000 recorded steps."""

from __future__ import annotations

import csv
import io
import math
import re
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

from flctool import compile_behaviour
from flctool.behaviour import (
    behaviour_from_data,
    behaviour_to_data,
    behaviour_to_yaml,
    load_behaviour,
)
from flctool.behaviour.ros2 import Ros2Config
from flctool.cli import app
from flctool.envs import make_env

from ..conftest import BEHAVIOURS
from ..ros2_support import handmade_rules, require_ros2, robot_behaviour, wait_until

runner = CliRunner()

#: A robot that walks unlike the default table: faster, drifting, noisier, one-sided turns.
MOTION = {"turn_right": {"forward": 12.0, "sideways": -3.0, "rotation": -20.0},
          "forward_right": {"forward": 70.0, "sideways": -6.0, "rotation": -9.0},
          "forward": {"forward": 85.0, "sideways": 4.0, "rotation": 1.5},
          "forward_left": {"forward": 65.0, "sideways": 5.0, "rotation": 11.0},
          "turn_left": {"forward": 8.0, "sideways": 2.0, "rotation": 18.0}}
NOISE = {"turn_right": {"forward": 5.0, "sideways": 3.0, "rotation": 2.5},
         "forward_right": {"forward": 10.0, "sideways": 6.0, "rotation": 2.0},
         "forward": {"forward": 12.0, "sideways": 7.0, "rotation": 1.0},
         "forward_left": {"forward": 9.0, "sideways": 5.0, "rotation": 2.0},
         "turn_left": {"forward": 4.0, "sideways": 2.0, "rotation": 3.0}}


@pytest.fixture(autouse=True)
def _ros() -> None:
    require_ros2()


def _simulator(tmp_path: Path) -> Path:
    """ballchase with the tables above, each step exactly one command (action: nearest), and
    a big pitch so that episodes end by the step limit or the ball, rarely off the pitch."""
    data = behaviour_to_data(load_behaviour(BEHAVIOURS / "ballchase.yaml"))
    data["environment"].update(action="nearest", motion=MOTION, noise=NOISE)
    path = tmp_path / "measured-robot.yaml"
    path.write_text(behaviour_to_yaml(behaviour_from_data(data)), encoding="utf-8")
    return path


def _record(tmp_path: Path, sim: Path, namespace: str, steps: int, drive: Any) -> Path:
    """A session of ``steps`` steps on the served ``sim``, driven by ``drive(env, obs, rng)
    -> action``, recorded as a bag (the robot file's topics and the odometry)."""
    from flctool.envs.ros2_robot import SimRobot
    from flctool.ros2.bags import BagRecorder, session_topics

    behaviour = robot_behaviour(namespace, step_timeout=5.0)
    config = behaviour.environment
    assert isinstance(config, Ros2Config)
    bag = tmp_path / "session"
    robot = SimRobot.from_behaviour(load_behaviour(sim), namespace=namespace)
    recorder = None
    try:
        with make_env(behaviour) as env:
            # recording starts once the session has found the robot: a recorder found first
            # would count as the reset topic's subscriber (see docs/ros2.md)
            recorder = BagRecorder(bag, session_topics(config, [(f"{namespace}/odom",
                                                                  "nav_msgs/Odometry")]))
            assert wait_until(recorder.publishers_found, 10.0)
            # discovery is not symmetric: the recorder can see a publisher before that
            # publisher has matched the recorder, and a sample sent before then is not
            # delivered to it; let both sides finish matching before the first step
            time.sleep(1.0)
            rng = np.random.default_rng(4)
            done, observation, seed = True, None, 0
            for _ in range(steps):
                if done:
                    observation, seed = env.reset_one(seed), seed + 1
                observation, _, terminated, truncated = env.step_one(
                    drive(observation, rng))
                done = terminated or truncated
        expected = 6 * steps  # a command, the observations, odometry, reward and status
        assert wait_until(lambda: recorder.messages >= expected, 10.0)  # type: ignore[union-attr]
    finally:
        if recorder is not None:
            recorder.close()
        robot.close()
    return bag


@pytest.mark.slow
def test_fit_sim_recovers_the_tables_of_a_measured_robot_from_1000_recorded_steps(
        tmp_path: Path) -> None:
    from flctool.ros2.bags import fit_motion

    sim = _simulator(tmp_path)
    singletons = [-1.0, -0.5, 0.0, 0.5, 1.0]
    bag = _record(tmp_path, sim, "/measured", 1000,
                  lambda observation, rng: float(rng.choice(singletons)))
    config = robot_behaviour("/measured").environment
    assert isinstance(config, Ros2Config)
    commands = dict(load_behaviour(BEHAVIOURS / "ballchase.yaml").output.commands)
    fits = fit_motion(bag, config, commands, "/measured/odom")
    assert sum(fit.steps for fit in fits.values()) == 1000
    within_5_percent = []
    for name, fit in fits.items():
        n = fit.steps
        assert n >= 150, (name, n)  # each command ran about 200 times
        for k, key in enumerate(("forward", "sideways", "rotation")):
            mean, std = MOTION[name][key], NOISE[name][key]
            mean_error, std_error = abs(fit.mean[k] - mean), abs(fit.std[k] - std)
            print(f"{name} {key}: mean {fit.mean[k]:.3f} ({100 * mean_error / abs(mean):.1f} %),"
                  f" std {fit.std[k]:.3f} ({100 * std_error / std:.1f} %), {n} steps")
            # What n steps can tell (benchmarks/fit_sim_accuracy.py, docs/ros2.md): a mean to
            # its standard error std / sqrt(n), a deviation to about std / sqrt(2 n) -- 5 % of
            # it from ~200 steps. Each within 4 standard errors, ...
            assert mean_error <= 4 * std / math.sqrt(n), (name, key, fit.mean[k], mean)
            assert std_error <= 4 * std / math.sqrt(2 * n), (name, key, fit.std[k], std)
            # ... and within 5 % every mean that 1,000 steps know to 5 % (4 standard errors
            # are at most 5 % of it): the forward speeds and the large turns
            if 4 * std / math.sqrt(n) <= 0.05 * abs(mean):
                within_5_percent.append(f"{name} {key}")
                assert mean_error <= 0.05 * abs(mean), (name, key, fit.mean[k], mean)
    assert len(within_5_percent) >= 5, within_5_percent

    robot = tmp_path / "robot.yaml"
    robot.write_text(behaviour_to_yaml(robot_behaviour("/measured")), encoding="utf-8")
    out = tmp_path / "fitted.yaml"
    result = runner.invoke(app, ["fit-sim", str(bag), "--robot", str(robot), "--sim", str(sim),
                                 "--odom", "/measured/odom", "-o", str(out)])
    assert result.exit_code == 0, result.output
    assert "forward_left" in result.output and f"wrote {out}" in result.output
    fitted = yaml.safe_load(out.read_text(encoding="utf-8"))["environment"]
    data = behaviour_to_data(load_behaviour(sim))
    data["environment"] = fitted
    assert behaviour_from_data(data).environment is not None  # a valid simulator section


@pytest.mark.slow
def test_replay_reproduces_a_recorded_controllers_outputs_exactly(tmp_path: Path) -> None:
    handmade = load_behaviour(BEHAVIOURS / "ballchase-handmade.yaml")
    flc = compile_behaviour(handmade)
    bag = _record(tmp_path, BEHAVIOURS / "ballchase-handmade.yaml", "/replayed", 150,
                  lambda observation, rng: flc.output_one(observation))
    controller = tmp_path / "controller.yaml"
    controller.write_text(behaviour_to_yaml(handmade_rules(robot_behaviour("/replayed"))),
                          encoding="utf-8")
    out = tmp_path / "replayed.csv"
    result = runner.invoke(app, ["replay", str(controller), str(bag), "-o", str(out)])
    assert result.exit_code == 0, result.output
    rows = list(csv.DictReader(io.StringIO(out.read_text(encoding="utf-8"))))
    assert len(rows) == 150
    assert all(float(row["difference"]) == 0.0 for row in rows)
    assert "150 commands replayed; 0 differ" in result.output
    # and into a bag, beside the recorded commands
    beside = tmp_path / "beside"
    result = runner.invoke(app, ["replay", str(controller), str(bag), "-o", str(tmp_path / "x.csv"),
                                 "--bag", str(beside)])
    assert result.exit_code == 0, result.output
    from flctool.ros2.bags import read_messages

    topics: dict[str, list[float]] = {}
    for topic, _, message in read_messages(beside):
        topics.setdefault(topic, []).append(getattr(message, "data", 0.0))
    assert len(topics["/replayed/cmd_vel/replayed"]) == 150
    assert set(topics["/replayed/cmd_vel/difference"]) == {0.0}
    assert len(topics["/replayed/cmd_vel"]) == len(list(read_messages(bag, ["/replayed/cmd_vel"])))
    # another controller differs, and replay says so
    data = behaviour_to_data(handmade)
    data["rules"] = [{**rule, "then": "turn_left"} for rule in data["rules"]]
    other = tmp_path / "other.yaml"
    other.write_text(behaviour_to_yaml(handmade_rules(robot_behaviour("/replayed")).model_copy(
        update={"rules": behaviour_from_data(data).rules})), encoding="utf-8")
    differs = runner.invoke(app, ["replay", str(other), str(bag)])
    assert differs.exit_code == 0 and "; 0 differ" not in differs.output, differs.output


@pytest.mark.slow
def test_record_writes_a_session_bag_and_refuses_an_existing_one(tmp_path: Path) -> None:
    from flctool.envs.ros2_robot import SimRobot
    from flctool.ros2.bags import read_messages

    robot_file = tmp_path / "robot.yaml"
    robot_file.write_text(behaviour_to_yaml(robot_behaviour("/recorded")), encoding="utf-8")
    robot = SimRobot.from_behaviour(load_behaviour(BEHAVIOURS / "ballchase-handmade.yaml"),
                                    namespace="/recorded", auto_reset=True)
    try:
        robot.start_episode()  # republishes its observations at 50 Hz while it waits
        bag = tmp_path / "bag"
        result = runner.invoke(app, ["record", str(robot_file), "-o", str(bag), "--duration",
                                     "1", "--wait", "2", "--topic",
                                     "/recorded/odom:nav_msgs/Odometry"])
        assert result.exit_code == 0, result.output
        topics = {topic for topic, _, _ in read_messages(bag)}
        assert {"/recorded/ball_size", "/recorded/pan", "/recorded/odom"} <= topics
        again = runner.invoke(app, ["record", str(robot_file), "-o", str(bag), "--duration",
                                    "0.1"])
        assert again.exit_code == 1 and "exists" in again.output
    finally:
        robot.close()


def _iterate(bag: Path) -> Iterator[Any]:
    from flctool.ros2.bags import read_messages

    return read_messages(bag)


def test_a_file_that_is_not_a_bag_is_a_clear_error(tmp_path: Path) -> None:
    junk = tmp_path / "junk.mcap"
    junk.write_bytes(b"\x89MCAP0\r\n" + b"\x00" * 64)
    from flctool.errors import FlcError

    with pytest.raises(FlcError, match="not a readable bag"):
        list(_iterate(junk))


@pytest.mark.slow
def test_a_deployment_recorded_by_flctool_record_replays_exactly(tmp_path: Path) -> None:
    """`flctool run --ros2` on the reference robot, recorded by `flctool record` in another
    process: replaying the bag gives every recorded command exactly."""
    import os
    import subprocess
    import sys
    import threading

    from ..ros2_support import ros_environment, served_robot

    controller = tmp_path / "controller.yaml"
    controller.write_text(behaviour_to_yaml(handmade_rules(robot_behaviour("/deployed",
                                                                           rate=20.0))),
                          encoding="utf-8")
    bag = tmp_path / "session"
    env = {**os.environ, **ros_environment()}
    with served_robot("--namespace", "/deployed", "--auto-reset", "--seed", "500"):
        recorder = subprocess.Popen(
            [sys.executable, "-m", "flctool", "record", str(controller), "-o", str(bag),
             "--wait", "2"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
        lines: list[str] = []
        reader = threading.Thread(target=lambda: lines.extend(recorder.stderr), daemon=True)  # type: ignore[arg-type]
        reader.start()
        try:
            assert wait_until(lambda: any("recording" in line for line in lines), 60.0), lines
            run = subprocess.run(
                [sys.executable, "-m", "flctool", "run", str(controller), "--ros2",
                 "--episodes", "5"], capture_output=True, text=True, timeout=240, env=env,
                check=False)
            assert run.returncode == 0, run.stderr
        finally:
            recorder.terminate()  # SIGTERM ends a recording cleanly
            assert recorder.wait(timeout=30) == 0
            reader.join(timeout=5)
    result = runner.invoke(app, ["replay", str(controller), str(bag), "-o",
                                 str(tmp_path / "replayed.csv")])
    assert result.exit_code == 0, result.output
    published = int(re.search(r"(\d+) commands published", run.stdout)[1])  # type: ignore[index]
    replayed = re.search(r"(\d+) commands replayed; (\d+) differ", result.output)
    assert replayed is not None, result.output
    # the recorder may match the node's command publisher some time after its first command
    # (discovery takes longer on a loaded machine): what it recorded must replay exactly
    assert published // 2 <= int(replayed[1]) <= published and replayed[2] == "0", (
        published, result.output)


@pytest.mark.slow
def test_an_export_bundle_deployed_with_run_record_drives_the_robot_and_replays_exactly(
        tmp_path: Path) -> None:
    """`flctool run BUNDLE --ros2 --record BAG`: the bundle's controller drives the reference
    robot on the topics of the controller it was exported from, and the bag it recorded while
    driving replays to every command it published, the last one the stop."""
    import os
    import subprocess
    import sys

    from flctool.ros2.bags import read_messages

    from ..ros2_support import ros_environment, served_robot

    controller = tmp_path / "controller.yaml"
    controller.write_text(behaviour_to_yaml(handmade_rules(robot_behaviour("/bundled",
                                                                           rate=20.0))),
                          encoding="utf-8")
    bundle = tmp_path / "bundle"
    exported = runner.invoke(app, ["export", str(controller), "--format", "bundle", "-o",
                                   str(bundle)])
    assert exported.exit_code == 0, exported.output
    bag = tmp_path / "session"
    with served_robot("--namespace", "/bundled", "--auto-reset", "--seed", "300"):
        run = subprocess.run(
            [sys.executable, "-m", "flctool", "run", str(bundle), "--ros2", "--episodes", "3",
             "--record", str(bag)], capture_output=True, text=True, timeout=240,
            env={**os.environ, **ros_environment()}, check=False)
    assert run.returncode == 0, run.stderr
    assert "3 episodes ended" in run.stdout, run.stdout
    assert f"recording 5 topics to {bag}" in run.stderr, run.stderr
    published = int(re.search(r"(\d+) commands published", run.stdout)[1])  # type: ignore[index]
    commands = [message for _, _, message in read_messages(bag, ["/bundled/cmd_vel"])]
    assert commands[-1].linear.x == 0.0 and commands[-1].angular.z == 0.0  # the stop
    result = runner.invoke(app, ["replay", str(controller), str(bag), "-o",
                                 str(tmp_path / "replayed.csv")])
    assert result.exit_code == 0, result.output
    replayed = re.search(r"(\d+) commands replayed; (\d+) differ", result.output)
    assert replayed is not None, result.output
    # recording starts once the recorder has found every publisher; on a loaded machine the
    # node's first commands may come before that
    assert published // 2 <= int(replayed[1]) <= published and replayed[2] == "0", (
        published, result.output)
    statuses = [m.data for _, _, m in read_messages(bag, ["/bundled/status"])]
    # the episodes' ends; the first may end before the recorder has found
    # the robot's publisher on a loaded machine (as the first commands may: above)
    ended = sum(s in ("success", "failure", "timeout") for s in statuses)
    assert ended >= 1, statuses
