"""``flctool run CONTROLLER --ros2``: deploy a controller as a ROS 2 node (docs/ros2.md);
``flctool run CONTROLLER --link HOST:PORT``: drive a robot (or ``flctool serve``) over the
robot link (docs/robot-link.md), one episode at a time. A composed behaviour deploys either
way as a whole: the arbiter and its parts run here, the robot only walks
(:mod:`flctool.deployable`); over ROS 2 its robot file maps every channel the tree reads.

The ROS 2 node logs on stderr: when it starts driving, every watchdog stop and recovery, each
episode's end (with a status topic), and the stop it publishes before it leaves.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from flctool.cli.app import app, example, load_controller, report_interrupted, user_errors
from flctool.errors import FlcError

if TYPE_CHECKING:
    from flctool.behaviour import Behaviour


def _log(text: str) -> None:
    print(f"flctool run: {text}", file=sys.stderr, flush=True)


@app.command(epilog=example(
    "flctool run runs/robot --ros2",
    "flctool run runs/sim/best.yaml --ros2 --robot behaviours/ballchase-ros2.yaml",
    "flctool run behaviours/ballchase-handmade.yaml --ros2 --robot "
    "behaviours/ballchase-ros2.yaml --episodes 20",
    "flctool run bundle/ --ros2",
    "flctool run runs/robot --ros2 --record session",
    "flctool run behaviours/striker-handmade.yaml --link 127.0.0.1:5757 --episodes 20"))
def run(
    file: Annotated[Path, typer.Argument(
        metavar="CONTROLLER", help="A behaviour file (YAML), a run directory (its best.yaml) "
        "or an export bundle (its controller.yaml).")],
    ros2: Annotated[bool, typer.Option("--ros2", help="Run as a ROS 2 node, with the topics "
                                       "of the environment: {adapter: ros2} section.")]
    = False,
    robot: Annotated[Path | None, typer.Option(help="A behaviour file whose environment: "
                                               "section (adapter: ros2) says the topics, when "
                                               "the controller's own is a simulator's.")]
    = None,
    link: Annotated[str | None, typer.Option(metavar="HOST:PORT", help="Drive the robot "
                                             "behind the robot link at this address (e.g. "
                                             "flctool serve).")] = None,
    episodes: Annotated[int | None, typer.Option(min=1, help="Stop after this many episodes "
                                                 "have ended (--ros2: needs an episode status "
                                                 "topic; --link: default 1).")] = None,
    seed: Annotated[int, typer.Option(min=0, help="--link: the episodes' seeds are the ones "
                                      "'flctool evaluate --seed SEED' draws.")] = 0,
    duration: Annotated[float | None, typer.Option(min=0.001, help="Stop after this many "
                                                   "seconds.")] = None,
    rate: Annotated[float | None, typer.Option(min=0.001, max=1000, help="Control rate in Hz "
                                               "(default: the environment's rate).")] = None,
    record: Annotated[Path | None, typer.Option(help="Also record the run (every mapped "
                                                "topic: inputs, commands, status, reward) as "
                                                "an MCAP bag, as flctool record does (a new "
                                                "folder).")] = None,
) -> None:
    """Deploy a controller on a robot. --ros2: publish its command at the control rate from
    the latest inputs, with a watchdog that publishes stop at once on a stale, NaN or
    out-of-range input or a lost publisher, and again on Ctrl-C. --link: run episodes on a
    robot-link robot. Either way a composed behaviour runs whole, its arbiter and parts here."""
    with user_errors():
        # an export bundle (flctool export --format bundle) deploys its controller.yaml
        bundled = file / "controller.yaml"
        if file.is_dir() and bundled.is_file() and (file / "wiring.json").is_file():
            file = bundled
        behaviour, source = load_controller(file)
        if ros2 == (link is not None):
            raise FlcError("flctool run needs one of --ros2 and --link HOST:PORT",
                           hint="--ros2 deploys as a ROS 2 node; --link drives a robot-link "
                           "robot, e.g. one served by 'flctool serve FILE --port 5757'")
        if link is not None:
            if record is not None:
                raise FlcError("--record records a ROS 2 deployment",
                               hint="use --ros2, or leave --record out with --link")
            _run_link(behaviour, link, episodes or 1, seed)
            return
        _run_ros2(behaviour, source, robot, episodes, duration, rate, record)


def _address(link: str) -> tuple[str, int]:
    host, _, port = link.rpartition(":")
    if not host or not port.isdigit() or not 1 <= int(port) <= 65535:
        raise FlcError(f"--link {link!r} is not HOST:PORT", hint="e.g. --link 127.0.0.1:5757 "
                       "(flctool serve prints its address)")
    return host, int(port)


def _run_link(behaviour: Behaviour, link: str, episodes: int, seed: int) -> None:
    from flctool.behaviour.environment import RobotLinkConfig
    from flctool.deployable import deployable, run_episodes
    from flctool.envs.robot_link import RobotLinkEnv
    from flctool.rollout import evaluation_seeds

    host, port = _address(link)
    deployment = deployable(behaviour)
    config = RobotLinkConfig(adapter="robot-link", host=host, port=port)
    with RobotLinkEnv(config, behaviour.name, deployment.observations,
                      deployment.commands) as env:
        what = "composition" if deployment.composed else "controller"
        _log(f"{behaviour.name} ({what}) on {env.robot} at {host}:{port}: "
             f"{', '.join(deployment.observations)} -> {', '.join(deployment.commands)}")
        try:
            ended = run_episodes(deployment, env, evaluation_seeds(seed, episodes).tolist())
        except KeyboardInterrupt:
            report_interrupted(f"{behaviour.name} stopped (the robot was sent stop)")
            raise
    successes = sum(e.success for e in ended)
    steps = sum(e.steps for e in ended)
    typer.echo(f"{len(ended)} episodes ended: success {successes}, failure "
               f"{len(ended) - successes}")
    typer.echo(f"success rate {successes / len(ended):.3f}, {steps} steps")


def _run_ros2(behaviour: Behaviour, source: Path, robot: Path | None, episodes: int | None,
              duration: float | None, rate: float | None, record: Path | None) -> None:
    from flctool.deployable import deployable
    from flctool.ros2.section import ros2_section

    # compiled (and the kernels loaded) now: the first tick must not stall the node for seconds
    deployment = deployable(behaviour)
    # a composition reads every channel of its arbiter and parts: its robot file maps them all
    config, where = ros2_section(behaviour, str(source), robot,
                                 inputs=deployment.observations)
    if rate is not None:
        config = config.model_copy(update={"rate": rate})
    if episodes is not None and config.episode.status is None:
        raise FlcError("--episodes needs an episode status topic to count episodes",
                       hint=f"add environment.episode.status to {where}, or use --duration")
    from flctool.ros2.deploy import ControllerNode

    recorder = None
    if record is not None:
        from flctool.ros2.bags import BagRecorder, session_topics

        # a deployment never resets: its reset topic would have no publisher to wait for
        reset = config.episode.reset
        topics = [(topic, type_name) for topic, type_name in session_topics(config)
                  if reset is None or topic != reset.topic]
        # in the graph before the node publishes, so that its first commands are recorded
        recorder = BagRecorder(record, topics)
    try:
        node = ControllerNode(config, deployment.observations, deployment.commands,
                              deployment.act, _log)
    except BaseException:
        if recorder is not None:
            recorder.close()
        raise
    try:
        what = " (composition)" if deployment.composed else ""
        _log(f"{behaviour.name}{what} at {config.rate:g} Hz: "
             f"{', '.join(s.topic for s in node.sources)} -> {config.command.topic}")
        if recorder is not None:
            _start_recording(recorder, record, config.startup_timeout)
        try:
            node.run(episodes, duration)
        except KeyboardInterrupt:
            report_interrupted(f"{behaviour.name} stopped (the stop command was published)")
            raise
        finally:
            if recorder is not None:
                # every command the node published and every status it received, since
                # the recorder was there first
                expected = {config.command.topic: node.commands_sent + len(node.stop_times)}
                if node.status is not None and config.episode.status is not None:
                    expected[config.episode.status.topic] = node.status_messages
                _finish_recording(recorder, record, expected)
        if node.status is not None:
            outcomes = ", ".join(f"{k} {v}" for k, v in node.outcomes.items())
            typer.echo(f"{node.episodes} episodes ended: {outcomes}")
            if node.episodes:
                typer.echo(f"success rate {node.outcomes['success'] / node.episodes:.3f}")
        typer.echo(f"{node.commands_sent} commands published, watchdog stops "
                   f"{node.deployment.stops}")
    finally:
        node.close()


def _start_recording(recorder: Any, bag: Path | None, timeout: float) -> None:
    """Wait (at most ``timeout`` s) until every recorded topic has a publisher."""
    if not recorder.graph.wait(recorder.publishers_found, timeout):
        missing = [s.topic_name for s in recorder.subscriptions if s.get_publisher_count() == 0]
        _log(f"no publisher yet on {', '.join(missing)}; recording anyway")
    _log(f"recording {len(recorder.subscriptions)} topics to {bag}")


#: Finishing a recording: a command still in flight arrives within QUIET s of the one before
#: it (more than a control period, even on a loaded machine); SETTLE bounds the whole wait.
QUIET, SETTLE = 2.0, 10.0


def _finish_recording(recorder: Any, bag: Path | None, expected: dict[str, int]) -> None:
    """Finish the bag once the messages the node published or received while recording
    (``expected``, by topic: its commands, the last stop included, and the episode statuses
    it counted) have reached it. One sent before the recorder matched never will, so the bag
    is also finished once none of those topics has had a message for ``QUIET`` s."""
    expected = {topic: n for topic, n in expected.items() if topic in recorder.counts}
    last: list[float] = [sum(recorder.counts[t] for t in expected), time.monotonic()]

    def settled() -> bool:
        count: int = sum(recorder.counts[t] for t in expected)
        now = time.monotonic()
        if count != last[0]:
            last[:] = [count, now]
        return (all(recorder.counts[t] >= n for t, n in expected.items())
                or now - last[1] >= QUIET)

    recorder.graph.wait(settled, SETTLE)
    recorder.close()
    typer.echo(f"recorded {recorder.messages} messages to {bag}")
