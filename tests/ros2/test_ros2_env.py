"""The ``ros2`` adapter over real rclpy on localhost, against the reference robot: the same
episodes, learning and resume as in process, and every fault a safe stop within its bound."""

from __future__ import annotations

import json
import math
import signal
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

from flctool import compile_behaviour
from flctool.behaviour import behaviour_to_data, behaviour_to_yaml, load_behaviour
from flctool.cli import app
from flctool.envs import make_env
from flctool.errors import LinkError
from flctool.rollout import evaluate

from ..conftest import BEHAVIOURS
from ..ros2_support import (
    handmade_rules,
    require_ros2,
    robot_behaviour,
    served_robot,
    sim_robot,
    wait_until,
)

runner = CliRunner()
#: Short, for the tests' sake, yet long enough for a loaded machine's simulator to answer.
STEP_TIMEOUT = 1.5


@pytest.fixture(autouse=True)
def _ros() -> None:
    require_ros2()


@pytest.mark.slow
def test_episodes_over_ros2_are_bit_for_bit_the_simulators() -> None:
    handmade = load_behaviour(BEHAVIOURS / "ballchase-handmade.yaml")
    seeds = np.arange(5, dtype=np.int64)
    direct = evaluate(compile_behaviour(handmade), make_env(handmade), seeds)
    with sim_robot("/same"):
        behaviour = handmade_rules(robot_behaviour("/same"))
        with make_env(behaviour) as env:
            over = evaluate(compile_behaviour(behaviour), env, seeds)
    assert np.array_equal(over.returns, direct.returns)
    assert np.array_equal(over.lengths, direct.lengths)
    assert np.array_equal(over.success, direct.success)
    assert np.array_equal(over.fitness, direct.fitness)


def test_the_robot_answers_a_reset_whose_client_subscribes_late() -> None:
    """A client's subscriptions can be discovered seconds after its reset reaches the robot
    (late in a loaded CI run, a learner waited out its reset timeout so); the lockstep robot
    answers a reset once, so it waits for them before answering."""
    from flctool.behaviour.ros2 import Qos
    from flctool.envs.ros2_robot import MATCH_WAIT
    from flctool.ros2.fields import message_class
    from flctool.ros2.graph import RosGraph

    with sim_robot("/late"):
        client = RosGraph("late_client")
        try:
            reset = client.publisher("/late/reset", "std_msgs/Int64", Qos())
            assert wait_until(lambda: reset.get_subscription_count() > 0, 30.0)
            reset.publish(message_class("std_msgs/Int64")(data=3))
            time.sleep(MATCH_WAIT + 1.0)  # past what the robot once waited for anyone
            status = client.subscribe("/late/status", "std_msgs/String", Qos())
            assert client.wait(lambda: status.count > 0, 30.0), "the reset went unanswered"
            assert status.text == "running"
        finally:
            client.close()


class _Spy:
    """Records every command on a topic: (time, linear.x, angular.z)."""

    def __init__(self, topic: str) -> None:
        from flctool.ros2.graph import RosGraph

        self.graph = RosGraph("spy")
        self.commands: list[tuple[float, float, float]] = []
        self.subscription = self.graph.node.create_subscription(
            __import__("geometry_msgs.msg", fromlist=["Twist"]).Twist, topic,
            lambda m: self.commands.append((time.monotonic(), m.linear.x, m.angular.z)), 10)

    def stops_after(self, moment: float) -> list[float]:
        return [t for t, x, z in self.commands if t >= moment and x == 0.0 and z == 0.0]


def _faulty(fault: str) -> Any:
    """A reference robot that misbehaves from its 5th step on."""
    from flctool.envs.ros2_robot import SimRobot

    class FaultyRobot(SimRobot):
        def _publish_observation(self, observation: Any) -> None:
            if self.steps >= 5:
                if fault == "nan":
                    observation = np.array([observation[0], math.nan])
                elif fault == "out of range":
                    observation = np.array([observation[0], 500.0])
                elif fault == "silent":  # pan is no longer published
                    self.observation_publishers[0].publish(self.float64(
                        data=float(observation[0])))
                    return
                elif fault == "slow":
                    time.sleep(3 * STEP_TIMEOUT)
            super()._publish_observation(observation)
    return FaultyRobot


FAULTS = {
    "nan": "input pan is nan (from /faulty/pan)",
    "out of range": "input pan = 500 is outside its valid range [-90, 90]",
    "silent": f"no fresh message on /faulty/pan within {STEP_TIMEOUT:g} s of the command",
    "slow": "no fresh message on /faulty/ball_size, /faulty/pan, /faulty/status, "
            f"/faulty/reward within {STEP_TIMEOUT:g} s",
}


@pytest.mark.parametrize("fault", list(FAULTS))
def test_a_faulty_input_stops_the_robot_within_the_bound(fault: str) -> None:
    from flctool.envs.ros2_robot import SimRobot

    robot_class = _faulty(fault)
    robot = robot_class(SimRobot.from_behaviour(
        load_behaviour(BEHAVIOURS / "ballchase-handmade.yaml")).env, namespace="/faulty")
    spy = _Spy("/faulty/cmd_vel")
    try:
        behaviour = handmade_rules(robot_behaviour("/faulty", step_timeout=STEP_TIMEOUT))
        data = behaviour.environment.model_dump()  # type: ignore[union-attr]
        data["inputs"]["pan"]["valid"] = (-90.0, 90.0)
        from flctool.behaviour.ros2 import Ros2Config

        config = Ros2Config.model_validate(data)
        from flctool.envs.ros2_env import Ros2Env

        flc = compile_behaviour(behaviour)
        with Ros2Env(config, behaviour.name, behaviour.input_names,
                     dict(behaviour.output.commands)) as env:
            assert wait_until(lambda: spy.subscription.get_publisher_count() > 0, 10.0)
            # discovery is not symmetric: the spy can see the command publisher before that
            # publisher has matched the spy, and a stop sent before then never reaches it
            time.sleep(1.0)
            observation = env.reset_one(3)
            started = 0.0
            with pytest.raises(LinkError) as caught:
                for _ in range(50):
                    started = time.monotonic()
                    observation, *_ = env.step_one(flc.output_one(observation))
            elapsed = time.monotonic() - started
            assert FAULTS[fault] in str(caught.value), str(caught.value)
            assert "the stop command was published" in str(caught.value)
            # a bad value is refused at once; a missing one after the step timeout
            assert elapsed <= STEP_TIMEOUT + 1.0
            assert wait_until(lambda: spy.stops_after(started), 5.0)
    finally:
        spy.graph.close()
        robot.close()


def _learn(*args: str) -> Any:
    return runner.invoke(app, ["learn", *args, "--json"], catch_exceptions=False)


SMALL = ["-g", "3", "-p", "4", "--set", "selection.candidates=2", "--set",
         "selection.episodes=3"]


def _records(path: Path) -> tuple[list[str], Any]:
    lines = (path / "metrics.csv").read_text(encoding="utf-8").splitlines()
    header = lines[0].split(",")
    keep = [i for i, name in enumerate(header) if name != "wall_time"]
    return ([",".join(row.split(",")[i] for i in keep) for row in lines],
            load_behaviour(path / "best.yaml").rules)


@pytest.mark.slow
def test_learning_survives_the_robot_killed_mid_run_and_resumes_to_the_same_run(
        tmp_path: Path) -> None:
    """The robot node killed during learning: a clear error and exit 1, the checkpoints
    kept; with the robot back, --resume ends exactly as learning in process does."""
    robot_file = tmp_path / "robot.yaml"
    robot_file.write_text(behaviour_to_yaml(robot_behaviour(
        "/killed", step_timeout=STEP_TIMEOUT, startup_timeout=10.0)), encoding="utf-8")
    run = tmp_path / "run"
    with served_robot("--namespace", "/killed") as robot:
        def kill_after_the_first_checkpoint() -> None:
            wait_until(lambda: any((run / "checkpoints").glob("*")), 120.0)
            robot.send_signal(signal.SIGSTOP)  # frozen mid-run: the learner waits for it
            time.sleep(0.2)
            robot.kill()

        killer = threading.Thread(target=kill_after_the_first_checkpoint)
        killer.start()
        result = _learn(str(robot_file), *SMALL, "-o", str(run))
        killer.join(timeout=130)
    assert result.exit_code == 1, result.output
    assert "the stop command was published" in result.output
    assert "Traceback" not in result.output
    assert any((run / "checkpoints").glob("*"))
    with served_robot("--namespace", "/killed"):
        resumed = runner.invoke(app, ["learn", "--resume", str(run), "--json"],
                                catch_exceptions=False)
    assert resumed.exit_code == 0, resumed.output
    direct = tmp_path / "direct"
    assert _learn(str(BEHAVIOURS / "ballchase.yaml"), *SMALL, "-o", str(direct)).exit_code == 0
    assert _records(run) == _records(direct)


#: 20 generations, as the paper learned on the robot, on a small population (a CPU budget for
#: CI): 197 episodes, 3,362 steps with selection, confirmation and the baselines; about 22 s of
#: CPU in all (12 s learning over ROS 2, 9 s the served robot, 2 s learning in process).
TWENTY = ["-g", "20", "-p", "4", "--set", "selection.candidates=2", "--set",
          "selection.episodes=3", "--set", "selection.confirmation=10"]


def _summary(result: Any) -> dict[str, Any]:
    """The run's JSON summary without what differs between two routes: its folder, its best
    file and the last generation's wall time."""
    data = json.loads(result.stdout)
    del data["run"], data["best_file"], data["last"]["wall_time"]
    return dict(data)


@pytest.mark.slow
def test_twenty_generations_over_ros2_learn_the_simulators_controller(tmp_path: Path) -> None:
    """Learning 20 generations against ``flctool serve --ros2`` ends with the in-process
    simulator's best controller and metrics for the same seed."""
    robot_file = tmp_path / "robot.yaml"
    robot_file.write_text(behaviour_to_yaml(robot_behaviour("/twenty")), encoding="utf-8")
    over, direct = tmp_path / "over", tmp_path / "direct"
    with served_robot("--namespace", "/twenty"):
        learned = _learn(str(robot_file), *TWENTY, "-o", str(over))
    assert learned.exit_code == 0, learned.output
    simulated = _learn(str(BEHAVIOURS / "ballchase.yaml"), *TWENTY, "-o", str(direct))
    assert simulated.exit_code == 0, simulated.output
    assert len((over / "metrics.csv").read_text(encoding="utf-8").splitlines()) == 21
    assert _records(over) == _records(direct)
    best_over, best_direct = (behaviour_to_data(load_behaviour(path / "best.yaml"))
                              for path in (over, direct))
    for key in ("inputs", "output", "rules"):
        assert best_over[key] == best_direct[key], key
    assert _summary(learned) == _summary(simulated)
