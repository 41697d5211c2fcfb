"""``flctool serve``: the reference robot side of the robot link (a simulator behind a socket).

It prints ``listening on HOST:PORT`` on stdout once it accepts connections (with ``--port 0``
the system picks a free port), and logs connections and safe stops on stderr.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from flctool.cli.app import app, example, user_errors


@app.command(epilog=example("flctool serve behaviours/ballchase.yaml --port 5555",
                            "flctool serve behaviours/ballchase.yaml --port 0 --once",
                            "flctool serve behaviours/ballchase.yaml --ros2"))
def serve(
    file: Annotated[Path, typer.Argument(help="A behaviour file whose environment is a "
                                         "simulator (e.g. adapter: ballchase-sim).")],
    host: Annotated[str, typer.Option(help="Address to listen on; 0.0.0.0 for every "
                                      "interface.")] = "127.0.0.1",
    port: Annotated[int, typer.Option(min=0, max=65535, help="Port to listen on; 0 picks a "
                                      "free one.")] = 0,
    once: Annotated[bool, typer.Option("--once", help="Exit after the first client "
                                       "disconnects.")] = False,
    idle_timeout: Annotated[float, typer.Option(min=0.001, help="Seconds without a message "
                                                "before the robot is stopped and the client "
                                                "dropped.")] = 60.0,
    max_batch: Annotated[int | None, typer.Option(min=1, help="Most episodes per reset, as a "
                                                  "real robot (1) would have; default any.")]
    = None,
    ros2: Annotated[bool, typer.Option("--ros2", help="Serve the simulator as a ROS 2 robot "
                                       "(topics under --namespace, docs/ros2.md) instead of "
                                       "over the robot link.")] = False,
    namespace: Annotated[str, typer.Option(help="The ROS 2 robot's namespace (--ros2); its "
                                           "topics are NAMESPACE/<input>, /cmd_vel, /reset, "
                                           "/status, /reward, /odom.")] = "/robot",
    auto_reset: Annotated[bool, typer.Option("--auto-reset", help="Start an episode at once "
                                             "and the next when one ends, from consecutive "
                                             "seeds (--ros2; for 'flctool run --ros2', which "
                                             "never resets).")] = False,
    seed: Annotated[int, typer.Option(min=0, help="The first episode's seed (--ros2 "
                                      "--auto-reset).")] = 0,
    episodes: Annotated[int | None, typer.Option(min=1, help="Exit after this many episodes "
                                                 "have ended (--ros2).")] = None,
) -> None:
    """Serve a behaviour's simulator over the robot-link protocol (docs/robot-link.md), for
    trying the link without a robot and as an example for bridge writers."""
    from flctool.behaviour import load_behaviour
    from flctool.envs.robot_server import RobotServer, print_log

    if ros2:
        _serve_ros2(file, namespace, auto_reset, seed, episodes)
        return
    with user_errors():
        behaviour = load_behaviour(file)
        server = RobotServer.from_behaviour(
            behaviour, host=host, port=port, idle_timeout=idle_timeout, max_batch=max_batch,
            robot=f"flctool serve {behaviour.name}", log=print_log)
        typer.echo(f"listening on {server.host}:{server.port}")
        try:
            server.serve(once=once)
        finally:
            server.close()


def _serve_ros2(file: Path, namespace: str, auto_reset: bool, seed: int,
                episodes: int | None) -> None:
    from flctool.behaviour import load_behaviour
    from flctool.envs.robot_server import print_log

    with user_errors():
        from flctool.envs.ros2_robot import SimRobot

        behaviour = load_behaviour(file)
        robot = SimRobot.from_behaviour(behaviour, namespace=namespace, auto_reset=auto_reset,
                                        first_seed=seed, log=print_log)
        try:
            typer.echo(f"serving ROS 2 robot {namespace}: {', '.join(robot.topics)}")
            if auto_reset:
                robot.start_episode()
            robot.serve(episodes)
            outcomes = ", ".join(f"{k} {v}" for k, v in robot.outcomes.items())
            print_log(f"{robot.episodes} episodes ended ({outcomes})")
        finally:
            robot.close()
