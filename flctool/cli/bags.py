"""``flctool record``, ``flctool replay`` and ``flctool fit-sim``: logged robot data in ROS 2
bags (docs/ros2.md, "Logged data")."""

from __future__ import annotations

import csv
import io
import signal
import sys
import threading
import time
from pathlib import Path
from typing import Annotated

import typer

from flctool.cli.app import (
    Force,
    app,
    check_output,
    example,
    load_controller,
    report_interrupted,
    user_errors,
    write_output,
)
from flctool.cli.behaviour_commands import ControllerArgument
from flctool.errors import FlcError

RobotOption = Annotated[Path | None, typer.Option(
    help="A behaviour file whose environment: {adapter: ros2} section names the topics "
    "(default: the controller's own).")]


def _log(text: str) -> None:
    print(f"flctool record: {text}", file=sys.stderr, flush=True)


def _topic(text: str) -> tuple[str, str]:
    topic, _, type_name = text.partition(":")
    if not topic or not type_name:
        raise FlcError(f"--topic {text!r}: write TOPIC:TYPE, e.g. /robot/odom:nav_msgs/Odometry")
    from flctool.behaviour.ros2_messages import message_problem, normal_type

    problem = message_problem(type_name)
    if problem:
        raise FlcError(f"--topic {text!r}: {problem}")
    return topic, normal_type(type_name)


@app.command(epilog=example(
    "flctool record behaviours/ballchase-ros2.yaml -o session --topic "
    "/robot/odom:nav_msgs/Odometry"))
def record(
    file: Annotated[Path, typer.Argument(help="A behaviour file with an environment: "
                                         "{adapter: ros2} section: its topics are recorded.")],
    out: Annotated[Path, typer.Option("--out", "-o", help="The bag to write (a folder, ROS 2 "
                                      "bag in MCAP storage).")],
    topic: Annotated[list[str] | None, typer.Option(help="Another topic to record, as "
                                                    "TOPIC:TYPE (repeatable), e.g. "
                                                    "/robot/odom:nav_msgs/Odometry.")] = None,
    duration: Annotated[float | None, typer.Option(min=0.001, help="Stop after this many "
                                                   "seconds (default: at Ctrl-C).")] = None,
    wait: Annotated[float, typer.Option(min=0.0, help="Seconds to wait for every topic's "
                                        "publisher before recording.")] = 10.0,
) -> None:
    """Record a learning or deployment session over ROS 2 (inputs, commands, status, rewards,
    and any --topic) as an MCAP bag, until --duration or Ctrl-C."""
    from flctool.behaviour import load_behaviour

    with user_errors():
        from flctool.ros2.bags import BagRecorder, session_topics
        from flctool.ros2.section import ros2_section

        behaviour = load_behaviour(file)
        config, _ = ros2_section(behaviour, str(file))
        topics = session_topics(config, [_topic(t) for t in topic or []])
        recorder = BagRecorder(out, topics)
        try:
            if not recorder.graph.wait(recorder.publishers_found, wait):
                missing = [t for (t, _), s in zip(topics, recorder.subscriptions, strict=True)
                           if s.get_publisher_count() == 0]
                _log(f"no publisher yet on {', '.join(missing)}; recording anyway")
            _log(f"recording {len(topics)} topics to {out}")
            deadline = float("inf") if duration is None else time.monotonic() + duration
            terminated = threading.Event()
            # `kill` (SIGTERM) ends a recording as cleanly as Ctrl-C: the bag is finished
            previous = signal.signal(signal.SIGTERM, lambda *_: terminated.set())
            try:
                while time.monotonic() < deadline and not terminated.is_set():
                    terminated.wait(min(0.1, max(deadline - time.monotonic(), 0.0)))
            except KeyboardInterrupt:
                report_interrupted(f"recording ended; the bag {out} is complete")
                raise
            finally:
                signal.signal(signal.SIGTERM, previous)
        finally:
            recorder.close()
            typer.echo(f"recorded {recorder.messages} messages to {out}")


@app.command(epilog=example(
    "flctool replay runs/robot session -o replayed.csv",
    "flctool replay runs/robot session -o replayed.csv --bag session-replayed",
    "flctool replay behaviours/ballchase-handmade.yaml session --robot "
    "behaviours/ballchase-ros2.yaml"))
def replay(
    file: ControllerArgument,
    bag: Annotated[Path, typer.Argument(help="A bag (folder, .mcap or .bag) with the inputs' "
                                        "and the command's topics.")],
    robot: RobotOption = None,
    out: Annotated[Path | None, typer.Option("--out", "-o", help="CSV to write (default: "
                                             "stdout).")] = None,
    bag_out: Annotated[Path | None, typer.Option("--bag", help="Also write a copy of the bag "
                                                 "with COMMAND/replayed and "
                                                 "COMMAND/difference beside the recorded "
                                                 "commands (a new folder).")] = None,
    force: Force = False,
) -> None:
    """Run a controller over a bag's recorded inputs: at each recorded command, its output
    from the latest inputs, beside the recorded one and their difference (CSV)."""
    with user_errors():
        import numpy as np

        from flctool.compile import compile_behaviour
        from flctool.ros2.bags import replay as replay_bag
        from flctool.ros2.section import ros2_section

        behaviour, source = load_controller(file)
        config, _ = ros2_section(behaviour, str(source), robot)
        if out is not None:
            check_output(out, "replay CSV", force=force)
        flc = compile_behaviour(behaviour)
        rows = replay_bag(bag, config, behaviour.input_names, dict(behaviour.output.commands),
                          lambda values: flc.output_one(np.array(values, dtype=np.float64)))
        buffer = io.StringIO()
        writer = csv.writer(buffer, lineterminator="\n")
        writer.writerow(["time", *behaviour.input_names, "recorded", behaviour.output.name,
                         "difference"])
        for row in rows:
            writer.writerow([repr(row.time), *map(repr, row.inputs), repr(row.recorded),
                             repr(row.replayed), repr(row.difference)])
        if out is None:
            sys.stdout.write(buffer.getvalue())
        else:
            write_output(out, buffer.getvalue(), "replay CSV", force=force)
        if bag_out is not None:
            from flctool.ros2.bags import write_replay_bag

            write_replay_bag(bag, bag_out, config.command.topic, rows)
            print(f"wrote {bag_out}", file=sys.stderr)
        differing = sum(1 for row in rows if row.difference != 0.0)
        largest = max((abs(row.difference) for row in rows), default=0.0)
        print(f"{len(rows)} commands replayed; {differing} differ from the recorded ones "
              f"(largest difference {largest:g})", file=sys.stderr)


@app.command(name="fit-sim", epilog=example(
    "flctool fit-sim session --robot behaviours/ballchase-ros2.yaml --sim "
    "behaviours/ballchase.yaml --odom /robot/odom -o fitted.yaml"))
def fit_sim(
    bag: Annotated[Path, typer.Argument(help="A bag with the command topic and odometry.")],
    robot: Annotated[Path, typer.Option(help="The robot's behaviour file (adapter: ros2): "
                                        "its command topic and commands.")],
    sim: Annotated[Path, typer.Option(help="A simulator behaviour file whose environment: "
                                      "section is the base of the fitted one.")],
    odom: Annotated[str, typer.Option(help="The odometry topic (nav_msgs/Odometry, "
                                      "PoseStamped, Pose or Pose2D).")] = "/odom",
    unit: Annotated[float, typer.Option(min=1e-9, help="Millimetres per odometry length "
                                        "unit (1000 for metres).")] = 1000.0,
    out: Annotated[Path | None, typer.Option("--out", "-o", help="Write the fitted "
                                             "environment: section here (YAML).")] = None,
    force: Force = False,
) -> None:
    """Fit the simulator's motion and noise tables (per command: forward, sideways and
    rotation per step, their standard deviations) to logged commands and odometry; writes
    an environment: section and reports the fit."""
    with user_errors():
        import yaml

        from flctool.behaviour import behaviour_to_data, load_behaviour
        from flctool.ros2.bags import environment_section, fit_motion
        from flctool.ros2.section import ros2_section

        robot_behaviour = load_behaviour(robot)
        config, _ = ros2_section(robot_behaviour, str(robot))
        simulator = load_behaviour(sim)
        if simulator.environment is None or simulator.environment.adapter not in (
                "ballchase-sim", "pitch"):
            raise FlcError(f"{sim}'s environment is not a simulator with a motion table",
                           hint="give a behaviour with adapter: ballchase-sim or pitch")
        if out is not None:
            check_output(out, "fitted environment", force=force)
        commands = dict(robot_behaviour.output.commands)
        fits = fit_motion(bag, config, commands, odom, unit)
        missing = [name for name in commands if name not in fits]
        if missing:
            raise FlcError(f"{bag}: fewer than 2 steps of command{'s' if len(missing) > 1 else ''}"
                           f" {', '.join(missing)} with odometry before and after",
                           hint="record a session in which every command runs (and --odom "
                           "names the odometry topic)")
        base = behaviour_to_data(simulator)["environment"]
        section = {"environment": environment_section(fits, base)}
        text = yaml.safe_dump(section, sort_keys=False)
        typer.echo(f"{'command':<16}{'steps':>6}  {'forward mm':>18}  {'sideways mm':>18}  "
                   f"{'rotation deg':>18}")
        for name, fit in fits.items():
            cells = [f"{m:8.3f} ± {s:7.3f}" for m, s in zip(fit.mean, fit.std, strict=True)]
            typer.echo(f"{name:<16}{fit.steps:>6}  " + "  ".join(f"{c:>18}" for c in cells))
        typer.echo("(mean ± standard deviation per step: the motion and noise tables; the "
                   "means' standard errors are the deviations / sqrt(steps))")
        if out is None:
            typer.echo(text, nl=False)
        else:
            write_output(out, text, "fitted environment", force=force)
            typer.echo(f"wrote {out}")
