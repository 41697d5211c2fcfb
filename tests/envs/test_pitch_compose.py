"""Composed behaviours: an arbiter whose commands are fixed behaviours (its parts) -- loading
as a trust boundary, the parts inlined, one dynamics for both paths, learning the arbiter."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from flctool import compile_behaviour, load_behaviour, parse_behaviour
from flctool.behaviour.dump import behaviour_to_data, behaviour_to_yaml
from flctool.envs import check_env, make_env
from flctool.errors import SpecError
from flctool.rollout import evaluate

from ..conftest import BEHAVIOURS

ARBITER = """flctool: 1
name: arbiter
inputs:
  behind:
    range: [0, 180]
    sets: {{front: [0, 0, 90, 160], behind: [90, 160, 180, 180]}}
output:
  name: part
  commands: {{chase: 0, dribble: 1}}
rules: {rules}
environment:
  adapter: pitch
  max_steps: 300
  start:
    robot: {{x: [-1500, 0], y: [-800, 800], heading: [-180, 180]}}
    ball: {{x: [-500, 500], y: [-500, 500]}}
  channels:
    behind: {{angle: [robot, ball, goal]}}
  compose:
    chase: {chase}
    dribble: {dribble}
  outcomes:
    - {{when: ball_in_goal, reward: 1, success: true}}
    - {{when: off_pitch, reward: -1}}
"""
LEARNED_RULES = """
  - {if: {behind: front}, then: chase}
  - {if: {behind: behind}, then: dribble}"""


def _write(folder: Path, rules: str = LEARNED_RULES, chase: str = "chase.yaml",
           dribble: str = "dribble.yaml") -> Path:
    shutil.copy(BEHAVIOURS / "dribble-handmade.yaml", folder / "dribble.yaml")
    chase_text = (BEHAVIOURS / "dribble-handmade.yaml").read_text().replace(
        "name: dribble_handmade", "name: chase")
    (folder / "chase.yaml").write_text(chase_text)
    path = folder / "arbiter.yaml"
    path.write_text(ARBITER.format(rules=rules, chase=chase, dribble=dribble))
    return path


def test_parts_are_inlined_and_a_written_composition_reads_back(tmp_path: Path) -> None:
    behaviour = load_behaviour(_write(tmp_path))
    parts = behaviour.environment.compose  # type: ignore[union-attr]
    assert set(parts) == {"chase", "dribble"} and parts["dribble"]["name"] == "dribble_handmade"
    # a run directory elsewhere holds the parts: nothing refers to the files any more
    text = behaviour_to_yaml(behaviour)
    again = parse_behaviour(text, "elsewhere/best.yaml")
    assert behaviour_to_data(again) == behaviour_to_data(behaviour)


@pytest.mark.slow
def test_both_paths_agree_bit_for_bit(tmp_path: Path) -> None:
    behaviour = load_behaviour(_write(tmp_path))
    check_env(lambda: make_env(behaviour, 4), batch_size=4)
    controller = compile_behaviour(behaviour)
    seeds = np.arange(24)
    batch = evaluate(controller, make_env(behaviour, 24), seeds)
    singles = [evaluate(controller, make_env(behaviour), seeds[i : i + 1]) for i in range(24)]
    assert np.array_equal(batch.lengths, np.concatenate([s.lengths for s in singles]))
    assert np.array_equal(batch.returns, np.concatenate([s.returns for s in singles]))
    assert batch.success.any()


def test_the_arbiter_chooses_the_part(tmp_path: Path) -> None:
    # one part that turns on the spot, one that walks: the arbiter's rules decide which runs
    spin = (BEHAVIOURS / "dribble-handmade.yaml").read_text()
    spin = spin[: spin.index("rules:")] + "rules:\n" + "".join(
        f"  - {{if: {{pan: {p}, goal_bearing: {g}}}, then: turn_left}}\n"
        for p in ("far_right", "right", "ahead", "left", "far_left")
        for g in ("behind_right", "right", "ahead", "left", "behind_left")) + \
        spin[spin.index("learning:"):]
    (tmp_path / "spin.yaml").write_text(spin.replace("name: dribble_handmade", "name: spin"))
    always = """
  - {if: {behind: front}, then: chase}
  - {if: {behind: behind}, then: chase}"""
    path = _write(tmp_path, rules=always, chase="spin.yaml")
    env = make_env(load_behaviour(path))
    env.reset_one(0)
    heading, x = float(env.heading[0]), float(env.x[0])
    env.step_one(0.0)  # the arbiter's output 0 is 'chase', i.e. spin
    assert np.degrees(float(env.heading[0]) - heading) > 8 and abs(float(env.x[0]) - x) < 40


@pytest.mark.slow
def test_learning_the_arbiter_keeps_the_parts_fixed(tmp_path: Path) -> None:
    from flctool.training import start_run

    path = _write(tmp_path, rules="[]")
    training = start_run(str(path), {"seed": 1, "generations": 2, "population": 4,
                                     "selection": {"candidates": 2, "episodes": 4}},
                         out=str(tmp_path / "run"))
    summary = training.train()
    best = load_behaviour(tmp_path / "run" / "best.yaml")
    assert best.is_deployable and summary is not None
    assert best.environment.compose == load_behaviour(path).environment.compose  # type: ignore[union-attr]


BAD = [
    ({"chase": "../outside.yaml"}, "environment.compose.chase", "outside the composing file"),
    ({"chase": "/etc/passwd.yaml"}, "environment.compose.chase", "absolute path"),
    ({"chase": "chase.txt"}, "environment.compose.chase", "not a .yaml"),
    ({"chase": "nothere.yaml"}, "environment.compose.chase", "no such file"),
    ({"chase": "arbiter.yaml"}, "environment.compose.chase", "cycle"),
]


@pytest.mark.parametrize(("parts", "path", "message"), BAD)
def test_part_files_are_a_trust_boundary(tmp_path: Path, parts: dict[str, str], path: str,
                                         message: str) -> None:
    (tmp_path / "sub").mkdir()
    (tmp_path / "outside.yaml").write_text((BEHAVIOURS / "dribble-handmade.yaml").read_text())
    target = _write(tmp_path / "sub", **parts)
    with pytest.raises(SpecError) as caught:
        load_behaviour(target)
    text = str(caught.value)
    assert f": {path}:" in text and message in text, text


def test_composition_mistakes_are_located(tmp_path: Path) -> None:
    path = _write(tmp_path)
    text = path.read_text()
    cases = [
        (text.replace("commands: {chase: 0, dribble: 1}",
                      "commands: {chase: 0, dribble: 1, shoot: 2}"),
         "environment.compose:", "the command 'shoot' has no part"),
        (text.replace("    dribble: dribble.yaml", "    dribbel: dribble.yaml"),
         "environment.compose.dribbel:", "Did you mean 'dribble'"),
        (text.replace("dribble: dribble.yaml", "dribble: learnable.yaml"),
         "environment.compose.dribble:", "rules without consequents"),
    ]
    shutil.copy(BEHAVIOURS / "dribble.yaml", tmp_path / "learnable.yaml")
    for written, where, message in cases:
        path.write_text(written)
        with pytest.raises(SpecError) as caught:
            make_env(load_behaviour(path))
        assert where in str(caught.value) and message in str(caught.value), str(caught.value)
    # a part reading a channel the composing world lacks
    chase = (tmp_path / "chase.yaml").read_text().replace("goal_bearing", "guard").replace(
        "  adapter: pitch\n", "  adapter: pitch\n  channels: {guard: {bearing: [ball, goal]}}\n")
    (tmp_path / "chase.yaml").write_text(chase)
    path.write_text(text)
    with pytest.raises(SpecError) as caught:
        load_behaviour(path)
    assert "environment.compose.chase:" in str(caught.value)
    assert "reads 'guard'" in str(caught.value)


def test_flctool_run_ros2_needs_a_robot_file_mapping_every_channel_of_the_tree(
        tmp_path: Path) -> None:
    """Over ROS 2 a composition deploys whole too (tests/ros2/test_deploy.py drives one); its
    own environment is the pitch world, so the topics come from --robot, which must map every
    channel the arbiter and its parts read: a clear error otherwise, at the robot file's line."""
    from typer.testing import CliRunner

    from flctool.cli.app import app

    from ..ros2_support import composition_robot

    path = _write(tmp_path)
    result = CliRunner().invoke(app, ["run", str(path), "--ros2"])
    assert result.exit_code == 1, result.output
    text = " ".join(result.output.split())
    assert "arbiter.yaml's environment is not a ROS 2 robot" in text
    assert "--robot ROBOT.yaml" in text and "inputs are behind, pan, goal_bearing" in text
    robot = tmp_path / "robot.yaml"
    robot.write_text(behaviour_to_yaml(composition_robot(("behind", "pan"))))
    result = CliRunner().invoke(app, ["run", str(path), "--ros2", "--robot", str(robot)])
    assert result.exit_code == 1, result.output
    text = " ".join(result.output.split())
    assert "robot.yaml:" in text and "environment.inputs: input 'goal_bearing' has no source" \
        in text, text
    assert "Traceback" not in result.output


def _nearest_chase(folder: Path) -> Path:
    """The test composition with its chase part walking its nearest command (the robot
    blends, so the deployment must send that command's singleton)."""
    path = _write(folder)
    chase = (folder / "chase.yaml").read_text().replace(
        "  adapter: pitch\n", "  adapter: pitch\n  action: nearest\n")
    (folder / "chase.yaml").write_text(chase)
    return path


def test_a_deployed_composition_walks_step_for_step_as_evaluation(tmp_path: Path) -> None:
    """Over the robot link (flctool serve's server), the arbiter and its parts run on the
    controller's side and send walking commands: the same walks, step for step, and the same
    episodes as evaluating the composition in process."""
    from flctool.behaviour.environment import RobotLinkConfig
    from flctool.deployable import deployable, run_episodes
    from flctool.envs.pitch_drive import CommandDrive
    from flctool.envs.robot_link import RobotLinkEnv
    from flctool.envs.robot_server import RobotServer

    behaviour = load_behaviour(_nearest_chase(tmp_path))
    controller = compile_behaviour(behaviour)
    seeds = np.arange(4, 10)  # seed 8 scores
    # in process: the composition's own drive, recorded
    env = make_env(behaviour)
    walks: list[tuple[list[float], list[float]]] = []
    drive = env.drive  # type: ignore[attr-defined]
    one = drive.one
    drive.one = lambda action, readings=(): walks.append(one(action, readings)) or walks[-1]
    expected = [evaluate(controller, env, [seed]) for seed in seeds.tolist()]
    # deployed: the values sent, walked by the composing world's table
    deployment = deployable(behaviour)
    config = behaviour.environment
    walk = CommandDrive(deployment.commands, config.motion, config.noise,  # type: ignore[union-attr]
                        False)
    sent: list[tuple[list[float], list[float]]] = []
    server = RobotServer.from_behaviour(behaviour, idle_timeout=10.0)
    thread = server.serve_in_background()
    try:
        link = RobotLinkConfig(adapter="robot-link", port=server.port)
        with RobotLinkEnv(link, behaviour.name, deployment.observations,
                          deployment.commands) as robot:
            episodes = run_episodes(deployment, robot, seeds.tolist(),
                                    lambda value: sent.append(walk.one(value)))
    finally:
        server.close()
        thread.join(timeout=5)
    assert sent == walks and len(sent) == sum(int(e.lengths[0]) for e in expected)
    assert [e.steps for e in episodes] == [int(e.lengths[0]) for e in expected]
    assert [e.total_reward for e in episodes] == [float(e.returns[0]) for e in expected]
    success = [e.success for e in episodes]
    assert success == [bool(e.success[0]) for e in expected] and any(success)


def test_flctool_run_drives_a_served_composition_as_evaluate_scores_it(tmp_path: Path) -> None:
    from typer.testing import CliRunner

    from flctool.cli.app import app
    from flctool.envs.robot_server import RobotServer
    from flctool.evaluation import evaluate_behaviour

    path = _nearest_chase(tmp_path)
    behaviour = load_behaviour(path)
    server = RobotServer.from_behaviour(behaviour, idle_timeout=10.0)
    thread = server.serve_in_background()
    try:
        result = CliRunner().invoke(app, ["run", str(path), "--link",
                                          f"127.0.0.1:{server.port}", "--episodes", "8"])
    finally:
        server.close()
        thread.join(timeout=5)
    assert result.exit_code == 0, result.output
    rate = evaluate_behaviour(behaviour, seed=0, episodes=8).result.success_rate.value
    assert f"success rate {rate:.3f}" in result.output
    assert "8 episodes ended" in result.output
    for args, message in [([], "needs one of --ros2 and --link"),
                          (["--link", "nowhere"], "is not HOST:PORT")]:
        refused = CliRunner().invoke(app, ["run", str(path), *args])
        assert refused.exit_code == 1 and message in refused.output, refused.output


def test_a_composition_deploys_only_with_one_command_table(tmp_path: Path) -> None:
    from flctool.deployable import deployable

    path = _write(tmp_path)
    chase = (tmp_path / "chase.yaml").read_text().replace("forward: 0.0", "forward: 0.1")
    assert chase != (tmp_path / "chase.yaml").read_text()
    (tmp_path / "chase.yaml").write_text(chase)
    with pytest.raises(SpecError) as caught:
        deployable(load_behaviour(path))
    assert "environment.compose." in str(caught.value)
    assert "one command table" in str(caught.value)
